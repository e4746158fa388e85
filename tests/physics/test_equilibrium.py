"""Static equilibria (pipeline.physics.equilibrium): the fold of a spring against an adhesion law, known
in closed form, found by continuation; the contact branch past it; the 2-DOF slider reduced to the same
case at its TFC point; Newton on a linear slider."""

from __future__ import annotations

from typing import Callable

import numpy as np
import pytest
from scipy.optimize import brentq

from pipeline.physics import air_bearing as ab
from pipeline.physics import equilibrium as eq


def slider_forces(*, l_f: float, l_r: float, l_c: float, friction_arm: float, k_f: float, g0: float,
                  rear: Callable[[float], float], nominal_gap: Callable[[float], float],
                  interface: Callable[[float, float], tuple[float, float]], pitch: bool = True) -> eq.Forces:
    """Generalised static forces ``R(y, mu)`` of a 2-DOF slider with a given interface law: a fixture of
    these tests of the solver (the pipeline's static start evaluates the kernel's own right-hand side).

    ``F_f = -k_f (z + l_f theta)`` (front, linear), ``F_r = rear(g_r)`` on the rear gap ``g_r = g0 + z - l_r theta``
    (e.g. :func:`pipeline.physics.air_bearing.rear_power_law`), the interface force ``F_i`` (up) and friction
    ``Q`` (along the disk's motion, at the air-bearing surface, ``friction_arm`` below the CG) at the TFC point
    ``l_c`` behind the CG, whose gap is ``g = nominal_gap(mu) + z - l_c theta`` (e.g. ``FH0 - delta``):
    ``R = (F_f + F_r + F_i, l_f F_f - l_r F_r - l_c F_i - friction_arm Q)`` (:mod:`pipeline.physics.air_bearing`;
    docs/model.md, section "Slider"). With ``pitch=False`` the state is ``(z,)``.

    Parameters
    ----------
    l_f, l_r, l_c, friction_arm [m]; k_f [N/m]; g0 : rear reference gap [m]; rear : ``g_r -> F_r`` [N]
    nominal_gap : ``mu -> `` TFC gap at the nominal attitude [m]
    interface : ``(g, mu) -> (F_i [N], Q [N])``: everything acting at the TFC point (bulge lift, adhesion,
        contact, friction) at gap ``g`` [m]
    """
    def R(y: np.ndarray, mu: float) -> np.ndarray:
        z = y[0]
        th = y[1] if pitch else 0.0
        F_f = -k_f * (z + l_f * th)
        F_r = rear(g0 + z - l_r * th)
        F_i, Q = interface(nominal_gap(mu) + z - l_c * th, mu)
        if not pitch:
            return np.array([F_f + F_r + F_i])
        return np.array([F_f + F_r + F_i, l_f * F_f - l_r * F_r - l_c * F_i - friction_arm * Q])

    return R

NM = 1e-9
# 1-DOF: a bearing spring k holds the TFC point at d0 = D - mu above the disk (mu: the protrusion); the
# adhesion A/(d + eps)^2 pulls it down (finite at contact, like the ISBL adhesion pressure); x is up.
K, A, EPS, D = 1e5, 4e-22, 0.3 * NM, 11 * NM
S_FOLD = (2 * A / K) ** (1 / 3)  # s = d + eps at the fold: d/ds [s - eps + A/(k s^2)] = 0 -> s^3 = 2A/k
MU_FOLD = D - (1.5 * S_FOLD - EPS)  # d0 = s + A/(k s^2) - eps = 1.5 s - eps at the fold
KC, DC = 2e7, 0.5 * NM  # contact spring below d_c


def forces_1dof(y, mu, contact=False):
    d = D - mu + y[0]
    F = -K * y[0] - A / (d + EPS) ** 2
    if contact and d < DC:
        F += KC * (DC - d)
    return np.array([F])


