"""The accuracy study's rules (pipeline/analyses/knob_study.py) on numbers and stand-in evaluations: the relative
error against max(|reference|, floor) (NaN where both are missing, inf where one is), the maximum and the pass
test ignoring what does not apply, a knob's solver values (atol_nm = 100 nm x rtol along the rtol knob), the
choice of a setting (the cheapest passing one, the scene's own among those within 10 % of its cost), and the
combined check that steps a knob back until the chosen settings pass together."""

from __future__ import annotations

import numpy as np

from pipeline.analyses import knob_study
from pipeline.analyses.knob_study import Knob, Result


def test_relative_error_definition():
    nan, inf = np.nan, np.inf
    err = knob_study.relative_error(np.array([1.1, 0.002, nan, nan, 1.0]), np.array([1.0, 0.0, nan, 2.0, nan]), 0.01)
    np.testing.assert_allclose(err[:2], [0.1, 0.2])  # tol: |a - b| / |b| of exact decimals, a few roundings
    assert np.isnan(err[2]) and err[3] == inf and err[4] == inf


def test_the_maximum_and_the_pass_test_ignore_what_does_not_apply():
    nan = np.nan
    err = np.array([[0.001, nan, 0.004], [nan, nan, nan]])
    np.testing.assert_array_equal(knob_study.max_error(err), [0.004, nan])
    assert knob_study.passes(err, 0.005) and not knob_study.passes(err, 0.004)   # strictly below
    assert knob_study.passes(np.full(3, nan), 1e-9)                                  # nothing applies
    assert not knob_study.passes(np.array([np.inf]), 1e300)


def _result(values, failed=(), sim_time=1.0, build=None) -> Result:
    values = np.asarray(values, float)
    return Result(values, np.full(values.shape[0], sim_time), build or {"table": 2.0, "record": 0.5, "model": 0.25},
                  np.zeros((values.shape[0], 3)), np.isin(np.arange(values.shape[0]), failed), [])


def test_errors_use_each_outputs_floor_and_a_failed_point_is_infinitely_wrong():
    n = len(knob_study.HEADLINE)
    ref = _result(np.ones((2, n)))
    ref.values[1, 0] = np.nan                                    # no FHM at the second point
    res = _result(np.full((2, n), 1.01), failed=[1])
    err = knob_study.errors(res, ref)
    np.testing.assert_allclose(err[0], 0.01)  # tol: |a - b| / |b| of exact decimals, a few roundings
    assert np.isnan(err[1, 0]) and np.isinf(err[1, 1:]).all()
    # below its floor a value's error is taken against the floor: 0.1 % FHM, 0.01 nm clearance
    small = _result(np.zeros((1, n)))
    off = _result(np.full((1, n), 0.001))
    assert knob_study.errors(off, small)[0, 0] == 0.001 / knob_study.ERROR_FLOORS["fhm_bv"] == 0.01
    assert Result.setup_time(ref, "table") == 2.25 and Result.setup_time(ref, "solver") == 0.0
    assert Result.setup_time(ref, "all") == 2.75 and Result.setup_time(ref, "dmw") == 0.75


def test_a_knobs_values_and_the_configuration_at_its_levels():
    rtol, nodes = knob_study.KNOBS[0], next(k for k in knob_study.KNOBS if k.name == "quadrature_nodes")
    assert rtol.solver_values(1e-7) == {"rtol": 1e-7, "atol_nm": 1e-5}             # 100 nm x rtol
    assert nodes.solver_values(16.0) == {"quadrature_nodes": 16} and isinstance(knob_study.cast("quadrature_nodes", 16.0), int)
    assert isinstance(knob_study.cast("table_step_nm", 1), float)
    ref = {"rtol": 1e-6, "atol_nm": 1e-4, "quadrature_nodes": 24}
    cfg = knob_study.configuration(ref, [rtol, nodes], {"rtol": 2, "quadrature_nodes": None})
    assert cfg == {"rtol": 1e-8, "atol_nm": 1e-6, "quadrature_nodes": 24} and ref["rtol"] == 1e-6


KNOB = Knob("max_step_ns", ("solver", "max_step_ns"), (25.0, 50.0, 100.0, 250.0), "ns", "largest step", "solver")


def test_the_choice_is_the_cheapest_passing_setting_and_the_scenes_own_within_ten_percent():
    ok = np.array([True, True, True, False])
    cost = np.array([4.0, 2.0, 1.05, 0.5])
    max_err = np.array([[0.001, 0.002, 0.004, 0.02]])
    assert knob_study.choose(KNOB, None, ok, cost, max_err) == 2                # the cheapest that passes
    cost_tie = np.array([4.0, 1.08, 1.0, 0.5])                                   # 50 ns within 10 % of 100 ns
    assert knob_study.choose(KNOB, 50.0, ok, cost_tie, max_err) == 1             # the scene's own
    assert knob_study.choose(KNOB, None, ok, cost_tie, max_err) == 1             # else the smaller error of the tie
    assert knob_study.choose(KNOB, None, np.zeros(4, bool), cost, max_err) is None


def test_the_combined_check_steps_back_the_knob_that_makes_it_pass_cheapest():
    """A stand-in whose error is the sum of each knob's own (a level-l setting errs by 0.004 l): two knobs at
    level 2 each pass 0.01 alone (0.008) but not together (0.016); one step back (0.004 + 0.008) passes."""
    other = Knob("min_dwell_ns", ("solver", "min_dwell_ns"), (1.0, 5.0, 20.0), "ns", "dwell", "solver")
    knobs = [KNOB, other]
    n = len(knob_study.HEADLINE)
    calls = []

    def evaluate(cfg, repeat):
        calls.append(dict(cfg))
        lvl = [kb.settings.index(cfg[kb.key[1]]) if kb.key[1] in cfg else 0 for kb in knobs]
        err = 0.004 * sum(lvl)
        # the cheaper run steps back max_step_ns (its smaller step costs less than the dwell's here)
        return _result(np.full((1, n), 1.0 + err), sim_time=1.0 + (0.5 if lvl[1] < 2 else 0.0))

    ref = _result(np.ones((1, n)))
    levels, res, notes = knob_study.combine(evaluate, knobs, {}, {"max_step_ns": 2, "min_dwell_ns": 2}, 1, ref, 0.013)
    assert levels == {"max_step_ns": 1, "min_dwell_ns": 2}
    assert knob_study.passes(knob_study.errors(res["chosen"], ref), 0.013)
    assert len(notes) == 1 and "max_step_ns stepped back to 50" in notes[0] and "max error then 0.012" in notes[0]
    assert len(calls) == 4                        # the combination, one trial per knob, the kept combination
