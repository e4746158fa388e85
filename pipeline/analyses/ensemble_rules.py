"""Statistics over DMW realisations: the one home of the rules that judge a paper target on an ensemble.

A synthetic DMW record is one realisation of a random process, and one seed moves the touchdown by a
0.2-nm actuation step (docs/model.md, section "Ensembles"), so the paper's targets are judged over ``N``
realisations (``identify.realisations``, ``report.realisations``). Every function here is pure and
works on xarray data with a ``realisation`` dimension (and, where it says so, ``protrusion`` [nm]):

* :func:`touched`, :func:`touchdown_probability`: contact in the steady window, the rule of the regime
  and of the calibration (:func:`pipeline.model.outcomes.touched_in_summary`: the exact minimum
  clearance below zero), and the fraction of the realisations that touch, versus protrusion;
* :func:`crossing`: where a curve first rises through a level, interpolated linearly between the
  evaluated protrusions (the touchdown protrusion is where the probability crosses 0.5, its spread
  the crossings of :data:`SPREAD`, the 10-90 % range of the touchdown protrusions);
* :func:`median_spread` (FHM/BV: median and the 10-90 % range, robust to the one realisation that
  snaps into contact), :func:`mean_std` (the light-contact state: mean +- sample standard deviation),
  :func:`exceedance_probability` (``P(BV > 20 %)``), :func:`flying_mean` (each realisation's mean FHM
  over its flying protrusions);
* :func:`statistics`: the ensemble summaries of ``sweep.nc`` and ``ensemble.nc`` (``<name>_mean``/``_std``,
  ``touchdown_probability``) from their per-realisation variables.

Realisations without a value (NaN: a failed run, a contact quantity of a flying run) count in no
statistic; a statistic with no value at all is NaN.

Each rule is written once, on numpy arrays (the ``*_values`` functions: an ``axis`` instead of a dimension
name); the xarray functions apply them over a named dimension. The identification scores thousands of
partial ensembles in its calling process (docs/performance.md, the paragraphs on racing), so it calls the numpy
forms directly, with the same numbers to the last bit (tests/analyses/test_ensemble_rules.py).
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from ..model.outcomes import FLYING, touched_in_summary
from ..variables import ENSEMBLE, ENSEMBLE_OF, REGIME_FILL

#: The realisation dimension.
DIM = "realisation"
#: The protrusion dimension [nm].
PROTRUSION = "protrusion"
#: Quantiles [1] of the spread of a median and of the touchdown protrusion: the 10-90 % range.
SPREAD = (0.1, 0.9)
#: Probability [1] at which the touchdown probability defines the touchdown protrusion.
TOUCHDOWN_LEVEL = 0.5


def touched_values(min_clearance: np.ndarray) -> np.ndarray:
    """:func:`touched` on a numpy array: 1.0 in contact, 0.0 flying, NaN not evaluated (or not finite)."""
    v = np.asarray(min_clearance, float)
    ok = np.isfinite(v)
    return np.where(ok, touched_in_summary(np.where(ok, v, np.nan)).astype(float), np.nan)


def touched(min_clearance: xr.DataArray) -> xr.DataArray:
    """1.0 where the run is in contact in the steady window (exact minimum clearance < 0), 0.0 where it
    flies, NaN where it was not evaluated. ``min_clearance``: any unit (only its sign is read)."""
    return xr.apply_ufunc(touched_values, min_clearance)


def touchdown_probability_values(min_clearance: np.ndarray, axis: int = -1) -> np.ndarray:
    """:func:`touchdown_probability` on a numpy array, over its ``axis`` of realisations."""
    return reduce_values(touched_values(min_clearance), axis, np.nanmean)


def touchdown_probability(min_clearance: xr.DataArray, dim: str = DIM) -> xr.DataArray:
    """Fraction [1] of the realisations (over ``dim``) in contact in the steady window; NaN where no
    realisation was evaluated."""
    return _nan_reduce(touched(min_clearance), dim, np.nanmean)


def exceedance_probability(values: xr.DataArray, threshold: float, dim: str = DIM) -> xr.DataArray:
    """Fraction [1] of the realisations with a value whose value exceeds ``threshold`` (same unit),
    e.g. ``P(BV > 20 %)``; NaN where none has a value."""
    above = (values > threshold).astype(float).where(values.notnull())
    return _nan_reduce(above, dim, np.nanmean)


def mean_std_values(values: np.ndarray, axis: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """:func:`mean_std` on a numpy array, over its ``axis``."""
    return reduce_values(values, axis, np.nanmean), reduce_values(values, axis, _sample_std)


def mean_std(values: xr.DataArray, dim: str = DIM) -> tuple[xr.DataArray, xr.DataArray]:
    """Mean and sample standard deviation (ddof = 1; NaN from fewer than two values) over ``dim``,
    in the unit of ``values``."""
    return _nan_reduce(values, dim, np.nanmean), _nan_reduce(values, dim, _sample_std)


def _sample_std(a: np.ndarray, axis: int) -> np.ndarray:
    return np.nanstd(a, axis=axis, ddof=1)


def median_spread_values(values: np.ndarray, axis: int = -1,
                         q: tuple[float, float] = SPREAD) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`median_spread` on a numpy array, over its ``axis``."""
    lo, med, hi = (reduce_values(values, axis, lambda a, axis, p=p: np.nanquantile(a, p, axis=axis))
                   for p in (q[0], 0.5, q[1]))
    return med, lo, hi


