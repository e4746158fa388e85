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

References
----------
.. [SP97] R. Storn, K. Price, "Differential evolution -- a simple and efficient heuristic for global
   optimization over continuous spaces", J. Global Optim. 11 (1997) 341-359.
.. [MM94] O. Maron, A. W. Moore, "Hoeffding races: accelerating model selection search for classification
   and function approximation", Advances in Neural Information Processing Systems 6 (1994) 59-66.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..config.limits import POLISH_EVALUATIONS  # (the polish's budget, step 1 of the module docstring)
from .study import (ObjectiveTerm, Parameter, cost, head, input_spreads, realisations_of, record_inputs,
                    residuals, score)

#: Role of an evaluation (``role`` variable of identify.nc).
ROLES = {0: "reconstructed", 1: "optimiser", 2: "profile", 3: "gauss-newton", 4: "profile-optimiser", 5: "polish"}
#: The interval methods (``identify.profile_method``) and what identify.nc and the report call them.
METHODS = {"optimised": "profile, other parameters re-optimised",
           "slice": "slice, other parameters held at the optimum"}
#: Compass step of the re-optimised profiles, a fraction of each other parameter's range [1]: the others
#: move by it while a poll finds a better point; after a poll that finds none, one point at the vertex of
#: the parabolas through the poll (finer than the step) finishes the point. The poll starts from a
#: prediction that is exact on a quadratic objective.
PROFILE_STEP = 0.05
#: Central-difference step of the Gauss-Newton Jacobian, a fraction of each parameter's range [1].
GN_STEP = 0.02
#: Rounds of profiles at most: a profile point better than the optimum by more than PROFILE_GAIN (in
#: the objective, the sum of squared residuals: the interval criterion's unit, so a smaller gain lies
#: within the optimum's own interval) becomes the optimum and the profiles are made again around it.
PROFILE_ROUNDS = 3
PROFILE_GAIN = 1.0


#: Asymptotic standard error of a sample median over that of a mean for Gaussian data, sqrt(pi / 2) [1]
#: (Kenney & Keeping 1962): the racing bound takes every ensemble statistic to be as noisy as a median.
MEDIAN_EFFICIENCY = math.sqrt(math.pi / 2.0)


@dataclass(frozen=True)
class Racing:
    """Racing of the candidates over the DMW records (docs/model.md, section "Identification", "Racing").

    A raced candidate runs on ``stages[0]`` records, then on the next stage's (the records nest: the first
    ``m`` of ``n`` realisations are those of ``m``) while the lower confidence bound of its metric
    (:func:`lower_bound`) does not exceed its bound (the best point's objective, or the current point of a
    profile walk); the last stage is every record (``realisations``). A first stage of one record
    (``identify.racing_records = 1``) has no record-to-record spread of its own: its margin is the pooled
    spreads' alone (:meth:`Identification.pooled_spread`), infinite before the first whole evaluation.

    Attributes
    ----------
    stages : increasing DMW record counts, the last the ensemble's size
    z : standard errors of each target's residual a candidate may lose by and still go on [1]
    """

    stages: tuple[int, ...]
    z: float = 3.0

    @classmethod
    def doubling(cls, first: int, total: int, z: float) -> "Racing":
        """Stages ``first, 2 first, 4 first, ...`` below ``total``, then ``total``."""
        stages, m = [], first
        while m < total:
            stages.append(m)
            m *= 2
        return cls(tuple(stages) + (total,), z)

    @property
    def total(self) -> int:
        """The ensemble's DMW records [1]."""
        return self.stages[-1]

    def margin(self, spread: np.ndarray, n: int) -> np.ndarray:
        """The error bound of each target's residual on the first ``n`` records against all of them [1]:
        ``z sqrt(pi/2) s sqrt((N - n) / (N n))`` with ``s`` the record-to-record spread in residual units
        (:func:`pipeline.analyses.study.record_spreads`; infinite where unknown). The full ensemble's mean
        of ``N`` records differs from that of its first ``n`` by ``(N - n)/N`` times the difference of the
        means of the other ``N - n`` and of the first ``n``, of variance ``s^2 (N - n) / (N n)``; zero at
        ``n = N``."""
        N = self.total
        s = np.where(np.isfinite(spread), spread, np.inf)
        return self.z * MEDIAN_EFFICIENCY * s * math.sqrt(max(N - n, 0) / (N * n))


def lower_bound(res: np.ndarray, margin: np.ndarray, metric: str) -> float:
    """The lower confidence bound of a metric of the residuals ``res`` whose errors are at most ``margin``
    (each residual's magnitude lowered by its margin, not below zero): of the objective (``"cost"``, the sum
    of squares) or of the largest ``|r|`` (``"max"``)."""
    low = np.maximum(np.abs(np.asarray(res, float)) - margin, 0.0)
    low = np.where(np.isfinite(low), low, 0.0)  # (an unknown residual with an infinite margin: no bound)
    return _metric(low, metric)


def upper_bound(res: np.ndarray, margin: np.ndarray, metric: str) -> float:
    """The upper confidence bound of the metric (:func:`lower_bound`): each ``|r|`` raised by its margin."""
    high = np.abs(np.asarray(res, float)) + margin
    return _metric(np.where(np.isnan(high), np.inf, high), metric)


def _metric(r: np.ndarray, metric: str) -> float:
    return float(np.max(r, initial=0.0)) if metric == "max" else float(np.sum(r**2))