def test_fold_of_spring_against_adhesion_is_found_where_the_closed_form_puts_it():
    """Flying equilibria ``k x = -A/(d0 + x + eps)^2`` exist for ``d0 >= 1.5 (2A/k)^(1/3) - eps``: the
    continuation from the nominal state (x = 0 is the state without adhesion) follows the stable root
    and stops at that fold to the requested bracket."""
    # tol: the fold's closed form of exact decimals, a few roundings and a cube root
    assert S_FOLD == pytest.approx(2.0 * NM, rel=1e-12) and MU_FOLD == pytest.approx(8.3 * NM, rel=1e-12)
    mus = np.linspace(0.0, 10.0, 11) * NM
    br = eq.flying_branch(forces_1dof, mus, np.zeros(1), scale=[1 * NM], mu_tol=1e-6 * NM)
    assert br.fold == pytest.approx(MU_FOLD, abs=2e-6 * NM)
    assert br.mu == pytest.approx(list(mus[:9]))  # 0..8 nm reached, 9 nm is past the fold
    for mu, y in zip(br.mu, br.states):
        d0 = D - mu
        # the stable (largest) root of k (s - d0 - eps) s^2 + A = 0 in s = d + eps, by bisection
        s = brentq(lambda s: K * (s - d0 - EPS) * s**2 + A, S_FOLD, d0 + EPS, xtol=1e-24, rtol=1e-14)
        assert y[0] == pytest.approx(s - d0 - EPS, abs=1e-9 * NM)
    # the stiffness k - 2A/s^3 vanishes at the fold: the last state is nearly neutral
    assert br.last.stiffness[0, 0] < 0.01 * K


def test_past_the_fold_there_is_no_flying_equilibrium_and_the_contact_branch_is_given():
    mu = 9.0 * NM
    flying_only = eq.static_equilibrium(forces_1dof, mu, scale=[1 * NM], mu_tol=1e-4 * NM)
    assert flying_only.kind == "none" and "no flying equilibrium" in flying_only.message
    assert flying_only.fold == pytest.approx(MU_FOLD, abs=2e-4 * NM)

    def with_contact(y, m):
        return forces_1dof(y, m, contact=True)

    # the flying branch must stay above the contact criterion d >= d_c; the contact start is half way into
    # the contact spring (the test's adhesion law is singular at d = -eps, unlike the ISBL's)
    st = eq.static_equilibrium(with_contact, mu, scale=[1 * NM], mu_tol=1e-4 * NM,
                               accept=lambda y: D - mu + y[0] >= DC, contact_start=np.array([DC / 2 - (D - mu)]),
                               contact_max_step=[0.02 * NM])
    assert st.kind == "contact"
    d = brentq(lambda d: -K * (d - (D - mu)) - A / (d + EPS) ** 2 + KC * (DC - d), DC / 2, DC, xtol=1e-24,
               rtol=1e-14)
    assert st.equilibrium.y[0] == pytest.approx(d - (D - mu), abs=1e-9 * NM)
    assert st.equilibrium.stable and st.equilibrium.stiffness[0, 0] == pytest.approx(K + KC - 2 * A / (d + EPS) ** 3,
                                                                                     rel=1e-5)
    # before the fold the same call gives the flying state
    st = eq.static_equilibrium(with_contact, 7.0 * NM, scale=[1 * NM], accept=lambda y: D - 7 * NM + y[0] >= DC)
    assert st.kind == "flying" and st.equilibrium.y[0] < 0


def test_a_known_fold_gives_the_same_states_without_the_continuation():
    """:func:`branch_fold` finds the closed-form fold once; :func:`static_equilibrium` given it returns, at
    every protrusion, the state the continuation from zero gives (the same path before the fold, the same
    contact Newton past it)."""
    def with_contact(y, m):
        return forces_1dof(y, m, contact=True)

    def accept(mu):
        return lambda y: D - mu + y[0] >= DC

    fold = eq.branch_fold(forces_1dof, 20 * NM, scale=[1 * NM], step=1 * NM, mu_tol=1e-4 * NM)
    assert fold == pytest.approx(MU_FOLD, abs=2e-4 * NM)
    calls = [0]

    def counted(y, m):
        calls[0] += 1
        return with_contact(y, m)

    for mu in np.array([2.0, 7.0, 8.2, 8.4, 9.0, 10.0]) * NM:
        kw = dict(scale=[1 * NM], mu_tol=1e-4 * NM, accept=accept(mu), contact_start=np.array([DC / 2 - (D - mu)]),
                  contact_max_step=[0.02 * NM])
        calls[0] = 0
        plain = eq.static_equilibrium(counted, mu, **kw)
        n_plain = calls[0]
        calls[0] = 0
        known = eq.static_equilibrium(counted, mu, fold=fold, **kw)
        assert known.kind == plain.kind == ("flying" if mu < MU_FOLD else "contact")
        np.testing.assert_array_equal(known.equilibrium.y, plain.equilibrium.y)
        if mu > fold:  # past the fold the bracketing of the fold is skipped: fewer force evaluations
            assert calls[0] < n_plain


