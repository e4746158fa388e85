"""Two adhesion populations and the lubricant-shear friction term (docs/model.md, sections "Two adhesion
populations" and "Lubricant friction"): the paper's ISBL as their limit, closed forms and brute-force
quadrature at chosen separations, smooth tables, the scene's rules, and the kernel's two-part slot."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate
from scipy.special import ndtr

from pipeline.config.scene import SceneError, load_scene
from pipeline.model import dynamics as dyn
from pipeline.model import forces as fo
from pipeline.model import piecewise as pw
from pipeline.model import assembly, kernel_inputs, running
from pipeline.model.interface_tables import build_tables, roughness_statistics
from pipeline.physics import adhesion, asperity, friction, isbl

NM = 1e-9
W = 0.10923            # J/m^2, the identified scene's work of adhesion
W_BRIDGE = 0.0054615   # J/m^2, 5 % of it
IDENTIFIED = "configs/paper-2009-identified.toml"
TWO = ["interface.adhesion=two-population", f"lubricant.bridge_work_of_adhesion_j_m2={W_BRIDGE}"]


def _paper_interface(dgamma_bridge=None, H=1.65e9):
    """The paper's surface (sigma_s 0.43 nm, R 5 um, eta 13.3 um^-2, E' 94 GPa), t = 0.75 nm."""
    return isbl.Interface(sigma_s=0.4317e-9, eta=13.3e12, R=5e-6, E=94.19e9, H=H, nu=0.3, t=0.75e-9,
                          dgamma=W, eps=0.3e-9, dgamma_bridge=dgamma_bridge)


def _phi(z, s):
    return np.exp(-0.5 * (z / s) ** 2) / (s * np.sqrt(2 * np.pi))


D = np.linspace(-1.5, 4.0, 56) * NM


def test_coinciding_populations_are_the_papers_isbl():
    one = isbl.isbl_tables(D, _paper_interface())
    two = isbl.isbl_tables(D, _paper_interface(dgamma_bridge=W))
    for k in one:
        # tol: the same integrals, the bridges' term added to zero: a few roundings
        np.testing.assert_allclose(two[k], one[k], rtol=1e-12, atol=1e-12 * np.max(np.abs(one[k])), err_msg=k)


@pytest.mark.parametrize("dgamma_bridge", [None, W_BRIDGE, 0.0])
def test_parts_sum_to_the_adhesion(dgamma_bridge):
    out = isbl.isbl_tables(D, _paper_interface(dgamma_bridge), quantities=["adhesion_pressure"])
    total = out["adhesion_pressure_bridges"] + out["adhesion_pressure_menisci"]
    # tol: a sum of the two parts the total is the sum of, one rounding
    np.testing.assert_allclose(total, out["adhesion_pressure"], rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("d_nm", [-0.5, 0.0, 0.4, 1.2])
def test_menisci_around_contacts_closed_form(d_nm):
    """eta 2 pi R dgamma P(d < z <= d + 110 w_c): every elastic and elastic-plastic summit rings with a
    full meniscus, whatever the bridges' work of adhesion."""
    p = _paper_interface(W_BRIDGE)
    d = d_nm * NM
    s = p.sigma_s
    expected = p.eta * 2 * np.pi * p.R * W * (ndtr(-d / s) - ndtr(-(d + asperity.X_PLASTIC * p.w_c) / s))
    got = isbl.isbl_tables(np.array([d]), p, quantities=["adhesion_pressure"])["adhesion_pressure_menisci"][0]
    # tol: the same closed form (ndtr: the same libm-free code), a few roundings
    assert got == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("d_nm", [0.3, 1.0, 2.5])
def test_bridges_against_brute_force_quadrature(d_nm):
    """Bridges = eta [2 pi R W_b P(d - t <= z < d) + int_{z < d - t} F_LJ(d - t - z + eps; W_b) phi dz]."""
    p = _paper_interface(W_BRIDGE)
    d, s, t = d_nm * NM, p.sigma_s, p.t
    lj = integrate.quad(lambda z: adhesion.lennard_jones_force(d - t - z + p.eps, p.R, W_BRIDGE, p.eps) * _phi(z, s),
                        -12 * s, d - t, epsabs=0, epsrel=1e-12, limit=400)[0]
    wetted = adhesion.meniscus_force(p.R, W_BRIDGE) * (ndtr((d) / s) - ndtr((d - t) / s))
    expected = p.eta * (wetted + lj)
    got = isbl.isbl_tables(np.array([d]), p, quantities=["adhesion_pressure"])["adhesion_pressure_bridges"][0]
    # tol: scipy.quad at epsrel 1e-12 against the table's integral, 1e-9 holds both errors
    assert got == pytest.approx(expected, rel=1e-9)


