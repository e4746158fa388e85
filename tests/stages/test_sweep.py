"""The calibration and the dask sweep: calibrated touchdown, determinism, resuming, bad grids."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from pipeline.model import assembly, outcomes
from pipeline.io import read_dataset
from pipeline.config.scene import SceneError, load_scene
from pipeline.analyses import calibration
from pipeline.analyses.sweep_assembly import Assembler
from pipeline.stages import sweep as sweep_stage
from pipeline.stages.simulate import model_inputs
from pipeline.model.inputs import from_folder
from pipeline.model.sweep_parts import part_problem, read_part
from pipeline.config.grid import roughness_label, roughness_sets, scene_label
from pipeline import encoding, runner
from pipeline.runner import ensure

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"

# A scene where the criterion decides touchdown: without adhesion there is no snap-in, so a k
# exists that puts contact at the touchdown and not one step below (the paper's procedure, docs/model.md,
# section "Contact criterion"). Its touchdown is 9.6 nm (none at 9.4 nm): at the paper's 9.8 nm the admissible
# interval, (-0.2179, 0.1668], has its middle below the physical bound k >= 0; here it is (0.1668, 0.5514].
FAST = [
    'scene.effects=["air_bearing","pitch","dmw","contact","friction"]',
    "solver.duration_ms=1.0",
    "solver.transient_ms=0.3",
    "touchdown.curve_points=3",
    "touchdown.onset_nm=9.6",
    "touchdown.previous_nm=9.4",
    "sweep.protrusion_nm={start=9.0, stop=10.4, step=0.2}",
    "sweep.batch_size=3",
]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    out = tmp_path_factory.mktemp("cal")
    scene = load_scene(PAPER, FAST)
    ensure("calibrate", scene, out)
    return scene, out


def _values(path: Path) -> xr.Dataset:
    """The dataset without its ``history`` attribute (the one attribute that records when it was made)."""
    ds = read_dataset(path)
    del ds.attrs["history"]
    return ds


def _copy_inputs(src: Path, dst: Path) -> None:
    dst.mkdir(parents=True, exist_ok=True)
    for name in ("calibration.nc", "dmw.nc", "interface.nc"):
        if (src / name).is_file():
            (dst / name).write_bytes((src / name).read_bytes())


def test_calibration_interval_ends_are_where_full_runs_start_touching(calibrated):
    """The ends of the admissible interval are contact thresholds of full runs with the contact law on.

    The exact method finds k*(onset) = k_low and k*(previous) = k_high from flying runs (contact law
    off); here :func:`calibrate.touches` runs the full model: at 9.6 nm it touches just above k_low and
    not just below, at 9.4 nm likewise around k_high. (That the chosen k puts the sweep's first
    contact at 9.6 nm is test_calibrated_k_puts_first_contact_at_touchdown.)
    """
    scene, out = calibrated
    cal = read_dataset(out / "calibration.nc")
    k, lo, hi = float(cal.k_calibrated), float(cal.k_low), float(cal.k_high)
    assert lo < k < hi
    tol = float(cal.attrs["k_tolerance"])          # bisection resolves k* to within tol (exact: to 0)
    assert hi - lo > 4 * tol                         # the probes below stay inside the interval
    interface, record = model_inputs(scene, out)
    model = assembly.build_model(scene, interface, record, k=0.0)
    td = scene["touchdown"]
    for delta, k_star in ((td["onset_nm"], lo), (td["previous_nm"], hi)):
        assert calibration.touches(model, delta, k_star + tol), (delta, k_star)
        assert not calibration.touches(model, delta, k_star - tol), (delta, k_star)
    # the probabilities against scipy's normal tail (the paper's convention is two-sided)
    from scipy.stats import norm
    # tol: scipy's ndtr both ways, a few roundings
    assert float(cal.contact_probability_one_sided) == pytest.approx(norm.sf(k), rel=1e-12)
    # tol: scipy's ndtr both ways, a few roundings
    assert float(cal.contact_probability_two_sided) == pytest.approx(2 * norm.sf(abs(k)), rel=1e-12)


def test_calibrated_k_puts_first_contact_at_touchdown(calibrated, tmp_path):
    """The sweep's first contact falls exactly at the scene's touchdown (9.6 nm), none at 9.4 nm."""
    scene, out = calibrated
    onset, previous = scene["touchdown"]["onset_nm"], scene["touchdown"]["previous_nm"]
    _copy_inputs(out, tmp_path)
    path = sweep_stage.run_sweep(scene, tmp_path, scheduler="synchronous")
    ds = read_dataset(path)
    regime = ds.regime.isel(roughness=0, damping=0)
    touching = regime.protrusion.values[regime.values != outcomes.FLYING]
    assert touching.min() == pytest.approx(onset) == 9.6
    assert float(ds.min_clearance.isel(roughness=0, damping=0).sel(protrusion=previous)) > 0
    assert float(ds.min_clearance.isel(roughness=0, damping=0).sel(protrusion=onset)) < 0
    assert "calibration" in ds.attrs["k_source"]


def test_uncalibratable_scene_writes_no_k(tmp_path):
    """The paper scene with adhesion snaps in below 9.6 nm: no k, and the outcome says why."""
    scene = load_scene(PAPER, ["solver.duration_ms=1.0", "solver.transient_ms=0.3", "touchdown.curve_points=2"])
    ensure("calibrate", scene, tmp_path)
    cal = read_dataset(tmp_path / "calibration.nc")
    assert np.isnan(float(cal.k_calibrated))
    assert "no admissible k" in cal.attrs["outcome"]
    assert "snap-in" in cal.attrs["outcome"] or "every k" in cal.attrs["outcome"]


def test_two_workers_equal_synchronous_bit_for_bit(calibrated, tmp_path):
    scene, out = calibrated
    a, b = tmp_path / "sync", tmp_path / "dask"
    _copy_inputs(out, a)
    _copy_inputs(out, b)
    pa = sweep_stage.run_sweep(scene, a, scheduler="synchronous")
    pb = sweep_stage.run_sweep(scene, b, workers=2)
    xr.testing.assert_identical(_values(pa), _values(pb))


#: Statistics for :meth:`Assembler.datasets` where only the data variables are compared
_STATS = {"sigma_nm": 0.5, "summit_radius_um": 5.0, "summit_density_per_um2": 13.3, "plasticity_index": 0.5}


def test_other_sets_tables_are_fanned_out_and_the_result_does_not_depend_on_workers(calibrated, tmp_path,
                                                                                  monkeypatch):
    """Another roughness set's interface tables are a task of the sweep's fan-out, in a first
    round alternating with the batches that do not read them, that set's batches in a second round; the
    parts are assembled as they arrive. 2 workers give the 1-worker datasets exactly, and sweep.nc holds
    what the parts assembled in one go in batch order hold, variables in the same order."""
    scene_, out = calibrated
    scene = load_scene(PAPER, FAST + ['sweep.roughness=["scene", {label="rough", sigma_nm=0.8}]',
                                      "sweep.histories_nm=[9.2, 10.0]"])
    own = scene_label(scene)
    rounds: list[list[tuple[str, str]]] = []
    real = sweep_stage.run_tasks

    def spy(fn, tasks, **kw):
        tasks = list(tasks)
        rounds.append([(t[0], t[1] if t[0] == "tables" else t[2].label) for t in tasks])
        return real(fn, tasks, **kw)

    monkeypatch.setattr(sweep_stage, "run_tasks", spy)
    paths = {}
    for n in (1, 2):
        _copy_inputs(out, tmp_path / str(n))
        paths[n] = sweep_stage.run_sweep(scene, tmp_path / str(n), workers=n)
    batches = sweep_stage.plan(scene)[3]
    per_set = len(batches) // 2
    assert per_set == 3
    expected = [[("tables", "rough"), ("batch", own), ("batch", own), ("batch", own)], [("batch", "rough")] * per_set]
    assert rounds == expected * 2
    assert (tmp_path / "2" / sweep_stage.PARTS / "interface-rough" / "interface.nc").is_file()
    xr.testing.assert_identical(_values(paths[1]), _values(paths[2]))
    h1, h2 = (read_dataset(p.parent / "sweep_histories.nc") for p in paths.values())
    del h1.attrs["history"], h2.attrs["history"]
    xr.testing.assert_identical(h1, h2)
    # the parts assembled in one go, in batch order, and in reverse order
    prot, sets, damp, _ = sweep_stage.plan(scene)
    made = {}
    for order in (batches, batches[::-1]):
        grid = Assembler(scene, prot, list(sets), damp)
        for b in order:
            grid.add(b, read_part(tmp_path / "1" / sweep_stage.PARTS / f"batch-{b.index:05d}.nc"))
        made[order[0].index] = grid.datasets("k", "calibration", {}, statistics={label: _STATS for label in sets})
    xr.testing.assert_identical(made[0]["sweep.nc"], made[batches[-1].index]["sweep.nc"])
    xr.testing.assert_identical(made[0]["sweep_histories.nc"], made[batches[-1].index]["sweep_histories.nc"])
    written = read_dataset(paths[1])
    names = list(made[0]["sweep.nc"].data_vars)
    assert names == [n for n in written.data_vars if n in names] and len(names) > 10
    for name in names:
        np.testing.assert_array_equal(made[0]["sweep.nc"][name].values, written[name].values)


@pytest.mark.parametrize("protocol", ["independent", "stepping"])
def test_a_batch_writes_its_part_uncompressed_and_it_reads_back_as_the_batch(calibrated, tmp_path, protocol):
    """:func:`sweep_stage.run_batch` writes its batch's dataset as a part file (the format:
    tests/model/test_sweep_parts.py) that reads back as that dataset, is accepted for its batch, and is stored
    uncompressed and contiguous (a working file, read back once if ever)."""
    scene, out = calibrated
    scene = scene.replace(sweep={"protocol": protocol})
    batch = sweep_stage.plan(scene)[3][0]
    sim = from_folder(scene, out)
    path = tmp_path / "batch-00000.nc"
    _, ds = sweep_stage.run_batch(scene, batch, sim, str(path), "key", (9.0, 10.0))
    assert "h_separation" in ds and len(ds.data_vars) > 20
    back = read_part(path)
    xr.testing.assert_identical(back.drop_attrs(), ds.drop_attrs())
    assert all(back.attrs[key] == value for key, value in ds.attrs.items())
    assert part_problem(path, "key", batch) is None
    # stored uncompressed (a working file; the histories' stack is far above encoding.COMPRESS_FROM)
    with netCDF4.Dataset(path) as nc:
        stacks = [v for name, v in nc.variables.items() if name.startswith("stack__")]
        assert max(int(np.prod(v.shape)) * v.dtype.itemsize for v in stacks) > 100 * encoding.COMPRESS_FROM
        assert all(v.chunking() == "contiguous" and not (v.filters() or {}).get("zlib") for v in stacks)


def test_several_workers_start_the_batches_of_the_highest_protrusions_first(calibrated):
    """The batches reaching the top of the grid (in contact: the longest) start first, ties in batch order,
    so a round ends with short batches; every batch is started once."""
    scene, _ = calibrated
    batches = sweep_stage.plan(scene.replace(sweep={"damping_ratio": [0.02, 0.05]}))[3]
    order = sweep_stage.costliest_first(batches)
    assert sorted(b.index for b in order) == [b.index for b in batches]
    tops = [max(b.protrusions) for b in order]
    assert tops == sorted(tops, reverse=True) and tops[0] == pytest.approx(10.4) and tops[-1] < tops[0]
    assert [b.index for b in order[:2]] == [b.index for b in batches if max(b.protrusions) == tops[0]]


def test_the_batches_that_keep_histories_are_those_of_the_first_realisation_at_a_history_point(calibrated):
    scene, _ = calibrated
    batches = sweep_stage.plan(scene.replace(sweep={"damping_ratio": [0.02, 0.05], "realisations": 2}))[3]
    # 9.0-10.4 nm in batches of 3: (9.0, 9.2, 9.4), (9.6, 9.8, 10.0), (10.2, 10.4) per damping and realisation
    assert [b.protrusions for b in batches[:3]] == [(9.0, 9.2, 9.4), (9.6, 9.8, 10.0), (10.2, 10.4)]
    assert sweep_stage.history_batches(batches, (9.2 + 1e-12, 10.4)) == {0, 2, 3, 5}
    assert sweep_stage.history_batches(batches, (5.0, 11.0)) == set()


def test_the_histories_are_written_once_a_worker_is_idle_and_equal_those_written_at_the_end(calibrated, tmp_path,
                                                                                           monkeypatch):
    """``sweep_histories.nc`` is written inside the fan-out, once the batches that keep histories are
    in and a worker has no batch left to start (fewer batches to finish than workers): one worker writes it in
    the last part's turn, two while the last batch runs. The files equal those of a sweep that writes both
    datasets at the end."""
    _, out = calibrated
    scene = load_scene(PAPER, FAST + ["sweep.histories_nm=[9.2, 10.4]"])  # (batches 0 and 2 of 3 keep histories)
    done: list[str] = []
    at_write: list[list[str]] = []
    write_early = runner.Inputs.write_early

    def spy(self, name, ds):
        at_write.append(list(done))
        write_early(self, name, ds)
        assert self.early[name][1].is_file() and not (self.out / name).exists()

    folders = {name: tmp_path / name for name in ("end", "one", "two")}
    for folder in folders.values():
        _copy_inputs(out, folder)
    with monkeypatch.context() as m:
        m.setattr(runner.Inputs, "write_early", lambda self, name, ds: None)
        sweep_stage.run_sweep(scene, folders["end"], scheduler="synchronous")
    monkeypatch.setattr(runner.Inputs, "write_early", spy)
    sweep_stage.run_sweep(scene, folders["one"], workers=1, on_batch=done.append)
    assert [len(d) for d in at_write] == [3]
    done.clear()
    sweep_stage.run_sweep(scene, folders["two"], workers=2, on_batch=done.append)
    parts = folders["two"] / sweep_stage.PARTS
    assert len(at_write) == 2 and len(at_write[1]) >= 3 - 1  # (at most one batch still to finish)
    assert {str(parts / "batch-00000.nc"), str(parts / "batch-00002.nc")} <= set(at_write[1])
    for name in ("sweep.nc", "sweep_histories.nc"):
        end = _values(folders["end"] / name)
        for folder in ("one", "two"):
            xr.testing.assert_identical(end, _values(folders[folder] / name))
    assert _values(folders["end"] / "sweep_histories.nc").sizes["protrusion"] == 2


def test_resume_after_interrupt_gives_identical_dataset(calibrated, tmp_path):
    scene, out = calibrated
    full, resumed = tmp_path / "full", tmp_path / "resumed"
    _copy_inputs(out, full)
    _copy_inputs(out, resumed)
    reference = sweep_stage.run_sweep(scene, full, scheduler="synchronous")
    with pytest.raises(KeyboardInterrupt):
        sweep_stage.run_sweep(scene, resumed, scheduler="synchronous", stop_after=2)
    parts = sorted((resumed / sweep_stage.PARTS).glob("batch-*.nc"))
    assert len(parts) == 2
    assert not (resumed / "sweep.nc").exists()
    stamps = {p: p.stat().st_mtime_ns for p in parts}
    done = []
    path = sweep_stage.run_sweep(scene, resumed, scheduler="synchronous", on_batch=done.append)
    # finished batches are not recomputed
    assert {p: p.stat().st_mtime_ns for p in parts} == stamps
    assert len(done) == len(sweep_stage.plan(scene)[3]) - 2
    xr.testing.assert_identical(_values(reference), _values(path))


def test_interrupt_keeps_an_existing_sweep_intact(calibrated, tmp_path):
    scene, out = calibrated
    _copy_inputs(out, tmp_path)
    first = sweep_stage.run_sweep(scene, tmp_path, scheduler="synchronous")
    before = first.read_bytes()
    changed = load_scene(PAPER, FAST + ["air_bearing.damping_ratio=0.07"])
    with pytest.raises(KeyboardInterrupt):
        sweep_stage.run_sweep(changed, tmp_path, scheduler="synchronous", stop_after=1, force=True)
    assert first.read_bytes() == before
    assert not list(tmp_path.glob(".sweep.nc.*"))


def test_killed_process_resumes(calibrated, tmp_path):
    """SIGKILL of `hdi sweep` mid-run: rerunning completes it, equal to an uninterrupted run."""
    scene, out = calibrated
    ref_dir, run_dir = tmp_path / "ref", tmp_path / "killed"
    _copy_inputs(out, ref_dir)
    _copy_inputs(out, run_dir)
    # the same scene as the killed command line (its provenance names every --set)
    scene = load_scene(PAPER, FAST + ["sweep.batch_size=1"])
    reference = sweep_stage.run_sweep(scene, ref_dir, scheduler="synchronous")
    cmd = [sys.executable, "-m", "pipeline.cli", "sweep", str(PAPER), "--out", str(run_dir), "--workers", "1"]
    for s in FAST:
        cmd += ["--set", s]
    cmd_slow = cmd + ["--set", "sweep.batch_size=1"]  # many small batches: a kill lands mid-sweep
    assert scene.overrides == cmd_slow[cmd_slow.index("--set") + 1::2]
    proc = subprocess.Popen(cmd_slow, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    parts = run_dir / sweep_stage.PARTS
    deadline = time.time() + 120
    while time.time() < deadline and not list(parts.glob("batch-*.nc")):
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)  # as soon as one batch is done: the kill lands mid-sweep
    proc.wait()
    before = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in parts.glob("batch-*.nc")}
    total = len(sweep_stage.plan(scene)[3])
    assert total == 8 and 1 <= len(before) < total, f"{len(before)} of {total} parts: the kill missed the sweep"
    assert not (run_dir / "sweep.nc").exists()
    done = subprocess.run(cmd_slow, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    # the rerun resumed: it ran only the missing batches and reused the parts of the killed run as they were
    assert f"sweep: {total} batches, {total - len(before)} to run" in done.stderr
    assert {name: (parts / name).stat() for name in before} and \
        {name: ((parts / name).stat().st_ino, (parts / name).stat().st_mtime_ns) for name in before} == before
    xr.testing.assert_identical(_values(reference), _values(run_dir / "sweep.nc"))


def test_lost_worker_loses_no_results(calibrated, tmp_path):
    """A worker process killed mid-sweep: dask reruns its task elsewhere; the result is unchanged."""
    import distributed
    scene, out = calibrated
    ref_dir, run_dir = tmp_path / "ref", tmp_path / "lost"
    _copy_inputs(out, ref_dir)
    _copy_inputs(out, run_dir)
    small = load_scene(PAPER, FAST + ["sweep.batch_size=1"])
    reference = sweep_stage.run_sweep(small, ref_dir, scheduler="synchronous")
    killed = []

    def kill_one(path: str) -> None:
        if killed:
            return
        client = distributed.default_client()
        worker = sorted(client.scheduler_info()["workers"])[0]
        try:  # (wait=False is not supported together with workers=: the call must wait)
            client.run(os._exit, 1, workers=[worker])
        except Exception:  # the worker dies before answering: the stream closes
            pass
        deadline = time.time() + 30
        while time.time() < deadline and worker in client.scheduler_info()["workers"]:
            time.sleep(0.05)
        killed.append((worker, worker not in client.scheduler_info()["workers"]))

    small = load_scene(PAPER, FAST + ["sweep.batch_size=1"])
    path = sweep_stage.run_sweep(small, run_dir, scheduler="processes", workers=2, on_batch=kill_one)
    assert killed and killed[0][1], "the worker process was not lost"
    xr.testing.assert_identical(_values(reference), _values(path))


@pytest.mark.parametrize("override, message", [
    ("sweep.protrusion_nm={start=5.0, stop=1.0, step=0.2}", "reversed"),
    ("sweep.protrusion_nm={start=-1.0, stop=1.0, step=0.2}", "negative"),
    ("sweep.protrusion_nm={start=1.0, stop=2.0, step=0.0}", "step > 0"),
    ("sweep.damping_ratio=[]", "non-empty"),
    ("sweep.roughness=[]", "non-empty"),
])
def test_bad_grids_are_clear_errors(override, message):
    with pytest.raises(SceneError) as err:
        load_scene(PAPER, [override])
    text = str(err.value)
    assert text.startswith(f"--set {override}: ") and message in text  # blamed on the option, not the file


def test_unknown_roughness_label_is_a_clear_error():
    scene = load_scene(PAPER, ['sweep.roughness=["scene", "polished"]'])
    with pytest.raises(SceneError) as err:
        roughness_sets(scene)
    assert "'polished'" in str(err.value) and "unknown roughness label" in str(err.value)
    assert str(PAPER) in str(err.value)


def test_roughness_sets_inherit_and_validate():
    scene = load_scene(PAPER, ['sweep.roughness=[{label="rough", sigma_nm=0.8}, "scene"]'])
    sets = roughness_sets(scene)
    assert list(sets) == ["rough", "sigma0.52nm_R5um_eta13.3"]  # ("scene": labelled by its values)
    assert sets["rough"]["sigma_nm"] == 0.8 and sets["rough"]["summit_radius_um"] == 5.0
    bad = load_scene(PAPER, ['sweep.roughness=[{label="x", sigma_nm=-1.0}]'])
    with pytest.raises(SceneError, match="sigma_nm"):
        roughness_sets(bad)


def test_roughness_labels_are_made_from_the_values_and_tell_sets_apart():
    """Without a label, a set is labelled by its values (exactly: sets that differ in the 7th digit
    differ in label), the same in every run; the scene's own set too, and a sweep over it alone."""
    assert list(roughness_sets(load_scene(PAPER))) == ["sigma0.52nm_R5um_eta13.3"]
    scene = load_scene(PAPER, ['sweep.roughness=[{sigma_nm=0.4}, {sigma_nm=0.4000001, summit_radius_um=2.5}, '
                               '{label="mine", sigma_nm=0.9}]'])
    sets = roughness_sets(scene)
    assert list(sets) == ["sigma0.4nm_R5um_eta13.3", "sigma0.4000001nm_R2.5um_eta13.3", "mine"]
    assert list(roughness_sets(scene)) == list(sets)
    assert roughness_label({"afm": ["/x/di-3.di", "/y/mi 1.mi"], "route": "summits"}) == "afm-di-3+mi_1-summits"
    twice = load_scene(PAPER, ['sweep.roughness=[{sigma_nm=0.52}, "scene"]'])
    with pytest.raises(SceneError, match="used twice"):
        roughness_sets(twice)


