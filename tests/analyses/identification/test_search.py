"""The identification's search (pipeline/analyses/identification/search.py): the polish starts the profiles at the
optimum and agrees with the method without it, on a stand-in and on the twin.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analyses import identification
from pipeline.config.limits import POLISH_EVALUATIONS
from identification_cases import (CFG, N_RECORDS, PARAMS, _agree_within_tolerance, _ensemble_twin,
                                  _identified_with_and_without, _mean_targets, _same_answer, _stand_in, _twin_targets)


def test_the_polish_starts_the_profiles_at_the_optimum_and_agrees_with_the_method_without_it():
    # one generation of 4 x 2 candidates stops short of the optimum (0, 0) of the noisy correlated quadratic: without
    # the polish a profile point beats it by more than PROFILE_GAIN and the profiles are made twice; with it once
    race = identification.Racing.doubling(2, N_RECORDS, 3.0)
    runs = {}
    for polish in (False, True):
        calls: list[int] = []
        ident = identification.Identification(_stand_in(calls), _mean_targets(), 10.0, race)
        cfg = dict(CFG, generations=1, population=4, polish=polish)
        runs[polish] = ident, identification.identify(ident, PARAMS, np.array([2.0, -1.0]), cfg)
    (plain_ident, plain), (ident, out) = runs[False], runs[True]
    assert plain["polish"] is None and plain_ident.roles and 5 not in plain_ident.roles.values()
    assert plain["profile_rounds"] == 2 and out["profile_rounds"] == 1
    # what it did: from the search's best point (objective 7.6) to within PROFILE_GAIN of the best of all, its
    # polls counted in the records with role 5, within its budget, the last at most the walks' step
    p = out["polish"]
    assert p["start_objective"] == pytest.approx(7.62, abs=0.01) and p["moves"] >= 1
    assert p["objective"] < p["start_objective"] and p["objective"] - ident.best_cost <= identification.PROFILE_GAIN
    # (a point the search asked for keeps its role)
    assert sum(r == 5 for r in ident.roles.values()) <= p["evaluations"] <= POLISH_EVALUATIONS * 2
    assert p["first_step"] == pytest.approx(1.0 / (CFG["profile_points"] - 1)) and \
        p["last_step"] <= identification.PROFILE_STEP
    # the best point ran on every record; it costs fewer (candidate, record) pairs than the second round it saves
    assert ident.depth[ident.best_key] == N_RECORDS
    assert ident.record_evaluations < 0.95 * plain_ident.record_evaluations
    # the same answer within the tolerance, the truth (0, 0) inside both (one profile step: 1)
    step = (PARAMS[0].high - PARAMS[0].low) / (CFG["profile_points"] - 1)
    _agree_within_tolerance(out, plain, step, np.zeros(2))
    assert abs(ident.best_cost - plain_ident.best_cost) < 0.01


@pytest.mark.slow  # (two identifications of the real slider on 4 DMW records: ~1 min on the shared 2 cores)
def test_twin_polish_agrees_with_the_method_without_it_within_the_tolerance(write_scene, paper_config, tmp_path):
    # one generation of 4 x 2 candidates, racing on: the search stops short of the truth, the polish takes it the
    # rest of the way before the profiles
    path, scene, params, tl, prots, inputs, whole = _ensemble_twin(write_scene, paper_config, tmp_path)
    sets = _twin_targets(tl, whole) + ["identify.generations=1"]
    on, off = _identified_with_and_without(path, sets, "polish", tmp_path)
    assert "polish" not in off.attrs and not np.any(off["role"].values == 5)
    assert on.attrs["polish_objective"] < on.attrs["polish_start_objective"] and on.attrs["polish_moves"] >= 1
    assert int(np.sum(on["role"].values == 5)) <= on.attrs["polish_evaluations"] <= \
        POLISH_EVALUATIONS * len(params)
    # the profiles' rounds and the pairs: fewer with the polish where the search stopped short (1 round and 230
    # (candidate, record) pairs against 2 and 276 when written)
    assert on.attrs["profile_rounds"] == 1 < off.attrs["profile_rounds"]
    assert on.attrs["record_evaluations"] < off.attrs["record_evaluations"]
    _same_answer(on, off, params, scene)