class Identification:
    """The state of one identification: the evaluation callable, every record it returned, and their scores.

    Parameters
    ----------
    evaluate
        ``evaluate(points) -> records``: one evaluation record per row of ``points`` (shape
        ``(n, parameters)``), as :func:`pipeline.analyses.study.residuals` reads them, each with its
        ``key`` (:class:`pipeline.evaluations.Evaluator` in ``hdi identify``). With ``racing``:
        ``evaluate(points, upto)``, each record on the first ``upto`` DMW records (a racing stage), the
        key the whole evaluation's.
    tlist
        The targets (:func:`pipeline.analyses.study.targets`).
    missing
        The residual of a target a record cannot produce (``identify.missing_residual``).
    racing
        Race the candidates of the calls given a ``bound`` (:meth:`evaluate`) over the DMW records
        (:class:`Racing`); None: every candidate on every record (the full method).
    """

    def __init__(self, evaluate: Callable[..., list[dict[str, Any]]], tlist: Sequence[ObjectiveTerm],
                 missing: float, racing: Racing | None = None):
        self.evaluate_points, self.tlist, self.missing = evaluate, list(tlist), missing
        self.racing = racing
        #: every record asked for, by key, in request order (the most records of each); and the role of its
        #: first request
        self.records: dict[str, dict[str, Any]] = {}
        self.roles: dict[str, int] = {}
        #: target values and residuals of every record, by key, scored when it (or more of its records) comes back,
        #: and the ensemble spread of each target's value (``(targets, 2)``, identify.nc's ``spread``)
        self.scores: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.value_spreads: dict[str, np.ndarray] = {}
        #: what each record's residuals are made of, per DMW record (:func:`record_inputs`), by key: made once
        #: per record held (racing bounds every candidate against the same reference at every stage)
        self._inputs: dict[str, np.ndarray] = {}
        #: DMW records of each key's record; the record-to-record spreads of the whole evaluations (racing)
        self.depth: dict[str, int] = {}
        self.spreads: dict[str, np.ndarray] = {}
        #: racing: each point's key (by :func:`_point`), the paired spreads of whole evaluations against their
        #: reference by role (:meth:`_race`: a poll and its walk's point are neighbours, a trial and the best
        #: point are not) and the residuals of a whole evaluation's first records, by (key, records)
        self.by_point: dict[tuple, str] = {}
        self.pair_spreads: dict[int, list[np.ndarray]] = {}
        self._heads: dict[tuple[str, int], np.ndarray] = {}
        #: the key and objective of the best record so far (lowest objective, the first on a tie; a whole
        #: evaluation: with racing, one on every record)
        self.best_key: str | None = None
        self.best_cost = float("inf")

    def is_full(self, key: str) -> bool:
        """The record of ``key`` holds every DMW record (always, without racing)."""
        return self.racing is None or self.depth.get(key, 0) >= self.racing.total

    @property
    def record_evaluations(self) -> int:
        """(candidate, DMW record) pairs of every record held [1]: the identification's cost."""
        return int(sum(self.depth.values()))

    @property
    def keys(self) -> list[str]:
        """The keys of every record asked for, in request order."""
        return list(self.records)

    @property
    def best_index(self) -> int:
        """The request-order index (:attr:`keys`) of the best record so far."""
        return self.keys.index(self.best_key) if self.best_key is not None else -1

    def evaluate(self, points: np.ndarray, role: int, bound: Any = None, metric: str = "cost",
                 groups: Any = None, refs: Any = None) -> tuple[list[dict], np.ndarray, np.ndarray]:
        """Records, target values and residuals of ``points`` (shape (n, parameters)).

        With :attr:`racing` and a ``bound`` (a number, or one per point; ``inf``: that point on every
        record), the points are raced (docs/model.md, section "Identification"): each stage's records for
        the points still running (one call of the evaluation callable per stage), and a point stops when
        the :func:`lower_bound` of its ``metric`` (``"cost"``, ``"max"``) exceeds its bound or the smallest
        :func:`upper_bound` of the points of its group (``groups``: a label per point, None: no groups),
        a point that will beat it. ``refs``: a reference point per row (a whole evaluation held here, e.g.
        the best point; NaN or None: none) against which each point's residuals are also bounded on the
        same records (:meth:`_bounds`). A stopped point's record, values and residuals are those of its
        partial ensemble."""
        if self.racing is None or bound is None:
            recs = self.evaluate_points(points) if self.racing is None else \
                self.evaluate_points(points, self.racing.total)
            self._take(recs, role)
        else:
            n = len(points)
            ref_keys = [None] * n if refs is None else \
                [self.by_point.get(_point(y)) if np.all(np.isfinite(y)) else None
                 for y in np.broadcast_to(np.asarray(refs, float), (n, np.shape(points)[1]))]
            recs = self._race(np.asarray(points, float), role, np.broadcast_to(np.asarray(bound, float), (n,)),
                              metric, np.arange(n) if groups is None else np.broadcast_to(np.asarray(groups), (n,)),
                              ref_keys)
        recs = [self.records[r["key"]] for r in recs]
        vals, res = zip(*(self.scores[r["key"]] for r in recs)) if recs else ((), ())
        return recs, np.array(vals).reshape(len(recs), -1), np.array(res).reshape(len(recs), -1)

    def _take(self, recs: list[dict[str, Any]], role: int) -> None:
        """Keep and score the records that are new or hold more DMW records than before."""
        for r in recs:
            key, depth = r["key"], realisations_of(r)
            if key not in self.roles:
                self.roles[key] = role
            if key in self.depth and depth <= self.depth[key]:
                continue
            self.records[key], self.depth[key] = r, depth  # (a known key keeps its place in request order)
            self.by_point[_point(r["params"])] = key
            vals, res, spread = score(r, self.tlist, self.missing)
            self.scores[key], self.value_spreads[key] = (vals, res), spread
            self._inputs.pop(key, None)
            if not self.is_full(key):
                continue
            if self.racing is not None and depth > 1:
                self.spreads[key] = input_spreads(self.inputs_of(key))
            elif self.racing is not None:
                self.spreads[key] = np.full(len(self.tlist), np.nan)
            c = cost(self.scores[key][1])
            if c < self.best_cost:  # (strictly: the first of equal objectives stays the best)
                self.best_key, self.best_cost = key, c

    def _race(self, pts: np.ndarray, role: int, bound: np.ndarray, metric: str, groups: np.ndarray,
              refs: list[str | None]) -> list[dict[str, Any]]:
        """The records of :meth:`evaluate` with racing, in the order of ``pts``."""
        assert self.racing is not None
        recs: list[dict[str, Any]] = [{}] * len(pts)
        alive = np.ones(len(pts), bool)
        low, high = np.zeros(len(pts)), np.full(len(pts), np.inf)
        for m in self.racing.stages:
            idx = np.flatnonzero(alive)
            if not idx.size:
                break
            got = self.evaluate_points(pts[idx], m)
            self._take(got, role)
            for i, r in zip(idx, got):
                recs[i] = r
                key = r["key"]
                if self.is_full(key):  # (exact: both bounds are its metric)
                    alive[i] = False
                    low[i] = high[i] = _metric(np.abs(self.scores[key][1]), metric)
                    if refs[i] is not None and refs[i] != key and self.is_full(refs[i]):
                        self.pair_spreads.setdefault(role, []).append(
                            input_spreads(self.inputs_of(key) - self.inputs_of(refs[i])))
                    continue
                lo_t, hi_t = self._bounds(key, refs[i], role)
                low[i], high[i] = _metric(lo_t, metric), _metric(hi_t, metric)
            # the smallest upper bound of each group: the point holding it is never stopped (its lower bound is
            # below it), so a point whose lower bound exceeds it will be beaten
            best_high = {g: np.min(high[groups == g]) for g in np.unique(groups[idx])}
            for i in idx:  # (an infinite bound: that point on every record)
                if alive[i] and np.isfinite(bound[i]) and low[i] > min(bound[i], best_high[groups[i]]):
                    alive[i] = False
        return recs

    def _bounds(self, key: str, ref: str | None, role: int) -> tuple[np.ndarray, np.ndarray]:
        """Per target, the lower and upper confidence bounds of ``|r|`` on the whole ensemble for the partial
        record ``key`` (docs/model.md, section "Identification"): from its own records (its residual, the
        margin of :meth:`Racing.margin` with the larger of its own and the pooled record-to-record spread) and,
        with a whole evaluation ``ref`` and paired spreads pooled from earlier whole evaluations of the same
        ``role`` against theirs, from the same
        records of ``ref`` (common random numbers: ``r(ref, all) + r(key, first n) - r(ref, first n)``, the
        margin with the spread of the records' differences, again the larger of its own and the pooled;
        where a one-sided target is on the wrong side in all three). The tighter of the two, per target. On one
        record (a first stage of ``racing_records = 1``) the own spreads are unknown (NaN) and the pooled ones
        alone count; with none pooled yet the margin is infinite: no bound."""
        assert self.racing is not None
        n, rec = self.depth[key], self.records[key]
        res = np.abs(self.scores[key][1])
        own_spread = input_spreads(self.inputs_of(key)) if realisations_of(rec) > 1 else np.full(len(res), np.nan)
        e = self.racing.margin(np.fmax(own_spread, self.pooled_spread()), n)
        lo, hi = np.maximum(res - e, 0.0), np.where(np.isnan(res + e), np.inf, res + e)
        pooled = self._pooled(self.pair_spreads.get(role, []))
        if ref is None or not self.is_full(ref) or not np.isfinite(pooled).any():
            return np.where(np.isfinite(lo), lo, 0.0), hi
        r_ref, r_ref_n = self.scores[ref][1], self._head_residuals(ref, n)
        r_key = self.scores[key][1]
        paired = r_key + r_ref - r_ref_n
        own = input_spreads(self.inputs_of(key) - self.inputs_of(ref)[:, :, :n])
        e2 = self.racing.margin(np.fmax(own, pooled), n)
        equal = np.array([t.kind == "equal" for t in self.tlist])
        usable = np.isfinite(paired) & np.isfinite(e2) & (equal | ((r_key != 0) & (r_ref != 0) & (r_ref_n != 0)))
        lo2 = np.where(usable, np.maximum(np.abs(paired) - e2, 0.0), 0.0)
        hi2 = np.where(usable, np.abs(paired) + e2, np.inf)
        return np.where(np.isfinite(lo), np.maximum(lo, lo2), lo2), np.minimum(hi, hi2)

    def inputs_of(self, key: str) -> np.ndarray:
        """:func:`pipeline.analyses.study.record_inputs` of the record held for ``key`` (made once per record)."""
        if key not in self._inputs:
            self._inputs[key] = record_inputs(self.records[key], self.tlist)
        return self._inputs[key]

    def _head_residuals(self, key: str, n: int) -> np.ndarray:
        """The residuals of the first ``n`` DMW records of the whole evaluation ``key`` (cached)."""
        if (key, n) not in self._heads:
            self._heads[key, n] = residuals(head(self.records[key], n), self.tlist, self.missing)[1]
        return self._heads[key, n]

    @staticmethod
    def _pooled(spreads: Any) -> np.ndarray:
        """The median of ``spreads`` (arrays over the targets), NaN where none is finite or there are none."""
        if not len(spreads):
            return np.full(0, np.nan)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # (an all-NaN column: NaN, the spread unknown)
            return np.nanmedian(np.array(spreads, float), axis=0)

    def pooled_spread(self) -> np.ndarray:
        """Per target, the median record-to-record spread of the whole evaluations so far [1] (NaN before
        the first): a floor under a partial ensemble's own spread, which two records estimate poorly."""
        p = self._pooled(list(self.spreads.values()))
        return p if p.size else np.full(len(self.tlist), np.nan)

    def costs(self, points: np.ndarray, role: int, bound: Any = None, groups: Any = None,
              refs: Any = None) -> np.ndarray:
        return np.array([cost(r) for r in self.evaluate(points, role, bound, groups=groups, refs=refs)[2]])