def test_bridges_scale_with_their_work_of_adhesion_alone():
    a = isbl.isbl_tables(D, _paper_interface(W_BRIDGE), quantities=["adhesion_pressure"])
    b = isbl.isbl_tables(D, _paper_interface(2 * W_BRIDGE), quantities=["adhesion_pressure"])
    # tol: a linear term doubled, one rounding
    np.testing.assert_allclose(b["adhesion_pressure_bridges"], 2 * a["adhesion_pressure_bridges"], rtol=1e-12)
    np.testing.assert_array_equal(b["adhesion_pressure_menisci"], a["adhesion_pressure_menisci"])


def test_two_population_tables_are_smooth_for_the_integrator():
    """The population boundaries move with d, so the tables are smooth: a cubic spline through the
    0.05-nm table interpolates the midpoints within 1e-4 of the table's largest value (the paper's
    ISBL meets the same bound)."""
    from scipy.interpolate import CubicSpline
    h = 0.05 * NM
    d = np.arange(-2.0 * NM, 4.0 * NM + h / 2, h)
    mid = d[:-1] + h / 2
    for dgb in (None, W_BRIDGE):
        p = _paper_interface(dgb)
        coarse = isbl.isbl_tables(d, p, quantities=["adhesion_pressure"])
        fine = isbl.isbl_tables(mid, p, quantities=["adhesion_pressure"])
        for k in ("adhesion_pressure", "adhesion_pressure_bridges", "adhesion_pressure_menisci"):
            err = np.max(np.abs(CubicSpline(d, coarse[k])(mid) - fine[k])) / np.max(coarse["adhesion_pressure"])
            assert err < 1e-4, (dgb, k, err)


@pytest.mark.parametrize("d_nm", [-0.6, 0.0, 0.5, 1.5])
def test_wetted_area_against_brute_force_quadrature(d_nm):
    """eta int_{z > d - t} 2 pi R min(z - d + t, t) phi dz: the annulus of every summit between the
    lubricant surface and the disk (docs/model.md, "Lubricant friction")."""
    p = _paper_interface()
    d, s, t, R = d_nm * NM, p.sigma_s, p.t, p.R
    expected = p.eta * 2 * np.pi * R * (
        integrate.quad(lambda z: (z - d + t) * _phi(z, s), d - t, d, epsabs=0, epsrel=1e-12)[0]
        + t * integrate.quad(lambda z: _phi(z, s), d, 12 * s, epsabs=0, epsrel=1e-12)[0])
    got = isbl.isbl_tables(np.array([d]), p, quantities=["wetted_area_fraction"])["wetted_area_fraction"][0]
    # tol: scipy.quad at epsrel 1e-12 against the closed form, 1e-9 holds its error
    assert got == pytest.approx(expected, rel=1e-9)


def test_wetted_area_limits():
    """Far apart nothing is wetted; without lubricant nothing is; deep in contact every summit wets its
    annulus 2 pi R t: eta 2 pi R t."""
    p = _paper_interface()
    far = isbl.isbl_tables(np.array([8.0 * p.sigma_s + p.t]), p, quantities=["wetted_area_fraction"])
    assert far["wetted_area_fraction"][0] < 1e-12
    dry = isbl.Interface(sigma_s=0.4317e-9, eta=13.3e12, R=5e-6, E=94.19e9, H=1e15, nu=0.3, t=0.0, dgamma=W,
                         eps=0.3e-9)
    assert np.all(isbl.isbl_tables(D, dry, quantities=["wetted_area_fraction"])["wetted_area_fraction"] == 0.0)
    deep = isbl.isbl_tables(np.array([-10 * p.sigma_s]), p, quantities=["wetted_area_fraction"])
    # tol: closed form of the deep limit (ndtr = 1 exactly there), a few roundings
    assert deep["wetted_area_fraction"][0] == pytest.approx(p.eta * 2 * np.pi * p.R * p.t, rel=1e-12)


