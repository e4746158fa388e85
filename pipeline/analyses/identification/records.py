"""The state of one identification: its evaluation callable, every record it returned and their scores
(:class:`Identification`), and the roles of its evaluations.
"""

from __future__ import annotations

import warnings
from typing import Any, Callable, Sequence

import numpy as np

from ..study import (ObjectiveTerm, cost, head, input_spreads, realisations_of, record_inputs,
                    residuals, score)
from .racing import Racing, metric_value


#: Role of an evaluation (``role`` variable of identify.nc).
ROLES = {0: "reconstructed", 1: "optimiser", 2: "profile", 3: "gauss-newton", 4: "profile-optimiser", 5: "polish"}


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
        #: racing: each point's key (by :func:`point_key`), the paired spreads of whole evaluations against their
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
                [self.by_point.get(point_key(y)) if np.all(np.isfinite(y)) else None
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
            self.by_point[point_key(r["params"])] = key
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
                    low[i] = high[i] = metric_value(np.abs(self.scores[key][1]), metric)
                    if refs[i] is not None and refs[i] != key and self.is_full(refs[i]):
                        self.pair_spreads.setdefault(role, []).append(
                            input_spreads(self.inputs_of(key) - self.inputs_of(refs[i])))
                    continue
                lo_t, hi_t = self._bounds(key, refs[i], role)
                low[i], high[i] = metric_value(lo_t, metric), metric_value(hi_t, metric)
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


def progress_note(ident: Identification) -> str:
    """The progress note: the best objective so far (one name: the log's last line says the same)."""
    return f"best objective {ident.best_cost:.4g}"


def point_key(x: np.ndarray) -> tuple[float, ...]:
    """A point's identity to 12 significant digits (a poll back to the point it left is that point, whatever
    the rounding of x + h - h; the evaluation keys round so too)."""
    return tuple(float(f"{v:.12g}") for v in x)
