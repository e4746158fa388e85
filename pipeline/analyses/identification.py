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

from typing import Any, Callable, Sequence

import numpy as np

from .study import ObjectiveTerm, Parameter, cost, residuals

#: Role of an evaluation (``role`` variable of identify.nc).
ROLES = {0: "reconstructed", 1: "optimiser", 2: "profile", 3: "gauss-newton", 4: "profile-optimiser"}
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

    def __init__(self, evaluate: Callable[[np.ndarray], list[dict[str, Any]]], tlist: Sequence[ObjectiveTerm],
                 missing: float):
        self.evaluate_points, self.tlist, self.missing = evaluate, list(tlist), missing
        #: every record asked for, by key, in request order; and the role of its first request
        self.records: dict[str, dict[str, Any]] = {}
        self.roles: dict[str, int] = {}
        #: target values and residuals of every record, by key, scored once when it first comes back
        self.scores: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        #: the key and objective of the best record so far (lowest objective, the first on a tie)
        self.best_key: str | None = None
        self.best_cost = float("inf")

    @property
    def keys(self) -> list[str]:
        """The keys of every record asked for, in request order."""
        return list(self.records)

    @property
    def best_index(self) -> int:
        """The request-order index (:attr:`keys`) of the best record so far."""
        return self.keys.index(self.best_key) if self.best_key is not None else -1

    def evaluate(self, points: np.ndarray, role: int) -> tuple[list[dict], np.ndarray, np.ndarray]:
        """Records, target values and residuals of ``points`` (shape (n, parameters))."""
        recs = self.evaluate_points(points)
        for r in recs:
            if r["key"] not in self.roles:
                self.roles[r["key"]] = role
                self.records[r["key"]] = r
                self.scores[r["key"]] = residuals(r, self.tlist, self.missing)
                c = cost(self.scores[r["key"]][1])
                if c < self.best_cost:  # (strictly: the first of equal objectives stays the best)
                    self.best_key, self.best_cost = r["key"], c
        vals, res = zip(*(self.scores[r["key"]] for r in recs)) if recs else ((), ())
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

    ``cfg``: ``generations``, ``population``, ``seed``, ``profile_points``, ``profile_method``
    (a key of :data:`METHODS`) and ``profile_evaluations`` (``[identify]``). Returns the best point,
    its residuals, whether it is within tolerance, the intervals, their criterion and method, the
    profiles (with the slices they started from), the correlation and the optimiser's report (arrays,
    for ``identify.nc``); the records are in ``ident``.

    ``progress``: how the work shows itself, a started :class:`pipeline.progress.Progress` (in ``hdi
    identify``; default None: nothing shown), counted in phases (:meth:`~pipeline.progress.Progress.phase`),
    each with a total fixed when it starts: the search's generations (``cfg["generations"]``), then each
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
            "profile_optimiser_evaluations": spent}


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
        count(len(rows))
        profiles = slices
        # a point this much better ends the round (a round more follows around it): not after the last round
        moved = c_best - PROFILE_GAIN if rounds < PROFILE_ROUNDS else -np.inf
        if budget and not np.nanmin(np.sum(r_round**2, axis=1), initial=np.inf) < moved:
            J = _jacobian(ident, best, lo, hi)  # (first: it predicts the walks' first steps)
            count(2 * n)
            within = bool(np.all(np.abs(best_res) <= 1.0))
            found, w_rows, w_res = _reoptimise(ident, best, c_best, within, slices, _valley_slopes(J, lo, hi),
                                               lo, hi, budget, count, moved)
            profiles = _merge(slices, found)
            spent += len(w_rows)
            rows, r_round = rows + w_rows, np.concatenate([r_round, w_res])
        c_prof = np.sum(r_round**2, axis=1)
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
        return ident.costs(np.atleast_2d(X.T), 1)

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
        #: residuals of every point this walk knows (a poll after a move meets the point it left: not asked again)
        self.seen: dict[tuple, np.ndarray] = {}
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
            self.asked = [self.x] if self.res is None else []
            self.polls = []
            for j in range(len(self.x)):
                if j == self.i:
                    continue
                for sign in (1.0, -1.0):
                    p = self.x.copy()
                    p[j] = np.clip(p[j] + sign * PROFILE_STEP * (self.hi[j] - self.lo[j]), self.lo[j], self.hi[j])
                    if p[j] != self.x[j]:
                        self.asked.append(p)
                        self.polls.append((j, p[j] - self.x[j]))
        new = {_point(p): p for p in self.asked if _point(p) not in self.seen}
        return list(new.values())

    def update(self, pts: list[np.ndarray], res: np.ndarray) -> None:
        """Take the round's results (``res`` of the new points ``pts``): move to the best poll point if
        it is better (and poll again), else try the parabolas' vertex once, then the point is finished.
        At a new value the slice point (the others at the optimum) competes with the prediction, so a
        profile point is never worse than the slice's."""
        self.seen.update((_point(p), r) for p, r in zip(pts, res))
        pts = self.asked
        res = [self.seen[_point(p)] for p in pts]
        if self.vertex is not None:
            if self.metric(res[0]) < self.metric(self.res):
                self.x, self.res = self.vertex, res[0]
            self._finish()
            return
        moved = False
        if self.res is None:
            self.res, pts, res = res[0], pts[1:], res[1:]
            if self.metric(self.slice[1]) < self.metric(self.res):
                self.x, self.res, moved = self.slice[0], self.slice[1], True
        c = np.array([self.metric(r) for r in res])
        j = int(np.nanargmin(c)) if np.isfinite(c).any() else -1
        if j >= 0 and c[j] < self.metric(self.res):
            self.x, self.res = pts[j], res[j]
        elif not moved:  # (after a move to the slice point the poll was around another point: poll again)
            self.vertex = self._vertex(c)
            if self.vertex is None:
                self._finish()

    def _vertex(self, c: np.ndarray) -> np.ndarray | None:
        """The point at the vertex of the parabola through each coordinate's two poll points (metrics
        ``c``) and the current point, where it curves upward (at most one step off), or None."""
        c0, step = self.metric(self.res), {}
        for (j, d), cj in zip(self.polls, c):
            step.setdefault(j, {})[np.sign(d)] = (abs(d), cj)
        x = self.x.copy()
        for j, s in step.items():
            if len(s) == 2 and np.isclose(s[1.0][0], s[-1.0][0]) and np.isfinite(s[1.0][1] + s[-1.0][1]):
                h, (cp, cm) = s[1.0][0], (s[1.0][1], s[-1.0][1])
                curve = cm - 2.0 * c0 + cp
                if curve > 0:
                    x[j] += float(np.clip(h * (cm - cp) / (2.0 * curve), -h, h))
        x = np.clip(x, self.lo, self.hi)
        return None if np.array_equal(x, self.x) else x

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


