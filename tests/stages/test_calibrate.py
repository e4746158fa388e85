"""The calibration stage: the exact method (one flying run per protrusion) against bisection on k."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.io import read_dataset
from pipeline.config.scene import load_scene
from pipeline.analyses import calibration
from pipeline.runner import ensure

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"
SHORT = ["solver.duration_ms=1.0", "solver.transient_ms=0.3", "touchdown.curve_points=5"]
# without adhesion there is no snap-in: a k exists that puts contact at 9.8 nm and not at 9.6 nm
NO_ADHESION = SHORT + ['scene.effects=["air_bearing","pitch","dmw","contact","friction"]',
                       "sweep.protrusion_nm={start=9.0, stop=10.4, step=0.2}"]
# the paper scene (with adhesion) touches at 7.6 nm for every k of the range
WITH_ADHESION = SHORT + ["sweep.protrusion_nm={start=7.0, stop=8.0, step=0.2}"]


def _both(overrides: list[str], tmp_path: Path):
    out = {}
    for method in ("exact", "bisection"):
        scene = load_scene(PAPER, overrides + [f'touchdown.method="{method}"'])
        ensure("calibrate", scene, tmp_path / method, force=True, scheduler="synchronous")
        out[method] = read_dataset(tmp_path / method / "calibration.nc")
    return out["exact"], out["bisection"]


@pytest.mark.slow
def test_exact_agrees_with_bisection_without_adhesion(tmp_path):
    exact, bis = _both(NO_ADHESION, tmp_path)
    tol = float(bis.attrs["k_tolerance"])
    for name in ("k_onset", "k_previous", "k_low", "k_high", "k_calibrated"):
        # bisection returns the upper end of its last bracket: k* <= k_bis < k* + tol
        diff = float(bis[name]) - float(exact[name])
        assert -1e-9 <= diff <= tol, (name, float(exact[name]), float(bis[name]))
    assert np.isfinite(float(exact.k_calibrated))
    # the curve: the same first touching protrusion wherever k is not within tol of a threshold
    kstar = exact.k_threshold.values
    near = np.array([np.any(np.abs(kstar - k) <= tol) for k in exact.k.values])
    a, b = exact.touchdown.values[~near], bis.touchdown.values[~near]
    assert np.array_equal(np.isnan(a), np.isnan(b)) and np.allclose(a[~np.isnan(a)], b[~np.isnan(b)])
    # k*(protrusion) is the flying run's minimum separation over sigma, except where the transient dips
    # below the steady window (here 10.4 nm, by 2.8e-4 nm): there bisection with real runs resolves k*
    # (a contact in the transient changes the trajectory after it: k* moved by 5e-4 here)
    flying = exact.min_separation.values / float(exact.sigma)
    assert np.allclose(kstar[:-1], flying[:-1]) and 1e-6 < abs(kstar[-1] - flying[-1]) < 0.01
    # two flying runs per protrusion, and bisection only at 10.4 nm
    assert exact.attrs["simulations"] > 2 * exact.protrusion.size


@pytest.mark.slow
def test_exact_agrees_with_bisection_on_the_snapping_paper_scene(tmp_path):
    exact, bis = _both(WITH_ADHESION, tmp_path)
    assert np.isnan(float(exact.k_calibrated)) and np.isnan(float(bis.k_calibrated))
    assert np.array_equal(exact.touchdown.values, bis.touchdown.values)
    assert np.all(exact.touchdown.values == pytest.approx(7.6))
    kstar = exact.k_threshold.sel(protrusion=[7.6, 7.8, 8.0]).values
    # adhesion pulls the flying slider (contact law off) 1.3 nm below the mean of summit heights or
    # further: contact for every k of the range
    assert np.all(kstar < -3.0), kstar
    assert float(exact.k_threshold.sel(protrusion=7.4)) > 3.0  # flying clear of every k in range
    assert "every k" in exact.attrs["outcome"]


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
