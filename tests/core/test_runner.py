"""The stage runner: content-hash dependencies, no stale results, atomic and locked folders.

The first tests are the content keys' cases: an input file
edited in place, a dataset of another scene, a part copied to another batch's name, a no-op run that
rewrote everything. Then the runner's machinery on toy stages (cheap, exact call counts), orphaned temporary files, and the
registry through which a new stage plugs in. (The folder's lock: core/test_folder_lock.py.)
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from pipeline import cli, io, runner
from pipeline.io import DatasetError, read_dataset, var
from pipeline.physics import microwaviness as phys_dmw
from pipeline.physics import surface as sf
from pipeline.config.scene import load_scene
from pipeline.model.sweep_parts import part_problem
from pipeline.stages import sweep as sweep_stage

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"

#: A cheap scene: flying with DMW, three protrusions in two batches, 0.6 ms runs.
FLY = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
       "sweep.protrusion_nm={start=2.0, stop=2.4, step=0.2}", "sweep.batch_size=2"]


def _identical_but_history(a: Path, b: Path) -> None:
    da, db = read_dataset(a), read_dataset(b)
    del da.attrs["history"], db.attrs["history"]
    xr.testing.assert_identical(da, db)


def _tree(folder: Path) -> dict[str, int]:
    """Every file below ``folder`` with its modification time [ns]."""
    return {str(p.relative_to(folder)): p.stat().st_mtime_ns for p in sorted(folder.rglob("*")) if p.is_file()}


def _record(path: Path, scale: float = 1.0) -> np.ndarray:
    """A measured DMW displacement record [nm] at 4 MS/s, 1 ms long, written as one CSV column."""
    x = phys_dmw.synthesize(0.16, (1e4, 5e5), -2.0, 1e-3, 4e6, seed=5)
    np.savetxt(path, scale * x)
    return scale * x


def _scan(path: Path, scale: float = 1.0) -> Path:
    """A self-affine AFM height map [nm] (SurfaceTopography NetCDF), 128 x 128 over 4 um."""
    from SurfaceTopography import Topography
    from SurfaceTopography.Generation import fourier_synthesis
    t = fourier_synthesis((128, 128), (4000.0, 4000.0), 0.8, rms_height=0.5, short_cutoff=120.0,
                          long_cutoff=2000.0, unit="nm", rng=np.random.default_rng(3))
    Topography(scale * t.heights(), (4000.0, 4000.0), periodic=True, unit="nm").to_netcdf(str(path))
    return path


# ------------------------------------------------------------------ content keys: what makes a recompute
def test_dmw_record_edited_in_place_recomputes_everything_downstream(tmp_path):
    rec = tmp_path / "ldv.csv"
    _record(rec)
    scene = load_scene(PAPER, FLY + [f'dmw.source="{rec}"', "dmw.sample_rate_hz=4e6", 'dmw.unit="nm"'])
    out = tmp_path / "out"
    path = sweep_stage.run_sweep(scene, out, scheduler="synchronous")
    fhm1 = read_dataset(path).fhm_bv.values.copy()
    rms1 = float(read_dataset(out / "dmw.nc").rms)
    with_contact = scene.replace(scene={"effects": ["air_bearing", "pitch", "dmw", "contact"]})
    cal_key = runner.Runner(with_contact, out).key("calibrate")

    _record(rec, scale=2.0)                                    # same path, new bytes
    assert runner.Runner(with_contact, out).key("calibrate") != cal_key   # the change reaches calibrate
    path = sweep_stage.run_sweep(scene, out, scheduler="synchronous")
    # tol: the processing is linear: twice the record, twice the rms up to FFT rounding (log2(n) eps)
    assert float(read_dataset(out / "dmw.nc").rms) == pytest.approx(2 * rms1, rel=1e-9)
    # flying, the FHM follows the DMW amplitude (within 5 %: the bearing's rear law is mildly nonlinear);
    # the stale result was the old FHM, off by a factor of 2
    np.testing.assert_allclose(read_dataset(path).fhm_bv.values, 2 * fhm1, rtol=0.05)
    fresh = sweep_stage.run_sweep(scene, tmp_path / "fresh", scheduler="synchronous")
    _identical_but_history(path, fresh)


def test_afm_scan_edited_in_place_reaches_interface_and_sweep_parts(tmp_path):
    scan = _scan(tmp_path / "scan.nc")
    scene = load_scene(PAPER, ['scene.effects=["air_bearing","pitch","contact"]', "contact.k=0.5",
                               f'roughness.afm=["{scan}"]'] + FLY[1:])
    out = tmp_path / "out"

    def sigmas() -> list[float]:
        rough = read_dataset(out / "roughness.nc").sigma.sel({"surface": "combined", "route": "spectral"})
        # (the sweep's tables of the scene's own roughness set are interface.nc: no copy in sweep.parts)
        assert not list((out / sweep_stage.PARTS).glob("interface-*"))
        return [float(rough), float(read_dataset(out / "interface.nc").sigma)]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sf.SurfaceWarning)
        runner.build(["interface", "sweep"], scene, out, scheduler="synchronous")
        before = sigmas()
        assert before == pytest.approx([before[0]] * 2, rel=1e-12)  # tol: the same summary of the same scan
        _scan(scan, scale=2.0)                                 # same path, heights doubled
        runner.build(["interface", "sweep"], scene, out, scheduler="synchronous")
        # tol: heights doubled: the moments' square root doubles up to ~log2(n) roundings of a mean
        assert sigmas() == pytest.approx([2 * before[0]] * 2, rel=1e-9)
        runner.build(["sweep"], scene, tmp_path / "fresh", scheduler="synchronous")
    _identical_but_history(out / "sweep.nc", tmp_path / "fresh" / "sweep.nc")


def test_simulate_never_uses_a_calibration_of_other_inputs(tmp_path):
    """`hdi simulate --set lubricant.work_of_adhesion_j_m2=0` with an older calibration.nc in the folder."""
    # (without adhesion the admissible k is (-0.2179, 0.1668]: its middle, -0.0256, is below the physical
    # bound and refused; the k_choice "paper" takes the upper end, 0.1668)
    base = ["solver.duration_ms=1.0", "solver.transient_ms=0.3", "touchdown.curve_points=2",
            "sweep.protrusion_nm={start=9.0, stop=10.4, step=0.2}", "tfc.protrusion_nm=5.0",
            'touchdown.k_choice="paper"']
    runner.build("calibrate", load_scene(PAPER, base), tmp_path)
    old = read_dataset(tmp_path / "calibration.nc")
    assert np.isnan(float(old.k_calibrated))                  # adhesive snap-in: no admissible k
    rc = cli.main(["simulate", str(PAPER), "--out", str(tmp_path), "--set", "lubricant.work_of_adhesion_j_m2=0"]
                  + [a for s in base for a in ("--set", s)])
    assert rc == 0
    new = read_dataset(tmp_path / "calibration.nc")
    assert new.attrs[runner.KEY_ATTR] != old.attrs[runner.KEY_ATTR]
    k = float(new.k_calibrated)
    assert np.isfinite(k)                                     # without adhesion the procedure works
    hist = read_dataset(tmp_path / "histories.nc")
    assert hist.attrs["k"] == pytest.approx(k) and hist.attrs["k_source"] == "calibration (calibration.nc)"
    assert json.loads(hist.attrs["upstream_keys"])["calibrate"] == new.attrs[runner.KEY_ATTR]


def test_foreign_dataset_is_recomputed_not_used(tmp_path, paper_config):
    other = load_scene(paper_config, ["lubricant.thickness_nm=1.0"])
    runner.build("interface", other, tmp_path / "other")
    shutil.copy(tmp_path / "other" / "interface.nc", tmp_path / "interface.nc")
    runner.build("interface", load_scene(paper_config), tmp_path)
    assert float(read_dataset(tmp_path / "interface.nc").lubricant_thickness) == 0.75
    # a compute that reads an upstream dataset through Inputs refuses one of other inputs
    inputs = runner.Inputs(out=tmp_path / "other", upstream={"interface": runner.Runner(
        load_scene(paper_config), tmp_path).key("interface")})
    with pytest.raises(DatasetError, match="made from other inputs.*inputs_key"):
        inputs.dataset("interface.nc", stage="interface")


def test_part_copied_to_another_batch_is_rejected_and_recomputed(tmp_path):
    scene = load_scene(PAPER, FLY + ["sweep.batch_size=1"])
    reference = sweep_stage.run_sweep(scene, tmp_path / "ref", scheduler="synchronous")
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        sweep_stage.run_sweep(scene, out, scheduler="synchronous", stop_after=1)
    parts = out / sweep_stage.PARTS
    shutil.copy(parts / "batch-00000.nc", parts / "batch-00001.nc")   # the wrong batch under batch 1's name
    b1 = sweep_stage.plan(scene)[3][1]
    assert "holds batch 0, not 1" in part_problem(parts / "batch-00001.nc",
                                                  read_dataset(parts / "batch-00000.nc").attrs[runner.KEY_ATTR], b1)
    done: list[str] = []
    path = sweep_stage.run_sweep(scene, out, scheduler="synchronous", on_batch=done.append)
    assert sorted(Path(p).name for p in done) == ["batch-00001.nc", "batch-00002.nc"]
    _identical_but_history(reference, path)


def test_an_edited_sweep_dataset_or_part_is_remade_from_the_parts_never_reused(tmp_path):
    from damage import edit_value
    scene = load_scene(PAPER, FLY + ["sweep.batch_size=1"])
    out = tmp_path / "out"
    path = sweep_stage.run_sweep(scene, out, scheduler="synchronous")
    fhm = read_dataset(path).fhm_bv.values.copy()
    edit_value(path, "fhm_bv", (0, 0, 0), 50.0)             # reported "up to date" before, the edit used
    done: list[str] = []
    sweep_stage.run_sweep(scene, out, scheduler="synchronous", on_batch=done.append)
    assert done == []                                        # assembled again from its parts, none rerun
    np.testing.assert_array_equal(read_dataset(path).fhm_bv.values, fhm)
    part = out / sweep_stage.PARTS / "batch-00001.nc"
    stack = next(v for v in read_dataset(part).data_vars if v.startswith("stack__protrusion"))
    edit_value(part, stack, (0, 0), 1e3)                     # a kept part damaged: that batch alone is rerun
    assert "values differ from the checksum" in part_problem(
        part, read_dataset(path).attrs[runner.KEY_ATTR], sweep_stage.plan(scene)[3][1])
    (out / "sweep.nc").unlink()                              # (so the sweep is not up to date: it assembles)
    sweep_stage.run_sweep(scene, out, scheduler="synchronous", on_batch=done.append)
    assert [Path(p).name for p in done] == ["batch-00001.nc"]
    np.testing.assert_array_equal(read_dataset(path).fhm_bv.values, fhm)


def test_noop_run_rewrites_nothing(tmp_path):
    argv = ["run", str(PAPER), "--out", str(tmp_path), "--scheduler", "synchronous"]
    for s in FLY + ["sweep.histories_nm=[2.0, 2.4]", "report.histories_nm=[2.0, 2.4]"]:
        argv += ["--set", s]
    assert cli.main(argv) == 0
    made = _tree(tmp_path)
    assert {"roughness.nc", "dmw.nc", "interface.nc", "sweep.nc", "sweep_histories.nc",
            "figures/fig6_fhm.png", "report/comparison.md"} <= set(made)
    assert not any(Path(p).name.startswith(".") and p.endswith(".tmp") for p in made)
    assert cli.main(argv) == 0
    assert _tree(tmp_path) == made
    os.utime(tmp_path / "figures" / "fig6_fhm.png", ns=(1, 1))    # touched, not changed: still current
    assert cli.main(argv) == 0
    assert _tree(tmp_path) == {**made, "figures/fig6_fhm.png": 1}
    (tmp_path / "report" / "summary.md").write_text("edited by hand\n")  # an output changed: its stage redone
    assert cli.main(argv) == 0
    after = _tree(tmp_path)
    assert "edited by hand" not in (tmp_path / "report" / "summary.md").read_text()
    assert after["figures/fig6_fhm.png"] != 1
    assert {k: v for k, v in after.items() if not k.startswith(("figures/", "report/", ".hdi/"))} == \
        {k: v for k, v in made.items() if not k.startswith(("figures/", "report/", ".hdi/"))}


# ------------------------------------------------------------------------------ the machinery (toys)
def _toy_stages(calls: list[str], tmp_path: Path) -> dict[str, runner.Stage]:
    """Two stages: ``a`` reads dmw.rms_nm and a file; ``b`` reads ``a`` and tfc.protrusion_nm and also
    writes a text output."""
    data = tmp_path / "input.txt"

    def compute_a(scene, inputs):
        calls.append("a")
        value = float(inputs.files["data"].read_text()) * scene["dmw"]["rms_nm"]
        return xr.Dataset({"x": var(value, (), "nm", "toy value")})

    def compute_b(scene, inputs):
        calls.append("b")
        a = inputs.dataset("a.nc", stage="a")
        (inputs.staging / "notes").mkdir()
        (inputs.staging / "notes" / "b.txt").write_text(f"{float(a.x):g}\n")
        return {"b.nc": xr.Dataset({"y": var(float(a.x) + scene["tfc"]["protrusion_nm"], (), "nm", "toy")}),
                "b_extra.nc": None}

    return {
        "a": runner.Stage("a", compute_a, outputs=("a.nc",), reads=("dmw.rms_nm",),
                          files=lambda scene: {"data": data}),
        "b": runner.Stage("b", compute_b, outputs=("b.nc", "b_extra.nc", "notes/b.txt"),
                          reads=("tfc.protrusion_nm",), upstream=("a",)),
    }


def test_runner_recomputes_exactly_what_changed(tmp_path, paper_scene):
    calls: list[str] = []
    stages = _toy_stages(calls, tmp_path)
    (tmp_path / "input.txt").write_text("2.0\n")
    out = tmp_path / "out"

    def build(scene, force=False):
        calls.clear()
        runner.Runner(scene, out, stages).build(["b"], force=force)
        return list(calls)

    assert build(paper_scene) == ["a", "b"]
    assert float(read_dataset(out / "b.nc").y) == pytest.approx(2.0 * 0.266 + 11.0)  # tfc.protrusion_nm = 11
    assert (out / "notes" / "b.txt").read_text() == "0.532\n"
    assert build(paper_scene) == []                                           # nothing changed
    assert build(paper_scene.replace(air_bearing={"damping_ratio": 0.07})) == []  # a key nobody reads
    assert build(paper_scene.replace(tfc={"protrusion_nm": 3.0})) == ["b"]   # only b reads it
    assert build(paper_scene.replace(tfc={"protrusion_nm": 3.0})) == []
    (tmp_path / "input.txt").write_text("4.0\n")                              # a's file, edited in place
    assert build(paper_scene.replace(tfc={"protrusion_nm": 3.0})) == ["a", "b"]  # ... propagates to b
    assert float(read_dataset(out / "b.nc").y) == pytest.approx(4.0 * 0.266 + 3.0)
    (out / "notes" / "b.txt").write_text("tampered\n")                         # a non-NetCDF output changed
    assert build(paper_scene.replace(tfc={"protrusion_nm": 3.0})) == ["b"]
    (out / "b_extra.nc").write_bytes(b"stale")                                 # not produced: not required ...
    assert build(paper_scene.replace(tfc={"protrusion_nm": 3.0}), force=True) == ["b"]  # ... and removed
    assert not (out / "b_extra.nc").exists()
    assert build(paper_scene.replace(tfc={"protrusion_nm": 3.0}), force=True) == ["b"]  # force: target only
    assert sorted(p.name for p in out.iterdir()) == [".hdi", "a.nc", "b.nc", "notes"]  # no lock, no temporaries
    assert json.loads(read_dataset(out / "b.nc").attrs["upstream_keys"]) == {"a": read_dataset(out / "a.nc").attrs[
        runner.KEY_ATTR]}


def test_the_kernel_compiles_ahead_when_a_stage_that_simulates_is_to_be_computed(tmp_path, paper_scene,
                                                                                   monkeypatch):
    """Before the first stage of a build, the runner starts the scene's kernel compile (a background process on
    a first run, pipeline.model.ahead.compile_kernel_ahead) when a stage it will compute simulates, and
    has the lazy imports of the stages it will compute done while the process waits for it; never when every
    such stage is current, nor for a build without one."""
    calls: list[str] = []
    stages = _toy_stages(calls, tmp_path)
    stages["b"] = dataclasses.replace(stages["b"], simulates=True, lazy_imports=("json", "csv"))
    (tmp_path / "input.txt").write_text("2.0\n")
    out = tmp_path / "out"
    events: list = []
    monkeypatch.setattr(runner, "compile_kernel_ahead", lambda scene: events.append(("compile", calls[:])))
    monkeypatch.setattr(runner.compiled, "while_waiting", lambda work: events.append(("idle", calls[:])))
    monkeypatch.setattr(runner.compiled, "import_modules", lambda names: names)

    def build(targets, scene=paper_scene, force=False):
        events.clear()
        calls.clear()
        runner.Runner(scene, out, stages).build(targets, force=force)
        return events[:]

    assert build(["a"]) == []                                      # no stage that simulates
    # before a stage ran (no call yet), once; the lazy imports of the stages to compute
    assert build(["b"]) == [("compile", []), ("idle", [])]
    assert calls == ["b"]
    assert build(["b"]) == []                                      # everything current
    assert build(["b"], force=True) == [("compile", []), ("idle", [])]  # forced: computed, so compiled
    assert build(["b"], scene=paper_scene.replace(tfc={"protrusion_nm": 3.0})) == [("compile", []), ("idle", [])]
    stages["b"] = dataclasses.replace(stages["b"], lazy_imports=())
    assert build(["b"], force=True) == [("compile", [])]           # nothing to import meanwhile
    stages["b"] = dataclasses.replace(stages["b"], simulates=False)
    assert build(["b"], force=True) == []


def test_optional_stage_is_read_only_when_current(tmp_path, paper_scene):
    """A stage ``r`` that reads ``a`` when it is current (as the report reads identify.nc) never builds
    it, sees it only while its inputs are those of this scene, and is redone when that changes."""
    calls: list[str] = []
    stages = _toy_stages(calls, tmp_path)
    seen: list[dict] = []

    def compute_r(scene, inputs):
        calls.append("r")
        seen.append(dict(inputs.optional))
        return xr.Dataset({"z": var(1.0, (), "1", "toy")})

    stages["r"] = runner.Stage("r", compute_r, outputs=("r.nc",), reads=(), optional=("a",))
    (tmp_path / "input.txt").write_text("2.0\n")
    out = tmp_path / "out"

    def build(scene, targets):
        calls.clear()
        runner.Runner(scene, out, stages).build(targets)
        return list(calls)

    assert build(paper_scene, ["r"]) == ["r"] and seen[-1] == {"a": None}     # not built by r
    assert build(paper_scene, ["a"]) == ["a"]
    assert build(paper_scene, ["r"]) == ["r"] and seen[-1] == {"a": read_dataset(out / "a.nc").attrs[runner.KEY_ATTR]}
    assert build(paper_scene, ["r"]) == []
    other = paper_scene.replace(dmw={"rms_nm": 0.1})                             # a.nc is now another scene's
    assert build(other, ["r"]) == ["r"] and seen[-1] == {"a": None}


def test_derived_inputs_key_on_the_value_not_the_keys(paper_scene):
    """The interface tables depend on the deepest protrusion, max(tfc, sweep stop) (interface.STAGE
    derived): a protrusion moved within the paper sweep (0-15 nm) changes neither the interface nor the
    sweep key (it is excluded there); one beyond the sweep's stop deepens the tables and changes both."""
    def keys(delta):
        r = runner.Runner(paper_scene.replace(tfc={"protrusion_nm": delta}), "unused")
        return r.key("interface"), r.key("sweep")

    assert paper_scene["sweep"]["protrusion_nm"]["stop"] == 15.0
    assert keys(5.0) == keys(11.0)
    deeper = keys(16.0)
    assert deeper[0] != keys(11.0)[0] and deeper[1] != keys(11.0)[1]


