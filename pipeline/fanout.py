"""Fan a list of tasks out over the local machine or a dask.distributed cluster.

:func:`run_tasks` calls ``fn(*args)`` for every ``args`` of ``tasks`` and hands each result to
``on_done`` in the calling thread as soon as it is ready (in completion order). Where the tasks run:

* ``scheduler=None`` (the local default): in this process, one after the other, when there is a
  single task or a single worker (``workers=1``, or a one-core machine); otherwise on a pool of
  ``workers`` threads (default: one per core) in this process. The numba kernels of
  :mod:`pipeline.model.dynamics` release the GIL (``nogil=True``), so threads run them in parallel and the
  job pays no start-up: no worker processes to spawn, no modules to import again, no numba cache
  to reload, no task graph to serialise. The Python around the kernels (histories, summaries,
  NetCDF I/O, which xarray serialises with its HDF5 lock) is the part that does not scale.
  Measured on 2 cores (benchmarks/bench_fanout.py): see the benchmark table of docs/performance.md.
* ``scheduler="threads"`` / ``"processes"``: force the thread pool / a ``distributed.LocalCluster``
  of ``workers`` single-threaded worker processes (the process cluster isolates tasks that hold
  the GIL, at a start-up cost of about a second per job).
* ``scheduler="synchronous"``: in this process, one after the other (tests, debugging, profiling).
* any other string: the address of a running dask.distributed scheduler (e.g. one started by
  dask-jobqueue), which is how a study outgrows one machine. Tasks are retried twice on a lost worker.
  (The command line also takes a scheduler file or ``DASK_SCHEDULER_ADDRESS``:
  :func:`pipeline.scheduler.check_scheduler` turns them into the address.) The first connection to a
  scheduler logs its dashboard link (:func:`pipeline.cluster.announce`).

Tasks must be deterministic functions of their arguments and safe to run twice (retries); large
inputs travel by file path inside ``args``, not as arrays. A worker resolves a relative path from its
own working directory, so every path a task carries is absolute (the runner hands each stage its
results folder as an absolute path) and the results folder must be on a file system the workers
share: within :func:`pipeline.cluster.shared_folder` (the runner sets it to the folder of the stage it computes) each
task on a cluster first checks that its worker sees that folder, and a worker that does not ends the
command with one line naming the folder (:class:`pipeline.cluster.ClusterError`).

The dask.distributed side (connecting, the code check, the shared folder, the wait and the stalls) is
:mod:`pipeline.cluster`; the command line's check of a ``--scheduler`` before anything runs is
:mod:`pipeline.scheduler`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from typing import Any, Callable, Iterable, Iterator, Sequence

from . import interrupts
from .progress import Progress, end_line
from .cluster import (CLIENT_TIMEOUT_S, SHARED_FOLDER, Watch, announce, check_code, cluster_threads, cluster_wait_s,
                      connect, gather_results, keep_dask_level, on_worker, run_everywhere, stall_s, task_code)


log = logging.getLogger(__name__)

LOCAL = ("synchronous", "threads", "processes")


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity: a ``taskset`` or a batch job's share),
    not the machine's count."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def local_workers(workers: int | None, n_tasks: int) -> int:
    """Workers a local run uses: ``workers`` (default one per available core), never more than the tasks."""
    n = workers if workers else available_cores()
    if n < 1:
        raise ValueError(f"workers = {n}: expected an integer >= 1")
    return max(1, min(n, n_tasks))


def split(items: Sequence[Any], scheduler: str | None = None, workers: int | None = None) -> list[tuple]:
    """``items`` dealt round-robin into as many tasks as local workers (:func:`local_workers`), or as the
    cluster's threads (:func:`cluster_threads`) for a scheduler address, none empty: for work whose items
    share a set-up in a task (a model and its static starts). The split decides where items run, not
    what they give (tests/core/test_fanout.py: a task's shared set-up gives each item what it gives alone)."""
    local = scheduler is None or scheduler in LOCAL
    n = local_workers(workers, len(items)) if local else cluster_threads(scheduler)
    return [c for c in (tuple(items[i::n]) for i in range(n)) if c]


def run_tasks(fn: Callable[..., Any], tasks: Iterable[tuple], *, scheduler: str | None = None,
              workers: int | None = None, on_done: Callable[[Any], None] | None = None) -> float:
    """Run ``fn(*args)`` for every ``args`` in ``tasks``; call ``on_done(result)`` as each finishes.

    Parameters
    ----------
    fn : a picklable (module-level) function
    tasks : argument tuples, one per task
    scheduler : ``None`` (local default, see the module docstring), ``"synchronous"``, ``"threads"``,
        ``"processes"`` or a dask.distributed scheduler address
    workers : local workers (default: one per core); ignored for a scheduler address
    on_done : called with each result in the calling thread; an exception it raises (e.g.
        ``KeyboardInterrupt``) cancels the tasks not yet started and is re-raised once the running
        ones have finished (each task's own output is then complete, never half-written)

    The finished tasks are counted on a :class:`pipeline.progress.Progress` (a bar on a terminal,
    periodic lines in a log), unless the caller counts its own work around the call.

    Returns
    -------
    float
        Wall time [s] of the batch phase: from the first task submitted to the last result handed
        to ``on_done`` (a process cluster is started and warmed up before it).
    """
    tasks = list(tasks)
    given = on_done if on_done is not None else (lambda result: None)
    if scheduler is None:
        n = local_workers(workers, len(tasks))
        scheduler = "synchronous" if n == 1 else "threads"
    with Progress(len(tasks), unit="task") as progress:

        def done(result: Any) -> None:
            given(result)
            progress.update()

        if scheduler == "synchronous" or not tasks:
            log.debug("fan-out: %d tasks in this process, one after the other", len(tasks))
            t0 = time.perf_counter()
            for args in tasks:
                done(fn(*args))
            return time.perf_counter() - t0
        if scheduler == "threads":
            return _threads(fn, tasks, local_workers(workers, len(tasks)), done)
        end_line()  # (a short batch on a cluster says its end too: nothing else shows it ran there)
        return _distributed(fn, tasks, scheduler, workers, done)


def _threads(fn: Callable[..., Any], tasks: list[tuple], n: int, done: Callable[[Any], None]) -> float:
    """A pool of ``n`` threads in this process; results in completion order."""
    log.info("fan-out: %d tasks on %d threads", len(tasks), n)
    pool = ThreadPoolExecutor(max_workers=n, thread_name_prefix="hdi-task")
    try:
        t0 = time.perf_counter()
        pending = {pool.submit(fn, *args) for args in tasks}
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                done(fut.result())
        return time.perf_counter() - t0
    finally:
        # on an error (or Ctrl-C) drop what has not started; the running tasks finish their output
        pool.shutdown(wait=True, cancel_futures=True)


def _process_cluster(n: int):
    """A ``distributed.LocalCluster`` of ``n`` single-threaded worker processes, no dashboard.

    Started within :func:`pipeline.interrupts.shielded`: its worker processes (and multiprocessing's resource
    tracker) have the signals a terminal sends its whole process group blocked (Ctrl-C, Ctrl-\\, a hang-up),
    so only this process answers them (one line from the CLI, not a traceback per worker) and closes the
    cluster; none of them is lost meanwhile (they were ignored here while the cluster started, and a
    Ctrl-C then did nothing). A worker still dies with this process however it ends (distributed's own
    watch of its parent)."""
    from distributed import LocalCluster
    keep_dask_level()
    with interrupts.shielded():
        return LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                            silence_logs=logging.CRITICAL)  # shutdown races log CommClosedError


