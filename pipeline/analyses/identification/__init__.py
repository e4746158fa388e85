"""The identification of free parameters from targets (the algorithm of ``hdi identify``), on in-memory data.

It takes an evaluation callable (points to records: :class:`Identification`) and returns arrays; the
stage (:mod:`pipeline.stages.identify`) reads the scene and the evaluation store, calls it and writes
``identify.nc``. The objective is the sum of squared residuals of the targets
(:func:`pipeline.analyses.study.residuals`), each normalised by its tolerance (docs/model.md, section
"Identification").

Method
------
1. **Global search**: :func:`scipy.optimize.differential_evolution` [SP97]_ (``best1bin``, Latin
   hypercube start seeded with the reconstructed scene, ``vectorized=True`` so each generation is one
   fan-out of batches, ``updating="deferred"``, seeded). The objective is noisy and partly discrete
   (a contact flag switches; a run snaps into contact or not), so no gradient polish (``polish=False``):
   L-BFGS-B on a piecewise-constant residual stops where it starts.
   **Polish** (``identify.polish``, :func:`_polish`): a compass search over every parameter from the
   search's best point, so that the profiles start at an optimum the search may have stopped short of.
   Polls of +- a step of each parameter's range (the profile grid's spacing first), raced against the
   current point like a walk's (step 2); a poll holding a better whole evaluation moves there and polls
   again, one that does not tries the vertex of the parabolas through it and halves the step; it ends
   after the poll at the first step at or below :data:`PROFILE_STEP` or at its budget
   (:data:`POLISH_EVALUATIONS` per parameter). Role ``polish``.
2. **Profiles**: first a *slice* of each parameter across its bounds (``profile_points`` and the
   optimum's value), the others held at the optimum. A slice is narrower than the profile where
   parameters correlate (it is the conditional, not the marginal, range), so with
   ``profile_method = "optimised"`` (the default) the others are then **re-optimised** at each point:
   two walks per parameter go outward from the optimum, all advanced together (each round one
   fan-out, role ``profile-optimiser``). At each value the others start from the neighbouring
   re-optimised point moved along the valley (the Gauss-Newton slope of step 3's Jacobian for the
   first step, exact on a quadratic objective; the secant of the last two points after), the slice
   point competes with that prediction, and a compass search (polls of +- :data:`PROFILE_STEP` of
   each other parameter's range while one improves, then one point at the vertex of the parabolas
   through the poll; no gradients: the objective is noisy and partly piecewise constant) lowers the
   interval criterion's metric (the largest ``|r|``, or the objective; below). A walk stops past the
   first point outside the interval, at the bounds, or when the parameter's ``profile_evaluations``
   are spent; the points it did not reach keep the slice's values (``profile_optimised`` 0 in the
   dataset). A profile point is never worse than the slice's, so (with the optimum the profile's
   minimum) its interval is never narrower. A profile point better than the optimum (by more than
   :data:`PROFILE_GAIN`) means the global search stopped short: it becomes the optimum and the
   profiles are made again around it (a round's re-optimisation stops at the first such point, and
   does not start after a slice found one), at most :data:`PROFILE_ROUNDS` rounds (``profile_rounds`` in
   the dataset).
   **The best point** is the evaluation of lowest objective of all (the reconstructed scene, the
   search, the profiles, the Gauss-Newton points; the first in request order on a tie): the identified
   values, ``best_evaluation``, the written scene and the log's last line all name it. It is the
   profiles' centre unless a point better by less than :data:`PROFILE_GAIN`, or one found in the last
   round or at the Gauss-Newton points, was left where it is (``profile_centre_evaluation`` then
   names the centre). The interval of a parameter is the connected range of its profile around the
   best point's value where **every target stays within tolerance** (all ``|r| <= 1``); when the best
   point itself misses a target, that range does not exist and the stage reports instead the range
   where the objective stays within 1 of its profile minimum (the 68 % profile interval if tolerances
   were one standard deviation) and says so. Crossings are interpolated linearly between profile points.
   **Racing** (``identify.racing``, ensembles only; :class:`Racing`, :meth:`Identification.evaluate`): the
   search's trials, the polish's polls and every point a walk asks for run on the first 2 DMW records, then
   4, then all, and stop at a stage where the lower confidence bound of their objective (each residual
   lowered by its margin from the record-to-record spread, own and paired with a reference on the same
   records) exceeds the best point's (a walk's point: its current point's, at a new value the slice
   point's) or the smallest upper bound of the candidates racing with them [MM94]_; a walk never takes a
   point stopped early. With ``identify.racing_records = 1`` the stages are 1, 2, 4, all: a one-record part is
   scored as a partial ensemble (:func:`pipeline.analyses.study.is_ensemble`) and bounded by the pooled
   spreads alone (no stop before the first whole evaluation). Everything else (the best point, the slices, the Gauss-Newton points) runs on every
   record, and so every profile point is a whole evaluation; docs/model.md, section "Identification",
   states the guarantee.
3. **Correlation**: Gauss-Newton at the optimum, ``C = (J^T J)^+`` with ``J`` the central-difference
   Jacobian of the residuals in parameters scaled to their bounds (steps of 2 % of the range);
   ``corr_ij = C_ij / sqrt(C_ii C_jj)``. A direction with no curvature (a parameter no target sees)
   gives a zero eigenvalue; its variance is then reported as infinite and its correlations as NaN.


Modules
-------
* :mod:`.racing`: the stages of DMW record counts and the confidence bounds a raced candidate is stopped by;
* :mod:`.records`: :class:`Identification`, the evaluation callable, every record and its score, the roles;
* :mod:`.search`: :func:`identify` (the three steps) and step 1, the global search and the polish;
* :mod:`.profiles`: step 2, the slices, the re-optimised walks and the intervals;
* :mod:`.gauss_newton`: step 3, the Jacobian and the correlation.

References
----------
.. [SP97] R. Storn, K. Price, "Differential evolution -- a simple and efficient heuristic for global
   optimization over continuous spaces", J. Global Optim. 11 (1997) 341-359.
.. [MM94] O. Maron, A. W. Moore, "Hoeffding races: accelerating model selection search for classification
   and function approximation", Advances in Neural Information Processing Systems 6 (1994) 59-66.
"""

from __future__ import annotations

from .racing import MEDIAN_EFFICIENCY, Racing, lower_bound, upper_bound
from .records import ROLES, Identification
from .search import METHODS, identify
from .profiles import PROFILE_STEP, PROFILE_ROUNDS, PROFILE_GAIN, interval
from .gauss_newton import GN_STEP

__all__ = ["MEDIAN_EFFICIENCY", "Racing", "lower_bound", "upper_bound", "ROLES", "Identification", "METHODS",
           "identify", "PROFILE_STEP", "PROFILE_ROUNDS", "PROFILE_GAIN", "interval", "GN_STEP"]
