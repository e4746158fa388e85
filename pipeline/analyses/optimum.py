"""The two optimum operating points the paper names, found in a sweep (pure functions, no I/O).

Vakis, Lee & Polycarpou (2009) single out two operating points of a TFC slider:

(a) **just before touchdown** (:func:`flying_optimum`): the slider still flies (regime 0, no contact
    in the steady window) with a stable flying-height modulation, FHM < 10 % [paper], and the
    least clearance among such points: the read/write spacing is smallest while nothing touches;
(b) **in steady sliding** (:func:`sliding_optimum`): the bulge surfs on the lubricant (regime 2,
    in contact in >= 99 % of the window) with a small bouncing vibration, BV < 2 %, and the least
    interference among such points: the lightest steady contact, hence the lowest contact
    stresses and wear.

Both work on one roughness/damping slice of ``sweep.nc`` (variables ``regime``, ``fhm_bv`` [%],
``clearance`` [nm], ``interference`` [nm] on the ``protrusion`` [nm] coordinate); a dataset with
``roughness``/``damping`` dimensions of length one is squeezed, longer ones must be selected first
(:func:`slices` iterates over them).

Rules shared by both finders:

* a point with a NaN (or a missing regime: NaN as xarray decodes the declared ``_FillValue``) in any
  quantity the rule uses is not a candidate;
* the FHM/BV limit is strict (``fhm_bv < limit``);
* ties in the minimised quantity (equal within ``atol`` [nm]) go to the *smallest protrusion*:
  the same clearance or interference for less heater power and less thermal bulge is preferable,
  and this makes the answer independent of the grid's storage order.

When no point qualifies the result has ``protrusion = None`` and ``reason`` says why (no point in
the regime at all, or none under the FHM/BV limit, with the smallest value found).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterator

import numpy as np
import xarray as xr

from ..config.grid import TOL_NM
from ..physics import paper
from ..variables import SCALARS, TIME, Regime, regime_name

FLYING, BOUNCING, SURFING = Regime.FLYING, Regime.BOUNCING, Regime.SURFING

#: Stable-flying criterion on the FHM [%] (the paper: :data:`pipeline.physics.paper.STABLE_FHM_PERCENT`).
FHM_LIMIT = paper.STABLE_FHM_PERCENT
#: Small-bouncing criterion on the BV [%] for the steady-sliding optimum (the paper's light-contact BV,
#: :data:`pipeline.physics.paper.SLIDING_BV_MAX_PERCENT`).
BV_LIMIT = paper.SLIDING_BV_MAX_PERCENT
#: Quantities copied into :attr:`Optimum.values` when the sweep has them: every steady-window scalar
#: of the variable schema but the bulge geometry.
REPORTED = tuple(n for n in SCALARS if n != "protrusion_radius")


@dataclass
class Optimum:
    """One optimum operating point.

    Attributes
    ----------
    kind : ``"before touchdown"`` or ``"steady sliding"``
    criterion : the rule, in words
    protrusion : protrusion [nm] of the point, or ``None`` when no point qualifies
    values : the sweep's quantities at that point (dataset units: see ``units``)
    units : units of ``values``
    reason : why no point qualifies (empty when one does)
    candidates : how many points passed the regime and limit tests
    """

    kind: str
    criterion: str
    protrusion: float | None
    values: dict[str, float] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    reason: str = ""
    candidates: int = 0

    @property
    def found(self) -> bool:
        return self.protrusion is not None

    def describe(self) -> str:
        """One line: the kind, then :meth:`summary`."""
        return f"{self.kind}: {self.summary()}"

    def summary(self) -> str:
        """Where the point is and its main values, or ``none: <reason>``."""
        if not self.found:
            return f"none: {self.reason}"
        v = self.values
        parts = [f"protrusion {self.protrusion:g} nm"]
        for name, label in (("fhm_bv", "FHM/BV"), ("clearance", "clearance"), ("interference", "interference"),
                            ("mean_pressure", "mean pressure"), ("shear_stress", "shear stress"),
                            ("friction_coefficient", "friction coefficient")):
            if name in v and np.isfinite(v[name]):
                unit = self.units.get(name, "")
                unit = "" if unit in ("", "1") else (" %" if unit == "%" else f" {unit}")
                parts.append(f"{label} {v[name]:.4g}{unit}")
        return ", ".join(parts)


def one_slice(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` reduced to the ``protrusion`` dimension (length-one ``roughness``/``damping`` squeezed).

    Raises
    ------
    ValueError
        When another dimension longer than one remains, or ``protrusion`` is missing.
    """
    if "protrusion" not in ds.dims:
        raise ValueError("the sweep has no 'protrusion' dimension")
    extra = {d: n for d, n in ds.sizes.items() if d != "protrusion" and d != TIME}
    long = {d: n for d, n in extra.items() if n > 1}
    if long:
        raise ValueError(f"select one roughness/damping slice first: dimensions {long} have more than one value")
    squeeze = [d for d in extra if d in ds.dims]
    return ds.isel({d: 0 for d in squeeze}, drop=False) if squeeze else ds


