"""The profiles of the identified parameters: slices, the re-optimised walks and the intervals.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from ..study import cost
from .gauss_newton import residual_jacobian
from .records import Identification, point_key, progress_note


#: Compass step of the re-optimised profiles, a fraction of each other parameter's range [1]: the others
#: move by it while a poll finds a better point; after a poll that finds none, one point at the vertex of
#: the parabolas through the poll (finer than the step) finishes the point. The poll starts from a
#: prediction that is exact on a quadratic objective.
PROFILE_STEP = 0.05
#: Rounds of profiles at most: a profile point better than the optimum by more than PROFILE_GAIN (in
#: the objective, the sum of squared residuals: the interval criterion's unit, so a smaller gain lies
#: within the optimum's own interval) becomes the optimum and the profiles are made again around it.
PROFILE_ROUNDS = 3
PROFILE_GAIN = 1.0


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


def profile_rounds(ident: Identification, best: np.ndarray, best_res: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                    m: int, budget: int, progress: Any | None) -> tuple:
    """Step 2 and the Jacobian of step 3, in rounds (package docstring); ``budget`` 0: slices only. Each
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
            progress.update(k, note=progress_note(ident))

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
            J = residual_jacobian(ident, best, lo, hi)  # (first: it predicts the walks' first steps)
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
            J = residual_jacobian(ident, best, lo, hi)
            count(2 * n)
        if progress is not None:  # (the budget's rest unspent, or a round that moved the optimum)
            progress.update(0, total=done[0])
        if last:
            break
        best, best_res, c_best = np.array(rows[j]), r_round[j], float(c_prof[j])
    return best, best_res, slices, profiles, J, rounds, spent


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


def profile_intervals(profiles: list[dict], best: np.ndarray, within: bool) -> np.ndarray:
    """The interval of each parameter from its profile (package docstring, step 2), shape (parameters, 2)."""
    out = np.full((len(profiles), 2), np.nan)
    for i, p in enumerate(profiles):
        if within:
            out[i] = interval(p["value"], np.max(np.abs(p["res"]), axis=1), 1.0, best[i])
        else:
            cc = np.sum(p["res"]**2, axis=1)
            out[i] = interval(p["value"], cc - np.nanmin(cc), 1.0, best[i])
    return out


def profile_arrays(profiles: list[dict], slices: list[dict], n: int) -> dict[str, np.ndarray]:
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
        self.seen[point_key(self.slice[0])] = self.slice[1]

    def candidates(self) -> list[np.ndarray]:
        """The points of this round not yet known: the parabolas' vertex after a poll that found nothing
        better; else the predicted point (at a new value) and the compass poll around the current one."""
        if self.vertex is not None:
            self.asked = [self.vertex]
        else:
            poll, self.polls = compass_poll(self.x, PROFILE_STEP, self.lo, self.hi, skip=self.i)
            self.asked = ([self.x] if self.res is None else []) + poll
        new = {point_key(p): p for p in self.asked if point_key(p) not in self.seen}
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
        self.seen.update((point_key(p), r) for p, r in zip(pts, res))
        self.partial.difference_update(point_key(p) for p, f in zip(pts, whole) if f)
        self.partial.update(point_key(p) for p, f in zip(pts, whole) if not f)
        pts = self.asked
        res = [self.seen[point_key(p)] for p in pts]
        part = np.array([point_key(p) in self.partial for p in pts], bool)
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
        """:func:`parabola_vertex` of this walk's poll (metrics ``c``) around its current point."""
        return parabola_vertex(self.x, self.metric(self.res), self.polls, c, self.lo, self.hi)

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


def compass_poll(x: np.ndarray, step: float, lo: np.ndarray, hi: np.ndarray,
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


def parabola_vertex(x: np.ndarray, c0: float, polls: list[tuple[int, float]], c: np.ndarray, lo: np.ndarray,
            hi: np.ndarray) -> np.ndarray | None:
    """The point at the vertex of the parabola through each coordinate's two poll points (``polls`` of
    :func:`compass_poll`, metrics ``c``) and ``x`` (metric ``c0``), where it curves upward (at most one step
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