@contextlib.contextmanager
def local_cluster(scheduler: str | None = None, workers: int | None = None) -> Iterator[str | None]:
    """A ``scheduler`` for repeated :func:`run_tasks` calls (one optimiser generation after another).

    ``"processes"`` starts one process cluster for the whole ``with`` block and yields its address, so
    its start-up is paid once; anything else (``None``: threads, ``"synchronous"``, an address) costs
    nothing to start and is yielded unchanged.
    """
    if scheduler != "processes":
        yield scheduler
        return
    cluster = _process_cluster(local_workers(workers, available_cores()))
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()


def _warm_worker() -> None:
    """Import the model on a worker (and load its numba cache index) before timing starts."""
    import importlib
    importlib.import_module("pipeline.model.running")  # (imported for its side effect: the kernels compiled or loaded)


def _distributed(fn: Callable[..., Any], tasks: list[tuple], scheduler: str, workers: int | None,
                 done: Callable[[Any], None]) -> float:
    """A local process cluster (``scheduler="processes"``) or the cluster at a scheduler address."""
    n = local_workers(workers, len(tasks)) if scheduler == "processes" else None
    folder, wait_s, stall = SHARED_FOLDER.get(), cluster_wait_s(), stall_s()
    code = task_code(fn)
    with local_cluster(scheduler, n) as address, connect(address, CLIENT_TIMEOUT_S) as client:
        if scheduler != "processes":  # (ours serves no dashboard pages: its HTTP port has dask's health routes only)
            announce(client, address)
        check_code(client, fn)
        log.info("fan-out: %d tasks on %s", len(tasks), f"{n} local processes" if scheduler == "processes" else
                 f"the dask scheduler {address} ({sum(client.nthreads().values())} worker threads)")
        run_everywhere(client, _warm_worker)
        t0 = time.perf_counter()
        # (keys named after fn, as the dashboard and the workers' logs would name fn itself)
        name = getattr(fn, "__name__", "task")
        futures = [client.submit(on_worker, folder, code, fn, *args, key=f"{name}-{uuid.uuid4().hex}", retries=2)
                   for args in tasks]
        for result in gather_results(client, futures, address, wait_s, Watch(client, address, stall)):
            done(result)
        return time.perf_counter() - t0
