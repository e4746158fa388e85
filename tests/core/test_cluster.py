"""The dask.distributed side of the fan-out (pipeline.cluster): the results folder a task checks it sees, the
cluster wait and the stall bound, the code check of every worker, the watch of a batch on stand-in clients, dask's
loggers kept quiet, the dashboard link and a scheduler that does not answer.
"""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from pipeline import cluster
from fanout_tasks import square


def test_the_fan_outs_client_is_current_only_inside_its_connection_and_never_the_process_default():
    """A user's process (a notebook with its own client) keeps its default client while a study runs on a
    cluster: the fan-out's client is current in the connecting thread only (its ``distributed.wait`` looks
    for it there), never registered as the process's default, and dask's ``scheduler`` option is as before
    once the connection ends (``as_current`` sets it for the connection's span)."""
    import dask
    import distributed
    from distributed import LocalCluster
    before = dask.config.get("scheduler", None)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc:
        with cluster.connect(lc.scheduler_address) as client:
            assert distributed.default_client() is client
            with ThreadPoolExecutor(1) as other:  # (another thread of the process: the user's)
                with pytest.raises(ValueError, match="No clients found"):
                    other.submit(distributed.default_client).result()
        assert client.status == "closed"
        with pytest.raises(ValueError, match="No clients found"):
            distributed.default_client()
    assert dask.config.get("scheduler", None) == before


# ------------------------------------------------------------ paths on workers, a cluster that stops
def test_a_task_on_a_worker_that_does_not_see_the_results_folder_fails_in_one_line(tmp_path):
    missing = tmp_path / "elsewhere"
    with pytest.raises(cluster.ClusterError) as err:
        cluster.in_shared_folder(str(missing), square, 3)
    assert str(err.value).startswith(f"{missing}: the results folder is not visible on dask worker ")
    assert "\n" not in str(err.value) and "file system every worker shares" in str(err.value)
    assert cluster.in_shared_folder(str(tmp_path), square, 3)[:2] == (3, 9)
    assert cluster.in_shared_folder(None, square, 2)[:2] == (2, 4)


def test_the_runner_hands_a_stage_its_folder_as_an_absolute_path_for_its_tasks(tmp_path, monkeypatch, paper_scene):
    # `--out relout` (or the default results/<scene>/) reaches the workers as an absolute path, not a relative
    # one they would resolve from their own working directory
    import xarray as xr

    from pipeline import runner
    from pipeline.io import var
    seen = {}

    def compute(scene, inputs):
        seen.update(out=inputs.out, shared=cluster.SHARED_FOLDER.get())
        return xr.Dataset({"v": var(1.0, (), "1", "toy value")})

    monkeypatch.chdir(tmp_path)
    stages = {"toy": runner.Stage("toy", compute, outputs=("toy.nc",), reads=())}
    made = runner.Runner(paper_scene, "relout", stages).build(["toy"])
    assert made["toy"] == (Path("relout") / "toy.nc",)  # what the user named, as named
    assert seen["out"] == tmp_path / "relout" and seen["out"].is_absolute()
    assert seen["shared"] == str(tmp_path / "relout")
    assert cluster.SHARED_FOLDER.get() is None  # only while the stage computes
    assert runner.Inputs.folder("relout").out == tmp_path / "relout"


def test_the_cluster_wait_is_a_documented_setting(monkeypatch):
    monkeypatch.delenv("HDI_CLUSTER_WAIT_S", raising=False)
    assert cluster.cluster_wait_s() == cluster.CLUSTER_WAIT_S
    monkeypatch.setenv("HDI_CLUSTER_WAIT_S", "2.5")
    assert cluster.cluster_wait_s() == 2.5
    for bad in ("0", "-1", "soon", "inf", "nan"):
        monkeypatch.setenv("HDI_CLUSTER_WAIT_S", bad)
        with pytest.raises(cluster.ClusterError, match=f"HDI_CLUSTER_WAIT_S={bad}: expected a number of seconds > 0"):
            cluster.cluster_wait_s()


class _Future:
    """A stand-in for a dask future: its result arrives, or never does (its worker died before sending it)."""

    def __init__(self, key: str, value=None):
        self.key, self.value = key, value

    def result(self, timeout=None):
        if self.value is None:
            time.sleep(min(timeout, 0.05))
            raise TimeoutError()
        return self.value


