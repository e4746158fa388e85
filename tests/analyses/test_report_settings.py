"""The scene keys the report reads (pipeline/analyses/report_settings.py): taken from a scene they are the scene's
values; without a scene, a section or a key they are the documented defaults (the paper's touchdown at 9.8 nm
after the 9.6 nm step); the report judges targets over realisations only when the scene can make them."""

from __future__ import annotations

import math

import pytest

from pipeline.analyses.report_settings import ReportSettings, wants_ensemble
from pipeline.physics import paper


def test_the_settings_of_the_paper_scene_are_its_values(paper_scene):
    s = ReportSettings.from_scene(paper_scene)
    assert s.damping_ratio == paper_scene["air_bearing"]["damping_ratio"]
    assert s.transient_ms == paper_scene["solver"]["transient_ms"]
    assert s.onset_nm == paper_scene["touchdown"]["onset_nm"] == paper.TOUCHDOWN_NM
    assert s.histories_nm == list(paper_scene["report"]["histories_nm"])
    assert s.dmw_rms_nm == paper_scene["dmw"]["rms_nm"] and s.dmw_source == "synthetic"
    assert s.bulge == paper_scene["air_bearing"]["bulge"]


def test_without_a_scene_or_a_key_the_defaults_hold():
    s = ReportSettings.from_scene(None)
    assert s == ReportSettings()
    assert (s.onset_nm, s.previous_nm) == (paper.TOUCHDOWN_NM, paper.PREVIOUS_STEP_NM) == (9.8, 9.6)
    assert math.isnan(s.dmw_rms_nm) and s.histories_nm == [] and s.bulge == "none" and s.lift_cap_nm is None
    # a partial scene (a plain dict): the keys it has, the defaults for the rest; None counts as absent
    part = ReportSettings.from_scene({"touchdown": {"onset_nm": 10.2, "previous_nm": None}, "dmw": {}})
    assert part.onset_nm == 10.2 and part.previous_nm == paper.PREVIOUS_STEP_NM and math.isnan(part.dmw_rms_nm)
    with pytest.raises(AttributeError):   # frozen: the report cannot change what it read
        part.onset_nm = 1.0


@pytest.mark.parametrize("realisations, effects, source, wanted", [
    (8, ["air_bearing", "dmw"], "synthetic", True),
    (1, ["air_bearing", "dmw"], "synthetic", False),      # one realisation makes no ensemble
    (8, ["air_bearing"], "synthetic", False),              # no DMW: every realisation is the same run
    (8, ["air_bearing", "dmw"], "disk.csv", False)])      # a measured record has one realisation
def test_the_report_wants_an_ensemble_only_when_the_scene_can_make_one(realisations, effects, source, wanted):
    scene = {"report": {"realisations": realisations}, "scene": {"effects": effects}, "dmw": {"source": source}}
    assert wants_ensemble(scene) is wanted
