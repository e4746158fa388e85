"""Every fault in one line: each test is one probe that could end in a traceback, fail late or silently,
or (the Python API) raise an undocumented error, and checks the one line or the documented error it gets.
"""

from __future__ import annotations

import math
import socket
import struct
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from pipeline import cli, fanout
from pipeline.cluster import ClusterError
from pipeline.cli_checks import OptionError, check_options, check_scheduler
from pipeline.config import limits
from pipeline.config.scene import SceneError, load_scene
from pipeline.io import DatasetError

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"
#: A flying scene of short runs (no contact law: no calibration, no interface tables).
FLY = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
       "sweep.protrusion_nm={start=2.0, stop=2.4, step=0.2}", "sweep.batch_size=1"]


def _sets(overrides: list[str]) -> list[str]:
    return [a for s in overrides for a in ("--set", s)]


def _one_line(capsys, prefix: str) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert err and "Traceback" not in "\n".join(err)
    assert err[-1].startswith(prefix), err
    return err[-1]


# ------------------------------------------------------------------------------ the scheduler lost
def _slow_task(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def test_a_scheduler_lost_mid_batch_is_one_line_to_rerun():
    """A real in-process dask scheduler, closed after the first result: dask cancels the futures it held
    (``FuturesCancelledError`` escaped ``fanout``, which caught only TimeoutError around its wait)."""
    from distributed import LocalCluster
    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://",
                           host="127.0.0.1", dashboard_address=None)
    done = []

    def close_after_first(result):
        done.append(result)
        if len(done) == 1:
            cluster.close()

    try:
        with pytest.raises(ClusterError) as exc:
            fanout.run_tasks(_slow_task, [(0.3,)] * 6, scheduler=cluster.scheduler_address, on_done=close_after_first)
    finally:
        cluster.close()
    text = str(exc.value)
    assert "\n" not in text and len(done) == 1
    # (dask cancels the futures it held, or the stall watch's next question finds no scheduler first: which one
    # comes first depends on the host's timing; both are the one line)
    assert text.startswith(tuple(f"dask scheduler {cluster.scheduler_address}: {what}"
                                 for what in ("lost with ", "stopped answering (")))
    assert text.endswith("finished work is kept, run again to resume")


# ------------------------------------------------------------------------------ heater stepping
def test_a_stepping_sweep_gives_the_ensemble_and_the_report_its_upward_pass():
    """``hdi run --set sweep.protocol=stepping`` ended in an IndexError at the ensemble stage: the
    ``(protrusion, direction)`` regimes were read as one flat list of twice the protrusions."""
    from pipeline.analyses.sweep_slices import combinations, first_contact, split_ensemble
    from pipeline.model.simulation import simulate
    from pipeline.model import outcomes
    from pipeline.stages import ensemble
    from slider_scenes import build, make_scene
    scene = make_scene(["air_bearing", "pitch", "contact"], solver={"duration_ms": 0.3, "transient_ms": 0.1})
    prot = [9.0, 10.0, 11.0, 12.0, 13.0]
    chain = simulate(build(scene), prot, protocol="stepping")
    up = chain.sel(direction="up")
    touched = outcomes.touched_in_summary(up["min_clearance"].values)
    assert touched.any() and not touched.all()  # (a touchdown inside the chain: the case that failed)
    sweep, whole = split_ensemble(chain)
    assert whole is None and "direction" not in sweep.dims
    (_, ds), = combinations(sweep)
    fc = first_contact(ds)
    # the upward pass's first protrusion in contact: the chain's touchdown
    assert fc == float(chain["touchdown_protrusion"]) == prot[int(np.argmax(touched))]
    assert first_contact(chain) == fc  # (a slice with both passes: the upward one)
    pts = ensemble.protrusions(scene, chain)
    assert {p for p in prot if abs(p - fc) <= ensemble.WINDOW_NM} <= set(pts)


