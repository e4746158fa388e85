"""Whether a scene takes its contact criterion k from a calibration: the one home of the rule, read by the
stages that make their upstream of it (simulate, sweep, statics, report, accuracy: through
:func:`pipeline.model.scene_inputs.input_stages` or directly) without importing the model itself.
"""

from __future__ import annotations

from typing import Any


def needs_calibration(scene: Any) -> bool:
    """Whether a simulation of the scene takes k from the calibration (``hdi calibrate``): the contact effect
    is on and the scene fixes no ``contact.k`` (:func:`pipeline.model.scene_inputs.contact_k`)."""
    return scene.has("contact") and scene["contact"]["k"] is None
