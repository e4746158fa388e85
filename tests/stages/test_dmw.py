"""Stage ``dmw`` (pipeline/stages/dmw.py) on the paper scene, checked against its documented layout and numbers:
the 2.1 ms record at 4 MHz (8400 samples at 250 ns), zero mean and exactly the scene's rms (a synthetic record
is rescaled to ``dmw.rms_nm``), its one-sided periodogram summing to the mean square (Parseval) with no power
outside the band, the disk speed ``2 pi r rpm / 60`` = 19.49 m/s; the same seed gives the same record bit for
bit, another seed another record of the same rms; with the effect off the record is zero and no random number
is drawn."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipeline.config.scene import load_scene
from pipeline.io import read_dataset
from pipeline.runner import ensure


def _dmw(scene, out):
    ensure("dmw", scene, out)
    return read_dataset(out / "dmw.nc", stage="dmw")


@pytest.fixture(scope="module")
def paper_dmw(tmp_path_factory, paper_config):
    scene = load_scene(paper_config)
    return scene, _dmw(scene, tmp_path_factory.mktemp("dmw"))


def test_the_record_has_the_documented_length_and_sampling(paper_dmw):
    scene, ds = paper_dmw
    assert ds.sizes["time"] == 8400 and float(ds["sample_rate"]) == 4e6
    np.testing.assert_allclose(np.diff(ds["time"].values), 250e-9, rtol=1e-9)
    assert ds.attrs["duration_s"] == pytest.approx(2.1e-3) and ds["time"].values[-1] == pytest.approx(2.1e-3 - 250e-9)
    assert ds["displacement"].attrs["units"] == "nm" and ds["psd"].attrs["units"] == "nm2 Hz-1"


def test_a_synthetic_record_has_zero_mean_and_the_scenes_rms(paper_dmw):
    scene, ds = paper_dmw
    w = ds["displacement"].values
    rms = scene["dmw"]["rms_nm"]
    assert abs(w.mean()) < 1e-12 * rms
    assert math.sqrt(np.mean(w * w)) == pytest.approx(rms, rel=1e-12) and float(ds["rms"]) == pytest.approx(rms, rel=1e-12)
    assert ds.attrs["dmw_source"] == "synthetic" and ds.attrs["dmw_enabled"] == 1
    assert ds.attrs["seed"] == scene["dmw"]["seed"]


def test_the_periodogram_holds_the_mean_square_inside_the_band(paper_dmw):
    scene, ds = paper_dmw
    f, p = ds["frequency"].values, ds["psd"].values
    df = f[1] - f[0]
    assert df == pytest.approx(1 / 2.1e-3) and f[-1] == pytest.approx(2e6)        # k / duration, to Nyquist
    w = ds["displacement"].values
    assert p.sum() * df == pytest.approx(np.mean(w * w), rel=1e-9)               # Parseval
    lo, hi = (1e3 * b for b in scene["dmw"]["band_khz"])
    assert (float(ds["band_low"]), float(ds["band_high"])) == (lo, hi) == (1e4, 5e5)
    inside = (f >= ds["band_low"].attrs["realised"]) & (f <= ds["band_high"].attrs["realised"])
    assert p[~inside].sum() < 1e-20 * p[inside].sum()
    assert lo <= ds["band_low"].attrs["realised"] <= ds["band_high"].attrs["realised"] <= hi


def test_the_disk_speed_is_two_pi_r_rpm_over_60(paper_dmw):
    scene, ds = paper_dmw
    r, rpm = scene["dmw"]["radius_mm"] * 1e-3, scene["dmw"]["rpm"]
    assert (r, rpm) == (34.3e-3, 5425.0)
    assert float(ds["disk_speed"]) == pytest.approx(2 * math.pi * r * rpm / 60, rel=1e-12)
    assert round(float(ds["disk_speed"]), 2) == 19.49


def test_the_seed_decides_the_record(paper_dmw, tmp_path):
    scene, ds = paper_dmw
    again = _dmw(scene, tmp_path / "again")
    np.testing.assert_array_equal(again["displacement"].values, ds["displacement"].values)
    other = _dmw(scene.replace(dmw={"seed": scene["dmw"]["seed"] + 1}), tmp_path / "other")
    assert not np.allclose(other["displacement"].values, ds["displacement"].values)
    assert float(other["rms"]) == pytest.approx(float(ds["rms"]), rel=1e-12)


def test_with_the_effect_off_the_record_is_zero(paper_dmw, tmp_path):
    scene, _ = paper_dmw
    off = _dmw(scene.replace(scene={"effects": ["air_bearing", "pitch"]}), tmp_path)
    assert off.sizes["time"] == 8400 and not off["displacement"].values.any() and float(off["rms"]) == 0.0
    assert off.attrs["dmw_enabled"] == 0 and off.attrs["dmw_source"] == "none" and "seed" not in off.attrs
    assert "disabled" in off.attrs