# ------------------------------------------------------------------------------ bounds at load
@pytest.mark.parametrize("override, message", [
    ("solver.max_step_ns=1e-6", r"solver\.max_step_ns = 1e-06: a run of solver\.duration_ms = 2 needs at least 2e\+12 "
                                r"steps of it, beyond the integrator's 5,000,000; expected at least 0\.4 ns"),
    ("lubricant.work_of_adhesion_j_m2=1e99", r"lubricant\.work_of_adhesion_j_m2 = 1e\+99: expected a number in \[0, 1\] "
                                             r"J/m\^2"),
    ("sensitivity.bootstrap=1000000000", r"sensitivity\.bootstrap = 1000000000: expected an integer in \[10, 100,000\]"),
    ("sweep.histories_nm=[5.0, 11.0, 5.0]", r"sweep\.histories_nm = \[5\.0, 11\.0, 5\.0\]: 5 appears more than once; "
                                            r"expected distinct protrusions"),
    ("report.histories_nm=[11.0, 11.0]", r"report\.histories_nm = \[11\.0, 11\.0\]: 11 appears more than once"),
])
def test_a_hopeless_value_is_refused_at_load_in_one_line(override, message):
    with pytest.raises(SceneError, match=message) as exc:
        load_scene(PAPER, [override])
    assert "\n" not in str(exc.value)


def test_the_step_bound_is_the_integrators_budget():
    import inspect
    from pipeline.model.running import run_model
    assert inspect.signature(run_model).parameters["max_steps"].default == limits.MAX_STEPS
    # the largest step that can still finish a run loads; a hair below it does not
    assert load_scene(PAPER, ["solver.max_step_ns=0.4"])["solver"]["max_step_ns"] == 0.4
    with pytest.raises(SceneError, match="max_step_ns"):
        load_scene(PAPER, ["solver.max_step_ns=0.3999"])


def test_a_file_name_that_is_no_folder_name_is_refused_at_load(tmp_path, capsys):
    """A scene file ``paper-2009 (copy).toml`` without ``scene.name`` failed only at the sweep, after
    roughness, dmw, interface and calibrate had run."""
    text = PAPER.read_text().replace('name = "paper-2009"\n', "")
    copy = tmp_path / "paper-2009 (copy).toml"
    copy.write_text(text)
    with pytest.raises(SceneError, match=r"scene\.name is missing and the file name gives 'paper-2009 \(copy\)': "
                                         r"expected scene\.name = a name of letters"):
        load_scene(copy)
    assert cli.main(["run", str(copy), "--out", str(tmp_path / "out")]) == 2
    _one_line(capsys, f"hdi run: error: {copy}: scene.name is missing")
    assert not (tmp_path / "out").exists()
    (tmp_path / "paper-2009-copy.toml").write_text(text)  # (a name the folder can take loads)
    assert load_scene(tmp_path / "paper-2009-copy.toml").name == "paper-2009-copy"


def test_the_histories_a_whole_sweep_keeps_are_bounded_before_it_runs(tmp_path):
    """Each run within the per-run limit of history samples, the sweep's total unchecked: a MemoryError."""
    over = ["solver.duration_ms=100", "solver.output_step_ns=100", "sweep.histories_nm=[2.0, 4.0, 6.0, 8.0, 10.0]"]
    # 1,000,001 samples per run (within 2,000,000) x 5 histories x 3 damping ratios: 15 million, kept
    check_options("sweep", load_scene(PAPER, over + ["sweep.damping_ratio=[0.03, 0.05, 0.07]"]), out=tmp_path)
    many = load_scene(PAPER, over + ["sweep.damping_ratio=[0.03, 0.04, 0.05, 0.06, 0.07]"])  # 25 million
    with pytest.raises(OptionError, match=r": 25,000,025 kept history samples \(5 protrusions of sweep\.histories_nm "
                                          r".* exceed 20,000,000; pass --yes to run them anyway$"):
        check_options("sweep", many, out=tmp_path)
    check_options("sweep", many, out=tmp_path, yes=True)  # (a big job that is legitimate)


