"""Meniscus formation (docs/model.md, section "Meniscus formation"): the adhesion pressure as a state q
[Pa] of the kernel, dq/dt = (p_a(d) - q) / tau_m, ``lubricant.meniscus_time_us``.

The interface is a synthetic adhesion table, p_a(d) = P0 exp(-d / L), written as the interface stage
writes it (separation [nm], adhesion pressure [MPa]); scenes are built in code.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import xarray as xr

from pipeline.config.scene import scene_from_dict
from pipeline.model import dynamics as dyn
from pipeline.model import state as st
from pipeline.model import assembly, outcomes, running
from pipeline.physics import microwaviness as pdmw

NM = 1e-9
P0, L = 40e6, 1.0 * NM  # [Pa], [m] the synthetic adhesion law
DMW = {"band_khz": [10.0, 500.0], "exponent": -2.0, "seed": 20090601, "sample_rate_mhz": 4.0,
       "rpm": 5425.0, "radius_mm": 34.3, "rms_nm": 0.5}


def adhesion_interface() -> xr.Dataset:
    d_nm = np.linspace(-2.0, 20.0, 221)
    return xr.Dataset({"adhesion_pressure": ("separation", P0 * np.exp(-d_nm * NM / L) / 1e6),
                       "sigma": 1.0, "y_s": 0.0}, coords={"separation": d_nm})


def make_model(tau_us: float | None, effects=("air_bearing", "pitch", "adhesion", "dmw"), duration_ms=0.3,
               start="static"):
    lub = {} if tau_us is None else {"meniscus_time_us": tau_us}
    scene = scene_from_dict({
        "scene": {"effects": list(effects)},
        "air_bearing": {"flying_height_nm": 11.0, "frequencies_khz": [120.0, 300.0], "rear_exponent": 2.0,
                        "damping_ratio": 0.05},
        "lubricant": lub,
        "solver": {"duration_ms": duration_ms, "transient_ms": 0.3 * duration_ms, "start": start},
        "dmw": DMW,
    })
    rec = None
    if "dmw" in effects:
        fs = DMW["sample_rate_mhz"] * 1e6
        rec = pdmw.synthesize(DMW["rms_nm"], (10e3, 500e3), -2.0, 1.2 * duration_ms * 1e-3, fs, DMW["seed"]), fs
    return assembly.build_model(scene, adhesion_interface(), rec, None)


def test_zero_time_is_the_model_without_the_state():
    # tau_m = 0 (the default) is today's kernel: no fifth state, the same numbers as a scene without the key
    a, b = make_model(0.0), make_model(None)
    assert a.meniscus is None and a.atol.size == 4
    ra, rb = running.run_model(a, 8 * NM), running.run_model(b, 8 * NM)
    assert ra.state.shape[1] == 4
    np.testing.assert_array_equal(ra.state, rb.state)


def test_fixed_separation_relaxes_exponentially():
    # a slider too heavy to move (m, I = 1e20): d stays at FH0 - delta - y_s, and q from 0 follows
    # q(t) = p_a(d) (1 - exp(-t / tau)) (the first-order ODE's solution)
    tau = 20e-6
    model = make_model(tau / 1e-6, effects=("air_bearing", "pitch", "adhesion"), duration_ms=0.1)
    model = replace(model, p=dyn.with_values(model.p, m=1e20, I=1e20))
    delta = 8 * NM
    run = running.run_model(model, delta, y0=np.zeros(5))
    pa = P0 * np.exp(-(11 * NM - delta) / L)
    q = run.state[:, st.MENISCUS]
    expected = pa * (1 - np.exp(-run.time / tau))
    np.testing.assert_allclose(q, expected, rtol=0, atol=1e-6 * pa)
    assert abs(run.state[:, st.Z]).max() < 1e-18  # the slider did not move
    h = outcomes.histories(run)
    # tol: the same product A_n q the history is made of
    np.testing.assert_allclose(h["adhesion_force"], run.nominal_area * q, rtol=1e-15)


def test_short_times_converge_to_the_instantaneous_adhesion():
    # tau -> 0: the lag of q behind p_a(d) is O(tau) (q = p_a - tau dp_a/dt + ...), so the separation's
    # distance from the tau = 0 run shrinks in proportion to tau (the transient from the nominal
    # attitude to the flying state under adhesion, d 3.5-4 nm: the nominal start, as the static one has no
    # transient; no DMW, whose response amplifies lags)
    effects = ("air_bearing", "pitch", "adhesion")
    delta = 7 * NM
    d0 = outcomes.histories(running.run_model(make_model(0.0, effects, start="nominal"), delta))["separation"]
    err = [np.max(np.abs(outcomes.histories(running.run_model(make_model(tau_us, effects, start="nominal"), delta))["separation"]
                         - d0))
           for tau_us in (0.1, 0.01, 0.001)]
    assert err[0] > 1e-3 * NM  # (measured 0.038 nm, 0.0046 nm, 0.0004 nm)
    for coarse, fine in zip(err, err[1:]):
        assert 5.0 < coarse / fine < 20.0  # first order in tau


def test_meniscus_state_stays_between_the_extremes_of_its_target():
    # q is a weighted average of its start value p_a(d(0)) and past p_a(d(t)): it never leaves their
    # range, and it starts at its equilibrium
    model = make_model(10.0)
    run = running.run_model(model, 9.5 * NM)
    assert run.info[st.STATUS] == st.OK and np.all(np.isfinite(run.state))
    d = outcomes.histories(run)["separation"]
    pa = P0 * np.exp(-d / L)
    q = run.state[:, st.MENISCUS]
    assert q[0] == pytest.approx(pa[0], rel=1e-6)
    assert q.min() >= pa.min() * (1 - 1e-3) and q.max() <= pa.max() * (1 + 1e-3)
    # the lag smooths: q varies less than its target
    assert np.ptp(q) < np.ptp(pa)


def test_meniscus_needs_the_adhesion_effect():
    # the state relaxes the adhesion pressure: without the adhesion effect the key is refused, by name
    scene = scene_from_dict({"scene": {"effects": ["air_bearing", "contact"]}, "contact": {"k": 1.0},
                             "lubricant": {"meniscus_time_us": 1.0}})
    interface = adhesion_interface().assign(contact_pressure=("separation", np.zeros(221)),
                                            real_area_fraction=("separation", np.zeros(221)))
    with pytest.raises(ValueError, match="meniscus_time_us"):
        assembly.build_model(scene, interface, None, 1.0)
