"""The calibration's rules (pipeline.analyses.calibration): k* is where a full run starts touching, the end probes
give the plain bisection's answer where touching is monotone and the one next to the upper end where it is not,
and the choice of k in the admissible interval (the middle, or the paper's two-sided 32.8 %: k = 0.978)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.config.scene import load_scene
from pipeline.analyses import calibration

PAPER = Path(__file__).resolve().parents[2] / "configs" / "paper-2009.toml"
# without adhesion there is no snap-in: a k exists that puts contact at 9.8 nm and not at 9.6 nm (as in
# stages/test_calibrate.py, which compares the stage's two methods on this scene)
NO_ADHESION = ["solver.duration_ms=1.0", "solver.transient_ms=0.3", "touchdown.curve_points=5",
               'scene.effects=["air_bearing","pitch","dmw","contact","friction"]',
               "sweep.protrusion_nm={start=9.0, stop=10.4, step=0.2}"]


def test_threshold_is_where_touching_starts():
    """Just above k* the full run touches, just below it does not (the definition of k*)."""
    scene = load_scene(PAPER, NO_ADHESION)
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        from pipeline.model import assembly
        from pipeline.stages.simulate import model_inputs
        interface, record = model_inputs(scene, Path(tmp))
        model = assembly.build_model(scene, interface, record, k=0.0)
        lo, lo_all, note = calibration.flying_minimum(model, 9.8)
        assert note == "" and lo_all <= lo
        tol = 1e-6
        k, sims = calibration.k_star(model, 9.8, lo, lo_all, (-3.0, 3.0), tol)
        if sims == 0:  # k* straight from the flying run: exact
            assert k == lo / model.sigma
        assert calibration.touches(model, 9.8, k + tol)
        assert not calibration.touches(model, 9.8, k - tol)


def _plain_bisection(touching, lo, hi, tol):
    """The bisection k_threshold ran before its end probes (the reference)."""
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if touching(mid):
            hi = mid
        else:
            lo = mid
    return hi


@pytest.mark.parametrize("k0", [-2.9996, -1.2345, 0.0, 0.7, 2.9995])
def test_the_end_probes_give_the_bisections_answer_where_touching_is_monotone(monkeypatch, k0):
    # touching for every k > k0: the answer is the plain bisection's, bit for bit; next to an end of the
    # range (where k* lies past the touchdown) one probe besides the range's ends settles it
    monkeypatch.setattr(calibration, "touches", lambda model, delta, k: k > k0)
    lo, hi, tol = -3.0, 3.0, 1e-3
    k, status, n = calibration.k_threshold(None, 10.0, (lo, hi), tol)
    assert status == "found" and k == _plain_bisection(lambda k: k > k0, lo, hi, tol)
    assert k - tol <= k0 < k
    plain_runs = 2 + int(np.ceil(np.log2((hi - lo) / tol)))
    assert n == (3 if k0 > hi - tol else 4 if k0 < lo + tol else plain_runs + 2), n


def test_where_touching_is_not_monotone_the_threshold_is_the_one_next_to_the_upper_end(monkeypatch):
    # a pocket of contact at -0.79 (a transient contact moving the window) below a window minimum at
    # -0.7806: the bisection met the pocket; k* is where contact holds for every k above it
    pocket, top = (-0.7893, -0.7880), -0.7806
    monkeypatch.setattr(calibration, "touches", lambda model, delta, k: pocket[0] < k < pocket[1] or k >= top)
    k, status, n = calibration.k_threshold(None, 13.2, (-0.85, top), 1e-3)
    assert (k, status, n) == (top, "found", 3)
    assert pocket[0] < _plain_bisection(lambda k: pocket[0] < k < pocket[1] or k >= top, -0.85, top, 1e-3) < pocket[1]


def test_k_choice_middle_and_paper():
    """touchdown.k_choice: the middle of the admissible interval, or the paper's k (32.8 % two-sided,
    k = 0.978) when admissible, else the admissible end nearest to it."""
    from pipeline.analyses.calibration import choose_k
    assert choose_k(-2.0, 1.0, "middle", None)[0] == -0.5
    k, why = choose_k(-2.48, 1.455, "paper", 0.328)
    assert k == pytest.approx(0.978, abs=5e-4) and "admissible" in why
    assert choose_k(-2.0, 0.5, "paper", 0.328)[0] == 0.5          # the upper end is admissible
    k_low = choose_k(1.2, 2.0, "paper", 0.328)[0]                  # the lower end is not: just above it
    assert 1.2 < k_low < 1.2 + 1e-2
    with pytest.raises(ValueError, match="fallback_probability"):
        choose_k(-2.0, 1.0, "paper", None)