def interval(grid: np.ndarray, metric: np.ndarray, limit: float, centre: float) -> tuple[float, float]:
    """Connected range of ``grid`` around ``centre`` where ``metric <= limit`` (linear crossings)."""
    order = np.argsort(grid)
    g, m = grid[order], metric[order]
    i0 = int(np.argmin(np.abs(g - centre)))
    if not m[i0] <= limit:
        return float("nan"), float("nan")

    def walk(step: int) -> float:
        i = i0
        while 0 <= i + step < len(g) and m[i + step] <= limit:
            i += step
        j = i + step
        if not 0 <= j < len(g):
            return float(g[i])
        if not np.isfinite(m[j]):
            return float(g[i])
        f = (limit - m[i]) / (m[j] - m[i]) if m[j] != m[i] else 0.0
        return float(g[i] + f * (g[j] - g[i]))

    return walk(-1), walk(+1)


def identify(ident: Identification, params: Sequence[Parameter], x_base: np.ndarray, cfg: dict,
             progress: Callable[..., Any] | None = None) -> dict[str, Any]:
    """Run the three steps of the module docstring from the reconstructed point ``x_base``.

    ``cfg``: ``generations``, ``population``, ``seed``, ``profile_points``, ``profile_method``
    (a key of :data:`METHODS`), ``profile_evaluations`` and ``polish`` (``[identify]``). Returns the best point,
    its residuals, whether it is within tolerance, the intervals, their criterion and method, the
    profiles (with the slices they started from), the correlation, the optimiser's report (arrays,
    for ``identify.nc``) and the polish's (``polish``: :func:`_polish`'s dict, None when off); the records
    are in ``ident``.

    ``progress``: how the work shows itself, a started :class:`pipeline.progress.Progress` (in ``hdi
    identify``; default None: nothing shown), counted in phases (:meth:`~pipeline.progress.Progress.phase`),
    each with a total fixed when it starts: the search's generations (``cfg["generations"]``), the
    polish's budget (an upper bound, lowered when it ends), then each
    round of profiles its evaluations (the slices, the Gauss-Newton points and the re-optimisation's
    budget, an upper bound lowered when the round ends), each step noted with the best objective so far.
    It only watches: the results are the same with or without it.

    ``best``, ``best_residuals`` and ``best_evaluation`` (its index in ``ident.keys``) are the best
    point of the module docstring; ``centre`` and ``centre_evaluation`` the profiles' centre.
    """
    lo = np.array([p.low for p in params])
    hi = np.array([p.high for p in params])
    n = len(params)
    if progress is not None:  # (the reconstructed point and the search's first population: before generation 1)
        progress.phase("search", cfg["generations"], unit="generation")
    ident.evaluate(x_base[None, :], 0)
    result = _global_search(ident, lo, hi, x_base, cfg, progress)
    polished = _polish(ident, lo, hi, 1.0 / (cfg["profile_points"] - 1), POLISH_EVALUATIONS * n, progress) \
        if cfg["polish"] else None
    # the profiles' first centre: the best of everything evaluated so far (the reconstruction included)
    centre = np.array(ident.records[ident.best_key]["params"], float)
    centre_res = ident.scores[ident.best_key][1]

    # profiles; a profile point better than the optimum is the new optimum, and the profiles are
    # made again around it (at most PROFILE_ROUNDS times)
    m = cfg["profile_points"]
    optimised = cfg["profile_method"] == "optimised" and n > 1  # (one parameter has no others)
    budget = cfg["profile_evaluations"] if optimised else 0
    centre, centre_res, slices, profiles, J, rounds, spent = _profile_rounds(ident, centre, centre_res, lo, hi, m,
                                                                             budget, progress)
    # the best point: the lowest objective of every evaluation (module docstring)
    i_best = ident.best_index
    best = np.array(ident.records[ident.best_key]["params"], float)
    best_res = ident.scores[ident.best_key][1]
    within = bool(np.all(np.abs(best_res) <= 1.0))
    criterion = "all targets within tolerance (|r| <= 1)" if within else \
        "objective within 1 of its profile minimum (the optimum misses a target, so no range keeps all within tolerance)"
    arrays = _profile_arrays(profiles, slices, n)
    corr, gn_std = _correlation(J, lo, hi)
    pts = np.array([r["params"] for r in ident.records.values()], float)
    i_centre = int(np.argmin(np.max(np.abs(pts - centre), axis=1)))  # (the centre is an evaluated point)
    return {"best": best, "best_residuals": best_res, "best_evaluation": i_best, "within": within,
            "centre": centre, "centre_evaluation": i_centre,
            "intervals": _intervals(profiles, best, within), "slice_intervals": _intervals(slices, best, within),
            "criterion": criterion, "method": METHODS["optimised" if optimised else "slice"], **arrays,
            "correlation": corr, "gn_std": gn_std, "de_message": str(result.message),
            "de_generations": int(result.nit), "de_evaluations": int(result.nfev), "profile_rounds": rounds,
            "profile_optimiser_evaluations": spent, "polish": polished}


