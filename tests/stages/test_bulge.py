"""``air_bearing.bulge = "reynolds"`` end to end: the ``bulge`` stage (bulge.nc), how the model reads it into
the kernel's tabulated TFC-point slot, and how the runner caches it.

Checked with real numbers: zero lift at zero protrusion; the table tends to the p h = const limit as the
bearing number grows (the measured order); the stiffness the kernel takes from its cubic equals the
derivative of the table's lift; the protrusion interpolation against direct solves; the stage's reads;
an edited bulge key recomputes the stage and a run that reads it, an edited other key does not.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline import runner
from pipeline.config.scene import load_scene
from pipeline.io import read_dataset
from pipeline.model import bulge_table as bt
from pipeline.model import dynamics as dyn
from pipeline.model import forces as fo
from pipeline.model import scene_inputs
from pipeline.model import assembly, kernel_inputs
from pipeline.physics import bulge_bearing as bb, reynolds

NM = 1e-9
#: the bulge scene with the Reynolds table on a coarse grid (16 x 8 cells per semi-axis: its lift is within
#: 1e-3 of the default grid's, tests/physics/test_bulge_bearing.py), flying only
REYNOLDS = ['air_bearing.bulge="reynolds"', "solver.bulge_cells_per_a=16", "solver.bulge_cells_per_b=8",
            'scene.effects=["air_bearing","pitch"]']
GRID = reynolds.ReynoldsGrid(cells_per_a=16, cells_per_b=8)


@pytest.fixture(scope="module")
def bulge_scene(repo_root):
    return load_scene(repo_root / "configs" / "paper-2009-bulge.toml", REYNOLDS)


@pytest.fixture(scope="module")
def table(bulge_scene):
    """The scene's bulge.nc dataset (the stage's compute) and the model built on it."""
    ds = bt.scene_table(bulge_scene)
    return ds, assembly.build_model(bulge_scene, None, None, None, bulge=ds)


def _solve(g, delta, ds, speed=None):
    return reynolds.reynolds_solve(g, delta, p_pad=float(ds["pad_pressure"]) * 1e6, a=3e-6, b=25e-6,
                             speed=ds.attrs["disk_speed_m_s"] if speed is None else speed,
                             viscosity=bt.AIR_VISCOSITY, mean_free_path=bt.AIR_MEAN_FREE_PATH,
                             ambient_pressure=bt.AMBIENT_PRESSURE, grid=GRID)["lift"]


def test_the_stage_is_upstream_only_with_the_reynolds_law(bulge_scene):
    assert "bulge" in scene_inputs.input_stages(bulge_scene)
    for law in ("none", "ph-limit"):
        other = bulge_scene.replace(air_bearing={"bulge": law})
        assert "bulge" not in scene_inputs.input_stages(other)
        assert "bulge" not in runner.main_job(other)
    assert "bulge" in runner.main_job(bulge_scene)
    with pytest.raises(ValueError, match="needs the bulge table"):
        assembly.build_model(bulge_scene, None, None, None)


def test_zero_lift_at_zero_protrusion(table):
    ds, model = table
    assert np.all(ds["bulge_lift"].values[0] == 0.0) and ds["protrusion"].values[0] == 0.0
    coefficients, _, _ = kernel_inputs.tfc_table(model, 0.0)
    assert np.all(coefficients == 0.0)
    # and it grows from zero: 1e-3 of the 10-nm lift at 0.01 nm, at the TFC gap of the nominal attitude
    fh0 = model.p.FH0
    lift = [float(bb.table_lift(bt.from_dataset(ds), fh0 - d, d)[0]) for d in (0.01 * NM, 10 * NM)]
    assert 0 < lift[0] < 1e-3 * lift[1]


def test_kernel_stiffness_is_the_derivative_of_the_table_lift(table):
    """The kernel takes force and stiffness from one cubic through the law sampled on 4001 gaps
    (:func:`pipeline.model.kernel_inputs.tfc_table`): against the table's lift and its central difference,
    measured within 2e-10 (force) and 2.5e-7 (stiffness) relative over 0.5-19.5 nm, between table rows
    (9.7 nm) and on one (10 nm); and the table's own stiffness variable at its nodes."""
    ds, model = table
    lt = bt.from_dataset(ds)
    g = np.linspace(0.5, 19.5, 39) * NM
    for delta in (9.7 * NM, 10.0 * NM, 4.3 * NM):
        c, x0, h = kernel_inputs.tfc_table(model, delta)
        p = dyn.with_values(model.p, delta=delta, tfc_x0=x0, tfc_h=h)
        kernel = np.array([fo.tfc_air_force(p, None, c, gi) for gi in g])
        F = bb.table_lift(lt, g, delta)[0]
        eps = 1e-4 * g
        fd = -(bb.table_lift(lt, g + eps, delta)[0] - bb.table_lift(lt, g - eps, delta)[0]) / (2 * eps)
        # tol: the kernel's compiled table reading against table_lift's, a few roundings
        np.testing.assert_allclose(kernel[:, 0], F, rtol=1e-9)
        np.testing.assert_allclose(kernel[:, 1], fd, rtol=1e-6)
        assert np.all(kernel[:, 1] > 0)  # the lift grows as the gap closes
    i = int(np.argmin(np.abs(ds["protrusion"].values - 10.0)))
    nodes = ds["apex_gap"].values[3:-3] * NM
    k_table = ds["bulge_stiffness"].values[i, 3:-3]
    # tol: the spline's slope at its nodes against the stored stiffness, tens of roundings of the slope
    np.testing.assert_allclose(bb.table_lift(lt, nodes, 10.0 * NM)[1], k_table, rtol=1e-9)


