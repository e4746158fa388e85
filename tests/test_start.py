"""The start state (``solver.start``; docs/model.md, section "Start state"; pipeline.model.start) decides
where a run begins, not where it ends, wherever the system has one steady state: static, nominal and
previous-heater-step starts reach the same steady window.

Scenes are built in code (tests/test_dynamics.py's ``make_scene``) with every effect, at protrusions
where one steady state exists: 5 nm, below the take-off of the adhesion hysteresis (flying only), and
11 nm, past the fold of the flying equilibria (contact only); between them the state depends on the
history (tests/test_stepping.py).
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from pipeline.model import slider as sl
from pipeline.model.simulation import simulate
from pipeline.units import NM
from test_dynamics import build, make_scene

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
    y_static, note = sl.start(static, delta * NM)
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
    assert int(ref["regime"]) == (sl.FLYING if delta == 5.0 else sl.SURFING)


def test_a_solver_copy_shares_the_fold_and_reaches_the_same_start():
    # with_solver changes how the dynamics are integrated, not the statics: its copy reuses the model's
    # fold (no new search) and starts where a fresh model starts; a change of force is refused
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact"), solver=SOLVER))
    fresh = replace(model)  # (dataclasses.replace: its own, empty fold cache)
    delta = 11 * NM  # past the fold: the start needs it
    y_model, note_model = sl.start(model, delta)
    assert "fold" in model.fold_cache
    copy = sl.with_solver(model, duration=0.1e-3, transient=0.0, rtol=1e-7)
    assert copy.fold_cache is model.fold_cache and copy.duration == 0.1e-3
    assert fresh.fold_cache is not model.fold_cache and not fresh.fold_cache
    y_copy, note_copy = sl.start(copy, delta)
    y_fresh, _ = sl.start(fresh, delta)
    assert note_copy == note_model and "contact" in note_model
    assert (y_copy == y_model).all() and (y_fresh == y_model).all()
    with pytest.raises(ValueError, match="solver settings only"):
        sl.with_solver(model, k=0.5)
