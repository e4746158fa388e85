"""The optimum-point finder (pipeline.analyses.optimum) on constructed sweeps whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import optimum as opt

F, B, S = 0, 1, 2
NAN = np.nan


def sweep(prot, regime, fhm, clearance=None, interference=None, *, dims=("protrusion",), extra=None):
    """A sweep slice; with ``dims`` including roughness/damping, those get length one."""
    n = len(prot)
    clearance = np.full(n, 1.0) if clearance is None else np.asarray(clearance, float)
    interference = np.where(np.asarray(regime) > 0, -clearance, NAN) if interference is None else \
        np.asarray(interference, float)
    shape = (n,) + (1,) * (len(dims) - 1)
    data = {
        "regime": (dims, np.asarray(regime, np.int8).reshape(shape), {"units": "1", "long_name": "regime"}),
        "fhm_bv": (dims, np.asarray(fhm, float).reshape(shape), {"units": "%", "long_name": "FHM/BV"}),
        "clearance": (dims, clearance.reshape(shape), {"units": "nm", "long_name": "clearance"}),
        "interference": (dims, interference.reshape(shape), {"units": "nm", "long_name": "interference"}),
        "mean_pressure": (dims, np.linspace(100, 200, n).reshape(shape), {"units": "MPa", "long_name": "p"}),
    }
    for name, values in (extra or {}).items():
        data[name] = (dims, np.asarray(values, float).reshape(shape), {"units": "1", "long_name": name})
    coords = {"protrusion": ("protrusion", np.asarray(prot, float), {"units": "nm", "long_name": "protrusion"})}
    if "roughness" in dims:
        coords["roughness"] = ("roughness", ["scene"])
    if "damping" in dims:
        coords["damping"] = ("damping", [0.05])
    return xr.Dataset(data, coords=coords)


# ------------------------------------------------------------------------------------------ (a) flying
def test_flying_picks_least_clearance_among_stable_flying_points():
    ds = sweep(prot=[0, 1, 2, 3, 4, 5],
               regime=[F, F, F, F, B, S],
               fhm=[9.0, 8.0, 9.9, 12.0, 5.0, 1.0],
               clearance=[5.0, 4.0, 3.0, 2.0, -0.1, -0.5])
    a = opt.flying_optimum(ds)
    # 3 nm has less clearance but FHM 12 % > 10 %; 4-5 nm are in contact
    assert a.found
    assert a.protrusion == 2.0
    assert a.values["clearance"] == 3.0
    assert a.values["fhm_bv"] == pytest.approx(9.9)
    assert a.units["clearance"] == "nm"
    assert a.candidates == 3
    assert "2 nm" in a.describe() and "clearance 3 nm" in a.describe()


def test_flying_limit_is_strict():
    ds = sweep(prot=[0, 1, 2], regime=[F, F, F], fhm=[9.0, 9.5, 10.0], clearance=[3.0, 2.0, 1.0])
    assert opt.flying_optimum(ds).protrusion == 1.0       # 10.0 % is not < 10 %
    assert opt.flying_optimum(ds, fhm_limit=10.01).protrusion == 2.0


def test_flying_tie_goes_to_smallest_protrusion_whatever_the_order():
    ds = sweep(prot=[4, 3, 2, 1], regime=[F, F, F, F], fhm=[5, 5, 5, 5], clearance=[2.0, 1.5, 1.5, 3.0])
    assert opt.flying_optimum(ds).protrusion == 2.0
    # within atol counts as a tie too
    ds2 = sweep(prot=[1, 2], regime=[F, F], fhm=[5, 5], clearance=[1.5 + 1e-12, 1.5])
    assert opt.flying_optimum(ds2).protrusion == 1.0
    assert opt.flying_optimum(ds2, atol=0.0).protrusion == 2.0


def test_flying_skips_nan_values():
    ds = sweep(prot=[0, 1, 2, 3], regime=[F, F, F, F], fhm=[5.0, NAN, 5.0, 5.0], clearance=[4.0, 0.5, NAN, 3.0])
    a = opt.flying_optimum(ds)
    assert a.protrusion == 3.0          # 1 nm has NaN FHM, 2 nm NaN clearance
    assert np.isfinite(a.values["clearance"])


def test_flying_skips_missing_regime_code():
    ds = sweep(prot=[0, 1, 2], regime=[F, -1, F], fhm=[5.0, 5.0, 5.0], clearance=[3.0, 0.1, 2.0])
    assert opt.flying_optimum(ds).protrusion == 2.0


def test_flying_none_when_every_flying_point_is_unstable():
    ds = sweep(prot=[0, 1, 2, 3], regime=[F, F, F, S], fhm=[11.7, 12.4, 13.0, 0.4], clearance=[3, 2, 1, -0.5])
    a = opt.flying_optimum(ds)
    assert not a.found and a.protrusion is None
    assert "FHM < 10 %" in a.reason and "11.7 % at 0 nm" in a.reason
    assert a.values == {}
    assert a.summary().startswith("none: ")


def test_flying_none_without_flying_points_or_regime():
    ds = sweep(prot=[0, 1], regime=[S, S], fhm=[0.5, 0.6], clearance=[-0.5, -0.6])
    assert opt.flying_optimum(ds).reason == "no flying point in the sweep"
    ds_all_nan = sweep(prot=[0, 1], regime=[F, F], fhm=[NAN, NAN], clearance=[1, 2])
    assert "NaN" in opt.flying_optimum(ds_all_nan).reason
    no_regime = sweep(prot=[0, 1], regime=[F, F], fhm=[5, 5]).drop_vars("regime")
    r = opt.flying_optimum(no_regime)
    assert not r.found and "regime" in r.reason


# ------------------------------------------------------------------------------------------ (b) sliding
def test_sliding_picks_least_interference_among_quiet_surfing_points():
    ds = sweep(prot=[7, 8, 9, 10, 11, 12],
               regime=[F, B, S, S, S, S],
               fhm=[12.0, 30.0, 2.5, 1.9, 0.5, 0.6],
               interference=[NAN, 0.1, 0.2, 0.3, 0.4, 0.35])
    b = opt.sliding_optimum(ds)
    # 8 nm bounces (excluded whatever its interference), 9 nm has BV 2.5 % >= 2 %
    assert b.protrusion == 10.0
    assert b.values["interference"] == pytest.approx(0.3)
    assert b.values["mean_pressure"] == pytest.approx(float(ds["mean_pressure"][3]))
    assert b.candidates == 3
    assert opt.sliding_optimum(ds, bv_limit=3.0).protrusion == 9.0


def test_sliding_tie_nan_and_none():
    ds = sweep(prot=[10, 9, 8, 7], regime=[S, S, S, S], fhm=[1, 1, 1, NAN], interference=[0.2, 0.2, NAN, 0.01])
    b = opt.sliding_optimum(ds)
    assert b.protrusion == 9.0          # tie 0.2 at 9 and 10 -> 9; 8 nm NaN interference; 7 nm NaN BV
    none = sweep(prot=[8, 9], regime=[S, S], fhm=[2.0, 3.0], interference=[0.1, 0.2])
    r = opt.sliding_optimum(none)
    assert not r.found and "BV < 2 %" in r.reason and "2 % at 8 nm" in r.reason
    flying_only = sweep(prot=[0, 1], regime=[F, F], fhm=[5, 5])
    assert opt.sliding_optimum(flying_only).reason == "no surfing point in the sweep"


# ------------------------------------------------------------------------------------------ slices
def test_length_one_dims_are_squeezed_and_longer_ones_refused():
    ds = sweep(prot=[0, 1, 2], regime=[F, F, S], fhm=[5, 6, 1], clearance=[2, 1, -0.5],
               dims=("protrusion", "roughness", "damping"))
    pts = opt.optimum_points(ds)
    assert pts["before_touchdown"].protrusion == 1.0
    assert pts["steady_sliding"].protrusion == 2.0
    two = xr.concat([ds, ds.assign_coords(damping=[0.1])], dim="damping")
    with pytest.raises(ValueError, match="slice"):
        opt.flying_optimum(two)
    combos = list(opt.slices(two))
    assert [c[0]["damping"] for c in combos] == [0.05, 0.1]
    assert all(opt.flying_optimum(s).protrusion == 1.0 for _, s in combos)


def test_paper_like_sweep_snap_in():
    """Flying with FHM above 10 % straight into surfing (the paper scene's pattern in this model)."""
    prot = np.round(np.arange(0, 10.01, 0.2), 9)
    regime = np.where(prot < 7.6, F, S)
    fhm = np.where(regime == F, 11.7 + 0.2 * prot, 0.36 + 0.03 * (prot - 7.6))
    interference = np.where(regime == S, 0.53 + 0.01 * (prot - 7.6), NAN)
    clearance = np.where(regime == F, 10.7 - prot, -interference)
    ds = sweep(prot, regime, fhm, clearance, interference)
    pts = opt.optimum_points(ds)
    assert not pts["before_touchdown"].found
    assert pts["steady_sliding"].protrusion == pytest.approx(7.6)