# ------------------------------------------------------------------------------ a fake handshake
@pytest.fixture
def fake_dask_server():
    """A loopback server that sends what looks like a dask handshake (a length, then a body naming
    ``pickle-protocol`` and ``compression``) and then garbage: dask's frame reader raised struct.error.
    It serves for at most 20 s and closes itself."""
    srv = socket.create_server(("127.0.0.1", 0))
    body = b"pickle-protocol compression \xff\xfe garbage"
    stop = threading.Event()

    def serve():
        srv.settimeout(0.2)
        end = time.monotonic() + 20
        while not stop.is_set() and time.monotonic() < end:
            try:
                conn, _ = srv.accept()
            except socket.timeout:
                continue
            with conn:
                conn.sendall(struct.pack("<Q", len(body)) + body)
                time.sleep(0.3)
        srv.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    stop.set()
    thread.join()


def test_a_server_imitating_the_dask_handshake_fails_closed_in_one_line(fake_dask_server, tmp_path, capsys):
    with pytest.raises(OptionError, match=r"answers with a dask-like handshake but not as a dask scheduler "
                                          r"\(error: ") as exc:
        check_scheduler(fake_dask_server, timeout=1.0, worker_wait=1.0)
    assert "\n" not in str(exc.value)
    args = ["sweep", str(PAPER), "--out", str(tmp_path / "out"), "--scheduler", fake_dask_server, *_sets(FLY)]
    assert cli.main(args) == 2
    _one_line(capsys, f"hdi sweep: error: --scheduler {fake_dask_server}: answers with a dask-like handshake")
    assert not (tmp_path / "out").exists()
    with pytest.raises(ClusterError, match=r"answers, but not as a dask scheduler \(error\)"):
        fanout.cluster_threads(fake_dask_server)  # (a scheduler replaced mid-run: the fan-out's own connection)
    # (and the failed connections leave dask's default scheduler as it was, which tests/conftest.py's autouse
    # guard asserts after every test: xarray's to_netcdf in this process once asked for a client that did not exist)


def _open_clients() -> list:
    """The ``distributed.Client`` objects alive in this process and not closed."""
    import gc
    from distributed import Client
    return [c for c in gc.get_objects() if issubclass(type(c), Client) and c.status != "closed"]  # (type: no proxy)


def test_a_failed_connection_leaves_no_half_built_client_for_the_garbage_collector(fake_dask_server):
    """A Client whose constructor failed stayed alive through the error's frames (the caller's ClusterError
    holds it as ``__context__``, as ``pytest.raises`` holds that) and was closed by the garbage collector at
    an arbitrary moment: inside the next Client's event-loop start, where it deadlocked (this file's
    handshake test, run alone, hung). It is closed where it failed."""
    assert _open_clients() == []
    with pytest.raises(ClusterError) as exc:
        fanout.cluster_threads(fake_dask_server)
    assert exc.value.__context__ is not None  # (the constructor's error, and its frames, are still held)
    assert _open_clients() == []
    with pytest.raises(OptionError):
        check_scheduler(fake_dask_server, timeout=1.0, worker_wait=1.0)
    assert _open_clients() == []


