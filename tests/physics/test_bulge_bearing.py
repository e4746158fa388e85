"""The bulge's air bearing (pipeline.physics.bulge_bearing): the p h = const closed form against quadrature, its
limits and its compiled stiffness, and the lift at zero protrusion."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from scipy import integrate

from pipeline.physics import bulge_bearing as bb
from bulge_cases import A_SEMI, B_SEMI, NM, P_PAD, PAB, solve


# ---- the p h = const limit ------------------------------------------------------------------------

def test_zero_lift_at_zero_protrusion():
    g = np.array([0.1, 1.0, 11.0]) * NM
    for profile in bb.PROFILES:
        F, k = bb.ph_lift(g, 0.0, P_PAD, A_SEMI, B_SEMI, profile)
        assert np.all(F == 0.0) and np.all(k == 0.0)
    r = solve(g, 0.0)
    assert np.all(r["lift"] == 0.0)
    # and continuously so: the lift is linear in a small protrusion, F ~ p_pad pi a b (2/3) delta/g (ellipsoid)
    F, _ = bb.ph_lift(2 * NM, 1e-4 * NM, P_PAD, A_SEMI, B_SEMI, "ellipsoid")
    assert F == pytest.approx(PAB * 2 / 3 * 1e-4 / 2.0001, rel=1e-4)


def footprint_average(g: float, delta: float, profile: str) -> float:
    """``<h_pad/h - 1>`` over the ellipse by adaptive 2-D quadrature in polar coordinates of the scaled plane."""
    hp = g + delta

    def integrand(r, t):  # X = r cos t, Y = r sin t, u = r^2; dA = a b r dr dt
        h = bb.gap_profile(np.array(r * r), g, delta, profile)
        return (hp / h - 1.0) * r

    val, _ = integrate.dblquad(integrand, 0, 2 * np.pi, 0, 1, epsabs=1e-13, epsrel=1e-11)
    return val / np.pi


@pytest.mark.parametrize("profile", ["ellipsoid", "paraboloid"])
@pytest.mark.parametrize("g_nm, delta_nm", [(1.0, 10.0), (0.05, 11.0), (5.0, 3.0), (11.0, 0.05), (2.0, 0.01)])
def test_closed_form_equals_quadrature_of_the_footprint_average(profile, g_nm, delta_nm):
    F, _ = bb.ph_lift(g_nm * NM, delta_nm * NM, P_PAD, A_SEMI, B_SEMI, profile)
    # tol: adaptive 2-D quadrature of the footprint average against the closed form: its error well under 1e-8
    assert F / PAB == pytest.approx(footprint_average(g_nm * NM, delta_nm * NM, profile), rel=1e-8)


@pytest.mark.parametrize("profile, slope, const", [("ellipsoid", 2.0, -3.0), ("paraboloid", 1.0, -1.0)])
def test_lift_grows_only_logarithmically_as_the_gap_closes(profile, slope, const):
    """As ``g -> 0``: ``F/(p_pad pi a b) -> slope ln((g + delta)/g) + const`` with an error
    ``~ slope eps ln(1/eps)`` (ellipsoid ``4 eps L``, paraboloid ``eps L``), ``eps = g/(g + delta)``."""
    delta = 10 * NM
    g = delta * np.array([1e-2, 1e-3, 1e-4, 1e-5])
    F, k = bb.ph_lift(g, delta, P_PAD, A_SEMI, B_SEMI, profile)
    L = np.log((g + delta) / g)
    err = F / PAB - (slope * L + const)
    eps = g / (g + delta)
    assert np.all(np.abs(err) < 1.05 * slope**2 * eps * L) and np.all(np.abs(err) > 0.9 * slope**2 * eps * L)
    # per decade of gap the lift gains slope ln 10 (times p_pad pi a b), and the stiffness is ~ slope/g
    assert np.diff(F / PAB)[-1] == pytest.approx(slope * np.log(10), rel=1e-3)
    assert k[-1] * g[-1] / PAB == pytest.approx(slope, rel=1e-3)


@njit(cache=True)
def _kernel_like(g, delta, profile):
    """What the kernel will do: call the compiled law from compiled code."""
    return bb.ph_force_stiffness(g, delta, 1e6, 3e-6, 25e-6, profile, 0.05e-9)


@pytest.mark.parametrize("profile", ["ellipsoid", "paraboloid"])
def test_compiled_stiffness_is_minus_the_derivative_of_the_lift(profile):
    code = bb.PROFILES[profile].behaviour
    for delta_nm in (0.01, 0.5, 3.0, 9.6, 11.0, 15.0):  # 0.01 nm at 11 nm gap: the series branch
        for g_nm in (0.06, 0.3, 1.0, 1.5, 2.0, 5.0, 11.0):
            g, dl = g_nm * NM, delta_nm * NM
            F, k = _kernel_like(g, dl, code)
            h = 1e-5 * g
            fd = -(_kernel_like(g + h, dl, code)[0] - _kernel_like(g - h, dl, code)[0]) / (2 * h)
            # tol: a central difference at h = 1e-5 g: truncation (h/g)^2 = 1e-10 and rounding eps g/h = 2e-11
            assert k == pytest.approx(fd, rel=1e-7), (delta_nm, g_nm)
            assert k > 0
            # tol: the same compiled law, called from compiled code or through its loop: the same operations
            assert [F, k] == pytest.approx([float(v) for v in bb.ph_lift(g, dl, 1e6, 3e-6, 25e-6, profile, 0.05e-9)],
                                           rel=1e-15)
    # below the floor the force is held and the stiffness vanishes
    F0, _ = _kernel_like(0.05 * NM, 10 * NM, code)
    assert _kernel_like(-0.3 * NM, 10 * NM, code) == (F0, 0.0)


def test_closed_form_series_and_logarithm_branches_meet():
    """At ``x = delta/(g + delta) = 0.01`` the Taylor series and the closed form agree (no jump)."""
    for code in (bb.PARABOLOID, bb.ELLIPSOID):
        lo, hi = bb.ph_shape(0.01 * (1 - 1e-12), code), bb.ph_shape(0.01 * (1 + 1e-12), code)
        # tol: series and closed form at their join: the series' truncation, under 1e-12
        assert lo[0] == pytest.approx(hi[0], rel=1e-10) and lo[1] == pytest.approx(hi[1], rel=1e-10)


def test_a_profile_it_does_not_know_is_refused():
    with pytest.raises(ValueError, match="profile"):
        bb.ph_lift(1 * NM, 10 * NM, P_PAD, A_SEMI, B_SEMI, "cone")
