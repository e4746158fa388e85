"""The start state (``solver.start``; docs/model.md, section "Start state"; pipeline.model.start) decides
where a run begins, not where it ends, wherever the system has one steady state: static, nominal and
previous-heater-step starts reach the same steady window.

Scenes are built in code (tests/slider_scenes.py's ``make_scene``) with every effect, at protrusions
where one steady state exists: 5 nm, below the take-off of the adhesion hysteresis (flying only), and
11 nm, past the fold of the flying equilibria (contact only); between them the state depends on the
history (tests/model/test_simulation.py).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pipeline.model import kernel_inputs, outcomes, running
from pipeline.model.simulation import simulate
from pipeline.units import NM
from slider_scenes import build, make_scene

#: modal damping 0.05: the slower mode (120 kHz) decays as exp(-zeta omega t), 1/(zeta omega) = 26.5 us,
#: so a 0.3 ms transient leaves exp(-11.3) ~ 1e-5 of the start's offset (< 1 nm) in the window
#: tolerances 1e3 below the scene's (rtol 1e-6, atol 1e-4 nm), whose own error in the window's exact
#: minimum is ~1e-3 nm (measured: the accuracy stage's rtol knob): the comparison is then of states,
#: not of integration errors (rtol 1e-9: 2e-6 nm in the minimum clearance at 5 nm)
SOLVER = {"duration_ms": 0.6, "transient_ms": 0.3, "rtol": 1e-9, "atol_nm": 1e-7}
TOL_NM = 1e-4


@pytest.mark.parametrize("delta", [5.0, 11.0])  # flying; in steady contact
def test_the_start_does_not_decide_the_steady_state(delta):
    scene = make_scene(["air_bearing", "pitch", "dmw", "adhesion", "contact", "friction"], solver=SOLVER,
                       air_bearing={"damping_ratio": 0.05}, dmw={"rms_nm": 0.163})
    static = build(scene)
    assert static.start == "static"  # the default
    nominal = replace(static, start="nominal")
    y_static, note = running.start(static, delta * NM)
    # the starts differ by far more than the tolerance: the test can tell them apart
    assert abs(y_static[0]) > 100 * TOL_NM * NM, note
    runs = {"static": simulate(static, [delta]).isel(protrusion=0),
            "nominal": simulate(nominal, [delta]).isel(protrusion=0),
            # from the end state of the heater step 0.4 nm below
            "previous step": simulate(static, [delta - 0.4, delta], protocol="stepping").sel(direction="up")
            .isel(protrusion=1)}
    ref = runs["static"]
    for how, ds in runs.items():
        for name in ("clearance", "min_clearance"):
            assert float(ds[name]) == pytest.approx(float(ref[name]), abs=TOL_NM), (how, name)
        # FHM/BV [%] of FH0 = 11 nm: TOL_NM is 1e-3 %
        assert float(ds["fhm_bv"]) == pytest.approx(float(ref["fhm_bv"]), abs=100 * TOL_NM / 11.0), how
        assert float(ds["contact_force"]) == pytest.approx(float(ref["contact_force"]), rel=1e-4, abs=1e-9), how
        assert int(ds["regime"]) == int(ref["regime"]), how
    assert int(ref["regime"]) == (outcomes.FLYING if delta == 5.0 else outcomes.SURFING)


# ------------------------------------------------------ the static start compiled, and its ladder
from pipeline.model.start import SCALE, start_state, static_forces  # noqa: E402
from pipeline.physics import equilibrium as eq  # noqa: E402

#: Newton's convergence test (pipeline.physics.equilibrium.newton): updates below 1e-10 of the scale
NEWTON_TOL = 1e-10 * SCALE


#: TFC-point air-bearing laws: none; compiled in the kernel (gap-power); tabulated per protrusion (ph-limit)
LAWS = {"none": {}, "gap-power": {"tfc_stiffening": "gap-power"}, "ph-limit": {"bulge": "ph-limit"}}


@pytest.mark.parametrize("law", list(LAWS))
def test_the_compiled_start_is_the_python_newton_start(law):
    # the compiled Newton (static_solver) and the Python one (physics.equilibrium.newton) on the same
    # forces reach the same state, flying before the fold and in contact past it, to the Newton tolerance
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact", "friction"), solver=SOLVER,
                             air_bearing=LAWS[law]))
    fold = None
    kinds = set()
    for delta in (0.0, 3.0, 7.5, 9.0, 11.0, 14.0):
        states = {}
        for compiled in (True, False):
            m = replace(model)  # (each its own fold and ladder)
            states[compiled] = start_state(lambda mu, m=m: kernel_inputs.run_parameters(m, mu), delta * NM, "static",
                                           delta * NM + m.p["y_s"] - m.p["FH0"], statics=m.statics,
                                           fold_max=2 * m.p["FH0"], compiled=compiled)
            fold = m.statics["fold"] if fold is None else fold
            assert m.statics["fold"] == fold  # the same fold, bracketed by the same steps
        (y_c, note_c), (y_p, note_p) = states[True], states[False]
        assert np.all(np.abs(y_c[:2] - y_p[:2]) <= NEWTON_TOL), (law, delta, y_c - y_p)
        assert note_c.split("(")[0] == note_p.split("(")[0], (note_c, note_p)
        kinds.add(note_c.split("(")[0].strip())
    # the protrusions reach both branches: the test compares the contact Newton too
    assert {"static flying equilibrium", "static contact equilibrium"} <= kinds, kinds


def test_a_start_from_the_ladder_is_the_start_continued_from_zero_protrusion():
    # the ladder (the flying branch kept per model) changes the continuation's path, not its end: a
    # start continued one step from the ladder's state below it equals, to the Newton tolerance, the
    # start continued from the nominal attitude at zero protrusion in STEPS steps (the start before)
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact", "friction"), solver=SOLVER,
                             air_bearing=LAWS["ph-limit"]))
    assert model.tfc_tabulated  # (the law tabulated per protrusion: the ladder's tables are kept)
    R, flying, solve = static_forces(
        lambda mu: kernel_inputs.run_parameters(model, mu))
    ladder = eq.flying_ladder(R, 2 * model.p["FH0"], y_start=np.zeros(2), scale=SCALE, accept=flying, step=1 * NM,
                              mu_tol=1e-3 * NM, solve=solve)
    assert len(ladder.mu) >= 5 and np.isfinite(ladder.fold)
    deltas = [0.0, 2.5 * NM, 4.0 * NM, 6.3 * NM, ladder.fold - 0.2 * NM, ladder.fold + 0.5 * NM]
    for delta in deltas:
        kw = dict(scale=SCALE, accept=flying, contact_start=np.array([delta + model.p["y_s"] - model.p["FH0"], 0.0]),
                  contact_max_step=0.05 * SCALE, mu_tol=1e-3 * NM, solve=solve)
        from_ladder = eq.static_equilibrium(R, delta, ladder=ladder, **kw)
        from_zero = eq.static_equilibrium(R, delta, steps=6, **kw)
        assert from_ladder.kind == from_zero.kind == ("flying" if delta < ladder.fold else "contact"), delta / NM
        assert np.all(np.abs(from_ladder.equilibrium.y - from_zero.equilibrium.y) <= NEWTON_TOL), delta / NM


@pytest.mark.parametrize("delta", [5.0, 11.0])  # flying; in steady contact
def test_a_pitch_locked_start_is_the_static_equilibrium_of_its_heave(delta):
    # with the pitch locked the moment's stand-in is -theta (positive stiffness): the start is the heave's
    # static equilibrium, flying before the fold and on the contact branch past it, not the nominal attitude
    # (+theta made every locked state unstable); the compiled and the Python Newton agree
    model = build(make_scene(("air_bearing", "adhesion", "contact", "friction"), solver=SOLVER))
    got = {}
    for compiled in (True, False):
        m = replace(model)
        got[compiled] = start_state(lambda mu, m=m: kernel_inputs.run_parameters(m, mu), delta * NM, "static",
                                    delta * NM + m.p["y_s"] - m.p["FH0"], statics=m.statics,
                                    fold_max=2 * m.p["FH0"], compiled=compiled)
    (y, note), (y_py, note_py) = got[True], got[False]
    assert note.startswith("static flying equilibrium" if delta == 5.0 else "static contact equilibrium"), note
    assert note_py.split("(")[0] == note.split("(")[0]
    assert y[1] == 0.0 and y_py[1] == 0.0 and np.all(y[2:] == 0.0)  # theta locked at zero, at rest
    assert abs(y[0] - y_py[0]) <= NEWTON_TOL[0]
    R, _, _ = static_forces(lambda mu: kernel_inputs.run_parameters(model, mu))
    e = eq.newton(lambda yy: R(yy, delta * NM), y[:2], scale=SCALE)
    assert e.converged and e.stable and abs(e.y[0] - y[0]) <= NEWTON_TOL[0]
    assert e.stiffness[0, 0] > 0.0 and e.stiffness[1, 1] == pytest.approx(1.0)  # the heave's stiffness; the stand-in's
    # the net static force there is zero to the Newton tolerance times the heave stiffness
    assert abs(R(y[:2], delta * NM)[0]) <= 10 * e.stiffness[0, 0] * NEWTON_TOL[0]
