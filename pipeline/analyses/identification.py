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
2. **Profiles**: each parameter alone across its bounds (``profile_points``), the others at the
   optimum. A profile point better than the optimum (by more than :data:`PROFILE_GAIN`) means the
   global search stopped short: it becomes the optimum and the profiles are made again around it, at
   most :data:`PROFILE_ROUNDS` rounds (``profile_rounds`` in the dataset; after the last, a better
   point is left where it is, and ``best_evaluation`` then names it, not the optimum). The interval of a parameter is the connected range around the optimum where **every target
   stays within tolerance** (all ``|r| <= 1``); when the optimum itself misses a target, that range
   does not exist and the stage reports instead the range where the objective stays within 1 of its
   profile minimum (the 68 % profile interval if tolerances were one standard deviation) and says so.
   Crossings are interpolated linearly between profile points.
3. **Correlation**: Gauss-Newton at the optimum, ``C = (J^T J)^+`` with ``J`` the central-difference
   Jacobian of the residuals in parameters scaled to their bounds (steps of 2 % of the range);
   ``corr_ij = C_ij / sqrt(C_ii C_jj)``. A direction with no curvature (a parameter no target sees)
   gives a zero eigenvalue; its variance is then reported as infinite and its correlations as NaN.

References
----------
.. [SP97] R. Storn, K. Price, "Differential evolution -- a simple and efficient heuristic for global
   optimization over continuous spaces", J. Global Optim. 11 (1997) 341-359.
