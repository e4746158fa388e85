"""Drawing independent figures at once, in a pool of forked processes (:func:`draw_all`).
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import sys
import threading
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence


from ... import interrupts
from ...fanout import available_cores
from .common import DRAWING_MODULES

if TYPE_CHECKING:
    pass


#: The figures of the :func:`draw_all` call in progress (its forked workers inherit them).
_JOBS: list[tuple[Callable[..., Path], tuple, dict]] = []


def _draw(i: int) -> Path:
    fn, args, kwargs = _JOBS[i]
    return fn(*args, **kwargs)


def _worker_init(parent: int) -> None:
    # Ctrl-C: the parent answers it and stops the pool; a killed parent takes its workers with it
    interrupts.default_in_child(parent)


def draw_all(jobs: Sequence[tuple[Callable[..., Path], tuple, dict]], workers: int | None = None) -> list[Path]:
    """Draw independent figures ``(function, args, kwargs)``; returns their paths, in order.

    Agg rendering holds the GIL, so threads do not draw two figures at once; processes do. On Linux,
    with no other thread alive in this process, the figures are drawn by a pool of ``workers``
    (default: the cores this process may use) *forked* processes, which inherit matplotlib already
    imported and the datasets: only an index goes to a worker and a path comes back. Anywhere else
    (another OS, or threads that might hold a lock at the fork) they are drawn here, in order. A
    figure's error is raised here either way (a worker that dies: ``BrokenProcessPool``). A worker dies
    with this process however it ends (:func:`pipeline.interrupts.die_with_parent`). The paper scene's 8
    figures: ``make bench``, row
    "report".
    """
    jobs = list(jobs)
    n = min(len(jobs), workers or available_cores())
    if n < 2 or not sys.platform.startswith("linux") or threading.active_count() > 1:
        return [fn(*args, **kwargs) for fn, args, kwargs in jobs]
    for module in DRAWING_MODULES:
        importlib.import_module(module)  # once, before the fork (~0.7 s every worker would pay again)
    global _JOBS
    _JOBS = jobs
    # (an executor, not multiprocessing.Pool: a worker that dies, e.g. killed for memory, raises
    # BrokenProcessPool here where Pool.map would wait for its lost figure forever)
    pool = ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork"), initializer=_worker_init,
                               initargs=(os.getpid(),))
    try:
        paths = list(pool.map(_draw, range(len(jobs))))
        interrupts.check()
        return paths
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        _JOBS = []
