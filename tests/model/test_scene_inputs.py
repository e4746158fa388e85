"""What one simulation of a scene reads (pipeline.model.scene_inputs): the inputs named by the stages that
make them, and the contact criterion k in its order of precedence (an option, ``contact.k``, the
calibration, the fallback probability), the fallback being the k whose two-sided contact probability
P(|z| > k sigma) = erfc(k / sqrt 2) is the given one (docs/model.md, section "Contact criterion": 32.8 % at
k = 0.978)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from pipeline.config.scene import scene_from_dict
from pipeline.model import scene_inputs as si

AFM = "tests/data/afm/di-3.di"


def _calibration(k: float, outcome: str = "") -> xr.Dataset:
    return xr.Dataset({"k_calibrated": k}, attrs={"outcome": outcome})


@pytest.mark.parametrize("raw, calibration, inputs", [
    ({}, True, ("dmw", "interface", "calibrate")),                            # the paper scene
    ({}, False, ("dmw", "interface")),                                        # a parameter study
    ({"contact": {"k": 0.978}}, True, ("dmw", "interface")),                  # k fixed: no calibration
    ({"air_bearing": {"bulge": "reynolds"}}, True, ("dmw", "interface", "bulge", "calibrate")),
    ({"scene": {"effects": ["air_bearing", "pitch"]}}, True, ()),
    ({"scene": {"effects": ["air_bearing", "pitch", "dmw"]}, "roughness": {"afm": [AFM]}}, True,
     ("dmw", "interface")),                                                   # AFM scans: y_s from the tables
])
def test_input_stages_are_the_stages_a_simulation_reads(raw, calibration, inputs, repo_root, monkeypatch):
    monkeypatch.chdir(repo_root)
    assert si.input_stages(scene_from_dict(raw), calibration=calibration) == inputs


def test_contact_k_precedence():
    fixed = scene_from_dict({"contact": {"k": 1.5, "fallback_probability": 0.1}})
    assert si.contact_k(fixed, _calibration(1.1), override=2.0) == (2.0, "option k")
    assert si.contact_k(fixed, _calibration(1.1)) == (1.5, "scene (contact.k)")
    free = scene_from_dict({"contact": {"fallback_probability": 0.328}})
    assert si.contact_k(free, _calibration(1.1), calibration_name="c.nc") == (1.1, "calibration (c.nc)")
    assert si.contact_k(scene_from_dict({"scene": {"effects": ["air_bearing"]}})) == (None, "no contact effect")


def test_fallback_is_the_two_sided_probability():
    free = scene_from_dict({"contact": {"fallback_probability": 0.328}})
    k, source = si.contact_k(free)
    # tol: erfc of the inverse it was made by: condition < 2, a few ulps of each
    assert math.erfc(k / math.sqrt(2)) == pytest.approx(0.328, rel=1e-9)
    assert k == pytest.approx(0.978, abs=5e-4) and source == "contact.fallback_probability (two-sided)"
    k_nan, source = si.contact_k(free, _calibration(np.nan))
    assert k_nan == k and "fallback: no admissible k in calibration.nc" in source and "one-sided 0.164" in source


def test_no_k_is_an_error_saying_what_to_set():
    paper = scene_from_dict({})
    with pytest.raises(ValueError, match=r"^no contact criterion k: set contact\.k or contact\.fallback_probability"):
        si.contact_k(paper)
    with pytest.raises(ValueError, match=r"^cal\.nc: the calibration found no admissible k \(no crossing\); set "
                                         r"contact\.k or contact\.fallback_probability$"):
        si.contact_k(paper, _calibration(np.nan, "no crossing"), calibration_name="cal.nc")
