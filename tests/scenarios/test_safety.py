"""Nothing lost, nothing silent (the file system and the processes): each test is one probe.

1. planted symbolic links inside a results folder (the lock, ``figures/``, ``.hdi/``, its run log, a
   dataset): refused in one line naming the link, the link's target untouched;
2. a signal caught and lost inside a C library's error check: never an exit 0 (the interrupt checks
   themselves: core/test_interrupts.py);
3. forked figure workers outliving a killed ``hdi``;
4. special files (a FIFO, ``/dev/zero``) as inputs, and file contents echoed in messages;
5. a dataset another process holds open for writing: busy, never replaced;
6. a results folder or scene name too long for the file system: one line before any stage runs.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from pipeline import cli, file_errors, folder_lock, io, paths, runner
from pipeline.config.scene import load_scene

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"


def _toy(tmp_path: Path) -> tuple:
    """A victim file outside the results folder and the results folder."""
    victim = tmp_path / "victim.txt"
    victim.write_text("a user's file")
    out = tmp_path / "out"
    out.mkdir()
    return victim, out


def _dataset() -> xr.Dataset:
    return xr.Dataset({"x": ("n", [1.0, 2.0], {"units": "1", "long_name": "x"})},
                      coords={"n": ("n", [0, 1], {"units": "1", "long_name": "n"})})


def _link_line(exc: OSError, link: Path) -> str:
    line = file_errors.os_error_line(exc)
    assert "\n" not in line and line.startswith(f"{link}: is a symbolic link (to ")
    assert line.endswith("hdi writes, locks and deletes no file through a link inside its results folder: "
                         "remove the link")
    return line


# ------------------------------------------------------------------------------------ 1. planted links
def test_a_lock_file_that_is_a_link_is_refused_and_its_target_kept(tmp_path):
    """hdi refuses a lock that is a link, rather than take the lock over and unlink the link's target."""
    victim, out = _toy(tmp_path)
    (out / runner.LOCK_NAME).symlink_to(victim)
    with pytest.raises(paths.LinkRefused) as info:
        with folder_lock.folder_lock(out):
            pass
    _link_line(info.value, out.resolve() / runner.LOCK_NAME)
    assert victim.read_text() == "a user's file" and (out / runner.LOCK_NAME).is_symlink()


def test_a_dangling_lock_link_is_refused_and_nothing_is_created(tmp_path):
    _, out = _toy(tmp_path)
    (out / runner.LOCK_NAME).symlink_to(tmp_path / "not-there")
    with pytest.raises(paths.LinkRefused):
        with folder_lock.folder_lock(out):
            pass
    assert not (tmp_path / "not-there").exists()


