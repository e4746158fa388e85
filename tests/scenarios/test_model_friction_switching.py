"""Switched and continuous friction (``contact.friction_switching``) and the count of contact switches per
ms of every run (docs/model.md, section "Switched and continuous friction").

The split of the friction tables, the scene's rules, the kernel's friction force on both sides of the
criterion, and the kernel's count of contact transitions in the steady window: zero for a flying run and
for steady contact, thousands per ms in the sliding mode that the switched friction holds on the criterion
(the two-population scene with the gimbal arm and 50 MPa of lubricant shear at 10.2 nm), and equal to
the transitions of the criterion in a finely sampled history.
"""

from __future__ import annotations

import numpy as np
import pytest

import pipeline as hdi
from pipeline.config.scene import SceneError, load_scene
from pipeline.model import dynamics as dyn
from pipeline.model import piecewise as pw
from pipeline.model import assembly, kernel_inputs, outcomes, running
from pipeline.model.interface_tables import build_tables, interface_parameters, roughness_statistics
from pipeline.model.state import SWITCHES, THETA_RATE, WINDOW_SWITCHES, Z_RATE
from pipeline.physics import isbl
from pipeline.physics.friction import FRICTION_SWITCHING, lubricant_shear_stress

NM = 1e-9
K = 0.978  # the paper's calibrated contact probability, the two-population scene's k (touchdown.k_choice)
TWO = "configs/paper-2009-two-population-identified.toml"
IDENTIFIED = "configs/paper-2009-identified.toml"


# ---------------------------------------------------------------------------------------------
# the split of the tables and the scene's rules


def test_scene_key_default_and_rules(write_scene, repo_root):
    assert load_scene(TWO)["contact"]["friction_switching"] == "criterion"
    assert load_scene(TWO, ["contact.friction_switching=continuous"])["contact"]["friction_switching"] == "continuous"
    with pytest.raises(SceneError, match="friction_switching"):
        load_scene(TWO, ["contact.friction_switching=sometimes"])
    path = write_scene(f'[scene]\nextends = "{repo_root / "configs" / "paper-2009.toml"}"\nname = "x"\n'
                       'effects = ["air_bearing", "pitch", "dmw", "adhesion", "contact"]\n'
                       '[contact]\nfriction_switching = "continuous"\n')
    with pytest.raises(SceneError, match="needs the 'friction' effect"):
        load_scene(path)


# ---------------------------------------------------------------------------------------------
# the model's tables and the kernel's friction force (no DMW: the disk at its mean)

@pytest.fixture(scope="module")
def models():
    """The two-population scene without DMW: criterion, continuous, and without lubricant shear."""
    def scene(*overrides):
        sc = load_scene(TWO, [f"contact.k={K}", *overrides])
        return sc.replace(scene={**sc["scene"], "effects": [e for e in sc.effects if e != "dmw"]})

    base = scene()
    stats = roughness_statistics(base)
    ds = build_tables(base, stats)
    out = {name: assembly.build_model(scene(*o), ds, None, K) for name, o in (
        ("criterion", ()), ("continuous", ("contact.friction_switching=continuous",)),
        ("solid", ("lubricant.shear_stress_mpa=0",)))}
    out["tables"] = ds
    out["interface"] = interface_parameters(base, stats)
    return out