def test_tables_of_other_roughness_sets_follow_their_own_inputs(tmp_path):
    """Another set's interface tables are the runner's (own inputs key): kept when only the sweep changes."""
    base = ['scene.effects=["air_bearing","pitch","contact"]', "contact.k=0.5",
            'sweep.roughness=[{label="rough", sigma_nm=0.8}, "scene"]']
    scene = load_scene(PAPER, base)
    paths, _ = sweep_stage.prepare_inputs(scene, tmp_path, roughness_sets(scene))
    rough = Path(paths["rough"])
    assert rough == tmp_path / sweep_stage.PARTS / "interface-rough" / "interface.nc"
    assert paths[scene_label(scene)] == str(tmp_path / "interface.nc")  # the interface stage's own, not a copy
    assert float(read_dataset(rough).sigma) == pytest.approx(0.8)
    stamp = rough.stat().st_mtime_ns
    damped = load_scene(PAPER, base + ["sweep.damping_ratio=[0.02, 0.05]"])
    sweep_stage.prepare_inputs(damped, tmp_path, roughness_sets(damped))
    assert rough.stat().st_mtime_ns == stamp                     # the sweep's key changed, the tables' did not
    sweep_stage.prepare_inputs(damped, tmp_path, roughness_sets(damped), force=True)
    assert rough.stat().st_mtime_ns != stamp