def _note(ident: Identification) -> str:
    """The progress note: the best objective so far (one name: the log's last line says the same)."""
    return f"best objective {ident.best_cost:.4g}"


def _profile_rounds(ident: Identification, best: np.ndarray, best_res: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                    m: int, budget: int, progress: Any | None) -> tuple:
    """Step 2 and the Jacobian of step 3, in rounds (module docstring); ``budget`` 0: slices only. Each
    round is a phase of ``progress`` (:func:`identify`) whose total, fixed when it starts, is the
    slices' points, the Gauss-Newton points and the re-optimisation's budget (an upper bound: the total
    is lowered to what was spent when the round ends).

    Returns the optimum (the profiles' centre) and its residuals, the last round's slices and profiles
    (:func:`_profile` dicts), the Jacobian at the optimum, the number of rounds and the
    re-optimisation's evaluations."""
    n = len(best)
    c_best, spent = float(np.sum(best_res**2)), 0
    done = [0]

    def count(k: int, *_: Any) -> None:
        """``k`` evaluations more in this round."""
        done[0] += k
        if progress is not None:
            progress.update(k, note=_note(ident))

    for rounds in range(1, PROFILE_ROUNDS + 1):
        grids = [_grid(lo[i], hi[i], m, best[i]) for i in range(n)]
        done[0] = 0
        if progress is not None:
            progress.phase(f"profiles, round {rounds} of at most {PROFILE_ROUNDS}",
                           sum(len(g) for g in grids) + 2 * n + n * budget, unit="evaluation")
        slices, rows, r_round = _slices(ident, best, grids)
        full = np.ones(len(rows), bool)  # (slice points run on every record)
        count(len(rows))
        profiles = slices
        # a point this much better ends the round (a round more follows around it): not after the last round
        moved = c_best - PROFILE_GAIN if rounds < PROFILE_ROUNDS else -np.inf
        if budget and not np.nanmin(np.sum(r_round**2, axis=1), initial=np.inf) < moved:
            J = _jacobian(ident, best, lo, hi)  # (first: it predicts the walks' first steps)
            count(2 * n)
            within = bool(np.all(np.abs(best_res) <= 1.0))
            found, w_rows, w_res, w_full = _reoptimise(ident, best, c_best, within, slices,
                                                       _valley_slopes(J, lo, hi), lo, hi, budget, count, moved)
            profiles = _merge(slices, found)
            spent += len(w_rows)
            rows, r_round = rows + w_rows, np.concatenate([r_round, w_res])
            full = np.concatenate([full, w_full])
        # (a raced point stopped early is no candidate for the optimum: its objective is a partial ensemble's)
        c_prof = np.where(full, np.sum(r_round**2, axis=1), np.nan)
        j = int(np.nanargmin(c_prof)) if np.isfinite(c_prof).any() else -1
        last = j < 0 or not c_prof[j] < c_best - PROFILE_GAIN or rounds == PROFILE_ROUNDS
        if last and not budget:  # (a slice's Jacobian after its profiles, as before the re-optimised method)
            J = _jacobian(ident, best, lo, hi)
            count(2 * n)
        if progress is not None:  # (the budget's rest unspent, or a round that moved the optimum)
            progress.update(0, total=done[0])
        if last:
            break
        best, best_res, c_best = np.array(rows[j]), r_round[j], float(c_prof[j])
    return best, best_res, slices, profiles, J, rounds, spent