def test_continuous_tables_are_the_solid_and_the_lubricant_side_by_side(models):
    crit, cont, solid, ds = models["criterion"], models["continuous"], models["solid"], models["tables"]
    assert crit.friction.shape[1] == 4 and cont.friction.shape[1] == 8
    np.testing.assert_array_equal(cont.friction[:, :4], solid.friction)  # the solid law alone, same spline
    x0, h = cont.p.tab_x0, cont.p.tab_h
    nodes = ds["separation"].values * NM
    lub = lubricant_shear_stress(ds["wetted_area_fraction"].values, 19e6)
    # tol: at a node ppval may read the end of the piece below, four terms of at most ~16 max|lub| that cancel
    # (the bound below): 1e-9 of the table's largest value holds that rounding with a margin of 1e4
    np.testing.assert_allclose(pw.ppval(np.ascontiguousarray(cont.friction[:, 4:]), x0, h, nodes), lub,
                               rtol=0, atol=1e-9 * lub.max())
    # A spline is linear in its data: the two parts sum to the switched table, up to rounding. The rounding
    # follows the magnitude of the terms each coefficient is summed from, not the coefficient itself (the
    # cubic ones are differences of slopes that nearly cancel, relative errors of 1e-6 where they are small):
    # with Y the data's largest value, the slopes of the not-a-knot system (diagonally dominant, 4h against
    # 2h) are at most 6 Y/h, so the terms of order k are at most 24 Y/h^(3-k); each coefficient of each of
    # the three tables is at most 4 roundings of them past the tridiagonal solve (a few eps of backward error):
    # 3 x 4 x 24 < 300 roundings of Y/h^(3-k) per order (measured: under 1 on both AMD EPYC hosts).
    sol, lub_c, both = cont.friction[:, :4], cont.friction[:, 4:], crit.friction
    y_max = max(np.abs(sol[:, 3]).max(), np.abs(lub_c[:, 3]).max(), np.abs(both[:, 3]).max())
    bound = 300 * np.finfo(float).eps * y_max / h ** (3 - np.arange(4))
    excess = np.abs(sol + lub_c - both) / bound
    worst = np.unravel_index(excess.argmax(), excess.shape)
    assert excess.max() <= 1.0, f"piece {worst[0]}, order {3 - worst[1]}: {excess.max():.3g} of the bound"
    # and what the kernel reads of them: the values at the nodes and between them, within the coefficients'
    # bound summed over the four orders (4 x 300 roundings of Y) and the evaluation's own (3 tables x 4
    # operations on terms of at most 24 Y + 16 Y + 6 Y + Y, under 600): 2048 roundings of Y
    x = x0 + h * np.arange(0.0, both.shape[0], 0.5)
    parts = pw.ppval(np.ascontiguousarray(sol), x0, h, x) + pw.ppval(np.ascontiguousarray(lub_c), x0, h, x)
    np.testing.assert_allclose(parts, pw.ppval(both, x0, h, x), rtol=0, atol=2048 * np.finfo(float).eps * y_max)


def _accelerations(model, d, in_contact, delta=10.2 * NM):
    """The kernel's dz''/dt and dtheta''/dt at rest with the separation ``d`` [m] (theta = 0, disk at 0)."""
    p, tables, variants = kernel_inputs.run_parameters(model, delta)
    z = d - (p["FH0"] - delta - p["y_s"])  # d = FH0 - delta + z - y_s at theta = 0, w = 0
    out = np.empty(4)
    dyn.rhs(0.0, np.array([z, 0.0, 0.0, 0.0]), p, tables, variants, in_contact, out)
    return out[Z_RATE], out[THETA_RATE], p


@pytest.mark.parametrize("above_nm", [0.05, 0.3, 1.0])
def test_out_of_contact_only_the_continuous_lubricant_shear_acts(models, above_nm):
    """Above the criterion the switched friction is off; the continuous one is A_n tau_lub a_w(d), seen
    as the pitch moment -friction_arm Q alone (the vertical force is unchanged)."""
    crit, cont = models["criterion"], models["continuous"]
    d = crit.k_sigma + above_nm * NM
    az0, at0, p = _accelerations(crit, d, False)
    az1, at1, _ = _accelerations(cont, d, False)
    assert az1 == az0
    # the closed form of the wetted area at d itself (the kernel reads its spline through the table)
    a_w = isbl.isbl_tables(np.array([d]), models["interface"], quantities=["wetted_area_fraction"])
    Q = p["A_n"] * 19e6 * float(a_w["wetted_area_fraction"][0])
    assert Q > 0
    assert (at0 - at1) * p["I"] / p["friction_arm"] == pytest.approx(Q, rel=1e-4)


@pytest.mark.parametrize("below_nm", [0.05, 0.3])
def test_in_contact_both_switchings_give_the_same_friction(models, below_nm):
    crit, cont = models["criterion"], models["continuous"]
    d = crit.k_sigma - below_nm * NM
    az0, at0, _ = _accelerations(crit, d, True)
    az1, at1, _ = _accelerations(cont, d, True)
    assert az1 == az0
    # tol: the spline sum's rounding (2048 eps of the table's largest value, above) in one moment: measured 2e-16
    assert at1 == pytest.approx(at0, rel=1e-9)