def test_protrusion_interpolation_error_against_direct_solves(table):
    """Between rows (0.5 nm apart) the ratio to the closed form is interpolated linearly: against direct
    solves on the same grid the lift errs by at most 1.2e-4 relative (measured 1.8e-5 at 2.25 nm to
    1.1e-4 at 12.25 nm over gaps 0.5-5 nm), well below the solver's own discretisation error."""
    ds, _ = table
    lt = bt.from_dataset(ds)
    g = np.array([0.5, 1.0, 1.5, 2.0, 3.0, 5.0]) * NM
    errors = []
    for dl in (2.25, 6.25, 9.75, 12.25):
        errors.append(np.abs(bb.table_lift(lt, g, dl * NM)[0] / _solve(g, dl * NM, ds) - 1).max())
    assert max(errors) < 2e-4, errors
    assert errors[0] < errors[-1]  # the ratio bends more at deep protrusions


def test_table_tends_to_the_ph_limit_as_the_bearing_number_grows(table):
    """Raising the disk speed raises the bearing number ``6 mu U a/(p_pad h_pad^2)``; the tabulated lift's
    largest deviation from the p h = const closed form over gaps 0.5-5 nm and protrusions 5-11 nm then
    falls like ``U^-n``: measured n = 1.7-2.3 per doubling (the O(1/Lambda) correction is odd along the
    sliding direction and integrates to ~0) until it meets the 16-cell grid's own error (~1e-4)."""
    ds, _ = table
    U = ds.attrs["disk_speed_m_s"]
    gaps = np.geomspace(0.5, 5.0, 6) * NM
    dls = np.array([0.0, 5.0, 8.0, 11.0]) * NM
    dev = []
    for s in (0.25, 0.5, 1.0, 2.0):
        t = bt.bulge_table(model="reynolds", p_pad=3e6, a=3e-6, b=25e-6, speed=s * U, gaps=gaps, protrusions=dls,
                           grid=GRID)
        dev.append(np.abs(t["bulge_lift"].values[1:] / t["bulge_lift_ph_limit"].values[1:] - 1).max())
    dev = np.array(dev)
    order = np.log2(dev[:-1] / dev[1:])
    assert np.all(dev[1:] < dev[:-1]), dev
    assert np.all(order[:2] > 1.4), order