def slices(ds: xr.Dataset) -> Iterator[tuple[dict[str, Any], xr.Dataset]]:
    """``(labels, slice)`` for every roughness x damping combination of a sweep (roughness-major)."""
    rough = list(ds["roughness"].values) if "roughness" in ds.dims else [None]
    damp = list(ds["damping"].values) if "damping" in ds.dims else [None]
    for r in rough:
        for d in damp:
            sel: dict[str, Any] = {}
            if r is not None:
                sel["roughness"] = r
            if d is not None:
                sel["damping"] = d
            sub = ds.sel(sel) if sel else ds
            labels = {"roughness": None if r is None else str(r), "damping": None if d is None else float(d)}
            yield labels, sub


def _column(ds: xr.Dataset, name: str, fill: float = np.nan) -> np.ndarray:
    if name not in ds:
        return np.full(ds.sizes["protrusion"], fill, dtype=float)
    return np.asarray(ds[name].values, dtype=float).reshape(-1)


def _values_at(ds: xr.Dataset, i: int) -> tuple[dict[str, float], dict[str, str]]:
    vals, units = {}, {}
    for name in REPORTED:
        if name in ds:
            vals[name] = float(np.asarray(ds[name].values).reshape(-1)[i])
            units[name] = str(ds[name].attrs.get("units", SCALARS[name].units))
    return vals, units


def _pick(protrusion: np.ndarray, key: np.ndarray, ok: np.ndarray, atol: float) -> int:
    """Index of the least ``key`` among ``ok`` (ties within ``atol`` -> smallest protrusion)."""
    idx = np.flatnonzero(ok)
    best = np.min(key[idx])
    tied = idx[key[idx] <= best + atol]
    return int(tied[np.argmin(protrusion[tied])])


def _find(ds: xr.Dataset, *, kind: str, regime: int, limit: float, minimise: str, limit_name: str,
          atol: float) -> Optimum:
    ds = one_slice(ds)
    prot = np.asarray(ds["protrusion"].values, dtype=float)
    reg = _column(ds, "regime")
    fhm = _column(ds, "fhm_bv")
    key = _column(ds, minimise)
    name = regime_name(regime)
    criterion = (f"{name} (regime {int(regime)}) with {limit_name} < {limit:g} %, least {minimise}; "
                 f"ties -> smallest protrusion")
    if "regime" not in ds:
        return Optimum(kind, criterion, None, reason="the sweep has no 'regime' variable (no contact effect)")
    in_regime = (reg == regime) & np.isfinite(prot)
    if not in_regime.any():
        return Optimum(kind, criterion, None, reason=f"no {name} point in the sweep")
    usable = in_regime & np.isfinite(fhm) & np.isfinite(key)
    if not usable.any():
        return Optimum(kind, criterion, None,
                       reason=f"every {name} point has NaN {limit_name} or {minimise}")
    ok = usable & (fhm < limit)
    if not ok.any():
        j = np.flatnonzero(usable)[np.argmin(fhm[usable])]
        return Optimum(kind, criterion, None,
                       reason=f"no {name} point has {limit_name} < {limit:g} %; the smallest is "
                              f"{fhm[j]:.3g} % at {prot[j]:g} nm")
    i = _pick(prot, key, ok, atol)
    vals, units = _values_at(ds, i)
    return Optimum(kind, criterion, float(prot[i]), vals, units, candidates=int(ok.sum()))


def flying_optimum(ds: xr.Dataset, fhm_limit: float = FHM_LIMIT, atol: float = TOL_NM) -> Optimum:
    """Optimum (a), just before touchdown: flying, FHM < ``fhm_limit`` [%], least ``clearance`` [nm].

    Parameters
    ----------
    ds : one roughness/damping slice of ``sweep.nc`` (see :func:`one_slice`)
    fhm_limit : stable-flying FHM limit [%] (the paper: 10 %)
    atol : clearances within ``atol`` [nm] of the least are ties (-> smallest protrusion)
    """
    return _find(ds, kind="before touchdown", regime=FLYING, limit=fhm_limit, minimise="clearance",
                 limit_name="FHM", atol=atol)


def sliding_optimum(ds: xr.Dataset, bv_limit: float = BV_LIMIT, atol: float = TOL_NM) -> Optimum:
    """Optimum (b), steady sliding: surfing, BV < ``bv_limit`` [%], least ``interference`` [nm].

    Parameters
    ----------
    ds : one roughness/damping slice of ``sweep.nc`` (see :func:`one_slice`)
    bv_limit : bouncing-vibration limit [%] (2 %)
    atol : interferences within ``atol`` [nm] of the least are ties (-> smallest protrusion)
    """
    return _find(ds, kind="steady sliding", regime=SURFING, limit=bv_limit, minimise="interference",
                 limit_name="BV", atol=atol)


def optimum_points(ds: xr.Dataset, fhm_limit: float = FHM_LIMIT, bv_limit: float = BV_LIMIT) -> dict[str, Optimum]:
    """Both optima of one slice: ``{"before_touchdown": ..., "steady_sliding": ...}``."""
    return {"before_touchdown": flying_optimum(ds, fhm_limit), "steady_sliding": sliding_optimum(ds, bv_limit)}