def test_the_jump_at_the_criterion_is_the_solid_friction_alone(models):
    """At d = k sigma the switched friction jumps by the whole stress, the continuous one by the solid part:
    its lubricant shear is the same on both sides of the criterion."""
    crit, cont, solid = models["criterion"], models["continuous"], models["solid"]
    d = crit.k_sigma
    jump = {name: _accelerations(m, d, True)[1] - _accelerations(m, d, False)[1]
            for name, m in (("criterion", crit), ("continuous", cont), ("solid", solid))}
    _, _, p = _accelerations(crit, d, True)
    tau_solid, tau_all = (pw.ppval(m.friction[:, :4].copy(), p.tab_x0, p.tab_h, np.array([d]))[0]
                          for m in (solid, crit))
    moment = -p["friction_arm"] * p["A_n"] / p["I"]  # (the contact force's moment is in every jump alike)
    # tol: the spline sum's rounding (2048 eps of the table's largest value, above) in one moment
    assert jump["continuous"] == pytest.approx(jump["solid"], rel=1e-9)
    assert jump["criterion"] - jump["continuous"] == pytest.approx(moment * (tau_all - tau_solid), rel=1e-6)


# ---------------------------------------------------------------------------------------------
# the count of contact switches per ms

@pytest.fixture(scope="module")
def two_population():
    """The two-population scene's model with its own DMW record (inputs made in memory)."""
    return hdi.build_model(load_scene(TWO, [f"contact.k={K}"]))


def test_a_flying_run_counts_no_switch(two_population):
    run = running.run_model(two_population, 5.0 * NM)
    s = outcomes.summarize(run)
    assert s["regime"] == outcomes.FLYING
    assert run.info[WINDOW_SWITCHES] == 0 and s["contact_switches_per_ms"] == 0.0


def test_steady_contact_counts_none_after_its_transient(two_population):
    run = running.run_model(two_population, 11.0 * NM)
    s = outcomes.summarize(run)
    assert s["contact_fraction"] == 1.0
    assert s["contact_switches_per_ms"] == 0.0  # [1/s]: none in the window
    assert run.info[SWITCHES] >= run.info[WINDOW_SWITCHES]


def test_a_constructed_chattering_case_counts_thousands_per_ms():
    """k = -1 puts the criterion 1 sigma below the summit mean, where the contact pressure that switches on
    (p_c(k sigma)) exceeds the pull into contact: without DMW the exact solution slides along d = k sigma
    (docs/model.md, section "Integrator") and the kernel switches at about its 20-ns dwell, at most 5e4 per ms."""
    k = -1.0
    sc = load_scene(TWO, [f"contact.k={k}", "solver.duration_ms=0.6", "solver.transient_ms=0.2"])
    sc = sc.replace(scene={**sc["scene"], "effects": [e for e in sc.effects if e != "dmw"]})
    model = assembly.build_model(sc, build_tables(sc, roughness_statistics(sc)), None, k)
    s = outcomes.summarize(running.run_model(model, 11.0 * NM))
    rate = s["contact_switches_per_ms"] * 1e-3  # [1/ms]
    assert 1e4 < rate <= 1.0 / (sc["solver"]["min_dwell_ns"] * 1e-6)
    assert s["fhm_bv"] < 0.1 and abs(s["min_clearance"]) < 0.01 * NM  # held on the criterion


def test_the_count_is_the_criterions_transitions_in_a_fine_history():
    """A bouncing run (10.0 nm) sampled every 5 ns: the kernel's count equals the transitions of the
    sampled contact mode and the sign changes of the clearance d - k sigma in the window, and the
    dataset says it per ms."""
    scene = load_scene(TWO, [f"contact.k={K}", "solver.output_step_ns=5", "solver.duration_ms=1.0"])
    model = hdi.build_model(scene)
    run = running.run_model(model, 10.0 * NM)
    win = run.time >= model.transient - 1e-15
    n = int(run.info[WINDOW_SWITCHES])
    assert n > 20  # (bouncing: a few hundred per ms)
    assert np.count_nonzero(np.diff(run.contact[win])) == n
    clearance = outcomes.histories(run)["clearance"][win]
    assert np.count_nonzero(np.diff(clearance < 0)) == n
    ds = hdi.simulate(model, [10.0])
    assert ds["contact_switches_per_ms"].attrs["units"] == "ms-1"
    # tol: a count over the 0.5-ms window, one rounding
    assert float(ds["contact_switches_per_ms"][0]) == pytest.approx(n / 0.5, rel=1e-12)  # 0.5-ms window