class _Scheduler:
    """A stand-in for a client's connection to its scheduler: the tasks each worker holds, and each worker's
    ``last_seen`` (the scheduler's time of its last heartbeat), which ``beat`` moves at every question, or not
    for the workers of ``frozen``."""

    def __init__(self, processing=None, workers=(), frozen=(), answers=True):
        self._processing = processing or {}
        self.results: dict = {}  # worker -> keys of finished tasks whose results it holds
        self.last_seen = dict.fromkeys(workers, 1000.0)
        self.frozen, self.answers = set(frozen), answers

    async def processing(self, workers=None):
        return self._processing

    async def who_has(self, keys=()):
        return {k: [w] for w, ks in self.results.items() for k in ks if k in keys}

    async def identity(self, n_workers=-1):
        for w in self.last_seen:
            if w not in self.frozen:
                self.last_seen[w] += 0.5
        return {"workers": {w: {"last_seen": t} for w, t in self.last_seen.items()}}


class _Client:
    """A stand-in for a ``distributed.Client``: ``sync`` runs a coroutine function of its :class:`_Scheduler`
    (or ``_run``, the results of ``run`` on the workers), and gives no answer within ``callback_timeout`` from
    a scheduler that does not answer (stopped)."""

    def __init__(self, scheduler=None, run=None):
        self.scheduler = scheduler or _Scheduler()
        self.ran = run

    async def _run(self, fn, *args, on_error="raise"):
        if self.ran is None:
            raise TimeoutError()
        return self.ran

    def sync(self, fn, *args, callback_timeout=None, **kwargs):
        import asyncio
        if not self.scheduler.answers:
            time.sleep(callback_timeout)
            raise TimeoutError(f"timed out after {callback_timeout} s.")
        return asyncio.run(fn(*args, **kwargs))

    def scheduler_info(self, n_workers=-1):
        return self.sync(self.scheduler.identity, n_workers=n_workers)


def _no_workers():
    """A stand-in for a client whose scheduler has lost its last worker."""
    return _Client(_Scheduler())


@pytest.mark.parametrize("lost_result", [False, True])
def test_a_cluster_without_workers_ends_the_wait_in_one_line_within_the_bound(monkeypatch, lost_result):
    # with the last worker killed the wait ends, on tasks no worker runs and (the race the real-scheduler test
    # can hit) on the result of a task whose worker died before sending it
    import distributed

    class _Done:
        def __init__(self, done):
            self.done = done

    def wait(fs, timeout=None, return_when=None):
        if lost_result:
            return _Done({f for f in fs if f.key != "never"})
        time.sleep(timeout)
        raise TimeoutError()

    monkeypatch.setattr(distributed, "wait", wait)
    monkeypatch.setattr(cluster, "_POLL_S", 0.05)
    futures = [_Future("ok", value=7), _Future("lost"), _Future("never")] if lost_result else [_Future("never")]
    got = []
    t0 = time.monotonic()
    with pytest.raises(cluster.ClusterError) as err:
        client = _no_workers()
        for result in cluster.gather_results(client, futures, "tcp://host:8786", 0.5, cluster.Watch(client, "h", 60.0)):
            got.append(result)
    took = time.monotonic() - t0
    assert got == ([7] if lost_result else [])  # what arrived was handed on (its part is kept)
    assert 0.5 <= took < 2.0, took
    n = 2 if lost_result else 1
    assert str(err.value) == (f"dask scheduler tcp://host:8786: {n} of {len(futures)} tasks waited 0.5 s with no "
                              "worker left (HDI_CLUSTER_WAIT_S sets the wait); finished work is kept, start workers "
                              "and run again to resume")


# ------------------------------------------------------------ a worker running other code
def _workers(keys):
    """A stand-in for a client whose workers answer ``run`` with these code keys (or exceptions)."""
    return _Client(run=keys)


def test_a_worker_with_another_code_key_is_refused_in_one_line_naming_it_and_both_keys():
    from pipeline.code_version import code_key
    ours = code_key("pipeline.code_version")
    assert ours  # (a module of the package: a real key)
    cluster.check_code(_workers({"tcp://10.0.0.1:1": ours, "tcp://10.0.0.2:1": ours}), code_key)  # all current
    with pytest.raises(cluster.ClusterError) as err:
        cluster.check_code(_workers({"tcp://10.0.0.1:1": ours, "tcp://10.0.0.2:1": "ab" * 32}), code_key)
    assert str(err.value) == (f"dask worker tcp://10.0.0.2:1 runs other code than this hdi: code key of "
                              f"pipeline.code_version {'ab' * 6} there, {ours[:12]} here; restart the workers from "
                              "this version of pipeline (install it where they run) and run again")
    with pytest.raises(cluster.ClusterError, match=r"^dask worker tcp://10.0.0.1:1 runs other code than this hdi: it "
                                                  r"cannot check its code key \(AttributeError: gone\)"):
        cluster.check_code(_workers({"tcp://10.0.0.1:1": AttributeError("gone")}), code_key)


