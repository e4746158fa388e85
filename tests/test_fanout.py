"""pipeline.fanout.run_tasks: every task once, results to on_done in the caller's thread, errors stop it."""

from __future__ import annotations

import threading
import time

import pytest

from pipeline import fanout
from pipeline.fanout import local_workers, run_tasks, split


def square(x: int) -> tuple[int, int, str]:
    time.sleep(0.01)  # long enough for a second thread to pick up work
    return x, x * x, threading.current_thread().name


@pytest.mark.parametrize("scheduler", [None, "synchronous", "threads"])
def test_every_task_once_results_in_the_calling_thread(scheduler):
    got, callers = [], set()

    def done(r):
        got.append(r)
        callers.add(threading.current_thread().name)

    seconds = run_tasks(square, [(i,) for i in range(12)], scheduler=scheduler, workers=3, on_done=done)
    assert sorted((x, y) for x, y, _ in got) == [(i, i * i) for i in range(12)]
    assert callers == {threading.current_thread().name}
    assert seconds > 0
    ran_on = {name for _, _, name in got}
    if scheduler == "synchronous":
        assert ran_on == {threading.current_thread().name}
    else:
        assert threading.current_thread().name not in ran_on and 1 < len(ran_on) <= 3


def test_one_worker_or_one_task_runs_in_process():
    here = threading.current_thread().name
    got = []
    run_tasks(square, [(1,), (2,)], workers=1, on_done=got.append)
    run_tasks(square, [(3,)], on_done=got.append)
    assert {name for _, _, name in got} == {here}
    assert local_workers(None, 1) == 1 and local_workers(8, 3) == 3
    with pytest.raises(ValueError, match="workers"):
        local_workers(-1, 3)


def test_split_deals_every_item_once_into_one_task_per_worker():
    items = list(range(11))
    for scheduler, workers, n in ((None, 3, 3), ("threads", 2, 2), ("synchronous", 20, 11),
                                  ("tcp://scheduler:8786", None, fanout.CLUSTER_TASKS)):
        chunks = split(items, scheduler, workers)
        assert len(chunks) == n and all(chunks)
        assert sorted(x for c in chunks for x in c) == items  # each once
        assert chunks[0] == tuple(items[::n])  # round-robin: each task spans the range
    assert split([5], "tcp://scheduler:8786") == [(5,)]  # no empty task


def test_an_error_in_on_done_cancels_what_has_not_started():
    started = []

    def slow(i):
        started.append(i)
        time.sleep(0.02)
        return i

    def stop(_):
        raise KeyboardInterrupt("stop")

    with pytest.raises(KeyboardInterrupt):
        run_tasks(slow, [(i,) for i in range(50)], scheduler="threads", workers=2, on_done=stop)
    assert len(started) < 50


def test_a_failing_task_raises():
    def bad(i):
        if i == 3:
            raise ValueError("task 3 failed")
        return i

    with pytest.raises(ValueError, match="task 3"):
        run_tasks(bad, [(i,) for i in range(6)], scheduler="threads", workers=2)
