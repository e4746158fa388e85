"""Shared builder of the model-variant tests (tests/model/test_outcomes.py, tests/scenarios/test_model_variants.py):
a slider scene built in code with explicit values for what those tests depend on, and its synthetic DMW record."""

from __future__ import annotations

import numpy as np

from pipeline.config.scene import scene_from_dict
from pipeline.physics import microwaviness as pdmw

#: The paper's DMW settings, written out (rms [nm], band [kHz], sample rate [MHz], disk rpm and radius [mm])
DMW = {"band_khz": [10.0, 500.0], "exponent": -2.0, "seed": 20090601, "sample_rate_mhz": 4.0,
       "rpm": 5425.0, "radius_mm": 34.3, "rms_nm": 0.5}


def make_scene(effects, **air_bearing):
    """A scene with ``effects``, an 11-nm flying height, 120/300 kHz modes and a 1-ms run."""
    return scene_from_dict({
        "scene": {"effects": list(effects)},
        "air_bearing": {"flying_height_nm": 11.0, "frequencies_khz": [120.0, 300.0], "rear_exponent": 2.0,
                        "damping_ratio": 0.05, **air_bearing},
        "solver": {"duration_ms": 1.0, "transient_ms": 0.3},
        "dmw": DMW,
    })


def record(scene, duration_s: float = 1.2e-3) -> tuple[np.ndarray, float]:
    """The scene's synthetic DMW record [m] of ``duration_s`` [s] and its sample rate [Hz]."""
    d = scene["dmw"]
    fs = d["sample_rate_mhz"] * 1e6
    return pdmw.synthesize(d["rms_nm"], tuple(b * 1e3 for b in d["band_khz"]), d["exponent"], duration_s, fs,
                           d["seed"]), fs