# ------------------------------------------------------------ a stalled worker or scheduler
def test_the_stall_bound_is_a_documented_setting(monkeypatch):
    monkeypatch.delenv("HDI_STALL_S", raising=False)
    assert cluster.stall_s() == cluster.STALL_S == 60.0
    monkeypatch.setenv("HDI_STALL_S", "7.5")
    assert cluster.stall_s() == 7.5
    monkeypatch.setenv("HDI_STALL_S", "0")
    with pytest.raises(cluster.ClusterError, match="HDI_STALL_S=0: expected a number of seconds > 0"):
        cluster.stall_s()


def _waiting(client, futures, wait_s=60.0, floor_s=0.3):
    """Run :func:`pipeline.cluster.gather_results` to its end: (the results handed on, the error, the seconds taken)."""
    got, t0 = [], time.monotonic()
    try:
        for result in cluster.gather_results(client, futures, "tcp://host:8786", wait_s, cluster.Watch(client, "tcp://host:8786",
                                                                                                floor_s)):
            got.append(result)
    except cluster.ClusterError as exc:
        return got, str(exc), time.monotonic() - t0
    return got, None, time.monotonic() - t0


@pytest.fixture()
def polling(monkeypatch):
    """distributed's wait, answering at once that nothing finished but the futures that have a value."""
    import distributed

    class _Done:
        def __init__(self, done):
            self.done = done

    def wait(fs, timeout=None, return_when=None):
        done = {f for f in fs if f.value is not None}
        if not done:
            time.sleep(0.02)
        return _Done(done)

    monkeypatch.setattr(distributed, "wait", wait)
    monkeypatch.setattr(cluster, "_POLL_S", 0.02)


def test_a_worker_whose_heartbeat_stopped_while_it_holds_tasks_ends_the_wait_in_one_line(polling):
    """A worker stopped with SIGSTOP: the scheduler still lists its tasks as running, and the sweep waited
    forever with a growing ETA. The other worker's heartbeat moves: only the stopped one is named."""
    futures = [_Future("a"), _Future("b"), _Future("c")]
    client = _Client(_Scheduler({"tcp://w1:1": ["a", "b"], "tcp://w2:1": ["c"]}, workers=["tcp://w1:1", "tcp://w2:1"],
                                frozen=["tcp://w1:1"]))
    got, err, took = _waiting(client, futures)
    assert got == [] and 0.3 <= took < 3.0, took
    assert err is not None and err.startswith("dask worker tcp://w1:1: no heartbeat for 0 s while it holds 2 task(s) "
                                              "of the batch (it is stopped, or its machine is unreachable; "
                                              "HDI_STALL_S sets the wait); finished work is kept")


def test_a_stopped_worker_holding_a_finished_tasks_result_is_named_too(polling, monkeypatch):
    """Stopped after its task finished and before its result was fetched: no task of the batch is running
    anywhere, and the wait ended as "1 worker(s) ran none of them" instead of naming the stopped worker."""
    finished = _Future("a")
    finished.status = "finished"  # (the scheduler has its result, on the stopped worker: it never arrives)
    client = _Client(_Scheduler({"tcp://w1:1": []}, workers=["tcp://w1:1"], frozen=["tcp://w1:1"]))
    client.scheduler.results = {"tcp://w1:1": ["a"]}
    got, err, took = _waiting(client, [finished])
    assert err is not None and err.startswith("dask worker tcp://w1:1: no heartbeat for 0 s while it holds 1 task(s) "
                                              "of the batch"), err


def test_a_live_worker_on_a_long_task_is_never_taken_for_a_stall(polling):
    """Its heartbeat moves: a batch that runs for many times the bound is waited for (the bound follows the
    heartbeats, not the tasks' run times)."""
    late = _Future("long")
    client = _Client(_Scheduler({"tcp://w1:1": ["long"]}, workers=["tcp://w1:1"]))
    timer = threading.Timer(1.5, lambda: setattr(late, "value", 42))  # (5 times the bound of 0.3 s)
    timer.start()
    got, err, took = _waiting(client, [late])
    timer.join()
    assert (got, err) == ([42], None) and took >= 1.5


def test_the_stall_bound_follows_the_longest_heartbeat_gap_seen():
    """A loaded worker's heartbeat comes late: the bound is 5 times the longest gap seen, if that is longer."""
    client = _Client(_Scheduler({}, workers=["tcp://w1:1"]))
    watch = cluster.Watch(client, "tcp://host:8786", 0.1)
    watch.look(set())
    client.scheduler.frozen = {"tcp://w1:1"}
    time.sleep(0.2)
    watch.look(set())
    client.scheduler.frozen = set()
    watch.look(set())  # (it moved: after a gap of 0.2 s)
    assert 0.2 <= watch.longest_gap < 1.0 and watch.bound() == pytest.approx(cluster.STALL_HEARTBEATS * watch.longest_gap)


