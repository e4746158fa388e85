"""The bulge table of an identification with a free pad pressure (``bulge_pads.nc``): the node tables
interpolated in ``ln p_pad`` against exact solves, the stage's key and cache, and ``hdi identify`` reading it.

Checked with real numbers: at a node the interpolated table is the node's solved table (bit for bit), and
next to one it equals it to rounding; between nodes the lift errs by at most twice the error the stage
measures half-way between them (measured 8e-6 with 5 nodes over 1.6-2.6 MPa on this coarse grid, and 1.1e-2
with the 2 end nodes); the stage's key changes with a table key and the bounds of p_pad, not with the base
p_pad nor a key of the dynamics, and an edited key rebuilds it; with p_pad fixed identify reads no node
tables (its upstream and evaluation keys are those of before), with p_pad free it names them in identify.nc.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline import candidates, evaluations, runner
from pipeline.config.scene import load_scene
from pipeline.model import bulge_pads as bp
from pipeline.model import bulge_table as bt
from pipeline.model.inputs import SimulationInputs, Source
from pipeline.runner import ensure
import twin

#: The bulge scene with the smooth Reynolds table on a very coarse grid, flying only
REYNOLDS = ['air_bearing.bulge="reynolds"', "solver.bulge_cells_per_a=8", "solver.bulge_cells_per_b=4",
            'scene.effects=["air_bearing","pitch"]', "solver.duration_ms=0.8", "solver.transient_ms=0.3"]
FREE = ('identify.parameters=[{key="air_bearing.pad_pressure_mpa", low=1.6, high=2.6}, '
        '{key="dmw.rms_nm", low=0.08, high=0.25}]')
FIXED = 'identify.parameters=[{key="dmw.rms_nm", low=0.08, high=0.25}]'


@pytest.fixture(autouse=True)
def coarse_rows(monkeypatch):
    """Table rows 2.5 nm apart (7 rows to 15 nm, not 31): the tests' tables in ~0.3 s each."""
    monkeypatch.setattr(bt, "PROTRUSION_STEP_NM", 2.5)


def _scene(repo_root, *more):
    return load_scene(repo_root / "configs" / "paper-2009-bulge.toml", [*REYNOLDS, *more])


@pytest.fixture()
def free(repo_root):
    return _scene(repo_root, FREE)


def test_nodes_are_the_solved_tables_and_the_interpolant_meets_them(free):
    pads = bp.pad_nodes(1.6, 2.6)
    # tol: geomspace's steps in ln p_pad, a few roundings of a logarithm
    np.testing.assert_allclose(np.log(pads[1:] / pads[:-1]), np.log(2.6 / 1.6) / 4, rtol=1e-12)
    stack = bp.node_tables(free, pads)
    for i in (0, 2, 4):
        exact = bt.scene_table(free.replace(air_bearing={"pad_pressure_mpa": float(pads[i])}))
        xr.testing.assert_identical(bp.table_at(stack, float(pads[i])), exact)
    # next to a node (the spline's path, not the node's table): the node's lift to rounding
    near = bp.table_at(stack, float(pads[2]) * (1 + 1e-11))
    node = bp.node(stack, 2)
    # tol: the ratio's slope in ln p_pad times 1e-11, and a few roundings of ratio x closed form
    np.testing.assert_allclose(near["bulge_lift"].values, node["bulge_lift"].values, rtol=1e-9, atol=0)
    # tol: the same through the ratio's spline slope in ln g (the stiffness), tens of roundings
    np.testing.assert_allclose(near["bulge_stiffness"].values, node["bulge_stiffness"].values, rtol=1e-8, atol=1e-12)
    # tol: the bearing number scaled by p_node / p = 1 - 1e-11
    np.testing.assert_allclose(near["bearing_number"].values, node["bearing_number"].values, rtol=1e-10)
    with pytest.raises(ValueError, match="outside the bulge table's pad nodes"):
        bp.table_at(stack, 2.7)


def test_between_nodes_the_lift_errs_within_the_measured_error(free):
    pads = bp.pad_nodes(1.6, 2.6)
    stack = bp.node_tables(free, pads)
    measured = bp.interpolation_error(stack, bp.node_tables(free, bp.check_pads(pads)))
    assert measured.max() < 2e-3 and measured.min() > 0  # (not at a node: a real interpolation)
    # other pad pressures than the checks: a third of the way between nodes, in ln p_pad
    thirds = np.exp(np.log(pads[:-1]) + np.log(pads[1:] / pads[:-1]) / 3)
    errors = bp.interpolation_error(stack, bp.node_tables(free, thirds))
    assert errors.max() <= 2 * measured.max(), (errors, measured)
    # the nodes matter: the two end nodes alone (linear) err by ~1e-2, > 100 times more
    ends = bp.node_tables(free, pads[[0, -1]])
    assert bp.interpolation_error(ends, bp.node_tables(free, bp.check_pads(pads))).max() > 100 * measured.max()


def _keys(scene, out):
    r = runner.Runner(scene, out)
    return r.key("bulge_pads"), r.key("identify")


def test_the_stage_key_holds_the_table_keys_and_the_bounds_only(free, tmp_path):
    base = _keys(free, tmp_path)
    for edit in ({"solver": {"bulge_cells_per_b": 5}}, {"tfc": {"half_width_um": 24.0}},
                 {"air_bearing": {"bulge": "rough-reynolds"}},
                 {"identify": {"parameters": [{"key": "air_bearing.pad_pressure_mpa", "low": 1.5, "high": 2.6},
                                              {"key": "dmw.rms_nm", "low": 0.08, "high": 0.25}]}}):
        new = _keys(free.replace(**edit), tmp_path)
        assert new[0] != base[0] and new[1] != base[1], edit
    for edit in ({"air_bearing": {"pad_pressure_mpa": 2.0}}, {"dmw": {"rms_nm": 0.2}}):
        new = _keys(free.replace(**edit), tmp_path)
        assert new[0] == base[0] and new[1] != base[1], edit  # (identify reads both)
    assert "air_bearing.pad_pressure_mpa" not in runner.registry()["bulge_pads"].keyed()


