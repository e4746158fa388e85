"""The outcomes of a run (pipeline.model.outcomes): ``touched``, the regime and calibration rule, reads the
exact minimum separation of the run against the contact criterion ``k sigma``, not the output samples."""

from __future__ import annotations

from dataclasses import replace

from pipeline.model import assembly, outcomes, running
from pipeline.units import NM
from variant_scenes import make_scene, record


def test_touched_is_the_regime_and_calibration_rule():
    # A flying run does not touch; the same run with k sigma above its exact minimum separation does,
    # although no output sample is in contact (there is no contact effect): the rule reads the exact minimum.
    scene = make_scene(["air_bearing", "pitch", "dmw"])
    model = assembly.build_model(scene, None, record(scene), None)
    run = running.run_model(model, 5 * NM)
    lo = run.d_extremes[0]
    assert not outcomes.touched(run) and not run.contact.any()
    above = replace(run, model=replace(model, k=1.0, sigma=lo + 1e-3 * NM))
    assert above.model.k_sigma > lo and outcomes.touched(above)
