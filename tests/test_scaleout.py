"""Scale-out for real: a `dask scheduler` and two `dask worker` processes on loopback, each in its own
working directory, and `hdi sweep --scheduler tcp://127.0.0.1:PORT` gives the dataset of a local run."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pipeline.io import read_dataset

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "configs" / "paper-2009.toml"
DASK = Path(sys.executable).with_name("dask")

#: 3 protrusions x 2 damping ratios in batches of 2: 4 tasks over the two workers; k fixed (no calibration).
SMALL = ["solver.duration_ms=0.6", "solver.transient_ms=0.2", "contact.k=0.5",
         "sweep.protrusion_nm={start=9.5, stop=10.5, step=0.5}", "sweep.batch_size=2",
         "sweep.damping_ratio=[0.03, 0.05]", "sweep.histories_nm=[10.0]"]
#: Global attributes that legitimately differ between two runs: when they ran (history). Timings go to
#: the run log, and the inputs are identified by the runner's keys, not by paths or file bytes.
DIFFERING = ("history",)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_port(port: int, proc: subprocess.Popen, timeout: float = 60.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if proc.poll() is not None:
            raise RuntimeError(f"dask scheduler exited with {proc.returncode}")
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1.0):
                return
        except OSError:
            time.sleep(0.2)
    raise TimeoutError(f"no dask scheduler on port {port} after {timeout} s")


def _hdi(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "pipeline.cli", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


@pytest.fixture()
def cluster(tmp_path):
    """``tcp://127.0.0.1:PORT`` of a scheduler and two single-threaded workers (always torn down)."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, PYTHONPATH=str(ROOT))  # the workers import this checkout's pipeline
    procs: list[subprocess.Popen] = []

    def start(args: list[str], where: str) -> subprocess.Popen:
        cwd = tmp_path / where
        cwd.mkdir()
        p = subprocess.Popen([str(DASK), *args], cwd=cwd, env=env, stdout=subprocess.DEVNULL,
                             stderr=(cwd / "log.txt").open("w"), start_new_session=True)
        procs.append(p)
        return p

    try:
        sched = start(["scheduler", "--host", "127.0.0.1", "--port", str(port), "--dashboard-address", ":0"],
                      "scheduler")
        _wait_for_port(port, sched)
        for i in (1, 2):
            start(["worker", address, "--nthreads", "1", "--nworkers", "1", "--no-dashboard",
                   "--local-directory", str(tmp_path / f"worker{i}" / "dask-scratch")], f"worker{i}")
        from distributed import Client
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=90)
            assert len(client.scheduler_info()["workers"]) == 2
        yield address
    finally:
        for p in reversed(procs):  # our own processes only, by their process group id
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait(timeout=10)


@pytest.mark.slow
def test_sweep_on_a_remote_cluster_equals_the_local_run(cluster, tmp_path):
    sets = [a for s in SMALL for a in ("--set", s)]
    remote = _hdi("sweep", str(PAPER), *sets, "--scheduler", cluster, "--out", str(tmp_path / "remote"),
                  cwd=tmp_path)
    assert remote.returncode == 0, remote.stderr
    local = _hdi("sweep", str(PAPER), *sets, "--workers", "2", "--out", str(tmp_path / "local"), cwd=tmp_path)
    assert local.returncode == 0, local.stderr
    for name in ("sweep.nc", "sweep_histories.nc"):
        a, b = read_dataset(tmp_path / "remote" / name), read_dataset(tmp_path / "local" / name)
        assert a.sizes["protrusion"] >= 1 and a.sizes["damping"] == 2
        differing = sorted(k for k in set(a.attrs) | set(b.attrs) if a.attrs.get(k) != b.attrs.get(k))
        assert set(differing) <= set(DIFFERING), differing
        # made from the same inputs (the runner's key covers the scene, the files and the upstream stages)
        assert a.attrs["inputs_key"] == b.attrs["inputs_key"]
        for ds in (a, b):
            for key in DIFFERING:
                ds.attrs.pop(key, None)
        assert a.identical(b), name
    assert len(list((tmp_path / "remote" / "sweep.parts").glob("batch-*.nc"))) == 4
    # the batches really ran on the cluster's workers, both of them (4 tasks, 2 idle workers)
    from distributed import Client
    with Client(cluster, timeout="30s") as client:
        done = client.run(lambda dask_worker: sum(1 for k in dask_worker.state.log if "run_batch" in str(k[0])))
    assert len(done) == 2 and all(n > 0 for n in done.values()), done