"""

from __future__ import annotations

import contextlib
from typing import Any, Callable, Sequence

import numpy as np

from .study import Parameter, Target, cost, residuals

#: Role of an evaluation (``role`` variable of identify.nc).
ROLES = {0: "reconstructed", 1: "optimiser", 2: "profile", 3: "gauss-newton"}
#: Central-difference step of the Gauss-Newton Jacobian, a fraction of each parameter's range [1].
GN_STEP = 0.02
#: Rounds of profiles at most: a profile point better than the optimum by more than PROFILE_GAIN (in
#: the objective, the sum of squared residuals: the interval criterion's unit, so a smaller gain lies
#: within the optimum's own interval) becomes the optimum and the profiles are made again around it.
PROFILE_ROUNDS = 3
PROFILE_GAIN = 1.0


class Identification:
    """The state of one identification: the evaluation callable, every record it returned, and their scores.

    Parameters
    ----------
    evaluate
        ``evaluate(points) -> records``: one evaluation record per row of ``points`` (shape
        ``(n, parameters)``), as :func:`pipeline.analyses.study.residuals` reads them, each with its
        ``key`` (:class:`pipeline.evaluations.Evaluator` in ``hdi identify``).
    tlist
        The targets (:func:`pipeline.analyses.study.targets`).
    missing
        The residual of a target a record cannot produce (``identify.missing_residual``).
    """

    def __init__(self, evaluate: Callable[[np.ndarray], list[dict[str, Any]]], tlist: Sequence[Target],
                 missing: float):
        self.evaluate_points, self.tlist, self.missing = evaluate, list(tlist), missing
        #: every record asked for, by key, in request order; and the role of its first request
        self.records: dict[str, dict[str, Any]] = {}
        self.roles: dict[str, int] = {}

    @property
    def keys(self) -> list[str]:
        """The keys of every record asked for, in request order."""
        return list(self.records)

    def evaluate(self, points: np.ndarray, role: int) -> tuple[list[dict], np.ndarray, np.ndarray]:
        """Records, target values and residuals of ``points`` (shape (n, parameters))."""
        recs = self.evaluate_points(points)
        for r in recs:
            if r["key"] not in self.roles:
                self.roles[r["key"]] = role
                self.records[r["key"]] = r
        vals, res = zip(*(residuals(r, self.tlist, self.missing) for r in recs)) if recs else ((), ())
        return recs, np.array(vals).reshape(len(recs), -1), np.array(res).reshape(len(recs), -1)

    def costs(self, points: np.ndarray, role: int) -> np.ndarray:
        return np.array([cost(r) for r in self.evaluate(points, role)[2]])


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

    ``cfg``: ``generations``, ``population``, ``seed``, ``profile_points`` (``[identify]``). Returns the
    best point, its residuals, whether it is within tolerance, the intervals and their criterion, the
    profiles, the correlation and the optimiser's report (arrays, for ``identify.nc``); the records are
    in ``ident``.

    ``progress``: how the work shows itself, ``progress(total, unit=...)`` a context manager whose
    ``update(n, note=...)`` counts steps (:class:`pipeline.progress.Progress` in ``hdi identify``;
    default: nothing shown): the global search counts its generations with the best cost so far, then
    the profiles and the correlation count their evaluations (so a log shows a line at every interval
    through the whole stage, not only through the search). It only watches: the results are the same
    with or without it.
    """
    lo = np.array([p.low for p in params])
    hi = np.array([p.high for p in params])
    n = len(params)
    ident.evaluate(x_base[None, :], 0)
    inside = bool(np.all((x_base >= lo) & (x_base <= hi)))

    def objective(X: np.ndarray) -> np.ndarray:  # vectorized: X has shape (parameters, S)
        return ident.costs(np.atleast_2d(X.T), 1)

    from scipy.optimize import differential_evolution  # (here: its import is not paid by every hdi command)
    shown = progress(cfg["generations"], unit="generation") if progress else contextlib.nullcontext()
    with shown as bar:

        def generation(intermediate_result: Any) -> None:  # (scipy passes the best so far by this name)
            if bar is not None:
                bar.update(note=f"best cost {float(intermediate_result.fun):.4g}")

        result = differential_evolution(objective, list(zip(lo, hi)), strategy="best1bin",
                                        maxiter=cfg["generations"], popsize=cfg["population"], tol=0.01,
                                        seed=cfg["seed"], polish=False, init="latinhypercube",
                                        x0=x_base if inside else None, vectorized=True, updating="deferred",
                                        callback=generation)
    # the best of everything evaluated so far (the reconstruction included)
    pts, res = _all(ident, params)
    c = np.sum(res**2, axis=1)
    best = pts[int(np.nanargmin(c))]
    best_res = res[int(np.nanargmin(c))]

    # profiles; a profile point better than the optimum is the new optimum, and the profiles are
    # made again around it (at most PROFILE_ROUNDS times): the written point is the best evaluated
    m = cfg["profile_points"]
    c_best = float(np.sum(best_res**2))
    # a count of the profile and correlation evaluations (a round more raises its total as it runs)
    first = sum(len(np.unique(np.append(np.linspace(lo[i], hi[i], m), best[i]))) for i in range(n))
    counted = progress(first + 2 * n, unit="evaluation") if progress else contextlib.nullcontext()
    with counted as after:
        for rounds in range(1, PROFILE_ROUNDS + 1):
            grids = [np.unique(np.append(np.linspace(lo[i], hi[i], m), best[i])) for i in range(n)]
            rows = []
            for i, g in enumerate(grids):
                for v in g:
                    x = best.copy()
                    x[i] = v
                    rows.append(x)
            _, _, r_prof = ident.evaluate(np.array(rows), 2)
            if after is not None:
                after.update(len(rows), note=f"profiles, round {rounds}")
            c_prof = np.sum(r_prof**2, axis=1)
            j = int(np.nanargmin(c_prof)) if np.isfinite(c_prof).any() else -1
            if j < 0 or not c_prof[j] < c_best - PROFILE_GAIN or rounds == PROFILE_ROUNDS:
                break
            best, best_res, c_best = np.array(rows[j]), r_prof[j], float(c_prof[j])
        gn_pts, plus, minus = _gauss_newton_points(best, lo, hi)
        _, _, r_gn = ident.evaluate(np.array(gn_pts), 3)
        if after is not None:
            after.update(len(gn_pts), note="correlation")
    within = bool(np.all(np.abs(best_res) <= 1.0))
    size = max(len(g) for g in grids)
    prof_x = np.full((n, size), np.nan)
    prof_cost = np.full((n, size), np.nan)
    prof_max = np.full((n, size), np.nan)
    k = 0
    intervals = np.full((n, 2), np.nan)
    criterion = "all targets within tolerance (|r| <= 1)" if within else \
        "objective within 1 of its profile minimum (the optimum misses a target, so no range keeps all within tolerance)"
    for i, g in enumerate(grids):
        rr = r_prof[k:k + len(g)]
        k += len(g)
        prof_x[i, :len(g)] = g
        prof_cost[i, :len(g)] = np.sum(rr**2, axis=1)
        prof_max[i, :len(g)] = np.max(np.abs(rr), axis=1)
        if within:
            intervals[i] = interval(g, prof_max[i, :len(g)], 1.0, best[i])
        else:
            cc = prof_cost[i, :len(g)]
            intervals[i] = interval(g, cc - np.nanmin(cc), 1.0, best[i])

    # Gauss-Newton correlation (parameters scaled to their bounds; its points evaluated above)
    J = np.stack([(r_gn[2 * i] - r_gn[2 * i + 1]) / ((plus[i] - minus[i]) / (hi[i] - lo[i])) for i in range(n)],
                 axis=1)
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
    return {"best": best, "best_residuals": best_res, "within": within, "intervals": intervals,
            "criterion": criterion, "profile_value": prof_x, "profile_cost": prof_cost, "profile_max": prof_max,
            "correlation": corr, "gn_std": np.sqrt(var_u) * (hi - lo), "de_message": str(result.message),
            "de_generations": int(result.nit), "de_evaluations": int(result.nfev), "profile_rounds": rounds}


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


def _all(ident: Identification, params: Sequence[Parameter]) -> tuple[np.ndarray, np.ndarray]:
    """Parameter values and residuals of every evaluation so far (in request order)."""
    recs = list(ident.records.values())
    pts = np.array([r["params"] for r in recs])
    res = np.array([residuals(r, ident.tlist, ident.missing)[1] for r in recs])
    return pts, res