# ------------------------------------------------------------------------------ a failed integration
def test_a_failed_integration_is_one_line_naming_the_scene_the_protrusion_and_what_to_change(tmp_path, capsys,
                                                                                            monkeypatch):
    """``solver.duration_ms=100`` on the two-population scene at 10 nm with k = 0.5 took 5,000,000 steps
    (chattering on the contact criterion) and the IntegrationError, a RuntimeError, escaped the CLI's
    one-line path as a traceback. The same failure here in a second: the integrator's step budget
    lowered to 200 steps (a 0.6-ms flying run needs more than 1,200 of 500 ns)."""
    from pipeline.model import running
    from pipeline.model.state import MAX_STEPS
    monkeypatch.setattr(running.run_model, "__defaults__", (None, 200))
    args = ["simulate", str(PAPER), "--out", str(tmp_path), *_sets(FLY[:3] + ["tfc.protrusion_nm=2.0"])]
    assert cli.main(args) == 2
    line = _one_line(capsys, f"hdi simulate: error: {PAPER} (scene paper-2009): integration failed at protrusion 2 nm: "
                             "too many steps (steps 200, ")
    assert line.endswith("); " + running.HINTS[MAX_STEPS])  # (the scene keys to change)


# ------------------------------------------------------------------------------ ensemble and report fan out
@pytest.mark.parametrize("stage", ["ensemble", "report"])
def test_the_ensemble_and_the_report_take_the_scheduler_like_the_other_fan_out_stages(stage, tmp_path, capsys,
                                                                                       monkeypatch):
    """They refused ``--scheduler`` and ``--workers`` and silently ignored ``DASK_SCHEDULER_ADDRESS``, though
    ``--help`` lists the ensemble among the fan-out stages (and the report makes it current)."""
    scene = load_scene(PAPER)
    assert check_options(stage, scene, out=tmp_path, scheduler="threads", workers=2) == "threads"
    closed = socket.create_server(("127.0.0.1", 0))
    port = closed.getsockname()[1]
    closed.close()  # (nothing listens there now)
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", f"tcp://127.0.0.1:{port}")
    with pytest.raises(OptionError, match=rf"^DASK_SCHEDULER_ADDRESS=tcp://127\.0\.0\.1:{port}: no scheduler answers"):
        check_options(stage, scene, out=tmp_path)
    assert cli.main([stage, str(PAPER), "--out", str(tmp_path / "out")]) == 2
    _one_line(capsys, f"hdi {stage}: error: DASK_SCHEDULER_ADDRESS=tcp://127.0.0.1:{port}: no scheduler answers")
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------------------ the Python API
API_FLY = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
           "sweep.protrusion_nm={start=4.0, stop=5.0, step=0.5}"]


@pytest.fixture(scope="module")
def api_model():
    import pipeline as hdi
    scene = hdi.load_scene(PAPER, API_FLY)
    return scene, hdi.build_model(scene)