def median_spread(values: xr.DataArray, dim: str = DIM,
                  q: tuple[float, float] = SPREAD) -> tuple[xr.DataArray, xr.DataArray, xr.DataArray]:
    """Median and the ``q`` quantiles (default the 10 % and 90 % ones) over ``dim``, in the unit of
    ``values`` (linear interpolation between order statistics, numpy's default)."""
    lo, med, hi = (_nan_reduce(values, dim, lambda a, axis, p=p: np.nanquantile(a, p, axis=axis))
                   for p in (q[0], 0.5, q[1]))
    return med, lo, hi


def flying_mean_values(fhm: np.ndarray, min_clearance: np.ndarray, axis: int = 0) -> np.ndarray:
    """:func:`flying_mean` on numpy arrays of one shape, over their ``axis`` of protrusions."""
    fhm = np.asarray(fhm, float)
    flying = touched_values(min_clearance) == 0.0
    return reduce_values(np.where(flying & ~np.isnan(fhm), fhm, np.nan), axis, np.nanmean)


def flying_mean(fhm: xr.DataArray, min_clearance: xr.DataArray, dim: str = PROTRUSION) -> xr.DataArray:
    """Mean of ``fhm`` over the protrusions (``dim``) where the run flies and has a value, per remaining
    index (one value per realisation); NaN for a realisation that flies nowhere. Unit of ``fhm``."""
    flying = touched(min_clearance) == 0.0
    return _nan_reduce(fhm.where(flying & fhm.notnull()), dim, np.nanmean)


def crossing_values(x: np.ndarray, y: np.ndarray, level: float) -> float:
    """:func:`crossing` of the curve ``y`` over the coordinates ``x`` (1-D numpy arrays, any order)."""
    order = np.argsort(np.asarray(x, float), kind="stable")
    x, y = np.asarray(x, float)[order], np.asarray(y, float)[order]
    ok = np.isfinite(y)
    x, y = x[ok], y[ok]
    hit = np.flatnonzero(y >= level)
    if hit.size == 0 or hit[0] == 0:
        return float("nan")
    i = int(hit[0])
    f = (level - y[i - 1]) / (y[i] - y[i - 1])
    return float(x[i - 1] + f * (x[i] - x[i - 1]))