def test_a_scheduler_that_stopped_answering_mid_batch_ends_the_wait_in_one_line(polling):
    """A scheduler stopped with SIGSTOP keeps its connections open: every question waited forever."""
    client = _Client(_Scheduler({"tcp://w1:1": ["a"]}, workers=["tcp://w1:1"], answers=False))
    got, err, took = _waiting(client, [_Future("a")])
    assert got == [] and 0.3 <= took < 3.0, took
    assert err == ("dask scheduler tcp://host:8786: no answer for 0.3 s (it is stopped, or overloaded; HDI_STALL_S "
                   "sets the wait); finished work is kept, run again to resume")


def test_a_worker_that_does_not_answer_the_code_check_is_named_as_such(monkeypatch):
    """A rerun against a stopped worker waited forever, or said that it "runs other code"."""
    from pipeline.code_version import code_key
    monkeypatch.setenv("HDI_STALL_S", "0.2")
    client = _Client(_Scheduler({}, workers=["tcp://w1:1", "tcp://w2:1"], frozen=["tcp://w2:1"]), run=None)
    monkeypatch.setattr(cluster, "_POLL_S", 0.05)
    with pytest.raises(cluster.ClusterError) as err:
        cluster.check_code(client, code_key)
    assert str(err.value) == ("dask worker(s) tcp://w2:1 did not answer for 0.2 s (stopped, or the machine is "
                              "unreachable; HDI_STALL_S sets the wait); restart or remove it and run again")
    from distributed.comm import CommClosedError
    with pytest.raises(cluster.ClusterError, match=r"^dask worker tcp://w1:1 does not answer \(CommClosedError: gone\): "
                                                  r"it is stopped, or its machine is unreachable; restart it or "
                                                  r"remove it from the cluster, and run again$"):
        cluster.check_code(_workers({"tcp://w1:1": CommClosedError("gone")}), code_key)


def test_dasks_loggers_stay_quiet_after_distributed_resets_them():
    """distributed sets its loggers' levels from its configuration when it is imported, after the command line
    had set them: a killed scheduler then printed ERROR tracebacks of distributed.client before the one line."""
    import logging

    import dask
    from distributed.config import initialize_logging
    before = {n: logging.getLogger(n).level for n in cluster.DASK_LOGGERS}
    try:
        cluster.dask_log_level(logging.CRITICAL)
        initialize_logging(dask.config.config)  # (what `import distributed` does)
        assert logging.getLogger("distributed.client").level == logging.WARNING
        with pytest.raises(cluster.ClusterError):
            cluster.connect("tcp://127.0.0.1:1", timeout=0.2).__enter__()
        assert {n: logging.getLogger(n).level for n in cluster.DASK_LOGGERS} == dict.fromkeys(cluster.DASK_LOGGERS,
                                                                                               logging.CRITICAL)
    finally:
        cluster.dask_log_level(None)
        for n, level in before.items():
            logging.getLogger(n).setLevel(level)


def test_a_task_checks_the_code_key_on_its_worker(monkeypatch):
    # a worker that joined after the check of the whole cluster (dask-jobqueue scaling up)
    key = cluster.code_key("pipeline.code_version")
    assert cluster.on_worker(None, ("pipeline.code_version", key), square, 3)[:2] == (3, 9)
    monkeypatch.setattr(cluster, "code_key", lambda module: "0" * 64)
    with pytest.raises(cluster.ClusterError, match=rf"^dask worker \S+ runs other code than this hdi: code key of "
                                                  rf"pipeline.code_version 000000000000 there, {key[:12]} here; "):
        cluster.on_worker(None, ("pipeline.code_version", key), square, 3)


def test_the_dashboard_link_is_logged_once_when_the_scheduler_has_one(caplog):
    import logging

    from distributed import Client, LocalCluster
    caplog.set_level(logging.INFO, logger="pipeline.fanout")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0") as lc, \
            Client(lc.scheduler_address) as client:
        address = lc.scheduler_address
        cluster.announce(client, address)
        cluster.announce(client, address)  # (identify's generations connect again and again: once)
        link = client.dashboard_link
    lines = [r for r in caplog.records if r.name == "pipeline.fanout" and address in r.getMessage()]
    assert [r.getMessage() for r in lines] == [f"dask scheduler {address}: dashboard {link}"]
    assert link.startswith("http://") and link.endswith("/status") and lines[0].levelno == logging.INFO


def test_a_scheduler_that_does_not_answer_is_one_line(monkeypatch):
    # (dask's own timeout, shortened: the split asks a scheduler that went away since the command started)
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 0.5)
    with pytest.raises(cluster.ClusterError) as err:
        cluster.cluster_threads(address)
    assert str(err.value).startswith(f"dask scheduler {address}: did not answer (Timed out trying to connect to "
                                     f"{address} after 0.5 s); start it again") and "\n" not in str(err.value)
