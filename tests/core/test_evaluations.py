"""The study evaluations (pipeline.evaluations): the store of evaluated points survives a line cut short by a
kill, and an evaluation's base key follows exactly the scene keys and inputs an evaluation reads."""

from __future__ import annotations

import json

from pipeline import candidates, evaluations
from pipeline.model.inputs import SimulationInputs, Source


def test_store_ignores_a_line_cut_short_by_a_kill(tmp_path):
    path = tmp_path / "identify.evals.jsonl"
    store = evaluations.EvaluationStore(path)
    store.put([("a", {"params": [1.0], "outputs": {}}), ("b", {"params": [2.0], "outputs": {}})])
    with open(path, "a") as fh:
        fh.write('{"key": "c", "params": [3.')  # the process died mid-write
    again = evaluations.EvaluationStore(path)
    assert list(again.records) == ["a", "b"] and again["b"]["params"] == [2.0]
    again.put([("c", {"params": [3.0], "outputs": {}})])  # the rerun computes it again and appends it
    assert evaluations.EvaluationStore(path)["c"]["params"] == [3.0]
    assert path.read_text().count("\n\n") == 0  # no empty lines from whole appends


def test_base_key_follows_what_an_evaluation_reads(paper_scene):
    inputs = SimulationInputs(Source("interface", key="interface-key"), Source("dmw", key="dmw-key"))
    key = evaluations.base_key(paper_scene, inputs)
    # settings of other stages and names do not change an evaluation
    assert evaluations.base_key(paper_scene.replace(sweep={"damping_ratio": [0.05]}, identify={"population": 5},
                                              scene={"description": "x"}), inputs) == key
    # a simulation key does; so does an input made from other data (e.g. a rescanned AFM file)
    assert evaluations.base_key(paper_scene.replace(solver={"duration_ms": 0.9}), inputs) != key
    assert evaluations.base_key(paper_scene, SimulationInputs(Source("interface", key="other"), inputs.dmw)) != key


def _counting_task(base, params, rows, protrusions, inputs):
    """A stand-in batch: each candidate's output is its first value; the task's size is recorded in it."""
    return [(key, {"params": list(map(float, x)), "protrusions": list(map(float, protrusions)),
                   "outputs": {"fhm_bv": [float(x[0])] * len(protrusions)}, "seconds": 0.0, "kernel_seconds": 0.0,
                   "error": None, "task_size": len(rows)}) for key, x in rows]


def test_a_short_batch_is_split_over_the_local_workers_and_gives_the_same_records(paper_scene, tmp_path):
    from pipeline.analyses import free_parameters
    params = [free_parameters.Parameter("dmw.rms_nm", 0.0, 1.0)]
    inputs = SimulationInputs(Source("interface", key="i"), Source("dmw", key="d"))
    points = [[0.1 * k] for k in range(1, 14)]
    sizes = {}
    for workers in (1, 2, 3):
        store = evaluations.EvaluationStore(tmp_path / f"w{workers}.jsonl")
        ev = evaluations.Evaluator(paper_scene, params, [9.0], inputs, store, 6, None, workers, task=_counting_task)
        # 3 candidates (the last racing stage's few): one task of 3 on one worker, 2 + 1 on two, 1 + 1 + 1 on three
        recs = ev(points[:3])
        sizes[workers, 3] = sorted(r["task_size"] for r in recs)
        assert [r["outputs"]["fhm_bv"] for r in recs] == [[0.1], [0.2], [0.30000000000000004]]
        # 13: never more than batch_size (6) a task, as many tasks as a multiple of the workers, near-equal
        recs = ev(points)
        sizes[workers, 13] = sorted(r["task_size"] for r in recs[3:])
        assert ev.evaluated == 13 and [r["params"] for r in recs] == points
    assert sizes[1, 3] == [3, 3, 3] and sizes[2, 3] == [1, 2, 2] and sizes[3, 3] == [1, 1, 1]
    # 10 new points: ceil(10 / 6) = 2 tasks of 5 on one or two workers; on three, 3 tasks (4, 3, 3)
    assert sizes[1, 13] == sizes[2, 13] == [5] * 10 and sizes[3, 13] == [3] * 6 + [4] * 4