def test_a_scene_that_extends_another_keys_on_its_values_not_on_the_base_path(tmp_path):
    """``scene.extends`` (an absolute path) is not an input: a scene that only extends the paper scene
    keys like the paper scene, wherever the files are; the 3x3 grid, which changes the sweep's sets
    and damping ratios only, shares the paper's calibration and differs in its sweep."""
    (tmp_path / "base").mkdir()
    shutil.copy(PAPER, tmp_path / "base" / "paper-2009.toml")
    (tmp_path / "child.toml").write_text('[scene]\nname = "paper-2009"\nextends = "base/paper-2009.toml"\n')
    paper, child = load_scene(PAPER), load_scene(tmp_path / "child.toml")
    assert child["scene"]["extends"] != paper["scene"]["extends"]
    for stage in ("roughness", "dmw", "interface", "calibrate", "sweep", "report"):
        assert runner.Runner(child, "a").key(stage) == runner.Runner(paper, "b").key(stage), stage
    grid = load_scene(PAPER.parent / "sweep-3x3.toml")
    assert runner.Runner(grid, "a").key("calibrate") == runner.Runner(paper, "a").key("calibrate")
    assert runner.Runner(grid, "a").key("sweep") != runner.Runner(paper, "a").key("sweep")


def test_failing_compute_writes_nothing_and_leaves_no_lock(tmp_path, paper_scene):
    def broken(scene, inputs):
        (inputs.staging / "half.txt").write_text("half")
        raise RuntimeError("disk full")

    stages = {"x": runner.Stage("x", broken, outputs=("x.nc", "half.txt"))}
    with pytest.raises(RuntimeError, match="disk full"):
        runner.Runner(paper_scene, tmp_path, stages).build(["x"])
    assert list(tmp_path.iterdir()) == []


