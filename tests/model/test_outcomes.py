"""The outcomes of a run (pipeline.model.outcomes): ``touched``, the regime and calibration rule, reads the
exact minimum separation of the run against the contact criterion ``k sigma``, not the output samples."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import slider_scenes
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


#: Scenes of :func:`test_the_steady_window_alone_gives_the_summary_bit_for_bit`: every series summarize reads
#: (the meniscus state, two adhesion tables, the continuous lubricant shear, contact damping, the integrated area).
VARIANTS = {
    "all effects": {},
    "meniscus, two populations": {"lubricant": {"meniscus_time_us": 20.0, "bridge_work_of_adhesion_j_m2": 0.005},
                                  "interface": {"adhesion": "two-population"}},
    "continuous friction, damped, integrated": {
        "lubricant": {"shear_stress_mpa": 2.0},
        "contact": {"friction_switching": "continuous", "damping_n_s_m": 0.02, "area_model": "integrated"}},
}


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_the_steady_window_alone_gives_the_summary_bit_for_bit(variant):
    """``summarize(run)`` computes the histories of the steady window's samples only (the parameter studies'
    path); every scalar is the one of the full histories, bit for bit, flying, bouncing and in steady contact."""
    extra = dict(VARIANTS[variant])
    scene = slider_scenes.make_scene(slider_scenes.ALL, contact=extra.pop("contact", None), **extra)
    model = slider_scenes.build(scene)
    regimes = set()
    for delta in (4.0, 9.5, 10.5, 12.0):
        run = running.run_model(model, delta * NM)
        full = outcomes.histories(run)
        whole, steady = outcomes.summarize(run, full), outcomes.summarize(run)
        regimes.add(whole.get("regime"))
        assert list(whole) == list(steady)
        for name in whole:
            assert np.array_equal(whole[name], steady[name], equal_nan=True), (variant, delta, name)
        win = outcomes.steady_window(run)
        # the window's rule, transient <= t, on the output times
        assert np.array_equal(np.arange(run.time.size)[win], np.flatnonzero(run.time >= model.transient - 1e-15))
        assert 0 < run.time[win].size < run.time.size
        for name, series in outcomes.histories(run, steady=True).items():
            assert np.array_equal(series, full[name][win], equal_nan=True), (variant, delta, name)
    assert {outcomes.FLYING, outcomes.SURFING} <= regimes  # (the test spans flying and contact)