def _global_search(ident: Identification, lo: np.ndarray, hi: np.ndarray, x_base: np.ndarray, cfg: dict,
                   progress: Callable[..., Any] | None) -> Any:
    """Step 1: differential evolution (its ``OptimizeResult``); every candidate's record is in ``ident``."""
    inside = bool(np.all((x_base >= lo) & (x_base <= hi)))

    def objective(X: np.ndarray) -> np.ndarray:  # vectorized: X has shape (parameters, S)
        # (racing: a trial goes on to more DMW records while it may still beat the best point; a stopped one
        # competes with its parent by its partial ensemble's objective, which exceeds the best point's)
        ref = ident.records[ident.best_key]["params"] if ident.best_key is not None else None
        return ident.costs(np.atleast_2d(X.T), 1, bound=ident.best_cost, groups=0, refs=ref)

    from scipy.optimize import differential_evolution  # (here: its import is not paid by every hdi command)

    def generation(intermediate_result: Any) -> None:  # (scipy passes the best so far by this name)
        if progress is not None:  # (the best of every evaluation: the reconstructed point included)
            progress.update(note=_note(ident))

    result = differential_evolution(objective, list(zip(lo, hi)), strategy="best1bin",
                                    maxiter=cfg["generations"], popsize=cfg["population"], tol=0.01,
                                    seed=cfg["seed"], polish=False, init="latinhypercube",
                                    x0=x_base if inside else None, vectorized=True, updating="deferred",
                                    callback=generation)
    if progress is not None:  # (converged before the last generation)
        progress.update(0, total=progress.done)
    return result


def _polish(ident: Identification, lo: np.ndarray, hi: np.ndarray, first: float, budget: int,
            progress: Any | None) -> dict[str, Any]:
    """The polish of step 1: a compass search over every parameter from the best point so far (module docstring).

    Each poll moves every parameter by +- ``step`` of its range (:func:`_compass`; one fan-out, role 5,
    raced against the current point: ``bound`` its objective, ``refs`` the point, the poll one group). A
    poll that holds a whole evaluation better than the current point (:attr:`Identification.best_cost`,
    strictly) moves there and polls again at the same step; after one that does not, the vertex of the
    parabolas through the poll (:func:`_vertex`) is tried once (raced the same way), and the step halves.
    It starts at ``first`` (the profile grid's spacing, a fraction of each range) and stops after the
    poll at the first step at or below :data:`PROFILE_STEP`, or before a poll that would spend more than
    ``budget`` evaluations in all. No gradients: the objective is noisy and partly piecewise constant.

    Returns what it did: ``evaluations`` (points asked for that were not held on every record before),
    ``polls`` (polls and vertices evaluated), ``moves`` (of them, those that found a better point),
    ``first_step`` and ``last_step`` (of its first and last poll, fractions of each range [1]),
    ``start_objective`` and ``objective`` (the best point's before and after [1])."""
    x = np.array(ident.records[ident.best_key]["params"], float)
    c_start = c = ident.best_cost
    step, spent, polls, moves = float(first), 0, 0, 0
    if progress is not None:
        progress.phase("polish", budget, unit="evaluation")

    def new(points: list[np.ndarray]) -> int:
        """How many of ``points`` are not held on every record yet (a poll after a move meets the point it
        left): what a poll spends of the budget."""
        keys = [ident.by_point.get(_point(p)) for p in points]
        return sum(k is None or not ident.is_full(k) for k in keys)

    def run(points: list[np.ndarray]) -> np.ndarray:
        """Race ``points`` against the current point; their objectives (a stopped one's partial)."""
        nonlocal spent, polls
        k = new(points)
        _, _, r = ident.evaluate(np.array(points), 5, bound=c, metric="cost", groups=0, refs=x)
        spent, polls = spent + k, polls + 1
        if progress is not None:
            progress.update(k, note=_note(ident))
        return np.sum(r**2, axis=1)

    last_step = float("nan")
    while True:
        points, offsets = _compass(x, step, lo, hi)
        if not points or spent + new(points) > budget:
            break
        costs, last_step = run(points), step
        if ident.best_cost < c:  # (the poll held a whole evaluation better than the current point)
            x, c, moves = np.array(ident.records[ident.best_key]["params"], float), ident.best_cost, moves + 1
            continue
        vertex = _vertex(x, c, offsets, costs, lo, hi)
        if vertex is not None and spent + new([vertex]) <= budget:
            run([vertex])
            if ident.best_cost < c:
                x, c, moves = np.array(ident.records[ident.best_key]["params"], float), ident.best_cost, moves + 1
        if step <= PROFILE_STEP:
            break
        step /= 2.0
    if progress is not None:  # (the budget's rest unspent)
        progress.update(0, total=spent)
    return {"evaluations": spent, "polls": polls, "moves": moves, "first_step": float(first),
            "last_step": last_step, "start_objective": float(c_start), "objective": float(c)}


def _grid(low: float, high: float, m: int, centre: float) -> np.ndarray:
    """The profile values of a parameter: ``m`` points across its bounds and the optimum's value ``centre``."""
    return np.unique(np.append(np.linspace(low, high, m), centre))


