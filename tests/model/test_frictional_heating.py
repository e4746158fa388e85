"""The frictional heat's protrusion in the dynamics (docs/model.md, section "Frictional heating";
pipeline.model.frictional_heating): its exact update per step, the kernel's response to a constant friction
force and in flight (analytic), its steady state against the statics' fixed point, the start, and the kernel
of ``eta_f = 0``.

Scenes are built in code (tests/slider_scenes.py) without DMW, at 11 nm (in steady contact: the heater's
protrusion is past the fold of the flying equilibria) and 5 nm (flying).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pipeline.analyses.mechanism_statics import NM_PER_MW, heated_contact
from pipeline.model import dynamics as dyn
from pipeline.model import outcomes, running
from pipeline.model.dmw_record import disk_speed_m_s
from pipeline import runner
from pipeline.config.loading import load_scene, shipped_scenes
from pipeline.model.frictional_heating import heat_tables, heat_update
from pipeline.model.piecewise import ppval
from pipeline.model.kernel_inputs import HEAT_STEP, heat_grid, run_parameters
from pipeline.model.state import ACCEPTED, WINDOW_SWITCHES
from pipeline.physics.geometry import nominal_area
from pipeline.units import NM
from slider_scenes import build, make_scene

EFFECTS = ["air_bearing", "pitch", "adhesion", "contact", "friction"]


def heated_model(eta_nm_mw: float, tau_s: float, duration_ms: float = 0.3, transient_ms: float = 0.2):
    """The test scene's model with the frictional heat ``eta_f`` [nm/mW] and a time constant ``tau_s`` [s] set
    on the model (below the scene key's bounds where a test needs it)."""
    sc = make_scene(EFFECTS, solver={"duration_ms": duration_ms, "transient_ms": transient_ms},
                    air_bearing={"damping_ratio": 0.05},
                    tfc={"frictional_heating_nm_per_mw": eta_nm_mw} if eta_nm_mw > 0 else {})
    m = build(sc)
    return replace(m, heating=(m.heating[0], tau_s)) if m.heating is not None else m


# ------------------------------------------------------------------ the update alone

def test_the_update_is_the_exact_lag_of_a_constant_forcing():
    # d(df)/dt = (a - df) / tau from df0: a + (df0 - a) exp(-t / tau), whatever the steps
    a, df0, tau = 0.7e-9, 0.2e-9, 150e-6
    h = np.diff(np.r_[0.0, np.cumsum(np.random.default_rng(1).uniform(1e-9, 5e-7, 2000))])
    df = df0
    for hk in h:
        df = heat_update(df, a, a, hk, tau)
    t = h.sum()
    # tol: 2000 updates of a few operations each, ~1e-16 apiece, against one exponential of their sum
    assert df == pytest.approx(a + (df0 - a) * np.exp(-t / tau), rel=1e-12)


def test_the_update_is_second_order_in_the_step():
    # a(t) = A sin(w t), df(0) = 0: df(t) = A [sin(w t) - w tau cos(w t) + w tau exp(-t/tau)] / (1 + (w tau)^2)
    A, tau, w, T = 1e-9, 100e-6, 2 * np.pi * 20e3, 400e-6

    def error(n: int) -> float:
        h = T / n
        df = 0.0
        for k in range(n):
            df = heat_update(df, A * np.sin(w * k * h), A * np.sin(w * (k + 1) * h), h, tau)
        wt = w * tau
        exact = A * (np.sin(w * T) - wt * np.cos(w * T) + wt * np.exp(-T / tau)) / (1 + wt * wt)
        return abs(df - exact)

    e = [error(n) for n in (200, 400, 800)]
    orders = np.log2(np.array(e[:-1]) / np.array(e[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.05), orders


# ------------------------------------------------------------------ the kernel

def test_eta_zero_is_the_kernel_of_today_bit_for_bit():
    """The heat's slot on with eta_f = 0 (df stays exactly 0) gives the state, the counters and the extremes of
    the kernel without it, bit for bit: the additions do not touch the mechanics' arithmetic."""
    m = heated_model(0.0, 0.0)
    assert m.heating is None
    p, tab, var = run_parameters(m, 11 * NM)
    y0, _ = running.start(m, 11 * NM)
    grid = dyn.Grid(m.duration, np.linspace(0.0, m.duration, 301))
    solver = dyn.Solver(m.rtol, m.atol, m.max_step, 2_000_000)
    off = dyn.integrate(y0, grid, p, tab, var, solver)
    on = dyn.integrate(np.append(y0, 0.0), grid, p, tab, var._replace(heating=heat_grid(replace(m, heating=(0.0, 100e-6)), 11 * NM)), solver)
    assert on[0].shape == (301, 5) and np.all(on[0][:, 4] == 0.0)
    assert np.array_equal(on[0][:, :4], off[0]) and np.array_equal(on[1], off[1])
    assert np.array_equal(on[2], off[2]) and np.array_equal(on[3], off[3])
    assert off[2][ACCEPTED] > 100  # (a real integration)


def test_a_constant_friction_force_gives_the_first_order_response():
    """With a friction table constant in d and a nominal area constant in the protrusion (Q = A_n tau_0 in
    contact) the kernel's delta_f is
    eta_f V Q (1 - exp(-t / tau_f)): exactly at a step's end (the update is exact for a constant force), to the
    chord of the exponential between them (the samples are linear in a step: ``(h / tau_f)^2 / 8`` of the lag)."""
    tau = 50e-6
    m = heated_model(0.01, tau)
    const = np.zeros_like(m.friction)
    const[:, 3] = 13e6  # [Pa]: Q = 3.1 mN over A_n = pi a b = 236 um^2, delta_f -> 0.6 nm
    # (a section depth beyond the protrusion: the whole footprint, A_n the same at every delta + delta_f)
    m = replace(m, friction=const, section_depth=100 * NM)
    y0, _ = running.start(m, 11 * NM)
    run = running.run_model(m, 11 * NM, y0=y0)  # (a given start without the heat: delta_f starts at 0)
    assert run.contact.all()
    Q = run.nominal_area * 13e6
    expected = m.heating[0] * Q * -np.expm1(-run.time / tau)
    A = m.heating[0] * Q
    assert A > 0.5 * NM
    # at a step's end (the last output) exact; between, the chord of the lag: (h / tau_f)^2 / 8 of A at most
    assert abs(run.state[-1, -1] - expected[-1]) < 1e-12 * A
    assert np.max(np.abs(run.state[:, -1] - expected)) < A * (m.max_step / tau) ** 2 / 8


def test_in_flight_the_heat_decays_exponentially():
    tau = 40e-6
    m = heated_model(0.05, tau)
    y0, note = running.start(m, 5 * NM)
    assert "flying" in note
    run = running.run_model(m, 5 * NM, y0=np.append(y0, 1.0 * NM))
    assert not run.contact.any()
    exact = NM * np.exp(-run.time / tau)  # (no friction in flight: the lag's free decay)
    assert abs(run.state[-1, -1] - exact[-1]) < 1e-12 * exact[-1]  # (a step's end: exact)
    assert np.max(np.abs(run.state[:, -1] - exact)) < NM * (m.max_step / tau) ** 2 / 8  # (the chord between)
    # the heat's protrusion lowers the flying separation by itself, at once
    cold = running.run_model(m, 5 * NM, y0=np.append(y0, 0.0))
    d_hot, d_cold = outcomes.histories(run)["separation"], outcomes.histories(cold)["separation"]
    # tol: the same state at t = 0, d = separation_at - delta_f: the difference is delta_f to d's rounding (~1e-24 m)
    assert d_hot[0] - d_cold[0] == pytest.approx(-NM, rel=1e-9)


def test_a_fast_heat_reaches_the_statics_heated_contact():
    """tau_f = 5 us (0.3 ms: 60 tau_f) from 95 % of the heat: the kernel's delta_f at 11 nm is the statics'
    (``heated_contact``: the model at delta + delta_f, A_n included) to the kernel's reading of A_n there, linear
    between protrusions HEAT_STEP apart (kernel_inputs.heat_grid): Q is A_n times the stress at one separation,
    so the kernel's fixed point exceeds the statics' by at most that reading's excess over the exact A_n (3.1e-4
    for 0.38 nm of heat; measured 2.9e-4); the heated start is the statics' fixed point to 1e-6. (At tau_f = 2 us
    the same 5 % leaves the contact state for a bouncing one, with steps of 2 ns too: the lag then couples to the
    slider's contact mode; docs/model.md, section "Frictional heating".)"""
    eta = 0.01
    m = heated_model(eta, 5e-6)
    y0, _ = running.start(m, 11 * NM)
    p, _, _ = run_parameters(m, 11 * NM)
    y_hot, x_start = running.heated_start(m, p, y0)
    # from the fixed point with 5 % less heat (the slider's state at it): back to it in the kernel's own time
    run = running.run_model(m, 11 * NM, y0=np.append(y_hot, 0.95 * x_start))
    assert run.contact.all() and run.info[WINDOW_SWITCHES] == 0  # (steady contact, no switch)
    x_kernel = float(run.state[-1, -1])
    x_statics, _, gain = heated_contact(m, 11 * NM, eta * NM_PER_MW, disk_speed_m_s(m.scene["dmw"]))
    assert 0.0 < gain < 0.1 and x_statics > 0.3 * NM
    assert x_start == pytest.approx(x_statics, rel=1e-6)

    def area(delta: float) -> float:
        return float(nominal_area(delta, m.half_length, m.half_width, m.section_depth))

    s = x_statics / HEAT_STEP  # (x < HEAT_STEP: the grid's first interval)
    read = area(11 * NM) + s * (area(11 * NM + HEAT_STEP) - area(11 * NM))
    ratio = read / area(11 * NM + x_statics)
    assert 1e-4 < ratio - 1.0 < 5e-4  # (the reading's error: the tolerance of the kernel's consistency)
    # the kernel's excess heat: of the reading's sign, at most its size (the contact state takes part of it: a
    # larger A_n bears the load at a larger separation, where the stress is less)
    assert 0.0 < x_kernel / x_statics - 1.0 <= ratio - 1.0


def test_the_start_does_not_decide_the_steady_heat():
    """The static heated start (the fixed point) and a start at delta_f = 0 reach the same steady window:
    tau_f = 20 us, 0.3 ms of transient (15 tau_f: exp(-15) of the 0.39-nm start's offset)."""
    m = heated_model(0.01, 20e-6, duration_ms=0.4, transient_ms=0.3)
    static = running.run_model(m, 11 * NM)
    assert static.state[0, -1] > 0.3 * NM  # (the fixed point: far from the other start)
    y0, _ = running.start(m, 11 * NM)
    cold = running.run_model(m, 11 * NM, y0=y0)
    assert cold.state[0, -1] == 0.0
    a, b = outcomes.summarize(static), outcomes.summarize(cold)
    for name in ("thermal_protrusion", "clearance", "interference"):
        assert a[name] == pytest.approx(b[name], abs=1e-5 * NM), name
    for name in ("friction_force", "friction_power", "flash_temperature"):
        assert a[name] == pytest.approx(b[name], rel=1e-5), name


def test_the_kernel_reads_a_n_and_the_bulge_lift_at_delta_plus_delta_f(tmp_path):
    """The heat grid of the rough-gap bulge scene (its lift tabulated per protrusion; a coarse Reynolds grid):
    at delta_f = 0 the heater's own table and A_n bit for bit, at a node of the grid its table, and in the middle
    of an interval (the largest error of a linear reading) the exact TFC-point force at delta + delta_f over
    the contact's gaps (0-3 nm) to 3e-4 (measured 0.6-2.3e-4) and A_n to 6e-4 (2.6-5.2e-4; its 1 / delta
    curvature), at 9.8 and 11 nm and delta_f up to 3.75 nm."""
    scene = load_scene(shipped_scenes()["paper-2009-two-population-rough"],
                       ["solver.bulge_cells_per_a=4", "solver.bulge_cells_per_b=2",
                        "tfc.frictional_heating_nm_per_mw=0.05"])
    model = runner.current_inputs(scene, tmp_path, k=1.0).model(scene)
    g = np.linspace(0.0, 3.0 * NM, 301)
    for delta in (9.8 * NM, 11.0 * NM):
        slot = heat_grid(model, delta)
        p, tab, _ = run_parameters(model, delta)
        tfc = slot[4][0].copy()
        assert heat_tables(tfc, slot, 0.0) == p["A_n"] and np.array_equal(tfc, tab.tfc)
        x0, h = p["tfc_x0"], p["tfc_h"]
        for df, tol_f, tol_a in ((2 * HEAT_STEP, 1e-12, 1e-12), (0.25 * NM, 3e-4, 6e-4), (1.25 * NM, 3e-4, 6e-4),
                                 (3.75 * NM, 3e-4, 6e-4)):
            area = heat_tables(tfc, slot, df)
            q, exact, _ = run_parameters(model, delta + df)
            f, f_exact = ppval(tfc, x0, h, g), ppval(exact.tfc, x0, h, g)
            assert np.max(np.abs(f / f_exact - 1.0)) < tol_f, (delta, df)
            assert abs(area / q["A_n"] - 1.0) < tol_a, (delta, df)
        assert np.max(np.abs(f / ppval(tab.tfc, x0, h, g) - 1.0)) > 0.05  # (3.75 nm more: another lift)