def test_each_roughness_set_flies_on_its_own_summit_datum(tmp_path):
    """Without contact or adhesion no set needs interface tables, and the trajectory does not depend
    on the roughness: each set's clearance is the scene's shifted by the difference of McCool's y_s
    (explicit statistics, docs/model.md, section "Asperity statistics"), exactly. (Every set was given the scene's y_s before.)"""
    from pipeline.physics.asperity_statistics import explicit_statistics
    scene = load_scene(ROOT / "configs" / "sweep-3x3.toml",
                       ['scene.effects=["air_bearing", "pitch", "dmw"]', "sweep.damping_ratio=[0.05]",
                        "sweep.protrusion_nm={start=0.0, stop=2.0, step=1.0}", "report.histories_nm=[]"])
    ds = read_dataset(sweep_stage.run_sweep(scene, tmp_path))
    sets = roughness_sets(scene)
    y_s = {label: explicit_statistics(t["sigma_nm"] * 1e-9, t["summit_radius_um"] * 1e-6,
                                      t["summit_density_per_um2"] / 1e-12)["y_s"] / 1e-9
           for label, t in sets.items()}
    assert len(set(y_s.values())) == 3
    for label in sets:  # (the sets read no tables: their statistics are computed as the interface stage would)
        # tol: the same McCool formula on the same numbers, through NetCDF float64
        assert float(ds.summit_offset.sel(roughness=label)) == pytest.approx(y_s[label], rel=1e-12)
        # tol: the same formula on the same numbers, through NetCDF float64
        assert float(ds.roughness_plasticity_index.sel(roughness=label)) == pytest.approx(0.52, rel=1e-12)
    ref = ds["min_clearance"].sel(roughness="paper", damping=0.05).values
    for label in sets:
        got = ds["min_clearance"].sel(roughness=label, damping=0.05).values
        np.testing.assert_allclose(got - ref, -(y_s[label] - y_s["paper"]), rtol=0, atol=1e-9)
        # tol: the same kernel on the same inputs: the roughness enters after the trajectory
        np.testing.assert_allclose(ds["fhm_bv"].sel(roughness=label).values, ds["fhm_bv"].sel(roughness="paper").values,
                                   rtol=1e-12)


