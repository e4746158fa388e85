"""Stage ``simulate`` (pipeline/stages/simulate.py): one protrusion in time, ``histories.nc`` and ``summary.nc``.

Checked with numbers: without DMW, contact or adhesion the slider rests where it starts, at the air bearing's
equilibrium, whose TFC-point clearance is the flying height less the protrusion and the summit offset
(11 - 5 - 0.6909 nm), constant to 1e-9 nm over the whole run, with FHM 0; the same clearance as the stage
``statics`` finds for that protrusion; with the DMW the summary's FHM is the peak-to-peak separation over the
steady window (from the exact extremes: at least the sampled spread, and within 2 % of it) over FH0."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.config.scene import load_scene
from pipeline.io import read_dataset
from pipeline.runner import ensure

#: A 1 ms run at 5 nm, air bearing and pitch only (no contact law: no calibration needed).
AIR = ['scene.effects=["air_bearing","pitch"]', "solver.duration_ms=1.0", "solver.transient_ms=0.3",
       "tfc.protrusion_nm=5.0", "sweep.protrusion_nm={start=4.0, stop=6.0, step=1.0}"]
WITH_DMW = AIR[1:] + ['scene.effects=["air_bearing","pitch","dmw"]']


def _run(paper_config, sets, out, stage="simulate"):
    scene = load_scene(paper_config, sets)
    ensure(stage, scene, out)
    return scene


@pytest.fixture(scope="module")
def air(tmp_path_factory, paper_config):
    out = tmp_path_factory.mktemp("air")
    scene = _run(paper_config, AIR, out)
    return scene, out, read_dataset(out / "histories.nc"), read_dataset(out / "summary.nc")


def test_the_stage_writes_the_histories_and_the_summary_at_the_scenes_protrusion(air):
    scene, out, hist, summ = air
    assert sorted(p.name for p in out.glob("*.nc")) == ["histories.nc", "summary.nc"]   # (no DMW: no dmw.nc)
    assert list(hist["protrusion"].values) == list(summ["protrusion"].values) == [5.0]
    assert hist.sizes["elapsed_time"] == 4001                                   # 1 ms at 250 ns, both ends
    assert hist["elapsed_time"].values[-1] == pytest.approx(1e-3)
    assert (float(summ["steady_window_start"]), float(summ["steady_window_end"])) == (0.3, 1.0)
    assert str(summ["k_source"].values) == "no contact effect" and np.isnan(float(summ["k"]))
    for name in summ.data_vars:
        assert "units" in summ[name].attrs or summ[name].dtype.kind in "OUS", name


def test_flying_without_excitation_rests_at_the_bearings_equilibrium(air):
    scene, _, hist, summ = air
    offset = float(summ["summit_offset"])
    assert offset == pytest.approx(0.6909, abs=1e-4)
    expected = scene["air_bearing"]["flying_height_nm"] - 5.0 - offset
    c = hist["clearance"].values[0]
    assert np.abs(c - expected).max() < 1e-9
    assert float(summ["clearance"][0]) == pytest.approx(expected, abs=1e-9)
    assert float(summ["min_clearance"][0]) == pytest.approx(expected, abs=1e-9)
    assert float(summ["fhm_bv"][0]) == 0.0 and int(hist["rejected_steps"][0]) == 0
    assert not hist["z"].values.any() and not hist["pitch"].values.any()


def test_the_rest_state_is_the_one_statics_finds(air):
    scene, out, _, summ = air
    ensure("statics", scene, out)
    st = read_dataset(out / "statics.nc").sel(protrusion=5.0)
    assert int(st["stable_count"]) == 1
    assert float(st["clearance"].isel(state=0)) == pytest.approx(float(summ["clearance"][0]), abs=1e-6)


def test_with_the_dmw_the_fhm_is_the_peak_to_peak_separation_over_fh0(tmp_path, paper_config):
    scene = _run(paper_config, WITH_DMW, tmp_path)
    hist, summ = read_dataset(tmp_path / "histories.nc"), read_dataset(tmp_path / "summary.nc")
    t = hist["elapsed_time"].values
    window = (t >= 0.3e-3 - 1e-12) & (t <= 1e-3 + 1e-12)
    d = hist["separation"].values[0][window]
    sampled = 100.0 * np.ptp(d) / scene["air_bearing"]["flying_height_nm"]
    fhm = float(summ["fhm_bv"][0])
    assert sampled > 0.1                                   # the DMW moves the slider
    assert sampled <= fhm + 1e-9 and fhm <= 1.02 * sampled
    assert hist["disk_displacement"].values.any()
