"""Racing the candidates over the DMW records: the stages of record counts and the confidence bounds of a
metric of the residuals (docs/model.md, section "Identification", "Racing").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np



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
    return metric_value(low, metric)


def upper_bound(res: np.ndarray, margin: np.ndarray, metric: str) -> float:
    """The upper confidence bound of the metric (:func:`lower_bound`): each ``|r|`` raised by its margin."""
    high = np.abs(np.asarray(res, float)) + margin
    return metric_value(np.where(np.isnan(high), np.inf, high), metric)


def metric_value(r: np.ndarray, metric: str) -> float:
    return float(np.max(r, initial=0.0)) if metric == "max" else float(np.sum(r**2))