AFM = ROOT / "tests" / "data" / "afm"
#: A sweep over the scene's own set, a scan and another given set at two damping ratios: one protrusion,
#: short runs, a fixed k and hardness (so that the plasticity index differs from set to set).
AFM_SWEEP = ['scene.effects=["air_bearing","pitch","contact"]', "contact.k=0.5", "materials.hardness_gpa=1.7",
             "solver.duration_ms=0.3", "solver.transient_ms=0.1", "sweep.protrusion_nm={start=9.0, stop=9.0, step=0.2}",
             f'sweep.roughness=["scene", {{label="afm-mi1", afm=["{AFM / "mi-1.mi"}"]}}, {{label="rough", sigma_nm=0.8}}]',
             "sweep.damping_ratio=[0.03, 0.05]", "report.histories_nm=[]"]


@pytest.fixture(scope="module")
def afm_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("afm-sweep")
    scene = load_scene(PAPER, AFM_SWEEP)
    return scene, read_dataset(sweep_stage.run_sweep(scene, out, scheduler="synchronous")), out


def test_an_afm_roughness_set_is_described_by_the_statistics_its_interface_used(afm_sweep):
    """Each roughness set carries, along ``roughness``, the statistics its interface tables were built from, not
    the scene's defaults (0.52 nm, 5 um, 13.3 um^-2) where a set's interface used its AFM scans' (3.43 nm, 2.23 um,
    11.4 um^-2): the scan's
    (equal to its own ``interface.nc``), the given values exactly, and the GW plasticity index
    psi = (E'/H) sqrt(sigma_s/R) of each (Greenwood & Williamson 1966)."""
    import hashlib
    import json
    from pipeline.physics.asperity_statistics import composite_modulus, explicit_statistics
    scene, ds, out = afm_sweep
    own = scene_label(scene)
    scan = read_dataset(out / sweep_stage.PARTS / "interface-afm-mi1" / "interface.nc")
    for name, var in (("roughness_sigma", "sigma"), ("roughness_summit_radius", "summit_radius"),
                      ("roughness_summit_density", "summit_density"), ("roughness_plasticity_index", "plasticity_index_gw")):
        assert float(ds[name].sel(roughness="afm-mi1")) == float(scan[var]), name
    # the scan's numbers as the issue measured them (spectral route, combined surface)
    assert float(ds.roughness_sigma.sel(roughness="afm-mi1")) == pytest.approx(3.43, abs=0.005)
    assert float(ds.roughness_summit_radius.sel(roughness="afm-mi1")) == pytest.approx(2.23, abs=0.005)
    assert float(ds.roughness_summit_density.sel(roughness="afm-mi1")) == pytest.approx(11.4, abs=0.05)
    E = composite_modulus(150e9, 200e9, 0.3)
    for label, (sigma, R, eta) in ((own, (0.52, 5.0, 13.3)), ("rough", (0.8, 5.0, 13.3))):
        assert float(ds.roughness_sigma.sel(roughness=label)) == sigma
        assert float(ds.roughness_summit_radius.sel(roughness=label)) == R
        assert float(ds.roughness_summit_density.sel(roughness=label)) == eta
        st = explicit_statistics(sigma * 1e-9, R * 1e-6, eta / 1e-12)
        # tol: the same formula on the same numbers, through NetCDF float64
        assert float(ds.roughness_plasticity_index.sel(roughness=label)) == pytest.approx(
            E / 1.7e9 * np.sqrt(st["sigma_s"] / st["R"]), rel=1e-12)
    # the attribute records what was used and the scans by their content
    sets = json.loads(ds.attrs["roughness_sets"])
    for label in ds.roughness.values:
        for key, name in (("sigma_nm", "roughness_sigma"), ("summit_radius_um", "roughness_summit_radius"),
                          ("summit_density_per_um2", "roughness_summit_density"),
                          ("plasticity_index", "roughness_plasticity_index")):
            assert sets[label][key] == float(ds[name].sel(roughness=label)), (label, key)
    path = str((AFM / "mi-1.mi").resolve())
    assert sets["afm-mi1"]["afm_sha256"] == {path: hashlib.sha256((AFM / "mi-1.mi").read_bytes()).hexdigest()}
    assert "afm_sha256" not in sets["rough"]