def paper_slider(rear: str = "linear"):
    """The paper's femto slider with the stiff-rear bearing (k_f 1.54e5, k_r 5.83e5 N/m); ``rear``: the
    linear law or the power law F_r0 [(g0/g)^2 - 1] with the same stiffness at g0 = 11 nm."""
    m, I = ab.mass_properties(0.85e-3, 0.70e-3, 0.23e-3, 4250.0)
    k_f, k_r, _ = ab.choose_stiffness(120e3, 300e3, m, I, 0.30e-3, 0.40e-3, 0.85e-3)
    g0 = 11 * NM
    law = ((lambda g: ab.rear_linear_law(g, g0, 2.0, k_r * g0 / 2, k_r)) if rear == "linear"
           else (lambda g: ab.rear_power_law(g, g0, 2.0, k_r * g0 / 2, k_r)))
    return dict(l_f=0.30e-3, l_r=0.40e-3, l_c=0.417e-3, friction_arm=0.115e-3, k_f=k_f, g0=g0, rear=law), k_r


def test_linear_slider_under_a_tfc_force_is_the_compliance_solution():
    """With linear pads and a constant force at the TFC point Newton gives ``K^-1 F``, ``K`` the pad matrix."""
    p, k_r = paper_slider()
    F = 1e-4
    R = slider_forces(**p, nominal_gap=lambda mu: 11 * NM - mu, interface=lambda g, mu: (F, 0.0))
    e = eq.newton(lambda y: R(y, 0.0), np.zeros(2))
    Kmat = ab.pad_matrix(p["k_f"], k_r, p["l_f"], p["l_r"])
    assert e.converged and e.stable
    # tol: Newton to steps below 1e-10 of the scale on a linear system: the last step and a 2x2 solve
    assert e.y == pytest.approx(np.linalg.solve(Kmat, [F, -p["l_c"] * F]), rel=1e-8)
    assert e.stiffness == pytest.approx(Kmat, rel=1e-6)
    # the friction moment -friction_arm Q pitches the nose down (theta < 0), as in the dynamics
    R = slider_forces(**p, nominal_gap=lambda mu: 11 * NM - mu, interface=lambda g, mu: (0.0, F))
    e = eq.newton(lambda y: R(y, 0.0), np.zeros(2))
    # tol: Newton to steps below 1e-10 of the scale on a linear system: the last step and a 2x2 solve
    assert e.y == pytest.approx(np.linalg.solve(Kmat, [0.0, -p["friction_arm"] * F]), rel=1e-8) and e.y[1] < 0


def test_two_dof_fold_is_the_one_dof_fold_of_the_tfc_point_compliance():
    """A 2-DOF slider with linear pads seen from the TFC point is a spring ``k_t = 1/(c^T K^-1 c)``,
    ``c = (1, -l_c)``: its adhesion fold is the closed form of the 1-DOF case with ``k_t``."""
    p, k_r = paper_slider()
    Kmat = ab.pad_matrix(p["k_f"], k_r, p["l_f"], p["l_r"])
    c = np.array([1.0, -p["l_c"]])
    k_t = 1.0 / (c @ np.linalg.solve(Kmat, c))
    s_fold = (2 * A / k_t) ** (1 / 3)
    mu_fold = D - (1.5 * s_fold - EPS)
    R = slider_forces(**p, nominal_gap=lambda mu: D - mu, interface=lambda g, mu: (-A / (g + EPS) ** 2, 0.0))
    br = eq.flying_branch(R, np.linspace(0, 10, 6) * NM, np.zeros(2), mu_tol=1e-5 * NM)
    assert br.fold == pytest.approx(mu_fold, abs=2e-5 * NM)


def test_nonlinear_rear_law_moves_the_fold_later():
    """The power-law rear pad stiffens as its gap closes under the adhesion's pull: the fold comes later
    than with the linear pad of the same nominal stiffness."""
    lin, _ = paper_slider("linear")
    pw, _ = paper_slider("power")
    folds = []
    for p in (lin, pw):
        R = slider_forces(**p, nominal_gap=lambda mu: D - mu, interface=lambda g, mu: (-A / (g + EPS) ** 2, 0.0))
        folds.append(eq.flying_branch(R, np.linspace(0, 10, 6) * NM, np.zeros(2), mu_tol=1e-5 * NM).fold)
    assert folds[1] > folds[0]