def test_a_compute_that_builds_in_its_own_folder_is_refused(tmp_path, paper_scene):
    """Stages read their inputs through Inputs; building in one's own folder (the re-entrant runner
    this replaced) is an error that says so, and leaves no lock behind."""
    stages = {"a": runner.Stage("a", lambda scene, inputs: xr.Dataset({"v": var(1.0, (), "1", "v")}), outputs=("a.nc",))}

    def nested(scene, inputs):
        runner.Runner(scene, inputs.out, stages).build(["a"])
        return xr.Dataset()

    stages["x"] = runner.Stage("x", nested, outputs=("x.nc",))
    with pytest.raises(RuntimeError, match="already holds the folder"):
        runner.Runner(paper_scene, tmp_path, stages).build(["x"])
    assert not (tmp_path / runner.LOCK_NAME).exists()
    runner.Runner(paper_scene, tmp_path, stages).build(["a"])  # the folder is free again


def _early_stage(seen: dict, *, same: bool = True, fail: bool = False) -> dict[str, runner.Stage]:
    """A stage of two dataset outputs whose second, ``late.nc``, is written early (:meth:`Inputs.write_early`);
    ``seen`` records what was in the folders while it computed. ``same``: the early dataset is returned;
    ``fail``: the computation fails after the early write."""
    def compute(scene, inputs):
        late = xr.Dataset({"h": var(np.linspace(0.0, 1.0, 5000), ("t",), "nm", "a history")})
        inputs.write_early("late.nc", late)
        seen["staged"] = sorted(p.name for p in inputs.staging.iterdir())
        seen["out"] = sorted(p.name for p in inputs.out.iterdir() if p.suffix == ".nc")
        if fail:
            raise RuntimeError("disk full")
        return {"first.nc": xr.Dataset({"v": var(2.0, (), "1", "v")}), "late.nc": late if same else late.copy()}
    return {"x": runner.Stage("x", compute, outputs=("first.nc", "late.nc"), reads=("dmw.rms_nm",))}


