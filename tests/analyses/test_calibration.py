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


IDENTIFIED = PAPER.parent / "paper-2009-identified.toml"


def test_the_touchdown_k_is_fitted_to_is_named_and_flagged_when_the_drive_is_not_the_paper_s(tmp_path):
    """The paper's touchdown (the keys' defaults) on the paper's drive: named, no warning; on a drive whose
    disk, roughness or slider differ: a warning naming those keys and the touchdown keys to set; a touchdown of
    the scene's own: named as such, no warning."""
    (tmp_path / "dmw.csv").write_text("time_s,displacement_nm\n0,0\n")
    fitted, warning = calibration.touchdown_provenance(load_scene(IDENTIFIED))
    assert "touchdown.onset_nm = 9.8 nm" in fitted and "the paper's measured touchdown" in fitted and warning == ""
    own = load_scene(IDENTIFIED, [f'dmw.source="{tmp_path / "dmw.csv"}"', "roughness.sigma_nm=0.6"])
    assert calibration.differing_from_paper(own) == {"disk": [f"dmw.source = '{tmp_path / 'dmw.csv'}'"],
                                                     "roughness": ["roughness.sigma_nm = 0.6"]}
    _, warning = calibration.touchdown_provenance(own)
    assert warning.startswith("k is fitted to the paper's touchdown (9.8 nm, none at 9.6 nm) while the disk "
                              "(dmw.source = ") and "the roughness (roughness.sigma_nm = 0.6) differ" in warning
    assert "set touchdown.onset_nm and touchdown.previous_nm" in warning
    slider = load_scene(IDENTIFIED, ["air_bearing.frequencies_khz=[100.0, 280.0]"])
    assert "the slider (air_bearing.frequencies_khz = [100.0, 280.0]) differs" in calibration.touchdown_provenance(slider)[1]
    mine = load_scene(IDENTIFIED, [f'dmw.source="{tmp_path / "dmw.csv"}"', "touchdown.onset_nm=10.4",
                                   "touchdown.previous_nm=10.2"])
    fitted, warning = calibration.touchdown_provenance(mine)
    assert "touchdown.onset_nm = 10.4 nm, none at touchdown.previous_nm = 10.2 nm: this scene's own" in fitted
    assert warning == ""
    for name in ("paper-2009", "paper-2009-bulge", "paper-2009-reynolds", "paper-2009-two-population",
                 "paper-2009-two-population-identified", "sweep-3x3"):  # (the shipped scenes: the paper's drive)
        assert calibration.differing_from_paper(load_scene(PAPER.parent / f"{name}.toml")) == {}, name


def test_a_calibrated_k_below_the_physical_bound_is_refused_in_one_line(tmp_path):
    """k below 0 (one-sided contact probability above 0.5) is refused naming the touchdown and the keys to set;
    the k of `make run` (the identified scene's, 1.0728 in (-0.8424, 2.9879], one-sided 0.142) is not."""
    (tmp_path / "dmw.csv").write_text("time_s,displacement_nm\n0,0\n")
    own = load_scene(IDENTIFIED, [f'dmw.source="{tmp_path / "dmw.csv"}"'])
    with pytest.raises(calibration.CalibrationError) as err:
        calibration.check_physical(-0.86, (-0.894, -0.826), own)
    text = str(err.value)
    assert "\n" not in text and text.startswith("calibrate: the calibrated k = -0.8600 is below 0: its one-sided "
                                                "contact probability P(z > k sigma) = 0.805 is above 0.5")
    assert "the paper's measured touchdown on another drive (dmw.source = " in text
    assert "set touchdown.onset_nm and touchdown.previous_nm" in text and text.endswith("fix contact.k (k >= 0)")
    with pytest.raises(calibration.CalibrationError, match=r"fix contact\.k \(\[0\.0000, 0\.1668\] is the physical "
                                                           r"part of the admissible interval\)$"):
        calibration.check_physical(-0.0256, (-0.2179, 0.1668), load_scene(IDENTIFIED))
    calibration.check_physical(1.0728, (-0.8424, 2.9879), load_scene(IDENTIFIED))
    calibration.check_physical(0.0, (-0.1, 0.1), own)  # (the bound itself is physical: one-sided 0.5)


@pytest.mark.slow
def test_the_user_s_record_with_the_paper_s_touchdown_is_refused_before_calibration_nc(tmp_path):
    """The case of a user's own record: a synthetic record of rms 0.42 nm (the identified scene's is 0.18 nm)
    written as CSV; calibrating the identified scene on it to the paper's touchdown gave k = -0.87 (one-sided
    probability 0.81) silently. Now refused, after the warning, before calibration.nc is written."""
    from pipeline.physics.microwaviness import synthesize
    from pipeline.runner import ensure
    fs = 4e6
    w = synthesize(0.40, (1e4, 5e5), -2.0, 2.1e-3, fs, 12345)
    rec = tmp_path / "dmw.csv"
    np.savetxt(rec, np.c_[np.arange(w.size) / fs, w], delimiter=",", header="time_s,displacement_nm", comments="")
    scene = load_scene(IDENTIFIED, [f'dmw.source="{rec}"', "solver.duration_ms=1.0", "solver.transient_ms=0.3",
                                    "sweep.protrusion_nm={start=9.6, stop=9.8, step=0.2}", "touchdown.curve_points=3"])
    with pytest.raises(calibration.CalibrationError, match=r"calibrated k = -0\.\d+ is below 0.*on another drive "
                                                           r"\(dmw\.source = "):
        ensure("calibrate", scene, tmp_path / "out", scheduler="synchronous")
    assert not (tmp_path / "out" / "calibration.nc").exists() and (tmp_path / "out" / "dmw.nc").is_file()
