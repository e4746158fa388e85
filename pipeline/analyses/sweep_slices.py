"""The roughness x damping slices of a sweep as the report reads them (pure functions on datasets).

A slice is one ``(labels, dataset)`` pair of :func:`pipeline.analyses.optimum.slices`: ``labels`` holds the
roughness set and the damping ratio [1] (``None`` when the sweep has no such dimension), the dataset
the variables over ``protrusion`` [nm].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from ..config.grid import roughness_label
from . import optimum as opt

#: Protrusions equal within this [nm] are the same grid point.
TOL = 1e-6


def split_ensemble(sweep: xr.Dataset) -> tuple[xr.Dataset, xr.Dataset | None]:
    """``(sweep, ensemble)``: a sweep over DMW realisations is reported through its first realisation
    (the scene's own record), the whole ensemble kept apart; ``ensemble`` is ``None`` for one realisation.

    A heater-stepping sweep (``sweep.protocol = "stepping"``: dim ``direction``) is reported through its
    upward pass, the experiment's approach to touchdown (:func:`upward`); both are then on ``protrusion``
    (and the slices' dims) alone, as an independent sweep is.
    """
    sweep = upward(sweep)
    if "realisation" in sweep.dims:
        return sweep.isel(realisation=0), sweep
    return sweep, None


def combinations(sweep: xr.Dataset, damping_ratio: float | None = None) -> list[tuple[dict[str, Any], xr.Dataset]]:
    """``(labels, one-slice dataset)`` per roughness x damping, the default combination first.

    The default is the scene's own roughness set (the label in the global attribute ``scene_roughness``;
    ``scene`` in sweeps written before labels were made from the values; else the first set) at
    ``damping_ratio`` [1] (the scene's ``air_bearing.damping_ratio``) when it is on the grid, else the
    first damping; the others keep grid order.
    """
    items = list(opt.slices(sweep))
    rough = [str(r) for r in sweep["roughness"].values] if "roughness" in sweep.dims else [None]
    damp = [float(d) for d in sweep["damping"].values] if "damping" in sweep.dims else [None]
    own = str(sweep.attrs.get("scene_roughness", "scene"))
    r0 = own if own in rough else rough[0]
    d0 = damp[0]
    if damping_ratio is not None and damp[0] is not None:
        close = [d for d in damp if abs(d - float(damping_ratio)) < 1e-12]
        d0 = close[0] if close else damp[0]

    def is_default(labels: dict[str, Any]) -> bool:
        return labels["roughness"] == r0 and (labels["damping"] is None or abs(labels["damping"] - d0) < 1e-12)

    items.sort(key=lambda it: 0 if is_default(it[0]) else 1)  # stable: the rest keep grid order
    return items


def upward(ds: xr.Dataset) -> xr.Dataset:
    """The upward pass of a heater-stepping sweep or slice (dim ``direction``: the heater stepped up, as in
    the experiment's approach to touchdown; the take-off and hysteresis of the downward pass stay in
    ``sweep.nc``); any other dataset unchanged."""
    return ds.sel(direction="up", drop=True) if "direction" in ds.dims else ds


def first_contact(ds: xr.Dataset) -> float | None:
    """Smallest protrusion [nm] of a slice in contact (regime 1 or 2), ``None`` when none is; of the upward
    pass for a heater-stepping slice (:func:`upward`: its ``(protrusion, direction)`` regimes were read as
    one flat list, an IndexError)."""
    if "regime" not in ds:
        return None
    ds = upward(ds)
    if ds["regime"].dims != ("protrusion",):
        raise ValueError(f"first_contact: expected the regimes of one slice on (protrusion,), got dims "
                         f"{ds['regime'].dims}")
    reg = np.asarray(ds["regime"].values)
    x = ds["protrusion"].values
    idx = np.flatnonzero((reg == 1) | (reg == 2))
    return float(x[idx].min()) if idx.size else None


#: The statistics of a roughness set in a slice's title: symbol, ``sweep.nc`` coordinate, ``[roughness]`` key.
_STATS = (("sigma", "roughness_sigma", "sigma_nm"), ("R", "roughness_summit_radius", "summit_radius_um"),
          ("eta", "roughness_summit_density", "summit_density_per_um2"))


def roughness_statistics(ds: xr.Dataset, label: str | None = None) -> str:
    """``sigma 3.43 nm, R 2.23 um, eta 11.4 um^-2`` of a one-set slice: the statistics its interface used
    (the coordinates ``roughness_sigma``, ... of ``sweep.nc``); ``""`` when the slice lacks them or when
    ``label`` is the one made from these values (:func:`pipeline.config.grid.roughness_label`: it states them)."""
    if not all(name in ds.coords and ds[name].size == 1 for _, name, _ in _STATS):
        return ""
    if label is not None and label == roughness_label({key: float(ds[name]) for _, name, key in _STATS}):
        return ""
    return ", ".join(f"{sym} {float(ds[name]):.3g} {ds[name].attrs.get('units', '')}".replace("um-2", "um^-2")
                     for sym, name, _ in _STATS)


def combo_title(labels: dict[str, Any], ds: xr.Dataset | None = None) -> str:
    """``roughness `set`, damping ratio z`` of a slice's labels (``sweep`` when it has none). With the
    slice ``ds`` of a set whose label does not state its values (an AFM set, a set named by the user),
    the statistics its interface used follow the label (:func:`roughness_statistics`)."""
    parts = []
    if labels["roughness"] is not None:
        stats = roughness_statistics(ds, str(labels["roughness"])) if ds is not None else ""
        if stats:
            parts.append(f"roughness `{labels['roughness']}` ({stats})")
        else:
            parts.append(f"roughness `{labels['roughness']}`")
    if labels["damping"] is not None:
        parts.append(f"damping ratio {labels['damping']:g}")
    return ", ".join(parts) or "sweep"


def scalar(ds: xr.Dataset | None, name: str) -> float:
    """The first value of variable ``name`` as a float (NaN when the dataset or the variable is missing)."""
    if ds is None or name not in ds:
        return math.nan
    try:
        return float(np.asarray(ds[name].values).reshape(-1)[0])
    except (TypeError, ValueError):
        return math.nan


def attr_float(ds: xr.Dataset | None, name: str) -> float:
    """Global attribute ``name`` as a float (NaN when missing or not a number)."""
    if ds is None:
        return math.nan
    try:
        return float(ds.attrs.get(name, math.nan))
    except (TypeError, ValueError):
        return math.nan


def regime_at(ds: xr.Dataset, delta: float) -> int | None:
    """Regime code of the slice at protrusion ``delta`` [nm] (``None`` off the grid or undefined)."""
    if "regime" not in ds:
        return None
    x = ds["protrusion"].values
    j = int(np.argmin(np.abs(x - delta)))
    code = float(np.asarray(ds["regime"].values).reshape(-1)[j])
    return int(code) if abs(x[j] - delta) < TOL and np.isfinite(code) else None


@dataclass(frozen=True)
class SweepSlice:
    """The default combination's sweep slice as the comparison reads it (arrays over protrusion)."""

    ds: xr.Dataset
    x: np.ndarray               # protrusion [nm]
    reg: np.ndarray             # regime code
    fhm: np.ndarray             # FHM/BV [%]
    fc: float | None            # first contact [nm]
    k: float                    # the sweep's contact criterion [1]
    k_source: str

    @classmethod
    def of(cls, ds: xr.Dataset, sweep: xr.Dataset) -> "SweepSlice":
        x = ds["protrusion"].values
        reg = np.asarray(ds["regime"].values).reshape(-1) if "regime" in ds else np.zeros(x.size, int)
        return cls(ds, x, reg, np.asarray(ds["fhm_bv"].values, float).reshape(-1), first_contact(ds),
                   attr_float(sweep, "k"), str(sweep.attrs.get("k_source", "not recorded")))

    def col(self, name: str) -> np.ndarray:
        """A variable as a flat float array (NaN when the sweep lacks it)."""
        if name not in self.ds:
            return np.full(self.x.size, np.nan)
        return np.asarray(self.ds[name].values, float).reshape(-1)
