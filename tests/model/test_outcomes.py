"""The outcomes of a run (pipeline.model.outcomes): ``touched``, the regime and calibration rule, reads the
exact minimum separation of the run against the contact criterion ``k sigma``, not the output samples."""

from __future__ import annotations

from dataclasses import replace

from pipeline.model import assembly, outcomes, running
from pipeline.physics import microwaviness as pdmw
from pipeline.config.scene import scene_from_dict


NM = 1e-9
DMW = {"band_khz": [10.0, 500.0], "exponent": -2.0, "seed": 20090601, "sample_rate_mhz": 4.0,
       "rpm": 5425.0, "radius_mm": 34.3, "rms_nm": 0.5}


def make_scene(effects, **air_bearing):
    return scene_from_dict({
        "scene": {"effects": list(effects)},
        "air_bearing": {"flying_height_nm": 11.0, "frequencies_khz": [120.0, 300.0], "rear_exponent": 2.0,
                        "damping_ratio": 0.05, **air_bearing},
        "solver": {"duration_ms": 1.0, "transient_ms": 0.3},
        "dmw": DMW,
    })


def record(scene, duration_s=1.2e-3):
    d = scene["dmw"]
    fs = d["sample_rate_mhz"] * 1e6
    return pdmw.synthesize(d["rms_nm"], tuple(b * 1e3 for b in d["band_khz"]), d["exponent"], duration_s, fs,
                           d["seed"]), fs


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