def _calls(scene, model, tmp: Path):
    """``(call, error class, message)``: arguments of the wrong type or range; each raised TypeError,
    AttributeError or a raw OSError, or (a negative protrusion) returned results marked valid."""
    import pipeline as hdi
    afile = tmp / "afile.txt"
    afile.write_text("x")
    return [
        (lambda: hdi.load_scene(123), SceneError, r"^load_scene: path = 123: expected the path of a scene file"),
        (lambda: hdi.load_scene(None), SceneError, r"^load_scene: path = None: expected the path"),
        (lambda: hdi.load_scene(PAPER, b"contact.k=0.5"), SceneError,  # (one str is one override: core/test_api.py)
         r"^load_scene: overrides = b'contact.k=0.5': expected a list of \"section.key=value\" strings"),
        (lambda: hdi.load_scene(PAPER, [0.5]), SceneError, r"^load_scene: overrides\[0\] = 0.5: expected a"),
        (lambda: hdi.load_scene(PAPER, None), SceneError, r"^load_scene: overrides = None: expected a list"),
        (lambda: hdi.build_model(123), SceneError, r"^scene = 123: expected a scene \(load_scene\) or the path"),
        (lambda: hdi.build_model(scene, afile), OptionError, rf"^results = '{afile}': is a file; expected a folder"),
        (lambda: hdi.build_model(scene, 42), OptionError, r"^results = 42: expected a path"),
        (lambda: hdi.build_model(scene, k="0.5"), SceneError, r"^k: contact\.k = '0\.5': expected a number"),
        (lambda: hdi.build_model(scene, k=math.nan), SceneError, r"^k: contact\.k = nan: expected a finite number"),
        (lambda: hdi.simulate(model, 9.0), OptionError, r"^protrusions = 9\.0: expected a list of protrusions \[nm\] "
                                                        r"\(e\.g\. \[9\.0\] for one\), got float"),
        (lambda: hdi.simulate(model, "9"), OptionError, r"^protrusions = '9': expected a list"),
        (lambda: hdi.simulate(model, [-1.0]), OptionError, r"^protrusions\[0\] = -1\.0: expected a number >= 0 "
                                                           r"\[nm\], finite \(as tfc\.protrusion_nm\)"),
        (lambda: hdi.simulate(model, [9.0, math.nan]), OptionError, r"^protrusions\[1\] = nan: expected a number >= 0"),
        (lambda: hdi.simulate(model, [1e6]), OptionError, r"^protrusions\[0\] = 1e\+06 nm: expected at most the "
                                                          r"flying height 11 nm \+ 100 nm"),
        (lambda: hdi.simulate(model, ["9"]), OptionError, r"^protrusions\[0\] = '9': expected a number \[nm\], got str"),
        (lambda: hdi.simulate(model, []), OptionError, r"^protrusions = \[\]: expected at least one protrusion"),
        (lambda: hdi.simulate(model, [9.0], histories=9.0), OptionError, r"^histories = 9\.0: expected a list"),
        (lambda: hdi.simulate("model", [9.0]), ValueError, r"^model = 'model': expected the model of build_model"),
        (lambda: hdi.simulate(model, [9.0], counters="yes"), OptionError, r"^counters = 'yes': expected True or False"),
        (lambda: hdi.histories_of(None), ValueError, r"^histories_of: expected the dataset of simulate"),
        (lambda: hdi.open_dataset(123, "sweep"), OptionError, r"^results = 123: expected a path"),
        (lambda: hdi.open_dataset(tmp, 7), ValueError, r"^name = 7: expected a stage"),
        (lambda: hdi.open_dataset(afile, "sweep"), DatasetError, rf"^{afile}: is a file; expected a results folder"),
        (lambda: hdi.run_stage("sweep", scene, tmp / "o", workers="2"), OptionError,
         r"^workers = '2': expected a positive integer number of local workers \(1 or more\), got str"),
        (lambda: hdi.run_stage("sweep", scene, tmp / "o", workers=2.0), OptionError, r"^workers = 2\.0: expected"),
        (lambda: hdi.run_stage("sweep", scene, tmp / "o", scheduler=8786), OptionError,
         r"^scheduler = 8786: expected an address"),
        (lambda: hdi.run_stage("sweep", scene, tmp / "o", force="no"), OptionError, r"^force = 'no': expected True"),
        (lambda: hdi.run_stage("sweep", scene, tmp / "o", yes=1), OptionError, r"^yes = 1: expected True or False"),
        (lambda: hdi.run_stage("sweep", scene, 3.5), OptionError, r"^out = 3\.5: expected a path"),
        (lambda: hdi.run_stage(None, scene, tmp / "o"), ValueError, r"^stage = None: expected a stage name"),
        (lambda: hdi.run(scene, afile), OptionError, rf"^out = '{afile}': is a file; expected a folder"),
    ]