def test_a_dataset_written_early_is_moved_into_place_as_the_end_would_write_it(tmp_path, paper_scene):
    """A dataset complete before the stage ends (the sweep's histories) is written then, into the
    staging folder, and moved into place at the end with the runner's attributes; the first output (with the
    list of outputs) and a dataset returned as another object are written at the end."""
    seen: dict = {}
    runner.Runner(paper_scene, tmp_path / "early", _early_stage(seen)).build(["x"])
    assert seen == {"staged": ["late.nc"], "out": []}  # (nothing in the results folder before the end)
    assert sorted(p.name for p in (tmp_path / "early").iterdir() if p.suffix == ".nc") == ["first.nc", "late.nc"]
    runner.Runner(paper_scene, tmp_path / "end", _early_stage({}, same=False)).build(["x"])
    key = runner.Runner(paper_scene, tmp_path / "early", _early_stage({})).key("x")
    for name in ("first.nc", "late.nc"):
        early, end = read_dataset(tmp_path / "early" / name), read_dataset(tmp_path / "end" / name)
        assert early.attrs[runner.KEY_ATTR] == end.attrs[runner.KEY_ATTR] == key
        for ds in (early, end):
            del ds.attrs["history"]
        xr.testing.assert_identical(early, end)
    assert json.loads(read_dataset(tmp_path / "early" / "first.nc").attrs[runner.OUTPUTS_ATTR]) == ["first.nc", "late.nc"]
    assert runner.OUTPUTS_ATTR not in read_dataset(tmp_path / "early" / "late.nc").attrs
    assert not [p for p in (tmp_path / "early").iterdir() if p.name.startswith(runner.STAGING_PREFIX)]