def _slices(ident: Identification, best: np.ndarray, grids: list[np.ndarray]) -> tuple[list[dict], list, np.ndarray]:
    """Each parameter along its grid, the others held at ``best`` (one fan-out, role 2): the slices
    (:func:`_profile` dicts), and the rows and residuals evaluated."""
    rows = []
    for i, g in enumerate(grids):
        for v in g:
            x = best.copy()
            x[i] = v
            rows.append(x)
    _, _, r = ident.evaluate(np.array(rows), 2)
    slices, k = [], 0
    for g in grids:
        slices.append(_profile(g, np.array(rows[k:k + len(g)]), r[k:k + len(g)], np.zeros(len(g), bool)))
        k += len(g)
    return slices, rows, r


def _profile(values: np.ndarray, x: np.ndarray, res: np.ndarray, optimised: np.ndarray) -> dict[str, np.ndarray]:
    """One parameter's profile: its ``values``, every parameter at each point ``x``, the residuals
    ``res`` there, and whether the others were re-optimised there (``optimised``)."""
    return {"value": values, "x": x, "res": res, "optimised": optimised}


def _merge(slices: list[dict], found: list[dict[float, tuple]]) -> list[dict]:
    """The slices with their re-optimised points (``found[i]``: value -> (point, residuals)) in place."""
    out = []
    for s, f in zip(slices, found):
        x, res, opt = s["x"].copy(), s["res"].copy(), s["optimised"].copy()
        for k, v in enumerate(s["value"]):
            if float(v) in f:
                x[k], res[k] = f[float(v)]
                opt[k] = True
        out.append(_profile(s["value"], x, res, opt))
    return out


def _intervals(profiles: list[dict], best: np.ndarray, within: bool) -> np.ndarray:
    """The interval of each parameter from its profile (module docstring, step 2), shape (parameters, 2)."""
    out = np.full((len(profiles), 2), np.nan)
    for i, p in enumerate(profiles):
        if within:
            out[i] = interval(p["value"], np.max(np.abs(p["res"]), axis=1), 1.0, best[i])
        else:
            cc = np.sum(p["res"]**2, axis=1)
            out[i] = interval(p["value"], cc - np.nanmin(cc), 1.0, best[i])
    return out


def _profile_arrays(profiles: list[dict], slices: list[dict], n: int) -> dict[str, np.ndarray]:
    """The profiles as padded arrays (NaN past a grid's end) for ``identify.nc``: values, objective,
    largest |residual|, every parameter at each point, the re-optimised flag and the slice's objective."""
    size = max(len(p["value"]) for p in profiles)
    out = {k: np.full((n, size), np.nan) for k in ("profile_value", "profile_cost", "profile_max", "slice_cost")}
    out["profile_points_x"] = np.full((n, size, n), np.nan)
    out["profile_optimised"] = np.zeros((n, size), bool)
    for i, (p, s) in enumerate(zip(profiles, slices)):
        k = len(p["value"])
        out["profile_value"][i, :k] = p["value"]
        out["profile_cost"][i, :k] = np.sum(p["res"]**2, axis=1)
        out["profile_max"][i, :k] = np.max(np.abs(p["res"]), axis=1)
        out["slice_cost"][i, :k] = np.sum(s["res"]**2, axis=1)
        out["profile_points_x"][i, :k] = p["x"]
        out["profile_optimised"][i, :k] = p["optimised"]
    return out


