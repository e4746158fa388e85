"""The per-process cache of study candidates (pipeline.candidates): a candidate kept between its racing parts
gives the records of a fresh one, and its tabulated TFC-point forces are made once for its records."""

from __future__ import annotations

import json

from pipeline import candidates, evaluations


def test_a_candidate_kept_between_its_racing_parts_gives_the_records_of_a_fresh_one(write_scene, paper_config,
                                                                                    tmp_path, monkeypatch):
    """The racing parts of one candidate share its static starts (:class:`pipeline.candidates.Candidates`): the flying
    branch is found once for all parts, and every output is the one a fresh candidate per part gives."""
    import numpy as np
    import twin
    from pipeline.analyses import free_parameters
    from pipeline.config.scene import load_scene
    from pipeline.model import start
    path = write_scene(twin.scene_text('targets = ["fhm_flying", "contact_force"]\nrealisations = 4\n')
                       .format(paper=paper_config))
    scene = load_scene(path)
    params = free_parameters.parse_parameters(scene["identify"]["parameters"], str(path), "identify.parameters")
    prots = [5.0, 10.0]
    inputs = evaluations.prepare_inputs(scene, tmp_path / "base")
    ladders = []
    real = start.flying_ladder
    monkeypatch.setattr(start, "flying_ladder", lambda *a, **k: ladders.append(1) or real(*a, **k))
    x, parts = [0.14, 0.07], ((0, 1), (1, 2), (2, 4))

    def run(fresh: bool) -> list[dict]:
        out = []
        for seg in parts:
            if fresh or not out:
                candidates._CANDIDATES.clear()
            out.append(evaluations.evaluate(scene, params, x, prots, inputs, 4, seg))
        return out

    kept = run(fresh=False)
    assert len(ladders) == 1  # (one candidate: its fold once, whatever part asks)
    fresh = run(fresh=True)
    assert len(ladders) == 1 + len(parts)
    for a, b in zip(kept, fresh):
        assert a["error"] is None and b["error"] is None and a["seeds"] == b["seeds"]
        assert a["outputs"].keys() == b["outputs"].keys()
        for k in a["outputs"]:
            np.testing.assert_array_equal(np.array(a["outputs"][k], float), np.array(b["outputs"][k], float))
    # a kept candidate is one of these base objects: another base with the same values is another candidate
    other = load_scene(path)
    assert candidates._CANDIDATES.get(other, inputs, params, x) is not candidates._CANDIDATES.get(scene, inputs, params, x)



def test_a_candidate_s_tfc_tables_are_made_once_for_its_records_and_give_the_same_outputs(write_scene, paper_config,
                                                                                           tmp_path, monkeypatch):
    """A candidate's records share its model (``assembly.with_record``) and, while it is among the last
    ``TABLES_KEPT`` candidates, its tabulated TFC-point forces (the bulge's law, one 4001-knot table per
    protrusion): made once for its records, not once per record, and every output is a fresh candidate's."""
    import numpy as np
    import twin
    from pipeline.analyses import free_parameters
    from pipeline.config.scene import load_scene
    from pipeline.model import kernel_inputs
    text = twin.scene_text('targets = ["fhm_flying"]\nrealisations = 3\n') + '\n[air_bearing]\nbulge = "ph-limit"\n'
    scene = load_scene(write_scene(text.format(paper=paper_config)))
    params = free_parameters.parse_parameters(scene["identify"]["parameters"], "twin", "identify.parameters")
    inputs = evaluations.prepare_inputs(scene, tmp_path / "base")
    made = []
    real = kernel_inputs._tfc_table
    monkeypatch.setattr(kernel_inputs, "_tfc_table", lambda *a: made.append(a[2]) or real(*a))
    prots, x, y = [5.0, 10.0], [0.14, 0.07], [0.2, 0.05]

    def records(fresh: bool, point: list[float]) -> tuple[list[dict], list[int]]:
        out, counts = [], []
        for r in range(3):
            if fresh or r == 0:
                candidates._CANDIDATES.clear()
            n = len(made)
            out.append(evaluations.evaluate(scene, params, point, prots, inputs, 3, (r, r + 1)))
            counts.append(len(made) - n)
        return out, counts

    kept, counts = records(False, x)
    # (the first record: the static starts' continuation ladder and the runs; the next ones none)
    assert counts[0] >= len(prots) and counts[1:] == [0, 0]
    fresh, again = records(True, x)
    assert again == [counts[0]] * 3
    for a, b in zip(kept, fresh):
        assert a["error"] is None and json.dumps(a["outputs"]) == json.dumps(b["outputs"])
    assert np.all(np.isfinite(np.array(kept[0]["outputs"]["fhm_bv"], float)))
    # the tables of the candidates run before the last TABLES_KEPT are dropped
    monkeypatch.setattr(candidates, "TABLES_KEPT", 1)
    first = candidates._CANDIDATES.get(scene, inputs, params, x)
    assert len(first.tfc_tables) == len(prots)
    evaluations.evaluate(scene, params, y, prots, inputs, 3, (0, 1))
    assert first.tfc_tables == {} and len(candidates._CANDIDATES.get(scene, inputs, params, y).tfc_tables) == 2
