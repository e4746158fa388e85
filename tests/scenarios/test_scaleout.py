"""Scale-out for real: a `dask scheduler` and `dask worker` processes on loopback, each in its own
working directory (not the client's): `hdi sweep --scheduler tcp://127.0.0.1:PORT` with a relative
results folder gives the dataset of a local run; a worker that does not see the results folder, and
the loss of the last worker mid-sweep, end the command with one line in bounded time, and a rerun
resumes; a scheduler file or DASK_SCHEDULER_ADDRESS names the cluster, its dashboard link
is printed, the batches follow its threads, and a worker running other code is refused."""

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

ROOT = Path(__file__).resolve().parents[2]
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


def _hdi(*args: str, cwd: Path, **env_vars: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), **env_vars)
    return subprocess.run([sys.executable, "-m", "pipeline.cli", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


class Cluster:
    """A scheduler and its workers as processes of their own (each in its own session and folder)."""

    def __init__(self, tmp_path: Path):
        self.tmp_path = tmp_path
        self.port = _free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.scheduler_file = tmp_path / "scheduler.json"  # (what `dask scheduler --scheduler-file` writes)
        self.env = dict(os.environ, PYTHONPATH=str(ROOT))  # the workers import this checkout's pipeline
        self.procs: list[subprocess.Popen] = []
        self.workers: list[subprocess.Popen] = []

    def _start(self, args: list[str], where: str) -> subprocess.Popen:
        cwd = self.tmp_path / where
        cwd.mkdir()
        p = subprocess.Popen([str(DASK), *args], cwd=cwd, env=self.env, stdout=subprocess.DEVNULL,
                             stderr=(cwd / "log.txt").open("w"), start_new_session=True)
        self.procs.append(p)
        return p

    def start_scheduler(self) -> None:
        sched = self._start(["scheduler", "--host", "127.0.0.1", "--port", str(self.port),
                             "--dashboard-address", ":0", "--scheduler-file", str(self.scheduler_file)], "scheduler")
        _wait_for_port(self.port, sched)

    def start_workers(self, n: int) -> None:
        """``n`` more single-threaded workers; returns once the scheduler has them all."""
        for _ in range(n):
            name = f"worker{len(self.workers) + 1}"
            self.workers.append(self._start(["worker", self.address, "--nthreads", "1", "--nworkers", "1",
                                             "--no-dashboard", "--local-directory",
                                             str(self.tmp_path / name / "dask-scratch")], name))
        from distributed import Client
        with Client(self.address, timeout="30s") as client:
            client.wait_for_workers(sum(p.poll() is None for p in self.workers), timeout=90)

    def kill_worker(self, p: subprocess.Popen) -> None:
        """SIGKILL a worker and its nanny (its process group): a lost machine, nothing cleaned up."""
        os.killpg(p.pid, signal.SIGKILL)
        p.wait(timeout=20)

    def stop(self) -> None:
        for p in reversed(self.procs):  # our own processes only, by their process group id
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in self.procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait(timeout=10)


@pytest.fixture(scope="module")
def running(tmp_path_factory):
    """A :class:`Cluster` of a scheduler and two single-threaded workers (always torn down; shared by the
    tests of this module that leave it as they found it)."""
    c = Cluster(tmp_path_factory.mktemp("cluster"))
    try:
        c.start_scheduler()
        c.start_workers(2)
        from distributed import Client
        with Client(c.address, timeout="30s") as client:
            assert len(client.scheduler_info(n_workers=-1)["workers"]) == 2
        yield c
    finally:
        c.stop()


@pytest.fixture(scope="module")
def cluster(running):
    """``tcp://127.0.0.1:PORT`` of :func:`running`."""
    return running.address


@pytest.fixture()
def one_worker(tmp_path):
    """A :class:`Cluster` of a scheduler and one worker (always torn down)."""
    c = Cluster(tmp_path)
    try:
        c.start_scheduler()
        c.start_workers(1)
        yield c
    finally:
        c.stop()


@pytest.mark.slow
def test_sweep_on_a_remote_cluster_equals_the_local_run(cluster, tmp_path):
    sets = [a for s in SMALL for a in ("--set", s)]
    # a relative results folder (the workers run in folders of their own: each task carries absolute paths);
    # a relative one would be "No such file or directory: 'remote/sweep.parts/...'" on the workers
    remote = _hdi("sweep", str(PAPER), *sets, "--scheduler", cluster, "--out", "remote", cwd=tmp_path)
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
        done = client.run(lambda dask_worker: sum(1 for k in dask_worker.state.log if "sweep_task" in str(k[0])))
    assert len(done) == 2 and all(n > 0 for n in done.values()), done


@pytest.mark.slow
def test_a_worker_that_does_not_see_the_results_folder_is_one_line_naming_it(cluster, tmp_path):
    from pipeline.cluster import ClusterError, shared_folder
    from pipeline.fanout import available_cores, run_tasks
    gone = tmp_path / "not-shared"  # a folder no worker sees (as on a disk local to the client's machine)
    with shared_folder(gone), pytest.raises(ClusterError) as err:
        run_tasks(available_cores, [(), ()], scheduler=cluster)
    message = str(err.value)
    assert message.startswith(f"{gone}: the results folder is not visible on dask worker") and "\n" not in message
    gone.mkdir()  # once the workers see it, the same tasks run
    with shared_folder(gone):
        assert run_tasks(available_cores, [(), ()], scheduler=cluster) >= 0


def _ran(address: str, name: str) -> set[str]:
    """The keys of the tasks of function ``name`` the workers of the cluster at ``address`` were given (a
    task stolen from one worker by another is in both logs)."""
    from distributed import Client
    with Client(address, timeout="30s") as client:
        logs = client.run(lambda dask_worker: {str(k[0]) for k in dask_worker.state.log if name in str(k[0])})
    return set().union(*logs.values())


@pytest.mark.slow
def test_a_scheduler_file_or_dask_scheduler_address_names_the_cluster_and_its_dashboard_is_printed(running, tmp_path):
    # a scheduler file and DASK_SCHEDULER_ADDRESS are taken as well as a tcp:// address, and the dashboard link shown
    sets = [a for s in SMALL for a in ("--set", s)]
    before = _ran(running.address, "sweep_task")
    dashboard = f"dask scheduler {running.address}: dashboard http://127.0.0.1:"
    viafile = _hdi("sweep", str(PAPER), *sets, "--scheduler", str(running.scheduler_file), "--out", "out", cwd=tmp_path)
    assert viafile.returncode == 0, viafile.stderr
    assert len(_ran(running.address, "sweep_task") - before) == 4  # the batches ran on the cluster
    assert [ln for ln in viafile.stderr.splitlines() if ln.startswith(dashboard)], viafile.stderr  # once, at INFO
    # without --scheduler, dask's DASK_SCHEDULER_ADDRESS is the cluster (checked and announced; up to date)
    viaenv = _hdi("sweep", str(PAPER), *sets, "--out", "out", cwd=tmp_path, DASK_SCHEDULER_ADDRESS=running.address)
    assert viaenv.returncode == 0, viaenv.stderr
    assert len([ln for ln in viaenv.stderr.splitlines() if ln.startswith(dashboard)]) == 1, viaenv.stderr
    from pipeline.cli_checks import check_scheduler
    assert check_scheduler(str(running.scheduler_file)) == running.address


@pytest.mark.slow
def test_the_split_follows_the_cluster_threads(cluster):
    from pipeline.fanout import cluster_threads, split
    assert cluster_threads(cluster) == 2  # two single-threaded workers (it was 8 tasks whatever the cluster)
    assert split(list(range(5)), cluster) == [(0, 2, 4), (1, 3)]


@pytest.mark.slow
def test_a_worker_running_other_code_is_refused_before_work_is_sent(cluster):
    # a worker importing other code would write parts stamped with this code's inputs key: refused first
    from distributed import Client

    from pipeline.code_version import code_key
    from pipeline.cluster import ClusterError
    from pipeline.fanout import run_tasks

    def make_stale():  # (nested: pickled by value, the workers import no test module)
        import pipeline.cluster
        pipeline.cluster.code_key = lambda module: "0" * 64

    def restore():
        import pipeline.cluster
        import pipeline.code_version
        pipeline.cluster.code_key = pipeline.code_version.code_key

    with Client(cluster, timeout="30s") as client:
        stale = sorted(client.scheduler_info(n_workers=-1)["workers"])[1]
        client.run(make_stale, workers=[stale])
        try:
            with pytest.raises(ClusterError) as err:
                run_tasks(code_key, [("pipeline.physics",), ("pipeline.model",)], scheduler=cluster)
        finally:
            client.run(restore, workers=[stale])
    ours = code_key("pipeline.code_version")
    assert str(err.value) == (f"dask worker {stale} runs other code than this hdi: code key of pipeline.code_version "
                              f"000000000000 there, {ours[:12]} here; restart the workers from this version of "
                              "pipeline (install it where they run) and run again")
    assert _ran(cluster, "code_key-") == set()  # refused before any task was sent
    got: list[str] = []
    run_tasks(code_key, [("pipeline.physics",)], scheduler=cluster, on_done=got.append)  # restored: it runs
    assert got == [code_key("pipeline.physics")]


#: 2 protrusions in contact x 2 damping ratios, one protrusion a batch: 4 batches of seconds each on one worker.
LOSS = ["solver.duration_ms=0.6", "solver.transient_ms=0.2", "contact.k=0.5",
        "sweep.protrusion_nm={start=10.0, stop=10.5, step=0.5}", "sweep.batch_size=1",
        "sweep.damping_ratio=[0.03, 0.05]", "sweep.histories_nm=[10.0]"]


@pytest.mark.slow
def test_losing_the_last_worker_ends_the_sweep_in_one_line_and_a_rerun_resumes(one_worker, tmp_path):
    # kill the only worker mid-sweep: `hdi sweep --scheduler` ends in one line within its wait, not never
    wait_s = 3.0
    env = dict(os.environ, PYTHONPATH=str(ROOT), HDI_CLUSTER_WAIT_S=f"{wait_s:g}")
    args = [sys.executable, "-m", "pipeline.cli", "sweep", str(PAPER), *[a for s in LOSS for a in ("--set", s)],
            "--scheduler", one_worker.address, "--out", "out"]
    client = tmp_path / "client"
    client.mkdir()
    parts = client / "out" / "sweep.parts"
    proc = subprocess.Popen(args, cwd=client, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        end = time.monotonic() + 240
        while not list(parts.glob("batch-*.nc")) and proc.poll() is None and time.monotonic() < end:
            time.sleep(0.05)
        assert proc.poll() is None, proc.communicate()  # (still running: the worker is lost mid-sweep)
        one_worker.kill_worker(one_worker.workers[0])
        killed = time.monotonic()
        _, err = proc.communicate(timeout=wait_s + 60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    took = time.monotonic() - killed
    lines = err.strip().splitlines()
    assert proc.returncode == 2 and "Traceback" not in err, err
    assert lines[-1].startswith(f"hdi sweep: error: dask scheduler {one_worker.address}: ") \
        and "no worker left" in lines[-1] and "run again to resume" in lines[-1], err
    # the documented wait, counted from when the scheduler lost the worker, which can be a little before
    # kill_worker returns here (2.99 s was seen for a 3-s wait); and the client's clean-up
    assert wait_s - 0.5 <= took < wait_s + 30, took
    kept = len(list(parts.glob("batch-*.nc")))
    assert 1 <= kept < 4
    # a new worker, the same command: the finished parts are kept, only the others run
    one_worker.start_workers(1)
    again = subprocess.run(args, cwd=client, env=env, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    import json
    log = [json.loads(line) for line in (client / "out" / ".hdi" / "runs.jsonl").read_text().splitlines()]
    assert log[-1]["batches"] == 4 and log[-1]["batches_run"] == 4 - kept
    assert read_dataset(client / "out" / "sweep.nc").sizes["damping"] == 2


# ------------------------------------------------------------------ a stalled or killed cluster mid-sweep
def _mid_sweep(cluster: Cluster, tmp_path: Path, stall_s: float):
    """``hdi sweep`` of :data:`LOSS` on ``cluster``, returned once its first part is written: (the process, its
    command, its environment, its working folder)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), HDI_STALL_S=f"{stall_s:g}", HDI_CLUSTER_WAIT_S=f"{stall_s:g}")
    args = [sys.executable, "-m", "pipeline.cli", "sweep", str(PAPER), *[a for s in LOSS for a in ("--set", s)],
            "--scheduler", cluster.address, "--out", "out"]
    client = tmp_path / "client"
    client.mkdir()
    proc = subprocess.Popen(args, cwd=client, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    end = time.monotonic() + 240
    while not list((client / "out" / "sweep.parts").glob("batch-*.nc")) and proc.poll() is None \
            and time.monotonic() < end:
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()
    return proc, args, env, client


def _one_line(proc: subprocess.Popen, timeout: float, client: Path) -> str:
    """The last line of ``proc``, which must end with exit 2, one error line, no traceback nor dask log line,
    and the folder lock and staging folders gone."""
    try:
        _, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 2, err
    assert "Traceback" not in err and " - ERROR - " not in err and " - WARNING - " not in err, err
    assert [ln for ln in err.splitlines() if ": error: " in ln] == err.strip().splitlines()[-1:], err
    assert not (client / "out" / ".hdi.lock").exists() and not list((client / "out").glob(".hdi-staging-*"))
    return err.strip().splitlines()[-1]


def _freeze(p: subprocess.Popen) -> None:
    """SIGSTOP a dask process and its children (a worker's nanny and worker process)."""
    import psutil
    for q in [psutil.Process(p.pid), *psutil.Process(p.pid).children(recursive=True)]:
        q.suspend()


@pytest.mark.slow
def test_a_stopped_worker_ends_the_sweep_in_one_line_naming_it_and_the_rerun_resumes(one_worker, tmp_path):
    """SIGSTOP of the worker mid-sweep: the sweep waited forever with a growing ETA, and a rerun against the
    stopped worker said that it "runs other code"."""
    import json
    stall_s = 20.0
    proc, args, env, client = _mid_sweep(one_worker, tmp_path, stall_s)
    _freeze(one_worker.workers[0])
    stopped = time.monotonic()
    line = _one_line(proc, stall_s * 6 + 60, client)
    took = time.monotonic() - stopped
    assert line.startswith("hdi sweep: error: dask worker tcp://127.0.0.1:") and "no heartbeat for" in line \
        and "finished work is kept" in line and "run again to resume" in line, line
    assert stall_s <= took < stall_s * 6 + 60, took
    kept = len(list((client / "out" / "sweep.parts").glob("batch-*.nc")))
    assert 1 <= kept < 4
    again = subprocess.run(args, cwd=client, env=env, capture_output=True, text=True, timeout=300)
    assert again.returncode == 2 and "Traceback" not in again.stderr, again.stderr
    assert "did not answer for" in again.stderr.strip().splitlines()[-1] and "runs other code" not in again.stderr
    one_worker.kill_worker(one_worker.workers[0])  # (SIGKILL reaches a stopped process)
    one_worker.start_workers(1)
    resumed = subprocess.run(args, cwd=client, env=env, capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    log = [json.loads(line) for line in (client / "out" / ".hdi" / "runs.jsonl").read_text().splitlines()]
    assert log[-1]["batches"] == 4 and log[-1]["batches_run"] == 4 - kept, \
        [ln for ln in resumed.stderr.splitlines() if "batch" in ln] + [again.stderr]


@pytest.mark.slow
@pytest.mark.parametrize("how", ["stopped", "killed"])
def test_a_stopped_or_killed_scheduler_ends_the_sweep_in_one_line_without_dasks_tracebacks(one_worker, tmp_path, how):
    """A killed scheduler printed distributed.client's ERROR tracebacks (and ended with a line of dask's comm
    error); a stopped one (SIGSTOP) left the sweep waiting forever."""
    stall_s = 20.0
    proc, args, env, client = _mid_sweep(one_worker, tmp_path, stall_s)
    scheduler = one_worker.procs[0]
    if how == "stopped":
        _freeze(scheduler)
    else:
        os.killpg(scheduler.pid, signal.SIGKILL)
    line = _one_line(proc, stall_s * 6 + 120, client)
    assert line.startswith(f"hdi sweep: error: dask scheduler {one_worker.address}: ") \
        and "finished work is kept, run again to resume" in line, line
    if how == "stopped":
        assert "no answer for" in line, line