def test_identify_reads_node_tables_only_with_a_free_pad_pressure(repo_root, free):
    ident = runner.registry()["identify"]
    assert ident.upstream_names(free) == (*evaluations.upstream(free), "bulge_pads")
    fixed = _scene(repo_root, FIXED)
    other = _scene(repo_root, 'identify.parameters=[{key="air_bearing.pad_pressure_mpa", low=1.6, high=2.6}, '
                   '{key="tfc.half_width_um", low=20.0, high=30.0}]')  # (another table key free: solved per candidate)
    closed = free.replace(air_bearing={"bulge": "ph-limit"})  # (no table at all)
    for scene in (fixed, other, closed):
        assert evaluations.pad_bounds(scene) is None
        assert ident.upstream_names(scene) == evaluations.upstream(scene)
        assert not runner.registry()["bulge_pads"].applies(scene)
    assert evaluations.pad_bounds(free) == (1.6, 2.6)
    assert "bulge_pads" not in runner.main_job(free)


def test_an_edited_key_rebuilds_the_stage_and_a_current_one_does_not(free, tmp_path):
    out = tmp_path / "out"
    nc = ensure("bulge_pads", free, out)
    ds = xr.open_dataset(nc, engine="netcdf4").load()
    # tol: the same geomspace, written and read back as doubles
    np.testing.assert_allclose(ds.attrs["pad_nodes_mpa"], bp.pad_nodes(1.6, 2.6), rtol=1e-12)
    assert ds.sizes["pad_node"] == bp.NODES and 0 < ds.attrs["max_lift_error"] < 2e-3
    before = nc.stat().st_mtime_ns
    ensure("bulge_pads", free.replace(air_bearing={"pad_pressure_mpa": 2.0}), out)  # (not a key: current)
    assert nc.stat().st_mtime_ns == before
    edited = free.replace(solver={"bulge_cells_per_a": 10})
    ensure("bulge_pads", edited, out)
    again = xr.open_dataset(nc, engine="netcdf4").load()
    assert nc.stat().st_mtime_ns != before
    assert not np.array_equal(again["bulge_lift"].values, ds["bulge_lift"].values)


def test_a_candidate_reads_its_table_interpolated_and_a_fixed_study_solves_it(free, repo_root):
    stack = bp.node_tables(free, bp.pad_nodes(1.6, 2.6))
    pads = Source.memory("bulge_pads", stack, "pads-key")
    cand = free.replace(air_bearing={"pad_pressure_mpa": 2.05})
    with_pads = candidates.candidate_inputs(cand, SimulationInputs(bulge_pads=pads))
    xr.testing.assert_identical(with_pads.bulge_table(), bp.table_at(stack, 2.05))
    assert with_pads.bulge.key == "pads-key@2.05"
    solved = candidates.candidate_inputs(cand, SimulationInputs())
    xr.testing.assert_identical(solved.bulge_table(), bt.scene_table(cand))
    # tol: the 5-node interpolant against the exact solve (measured < 1e-5 here)
    np.testing.assert_allclose(with_pads.bulge_table()["bulge_lift"].values[1:],
                               solved.bulge_table()["bulge_lift"].values[1:], rtol=1e-4)
    # the evaluation store's base key: that of before without node tables, another with them
    plain = SimulationInputs(bulge=solved.bulge)
    assert evaluations.base_key(cand, plain) != evaluations.base_key(cand, SimulationInputs(bulge=solved.bulge,
                                                                                            bulge_pads=pads))


def _stub_batch(base, params, rows, protrusions, inputs):
    """A stand-in for the slider (the stage's outputs around the fit are tested, not the fit)."""
    return twin.stub_records(rows, protrusions, lambda x: {
        "fhm_bv": 5.0 * float(x[0]), "contact_fraction": 1.0, "min_clearance": -0.1, "contact_force": float(x[-1]),
        "interference": 0.5, "mean_pressure": 400.0})


def test_identify_names_its_interpolated_table(repo_root, tmp_path):
    scene = _scene(repo_root, FREE, 'identify.targets=["fhm_flying", "contact_force"]', "identify.population=4",
                   "identify.generations=1", "identify.profile_points=3", "identify.realisations=1")
    nc = ensure("identify", scene, tmp_path / "out", scheduler="synchronous", task=_stub_batch)
    ds = xr.open_dataset(nc, engine="netcdf4")
    # tol: the same geomspace, written and read back as doubles
    np.testing.assert_allclose(ds.attrs["bulge_pad_nodes_mpa"], bp.pad_nodes(1.6, 2.6), rtol=1e-12)
    assert ds.attrs["bulge_pad_lift_error"].max() < 2e-3 and "reynolds bulge table" in ds.attrs["bulge_table"]
    fixed = _scene(repo_root, FIXED, 'identify.targets=["fhm_flying", "contact_force"]', "identify.population=4",
                   "identify.generations=1", "identify.profile_points=3", "identify.realisations=1")
    nc = ensure("identify", fixed, tmp_path / "fixed", scheduler="synchronous", task=_stub_batch)
    assert "bulge_table" not in xr.open_dataset(nc, engine="netcdf4").attrs
    assert not (tmp_path / "fixed" / "bulge_pads.nc").exists()
