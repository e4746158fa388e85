"""The identification's global search and polish, and the whole method (:func:`identify`; the package's
docstring).
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from ...config.limits import POLISH_EVALUATIONS  # (the polish's budget, step 1 of the package docstring)
from ..free_parameters import Parameter
from .gauss_newton import gn_correlation
from .profiles import (PROFILE_STEP, compass_poll, parabola_vertex, profile_arrays, profile_intervals,
                       profile_rounds)
from .records import Identification, point_key, progress_note


#: The interval methods (``identify.profile_method``) and what identify.nc and the report call them.
METHODS = {"optimised": "profile, other parameters re-optimised",
           "slice": "slice, other parameters held at the optimum"}


def identify(ident: Identification, params: Sequence[Parameter], x_base: np.ndarray, cfg: dict,
             progress: Callable[..., Any] | None = None) -> dict[str, Any]:
    """Run the three steps of the package docstring from the reconstructed point ``x_base``.

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
    point of the package docstring; ``centre`` and ``centre_evaluation`` the profiles' centre.
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
    centre, centre_res, slices, profiles, J, rounds, spent = profile_rounds(ident, centre, centre_res, lo, hi, m,
                                                                             budget, progress)
    # the best point: the lowest objective of every evaluation (package docstring)
    i_best = ident.best_index
    best = np.array(ident.records[ident.best_key]["params"], float)
    best_res = ident.scores[ident.best_key][1]
    within = bool(np.all(np.abs(best_res) <= 1.0))
    criterion = "all targets within tolerance (|r| <= 1)" if within else \
        "objective within 1 of its profile minimum (the optimum misses a target, so no range keeps all within tolerance)"
    arrays = profile_arrays(profiles, slices, n)
    corr, gn_std = gn_correlation(J, lo, hi)
    pts = np.array([r["params"] for r in ident.records.values()], float)
    i_centre = int(np.argmin(np.max(np.abs(pts - centre), axis=1)))  # (the centre is an evaluated point)
    return {"best": best, "best_residuals": best_res, "best_evaluation": i_best, "within": within,
            "centre": centre, "centre_evaluation": i_centre,
            "intervals": profile_intervals(profiles, best, within),
            "slice_intervals": profile_intervals(slices, best, within),
            "criterion": criterion, "method": METHODS["optimised" if optimised else "slice"], **arrays,
            "correlation": corr, "gn_std": gn_std, "de_message": str(result.message),
            "de_generations": int(result.nit), "de_evaluations": int(result.nfev), "profile_rounds": rounds,
            "profile_optimiser_evaluations": spent, "polish": polished}


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
            progress.update(note=progress_note(ident))

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
    """The polish of step 1: a compass search over every parameter from the best point so far (package docstring).

    Each poll moves every parameter by +- ``step`` of its range (:func:`compass_poll`; one fan-out, role 5,
    raced against the current point: ``bound`` its objective, ``refs`` the point, the poll one group). A
    poll that holds a whole evaluation better than the current point (:attr:`Identification.best_cost`,
    strictly) moves there and polls again at the same step; after one that does not, the vertex of the
    parabolas through the poll (:func:`parabola_vertex`) is tried once (raced the same way), and the step halves.
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
        keys = [ident.by_point.get(point_key(p)) for p in points]
        return sum(k is None or not ident.is_full(k) for k in keys)

    def run(points: list[np.ndarray]) -> np.ndarray:
        """Race ``points`` against the current point; their objectives (a stopped one's partial)."""
        nonlocal spent, polls
        k = new(points)
        _, _, r = ident.evaluate(np.array(points), 5, bound=c, metric="cost", groups=0, refs=x)
        spent, polls = spent + k, polls + 1
        if progress is not None:
            progress.update(k, note=progress_note(ident))
        return np.sum(r**2, axis=1)

    last_step = float("nan")
    while True:
        points, offsets = compass_poll(x, step, lo, hi)
        if not points or spent + new(points) > budget:
            break
        costs, last_step = run(points), step
        if ident.best_cost < c:  # (the poll held a whole evaluation better than the current point)
            x, c, moves = np.array(ident.records[ident.best_key]["params"], float), ident.best_cost, moves + 1
            continue
        vertex = parabola_vertex(x, c, offsets, costs, lo, hi)
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