def test_run_numbers_that_depend_on_the_grid_carry_its_dimension(afm_sweep):
    """``k_sigma`` = k sigma and the summit offset y_s of every roughness set (they were the first set's
    for all); the pad dampers of every damping ratio, proportional to it (c = 2 zeta omega m per mode)."""
    from pipeline.physics.asperity_statistics import explicit_statistics
    scene, ds, out = afm_sweep
    scan = read_dataset(out / sweep_stage.PARTS / "interface-afm-mi1" / "interface.nc")
    assert ds.k_sigma.dims == ("roughness",) and ds.summit_offset.dims == ("roughness",)
    # tol: one product by 0.5, exact
    np.testing.assert_allclose(ds.k_sigma.values, 0.5 * ds.roughness_sigma.values, rtol=1e-14)
    # tol: the same number through NetCDF float64
    assert float(ds.summit_offset.sel(roughness="afm-mi1")) == pytest.approx(float(scan.y_s), rel=1e-14)
    y_s = explicit_statistics(0.8e-9, 5.0e-6, 13.3 / 1e-12)["y_s"] / 1e-9
    # tol: the same McCool formula on the same numbers
    assert float(ds.summit_offset.sel(roughness="rough")) == pytest.approx(y_s, rel=1e-12)
    for name in ("front_damper", "rear_damper"):
        assert ds[name].dims == ("damping",), name
    # the modal damping ratio of each model is the coordinate `damping` itself, not a second variable
    assert "damping_ratio" not in ds.variables and "damping_ratio" not in ds.attrs
    assert ds.damping.values.tolist() == [0.03, 0.05]
    ratio = ds.front_damper.sel(damping=0.05) / ds.front_damper.sel(damping=0.03)
    # tol: a ratio of dampers linear in the ratio: a few roundings
    assert float(ratio) == pytest.approx(5 / 3, rel=1e-12)
    for name in ("k", "front_stiffness", "rear_stiffness", "steady_window_start"):
        assert ds[name].dims == (), name
    # what is not one number for the whole run is not a global attribute either
    assert not {"k_sigma_nm", "summit_offset_y_s_nm", "front_damper_n_s_m", "rear_damper_n_s_m"} & set(ds.attrs)