def test_racing_parts_on_threads_run_a_task_per_record_and_store_the_parts_of_one_task(write_scene, paper_config,
                                                                                        tmp_path):
    """On the local threads a racing part runs one task per (candidate, DMW record), record-major, so that a
    lone candidate (a walk's poll, the last stage's survivor) keeps both threads busy; the parts stored are
    those of one task per part (one worker), but for the times."""
    import numpy as np
    import threading
    import twin
    from pipeline.analyses import free_parameters
    from pipeline.config.scene import load_scene
    path = write_scene(twin.scene_text('targets = ["fhm_flying", "contact_force"]\nrealisations = 4\n')
                       .format(paper=paper_config))
    scene = load_scene(path)
    params = free_parameters.parse_parameters(scene["identify"]["parameters"], str(path), "identify.parameters")
    inputs = evaluations.prepare_inputs(scene, tmp_path / "base")
    calls: list[tuple] = []
    lock = threading.Lock()

    def task(*args):
        with lock:
            calls.append((len(args[2]), args[6], tuple(args[2][0][1])))
        return evaluations.evaluate_batch(*args)

    got = {}
    for workers in (1, 2):
        candidates._CANDIDATES.clear()
        calls.clear()
        store = evaluations.EvaluationStore(tmp_path / f"w{workers}.jsonl")
        ev = evaluations.Evaluator(scene, params, [5.0, 10.0], inputs, store, 4, None, workers, task=task,
                                   realisations=4, stages=(1, 2, 4))
        ev([[0.14, 0.07], [0.16, 0.05]], 1)
        ev([[0.14, 0.07]], 4)  # (a lone candidate's last two parts)
        keys = [ev.key([0.14, 0.07], seg) for seg in ((0, 1), (1, 2), (2, 4))] + [ev.key([0.16, 0.05], (0, 1))]
        got[workers] = [store[k] for k in keys]
        if workers == 1:  # tasks of up to batch_size (4) candidates, one part each
            assert sorted(c[:2] for c in calls) == [(1, (1, 2)), (1, (2, 4)), (2, (0, 1))]
        else:  # one per record, the records in order, the two candidates of the first stage side by side
            assert [c[1] for c in calls[:2]] == [(0, 1), (0, 1)]
            assert {c[2] for c in calls[:2]} == {(0.14, 0.07), (0.16, 0.05)}
            assert sorted(c[1] for c in calls[2:]) == [(1, 2), (2, 3), (3, 4)]
    for one, two in zip(got[1], got[2]):  # (as JSON: a NaN output equals itself)
        assert json.dumps({k: v for k, v in one.items() if "seconds" not in k}, sort_keys=True) == \
            json.dumps({k: v for k, v in two.items() if "seconds" not in k}, sort_keys=True)
    assert got[2][2]["realisations"] == 2 and got[2][2]["first_record"] == 2 and len(got[2][2]["seeds"]) == 2
    assert np.all(np.isfinite(np.array(got[2][2]["outputs"]["fhm_bv"], float)))


def test_joined_parts_state_a_candidate_s_build_error_once_and_every_record_s_own():
    def part(a, b, error, outputs):
        return {"params": [0.1], "protrusions": [9.0], "outputs": outputs, "seconds": 1.0, "kernel_seconds": 0.5,
                "error": error, "realisations": b - a, "seeds": list(range(a, b)), "first_record": a}
    bad = "dmw.rms_nm = 9: above its bound"
    joined = evaluations.join_parts([part(0, 2, bad, {}), part(2, 4, bad, {}), part(4, 8, bad, {})])
    assert joined["error"] == bad and joined["outputs"] == {} and joined["realisations"] == 8
    ok = {"fhm_bv": [[1.0, 2.0]]}
    joined = evaluations.join_parts([part(0, 2, "realisation 1: no start", ok), part(2, 4, None, ok),
                                     part(4, 6, "realisation 5: no start", ok)])
    assert joined["error"] == "realisation 1: no start; realisation 5: no start"
    assert joined["outputs"]["fhm_bv"] == [[1.0, 2.0] * 3] and joined["seeds"] == list(range(6))
    # a part starting at 0 names its first record; join_parts leaves that to the caller, which knows the whole
    assert "first_record" not in joined and evaluations.join_records([part(0, 1, None, ok)], 0)["first_record"] == 0
    assert "first_record" not in evaluations.join_records([part(0, 1, None, ok)], None)


def test_racing_records_on_threads_run_in_blocks_of_as_many_candidates_as_threads(paper_scene, tmp_path):
    """One task per (candidate, record) on the threads: record-major within blocks of as many candidates as
    threads, so that two threads start two candidates and a candidate's next record comes within its block."""
    store = evaluations.EvaluationStore(tmp_path / "s.jsonl")
    ev = evaluations.Evaluator(paper_scene, [], [5.0], SimulationInputs(None, None, None), store, 4, None, 2,
                               realisations=4, stages=(2, 4))
    todo = {(0, 2): {"a": [1.0], "b": [2.0], "c": [3.0]}, (2, 4): {"a2": [1.0]}}
    tasks, _, _ = ev._record_tasks(todo)
    order = [(t[2][0][1][0], t[6][0]) for t in tasks]
    assert order == [(1.0, 0), (2.0, 0), (1.0, 1), (2.0, 1), (1.0, 2), (1.0, 3), (3.0, 0), (3.0, 1)]