# ----------------------------------------------------------- re-optimised profiles (profile_method "optimised")
class _Walk:
    """One side of one parameter's re-optimised profile: its grid values walked outward from the optimum.

    At each value the other parameters start from a prediction (the neighbouring re-optimised point
    moved along the valley: the Gauss-Newton slope for the first step, the secant of the last two
    points after) and a compass search lowers the interval criterion's ``metric`` of the residuals
    (:meth:`candidates`, :meth:`update`): polls of +- :data:`PROFILE_STEP` of each other parameter's
    range while one finds a better point, then one point at the vertex of the parabolas through each
    coordinate's poll (finer than the step). The walk ends past the first point whose metric exceeds
    ``limit`` (outside the interval), at the grid's end, or when its parameter's budget is spent
    (:meth:`stop`). ``found``: value -> (point, residuals).
    """

    def __init__(self, i: int, values: np.ndarray, start: np.ndarray, slope: np.ndarray, lo: np.ndarray,
                 hi: np.ndarray, metric: Callable[[np.ndarray], float], limit: float,
                 slice_at: Callable[[float], tuple[np.ndarray, np.ndarray]]):
        self.i, self.values, self.slope, self.lo, self.hi = i, values, slope, lo, hi
        self.metric, self.limit, self.slice_at = metric, limit, slice_at
        self.path = [start]  # the finished points, the optimum first
        self.found: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self.k, self.done = -1, False
        #: residuals of every point this walk knows (a poll after a move meets the point it left: not asked again),
        #: and those of them stopped early by racing (partial ensembles: never the walk's point)
        self.seen: dict[tuple, np.ndarray] = {}
        self.partial: set[tuple] = set()
        self.asked: list[np.ndarray] = []  # this round's points, known ones included
        self.polls: list[tuple[int, float]] = []  # (coordinate, offset) of each poll point
        self._next()

    @property
    def value(self) -> float:
        """The profiled parameter's value at the current point."""
        return float(self.values[self.k])

    def _next(self) -> None:
        """Move to the next value, the others predicted from the last finished points."""
        self.k += 1
        if self.k >= len(self.values):
            self.done = True
            return
        prev, i = self.path[-1], self.i
        if len(self.path) < 2:
            slope = self.slope
        else:  # the secant of the last two points
            slope = (prev - self.path[-2]) / (prev[i] - self.path[-2][i])
        x = np.clip(prev + slope * (self.value - prev[i]), self.lo, self.hi)
        x[i] = self.value
        self.x, self.res, self.vertex = x, None, None
        self.slice = self.slice_at(self.value)
        self.seen[_point(self.slice[0])] = self.slice[1]

    def candidates(self) -> list[np.ndarray]:
        """The points of this round not yet known: the parabolas' vertex after a poll that found nothing
        better; else the predicted point (at a new value) and the compass poll around the current one."""
        if self.vertex is not None:
            self.asked = [self.vertex]
        else:
            poll, self.polls = _compass(self.x, PROFILE_STEP, self.lo, self.hi, skip=self.i)
            self.asked = ([self.x] if self.res is None else []) + poll
        new = {_point(p): p for p in self.asked if _point(p) not in self.seen}
        return list(new.values())

    def bound(self, p: np.ndarray) -> float:
        """The racing bound of a candidate ``p`` of this round (:meth:`Identification.evaluate`): a point is
        taken only if its metric is below the current point's (at a new value: below the slice point's,
        which the current point will be no worse than), so past that bound it may stop early. So for every
        point of a round: the polls, the predicted point (at a new value it competes with the slice point)
        and the vertex (it competes with the current point); one stopped early is not taken
        (:meth:`update`)."""
        return self.metric(self.res if self.res is not None else self.slice[1])

    def reference(self) -> np.ndarray:
        """The whole evaluation a poll point is raced against on the same DMW records: the current point (at a
        new value, the slice point)."""
        return self.x if self.res is not None else self.slice[0]

    def update(self, pts: list[np.ndarray], res: np.ndarray, full: Sequence[bool] | None = None) -> None:
        """Take the round's results (``res`` of the new points ``pts``; ``full``: whether each ran on every
        DMW record, default all): move to the best poll point if it is better (and poll again), else try the
        parabolas' vertex once, then the point is finished. At a new value the slice point (the others at
        the optimum) competes with the prediction, so a profile point is never worse than the slice's. A
        point stopped early by racing is never taken (its residuals are a partial ensemble's: it lost to
        its bound, the point it would replace), so every profile point is a whole evaluation."""
        whole = [True] * len(pts) if full is None else [bool(f) for f in full]
        self.seen.update((_point(p), r) for p, r in zip(pts, res))
        self.partial.difference_update(_point(p) for p, f in zip(pts, whole) if f)
        self.partial.update(_point(p) for p, f in zip(pts, whole) if not f)
        pts = self.asked
        res = [self.seen[_point(p)] for p in pts]
        part = np.array([_point(p) in self.partial for p in pts], bool)
        if self.vertex is not None:
            if not part[0] and self.metric(res[0]) < self.metric(self.res):
                self.x, self.res = self.vertex, res[0]
            self._finish()
            return
        moved = False
        if self.res is None:
            if not part[0]:
                self.res = res[0]
            if part[0] or self.metric(self.slice[1]) < self.metric(self.res):
                self.x, self.res, moved = self.slice[0], self.slice[1], True
            pts, res, part = pts[1:], res[1:], part[1:]
        c = np.array([self.metric(r) for r in res])
        taken = np.where(part, np.inf, c)  # (the parabolas below take a stopped poll's partial metric)
        j = int(np.nanargmin(taken)) if np.isfinite(taken).any() else -1
        if j >= 0 and taken[j] < self.metric(self.res):
            self.x, self.res = pts[j], res[j]
        elif not moved:  # (after a move to the slice point the poll was around another point: poll again)
            self.vertex = self._vertex(c)
            if self.vertex is None:
                self._finish()

    def _vertex(self, c: np.ndarray) -> np.ndarray | None:
        """:func:`_vertex` of this walk's poll (metrics ``c``) around its current point."""
        return _vertex(self.x, self.metric(self.res), self.polls, c, self.lo, self.hi)

    def _finish(self) -> None:
        """The current point is re-optimised: keep it; go on to the next value unless it is outside."""
        self.found[self.value] = (self.x, self.res)
        self.path.append(self.x)
        if self.metric(self.res) > self.limit:
            self.done = True
        else:
            self._next()

    def stop(self) -> None:
        """The budget is spent: the current point keeps the best found so far (if evaluated)."""
        if self.res is not None:
            self.found[self.value] = (self.x, self.res)
        self.done = True


def _compass(x: np.ndarray, step: float, lo: np.ndarray, hi: np.ndarray,
             skip: int = -1) -> tuple[list[np.ndarray], list[tuple[int, float]]]:
    """The compass poll around ``x``: each coordinate but ``skip`` moved by +- ``step`` of its range [1],
    kept inside the bounds (a move the bound cancels is left out). Returns the points and each one's
    (coordinate, offset) [parameter units]."""
    points, polls = [], []
    for j in range(len(x)):
        if j == skip:
            continue
        for sign in (1.0, -1.0):
            p = x.copy()
            p[j] = np.clip(p[j] + sign * step * (hi[j] - lo[j]), lo[j], hi[j])
            if p[j] != x[j]:
                points.append(p)
                polls.append((j, p[j] - x[j]))
    return points, polls


def _vertex(x: np.ndarray, c0: float, polls: list[tuple[int, float]], c: np.ndarray, lo: np.ndarray,
            hi: np.ndarray) -> np.ndarray | None:
    """The point at the vertex of the parabola through each coordinate's two poll points (``polls`` of
    :func:`_compass`, metrics ``c``) and ``x`` (metric ``c0``), where it curves upward (at most one step
    off), or None (no coordinate moves)."""
    step: dict[int, dict[float, tuple[float, float]]] = {}
    for (j, d), cj in zip(polls, c):
        step.setdefault(j, {})[np.sign(d)] = (abs(d), cj)
    v = x.copy()
    for j, s in step.items():
        if len(s) == 2 and np.isclose(s[1.0][0], s[-1.0][0]) and np.isfinite(s[1.0][1] + s[-1.0][1]):
            h, (cp, cm) = s[1.0][0], (s[1.0][1], s[-1.0][1])
            curve = cm - 2.0 * c0 + cp
            if curve > 0:
                v[j] += float(np.clip(h * (cm - cp) / (2.0 * curve), -h, h))
    v = np.clip(v, lo, hi)
    return None if np.array_equal(v, x) else v


def _point(x: np.ndarray) -> tuple[float, ...]:
    """A point's identity to 12 significant digits (a poll back to the point it left is that point, whatever
    the rounding of x + h - h; the evaluation keys round so too)."""
    return tuple(float(f"{v:.12g}") for v in x)