def test_lubricant_shear_term():
    a = np.array([0.0, 0.1, 0.3])
    np.testing.assert_array_equal(friction.lubricant_shear_stress(a, 19e6), 19e6 * a)
    with pytest.raises(ValueError, match="lubricant shear stress"):
        friction.lubricant_shear_stress(a, -1.0)


def test_model_friction_table_adds_the_lubricant_term():
    """The model's friction table is tau_y a_r + tau_lub a_w: at the 11-nm state (d ~ -0.08 nm) the
    lubricant term needed for the paper's mu ~1.2 is ~19 MPa (docs/model.md, "Lubricant friction")."""
    sc0 = load_scene(IDENTIFIED, ["contact.k=0.978"])
    sc1 = load_scene(IDENTIFIED, ["contact.k=0.978", "lubricant.shear_stress_mpa=19"])
    ds = build_tables(sc1, roughness_statistics(sc1))  # (the tables with the wetted area: the term is on)
    sc0 = sc0.replace(scene={**sc0["scene"], "effects": [e for e in sc0.effects if e != "dmw"]})
    sc1 = sc1.replace(scene={**sc1["scene"], "effects": [e for e in sc1.effects if e != "dmw"]})
    m0, m1 = assembly.build_model(sc0, ds, None, 0.978), assembly.build_model(sc1, ds, None, 0.978)
    d = np.array([-0.08 * NM])
    x0, h = m0.p.tab_x0, m0.p.tab_h
    extra = pw.ppval(m1.friction, x0, h, d)[0] - pw.ppval(m0.friction, x0, h, d)[0]
    a_w = float(ds.wetted_area_fraction.interp(separation=-0.08))
    assert extra == pytest.approx(19e6 * a_w, rel=1e-3)
    mu0 = pw.ppval(m0.friction, x0, h, d)[0] / pw.ppval(m0.contact, x0, h, d)[0]
    mu1 = pw.ppval(m1.friction, x0, h, d)[0] / pw.ppval(m1.contact, x0, h, d)[0]
    assert 0.8 < mu0 < 0.9 and 1.1 < mu1 < 1.3


@pytest.mark.parametrize("overrides, message", [
    (["interface.adhesion=two-population"], "needs lubricant.bridge_work_of_adhesion_j_m2"),
    ([f"lubricant.bridge_work_of_adhesion_j_m2={W_BRIDGE}"], "acts only with interface.adhesion"),
    (["interface.adhesion=three"], "interface.adhesion"),
    (["lubricant.shear_stress_mpa=-1"], "shear_stress_mpa"),
])
def test_scene_rules(overrides, message):
    with pytest.raises(SceneError, match=message):
        load_scene(IDENTIFIED, overrides)


def test_lubricant_shear_needs_friction(write_scene, repo_root):
    path = write_scene(f'[scene]\nextends = "{repo_root / "configs" / "paper-2009.toml"}"\nname = "x"\n'
                       'effects = ["air_bearing", "pitch", "dmw", "adhesion", "contact"]\n'
                       '[lubricant]\nshear_stress_mpa = 10\n')
    with pytest.raises(SceneError, match="needs the 'friction' effect"):
        load_scene(path)


def _meniscus_model(overrides):
    sc = load_scene(IDENTIFIED, ["contact.k=0.978", *overrides])
    sc = sc.replace(scene={**sc["scene"], "effects": [e for e in sc.effects if e != "dmw"]})
    return sc, assembly.build_model(sc, build_tables(sc, roughness_statistics(sc)), None, 0.978)