def test_a_dataset_written_early_is_not_kept_when_the_stage_fails(tmp_path, paper_scene):
    seen: dict = {}
    with pytest.raises(RuntimeError, match="disk full"):
        runner.Runner(paper_scene, tmp_path, _early_stage(seen, fail=True)).build(["x"])
    assert seen["staged"] == ["late.nc"]
    assert list(tmp_path.iterdir()) == []


def test_an_early_write_of_an_undeclared_output_is_an_error(tmp_path, paper_scene):
    def compute(scene, inputs):
        inputs.write_early("other.nc", xr.Dataset())
    stages = {"x": runner.Stage("x", compute, outputs=("x.nc",))}
    with pytest.raises(ValueError, match=r"stage x wrote 'other.nc' early; its dataset outputs are \['x.nc'\]"):
        runner.Runner(paper_scene, tmp_path, stages).build(["x"])
    assert runner.Inputs.folder(tmp_path).write_early("x.nc", xr.Dataset()) is None  # (no runner: nothing)
    assert not (tmp_path / "x.nc").exists()


def test_undeclared_output_is_an_error(tmp_path, paper_scene):
    stages = {"x": runner.Stage("x", lambda scene, inputs: {"y.nc": xr.Dataset()}, outputs=("x.nc",))}
    with pytest.raises(RuntimeError, match="undeclared outputs"):
        runner.Runner(paper_scene, tmp_path, stages).build(["x"])