def _reoptimise(ident: Identification, best: np.ndarray, c_best: float, within: bool, slices: list[dict],
                slopes: np.ndarray, lo: np.ndarray, hi: np.ndarray, budget: int,
                count: Callable[[int], None], moved: float = -np.inf) -> tuple[list[dict], list, np.ndarray, np.ndarray]:
    """The re-optimised profile points of every parameter: two walks (:class:`_Walk`) per parameter,
    all advanced together, one fan-out per round (role 4; with racing, one per racing stage, the poll
    points raced against their walk's :meth:`_Walk.bound`), each parameter's walks spending at most
    ``budget`` evaluations; all stop at once when a whole evaluation's objective falls below ``moved``
    (the optimum moves there and the profiles are made again). Returns ``found`` (per parameter: value
    -> (point, residuals)), the rows and residuals evaluated and whether each is a whole evaluation.

    The walks lower the metric of the interval criterion: where the optimum is within tolerance, the
    largest |r| (the profile of "some setting of the others keeps every target within tolerance"), and
    a walk stops past the first point with a |r| > 1; else the objective, and a walk stops past the
    first point whose objective exceeds the optimum's by more than 1 (the profile minimum is at most
    the optimum's, so that point is outside too)."""
    metric = (lambda r: float(np.max(np.abs(r)))) if within else cost
    limit = 1.0 if within else c_best + 1.0

    def slice_at(i: int) -> Callable[[float], tuple[np.ndarray, np.ndarray]]:
        s = slices[i]
        return lambda v: (s["x"][s["value"] == v][0], s["res"][s["value"] == v][0])

    walks = []
    for i, s in enumerate(slices):
        g = s["value"]
        for values in (g[g < best[i]][::-1], g[g > best[i]]):
            walks.append(_Walk(i, values, best, slopes[i], lo, hi, metric, limit, slice_at(i)))
    spent = np.zeros(len(best), int)
    rows: list[np.ndarray] = []
    results: list[np.ndarray] = []
    whole: list[np.ndarray] = []
    while True:
        batch = []
        for w in walks:
            if w.done:
                continue
            pts = w.candidates()
            if spent[w.i] + len(pts) > budget:
                w.stop()
                continue
            spent[w.i] += len(pts)
            batch.append((w, pts))
        if not batch:
            break
        flat = [p for _, ps in batch for p in ps]
        bounds = [w.bound(p) for w, ps in batch for p in ps]
        walk_of = [k for k, (_, ps) in enumerate(batch) for _ in ps]  # (a walk's points race each other)
        refs = [w.reference() for w, ps in batch for _ in ps]
        if flat:
            recs, _, r = ident.evaluate(np.array(flat), 4, bound=bounds, metric="max" if within else "cost",
                                        groups=walk_of, refs=np.array(refs))
            full = np.array([ident.is_full(x["key"]) for x in recs], bool)
        else:
            r, full = np.zeros((0, len(ident.tlist))), np.zeros(0, bool)
        count(len(flat))
        rows += flat
        results.append(r)
        whole.append(full)
        if np.nanmin(np.where(full, np.sum(r**2, axis=1), np.inf), initial=np.inf) < moved:
            break
        k = 0
        for w, ps in batch:
            w.update(ps, r[k:k + len(ps)], full[k:k + len(ps)])
            k += len(ps)
    found = [{} for _ in slices]
    for w in walks:
        found[w.i].update(w.found)
    return found, rows, np.concatenate(results) if results else np.zeros((0, len(ident.tlist))), \
        np.concatenate(whole) if whole else np.zeros(0, bool)


def _valley_slopes(J: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Gauss-Newton prediction of the profiles' paths: row ``i`` is how every parameter moves per unit
    of parameter ``i`` when the others are re-optimised on the linearised residuals (``J`` in
    parameters scaled to their bounds), ``d u_o / d u_i = -(H_oo)^+ H_oi`` with ``H = J^T J``; in
    parameter units, 1 at ``i``. A direction no target sees does not move."""
    J = np.nan_to_num(J)
    H = J.T @ J
    n = len(lo)
    slopes = np.eye(n)
    for i in range(n):
        o = np.arange(n) != i
        du = -np.linalg.pinv(H[np.ix_(o, o)], rcond=1e-10) @ H[o, i]
        slopes[i, o] = du * (hi[o] - lo[o]) / (hi[i] - lo[i])
    return slopes


# ----------------------------------------------------------------------------------- correlation
def _jacobian(ident: Identification, best: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The central-difference Jacobian of the residuals at ``best`` in parameters scaled to their
    bounds (one fan-out, role 3), shape (targets, parameters)."""
    gn_pts, plus, minus = _gauss_newton_points(best, lo, hi)
    _, _, r_gn = ident.evaluate(np.array(gn_pts), 3)
    return np.stack([(r_gn[2 * i] - r_gn[2 * i + 1]) / ((plus[i] - minus[i]) / (hi[i] - lo[i]))
                     for i in range(len(best))], axis=1)


def _correlation(J: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: the Gauss-Newton correlation matrix and standard deviations [parameter units] from ``J``."""
    n = len(lo)
    JTJ = J.T @ J
    w, V = np.linalg.eigh(JTJ)
    tiny = w <= max(w.max(), 0.0) * 1e-10
    C = (V[:, ~tiny] / w[~tiny]) @ V[:, ~tiny].T
    var_u = np.diag(C).copy()
    free = np.abs(V[:, tiny]).max(axis=1) > 1e-6 if tiny.any() else np.zeros(n, bool)
    var_u[free] = np.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = C / np.sqrt(np.outer(np.diag(C), np.diag(C)))
    corr[free, :] = np.nan
    corr[:, free] = np.nan
    return corr, np.sqrt(var_u) * (hi - lo)


def _gauss_newton_points(best: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[list, np.ndarray, np.ndarray]:
    """The central-difference points of the Jacobian at ``best`` (steps of :data:`GN_STEP` of each
    parameter's range, kept inside the bounds): ``(points, plus, minus)``."""
    h = GN_STEP * (hi - lo)
    plus = np.minimum(best + h, hi)
    minus = np.maximum(best - h, lo)
    points = []
    for i in range(len(best)):
        a, b = best.copy(), best.copy()
        a[i], b[i] = plus[i], minus[i]
        points += [a, b]
    return points, plus, minus
