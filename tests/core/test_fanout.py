"""pipeline.fanout.run_tasks: every task once, results to on_done in the caller's thread, errors stop it; the
split of items into tasks, which decides where they run, not what they give.
"""

from __future__ import annotations

import threading
import time

import pytest

from pipeline import fanout
from pipeline.fanout import local_workers, run_tasks, split
from pipeline.runner import ensure
from fanout_tasks import square


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


def test_split_deals_every_item_once_into_one_task_per_worker(monkeypatch):
    items = list(range(11))
    threads = {"tcp://big:8786": 64, "tcp://small:8786": 4}
    monkeypatch.setattr(fanout, "cluster_threads", threads.__getitem__)
    for scheduler, workers, n in ((None, 3, 3), ("threads", 2, 2), ("synchronous", 20, 11),
                                  ("tcp://small:8786", None, 4), ("tcp://big:8786", 3, 11)):
        chunks = split(items, scheduler, workers)
        assert len(chunks) == n and all(chunks)
        assert sorted(x for c in chunks for x in c) == items  # each once
        assert chunks[0] == tuple(items[::n])  # round-robin: each task spans the range
    assert split([5], "tcp://big:8786") == [(5,)]  # no empty task


def test_a_cluster_split_follows_its_threads():
    # a cluster gets a task per thread, not a fixed number (a 64-worker dask-jobqueue cluster runs calibrate on 64)
    from distributed import LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=3, processes=False, dashboard_address=None) as cluster:
        assert fanout.cluster_threads(cluster.scheduler_address) == 6
        chunks = split(list(range(20)), cluster.scheduler_address)
    assert len(chunks) == 6 and sorted(x for c in chunks for x in c) == list(range(20))


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


# ------------------------------------------------------------ the split decides where, not what
def _same_rows(a: list[tuple], b: list[tuple]) -> bool:
    """Realisation rows ``(realisation, outputs, kernel seconds, errors)`` equal bit for bit but the timing."""
    import numpy as np
    return len(a) == len(b) and all(
        x[0] == y[0] and x[3] == y[3] and x[1].keys() == y[1].keys()
        and all(np.array_equal(x[1][k], y[1][k], equal_nan=True) for k in x[1]) for x, y in zip(a, b))


def test_an_ensemble_realisation_does_not_depend_on_the_task_it_shares(paper_config):
    # the split follows the cluster's threads: the realisations a task holds (sharing static starts) vary with it
    from pipeline import evaluations
    from pipeline.config.scene import load_scene
    from pipeline.model import dmw_record
    from pipeline.model.inputs import SimulationInputs
    scene = load_scene(paper_config, ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.4",
                                      "solver.transient_ms=0.1"])
    seeds = dmw_record.realisation_seeds(scene["dmw"]["seed"], 4)
    inputs, prots = SimulationInputs(), [2.0, 2.2]  # (no contact: no k; seeded records, no dmw.nc)
    together = evaluations.evaluate_realisations(scene, prots, inputs, (1, 2, 3), tuple(seeds[1:]))
    apart = [row for r in (1, 2, 3)
             for row in evaluations.evaluate_realisations(scene, prots, inputs, (r,), (seeds[r],))]
    assert _same_rows(together, apart)
    assert not _same_rows(together[:1], together[1:2])  # (the realisations differ: the comparison can fail)


@pytest.mark.slow
def test_the_calibration_does_not_depend_on_its_split(paper_config, tmp_path):
    # one task holding every protrusion (its flying runs share one model) against four
    from pipeline.config.scene import load_scene
    from pipeline.io import read_dataset
    scene = load_scene(paper_config, ["solver.duration_ms=1.0", "solver.transient_ms=0.3", "touchdown.curve_points=5",
                                      'scene.effects=["air_bearing","pitch","dmw","contact","friction"]',
                                      "sweep.protrusion_nm={start=9.6, stop=10.4, step=0.2}",
                                      # (a touchdown whose k is physical without adhesion: tests/stages/test_sweep.py)
                                      "touchdown.onset_nm=9.6", "touchdown.previous_nm=9.4"])
    got = []
    for workers in (1, 4):
        path = ensure("calibrate", scene, tmp_path / f"w{workers}", scheduler="synchronous", workers=workers)
        got.append(read_dataset(path))
        got[-1].attrs.pop("history", None)
    assert got[0].identical(got[1]) and got[0].sizes["protrusion"] == 5
