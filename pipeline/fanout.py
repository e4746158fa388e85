"""Fan-out of batched tasks on dask: one call, three schedulers.

:func:`run_tasks` calls ``fn(*args)`` for every ``args`` tuple of ``tasks`` and hands each result to
``on_done`` as it finishes (in completion order). It generalises the sweep's executor
(:func:`pipeline.stages.sweep.execute`) to any task function, so the sweep, ``hdi identify`` and
``hdi sensitivity`` share one fan-out.

Schedulers: ``None`` starts a ``distributed.LocalCluster`` (one single-threaded worker process per
core, no dashboard) for this call; ``"synchronous"`` runs the tasks in this process, in order
(tests, debugging); any other string is the address of a running dask.distributed scheduler.
Callers that fan out many times (one generation of an optimiser after another) start one cluster
with :func:`local_cluster` and pass its address, so the start-up is paid once.

This is the minimal version; the speed branch replaces it by one with the same API (in-process or
threaded below a size threshold, a process cluster above).
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from typing import Any, Callable, Iterable, Iterator, Sequence


def _warm_worker() -> None:
    """Import the model on a worker (and load its numba cache index) before timing starts."""
    from . import slider  # noqa: F401


@contextlib.contextmanager
def local_cluster(scheduler: str | None = None, workers: int | None = None) -> Iterator[str | None]:
    """Yield a scheduler address for repeated :func:`run_tasks` calls.

    ``scheduler=None`` starts one local process cluster for the whole ``with`` block (closed at its
    end) and yields its address; ``"synchronous"`` or an address is yielded unchanged.
    """
    if scheduler is not None:
        yield scheduler
        return
    from distributed import LocalCluster
    n = workers or os.cpu_count() or 1
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.CRITICAL)
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()


def run_tasks(fn: Callable[..., Any], tasks: Sequence[tuple] | Iterable[tuple], *, scheduler: str | None = None,
              workers: int | None = None, on_done: Callable[[Any], None] | None = None) -> float:
    """Run ``fn(*args)`` for each ``args`` in ``tasks``; call ``on_done(result)`` as each finishes.

    Parameters
    ----------
    fn
        An importable function (it is pickled to the workers).
    tasks
        Argument tuples, one per task. Large inputs should travel as file paths.
    scheduler
        ``None`` (a local process cluster for this call), ``"synchronous"`` (this process) or the
        address of a dask.distributed scheduler.
    workers
        Worker processes of a local cluster (default: one per core).
    on_done
        Called in this process with each task's result, in completion order; an exception it raises
        (e.g. ``KeyboardInterrupt``) stops the fan-out, finished results having been handed over.

    Returns
    -------
    float
        Wall time [s] of the batch phase alone (workers started and warmed before it).
    """
    tasks = list(tasks)
    done = on_done or (lambda result: None)
    if scheduler == "synchronous" or not tasks:
        t0 = time.perf_counter()
        for args in tasks:
            done(fn(*args))
        return time.perf_counter() - t0
    from distributed import Client, as_completed
    with local_cluster(scheduler, workers) as address:
        client = Client(address)
        try:
            client.run(_warm_worker)
            t0 = time.perf_counter()
            futures = [client.submit(fn, *args, pure=False, retries=2) for args in tasks]
            for fut in as_completed(futures):
                done(fut.result())
            return time.perf_counter() - t0
        finally:
            client.close()
