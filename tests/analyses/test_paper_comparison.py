"""The comparison with the paper (pipeline/analyses/paper_comparison.py): the contact probabilities of k in words,
checked against the Gaussian tail (the paper's 32.8 % two-sided is k = 0.978, its one-sided 16.4 %; a negative k
puts most summits above the threshold), and an ``identify.nc`` of the older layout refused in one line that
names the old variable and what to run."""

from __future__ import annotations

import math
import re

import pytest
import xarray as xr

from pipeline.analyses.paper_comparison import check_identify_layout, probability_text


def _q(k: float) -> float:
    """The standard normal tail Q(k) = P(z > k) [1]."""
    return 0.5 * math.erfc(k / math.sqrt(2.0))


def test_the_papers_k_is_32_8_percent_two_sided():
    text = probability_text(0.978)
    assert text == "k = 0.978: P(|z| > k sigma) = 32.8 % (two-sided), one-sided 16.4 %"
    two, one = (float(v) for v in re.findall(r"([\d.]+) %", text))
    assert two == pytest.approx(100 * 2 * _q(0.978), abs=0.05) and one == pytest.approx(100 * _q(0.978), abs=0.05)


def test_a_negative_k_says_why_most_summits_are_above_it():
    text = probability_text(-0.5)
    assert text.startswith("k = -0.5: two-sided 2 Q(|k|) = 61.7 % (the paper's convention, which sees only |k|)")
    assert "0.5 sigma below the mean summit height, so 69.1 % of the summits lie above it" in text
    assert 100 * 2 * _q(0.5) == pytest.approx(61.7, abs=0.05) and 100 * _q(-0.5) == pytest.approx(69.1, abs=0.05)


def test_an_identify_dataset_of_the_older_layout_is_refused_in_one_line():
    old = xr.Dataset({"dmw__rms_nm_best": ((), 0.2), "value_fhm_flying": ("evaluation", [1.0, 2.0])})
    with pytest.raises(ValueError) as info:
        check_identify_layout(old, "out/identify.nc")
    line = str(info.value)
    assert line.startswith("out/identify.nc: written by an older hdi identify (a variable per parameter and target, "
                           "e.g. dmw__rms_nm_best)") and line.endswith("run `hdi identify` again (it reads its "
                                                                      "evaluations back from identify.evals.jsonl)")
    new = xr.Dataset({"best": ("parameter", [0.2]), "value": (("evaluation", "target"), [[1.0]])},
                     coords={"target_units": ("target", ["%"])})
    check_identify_layout(new)


def test_the_touchdown_note_repeats_the_calibration_s_warning_and_names_a_touchdown_of_the_scene(tmp_path):
    """The report says which touchdown k was fitted to when it is not simply the paper's on the paper's drive:
    the calibration's warning (the paper's touchdown on another drive), or the scene's own touchdown."""
    import report_data
    from pipeline.analyses.paper_comparison import _touchdown_section
    from pipeline.analyses.sweep_slices import SweepSlice
    report_data.write_sweep(tmp_path)
    report_data.write_calibration(tmp_path)
    sweep = xr.open_dataset(tmp_path / "sweep.nc").load()
    cal = xr.open_dataset(tmp_path / "calibration.nc").load()
    c = SweepSlice.of(sweep.isel(roughness=0, damping=0), sweep)
    plain = _touchdown_section(c, sweep, cal)[1][0]  # (a calibration.nc without the attributes: as before)
    assert "Warning" not in plain and "k was fitted to" not in plain
    warning = "k is fitted to the paper's touchdown (9.8 nm, none at 9.6 nm) while the disk (dmw.source = 'a.csv') differs"
    flagged = _touchdown_section(c, sweep, cal.assign_attrs(touchdown_warning=warning, touchdown_source="paper"))
    assert f"Warning: {warning}." in flagged[1][0]
    fitted = "contact at touchdown.onset_nm = 3 nm, none at touchdown.previous_nm = 2.5 nm: this scene's own touchdown"
    own = _touchdown_section(c, sweep, cal.assign_attrs(touchdown_fitted=fitted, touchdown_warning="none",
                                                        touchdown_source="scene"))
    assert f"k was fitted to {fitted}." in own[1][0] and "Warning" not in own[1][0]
