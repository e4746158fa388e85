"""The needs-calibration rule (pipeline/model/contact_rule.py): a simulation takes k from the calibration
exactly when the contact effect is on and the scene fixes no contact.k."""

from __future__ import annotations

from pipeline.model import scene_inputs
from pipeline.model.contact_rule import needs_calibration


def test_the_contact_effect_without_k_needs_the_calibration(paper_scene):
    assert paper_scene.has("contact") and paper_scene["contact"]["k"] is None
    assert needs_calibration(paper_scene)
    assert "calibrate" in scene_inputs.input_stages(paper_scene)
    fixed = paper_scene.replace(contact={"k": 0.9})
    assert not needs_calibration(fixed) and "calibrate" not in scene_inputs.input_stages(fixed)
    flying = paper_scene.replace(scene={"effects": ["air_bearing", "pitch", "dmw"]})
    assert not needs_calibration(flying) and "calibrate" not in scene_inputs.input_stages(flying)
