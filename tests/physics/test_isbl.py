"""The ISBL rough-surface interface (docs/model.md, section "ISBL interface"): external check against the CML tables,
closed forms of the GW integrals, brute-force quadrature, convergence, and physical properties."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst
from scipy import integrate
from scipy.special import erfc, gamma, pbdv

from pipeline.physics import adhesion, asperity, friction, isbl
from pipeline.physics import asperity_statistics as st
from pipeline.model.interface_tables import interface_parameters, roughness_statistics

NM = 1e-9
HUGE_H = 1e6 * 1e9  # 1e6 GPa: w_c ~ 1e11 m, so every summit stays elastic (Hertz)


# --------------------------------------------------------------------------------------------
# Closed forms of the GW integrals
# --------------------------------------------------------------------------------------------

def gw_F(n: float, h: np.ndarray) -> np.ndarray:
    """F_n(h) = int_h^inf (s-h)^n phi(s) ds = Gamma(n+1)/sqrt(2 pi) exp(-h^2/4) D_{-n-1}(h).

    (Parabolic-cylinder representation: D_{-n-1}(h) = exp(-h^2/4)/Gamma(n+1) int_0^inf t^n
    exp(-h t - t^2/2) dt, e.g. Abramowitz & Stegun 19.5.3 / DLMF 12.5.1.)
    """
    h = np.asarray(h, dtype=float)
    return gamma(n + 1) / np.sqrt(2 * np.pi) * np.exp(-h * h / 4) * pbdv(-n - 1, h)[0]


def test_closed_forms_agree_with_elementary_ones():
    h = np.linspace(-5, 8, 53)
    phi = np.exp(-h * h / 2) / np.sqrt(2 * np.pi)
    Q = 0.5 * erfc(h / np.sqrt(2))
    # tol: pbdv's series against erfc (measured 7e-15 relative)
    np.testing.assert_allclose(gw_F(0, h), Q, rtol=1e-12)                 # F0 = Q(h)
    # tol: pbdv's series against phi - h Q, which cancels 64-fold at h = 8 (measured 5e-13)
    np.testing.assert_allclose(gw_F(1, h), phi - h * Q, rtol=1e-10)       # F1 = phi - h Q
    # F_{3/2} against adaptive quadrature of its definition
    for hh in (-3.0, 0.0, 2.5):
        ref = integrate.quad(lambda s: (s - hh) ** 1.5 * np.exp(-s * s / 2) / np.sqrt(2 * np.pi),
                             hh, np.inf, epsabs=0, epsrel=1e-13)[0]
        # tol: scipy.quad at epsrel 1e-13 against pbdv, 1e-10 holds both
        assert gw_F(1.5, hh) == pytest.approx(ref, rel=1e-10)


def _elastic_interface(sigma_s=0.46e-9, eta=5e15, R=20e-9, E=148.6e9, t=1e-9, dgamma=0.106, eps=0.3e-9):
    return isbl.Interface(sigma_s=sigma_s, eta=eta, R=R, E=E, H=HUGE_H, nu=0.3, t=t, dgamma=dgamma, eps=eps)


@pytest.mark.parametrize("sigma_s, eta, R, E", [
    (0.4613e-9, 5e15, 20e-9, 148.6e9),     # the CML surface
    (0.3489e-9, 1e13, 5e-6, 94.19e9),      # the paper surface
    (3.0e-9, 2e12, 10e-6, 250e9),
])
def test_elastic_limit_equals_gw_closed_forms(sigma_s, eta, R, E):
    p = _elastic_interface(sigma_s=sigma_s, eta=eta, R=R, E=E)
    h = np.linspace(-5, 8, 131)  # beyond ~10 sigma_s the |z| <= 12 sigma_s window truncates (tiny values)
    out = isbl.isbl_tables(h * sigma_s, p)
    # GW66: contact fraction = F0(h), real area = eta pi R sigma_s F1(h),
    # pressure = eta (4/3) E' sqrt(R) sigma_s^1.5 F_{3/2}(h)
    # tol: the table's ndtr against pbdv's series (measured 7e-15 relative)
    np.testing.assert_allclose(out["contact_fraction"], gw_F(0, h), rtol=1e-12)
    # tol: the closed-form integrals against pbdv's series, 1e-8 holds both
    np.testing.assert_allclose(out["real_area_fraction"], eta * np.pi * R * sigma_s * gw_F(1, h), rtol=1e-8)
    # tol: the closed-form integrals against pbdv's series, 1e-8 holds both
    np.testing.assert_allclose(out["contact_pressure"],
                               eta * 4 / 3 * E * np.sqrt(R) * sigma_s**1.5 * gw_F(1.5, h), rtol=1e-8)
    # every contacting summit is elastic
    # tol: the table's ndtr against pbdv's series (measured 7e-15 relative)
    np.testing.assert_allclose(out["elastic_fraction"], gw_F(0, h), rtol=1e-12)
    assert np.all(out["plastic_fraction"] == 0)


def test_zero_work_of_adhesion_gives_exactly_zero_adhesion():
    p = _elastic_interface(dgamma=0.0)
    d = np.linspace(-5 * p.sigma_s, 30 * NM, 301)
    assert np.all(isbl.isbl_tables(d, p, quantities=["adhesion_pressure"])["adhesion_pressure"] == 0.0)


# --------------------------------------------------------------------------------------------
# External check: the Berkeley CML flying-touchdown SBL tables (docs/model.md, section "ISBL interface")
# --------------------------------------------------------------------------------------------

CML_D_NM = [0.0, 0.5, 1.0, 2.0]
CML_ADHESION_MPA = [67.33, 62.64, 46.76, 8.238]
CML_CONTACT_MPA = [596.8, 88.11, 5.691, 0.001282]


@pytest.fixture(scope="module")
def cml_tables():
    # sigma = 0.5 nm, eta = 5e15 m^-2, R = 20 nm -> McCool sigma_s = 0.461335 nm (docs/model.md, section "Asperity statistics");
    # dgamma = 0.106 J/m^2, t = 1.0 nm, eps = 0.3 nm; elastic only (huge H); E' = 148.6 GPa passed
    # as our E': the CML Hertz law used (4/3)*148.6 GPa where ours is (4/3) E' sqrt(R) w^1.5.
    sigma, eta, R = 0.5e-9, 5e15, 20e-9
    p = isbl.Interface(sigma_s=st.summit_sigma(sigma, eta, R), eta=eta, R=R, E=148.6e9, H=HUGE_H, nu=0.3,
                       t=1.0e-9, dgamma=0.106, eps=0.3e-9)
    # The tables' d is our separation from the mean of summit heights (their h = d + y_s is the
    # separation from the mean of surface heights): with d -> d + y_s the contact pressure is off
    # by -82 % at d = 0, with d unchanged it matches to 0.05 %.
    return isbl.isbl_tables(np.array(CML_D_NM) * NM, p)


# Measured deviations (ours / CML - 1): adhesion -1.62 %, -0.53 %, -0.28 %, -0.24 %;
# contact +0.029 %, +0.031 %, +0.025 %, +0.052 % at d = 0, 0.5, 1, 2 nm.
# Note: CML's 67.33 MPa at d = 0 exceeds eta 2 pi R dgamma = 66.60 MPa, the most this model can
# give (every summit at most at the meniscus force), so that -1.6 % is a model difference, not
# quadrature error.
@pytest.mark.parametrize("i", range(4))
def test_cml_adhesion_pressure(cml_tables, i):
    # Source: docs/model.md, section "ISBL interface", CML SBL tables: 67.33, 62.64, 46.76, 8.238 MPa at d = 0, 0.5, 1, 2 nm
    assert cml_tables["adhesion_pressure"][i] / 1e6 == pytest.approx(CML_ADHESION_MPA[i], rel=0.02)


@pytest.mark.parametrize("i", range(4))
def test_cml_contact_pressure(cml_tables, i):
    # Source: docs/model.md, section "ISBL interface", CML SBL tables: 596.8, 88.11, 5.691, 0.001282 MPa at d = 0, 0.5, 1, 2 nm
    assert cml_tables["contact_pressure"][i] / 1e6 == pytest.approx(CML_CONTACT_MPA[i], rel=0.02)


def test_cml_adhesion_below_the_meniscus_bound(cml_tables):
    # eta 2 pi R dgamma = 5e15 * 2 pi * 20e-9 * 0.106 = 66.6018 MPa: no summit pulls harder than 2 pi R dgamma
    assert np.all(cml_tables["adhesion_pressure"] / 1e6 <= 66.6018)


# --------------------------------------------------------------------------------------------
# Brute force: adaptive quadrature of the raw single-summit laws (full elastic-plastic + adhesion)
# --------------------------------------------------------------------------------------------

def _ep_interface():
    """A surface with every regime inside the Gaussian: w_c = 0.0103 nm, 110 w_c = 1.13 nm,
    sigma_s = 0.419 nm (sigma = 0.5 nm, R = 0.5 um, alpha = 3, E' = 200 GPa, H = 1 GPa)."""
    sigma, R, alpha = 0.5e-9, 0.5e-6, 3.0
    eta = np.sqrt(alpha / 2412.74) / (sigma * R)
    return isbl.Interface(sigma_s=st.summit_sigma(sigma, eta, R), eta=eta, R=R, E=200e9, H=1e9, nu=0.3,
                          t=0.75e-9, dgamma=0.106, eps=0.3e-9)


def _paper_interface():
    from pipeline.config.scene import load_scene
    scene = load_scene(Path(__file__).resolve().parents[2] / "configs" / "paper-2009.toml")
    return interface_parameters(scene, roughness_statistics(scene))


def _brute_force(d: float, p: isbl.Interface) -> dict[str, float]:
    """eta * int law(z) phi(z) dz by scipy.integrate.quad, split at every break of the laws.

    Integrated in u = z / sigma_s over |u| <= 40 (quad on an infinite range in metres misses the
    nanometre-wide Gaussian).
    """
    s, R, E, H, nu = p.sigma_s, p.R, p.E, p.H, p.nu
    wc = p.w_c
    U = 40.0

    def phi(u):  # standard normal density: phi_s(z) dz = phi(u) du
        return np.exp(-0.5 * u * u) / np.sqrt(2 * np.pi)

    def q(f, a, b):
        a, b = max(a / s, -U), min(b / s, U)
        if b <= a:
            return 0.0
        return integrate.quad(lambda u: f(u * s) * phi(u), a, b, epsabs=0.0, epsrel=1e-12, limit=500)[0]

    breaks = [d, d + wc, d + asperity.X_MID * wc, d + asperity.X_PLASTIC * wc, np.inf]
    ranges = list(zip(breaks[:-1], breaks[1:]))
    load = sum(q(lambda z: float(asperity.contact_load(z - d, R, E, H, nu)), a, b) for a, b in ranges)
    area = sum(q(lambda z: float(asperity.contact_area(z - d, R, E, H, nu)), a, b) for a, b in ranges)
    fric = sum(q(lambda z: float(friction.friction_force(asperity.contact_area(z - d, R, E, H, nu), H)), a, b)
               for a, b in ranges[:-1])  # elastic + elastic-plastic only
    lj = q(lambda z: float(adhesion.lennard_jones_force(d - p.t - z + p.eps, R, p.dgamma, p.eps)),
           -np.inf, d - p.t)
    men = q(lambda z: adhesion.meniscus_force(R, p.dgamma), d - p.t, d + asperity.X_PLASTIC * wc)
    return {"contact_pressure": p.eta * load, "real_area_fraction": p.eta * area,
            "friction_stress": p.eta * fric, "adhesion_pressure": p.eta * (lj + men)}


@pytest.mark.parametrize("case", ["elastic-plastic", "paper"])
def test_against_brute_force_quadrature(case):
    p = _ep_interface() if case == "elastic-plastic" else _paper_interface()
    d_nm = [-2.0, -0.8, -0.3, 0.0, 0.4, 1.2, 2.5]
    ours = isbl.isbl_tables(np.array(d_nm) * NM, p)
    for i, dn in enumerate(d_nm):
        ref = _brute_force(dn * NM, p)
        for k, v in ref.items():
            assert ours[k][i] == pytest.approx(v, rel=1e-6), (case, dn, k)


def test_ep_case_exercises_every_regime():
    p = _ep_interface()
    out = isbl.isbl_tables(np.array([0.0]), p)
    # w_c / sigma_s = 0.025: about phi(0) * 0.025 = 1 % of the summits are elastic at d = 0,
    # and Q(1.13 / 0.419) = 0.35 % fully plastic
    assert 0.005 < out["elastic_fraction"][0] < 0.02
    assert 0.001 < out["plastic_fraction"][0] < 0.01


# --------------------------------------------------------------------------------------------
# Quadrature convergence
# --------------------------------------------------------------------------------------------

def _max_rel(a, b, floor=1e-25):
    """Largest relative difference where the reference is not tiny (> floor x its maximum)."""
    m = np.abs(b) > floor * np.max(np.abs(b))
    return float(np.max(np.abs(a[m] - b[m]) / np.abs(b[m]))) if m.any() else 0.0


def _convergence(p, step=0.01 * NM):
    d = np.arange(-5 * p.sigma_s, 30 * NM + step / 2, step)
    default = isbl.isbl_tables(d, p)
    doubled = isbl.isbl_tables(d, p, nodes=48, panels=8)
    chunks = [isbl.isbl_tables(c, p, nodes=96, panels=16) for c in np.array_split(d, 8)]  # bounded memory
    fine = {k: np.concatenate([c[k] for c in chunks]) for k in isbl.QUANTITIES}
    return {k: (_max_rel(default[k], doubled[k]), _max_rel(default[k], fine[k])) for k in isbl.QUANTITIES}


def _rough_interface():
    """The rough end of the physical range: sigma = 5 nm (sigma_s = 4.4 nm >> eps = 0.3 nm)."""
    sigma, R, alpha = 5e-9, 5e-6, 5.0
    eta = np.sqrt(alpha / 2412.74) / (sigma * R)
    return isbl.Interface(sigma_s=st.summit_sigma(sigma, eta, R), eta=eta, R=R, E=94e9, H=1.5e9, nu=0.3,
                          t=0.75e-9, dgamma=0.106, eps=0.3e-9)


@pytest.mark.parametrize("case", ["paper", "cml", "elastic-plastic", "rough"])
def test_quadrature_converged(case):
    if case == "paper":
        p = _paper_interface()
    elif case == "cml":
        p = _elastic_interface(sigma_s=st.summit_sigma(0.5e-9, 5e15, 20e-9), t=1e-9)
    elif case == "rough":
        # before the Lennard-Jones grading in isbl.py the default was 2e-4 off here (adhesion)
        p = _rough_interface()
    else:
        p = _ep_interface()
    for k, (dbl, fine) in _convergence(p).items():
        assert dbl < 1e-8, (k, dbl)    # doubling nodes and panels changes nothing at 1e-8
        assert fine < 1e-8, (k, fine)  # the default against a very fine reference


# --------------------------------------------------------------------------------------------
# Properties over the physical parameter ranges (hypothesis)
# --------------------------------------------------------------------------------------------

@hst.composite
def physical_interfaces(draw):
    sigma = 10 ** draw(hst.floats(np.log10(0.05e-9), np.log10(5e-9)))
    R = 10 ** draw(hst.floats(np.log10(0.02e-6), np.log10(50e-6)))
    alpha = draw(hst.floats(1.0, 50.0, exclude_min=True, exclude_max=True))
    eta = np.sqrt(alpha / 2412.74) / (sigma * R)
    E = draw(hst.floats(50e9, 300e9))
    H = draw(hst.floats(1e9, 30e9))
    t = draw(hst.floats(0.0, 2e-9))
    return isbl.Interface(sigma_s=st.summit_sigma(sigma, eta, R), eta=eta, R=R, E=E, H=H, nu=0.3, t=t,
                          dgamma=0.106, eps=0.3e-9)


def _grid(p, step=0.02 * NM):
    return np.arange(-5 * p.sigma_s, 30 * NM + step / 2, step)


PROPS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@PROPS
@given(physical_interfaces())
def test_tables_are_finite_and_physical(p):
    d = _grid(p)
    out = isbl.isbl_tables(d, p)
    for k, v in out.items():
        assert np.all(np.isfinite(v)), k
        assert np.all(v >= 0), k
    # adhesion never exceeds every summit pulling with the meniscus force 2 pi R dgamma
    assert np.all(out["adhesion_pressure"] <= p.eta * 2 * np.pi * p.R * p.dgamma * (1 + 1e-12))
    assert np.all(out["contact_fraction"] <= 1)
    # the real area is a fraction of the nominal one where the model is physical (d >= 0: at most
    # half of the summits touch); deep interference of a dense surface may exceed 1
    assert np.all(out["real_area_fraction"][d >= 0] < 1)


@PROPS
@given(physical_interfaces())
def test_contact_pressure_decreases_with_separation(p):
    out = isbl.isbl_tables(_grid(p), p, quantities=["contact_pressure", "real_area_fraction",
                                                    "friction_stress", "contact_fraction"])
    for k in ("contact_pressure", "real_area_fraction", "contact_fraction"):
        v = out[k]
        assert np.all(np.diff(v) <= 0), k
        pos = v[:-1] > 0
        assert np.all(np.diff(v)[pos] < 0), k   # strictly, while anything touches


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(physical_interfaces())
def test_quadrature_converged_over_physical_ranges(p):
    # Before the fix in isbl.py (geometric grading of the Lennard-Jones range) the adhesion
    # pressure was off by up to 1e-3 relative at sigma ~ 5 nm.
    d = _grid(p, step=0.05 * NM)
    a = isbl.isbl_tables(d, p)
    b = isbl.isbl_tables(d, p, nodes=48, panels=8)
    for k in isbl.QUANTITIES:
        assert _max_rel(a[k], b[k]) < 1e-8, k


# --------------------------------------------------------------------------------------------
# Smoothness on the default grid: the Kogut-Etsion jumps are integrated, the tables stay smooth
# --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("case", ["paper", "elastic-plastic"])
def test_tables_smooth_across_population_boundaries(case):
    p = _paper_interface() if case == "paper" else _ep_interface()
    step = 0.01 * NM                                  # the default solver.table_step_nm
    d = isbl.separation_grid(-8.0 * p.sigma_s, 30e-9, step)
    out = isbl.isbl_tables(d, p)
    # A Gaussian tail has (log p)'' -> -1/sigma_s^2, i.e. a second difference of step^2/sigma_s^2
    # (8e-4 for the paper surface); a per-cent jump of the tables would show as a spike ~1e-2.
    bound = 1.5 * step**2 / p.sigma_s**2
    for k, floor in [("contact_pressure", 1.0), ("friction_stress", 1.0), ("adhesion_pressure", 1.0),
                     ("real_area_fraction", 1e-12)]:
        v = out[k]
        m = v > floor                                  # 1 Pa = 1e-6 MPa
        assert m.sum() > 100
        d2 = np.diff(np.log(v[m]), 2)
        assert np.max(np.abs(d2)) < bound, (k, np.max(np.abs(d2)), bound)
        # the neighbour-to-neighbour ratio changes by less than 5 % from one step to the next
        r = v[m][1:] / v[m][:-1]
        assert np.max(np.abs(r[1:] / r[:-1] - 1)) < 0.05, k


# --------------------------------------------------------------------------------------------
# API
# --------------------------------------------------------------------------------------------

def test_only_requested_quantities_are_computed():
    p = _ep_interface()
    out = isbl.isbl_tables(np.array([0.0]), p, quantities=["adhesion_pressure"])
    assert set(out) == {"adhesion_pressure", "adhesion_pressure_bridges", "adhesion_pressure_menisci"}
    with pytest.raises(ValueError, match="unknown ISBL quantities"):
        isbl.isbl_tables(np.array([0.0]), p, quantities=["pressure"])


def test_interface_rejects_bad_parameters():
    with pytest.raises(ValueError, match="sigma_s"):
        isbl.Interface(sigma_s=0.0, eta=1e13, R=5e-6, E=1e11, H=1e9, nu=0.3, t=0, dgamma=0.1, eps=3e-10)
    with pytest.raises(ValueError, match="t"):
        isbl.Interface(sigma_s=1e-9, eta=1e13, R=5e-6, E=1e11, H=1e9, nu=0.3, t=-1e-9, dgamma=0.1, eps=3e-10)


def test_separation_grid():
    s, step = 0.35e-9, 0.01e-9
    d = isbl.separation_grid(-8.0 * s, 30e-9, step)
    assert d[0] == pytest.approx(-8 * s, rel=1e-15)  # tol: the grid's first point, one or two roundings
    # tol: steps of a grid of n multiples: rounding of x_i (|x|/step < 4e3) over the step
    np.testing.assert_allclose(np.diff(d), step, rtol=1e-9)
    assert 30e-9 <= d[-1] < 30e-9 + step


# --------------------------------------------------------------------------------------------
# Static friction of the summits: the per-summit laws integrated (friction_law of the Interface)
# --------------------------------------------------------------------------------------------

SUMMIT_LAWS = ("kogut-etsion", "brizmer-kligerman-etsion")


def test_laws_without_a_summit_form_keep_the_shear_strength_table():
    p = _paper_interface()
    d = np.linspace(-1.0, 2.0, 13) * NM
    ref = isbl.isbl_tables(d, p)
    for law in ("shear-strength", "coefficient"):
        out = isbl.isbl_tables(d, replace(p, friction_law=law))
        for k in ref:
            np.testing.assert_array_equal(out[k], ref[k])
    with pytest.raises(ValueError, match="contact.friction_law = 'stick'"):
        replace(p, friction_law="stick")


def test_elastic_kogut_etsion_equals_its_gw_closed_form():
    # every summit elastic (H huge): tau = eta c L_c (sigma_s / w_c)^e F_e(d / sigma_s) with Q*_max = c x^e
    p = replace(_elastic_interface(sigma_s=0.3489e-9, eta=1e13, R=5e-6, E=94.19e9), friction_law="kogut-etsion")
    (c, e), _ = friction.KE_SLIDING_FITS
    Lc = asperity.critical_load(p.R, p.E, p.H, p.nu)
    h = np.array([-2.0, -0.5, 0.0, 0.7, 2.0, 4.0])
    ours = isbl.isbl_tables(h * p.sigma_s, p, quantities=("friction_stress",))["friction_stress"]
    ref = p.eta * c * Lc * (p.sigma_s / p.w_c) ** e * gw_F(e, h)
    # tol: the Gauss-Legendre quadrature's error against the closed form's special functions (the module's
    # convergence test: 1e-8 level), not rounding
    np.testing.assert_allclose(ours, ref, rtol=1e-7)


@pytest.mark.parametrize("law", SUMMIT_LAWS)
@pytest.mark.parametrize("case", ["elastic-plastic", "paper"])
def test_summit_friction_against_brute_force_quadrature(case, law):
    p = replace(_ep_interface() if case == "elastic-plastic" else _paper_interface(), friction_law=law)
    summit = friction.FRICTION_LAWS[law].summit
    s, wc = p.sigma_s, p.w_c
    d_nm = [-2.0, -0.8, -0.3, 0.0, 0.4, 1.2, 2.5]
    ours = isbl.isbl_tables(np.array(d_nm) * NM, p, quantities=("friction_stress",))["friction_stress"]
    for i, dn in enumerate(d_nm):
        d = dn * NM
        x = [0.0, 1.0, 6.0, *summit.breaks(), 110.0]
        edges = sorted(min(max((d + xx * wc) / s, -40.0), 40.0) for xx in x)
        ref = sum(integrate.quad(lambda u: float(summit.force(u * s - d, p.R, p.E, p.H, p.nu))
                                 * np.exp(-0.5 * u * u) / np.sqrt(2 * np.pi), a, b, epsabs=0.0, epsrel=1e-12,
                                 limit=500)[0] for a, b in zip(edges[:-1], edges[1:]) if b > a)
        assert ours[i] == pytest.approx(p.eta * ref, rel=1e-6), (case, law, dn)


@pytest.mark.parametrize("law", SUMMIT_LAWS)
@pytest.mark.parametrize("case", ["elastic-plastic", "paper"])
def test_summit_friction_against_a_sampled_summit_population(case, law):
    # a direct sum over N summits drawn from the Gaussian (fixed seed): the mean of eta Q agrees with the
    # integral within 4 standard errors of the sample
    p = replace(_ep_interface() if case == "elastic-plastic" else _paper_interface(), friction_law=law)
    summit = friction.FRICTION_LAWS[law].summit
    z = np.random.default_rng(20261201).normal(0.0, p.sigma_s, 400_000)
    d = np.array([-0.5, 0.0, 0.5]) * p.sigma_s
    ours = isbl.isbl_tables(d, p, quantities=("friction_stress",))["friction_stress"]
    for i, dd in enumerate(d):
        q = p.eta * summit.force(z - dd, p.R, p.E, p.H, p.nu)
        se = q.std(ddof=1) / np.sqrt(q.size)
        assert se > 0 and abs(q.mean() - ours[i]) < 4.0 * se, (case, law, dd, q.mean(), ours[i], se)
        assert se < 0.01 * ours[i]  # (a sample large enough that the check means something)


@pytest.mark.parametrize("law", SUMMIT_LAWS)
def test_summit_friction_quadrature_converged(law):
    p = replace(_paper_interface(), friction_law=law)
    d = np.arange(-5 * p.sigma_s, 5 * NM, 0.01 * NM)
    default = isbl.isbl_tables(d, p, quantities=("friction_stress",))["friction_stress"]
    fine = isbl.isbl_tables(d, p, quantities=("friction_stress",), nodes=96, panels=16)["friction_stress"]
    assert _max_rel(default, fine) < 1e-8


@pytest.mark.parametrize("law", SUMMIT_LAWS)
def test_paper_scene_static_shear_stress_of_the_summit_laws(law):
    # The shear stress tau / a_r of the paper scene's tables over the separations of light contact (d from
    # 1 nm down to 0; the 9-11.4 nm protrusions sit there): the static-friction laws give each light summit
    # a tangential load nearly proportional to its area (Q ~ w^0.98 for KE, (P*)^0.65 ~ w^0.975 for BKE,
    # against A ~ w), so the shear stress is flat to within 1.5 % and falls slightly as the contact deepens:
    # it does not rise with protrusion as the paper's Fig. 7 does.
    p = replace(_paper_interface(), friction_law=law)
    d = np.linspace(1.0, 0.0, 11) * NM
    t = isbl.isbl_tables(d, p, quantities=("friction_stress", "real_area_fraction", "contact_pressure"))
    shear = t["friction_stress"] / t["real_area_fraction"]
    assert np.all(np.diff(shear) < 0)
    assert shear.max() / shear.min() - 1.0 < 0.015
    # against the shear-strength law's tau_y: KE within 1.5 % of it (its elastic fit is about tau_y A,
    # tests/physics/test_friction.py), BKE's full stick about twice it
    ratio = shear / friction.shear_strength(p.H)
    lo, hi = {"kogut-etsion": (0.985, 1.015), "brizmer-kligerman-etsion": (1.9, 2.0)}[law]
    assert np.all((ratio > lo) & (ratio < hi)), ratio


# --------------------------------------------------------------------------------------------
# Adhesion rising with penetration into the bonded layer
# --------------------------------------------------------------------------------------------

# the paper scene's interface at a rough scale (sigma_s ~ 0.5 nm, w_c ~ 1.3 nm, t = 0.75 nm)
PEN = isbl.Interface(sigma_s=0.5 * NM, eta=13.3e12, R=1.1e-6, E=94.2e9, H=1.68e9, nu=0.3, t=0.75 * NM,
                     dgamma=0.109, eps=0.3 * NM)


def _extra(p: isbl.Interface, d: np.ndarray, ws: float) -> np.ndarray:
    q = ("adhesion_pressure",)
    return (isbl.isbl_tables(d, replace(p, dgamma_solid=ws), quantities=q)["adhesion_pressure"]
            - isbl.isbl_tables(d, p, quantities=q)["adhesion_pressure"])


def test_penetration_with_the_lubricant_value_gives_todays_tables_bit_for_bit():
    """dgamma_solid = dgamma adds exactly 0 in the paper's ISBL: every table equals the one without the option."""
    d = np.linspace(-3.0, 8.0, 221) * NM
    off = isbl.isbl_tables(d, PEN)
    on = isbl.isbl_tables(d, replace(PEN, dgamma_solid=PEN.dgamma))
    assert off.keys() == on.keys()
    for k in off:
        assert np.array_equal(off[k], on[k]), k


def test_with_two_populations_each_rises_from_its_own_surface_value():
    """With bridges of their own work of adhesion, the bridges' extra is 0 exactly at dgamma_solid = dgamma_bridge
    and the menisci's at dgamma_solid = dgamma (each table column then bit for bit), and each is linear in its own
    difference: a summit's work of adhesion is dgamma_solid on both sides of touching, never below 0."""
    p = replace(PEN, dgamma_bridge=0.03)
    d = np.linspace(-3.0, 8.0, 221) * NM
    off = isbl.isbl_tables(d, p)
    at_bridge = isbl.isbl_tables(d, replace(p, dgamma_solid=0.03))
    at_meniscus = isbl.isbl_tables(d, replace(p, dgamma_solid=p.dgamma))
    assert np.array_equal(at_bridge["adhesion_pressure_bridges"], off["adhesion_pressure_bridges"])
    assert np.array_equal(at_meniscus["adhesion_pressure_menisci"], off["adhesion_pressure_menisci"])
    b1, m1 = isbl.penetration_adhesion(d, replace(p, dgamma_solid=0.05))
    b2, m2 = isbl.penetration_adhesion(d, replace(p, dgamma_solid=0.07))
    # W_s 0.05 -> 0.07: the bridges' difference 0.02 -> 0.04 (x 2), the menisci's -0.059 -> -0.039
    # tol: the same closed form times two scale factors: a few ulps of the products
    np.testing.assert_allclose(b2, 2.0 * b1, rtol=1e-12, atol=0.0)
    # tol: as above, the menisci's scale factors
    np.testing.assert_allclose(m2 * (0.05 - p.dgamma), m1 * (0.07 - p.dgamma), rtol=1e-12, atol=0.0)
    assert np.all(b1 >= 0.0) and b1.max() > 0.0 and np.all(m1 <= 0.0) and m1.min() < 0.0


def test_penetration_adhesion_is_zero_where_no_summit_reaches_the_film():
    """Only summits inside the film (z > d - t) get the extra: it is bounded by eta 2 pi R (W_s - W) P(z > d - t),
    so it vanishes out of contact (exactly 0 once the Gaussian tail underflows), and the Lennard-Jones part of the
    non-wetted summits is unchanged."""
    p, ws = PEN, 0.15
    d = np.array([1.0, 2.0, 3.0, 4.0, 6.0, 40.0]) * NM
    extra = _extra(p, d, ws)
    bound = p.eta * 2 * np.pi * p.R * (ws - p.dgamma) * 0.5 * erfc((d - p.t) / p.sigma_s / np.sqrt(2))
    assert np.all(extra >= 0) and np.all(extra <= bound * (1 + 1e-9))
    assert extra[-1] == 0.0
    assert extra[3] < 1e-9 * _extra(p, np.array([0.0]), ws)[0]     # 4 nm = 6.5 sigma_s above the film
    # the change of the table is the closed form over the summits inside the film alone
    parts = isbl.penetration_adhesion(d, replace(p, dgamma_solid=ws))
    # tol: a difference of two adhesion tables against the closed form: the cancellation costs ~table / extra eps (<1e4)
    np.testing.assert_allclose(parts[0] + parts[1], extra, rtol=1e-9, atol=1e-12 * abs(extra).max())


def test_penetration_adhesion_is_monotonic_and_linear_in_the_solid_value():
    d = np.linspace(-2.0, 3.0, 101) * NM
    values = [0.05, 0.09, 0.109, 0.12, 0.15, 0.3]
    tables = [isbl.isbl_tables(d, replace(PEN, dgamma_solid=w), quantities=("adhesion_pressure",))["adhesion_pressure"]
              for w in values]
    for lo, hi in zip(tables[:-1], tables[1:]):
        assert np.all(hi >= lo) and np.all(hi[d < 2.0 * NM] > lo[d < 2.0 * NM])
    e1, e2 = _extra(PEN, d, PEN.dgamma + 0.02), _extra(PEN, d, PEN.dgamma + 0.04)
    # tol: differences of tables linear in W_s: the cancellation costs ~table / extra eps (<1e4), no libm
    np.testing.assert_allclose(e2, 2 * e1, rtol=1e-9, atol=1e-9 * abs(e2).max())


@pytest.mark.parametrize("bridge", [None, 0.03])          # (0.03: the bridges rise from their own value)
@pytest.mark.parametrize("hardness", [1.68e9, 0.3e9])   # (0.3 GPa: w_c 0.04 nm, plastic summits cut off)
def test_penetration_adhesion_against_a_sampled_summit_population(hardness, bridge):
    """The closed form against a direct sum over 400 000 sampled summits (fixed seed): eta mean of the per-summit
    extra force 2 pi R (W(z) - W_0(z)), W_0 the summit's value at the film surface (the bridges' below touching,
    dgamma above), with no adhesion on fully plastic summits (w > 110 w_c), within four standard errors."""
    p = replace(PEN, H=hardness, dgamma_solid=0.15, dgamma_bridge=bridge)
    z = np.random.default_rng(20121).normal(0.0, p.sigma_s, 400_000)
    for d in np.array([-0.8, -0.3, 0.0, 0.3, 0.8, 1.2]) * NM:
        w0 = np.where(z < d, p.dgamma if bridge is None else bridge, p.dgamma)
        W = adhesion.penetration_work_of_adhesion(z - (d - p.t), p.t, w0, p.dgamma_solid)
        f = np.where(z - d <= asperity.X_PLASTIC * p.w_c, adhesion.meniscus_force(p.R, 1.0) * (W - w0), 0.0)
        mc, se = p.eta * f.mean(), p.eta * f.std(ddof=1) / np.sqrt(f.size)
        b, m = isbl.penetration_adhesion(np.array([d]), p)
        assert se < 0.05 * mc
        assert abs(b[0] + m[0] - mc) < 4 * se, (d / NM, b[0] + m[0], mc, se)


def test_penetration_adhesion_is_continuous_in_separation():
    """The extra (and the summed tables with it) changes by O(h) between neighbours h apart: halving h halves the
    largest step, across the population boundaries d - t, d and d + 110 w_c."""
    p = replace(PEN, dgamma_solid=0.15, H=0.3e9)
    steps = []
    for h in (0.01, 0.005):
        d = np.arange(-3.0, 3.0 + h / 2, h) * NM
        b, m = isbl.penetration_adhesion(d, p)
        total = isbl.isbl_tables(d, p, quantities=("adhesion_pressure",))["adhesion_pressure"]
        steps.append((np.abs(np.diff(b + m)).max(), np.abs(np.diff(total)).max()))
    for coarse, fine in zip(*steps):
        assert fine / coarse == pytest.approx(0.5, abs=0.03)
