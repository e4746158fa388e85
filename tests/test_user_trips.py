"""What a new user trips over (issue 18): each test reproduces one probe that failed before.

A scheduler address that is not a dask scheduler, SIGTERM, the umask of written datasets, interface
coordinates ``.sel`` could not hit, unbounded sizes, and the smaller messages. (The time axis and the
ensemble's CF-1.8 are in ``test_variables.py`` and ``test_ensemble.py``; the resumed sweep in
``test_sweep.py``.)
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import numpy as np
import pytest

from pipeline import cli, runner
from pipeline.io import read_dataset, write_dataset
from pipeline.scene import load_scene
from pipeline.validation import OptionError, check_scheduler

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "configs" / "paper-2009.toml"
FLY = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
       "sweep.protrusion_nm={start=2.0, stop=2.4, step=0.2}", "sweep.batch_size=2"]


# ------------------------------------------------------------------------------ 2. --scheduler
class _Quiet(BaseHTTPRequestHandler):
    def do_GET(self):  # noqa: N802 (http.server's name)
        self.send_response(200)
        self.end_headers()
        self.wfile.write(b"dashboard")

    def log_message(self, *args):
        pass


@pytest.fixture
def http_server():
    """A plain HTTP server on loopback (what the dashboard port 8787 is)."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), _Quiet)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.fixture
def banner_server():
    """A TCP service that speaks first with a banner (like SSH): dask read it as a frame length."""
    srv = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve():
        srv.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = srv.accept()
            except socket.timeout:
                continue
            with conn:
                conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
                time.sleep(0.5)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    stop.set()
    thread.join()
    srv.close()


def test_an_http_server_is_not_a_scheduler_in_one_line_within_the_timeout(http_server):
    t0 = time.perf_counter()
    with pytest.raises(OptionError, match=r"answers but is not a dask scheduler \(no dask handshake within "
                                          r"1 s, as an HTTP server or dashboard does\)") as exc:
        check_scheduler(http_server, timeout=1.0)
    assert time.perf_counter() - t0 < 5 and "\n" not in str(exc.value)


def test_a_service_sending_a_banner_is_not_a_scheduler(banner_server):
    with pytest.raises(OptionError, match=r"not a dask scheduler \(it sent b'SSH-2.0-' instead of a dask handshake"):
        check_scheduler(banner_server, timeout=1.0)


def test_the_cli_says_so_in_one_line_and_writes_nothing(http_server, tmp_path, capsys):
    args = ["sweep", str(PAPER), "--out", str(tmp_path / "out"), "--scheduler", http_server]
    for s in FLY:
        args += ["--set", s]
    t0 = time.perf_counter()
    assert cli.main(args) == 2
    assert time.perf_counter() - t0 < 15  # (3 s handshake timeout; it hung for minutes)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"hdi sweep: error: --scheduler {http_server}: ")
    assert not (tmp_path / "out").exists()


def test_a_scheduler_without_workers_is_reported_and_one_with_workers_passes():
    from distributed import LocalCluster
    with LocalCluster(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1",
                      dashboard_address=None) as empty:
        with pytest.raises(OptionError, match=r"the dask scheduler has no workers \(0.5 s waited\)"):
            check_scheduler(empty.scheduler_address, timeout=3.0, worker_wait=0.5)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://",
                      host="127.0.0.1", dashboard_address=None) as cluster:
        check_scheduler(cluster.scheduler_address, timeout=3.0, worker_wait=0.5)  # no error


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
def test_sigterm_removes_the_lock_and_the_staging_folder_like_ctrl_c(tmp_path):
    """What ``timeout``, SLURM's scancel and a requeue send: the lock used to stay, refusing the rerun."""
    from pipeline.stages import sweep as sweep_stage
    cmd = [sys.executable, "-m", "pipeline.cli", "sweep", str(PAPER), "--out", str(tmp_path), "--workers", "2"]
    for s in FLY[:3] + ["sweep.protrusion_nm={start=0.0, stop=6.0, step=0.2}", "sweep.batch_size=1"]:
        cmd += ["--set", s]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    parts = tmp_path / sweep_stage.PARTS
    deadline = time.time() + 180
    while time.time() < deadline and len(list(parts.glob("batch-*.nc"))) < 2:
        time.sleep(0.05)
    assert (tmp_path / runner.LOCK_NAME).exists() and list(tmp_path.glob(runner.STAGING_PREFIX + "*"))
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1] == "hdi sweep: terminated (SIGTERM); finished work is kept, run again to resume"
    assert not (tmp_path / runner.LOCK_NAME).exists()
    assert not list(tmp_path.glob(runner.STAGING_PREFIX + "*"))
    assert len(list(parts.glob("batch-*.nc"))) >= 2


# ------------------------------------------------------------------------------ 7. interface labels
def test_interface_separation_labels_are_exact_for_sel(tmp_path):
    from pipeline.stages import interface
    scene = load_scene(PAPER)
    ds = read_dataset(interface.run(scene, tmp_path))
    d = ds["separation"].values
    step = scene["solver"]["table_step_nm"]
    np.testing.assert_array_equal(d, np.round(d, 9))
    np.testing.assert_allclose(np.diff(d), step, rtol=0, atol=1e-9)
    for label in (0.0, -4.9, 30.0, 11.0):  # (-4.8999999999999995 and 30.000000000000007 before)
        assert float(ds["separation"].sel(separation=label)) == label
    assert d[0] <= min(scene["solver"]["table_min_sigma"] * float(ds["sigma_s"]), 11.0 - 15.0 - 1.0)
    assert d[-1] >= scene["solver"]["table_max_nm"]