def test_missing_input_file_names_the_role(tmp_path, paper_scene):
    stages = {"x": runner.Stage("x", lambda s, i: xr.Dataset(), outputs=("x.nc",),
                                files=lambda scene: {"dmw.source": tmp_path / "gone.csv"})}
    with pytest.raises(FileNotFoundError, match=r"x: input file .*gone\.csv \(dmw\.source\) does not exist"):
        runner.Runner(paper_scene, tmp_path, stages).build(["x"])


def test_orphaned_temporaries_are_cleaned(tmp_path, paper_config):
    (tmp_path / sweep_stage.PARTS).mkdir()
    orphans = [tmp_path / ".sweep.nc.hdi-0123456789ab.k2j3h4.tmp",      # (hdi's names, of another run)
               tmp_path / sweep_stage.PARTS / ".batch-00003.nc.hdi-0123456789ab.x8y.tmp",
               tmp_path / ".hdi-staging-abc" / "figures" / "fig6_fhm.png"]
    for p in orphans:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(b"half written by a killed run")
    keep = tmp_path / "notes.tmp"                              # not one of ours: left alone
    keep.write_text("mine")
    runner.build("dmw", load_scene(paper_config), tmp_path)
    assert not any(p.exists() for p in orphans) and not (tmp_path / ".hdi-staging-abc").exists()
    assert keep.read_text() == "mine"


# ------------------------------------------------------------------------------------------ registry
def test_registry_holds_every_stage_and_the_main_job(paper_scene):
    stages = runner.registry()
    assert list(stages)[:12] == ["roughness", "dmw", "interface", "bulge", "bulge_pads", "calibrate", "simulate",
                                 "statics", "sweep", "accuracy", "ensemble", "report"]
    assert runner.main_job(paper_scene) == ["roughness", "dmw", "interface", "calibrate", "statics", "sweep",
                                            "ensemble", "report"]
    single = paper_scene.replace(report={"realisations": 1})  # (the report's checks on the scene's record alone)
    assert runner.main_job(single) == ["roughness", "dmw", "interface", "calibrate", "statics", "sweep", "report"]
    flying = paper_scene.replace(scene={"effects": ["air_bearing", "pitch", "dmw"]})
    assert runner.main_job(flying) == ["roughness", "dmw", "interface", "statics", "sweep", "ensemble", "report"]
    plan = runner.Runner(paper_scene, "unused", stages).plan(["report"])
    assert plan.index("calibrate") < plan.index("sweep") < plan.index("report")
    assert runner.Runner(paper_scene.replace(contact={"k": 0.5}), "unused", stages).plan(["sweep"]) == \
        ["dmw", "interface", "sweep"]  # (the record first: one the simulation cannot use stops it before any dataset)


def test_a_new_stage_plugs_in_by_declaring_itself(tmp_path, paper_config, monkeypatch):
    import pipeline.stages as package
    plug = tmp_path / "plug"
    plug.mkdir()
    (plug / "toy_plugin.py").write_text(
        "import xarray as xr\n"
        "from pipeline.io import var\n"
        "from pipeline.runner import Stage\n"
        "def compute(scene, inputs):\n"
        "    rms = float(inputs.dataset('dmw.nc', stage='dmw').rms)\n"
        "    return xr.Dataset({'twice_rms': var(2 * rms, (), 'nm', 'twice the DMW rms')})\n"
        "STAGE = Stage('toy', compute, outputs=('toy.nc',), reads=(), upstream=('dmw',), order=99,\n"
        "              doc='a plugged-in stage')\n")
    monkeypatch.setattr(package, "__path__", [*package.__path__, str(plug)])
    monkeypatch.delitem(sys.modules, "pipeline.stages.toy_plugin", raising=False)
    assert "toy" in runner.registry()
    assert cli.main(["toy", str(paper_config), "--out", str(tmp_path / "out")]) == 0
    # tol: the plugin doubles the stored rms: one rounding
    assert float(read_dataset(tmp_path / "out" / "toy.nc").twice_rms) == pytest.approx(2 * 0.266, rel=1e-9)
    sys.modules.pop("pipeline.stages.toy_plugin", None)


