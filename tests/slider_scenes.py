"""Scenes built in code for the kernel tests: ``make_scene`` (effects and section overrides on the paper
slider), a synthetic DMW record and the model at a given k; shared by the dynamics, start, statics,
stepping, rear-law and fault tests."""

from __future__ import annotations

from pipeline.model import assembly
from pipeline.physics import microwaviness as pdmw
from pipeline.config.scene import scene_from_dict
from pipeline.model.interface_tables import build_tables, roughness_statistics


NM = 1e-9
K = 0.445  # contact criterion constant used throughout (the brief's paper value)
FLYING = ["air_bearing", "pitch"]
ALL = ["air_bearing", "pitch", "dmw", "adhesion", "contact", "friction"]
# An explicit synthetic DMW (docs/model.md, section "DMW"): band 10-500 kHz, PSD ~ f^-2, 4 MS/s, fixed seed.
DMW = {"band_khz": [10.0, 500.0], "exponent": -2.0, "seed": 20090601, "sample_rate_mhz": 4.0,
       "rpm": 5425.0, "radius_mm": 34.3}


def make_scene(effects, air_bearing=None, solver=None, dmw=None, contact=None, **sections):
    raw = {"scene": {"effects": list(effects)},
           "air_bearing": {"flying_height_nm": 11.0, "frequencies_khz": [120.0, 300.0],
                           "rear_exponent": 2.0, **(air_bearing or {})},
           "solver": {"duration_ms": 1.0, "transient_ms": 0.3, **(solver or {})},
           "dmw": {**DMW, "rms_nm": 0.5, **(dmw or {})},
           "contact": {"k": K, "damping_n_s_m": 0.0, **(contact or {})}}
    raw.update(sections)
    return scene_from_dict(raw)


def synthetic_record(scene, duration_s=1.2e-3):
    """The scene's synthetic DMW record (displacement [nm], sample rate [Hz])."""
    d = scene["dmw"]
    fs = d["sample_rate_mhz"] * 1e6
    w = pdmw.synthesize(d["rms_nm"], tuple(b * 1e3 for b in d["band_khz"]), d["exponent"], duration_s, fs,
                        d["seed"])
    return w, fs


def build(scene, record=None, k=K):
    """Model of a scene: interface tables in memory when needed, the scene's DMW when enabled."""
    interface = build_tables(scene, roughness_statistics(scene)) if scene.effects & {"contact", "adhesion"} else None
    if "dmw" in scene.effects and record is None:
        record = synthetic_record(scene)
    return assembly.build_model(scene, interface, record if "dmw" in scene.effects else None,
                          k if "contact" in scene.effects else None)
