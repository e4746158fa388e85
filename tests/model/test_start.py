"""The start state (``solver.start``; docs/model.md, section "Start state"; pipeline.model.start) decides
where a run begins, not where it ends, wherever the system has one steady state: static, nominal and
previous-heater-step starts reach the same steady window.

Scenes are built in code (tests/slider_scenes.py's ``make_scene``) with every effect, at protrusions
where one steady state exists: 5 nm, below the take-off of the adhesion hysteresis (flying only), and
11 nm, past the fold of the flying equilibria (contact only); between them the state depends on the
history (tests/test_stepping.py).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from pipeline.model import copies, kernel_inputs, outcomes, running
from pipeline.model.simulation import simulate
from pipeline.units import NM
from slider_scenes import build, make_scene, synthetic_record

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


def test_a_solver_copy_shares_the_fold_and_reaches_the_same_start():
    # with_solver changes how the dynamics are integrated, not the statics: its copy reuses the model's
    # fold (no new search) and starts where a fresh model starts; a change of force is refused
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact"), solver=SOLVER))
    fresh = replace(model)  # (dataclasses.replace: its own, empty fold cache)
    delta = 11 * NM  # past the fold: the start needs it
    y_model, note_model = running.start(model, delta)
    assert "fold" in model.statics
    copy = copies.with_solver(model, duration=0.1e-3, transient=0.0, rtol=1e-7)
    assert copy.statics is model.statics and copy.duration == 0.1e-3
    assert fresh.statics is not model.statics and not fresh.statics
    y_copy, note_copy = running.start(copy, delta)
    y_fresh, _ = running.start(fresh, delta)
    assert note_copy == note_model and "contact" in note_model
    assert (y_copy == y_model).all() and (y_fresh == y_model).all()
    with pytest.raises(ValueError, match="solver settings only"):
        copies.with_solver(model, k=0.5)


def test_a_criterion_copy_starts_where_a_fresh_model_does_without_its_own_fold_search():
    # with_criterion(model, k): the contact-off fold bounds every k's fold (contact is off on the flying
    # branch under either criterion); the copy's starts, below the bound (continued to the protrusion)
    # and past it (the contact branch), equal a fresh model's with k, which searches its own fold
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact"), solver=SOLVER))
    off = replace(model, k=-1e300)
    running.start(off, 0.0)
    bound = off.statics["fold"]
    assert 5 * NM < bound < 11 * NM  # the adhesion fold of this scene
    # k sigma 0.5 nm ends the flying branch before the adhesion fold: a bound, not the fold itself
    for k in (-1.0, 0.0, 1.0, 3.0):
        copy = copies.with_criterion(off, k)
        fresh = replace(model, k=k)
        for delta in (5 * NM, bound - 0.3 * NM, bound, 11 * NM):
            y_copy, note_copy = running.start(copy, delta)
            y_fresh, note_fresh = running.start(fresh, delta)
            assert (y_copy == y_fresh).all(), (k, delta / NM, note_copy, note_fresh)
            assert note_copy.split(":")[0] == note_fresh.split(":")[0]  # same kind of state and values
            assert ("contact" in note_copy) == (delta >= fresh.statics["fold"]), (k, delta / NM)
        assert "fold" not in copy.statics and copy.statics["bound"] == bound
        assert fresh.statics["fold"] <= bound, k
    # a model's own fold bounds a higher criterion's, not a lower one's (whose fold may lie past it)
    one = replace(model, k=1.0)
    running.start(one, 0.0)
    assert copies.with_criterion(one, 2.0).statics["bound"] == one.statics["fold"]
    assert "bound" not in copies.with_criterion(one, 0.5).statics


def test_the_realisations_of_an_ensemble_share_their_static_starts():
    # the static equilibria are on the mean disk: models of one scene on other DMW records start from the
    # same states, found once for all (share_statics), and run exactly as each does alone
    scene = make_scene(("air_bearing", "pitch", "adhesion", "contact", "dmw"),
                       solver={"duration_ms": 0.6, "transient_ms": 0.3})
    records = [synthetic_record(scene)] + [synthetic_record(make_scene(
        ("air_bearing", "pitch", "adhesion", "contact", "dmw"), solver={"duration_ms": 0.6, "transient_ms": 0.3},
        dmw={"seed": seed})) for seed in (7, 8)]
    assert not np.array_equal(records[0][0], records[1][0])
    alone = [build(scene, rec) for rec in records]
    shared = [build(scene, rec) for rec in records]
    copies.share_statics(shared)
    deltas = [5.0, 11.0]  # flying; past the fold (contact branch)
    for a, s in zip(alone, shared):
        ra, rs = simulate(a, deltas), simulate(s, deltas)
        for name in ra.data_vars:
            assert_array_equal(ra[name].values, rs[name].values, err_msg=name)
    assert all(s.statics is shared[0].statics for s in shared)
    assert sorted(mu for _, mu in shared[0].statics["starts"]) == [5 * NM, 11 * NM]  # one dict: found once for the three
    assert not np.array_equal(simulate(shared[0], [5.0])["fhm_bv"], simulate(shared[1], [5.0])["fhm_bv"])
    with pytest.raises(ValueError, match="one scene and criterion"):
        copies.share_statics([alone[0], replace(alone[1], k=0.5)])
    # without the contact law k is NaN on every model: one criterion all the same
    flying = make_scene(("air_bearing", "pitch", "dmw"), solver={"duration_ms": 0.6, "transient_ms": 0.3})
    pair = [build(flying, rec) for rec in records[:2]]
    assert np.isnan(pair[0].k)
    copies.share_statics(pair)
    assert pair[1].statics is pair[0].statics


# ------------------------------------------------ issue 26: the static start compiled, and its ladder
from pipeline.model import static_solver  # noqa: E402
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


def test_the_compiled_newton_reports_what_the_python_newton_reports():
    # the Equilibrium of one solve: state, stiffness, convergence, stability, iterations, residual
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact"), solver=SOLVER))
    R, flying, solve = static_forces(
        lambda mu: kernel_inputs.run_parameters(model, mu))
    for delta, y0, max_step in ((4 * NM, np.zeros(2), None), (12 * NM, np.array([1 * NM, 0.0]), 0.05 * SCALE)):
        c = solve(delta, y0, max_step=max_step, max_iter=200)
        p = eq.newton(lambda y: R(y, delta), y0, scale=SCALE, max_step=max_step, max_iter=200)
        assert c.converged and p.converged and c.stable == p.stable and c.iterations == p.iterations
        assert np.all(np.abs(c.y - p.y) <= NEWTON_TOL)
        np.testing.assert_allclose(c.stiffness, p.stiffness, rtol=1e-6)
        assert c.residual == pytest.approx(p.residual, abs=1e-12)
    # an unstable state (the saddle of the adhesion fold's other branch) is reported unstable by both:
    # Newton from deep below the flying state at a protrusion just before the fold
    fold = eq.branch_fold(R, 2 * model.p["FH0"], y_start=np.zeros(2), scale=SCALE, accept=flying, step=1 * NM,
                          mu_tol=1e-3 * NM, solve=solve)
    delta = fold - 0.05 * NM
    start = solve(delta, np.zeros(2)).y - np.array([0.5 * NM, 0.0])
    c = solve(delta, start, max_iter=200)
    p = eq.newton(lambda y: R(y, delta), start, scale=SCALE, max_iter=200)
    assert c.converged and p.converged and not c.stable and not p.stable
    assert np.all(np.abs(c.y - p.y) <= NEWTON_TOL)


def test_the_compiled_solve_of_two_equations():
    # the 2x2 solve (partial pivoting) against numpy's, a zero pivot reported as singular
    rng = np.random.default_rng(3)
    x = np.empty(2)
    for _ in range(200):
        J, b = rng.normal(size=(2, 2)) * 10.0 ** rng.integers(-6, 6, size=2), rng.normal(size=2)
        assert static_solver._solve2(J, b, x)
        np.testing.assert_allclose(x, np.linalg.solve(J, b), rtol=1e-9)
    assert static_solver._solve2(np.array([[0.0, 1.0], [2.0, 0.0]]), np.array([1.0, 4.0]), x)  # needs the pivot
    np.testing.assert_array_equal(x, [2.0, 1.0])
    assert not static_solver._solve2(np.array([[1.0, 2.0], [2.0, 4.0]]), np.ones(2), x)
    assert not static_solver._solve2(np.zeros((2, 2)), np.ones(2), x)
    # and it runs without the GIL, like the kernel (the point of compiling it: parallel threads)
    assert static_solver._newton.targetoptions["nogil"]


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