@pytest.mark.slow
def test_ctrl_c_prints_one_line(tmp_path):
    """SIGINT to the whole process group (what a terminal's Ctrl-C does) during a 2-worker sweep: the
    command says so in one line, the workers print no tracebacks, finished parts are kept."""
    import signal
    import time
    cmd = [sys.executable, "-m", "pipeline.cli", "sweep", str(PAPER), "--out", str(tmp_path), "--workers", "2"]
    for s in FLY[:3] + ["sweep.protrusion_nm={start=0.0, stop=6.0, step=0.2}", "sweep.batch_size=1"]:
        cmd += ["--set", s]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    parts = tmp_path / sweep_stage.PARTS
    deadline = time.time() + 180
    while time.time() < deadline and len(list(parts.glob("batch-*.nc"))) < 2:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert err.strip().splitlines()[-1] == "hdi sweep: interrupted; finished work is kept, run again to resume"
    assert len(err.strip().splitlines()) <= 8          # the stages' progress lines and that one line
    assert len(list(parts.glob("batch-*.nc"))) >= 2 and not (tmp_path / runner.LOCK_NAME).exists()


def test_the_scene_part_is_the_declared_keys(paper_scene, tmp_path):
    """A stage is keyed by the keys it declares, each by its value (the interface stage: the lubricant's
    thickness, not its meniscus time, a property of the dynamics); a measured DMW record's key leaves the
    synthesis keys out."""
    from pipeline.config.fields import expand
    from pipeline.runner import scene_part
    reads = runner.registry()["interface"].reads
    part = scene_part(paper_scene, reads)
    assert set(part) == set(expand(reads)) and part["lubricant.thickness_nm"] == paper_scene["lubricant"]["thickness_nm"]
    assert "lubricant.meniscus_time_us" not in part
    assert scene_part(paper_scene.replace(lubricant={"meniscus_time_us": 40.0}), reads) == part
    record = tmp_path / "w.csv"
    record.write_text("time_s,displacement_nm\n" + "".join(f"{i * 2.5e-7},{0.1 * (i % 7)}\n" for i in range(20000)))
    measured = paper_scene.replace(dmw={"source": str(record)})
    dmw_reads = runner.registry()["dmw"].reads
    assert set(scene_part(paper_scene, dmw_reads)) - set(scene_part(measured, dmw_reads)) == set(runner.SYNTHESIS_ONLY)


# ------------------------------------------------- stored datasets checked on reuse; files that are not outputs'
def _history_stage(calls: list[str], name: str = "h", upstream: tuple[str, ...] = ()) -> runner.Stage:
    """A stage writing a compressed 8000-sample history (zlib chunks, :func:`pipeline.encoding.compression`) scaled
    by dmw.rms_nm [nm], and reading its upstream stages' histories."""
    def compute(scene, inputs):
        calls.append(name)
        base = sum(float(inputs.dataset(f"{u}.nc", stage=u).v.sum()) for u in upstream)
        t = np.arange(8000) * 250e-9
        return xr.Dataset({"v": var(scene["dmw"]["rms_nm"] * np.sin(t * 1e5) + base, "elapsed_time", "nm", "toy")},
                          coords={"elapsed_time": var(t, "elapsed_time", "s", "elapsed simulated time")})
    return runner.Stage(name, compute, outputs=(f"{name}.nc",), reads=("dmw.rms_nm",), upstream=upstream)


def test_a_damaged_or_hand_edited_output_is_recomputed_never_reused(tmp_path, paper_scene, caplog, monkeypatch):
    from damage import damage_chunk, edit_value
    calls: list[str] = []
    stages = {"h": _history_stage(calls)}
    out = tmp_path / "out"

    def build(force: bool = False) -> list[str]:
        calls.clear()
        runner.Runner(paper_scene, out, stages).build(["h"], force=force)
        return list(calls)

    assert build() == ["h"]
    first = read_dataset(out / "h.nc").v.values.copy()
    assert build() == []
    reads: list[Path] = []                                  # bytes as written (the stage's record): not read back
    monkeypatch.setattr(io, "read_dataset", lambda path, **kw: reads.append(path) or read_dataset(path, **kw))
    io._VERIFIED.clear()
    assert runner.Runner(paper_scene, out, stages).stale_reason("h") is None and reads == []
    damage_chunk(out / "h.nc", "v")                        # (reported "up to date" before, and used)
    with caplog.at_level("INFO", logger="pipeline.runner"):
        assert build() == ["h"]
    assert "h: computing (h.nc: variable 'v': its data cannot be read back (NetCDF: HDF error))" in caplog.text
    assert reads[0] == out / "h.nc"                          # (changed bytes: read back, value by value)
    np.testing.assert_array_equal(read_dataset(out / "h.nc").v.values, first)
    edit_value(out / "h.nc", "v", (10,), 99.0)             # by hand, in place: the inputs key still the same
    assert build() == ["h"]
    np.testing.assert_array_equal(read_dataset(out / "h.nc").v.values, first)
    edit_value(out / "h.nc", "elapsed_time", (3,), 1.0)   # a coordinate too
    assert build() == ["h"] and build() == []