def test_the_switched_friction_holds_a_sliding_mode_the_continuous_one_does_not():
    """The lab's case (two-population scene, gimbal arm, 50 MPa, 10.2 nm): with the friction switched
    by the criterion the TFC point is held on it, thousands of switches per ms (the 20-ns dwell bounds
    them at 5e4 per ms) and a BV near 0; with the lubricant shear continuous it bounces."""
    out = {}
    for how in FRICTION_SWITCHING:
        scene = load_scene(TWO, [f"contact.k={K}", 'slider.friction_arm="gimbal"', "lubricant.shear_stress_mpa=50",
                                 f"contact.friction_switching={how}"])
        out[how] = hdi.simulate(hdi.build_model(scene), [10.2])
    crit, cont = (float(out[h]["contact_switches_per_ms"][0]) for h in FRICTION_SWITCHING)
    assert crit > 1e4
    assert cont < 1e3
    assert float(out["criterion"]["fhm_bv"][0]) < 0.1 < float(out["continuous"]["fhm_bv"][0])


def test_integrated_area_model_integrates_both_friction_parts():
    """contact.area_model = 'integrated' with the continuous friction (and the meniscus state's two adhesion
    tables beside it): each part is integrated over the bulge on its own, and (the integral being linear)
    the parts sum to the integral of the switched table."""
    def model(*overrides):
        sc = load_scene(TWO, [f"contact.k={K}", "contact.area_model=integrated", "lubricant.meniscus_time_us=46",
                              *overrides])
        sc = sc.replace(scene={**sc["scene"], "effects": [e for e in sc.effects if e != "dmw"]})
        return assembly.build_model(sc, build_tables(sc, roughness_statistics(sc)), None, K)

    cont, crit = model("contact.friction_switching=continuous"), model()
    delta, An = 11.0 * NM, 62e-12
    two, one = kernel_inputs.interface_tables(cont, delta, An), kernel_inputs.interface_tables(crit, delta, An)
    assert two.friction.shape[1] == 8 and one.friction.shape[1] == 4
    assert two.adhesion.shape[1] == 8  # (the adhesion's two tables still side by side)
    # tol: the switching leaves the adhesion alone: the same tables by the same operations
    np.testing.assert_allclose(two.adhesion, one.adhesion, rtol=1e-12, atol=0)
    x0, h = cont.p.tab_x0, cont.p.tab_h
    d = np.linspace(-1.0, 3.0, 41) * NM
    parts = sum(pw.ppval(np.ascontiguousarray(two.friction[:, j:j + 4]), x0, h, d) for j in (0, 4))
    # tol: the bulge integral and the spline are linear: the parts' sum and the sum's table differ by the rounding
    # of their weighted sums, a few thousand eps of the table's largest value (not of its cubic coefficients)
    np.testing.assert_allclose(parts, pw.ppval(one.friction, x0, h, d), rtol=0,
                               atol=1e-12 * np.max(np.abs(one.friction[:, 3])))
    assert np.all(pw.ppval(np.ascontiguousarray(two.friction[:, 4:]), x0, h, d) > 0)  # the lubricant shear


def test_ensembles_carry_the_switch_rate_mean_and_spread():
    """``sweep.nc``/``ensemble.nc`` of a DMW ensemble: the mean and sample standard deviation of the rate
    over the realisations, in its unit (pipeline.variables.ENSEMBLE_OF)."""
    from pipeline.analyses.ensemble_rules import statistics
    from pipeline.variables import SCALARS

    rate = np.array([[0.0, 30.0, 60.0], [900.0, 500.0, 100.0]])  # [1/ms], (protrusion, realisation)
    out = statistics({"contact_switches_per_ms": SCALARS["contact_switches_per_ms"].data(rate, ("protrusion",
                                                                                               "realisation"))})
    # tol: a mean of exact integers, a few roundings
    np.testing.assert_allclose(out["contact_switches_per_ms_mean"].values, [30.0, 500.0])
    # tol: a std of exact integers, a few roundings and a sqrt
    np.testing.assert_allclose(out["contact_switches_per_ms_std"].values, [30.0, 400.0])
    assert out["contact_switches_per_ms_mean"].attrs["units"] == "ms-1"