def _point(x: np.ndarray) -> tuple[float, ...]:
    """A point's identity to 12 significant digits (a poll back to the point it left is that point, whatever
    the rounding of x + h - h; the evaluation keys round so too)."""
    return tuple(float(f"{v:.12g}") for v in x)


def _reoptimise(ident: Identification, best: np.ndarray, c_best: float, within: bool, slices: list[dict],
                slopes: np.ndarray, lo: np.ndarray, hi: np.ndarray, budget: int,
                count: Callable[[int], None], moved: float = -np.inf) -> tuple[list[dict], list, np.ndarray]:
    """The re-optimised profile points of every parameter: two walks (:class:`_Walk`) per parameter,
    all advanced together, one fan-out per round (role 4), each parameter's walks spending at most
    ``budget`` evaluations; all stop at once when a point's objective falls below ``moved`` (the
    optimum moves there and the profiles are made again). Returns ``found`` (per parameter: value ->
    (point, residuals)) and the rows and residuals evaluated.

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
        r = ident.evaluate(np.array(flat), 4)[2] if flat else np.zeros((0, len(ident.tlist)))
        count(len(flat))
        rows += flat
        results.append(r)
        if np.nanmin(np.sum(r**2, axis=1), initial=np.inf) < moved:
            break
        k = 0
        for w, ps in batch:
            w.update(ps, r[k:k + len(ps)])
            k += len(ps)
    found = [{} for _ in slices]
    for w in walks:
        found[w.i].update(w.found)
    return found, rows, np.concatenate(results) if results else np.zeros((0, len(ident.tlist)))


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