def test_a_damaged_upstream_dataset_is_recomputed_when_its_downstream_stage_is_forced(tmp_path, paper_scene):
    from damage import damage_chunk
    calls: list[str] = []
    stages = {"u": _history_stage(calls, "u"), "d": _history_stage(calls, "d", upstream=("u",))}
    out = tmp_path / "out"
    runner.Runner(paper_scene, out, stages).build(["d"])
    d = read_dataset(out / "d.nc").v.values.copy()
    damage_chunk(out / "u.nc", "v")
    calls.clear()
    runner.Runner(paper_scene, out, stages).build(["d"], force=True)   # (a traceback, "NetCDF: HDF error", before)
    assert calls == ["u", "d"]
    np.testing.assert_array_equal(read_dataset(out / "d.nc").v.values, d)


def test_an_input_file_is_never_an_outputs_target(tmp_path, paper_scene):
    calls: list[str] = []
    stages = {"h": _history_stage(calls)}
    out = tmp_path / "out"
    out.mkdir()
    record = out / "h.nc"
    record.write_bytes(b"the user's own record")
    stages["h"] = dataclasses.replace(stages["h"], files=lambda scene: {"dmw.source": record})
    for force in (False, True):                                         # (no option lifts it)
        with pytest.raises(runner.OutputRefused, match=rf"dmw\.source = {record}: is the file h\.nc the h stage "
                                                       r"writes in the results folder .*; an input is never "
                                                       "overwritten by an output: move it out"):
            runner.Runner(paper_scene, out, stages).build(["h"], force=force)
    (tmp_path / "link.nc").symlink_to(record)                          # a link to it names the same file
    stages["h"] = dataclasses.replace(stages["h"], files=lambda scene: {"dmw.source": tmp_path / "link.nc"})
    with pytest.raises(runner.OutputRefused, match="is the file h.nc"):
        runner.Runner(paper_scene, out, stages).build(["h"])
    assert record.read_bytes() == b"the user's own record" and calls == []


def test_a_file_hdi_did_not_write_at_an_output_path_is_replaced_only_with_force(tmp_path, paper_scene):
    calls: list[str] = []
    stages = _toy_stages(calls, tmp_path)
    (tmp_path / "input.txt").write_text("2.0\n")
    out = tmp_path / "out"
    (out / "notes").mkdir(parents=True)
    (out / "notes" / "b.txt").write_text("my own notes\n")
    with pytest.raises(runner.OutputRefused, match=r"notes/b\.txt: not written by hdi \(no b stage's record of "
                                                   r"it\), and the b stage would replace it: move it away, choose "
                                                   "another --out, or pass --force to replace it"):
        runner.Runner(paper_scene, out, stages).build(["b"])
    assert calls == [] and not (out / "a.nc").exists()                 # (refused before any stage computed)
    assert (out / "notes" / "b.txt").read_text() == "my own notes\n"
    xr.Dataset({"y": var(1.0, (), "nm", "mine")}).to_netcdf(out / "b_extra.nc")  # a dataset of the user's
    (out / "notes" / "b.txt").unlink()
    with pytest.raises(runner.OutputRefused, match=r"b_extra\.nc: not written by hdi"):
        runner.Runner(paper_scene, out, stages).build(["b"])
    runner.Runner(paper_scene, out, stages).build(["b"], force=True)
    assert calls == ["a", "b"] and not (out / "b_extra.nc").exists()
    (out / "notes" / "b.txt").write_text("edited\n")                   # a file hdi wrote, edited: hdi's to remake
    calls.clear()
    runner.Runner(paper_scene, out, stages).build(["b"])
    assert calls == ["b"] and (out / "notes" / "b.txt").read_text() == "0.532\n"


def test_another_scenes_results_are_replaced_only_with_force(tmp_path, paper_scene):
    calls: list[str] = []
    stages = _toy_stages(calls, tmp_path)
    (tmp_path / "input.txt").write_text("2.0\n")
    out = tmp_path / "out"
    runner.Runner(paper_scene, out, stages).build(["b"])
    before = _tree(out)
    other = paper_scene.replace(scene={"name": "other"}, dmw={"rms_nm": 0.5})
    with pytest.raises(runner.OutputRefused, match=rf"{out / 'a.nc'}: results of the scene 'paper-2009', not of "
                                                   r"this run's 'other'; run each scene into its own folder \(--out"):
        runner.Runner(other, out, stages).build(["b"])
    assert _tree(out) == before
    calls.clear()
    runner.Runner(paper_scene.replace(dmw={"rms_nm": 0.5}), out, stages).build(["b"])   # the same scene, edited
    assert calls == ["a", "b"]
    calls.clear()
    runner.Runner(other, out, stages).build(["b"], force=True)   # (a's inputs are now the same: a is reused)
    assert calls == ["b"] and read_dataset(out / "b.nc").attrs["scene_name"] == "other"
    assert json.loads((out / ".hdi" / "b.json").read_text())["scene"] == "other"
