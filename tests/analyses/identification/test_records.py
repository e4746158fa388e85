"""The identification's records (pipeline/analyses/identification/records.py): any evaluation callable, an
ensemble evaluated in parts and joined, a point evaluated already not run again.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analyses import free_parameters, identification, study
from identification_cases import _ensemble_task, _racing_evaluator


def test_the_identification_takes_any_evaluation_callable(paper_scene):
    # the algorithm (analyses) on a plain function, no stage, store or fan-out: the FHM at 9 nm is ten times
    # the first parameter, which the second does not touch; the target is 9 % within 1 %
    scene = paper_scene.replace(identify={"targets": ["fhm_touchdown"]})
    tlist = study.targets(scene)
    params = [free_parameters.Parameter("dmw.rms_nm", 0.5, 1.5), free_parameters.Parameter("air_bearing.damping_ratio", 0.01, 0.2)]

    def evaluate(points):
        return [{"key": repr(tuple(x)), "params": list(map(float, x)), "protrusions": [9.0],
                 "outputs": {"fhm_bv": [10.0 * float(x[0])]}} for x in points]

    ident = identification.Identification(evaluate, tlist, 10.0)
    out = identification.identify(ident, params, np.array([1.2, 0.05]),
                                  {"generations": 5, "population": 5, "seed": 1, "profile_points": 5,
                                   "profile_method": "optimised", "profile_evaluations": 40, "polish": True})
    assert out["within"] and abs(10.0 * out["best"][0] - 9.0) <= 1.0
    # the interval of the first parameter is where |10 x - 9| <= 1; the second is seen by no target
    assert out["intervals"][0] == pytest.approx([0.8, 1.0], abs=1e-9)
    assert np.isinf(out["gn_std"][1]) and np.all(np.isnan(out["correlation"][1]))
    assert ident.roles[ident.keys[0]] == 0 and len(ident.records) == len(set(ident.keys))


def test_the_evaluator_runs_an_ensemble_in_parts_and_joins_them(paper_scene, tmp_path):
    ev, store = _racing_evaluator(paper_scene, tmp_path)
    first = ev([[0.1], [0.2]], 2)
    assert [r["realisations"] for r in first] == [2, 2] and ev.record_evaluations == 4
    assert first[0]["outputs"]["fhm_bv"] == [[0.1, 1.1]] and first[0]["key"] == ev.key([0.1])
    whole = ev([[0.1]], 8)[0]  # the first part is read back: 6 records more
    assert ev.record_evaluations == 4 + 6 and whole["realisations"] == 8 and whole["key"] == ev.key([0.1])
    assert whole["outputs"]["fhm_bv"] == [[0.1 + r for r in range(8)]] and whole["seeds"] == list(range(8))
    assert whole["seconds"] == 8.0 and whole["error"] is None
    with pytest.raises(ValueError, match="records 3: expected one of the racing stages"):
        ev([[0.1]], 3)
    # a whole evaluation of the full method in the store is read back, its first records as the part
    store.put([(ev.key([0.3]), _ensemble_task(None, None, [("k", [0.3])], [9.0], None, 8)[0][1])])
    part = ev([[0.3]], 4)[0]
    assert part["outputs"]["fhm_bv"] == [[0.3, 1.3, 2.3, 3.3]] and part["seconds"] == 4.0
    assert ev.record_evaluations == 10  # nothing computed
    # the stages' parts of the real evaluation are the whole, bit for bit: tests/analyses below (twin)


def test_a_point_evaluated_already_is_not_run_again(paper_scene, tmp_path):
    # a racing identification on the evaluator: the (candidate, record) pairs computed are counted once, whatever
    # asks for the point again (a walk's poll met by another walk, a slice point, a resumed run)
    ev, store = _racing_evaluator(paper_scene, tmp_path)
    targets = [study.ObjectiveTerm("fhm", "fhm", "%", "equal", 0.0, 1.0, (9.0,), lambda t: t.value("fhm_bv", 9.0),
                                   "", lambda e: study._median(study.Ensemble.of(e).at("fhm_bv", (9.0,))[0]))]
    ident = identification.Identification(ev, targets, 10.0, identification.Racing.doubling(2, 8, 3.0))
    pts = np.array([[0.1], [20.0], [30.0]])
    ident.evaluate(pts[:1], 0)  # the best point, on every record: objective (0.1 + 3.5)^2
    _, _, r = ident.evaluate(pts, 1, bound=ident.best_cost, refs=pts[0])
    # 20 and 30 stop after their first 2 records (residuals 20.5 and 30.5, less a margin of 5.6 from the best
    # point's spread of the records, 2.45, are above its 3.6); 0.1 is the best point, held
    assert [ident.depth[k] for k in ident.keys] == [8, 2, 2]
    assert ev.record_evaluations == 8 + 2 + 2 and ident.record_evaluations == 12
    assert r[:, 0] == pytest.approx([3.6, 20.5, 30.5])
    # asked again, on every record: only their records 2-7 run; a third time, nothing
    ident.evaluate(pts, 4)
    assert ev.record_evaluations == 8 + 8 + 8 and [ident.depth[k] for k in ident.keys] == [8, 8, 8]
    ident.evaluate(pts[::-1], 2, bound=0.0, refs=pts[0])
    assert ev.record_evaluations == 24 and ident.record_evaluations == 24
