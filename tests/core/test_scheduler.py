"""The --scheduler check (pipeline.scheduler.check_scheduler): an HTTP server (a dashboard port) or a service
that speaks first is no dask scheduler, said in one line within the handshake timeout, before the command writes
anything; a scheduler without workers is reported and one with a worker passes."""

from __future__ import annotations

import socket
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from pipeline import cli
from pipeline.options import OptionError
from pipeline.scheduler import check_scheduler

PAPER = Path(__file__).resolve().parents[2] / "configs" / "paper-2009.toml"
#: A short flying sweep (the command must refuse the scheduler before it runs any of it).
FLY = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
       "sweep.protrusion_nm={start=2.0, stop=2.4, step=0.2}", "sweep.batch_size=2"]


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