def test_the_api_raises_its_documented_errors_for_bad_arguments(api_model, tmp_path):
    """22 calls raised TypeError, AttributeError or a raw OSError; ``simulate(model, [-1.0])`` returned
    results marked valid where the command line refuses a negative protrusion. Each is now the error
    the API documents (pipeline/api.py), in one line, before anything runs or is written."""
    scene, model = api_model
    for call, error, message in _calls(scene, model, tmp_path):
        with pytest.raises(error, match=message) as exc:
            call()
        assert "\n" not in str(exc.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile.txt"]


def test_the_api_refuses_a_folder_it_cannot_write_even_when_up_to_date(api_model, tmp_path, monkeypatch):
    """An up-to-date results folder made read-only: building its model raised a raw PermissionError (the
    runner locks the folder). As root every folder is writable, so there the file system's refusal is
    emulated where the check meets it (``tempfile.mkstemp`` in the folder)."""
    import os
    import tempfile
    import pipeline as hdi
    scene, _ = api_model
    folder = tmp_path / "res"
    hdi.build_model(scene, folder)  # (made current)
    os.chmod(folder, 0o555)
    try:
        if os.geteuid() == 0:
            real = tempfile.mkstemp

            def refuse(*args, dir=None, **kw):
                if dir is not None and Path(dir) == folder:
                    raise PermissionError(13, "Permission denied")
                return real(*args, dir=dir, **kw)
            monkeypatch.setattr(tempfile, "mkstemp", refuse)
        with pytest.raises(OptionError, match=rf"^results = '{folder}': not writable: Permission denied$"):
            hdi.build_model(scene, folder)
    finally:
        os.chmod(folder, 0o755)


def test_a_failed_integration_from_the_api_is_the_same_one_line(api_model, monkeypatch):
    """NaN protrusions reached the integrator (an IntegrationError without the scene or what to change)."""
    import pipeline as hdi
    scene, model = api_model
    from pipeline.model import running
    monkeypatch.setattr(running.run_model, "__defaults__", (None, 200))
    with pytest.raises(running.IntegrationError, match=rf"^{PAPER} \(scene paper-2009\): integration failed at protrusion "
                                                  r"4\.5 nm: too many steps .*; shorten solver\.duration_ms"):
        hdi.simulate(model, [4.5])


def test_memory_no_limit_foresaw_is_one_line(tmp_path, capsys, monkeypatch):
    """The sizes of config/limits.py are checked before a run; a MemoryError past them (a machine with
    less memory than they assume) is one line, not a traceback."""
    from pipeline import runner

    def exhausted(self, targets, force=False):
        raise MemoryError()
    monkeypatch.setattr(runner.Runner, "build", exhausted)
    assert cli.main(["sweep", str(PAPER), "--out", str(tmp_path), *_sets(FLY)]) == 2
    _one_line(capsys, "hdi sweep: error: out of memory (MemoryError); finished work is kept")


@pytest.mark.slow
def test_hdi_run_with_heater_stepping_finishes(tmp_path, capsys):
    """The probe itself: ``hdi run --set sweep.protocol=stepping`` (short runs, a grid through touchdown)
    stopped at the ensemble stage with an IndexError; now the ensemble and the report are written."""
    import xarray as xr
    over = ["sweep.protocol=stepping", "solver.duration_ms=0.5", "solver.transient_ms=0.2", "contact.k=0.978",
            "sweep.protrusion_nm={start=5.0, stop=9.0, step=0.5}", "report.realisations=2",
            "report.histories_nm=[5.0, 9.0]"]
    assert cli.main(["run", str(PAPER), "--out", str(tmp_path), "-q", *_sets(over)]) == 0, capsys.readouterr().err
    sweep = xr.open_dataset(tmp_path / "sweep.nc", engine="netcdf4")
    ens = xr.open_dataset(tmp_path / "ensemble.nc", engine="netcdf4")
    td = float(sweep["touchdown_protrusion"].squeeze())
    assert 5.0 < td <= 9.0  # (the chain touched down inside the grid: the case that failed)
    # the ensemble runs the grid points within its window of the upward pass's first contact
    from pipeline.stages.ensemble import WINDOW_NM
    assert {p for p in np.arange(5.0, 9.01, 0.5) if abs(p - td) <= WINDOW_NM} <= set(ens["protrusion"].values)
    assert (tmp_path / "report" / "summary.md").is_file()