def test_the_stage_reads_only_what_it_declares(bulge_scene, tmp_path):
    """The table computed on the scene as the stage may read it (any other key raises)."""
    stage = runner.registry()["bulge"]
    scene = bulge_scene.replace(solver={"bulge_cells_per_a": 8, "bulge_cells_per_b": 4})
    ds = stage.compute(stage.view(scene), runner.Inputs.folder(tmp_path))
    assert ds.sizes["protrusion"] == 31  # (0-15 nm by 0.5 nm: table_stop_nm)
    assert "air_bearing.pad_pressure_mpa" in stage.reads and "tfc.protrusion_nm" in stage.unkeyed


def test_an_edited_bulge_key_recomputes_the_stage_and_the_run(write_scene, repo_root, tmp_path):
    """The scene file edited in place: a new pad pressure recomputes bulge.nc and the simulation that
    reads it (which then flies higher); a solver key of the dynamics recomputes the simulation only."""
    base = repo_root / "configs" / "paper-2009-bulge.toml"

    def scene_text(p_pad: float, duration: float) -> str:
        return (f'[scene]\nname = "reyn"\nextends = "{base}"\neffects = ["air_bearing", "pitch"]\n'
                f'[air_bearing]\nbulge = "reynolds"\npad_pressure_mpa = {p_pad}\n'
                f'[tfc]\nprotrusion_nm = 9.0\n'
                f'[solver]\nbulge_cells_per_a = 8\nbulge_cells_per_b = 4\nduration_ms = {duration}\n'
                f'transient_ms = 0.1\n')

    path = write_scene(scene_text(3.0, 0.3))
    out = tmp_path / "out"

    def run() -> tuple[str, int, float]:
        runner.build("simulate", load_scene(path), out)
        ds = read_dataset(out / "bulge.nc")
        sep = float(read_dataset(out / "summary.nc")["clearance"].values[0])
        return ds.attrs[runner.KEY_ATTR], (out / "bulge.nc").stat().st_mtime_ns, sep

    key1, mtime1, sep1 = run()
    assert float(read_dataset(out / "bulge.nc")["pad_pressure"]) == 3.0
    path.write_text(scene_text(1.0, 0.3))                       # same file, a bulge key changed
    key2, mtime2, sep2 = run()
    assert key2 != key1 and mtime2 != mtime1
    assert float(read_dataset(out / "bulge.nc")["pad_pressure"]) == 1.0
    assert sep2 < sep1 - 0.3                                    # less lift, lower flight (measured 0.7 nm)
    path.write_text(scene_text(1.0, 0.35))                      # a key the table does not read
    key3, mtime3, _ = run()
    assert (key3, mtime3) == (key2, mtime2)
    hist = read_dataset(out / "summary.nc")
    assert hist.attrs.get(runner.KEY_ATTR) and "bulge" in hist.attrs["upstream_keys"]


def test_the_accuracy_stage_runs_the_reynolds_scene(bulge_scene, tmp_path):
    """The accuracy stage reads the bulge table too (its runs are the scene's model): one knob, one
    point, every run integrated and within 1 % of the reference (measured 4e-5 at rtol 1e-8 and 8e-4 at
    1e-6, the FHM of a 0.3-ms window)."""
    scene = bulge_scene.replace(solver={"duration_ms": 0.4, "transient_ms": 0.1, "bulge_cells_per_a": 8,
                                        "bulge_cells_per_b": 4},
                                scene={"effects": ["air_bearing", "pitch", "dmw"]})  # (an FHM to compare)
    assert "bulge" in runner.Runner(scene, tmp_path).plan(["accuracy"])
    path = runner.ensure("accuracy", scene, tmp_path, points={"flying": 9.0}, knobs={"rtol": [1e-8, 1e-6]},
                         only=["rtol"], repeat=1)
    ds = read_dataset(path)
    assert "bulge" in ds.attrs["upstream_keys"]
    assert not ds["failed"].values.any()
    err = ds["max_error"].values
    assert np.isfinite(err).any() and np.nanmax(err) < 1e-2
