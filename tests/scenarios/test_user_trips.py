"""What a new user trips over: each test is one probe of a user's first runs and what it must give.

SIGTERM, the umask of written datasets, interface coordinates ``.sel`` could not hit, unbounded sizes, and
the smaller messages. (A scheduler address that is not a dask scheduler: ``core/test_scheduler.py``; the
validity bits: ``core/test_validity.py``. The time axis and the
ensemble's CF-1.8 are in ``core/test_variables.py`` and ``scenarios/test_realisations.py``; the resumed sweep in
``stages/test_sweep.py``.)
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pipeline import cli, runner
from pipeline.io import read_dataset, write_dataset
from pipeline.config.scene import load_scene
from pipeline.runner import ensure

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"
FLY = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
       "sweep.protrusion_nm={start=2.0, stop=2.4, step=0.2}", "sweep.batch_size=2"]


# ------------------------------------------------------------------------------ 5. the umask
@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o002, 0o664), (0o077, 0o600)])
def test_datasets_are_created_with_the_umask_like_any_file(tmp_path, umask, mode):
    import xarray as xr
    from pipeline.io import var
    ds = xr.Dataset({"x": var(np.arange(3.0), ("i",), "nm", "x")})
    old = os.umask(umask)
    try:
        path = write_dataset(ds, tmp_path / "x.nc", stage="test")
        (tmp_path / "plain.txt").write_text("a")
    finally:
        os.umask(old)
    assert (path.stat().st_mode & 0o777) == mode == ((tmp_path / "plain.txt").stat().st_mode & 0o777)


# ------------------------------------------------------------------------------ 6. SIGTERM
#: A sweep of :data:`LONG_BATCHES` one-protrusion batches over 0-6 nm: still running when its second part is written
#: (31 batches of these short scenes took 0.38 s on a fast host: a signal sent after the second part came after the end).
LONG_STEP_NM = 0.02
LONG_BATCHES = round(6.0 / LONG_STEP_NM) + 1
LONG = FLY[:3] + [f"sweep.protrusion_nm={{start=0.0, stop=6.0, step={LONG_STEP_NM}}}", "sweep.batch_size=1"]


def _sweep(out: Path, *extra: str, **popen) -> subprocess.Popen:
    """``hdi sweep`` of :data:`LONG` into ``out`` as a process of its own session, SIGHUP at its default (as
    from a terminal: a test session run under nohup passes it ignored)."""
    cmd = [sys.executable, "-m", "pipeline.cli", "sweep", str(PAPER), "--out", str(out), "--workers", "2", *extra]
    for s in LONG:
        cmd += ["--set", s]
    popen = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, "text": True, **popen}
    return subprocess.Popen(cmd, cwd=ROOT, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_DFL), **popen)


def _two_parts_written(out: Path, proc: subprocess.Popen) -> list:
    """Wait until the sweep has written two parts; its descendant processes then (psutil)."""
    import psutil
    from pipeline.stages import sweep as sweep_stage
    parts = out / sweep_stage.PARTS
    deadline = time.time() + 240
    while time.time() < deadline and len(list(parts.glob("batch-*.nc"))) < 2 and proc.poll() is None:
        time.sleep(0.05)
    assert proc.poll() is None and (out / runner.LOCK_NAME).exists() and list(out.glob(runner.STAGING_PREFIX + "*"))
    return psutil.Process(proc.pid).children(recursive=True)


def _none_alive(children: list, wait_s: float = 10.0) -> list:
    """The processes of ``children`` still alive ``wait_s`` after their parent ended (killed here, if any)."""
    import psutil
    _, alive = psutil.wait_procs(children, timeout=wait_s)
    for p in alive:
        p.kill()
    return [(p.pid, p.name()) for p in alive]


def _ended_cleanly(out: Path, code: int, err: str, words: str, returncode: int) -> None:
    from pipeline.stages import sweep as sweep_stage
    assert returncode == code, err
    assert "Traceback" not in err and "Error" not in err, err
    assert err.strip().splitlines()[-1] == f"hdi sweep: {words}; finished work is kept, run again to resume"
    assert not (out / runner.LOCK_NAME).exists()
    assert not list(out.glob(runner.STAGING_PREFIX + "*"))
    assert len(list((out / sweep_stage.PARTS).glob("batch-*.nc"))) >= 2


@pytest.mark.parametrize("signum, code, words", [
    (signal.SIGTERM, 143, "terminated (SIGTERM)"),
    (signal.SIGHUP, 129, "hung up (SIGHUP: the terminal closed)"),
    (signal.SIGQUIT, 131, "quit (SIGQUIT)"),
    (signal.SIGUSR1, 138, "ended by SIGUSR1"),
    pytest.param(signal.SIGUSR2, 140, "ended by SIGUSR2", marks=pytest.mark.slow)])
def test_sigterm_removes_the_lock_and_the_staging_folder_like_ctrl_c(tmp_path, signum, code, words):
    """What ``timeout``, SLURM's scancel and a requeue send (SIGTERM), and a closed terminal or a dropped ssh
    session (SIGHUP): the lock used to stay, refusing the rerun; SIGHUP killed the command outright, and so
    did SIGQUIT (Ctrl-\\) and SIGUSR1/2 (a batch system's warning of its time limit), without a line."""
    proc = _sweep(tmp_path)
    children = _two_parts_written(tmp_path, proc)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    _ended_cleanly(tmp_path, code, err, words, proc.returncode)
    assert _none_alive(children) == []


def test_a_hang_up_under_a_pipe_ends_with_129(tmp_path):
    """``hdi sweep ... 2>&1 | cat`` and the terminal closed: SIGHUP reaches both, the reader first; the last
    line's write then failed on the broken pipe and the command ended with exit 1, not 129."""
    log = (tmp_path / "log.txt").open("w")
    out = tmp_path / "out"
    proc = _sweep(out, stderr=subprocess.STDOUT, text=False)
    reader = subprocess.Popen(["cat"], stdin=proc.stdout, stdout=log)
    proc.stdout.close()
    _two_parts_written(out, proc)
    reader.send_signal(signal.SIGHUP)
    reader.wait(timeout=20)
    proc.send_signal(signal.SIGHUP)
    assert proc.wait(timeout=120) == 129
    assert not (out / runner.LOCK_NAME).exists() and not list(out.glob(runner.STAGING_PREFIX + "*"))


@pytest.mark.slow
def test_a_hang_up_of_the_whole_group_during_a_process_fan_out_ends_it_in_one_line_and_resumes(tmp_path):
    """The terminal closed while dask's worker processes ran the sweep: SIGHUP reaches the whole foreground
    group. The workers and multiprocessing's resource tracker died of it first, which printed a traceback per
    shared-memory name and raced the clean-up. Now the command alone answers it: one line, 129, no process
    left, the lock and the staging folder gone, and a rerun resumes from the parts kept."""
    import json
    proc = _sweep(tmp_path, "--scheduler", "processes")
    children = _two_parts_written(tmp_path, proc)
    assert len(children) >= 2  # (the two workers, the resource tracker)
    os.killpg(proc.pid, signal.SIGHUP)
    _, err = proc.communicate(timeout=180)
    _ended_cleanly(tmp_path, 129, err, "hung up (SIGHUP: the terminal closed)", proc.returncode)
    assert "resource_tracker" not in err and "KeyError" not in err, err
    assert _none_alive(children) == []
    from pipeline.stages import sweep as sweep_stage
    kept = len(list((tmp_path / sweep_stage.PARTS).glob("batch-*.nc")))
    again = _sweep(tmp_path)
    _, err = again.communicate(timeout=600)
    assert again.returncode == 0, err
    runs = [json.loads(line) for line in (tmp_path / ".hdi" / "runs.jsonl").read_text().splitlines()]
    assert runs[-1]["batches"] == LONG_BATCHES and runs[-1]["batches_run"] == LONG_BATCHES - kept


# ------------------------------------------------------------------------------ 7. interface labels
def test_interface_separation_labels_are_exact_for_sel(tmp_path):
    scene = load_scene(PAPER)
    ds = read_dataset(ensure("interface", scene, tmp_path))
    d = ds["separation"].values
    step = scene["solver"]["table_step_nm"]
    np.testing.assert_array_equal(d, np.round(d, 9))
    np.testing.assert_allclose(np.diff(d), step, rtol=0, atol=1e-9)
    for label in (0.0, -4.9, 30.0, 11.0):  # (-4.8999999999999995 and 30.000000000000007 before)
        assert float(ds["separation"].sel(separation=label)) == label
    assert d[0] <= min(scene["solver"]["table_min_sigma"] * float(ds["sigma_s"]), 11.0 - 15.0 - 1.0)
    assert d[-1] >= scene["solver"]["table_max_nm"]


# ------------------------------------------------------------------------------ 9. smaller items
def test_set_scene_extends_is_refused_in_one_line(tmp_path):
    from pipeline.config.scene import SceneError
    with pytest.raises(SceneError, match=r"^--set scene\.extends=base\.toml: scene\.extends cannot be set on the "
                                         r"command line; write `extends = \"base\.toml\"`"):
        load_scene(PAPER, ["scene.extends=base.toml"])


def test_a_scene_with_a_utf8_byte_order_mark_loads_like_without(tmp_path):
    text = PAPER.read_text()
    bom = tmp_path / "paper-2009.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert load_scene(bom).config == load_scene(PAPER).config


def test_a_folder_given_as_config_is_called_a_folder(tmp_path, capsys):
    assert cli.main(["simulate", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"hdi simulate: error: {tmp_path}: is a folder; expected a scene file (TOML), e.g. " \
                  "configs/paper-2009.toml"


def test_simulate_prints_the_regime_by_name(tmp_path, capsys):
    args = ["simulate", str(PAPER), "--out", str(tmp_path)]
    for s in FLY[1:3] + ["tfc.protrusion_nm=2.0", "contact.k=0.978"]:
        args += ["--set", s]
    assert cli.main(args) == 0
    lines = [line.split() for line in capsys.readouterr().err.splitlines() if line.strip().startswith("regime")]
    assert lines == [["regime", "flying"]]


def test_flying_point_has_no_nominal_area_to_compare(tmp_path):
    """A_n = 0 at a flying 11 nm point read "0 um^2 (-100 %)"."""
    import xarray as xr
    from pipeline.analyses import paper_comparison as report
    from pipeline.analyses.report_settings import ReportSettings
    from pipeline.analyses.sweep_slices import SweepSlice
    ds = xr.Dataset({"regime": ("protrusion", [0, 0]), "fhm_bv": ("protrusion", [12.0, 12.5]),
                     "nominal_area": ("protrusion", [0.0, 0.0])}, coords={"protrusion": [10.8, 11.0]})
    rows, notes = report._nominal_area_section(SweepSlice.of(ds, xr.Dataset()), ReportSettings.from_scene(None), None)
    assert rows == [["A_n at 11 nm", "62 um^2", "n/a: not in contact at 11 nm (flying)", "–"]] and notes == []
    ds["nominal_area"][:] = 61.0
    ds["regime"][:] = 2
    rows, _ = report._nominal_area_section(SweepSlice.of(ds, xr.Dataset()), ReportSettings.from_scene(None), None)
    assert rows[0][2:] == ["61 um^2", "-1 um^2 (-1.6 %)"]


def test_negative_k_probabilities_say_why_they_differ():
    from pipeline.analyses.paper_comparison import probability_text
    text = probability_text(-2.08)
    assert "two-sided 2 Q(|k|) = 3.8 %" in text and "98.1 % of the summits lie above it" in text
    assert "below the mean summit height" in text
    assert probability_text(0.978) == "k = 0.978: P(|z| > k sigma) = 32.8 % (two-sided), one-sided 16.4 %"


def test_readme_keeps_its_identification_section_when_the_report_has_none(tmp_path):
    from pipeline.analyses import narrative
    from pipeline.stages import report
    readme = tmp_path / "README.md"
    ident = (f"{narrative.IDENTIFICATION_HEADING}\n\nFrom `identify.nc` (1337 evaluations).\n\n| a | b |\n|---|---|\n"
             "| 1 | 2 |")
    readme.write_text(f"intro\n{narrative.README_BEGIN}\n## Comparison\n\nold table\n\n{ident}\n{narrative.README_END}\nend\n")
    report.update_readme(readme, "# Comparison\n\nnew table\n", tmp_path)  # (what `make run` then `make readme` gives)
    text = readme.read_text()
    assert "new table" in text and "old table" not in text
    assert ident in text and text.index(ident) < text.index(narrative.README_END)
    assert text.startswith("intro\n") and text.endswith(f"{narrative.README_END}\nend\n")
    # a report with its own identification section replaces the old one
    report.update_readme(readme, "# Comparison\n\nnewer\n\n## Paper, reconstructed scene, identified scene\n\nfresh\n",
                         tmp_path)
    text = readme.read_text()
    assert "fresh" in text and "1337" not in text and text.count(narrative.IDENTIFICATION_HEADING) == 1


def test_with_a_measured_record_the_synthesis_keys_change_no_inputs_key(tmp_path):
    """``--set dmw.rms_nm`` (documented as ignored for a measured record) recomputed the whole chain."""
    from pipeline.physics import microwaviness as phys_dmw
    rec = tmp_path / "record.csv"
    np.savetxt(rec, phys_dmw.synthesize(0.16, (1e4, 5e5), -2.0, 3e-3, 4e6, seed=5))
    base = [f"dmw.source={str(rec)!r}".replace("'", '"')]
    keys = {}
    for extra in ([], ["dmw.rms_nm=0.3"], ["dmw.seed=7"], ["dmw.exponent=-1.5"]):
        r = runner.Runner(load_scene(PAPER, base + extra), tmp_path / "out")
        keys[tuple(extra)] = (r.key("dmw"), r.key("sweep"), r.key("simulate"))
    assert len(set(keys.values())) == 1
    # with the synthetic record they are inputs
    syn = [runner.Runner(load_scene(PAPER, extra), tmp_path / "out").key("dmw") for extra in ([], ["dmw.rms_nm=0.3"])]
    assert syn[0] != syn[1]


# ------------------------------------------------------------------------------ 3. upper bounds
def test_limits_count_the_paper_scene_exactly(tmp_path):
    from pipeline import sizing as limits
    scene = load_scene(PAPER)
    sizes = {what.split(" (")[0]: n for what, n, _ in limits.sizes(scene, "run")}
    rows = read_dataset(ensure("interface", scene, tmp_path)).sizes["separation"]
    assert sizes == {"interface table rows": rows, "history samples per run": 8001, "DMW record samples": 8400,
                     "sweep scenes": 76, "kept history samples": 2 * 8001}  # (report.histories_nm: 5 and 11 nm)
    assert rows == 701


@pytest.mark.parametrize("override, what", [
    ("solver.table_step_nm=1e-5", "interface table rows"),
    ("solver.output_step_ns=1e-3", "history samples per run"),
    ("dmw.sample_rate_mhz=1e5", "DMW record samples"),
    ("sweep.realisations=10000", "sweep scenes"),
])
def test_a_size_beyond_its_limit_is_one_line_before_anything_runs_and_yes_lifts_it(tmp_path, capsys, override, what):
    from pipeline import sizing as limits
    if override.startswith("dmw."):
        override = [override, "dmw.band_khz=[10.0, 500.0]"]
    else:
        override = [override]
    args = ["sweep", str(PAPER), "--out", str(tmp_path / "out")]
    for s in override:
        args += ["--set", s]
    t0 = time.perf_counter()
    assert cli.main(args) == 2
    assert time.perf_counter() - t0 < 10
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f" {what} (" in err[0] and err[0].endswith("; pass --yes to run them anyway")
    assert not (tmp_path / "out").exists()
    limits.check_sizes(load_scene(PAPER, override), "sweep", yes=True)  # allowed with --yes


def test_a_protrusion_far_beyond_the_flying_height_is_refused_even_with_yes(tmp_path, capsys):
    """``--set tfc.protrusion_nm=1e6`` allocated a 20-million-row table and was OOM-killed."""
    assert cli.main(["interface", str(PAPER), "--out", str(tmp_path / "out"), "--yes",
                     "--set", "tfc.protrusion_nm=1e6"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"hdi interface: error: {PAPER}: tfc.protrusion_nm = 1e+06 nm: expected at most the flying height "
                   "air_bearing.flying_height_nm = 11 nm + 100 nm; an interference of 999989 nm is outside the "
                   "rough-surface contact model"]
    from pipeline.config.scene import SceneError
    with pytest.raises(SceneError, match="sweep.protrusion_nm stop = 200 nm"):
        load_scene(PAPER, ["sweep.protrusion_nm={start=0.0, stop=200.0, step=0.2}"])
    load_scene(PAPER, ["tfc.protrusion_nm=111.0"])  # the limit itself is allowed


def test_a_slider_shaken_beyond_its_flying_height_is_flagged_and_the_report_refuses_it(tmp_path, capsys):
    """A DMW of 5 nm rms under an 11 nm bearing: FHM 180 %, reported as results before."""
    args = ["report", str(PAPER), "--out", str(tmp_path)]
    for s in FLY + ["dmw.rms_nm=5.0", "report.histories_nm=[2.0]"]:
        args += ["--set", s]
    assert cli.main(args) == 2
    err = [line for line in capsys.readouterr().err.strip().splitlines() if "error" in line]  # (no progress)
    assert len(err) == 1, err
    assert err[0].startswith(f"hdi report: error: {tmp_path / 'sweep.nc'}: 3 of 3 scenes outside the model's validity "
                             "[protrusion 2, roughness sigma0.52nm_R5um_eta13.3, damping 0.05], [protrusion 2.2, ")
    assert err[0].endswith("the slider moved by more than the flying height (outside the air bearing's range); "
                           "no report drawn from them (see its variable validity)")
    sw = read_dataset(tmp_path / "sweep.nc")
    assert (sw["validity"].values == 1).all() and (sw["fhm_bv"].values > 100).all()
    assert not (tmp_path / "report").exists() and not (tmp_path / "figures").exists()
    # the paper's DMW amplitude: valid, reported
    ok = ["report", str(PAPER), "--out", str(tmp_path / "ok")]
    for s in FLY + ["report.histories_nm=[2.0]"]:
        ok += ["--set", s]
    assert cli.main(ok) == 0
    assert (read_dataset(tmp_path / "ok" / "sweep.nc")["validity"].values == 0).all()