def test_kernel_two_part_slot_and_the_meniscus_state():
    """With two populations the meniscus state q relaxes towards the menisci around contacts and the
    bridges act at once: the kernel's adhesion force is -A_n (q + p_bridges(d)); the static slot sums
    the two parts into the spline of the total adhesion."""
    sc, m = _meniscus_model(TWO)
    assert m.meniscus is not None and m.adhesion.shape[1] == 8
    ds = build_tables(sc, roughness_statistics(sc))
    x0, h = m.p.tab_x0, m.p.tab_h
    d = np.linspace(-1.0, 3.0, 41) * NM
    total = pw.ppval(pw.static_table(m.adhesion), x0, h, d)
    np.testing.assert_allclose(total, np.interp(d / NM, ds.separation, ds.adhesion_pressure) * 1e6,
                               rtol=2e-3, atol=1e-3 * float(ds.adhesion_pressure.max()) * 1e6)
    np.testing.assert_allclose(pw.ppval(np.ascontiguousarray(m.adhesion[:, :4]), x0, h, d),
                               np.interp(d / NM, ds.separation, ds.adhesion_pressure_menisci) * 1e6,
                               rtol=2e-3, atol=1e-3 * float(ds.adhesion_pressure.max()) * 1e6)
    # the kernel's right-hand side at a state: only the adhesion differs between q = 0 and q = q1
    p, tables, variants = kernel_inputs.run_parameters(m, 9.0 * NM)
    y = np.array([0.0, 0.0, 0.0, 0.0, 0.0])
    out0, out1 = np.empty(5), np.empty(5)
    dyn.rhs(0.0, y, p, tables, variants, False, out0)
    q1 = 1e6
    y[4] = q1
    dyn.rhs(0.0, y, p, tables, variants, False, out1)
    # tol: a difference of two force sums: cancellation |F|/(A_n q1) < 1e4 times tens of roundings
    assert (out0[2] - out1[2]) * p["m"] == pytest.approx(p["A_n"] * q1, rel=1e-9)
    # q's rate relaxes towards the menisci part at d(y = 0)
    dd = fo.separation_at(p, 0.0, 0.0, 0.0)
    pm = pw.ppval(np.ascontiguousarray(m.adhesion[:, :4]), x0, h, np.array([dd]))[0]
    # tol: the kernel's spline reading against ppval and a division, a few roundings
    assert out0[4] == pytest.approx(pm / m.meniscus, rel=1e-9)
    # the bridges act at once: with q = 0 the force is -A_n p_bridges(d) (no other interface force when
    # flying), seen as the difference to the model without adhesion effect at the same state
    pb = pw.ppval(np.ascontiguousarray(m.adhesion[:, 4:]), x0, h, np.array([dd]))[0]
    no_adh = dyn.Tables(dmw=None, contact=tables.contact, adhesion=None, friction=tables.friction, tfc=tables.tfc)
    out2 = np.empty(4)
    dyn.rhs(0.0, y[:4].copy(), p, no_adh, variants._replace(meniscus=None), False, out2)
    # tol: a difference of two force sums: cancellation |F|/(A_n p_b) < 1e4 times tens of roundings
    assert (out2[2] - out0[2]) * p["m"] == pytest.approx(p["A_n"] * pb, rel=1e-9)


def test_meniscus_state_starts_at_the_menisci_equilibrium():
    _, m = _meniscus_model(TWO)
    p, _, _ = kernel_inputs.run_parameters(m, 9.0 * NM)
    y = np.zeros(4)
    q0 = running.meniscus_equilibrium(m, p, y)
    dd = fo.separation_at(p, 0.0, 0.0, 0.0)
    # tol: the same spline evaluation
    assert q0 == pytest.approx(pw.ppval(np.ascontiguousarray(m.adhesion[:, :4]), p.tab_x0, p.tab_h,
                                         np.array([dd]))[0], rel=1e-12)


def test_integrated_area_model_integrates_both_adhesion_parts():
    """contact.area_model = 'integrated' with the meniscus state: the two adhesion tables are integrated
    over the bulge each on its own, and (the integral being linear) their sum is the integral of the
    summed table of the meniscus-free model."""
    sc, m = _meniscus_model(TWO + ["lubricant.meniscus_time_us=46", "contact.area_model=integrated"])
    sc0, m0 = _meniscus_model(TWO + ["lubricant.meniscus_time_us=0", "contact.area_model=integrated"])
    delta, An = 11.0 * NM, 62e-12
    two = kernel_inputs.interface_tables(m, delta, An).adhesion
    one = kernel_inputs.interface_tables(m0, delta, An).adhesion
    assert two.shape[1] == 8 and one.shape[1] == 4
    x0, h = m.p.tab_x0, m.p.tab_h
    d = np.linspace(-1.0, 3.0, 41) * NM
    # tol: the bulge integral and the spline are linear: the parts' sum and the sum's table differ by the rounding
    # of their weighted sums, a few thousand eps of the table's largest value (not of its cubic coefficients,
    # ~1e26 times larger): 1e-12 of it (measured: 1e-16)
    y_max = np.max(np.abs(one[:, 3]))
    np.testing.assert_allclose(pw.ppval(pw.static_table(two), x0, h, d), pw.ppval(one, x0, h, d),
                               rtol=0, atol=1e-12 * y_max)
