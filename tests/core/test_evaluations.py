"""The study evaluations (pipeline.evaluations): the store of evaluated points survives a line cut short by a
kill, and an evaluation's base key follows exactly the scene keys and inputs an evaluation reads."""

from __future__ import annotations

from pipeline import evaluations
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
