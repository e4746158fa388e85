"""The screening and variance-based sensitivity algorithms (pipeline/analyses/screening.py) on plain functions
with known indices, without the stage: for ``y = sum a_i x_i`` on ranges ``w_i`` Morris gives ``mu = mu* = a_i
w_i`` (the change over the whole range) with ``sigma = 0``, and Sobol ``S1 = ST = (a_i w_i)^2 / sum_j (a_j
w_j)^2``; a parameter the output ignores gets 0; a trajectory or Saltelli block with an undefined sample is left
out and the note says how many were used, too few whole ones or a constant output leave the indices undefined
with the reason."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analyses import screening
from pipeline.analyses.free_parameters import Parameter

PARAMS = [Parameter("dmw.rms_nm", 0.1, 0.3), Parameter("air_bearing.damping_ratio", 0.01, 0.21),
          Parameter("contact.damping_n_s_m", 0.0, 0.05)]
A = np.array([5.0, -2.0, 0.0])                   # the third parameter does not enter
WIDTH = np.array([p.high - p.low for p in PARAMS])
SETTINGS = {"morris_trajectories": 20, "morris_levels": 4, "sobol_samples": 512, "seed": 7, "bootstrap": 50,
            "confidence_level": 0.95}


def linear(X: np.ndarray) -> dict[str, np.ndarray]:
    return {"fhm": X @ A}


def test_morris_of_a_linear_model_is_the_change_over_each_range():
    X, Y, out = screening.morris(linear, PARAMS, SETTINGS)
    assert X.shape == (20 * (len(PARAMS) + 1), len(PARAMS)) and Y["fhm"].shape == (X.shape[0],)
    ind = out["fhm"]
    np.testing.assert_allclose(ind.values["mu_star"], np.abs(A) * WIDTH, atol=1e-12)
    np.testing.assert_allclose(ind.values["mu"], A * WIDTH, atol=1e-12)
    np.testing.assert_allclose(ind.values["sigma"], 0.0, atol=1e-12)
    assert (ind.used, ind.total, ind.undefined, ind.note) == (20, 20, 0, "") and ind.defined


def test_sobol_of_a_linear_model_shares_the_variance_by_the_squared_changes():
    X, Y, out = screening.sobol(linear, PARAMS, SETTINGS)
    assert X.shape == (512 * (len(PARAMS) + 2), len(PARAMS))
    share = (A * WIDTH) ** 2 / np.sum((A * WIDTH) ** 2)          # (1.0, 0.4, 0) squared: 0.862, 0.138, 0
    ind = out["fhm"].values
    np.testing.assert_allclose(ind["S1"], share, atol=0.03)
    np.testing.assert_allclose(ind["ST"], share, atol=0.03)
    assert ind["ST"][2] == pytest.approx(0.0, abs=1e-12) and out["fhm"].note == ""


def test_an_undefined_sample_leaves_out_its_trajectory_or_block_and_the_note_says_so():
    def with_holes(X):
        y = X @ A
        y[[0, 5]] = np.nan               # one point of the first trajectory (block) and one of the second
        return {"fhm": y}
    _, _, m = screening.morris(with_holes, PARAMS, SETTINGS)
    ind = m["fhm"]
    assert (ind.used, ind.total, ind.undefined) == (18, 20, 2)
    assert ind.note == "over 18 of 20 trajectories (the whole ones); 2 of 80 samples undefined (no value or a " \
                       "failed evaluation)"
    np.testing.assert_allclose(ind.values["mu_star"], np.abs(A) * WIDTH, atol=1e-12)   # exact on the rest
    _, _, s = screening.sobol(with_holes, PARAMS, SETTINGS)
    assert (s["fhm"].used, s["fhm"].total) == (510, 512) and s["fhm"].note.startswith("over 510 of 512 Saltelli blocks")


def test_too_few_whole_samples_or_a_constant_output_leave_the_indices_undefined():
    def mostly_undefined(X):
        y = np.full(X.shape[0], np.nan)
        y[:4] = 1.0                      # one whole trajectory of 4 points: fewer than MIN_WHOLE = 2
        return {"fhm": y}
    _, _, m = screening.morris(mostly_undefined, PARAMS, SETTINGS)
    assert not m["fhm"].defined and np.isnan(m["fhm"].values["mu_star"]).all()
    assert m["fhm"].note.startswith("undefined: 1 of 20 trajectories whole, 2 needed")
    _, _, s = screening.sobol(lambda X: {"fhm": np.full(X.shape[0], 3.0)}, PARAMS, SETTINGS)
    assert not s["fhm"].defined
    assert s["fhm"].note == "undefined: the output does not vary (every used sample 3: zero variance)"


def test_the_problem_and_the_failures_text():
    assert screening.problem(PARAMS[:1]) == {"num_vars": 1, "names": ["dmw.rms_nm"], "bounds": [[0.1, 0.3]]}
    assert screening.failures_text([None, None]) == ""
    assert screening.failures_text([None, "diverged", "timeout"]) == "2 of 3 evaluations failed; first: diverged"