def test_the_cli_refuses_a_planted_lock_link_in_one_line(tmp_path, capsys):
    victim, out = _toy(tmp_path)
    (out / runner.LOCK_NAME).symlink_to(victim)
    assert cli.main(["dmw", str(PAPER), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    lock = out.resolve() / runner.LOCK_NAME
    assert len(err) == 1 and err[0].startswith(f"hdi dmw: error: {lock}: is a symbolic link")
    assert victim.read_text() == "a user's file" and sorted(p.name for p in out.iterdir()) == [runner.LOCK_NAME]


def _stage_writing(name: str, out_name: str, metrics: bool = False) -> runner.Stage:
    def compute(scene, inputs):
        if metrics:
            inputs.record(seconds=1.0)
        if out_name.endswith(".nc"):
            return {out_name: _dataset()}
        (inputs.staging / out_name).parent.mkdir(parents=True, exist_ok=True)
        (inputs.staging / out_name).write_text("drawn")
        return {}
    return runner.Stage(name, compute, outputs=(out_name,))


@pytest.mark.parametrize("planted, output, metrics", [
    ("figures", "figures/a.png", False),            # a folder of outputs
    (".hdi", "figures/a.png", False),                # the runner's records (manifests)
    (".hdi/runs.jsonl", "a.nc", True),               # the run log
    (".hdi/toy.json", "figures/a.png", False),       # a manifest
    ("a.nc", "a.nc", False),                         # a dataset
])
def test_a_planted_link_on_the_way_to_an_output_is_refused_before_computing(tmp_path, planted, output, metrics):
    """No PNG, record or run line is written through the link, outside the folder: refused first."""
    victim, out = _toy(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    link = out / planted
    link.parent.mkdir(parents=True, exist_ok=True)
    link.symlink_to(victim if "." in Path(planted).name and planted != ".hdi" else elsewhere)
    computed = []
    stage = _stage_writing("toy", output, metrics)
    stage = runner.Stage("toy", lambda s, i: (computed.append(1), stage.compute(s, i))[1], outputs=stage.outputs)
    with pytest.raises(paths.LinkRefused) as info:
        runner.Runner(load_scene(PAPER), out, {"toy": stage}).build(["toy"])
    _link_line(info.value, link)
    assert computed == []
    assert victim.read_text() == "a user's file" and list(elsewhere.iterdir()) == []
    assert link.is_symlink() and not (out / runner.LOCK_NAME).exists()


def test_a_link_planted_while_the_stage_computes_is_refused_at_the_write(tmp_path):
    victim, out = _toy(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()

    def compute(scene, inputs):
        (out / "figures").symlink_to(elsewhere)      # another user, while the stage runs
        (inputs.staging / "figures").mkdir()
        (inputs.staging / "figures" / "a.png").write_text("drawn")
        return {}
    stage = runner.Stage("toy", compute, outputs=("figures/a.png",))
    with pytest.raises(paths.LinkRefused):
        runner.Runner(load_scene(PAPER), out, {"toy": stage}).build(["toy"])
    assert list(elsewhere.iterdir()) == []


def test_write_dataset_and_the_run_log_refuse_links_below_a_held_folder(tmp_path):
    victim, out = _toy(tmp_path)
    (out / "d.nc").symlink_to(victim)
    (out / ".hdi").mkdir()
    (out / ".hdi" / runner.RUN_LOG).symlink_to(victim)
    with folder_lock.folder_lock(out):
        with pytest.raises(paths.LinkRefused):
            io.write_dataset(_dataset(), out / "d.nc", stage="test")
        with pytest.raises(paths.LinkRefused):
            paths.append_text(out / ".hdi" / runner.RUN_LOG, "{}\n")
    assert victim.read_text() == "a user's file"
    io.write_dataset(_dataset(), tmp_path / "free.nc", stage="test")   # (outside a held folder: no check)


def test_the_cleaner_removes_no_link_named_like_a_temporary_file(tmp_path):
    victim, out = _toy(tmp_path)
    link = out / f".sweep.nc.hdi-{'0' * 12}.tmp"
    link.symlink_to(victim)
    staging = out / (runner.STAGING_PREFIX + "x")
    staging.symlink_to(tmp_path)
    with folder_lock.folder_lock(out):
        pass
    assert link.is_symlink() and staging.is_symlink() and victim.read_text() == "a user's file"


def test_a_fifo_at_the_lock_name_is_refused_without_blocking(tmp_path):
    _, out = _toy(tmp_path)
    os.mkfifo(out / runner.LOCK_NAME)
    with pytest.raises(OSError) as info:
        with folder_lock.folder_lock(out):
            pass
    assert file_errors.os_error_line(info.value) == (f"{out.resolve() / runner.LOCK_NAME}: is a FIFO (named pipe), not hdi's "
                                            "lock file; remove it")


#: ``hdi report`` on the datasets of tests/report_data.py with no upstream stage; SIGTERM delivered
#: during the report's read of ``sweep.nc`` and swallowed there, as netCDF4's error check did.
_SWALLOWED = """
import dataclasses, os, signal, sys
from pipeline import cli, io, paths, runner
from pipeline.stages import report
stage = dataclasses.replace(report.STAGE, upstream=(), optional=())
runner.registry = lambda: {"report": stage}
real = io.xr.open_dataset

def swallowing(path, *args, **kwargs):
    ds = real(path, *args, **kwargs)
    if str(path).endswith("sweep.nc"):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10_000):
                pass
        except BaseException:
            pass
    return ds

io.xr.open_dataset = swallowing
sys.exit(cli.main(sys.argv[1:]))
"""


def test_sigterm_during_the_reports_netcdf_reads_never_ends_with_exit_0(tmp_path):
    """A SIGTERM that a C library's error check swallows during the report's NetCDF reads still ends the run
    (143 and one line): it never goes on to draw the report and exit 0."""
    from report_data import write_dmw, write_histories, write_roughness, write_sweep
    out = tmp_path / "out"
    out.mkdir()
    for write in (write_sweep, write_histories, write_dmw, write_roughness):
        write(out)
    done = subprocess.run([sys.executable, "-c", _SWALLOWED, "report", str(PAPER), "--out", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 143, done.stderr
    assert done.stderr.strip().splitlines()[-1] == ("hdi report: terminated (SIGTERM); finished work is kept, run "
                                                    "again to resume")
    assert not (out / "figures").exists() and not (out / runner.LOCK_NAME).exists()


# ------------------------------------------------------------------------------------ 3. figure workers
#: Draws two figures that never end in forked workers (each writes its pid first).
_DRAWING = """
import os, sys, time
from pipeline.analyses import plots

def forever(folder):
    (folder / f"{os.getpid()}.pid").write_text("")
    time.sleep(600)

from pathlib import Path
folder = Path(sys.argv[1])
plots.draw_all([(forever, (folder,), {}), (forever, (folder,), {})], workers=2)
"""


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"   # (a zombie is dead, waiting to be reaped)
    except (FileNotFoundError, ProcessLookupError):
        return False


def _kill_and_expect_no_worker(proc: subprocess.Popen, pids: Path, wait_s: float) -> None:
    """Wait for the two figure workers to write their pid files into ``pids``, SIGKILL ``proc`` (no handler
    of hdi runs) and expect no worker alive within 10 s; the workers are killed in any case."""
    try:
        deadline = time.monotonic() + wait_s
        while len(list(pids.glob("*.pid"))) < 2 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        workers = [int(p.stem) for p in pids.glob("*.pid")]
        assert len(workers) == 2 and proc.pid not in workers and all(_alive(w) for w in workers)
        proc.kill()
        proc.wait(timeout=10)
        deadline = time.monotonic() + 10
        while any(_alive(w) for w in workers) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not any(_alive(w) for w in workers)
    finally:
        proc.kill()
        for p in pids.glob("*.pid"):
            try:
                os.kill(int(p.stem), signal.SIGKILL)
            except ProcessLookupError:
                pass


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the figure pool forks on Linux only")
def test_figure_workers_die_with_a_killed_parent(tmp_path):
    """SIGKILL (or SIGHUP) of hdi while drawing ends its figure workers too: they would otherwise sleep forever,
    holding its stdout and stderr (``hdi run ... | tee log`` would never end)."""
    proc = subprocess.Popen([sys.executable, "-c", _DRAWING, str(tmp_path)], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _kill_and_expect_no_worker(proc, tmp_path, 60)


# ------------------------------------------------------------------------------------ 4. special files
def _hdi(args: list[str], timeout: float = 120) -> subprocess.CompletedProcess:
    """``hdi ARGS`` in a subprocess (a hang fails the test at ``timeout`` instead of blocking the run)."""
    return subprocess.run([sys.executable, "-m", "pipeline.cli", *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=timeout)


def _one_error(done: subprocess.CompletedProcess) -> str:
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    return lines[0]


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_special_file_as_the_dmw_record_is_refused_at_load(tmp_path, kind):
    """A FIFO or ``/dev/zero`` as ``dmw.source`` is refused at load, before its size is counted by reading it
    (which would hang)."""
    if kind == "fifo":
        source = tmp_path / "record.csv"
        os.mkfifo(source)
        what = "a FIFO (named pipe)"
    else:
        source, what = Path("/dev/zero"), "a character device"
    done = _hdi(["dmw", str(PAPER), "--out", str(tmp_path / "out"), "--set", f'dmw.source="{source}"'], timeout=60)
    assert _one_error(done) == (f"hdi dmw: error: {PAPER}: dmw.source: {source} is {what}; expected a regular file "
                                "(a CSV or NetCDF record)")
    assert not (tmp_path / "out").exists()


def test_the_record_reader_refuses_a_special_file_before_opening_it(tmp_path):
    from pipeline.model import measured_dmw
    from pipeline.physics.microwaviness import DMWError
    os.mkfifo(tmp_path / "record.csv")
    assert measured_dmw.record_samples(tmp_path / "record.csv") == 0
    with pytest.raises(DMWError, match=r"record\.csv: is a FIFO \(named pipe\); expected a regular file"):
        measured_dmw.load_record(tmp_path / "record.csv")


def test_a_fifo_as_the_scheduler_file_is_refused(tmp_path):
    fifo = tmp_path / "scheduler.json"
    os.mkfifo(fifo)
    done = _hdi(["sweep", str(PAPER), "--out", str(tmp_path / "out"), "--scheduler", str(fifo)], timeout=60)
    assert _one_error(done) == (f"hdi sweep: error: --scheduler {fifo}: is a FIFO (named pipe); expected the JSON "
                                "file `dask scheduler --scheduler-file FILE` writes, or tcp://HOST:PORT")


@pytest.mark.parametrize("content, kw", [
    (b"SHELL=/bin/bash\x00SECRET_TOKEN=abc123\x00HOME=/root\x00", {}),               # /proc/self/environ
    (b"SECRET_TOKEN=abc123\nHOME=/root\n", {"sample_rate_hz": 1e6}),                  # the same, as text
    (b"time,value\n0,1\n1e-6,SECRET_TOKEN=abc123\n", {}),                              # a data value
    (b"SECRET_TOKEN=abc123 HOME=/root\n1 2\n", {"column": "x", "sample_rate_hz": 1e6}),  # a header listed
    (b"time [s],x [SECRET_TOKEN=abc123]\n0,1\n1e-6,2\n", {}),                          # a unit
])
def test_record_errors_never_repeat_the_files_content(tmp_path, content, kw):
    """An error about a record names the file, never its content (``dmw.source = "/proc/self/environ"`` would
    print the environment)."""
    from pipeline.model import measured_dmw
    from pipeline.physics.microwaviness import DMWError
    path = tmp_path / "record.csv"
    path.write_bytes(content)
    with pytest.raises(DMWError) as info:
        measured_dmw.load_record(path, **kw)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and "\n" not in message
    assert "SECRET" not in message and "abc123" not in message and "HOME" not in message


def test_proc_self_environ_as_the_record_is_one_line_without_the_environment(tmp_path):
    done = _hdi(["dmw", str(PAPER), "-q", "--out", str(tmp_path), "--set", 'dmw.source="/proc/self/environ"',
                 "--set", "dmw.sample_rate_hz=1e6"], timeout=120)
    line = _one_error(done)
    assert re.fullmatch(r"hdi dmw: error: /proc/(self|\d+)/environ: not a text \(CSV\) file \(it holds NUL bytes\); "
                        r"expected CSV or NetCDF \(\.nc\)", line), line
    assert "PATH=" not in done.stderr and os.environ.get("HOME", "~") not in done.stderr


# ------------------------------------------------------------------------------------ 5. busy datasets
def test_a_dataset_another_process_writes_is_busy_and_never_replaced(tmp_path):
    """A dataset open for writing elsewhere is busy: never taken for one with "no inputs key" and replaced (that
    process's edit lost). The HDF5 file lock
    of a writer in this process stands in for another's (``flock`` locks conflict between open files)."""
    import netCDF4
    out = tmp_path / "out"
    computed = []
    stage = runner.Stage("toy", lambda scene, inputs: computed.append(1) or _dataset(), outputs=("a.nc",))
    io.write_dataset(_dataset(), out / "a.nc", stage="a user's")           # (no inputs key: stale)
    with netCDF4.Dataset(out / "a.nc", "a") as nc:
        nc.setncattr("edit", "being written")
        with pytest.raises(io.DatasetBusy) as info:
            runner.Runner(load_scene(PAPER), out, {"toy": stage}).build(["toy"])
        assert str(info.value) == (f"{out / 'a.nc'}: busy: another process has it open for writing (its HDF5 "
                                   "file lock); close it there, or wait for that process, and run again")
        with pytest.raises(io.DatasetBusy):
            io.read_dataset(out / "a.nc")
    assert computed == [] and netCDF4.Dataset(out / "a.nc").getncattr("edit") == "being written"
    assert not (out / runner.LOCK_NAME).exists()
    # closed: a user's file, replaced with force only (pipeline.runner.Runner.check_owners)
    with pytest.raises(runner.OutputRefused, match="not written by hdi"):
        runner.Runner(load_scene(PAPER), out, {"toy": stage}).build(["toy"])
    runner.Runner(load_scene(PAPER), out, {"toy": stage}).build(["toy"], force=True)
    assert computed == [1] and io.read_attrs(out / "a.nc")[0][io.KEY_ATTR]


def test_a_dataset_opened_for_writing_during_the_computation_is_not_replaced(tmp_path):
    import netCDF4
    out = tmp_path / "out"
    io.write_dataset(_dataset(), out / "a.nc", stage="toy", extra_attrs={io.KEY_ATTR: "of other inputs"})
    held = []

    def compute(scene, inputs):
        held.append(netCDF4.Dataset(out / "a.nc", "a"))     # another writer, while the stage runs
        return _dataset()
    with pytest.raises(io.DatasetBusy):
        runner.Runner(load_scene(PAPER), out, {"toy": runner.Stage("toy", compute, outputs=("a.nc",))}).build(["toy"])
    held[0].close()
    assert io.read_attrs(out / "a.nc")[0][io.KEY_ATTR] == "of other inputs"
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []   # no temporary file left
    assert not io.is_busy(out / "a.nc") and not io.is_busy(out / "missing.nc")


# ------------------------------------------------------------------------------------ 6. lengths
def test_a_long_scene_name_no_longer_lengthens_the_identified_scenes_file(tmp_path):
    """The identified scene is ``identified.toml`` whatever the scene's name, so a 250-character name (which
    ``<name>-identified.toml`` would exceed the file system with) passes the length check before any stage."""
    scene = load_scene(PAPER, [f'scene.name="{"a" * 250}"'])
    paths = runner.Runner(scene, tmp_path).written_paths(["identify"])
    assert f".identified.toml.hdi-{io.RUN_ID}.xxxxxxxx.tmp" in paths
    assert not any("a" * 250 in p for p in paths)
    runner.Runner(scene, tmp_path).check_lengths(["identify"])


def test_a_results_folder_too_long_for_the_reports_files_is_one_line_before_any_stage(tmp_path):
    """A 4030-byte ``--out`` is refused in one line before any stage, not at the report naming a temporary file."""
    limit = os.pathconf(tmp_path, "PC_PATH_MAX")
    out = tmp_path
    while len(os.fsencode(str(out))) < limit - 66 - 200:
        out = out / ("d" * 200)
    out = out / ("e" * (limit - 66 - len(os.fsencode(str(out))) - 1))
    assert len(os.fsencode(str(out))) == limit - 66
    done = _hdi(["report", str(PAPER), "--out", str(out)], timeout=120)
    line = _one_error(done)
    assert line.startswith(f"hdi report: error: {out}: the longest path this run writes, ")
    assert line.endswith(f" bytes long, the file system allows {limit - 1}; choose a shorter --out")
    assert not (tmp_path / ("d" * 200)).exists()


def test_the_paths_a_run_writes_include_temporary_names_and_what_stages_keep(tmp_path):
    scene = load_scene(PAPER)
    paths = runner.Runner(scene, tmp_path).written_paths(["identify", "report", "sweep"])
    assert f".identified.toml.hdi-{io.RUN_ID}.xxxxxxxx.tmp" in paths
    assert f"{runner.STAGING_PREFIX}xxxxxxxx/figures/.fig3_clearance.png.hdi-{io.RUN_ID}.xxxxxxxx.tmp" in paths
    assert f"sweep.parts/.batch-00000.nc.hdi-{io.RUN_ID}.xxxxxxxx.tmp" in paths
    runner.Runner(scene, tmp_path).check_lengths(["identify", "report", "sweep"])     # (a usual folder: passes)


def test_a_fifo_as_an_afm_file_is_refused_before_opening(tmp_path):
    fifo = tmp_path / "scan.ibw"
    os.mkfifo(fifo)
    done = _hdi(["roughness", str(fifo), "--out", str(tmp_path / "out")], timeout=120)
    assert _one_error(done) == (f"hdi roughness: error: {fifo}: is a FIFO (named pipe) (expected a regular file, an "
                                "AFM/profilometer height map in a format SurfaceTopography reads)")


def test_a_nested_results_folder_that_is_a_link_is_refused(tmp_path):
    """A stage's own sub-run (``sweep.parts/interface-<label>/``) locks no folder a planted link leads to."""
    _, out = _toy(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    with folder_lock.folder_lock(out):
        (out / "sweep.parts").mkdir()
        (out / "sweep.parts" / "interface-x").symlink_to(elsewhere)
        with pytest.raises(paths.LinkRefused):
            with folder_lock.folder_lock(out / "sweep.parts" / "interface-x"):
                pass
    assert list(elsewhere.iterdir()) == []


def test_a_worker_thread_finishing_while_the_main_thread_unwinds_keeps_its_output():
    """The check raises in the main thread only: a fan-out task still writes its finished part."""
    import threading
    from pipeline import interrupts
    raised = []

    def task():
        try:
            interrupts.check()
        except KeyboardInterrupt:
            raised.append(True)
    with interrupts.handling():
        interrupts._PENDING.append(signal.SIGTERM)
        worker = threading.Thread(target=task)
        worker.start()
        worker.join()
        with pytest.raises(interrupts.Terminated):
            interrupts.check()
        interrupts.answered()
    assert raised == []


def test_a_fifo_as_the_readme_page_is_refused_before_the_run():
    from pipeline.cli_checks import OptionError, check_readme
    import tempfile
    with tempfile.TemporaryDirectory() as folder:
        page = Path(folder) / "results.md"
        os.mkfifo(page)
        with pytest.raises(OptionError, match=r"results\.md: is a FIFO \(named pipe\); expected the page whose"):
            check_readme(page)


#: ``hdi report`` (no upstream stage) whose figures never finish: each forked worker writes its pid first.
_REPORT_DRAWING = """
import dataclasses, os, sys, time
from pathlib import Path
from pipeline import cli, runner
from pipeline.analyses import plots
from pipeline.stages import report
stage = dataclasses.replace(report.STAGE, upstream=(), optional=())
runner.registry = lambda: {"report": stage}
folder = Path(sys.argv[1])

def drawing(i):
    (folder / f"{os.getpid()}.pid").write_text("")
    time.sleep(600)

plots.pool._draw = drawing
sys.exit(cli.main(sys.argv[2:]))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the figure pool forks on Linux only")
def test_sigkill_of_hdi_report_during_figure_drawing_leaves_no_worker(tmp_path):
    from report_data import write_dmw, write_histories, write_roughness, write_sweep
    out, pids = tmp_path / "out", tmp_path / "pids"
    out.mkdir()
    pids.mkdir()
    for write in (write_sweep, write_histories, write_dmw, write_roughness):
        write(out)
    proc = subprocess.Popen([sys.executable, "-c", _REPORT_DRAWING, str(pids), "report", str(PAPER), "--out", str(out),
                             "-q"], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _kill_and_expect_no_worker(proc, pids, 120)


# ------------------------------------------ 7. stored datasets checked when read; inputs and others' files kept
def test_a_damaged_or_hand_edited_dmw_nc_is_recomputed_and_refused_when_opened(tmp_path, capsys):
    from damage import damage_chunk, edit_value
    from pipeline import api
    out = tmp_path / "out"
    assert cli.main(["dmw", str(PAPER), "--out", str(out), "-q"]) == 0
    w = io.read_dataset(out / "dmw.nc").displacement.values.copy()
    damage_chunk(out / "dmw.nc", "displacement")
    with pytest.raises(io.DatasetDamaged) as info:            # (RuntimeError: NetCDF: HDF error, before)
        api.open_dataset(out, "dmw")
    assert str(info.value) == (f"{out / 'dmw.nc'}: variable 'displacement': its data cannot be read back (NetCDF: "
                               "HDF error); run `hdi dmw` again: it recomputes a damaged dataset of its own")
    assert cli.main(["dmw", str(PAPER), "--out", str(out)]) == 0
    assert "dmw: computing (dmw.nc: variable 'displacement': its data cannot be read back" in capsys.readouterr().err
    np.testing.assert_array_equal(api.open_dataset(out, "dmw").displacement.values, w)
    edit_value(out / "dmw.nc", "displacement", (0,), 5.0)   # by hand: used with no warning, before
    with pytest.raises(io.DatasetDamaged, match="variable 'displacement': values differ from the checksum"):
        api.open_dataset(out, "dmw")
    assert cli.main(["dmw", str(PAPER), "--out", str(out)]) == 0
    assert "dmw: computing (dmw.nc: variable 'displacement': values differ" in capsys.readouterr().err
    np.testing.assert_array_equal(api.open_dataset(out, "dmw").displacement.values, w)


def test_a_record_given_at_the_outputs_path_and_others_files_are_never_replaced(tmp_path, capsys):
    first = tmp_path / "first"
    assert cli.main(["dmw", str(PAPER), "--out", str(first), "-q"]) == 0
    out = tmp_path / "out"
    out.mkdir()
    record = out / "dmw.nc"                                   # a user's record, under the stage's file name
    record.write_bytes((first / "dmw.nc").read_bytes())
    before = record.read_bytes()
    for force in ([], ["--force"]):                          # (overwritten by the output, before)
        assert cli.main(["dmw", str(PAPER), "--out", str(out), "--set", f'dmw.source="{record}"', *force]) == 2
        assert capsys.readouterr().err.strip() == (
            f"hdi dmw: error: dmw.source = {record}: is the file dmw.nc the dmw stage writes in the results folder "
            f"{out}; an input is never overwritten by an output: move it out of the results folder, or choose "
            "another --out")
        assert record.read_bytes() == before
    other = ["--set", 'scene.name="other"', "--set", "dmw.rms_nm=0.3"]   # another scene into the folder
    assert cli.main(["dmw", str(PAPER), "--out", str(first), *other]) == 2
    assert capsys.readouterr().err.strip() == (
        f"hdi dmw: error: {first / 'dmw.nc'}: results of the scene 'paper-2009', not of this run's 'other'; run each "
        "scene into its own folder (--out; the default is results/<scene name>/), or pass --force to replace them")
    assert io.read_dataset(first / "dmw.nc").attrs["scene_name"] == "paper-2009"
    assert cli.main(["dmw", str(PAPER), "--out", str(first), *other, "--force", "-q"]) == 0
    assert io.read_dataset(first / "dmw.nc").attrs["scene_name"] == "other"
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "dmw.nc").write_text("my own notes, not a dataset\n")     # a file hdi did not write
    assert cli.main(["dmw", str(PAPER), "--out", str(mine)]) == 2
    assert "dmw.nc: not written by hdi (no dmw stage's record of it)" in capsys.readouterr().err
    assert (mine / "dmw.nc").read_text() == "my own notes, not a dataset\n"
