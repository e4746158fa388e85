"""Assembling sweep.nc and sweep_histories.nc from the sweep's parts (pipeline/analyses/sweep_assembly.py): each
part's values in its batch's slots, datasets that do not depend on the order the parts arrive in, the
roughness sets' statistics as coordinates."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses.sweep_assembly import ROUGHNESS_COORDINATES, Assembler, roughness_coordinates
from pipeline.config.grid import damping_grid, protrusion_grid, roughness_sets
from pipeline.model.simulation import simulate
from pipeline.model.sweep_parts import Batch
from slider_scenes import ALL, build, make_scene

SHORT = {"duration_ms": 0.3, "transient_ms": 0.1}
SWEEP = {"protrusion_nm": {"start": 4.0, "stop": 10.0, "step": 3.0}, "damping_ratio": [0.05, 0.1],
         "histories_nm": [10.0]}
#: Statistics of a set as its interface model used them (pipeline.model.interface_tables.used_statistics).
STATS = {"sigma_nm": 0.5, "summit_radius_um": 5.0, "summit_density_per_um2": 13.3, "plasticity_index": 0.5,
         "y_s_nm": 0.69, "source": "explicit"}


@pytest.fixture(scope="module")
def parts():
    """The scene, its grid, batches of two protrusions and one (one damping ratio each) and their parts."""
    scene = make_scene(ALL, solver=SHORT, sweep=SWEEP)
    model = build(scene)
    prot, labels, damp = protrusion_grid(scene), list(roughness_sets(scene)), damping_grid(scene)
    batches, made = [], {}
    for d, idx in itertools.product(damp, [(0, 1), (2,)]):
        b = Batch(len(batches), labels[0], float(d), idx, tuple(float(prot[i]) for i in idx))
        batches.append(b)
        # (the model's damping is the scene's: what is assembled is the parts' numbers, whichever they are)
        made[b.index] = simulate(model, b.protrusions, histories=(10.0,))
    return scene, prot, labels, damp, batches, made


def _assemble(parts, order):
    scene, prot, labels, damp, batches, made = parts
    grid = Assembler(scene, prot, labels, damp)
    for b in order:
        grid.add(b, made[b.index])
    assert grid.added == {b.index for b in batches}
    return grid.datasets("key", "calibration", {"note": "x"}, statistics={label: STATS for label in labels})


def test_each_part_fills_its_batch_slots_and_the_order_of_the_parts_does_not_matter(parts):
    scene, prot, labels, damp, batches, made = parts
    forward = _assemble(parts, batches)
    backward = _assemble(parts, batches[::-1])
    for name in ("sweep.nc", "sweep_histories.nc"):
        xr.testing.assert_identical(forward[name], backward[name])
        assert list(forward[name].data_vars) == list(backward[name].data_vars)
    ds, hist = forward["sweep.nc"], forward["sweep_histories.nc"]
    assert ds["fhm_bv"].dims == ("protrusion", "roughness", "damping")
    np.testing.assert_array_equal(ds["protrusion"].values, prot)
    # the variables in the order the first batch's part holds them
    assert list(ds.data_vars) == [n for n in made[0].data_vars if not n.startswith("h_")]
    for b in batches:
        d = damp.index(b.damping)
        for name in ("fhm_bv", "clearance", "regime"):
            got = ds[name].values[list(b.indices), 0, d]
            np.testing.assert_array_equal(got, made[b.index][name].values.astype(float))
    # the histories: the one history protrusion, from the batch that holds it, per damping ratio
    assert hist["separation"].dims == ("protrusion", "roughness", "damping", "elapsed_time")
    np.testing.assert_array_equal(hist["protrusion"].values, [10.0])
    for b in (b for b in batches if 2 in b.indices):
        np.testing.assert_array_equal(hist["separation"].values[0, 0, damp.index(b.damping)],
                                      made[b.index]["h_separation"].values[0])
    assert ds.attrs["note"] == "x" and ds.attrs["k_source"] == "calibration" and hist.attrs["k_source"] == "calibration"
    assert ds.attrs["scene_roughness"] == labels[0]


def test_a_grid_slot_without_a_part_is_missing_and_histories_need_a_part_that_keeps_them(parts):
    scene, prot, labels, damp, batches, made = parts
    grid = Assembler(scene, prot, labels, damp)
    grid.add(batches[0], made[0].drop_vars([n for n in made[0].variables if n.startswith("h_")] +
                                           ["hist_protrusion", "elapsed_time"], errors="ignore"))
    out = grid.datasets("key", "calibration", {}, statistics={label: STATS for label in labels})
    assert out["sweep_histories.nc"] is None
    fhm = out["sweep.nc"]["fhm_bv"].values
    assert np.isfinite(fhm[[0, 1], 0, 0]).all() and np.isnan(fhm[2, 0, 0]) and np.isnan(fhm[:, 0, 1]).all()


def test_the_roughness_coordinates_are_the_statistics_each_set_used():
    coords = roughness_coordinates([STATS, {**STATS, "sigma_nm": 0.8, "plasticity_index": 0.9}])
    assert set(coords) == set(ROUGHNESS_COORDINATES)
    np.testing.assert_array_equal(coords["roughness_sigma"].values, [0.5, 0.8])
    np.testing.assert_array_equal(coords["roughness_plasticity_index"].values, [0.5, 0.9])
    np.testing.assert_array_equal(coords["roughness_summit_density"].values, [13.3, 13.3])
    assert coords["roughness_sigma"].attrs["units"] == "nm" and coords["roughness_sigma"].dims == ("roughness",)