def test_help_keys_documents_both_forms_of_a_roughness_set(capsys):
    from pipeline.cli import main
    with pytest.raises(SystemExit):
        main(["--help-keys", "sweep"])
    text = capsys.readouterr().out
    assert "sigma_nm=" in text and "afm=[" in text


def test_the_reports_title_of_a_scan_set_states_its_statistics(afm_sweep):
    """A label that does not state the values (an AFM set) is followed by the statistics its interface used;
    a label made from the values is not repeated."""
    from pipeline.analyses.sweep_slices import combinations, combo_title
    scene, ds, out = afm_sweep
    titles = [combo_title(labels, sub) for labels, sub in combinations(ds, 0.05)]
    assert titles[0] == f"roughness `{scene_label(scene)}`, damping ratio 0.05"  # (the default first)
    assert "roughness `afm-mi1` (sigma 3.43 nm, R 2.23 um, eta 11.4 um^-2), damping ratio 0.03" in titles
    assert "roughness `rough` (sigma 0.8 nm, R 5 um, eta 13.3 um^-2), damping ratio 0.05" in titles


def test_with_an_actuation_the_sweep_carries_the_heater_power_beside_the_protrusion(tmp_path):
    """``heater_power`` [mW] on the ``protrusion`` dimension of both datasets (protrusion / efficiency), the
    numbers of every variable those of the same sweep without it, which has no such coordinate."""
    base = ['scene.effects=["air_bearing","pitch","contact"]', "contact.k=0.5", "solver.duration_ms=0.3",
            "solver.transient_ms=0.1", "sweep.protrusion_nm={start=9.0, stop=10.0, step=0.5}",
            "report.histories_nm=[9.5]"]
    plain = read_dataset(ensure("sweep", load_scene(PAPER, base), tmp_path / "plain"))
    scene = load_scene(PAPER, base + ["tfc.actuation_nm_per_mw=0.125"])
    out = tmp_path / "heater"
    powered = read_dataset(ensure("sweep", scene, out))
    assert "heater_power" not in plain.variables
    hp = powered["heater_power"]
    assert hp.dims == ("protrusion",) and "heater_power" in powered.coords and hp.attrs["units"] == "mW"
    # tol: one division by the efficiency, through NetCDF float64: a rounding
    np.testing.assert_allclose(hp.values, [72.0, 76.0, 80.0], rtol=1e-14)
    hist = read_dataset(out / "sweep_histories.nc")
    # tol: one division by the efficiency, through NetCDF float64: a rounding
    np.testing.assert_allclose(hist["heater_power"].values, [76.0], rtol=1e-14)
    assert hist["heater_power"].dims == ("protrusion",)
    xr.testing.assert_identical(powered.drop_vars("heater_power").drop_attrs(), plain.drop_attrs())