def crossing(curve: xr.DataArray, level: float, dim: str = PROTRUSION) -> float:
    """The first ``dim`` coordinate [nm] where the 1-D ``curve`` rises through ``level``.

    Points are taken in increasing ``dim`` (NaN values skipped); at the first point ``i`` with
    ``curve >= level``, the crossing is interpolated linearly between points ``i - 1`` and ``i``.
    NaN when the curve never reaches the level, or already reaches it at its first point (the
    crossing lies below the evaluated range, not on it).
    """
    return crossing_values(curve[dim].values, curve.values, level)


def touchdown_protrusion_values(protrusions: np.ndarray, min_clearance: np.ndarray) -> tuple[float, float, float]:
    """:func:`touchdown_protrusion` on numpy arrays: ``min_clearance`` of shape (protrusion, realisation) at
    the ``protrusions`` [nm]."""
    p = touchdown_probability_values(min_clearance, axis=-1)
    return (crossing_values(protrusions, p, TOUCHDOWN_LEVEL), crossing_values(protrusions, p, SPREAD[0]),
            crossing_values(protrusions, p, SPREAD[1]))


def touchdown_protrusion(min_clearance: xr.DataArray, dim: str = DIM) -> tuple[float, float, float]:
    """Touchdown protrusion [nm] of an ensemble and its spread: the :func:`crossing` of the
    :func:`touchdown_probability` versus protrusion at :data:`TOUCHDOWN_LEVEL` and at the
    :data:`SPREAD` levels (the 10-90 % range of the realisations' touchdown protrusions when the
    probability grows monotonically). Returns ``(touchdown, low, high)``; NaN for a level not crossed
    on the evaluated protrusions."""
    p = touchdown_probability(min_clearance, dim)
    return (crossing(p, TOUCHDOWN_LEVEL), crossing(p, SPREAD[0]), crossing(p, SPREAD[1]))


def reduce_values(values: np.ndarray, axis: int, fn) -> np.ndarray:
    """``fn(array, axis=-1)`` over ``axis`` of ``values`` (moved last, as :func:`xarray.apply_ufunc` moves a
    core dimension) with the all-NaN warnings silenced (NaN is the documented result)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return fn(np.moveaxis(np.asarray(values, float), axis, -1), axis=-1)


def _nan_reduce(values: xr.DataArray, dim: str, fn) -> xr.DataArray:
    """``fn(array, axis)`` over ``dim`` with the all-NaN warnings silenced (NaN is the documented result)."""
    return xr.apply_ufunc(lambda a: reduce_values(a, -1, fn), values, input_core_dims=[[dim]])


def statistics(data: dict[str, xr.Variable]) -> dict[str, xr.Variable]:
    """Mean, standard deviation and touchdown probability over the ``realisation`` dimension.

    ``<name>_mean``/``<name>_std`` [units of name]: mean and sample standard deviation (ddof = 1) over
    the realisations with a value (``interference`` and the stresses are NaN while flying);
    ``touchdown_probability`` [1]: fraction of the realisations with a regime that are in contact at
    some time of the steady window (regime not flying), versus protrusion, roughness and damping; a
    point not computed (regime = its fill value) counts in neither, as the NaNs of the means.
    """
    out: dict[str, xr.Variable] = {}
    for name in ENSEMBLE_OF:
        if name not in data:
            continue
        v = data[name]
        # (all-NaN slices, never in contact, give NaN, as documented)
        mean, std = (x.values for x in mean_std(xr.DataArray(v).astype(float), dim=v.dims[-1]))
        dims = v.dims[:-1]
        out[name + "_mean"] = ENSEMBLE[name + "_mean"].data(mean, dims)
        out[name + "_std"] = ENSEMBLE[name + "_std"].data(std, dims)
    if "regime" in data:
        reg = np.asarray(data["regime"].values)
        computed = reg != REGIME_FILL
        with np.errstate(invalid="ignore"):  # no realisation computed: NaN
            p = np.sum(computed & (reg != FLYING), axis=-1) / np.sum(computed, axis=-1)
        out["touchdown_probability"] = ENSEMBLE["touchdown_probability"].data(p, data["regime"].dims[:-1])
    return out
