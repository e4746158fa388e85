"""The DMW record of a scene in memory (pipeline.model.dmw_record): the disk speed of the ``[dmw]``
settings, ``2 pi r rpm / 60`` [m/s], and the default record long enough for the dynamics' duration."""

from __future__ import annotations

import math

import pytest

from pipeline.config.scene import scene_from_dict
from pipeline.model import dmw_record
from pipeline.runner import ensure


def test_disk_speed_formula():
    s = dmw_record.settings(scene_from_dict({"dmw": {"rpm": 7200.0, "radius_mm": 20.0}}))
    assert s["disk_speed_m_s"] == pytest.approx(2 * math.pi * 0.02 * 7200 / 60)


def test_default_record_is_long_enough_for_the_dynamics(tmp_path):
    from pipeline.model import assembly
    scene = scene_from_dict({"scene": {"effects": ["air_bearing", "pitch", "dmw"]}})
    _, w, fs = dmw_record.load(ensure("dmw", scene, tmp_path))
    model = assembly.build_model(scene, None, (w, fs), None)   # raises if the record is too short
    from pipeline.config.si import to_si
    duration, lead = to_si(scene).solver.duration, dmw_record.front_pad_lead_s(scene)
    # the record holds the rule's samples: the duration, the front pad's lead (l_f + l_c) / V, and the end samples
    assert w.size >= dmw_record.needed_samples(duration, lead, fs)
    assert model.p.off_f == lead and model.p.dmw_dt == 1.0 / fs               # (the same arms over the same speed)
    # its pieces (one per sample interval, three columns of 4 coefficients: TFC, front and rear pad) cover the run
    assert model.dmw.shape[1] == 12 and (model.dmw.shape[0] - 1) / fs >= duration
