"""The sweep slices as the report reads them (pipeline/analyses/sweep_slices.py), on hand-made sweeps whose
answers are known: the default roughness x damping combination first and the others in grid order, the first
realisation and the upward pass reported, the first protrusion in contact, a slice's title and the regime at a
protrusion on and off the grid."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import sweep_slices as ss
from pipeline.config.grid import roughness_label

X = np.array([9.0, 9.2, 9.4, 9.6])
#: Regimes of the four protrusions: flying, flying, sliding (1), bouncing (2); the sweep's regime codes.
REGIMES = np.array([0, 0, 1, 2])


def _sweep(roughness=("a", "b"), damping=(0.02, 0.05), realisations=0, direction=False) -> xr.Dataset:
    """A sweep over protrusion x roughness x damping (x realisation, x direction) whose FHM is
    ``100 r + 10 d_index + protrusion`` and whose regimes are :data:`REGIMES` at every point."""
    dims, coords = ["protrusion"], {"protrusion": X}
    shape = [X.size]
    for name, values in (("roughness", roughness), ("damping", damping)):
        if values:
            dims.append(name)
            coords[name] = list(values)
            shape.append(len(values))
    fhm = np.broadcast_to(X.reshape([-1] + [1] * (len(shape) - 1)), shape).astype(float).copy()
    if roughness:
        fhm += 100.0 * np.arange(len(roughness)).reshape([1, -1] + [1] * (len(shape) - 2))
    if damping:
        fhm += 10.0 * np.arange(len(damping)).reshape([1] * (len(shape) - 1) + [-1])
    reg = np.broadcast_to(REGIMES.reshape([-1] + [1] * (len(shape) - 1)), shape).copy()
    ds = xr.Dataset({"fhm_bv": (dims, fhm, {"units": "%"}), "regime": (dims, reg)}, coords=coords,
                    attrs={"k": 0.978, "k_source": "scene (contact.k)", "scene_roughness": "b"})
    if realisations:
        ds = xr.concat([ds + 0.0 * r if r == 0 else ds.assign(fhm_bv=ds["fhm_bv"] + 1000.0 * r)
                        for r in range(realisations)], dim="realisation")
        ds["regime"] = ds["regime"].astype(int)
    if direction:
        down = ds.assign(fhm_bv=-ds["fhm_bv"], regime=xr.zeros_like(ds["regime"]))
        ds = xr.concat([ds, down], dim=xr.DataArray(["up", "down"], dims="direction", name="direction"))
    return ds


def test_the_scenes_own_roughness_at_its_damping_comes_first_the_rest_in_grid_order():
    combos = ss.combinations(_sweep(), damping_ratio=0.05)
    labels = [(c["roughness"], c["damping"]) for c, _ in combos]
    assert labels == [("b", 0.05), ("a", 0.02), ("a", 0.05), ("b", 0.02)]
    first = combos[0][1]
    np.testing.assert_array_equal(first["fhm_bv"].values, X + 100.0 + 10.0)
    # a damping ratio off the grid: the first damping of the scene's roughness
    assert [(c["roughness"], c["damping"]) for c, _ in ss.combinations(_sweep(), 0.07)][0] == ("b", 0.02)
    # no such dimensions: one combination, labelled None
    (only, ds), = ss.combinations(_sweep(roughness=(), damping=()))
    assert only == {"roughness": None, "damping": None} and ss.combo_title(only) == "sweep"


def test_a_sweep_over_realisations_is_reported_through_the_first_and_kept_whole():
    sweep = _sweep(realisations=3)
    first, whole = ss.split_ensemble(sweep)
    assert "realisation" not in first.dims and whole.sizes["realisation"] == 3
    np.testing.assert_array_equal(first["fhm_bv"].values, _sweep()["fhm_bv"].values)
    single, none = ss.split_ensemble(_sweep())
    assert none is None and single.identical(_sweep())


def test_a_stepping_sweep_is_reported_through_its_upward_pass():
    up, _ = ss.split_ensemble(_sweep(direction=True))
    assert "direction" not in up.dims
    np.testing.assert_array_equal(up["fhm_bv"].values, _sweep()["fhm_bv"].values)
    one = ss.combinations(_sweep(direction=True))[0][1]
    assert ss.first_contact(one) == 9.4      # of the upward pass (the downward one flies everywhere here)


def test_first_contact_is_the_smallest_protrusion_sliding_or_bouncing():
    one = _sweep(roughness=(), damping=())
    assert ss.first_contact(one) == 9.4
    assert ss.first_contact(one.assign(regime=("protrusion", [0, 0, 0, 2]))) == 9.6
    assert ss.first_contact(one.assign(regime=("protrusion", [0, 0, 0, 0]))) is None
    assert ss.first_contact(one.drop_vars("regime")) is None
    with pytest.raises(ValueError, match=r"first_contact: expected the regimes of one slice on \(protrusion,\)"):
        ss.first_contact(_sweep())


def test_the_regime_at_a_protrusion_on_and_off_the_grid():
    one = _sweep(roughness=(), damping=())
    assert [ss.regime_at(one, x) for x in X] == [0, 0, 1, 2]
    assert ss.regime_at(one, 9.4 + 1e-7) == 1            # within TOL = 1e-6 nm
    assert ss.regime_at(one, 9.3) is None                 # between two grid points
    assert ss.regime_at(one.assign(regime=("protrusion", [0.0, np.nan, 1.0, 2.0])), 9.2) is None


def test_a_slice_title_states_the_statistics_a_label_does_not():
    stats = {"sigma_nm": 0.52, "summit_radius_um": 5.0, "summit_density_per_um2": 13.3}
    coords = {"roughness_sigma": ((), 0.52, {"units": "nm"}), "roughness_summit_radius": ((), 5.0, {"units": "um"}),
              "roughness_summit_density": ((), 13.3, {"units": "um-2"})}
    ds = xr.Dataset(coords=coords)
    own = roughness_label(stats)
    assert own == "sigma0.52nm_R5um_eta13.3"
    assert ss.roughness_statistics(ds, own) == ""        # the label states them already
    assert ss.roughness_statistics(ds, "afm-di-3") == "sigma 0.52 nm, R 5 um, eta 13.3 um^-2"
    assert ss.combo_title({"roughness": "afm-di-3", "damping": 0.05}, ds) == \
        "roughness `afm-di-3` (sigma 0.52 nm, R 5 um, eta 13.3 um^-2), damping ratio 0.05"
    assert ss.combo_title({"roughness": own, "damping": None}, ds) == f"roughness `{own}`"
    assert ss.roughness_statistics(xr.Dataset(), "afm-di-3") == ""   # a sweep without the coordinates


def test_scalars_and_attributes_are_nan_when_missing():
    one = _sweep(roughness=(), damping=())
    assert ss.scalar(one, "fhm_bv") == 9.0 and math.isnan(ss.scalar(one, "nothing")) and math.isnan(ss.scalar(None, "x"))
    assert ss.attr_float(one, "k") == 0.978
    assert math.isnan(ss.attr_float(one, "k_source")) and math.isnan(ss.attr_float(None, "k"))
    c = ss.SweepSlice.of(one, one)
    assert (c.fc, c.k, c.k_source) == (9.4, 0.978, "scene (contact.k)")
    np.testing.assert_array_equal(c.col("fhm_bv"), X)
    assert np.isnan(c.col("nothing")).all() and c.col("nothing").size == X.size
