"""Gas flow in a nanometre gap (pipeline.physics.gas_flow): the Fukui-Kaneko Poiseuille flow rate against its
slip limit and its continuity, the Patir-Cheng flow factors against their published values and limits, and
the mean gap against quadrature."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate, stats

from pipeline.physics import gas_flow as gf


def test_fk_flow_rate_gives_first_order_slip_with_the_kinetic_coefficient_at_small_knudsen():
    """``Q = 1 + 6 x 1.1466 Kn + O(Kn^2)``: the slope of ``(Q - 1) / (6 Kn)`` tends to 2 x 1.0162 / sqrt(pi)
    linearly in Kn, so Boltzmann and first-order slip (coefficient 1) agree to first order as Kn -> 0."""
    assert gf.SLIP_FK == pytest.approx(1.1466, abs=1e-4)
    kn = np.array([1e-2, 5e-3, 2.5e-3])
    q, _ = gf.poiseuille_factor(kn)
    err = (q - 1.0) / (6.0 * kn) - gf.SLIP_FK
    assert np.all(np.abs(err) < 0.14)
    np.testing.assert_allclose(err[:-1] / err[1:], 2.0, rtol=0.02)  # O(Kn)
    fo = 1.0 + 6.0 * kn
    assert np.all(np.abs(q / fo - 1.0) < 0.01)  # within 1 % of first-order slip at Kn <= 0.01
    assert abs(q[-1] / fo[-1] - 1.0) < abs(q[0] / fo[0] - 1.0) / 3.5


def test_fk_flow_rate_pieces_and_blend():
    """The published pieces hold away from their joins (value at D = 1 and 10 by hand); the blend at the joins
    is continuous with a derivative that matches a finite difference everywhere."""
    D = np.array([1.0, 10.0, 0.05])
    expected = [0.13852 + 1.25087 + 0.15653 - 0.00969, 10 / 6 + 1.0162 + 0.10653 - 0.021354,
                -2.22919 * 0.05 + 2.10673 + 0.01653 / 0.05 - 0.0000694 / 0.0025]
    # tol: sums of the fit's terms of exact decimals, a few roundings (cancellation < 10)
    np.testing.assert_allclose(gf.fk_flow_rate(D)[0], expected, rtol=1e-12)
    D = np.geomspace(0.02, 50.0, 20001)
    Q, dQ = gf.fk_flow_rate(D)
    # no jump (the raw pieces jump by up to 3e-3): each step is its trapezoidal slope times the step
    assert np.max(np.abs(np.diff(Q) - 0.5 * (dQ[1:] + dQ[:-1]) * np.diff(D)) / Q[:-1]) < 1e-6
    fd = np.gradient(Q, D)
    np.testing.assert_allclose(dQ[1:-1], fd[1:-1], rtol=5e-3, atol=1e-4)
    q, dq = gf.poiseuille_factor(np.array([0.3, 1.0, 3.0]))
    h = 1e-6
    qp, _ = gf.poiseuille_factor(np.array([0.3, 1.0, 3.0]) * (1 + h))
    qm, _ = gf.poiseuille_factor(np.array([0.3, 1.0, 3.0]) * (1 - h))
    np.testing.assert_allclose(dq, (qp - qm) / (2 * h * np.array([0.3, 1.0, 3.0])), rtol=1e-6)
    assert np.all(q > 1.0 + 6.0 * np.array([0.3, 1.0, 3.0]))  # more flow than Burgdorfer's slip at Kn 0.3-3


def test_mean_gap_is_the_mean_of_the_open_local_gap():
    """``h_T / sigma = E[max(H - z, 0)]`` for a standard normal ``z``, by quadrature; 1/sqrt(2 pi) at H = 0."""
    for H in (-1.0, 0.0, 0.5, 1.0, 3.0):
        ref = integrate.quad(lambda z: (H - z) * stats.norm.pdf(z), -np.inf, H)[0]
        # tol: quad of a smooth Gaussian integrand against the closed form: measured 3e-15 (its estimate 1e-8 is loose)
        assert gf.mean_gap(H) == pytest.approx(ref, rel=1e-10)
    assert gf.mean_gap(0.0) == pytest.approx(1 / np.sqrt(2 * np.pi))
    assert abs(gf.mean_gap(3.0) - 3.0) < 5e-4 and abs(gf.mean_gap(5.0) - 5.0) < 1e-7


def test_patir_cheng_flow_factors_values_and_limits():
    """Published forms at gamma = 1: phi_x(1) = 1 - 0.9 e^-0.56, Phi_s(1) = 1.899 e^(-0.92 + 0.05); the two
    pieces of Phi_s meet at H = 5 within 0.1 %; both factors tend to the smooth gap (phi_x -> 1, phi_s -> 0)
    for H >> 3; phi_x falls to 0 at H = 0 (percolation), continuously at H = 0.5; phi_s scales with
    V_r1 - V_r2 = 2 share - 1."""
    # tol: the same exp of the same argument: libm and numpy's SIMD exp differ by an ulp at most
    assert gf.pressure_flow_factor(1.0) == pytest.approx(1 - 0.9 * np.exp(-0.56), rel=1e-14)
    # tol: the same exp of the same argument: libm and numpy's SIMD exp differ by an ulp at most
    assert gf.shear_flow_factor(1.0) == pytest.approx(1.899 * np.exp(-0.87), rel=1e-14)
    lo = 1.899 * 5**0.98 * np.exp(-0.92 * 5 + 0.05 * 25)
    assert lo == pytest.approx(1.126 * np.exp(-1.25), rel=1e-3)
    assert abs(1 - gf.pressure_flow_factor(8.0)) < 0.011 and abs(1 - gf.pressure_flow_factor(12.0)) < 1.1e-3
    assert gf.shear_flow_factor(20.0) < 0.008 and gf.shear_flow_factor(40.0) < 6e-5
    assert gf.pressure_flow_factor(0.0) == 0.0
    # tol: continuity at H = 0.5: the law's change over 1e-9 of H is of order 1e-9 (and libm ulps)
    assert gf.pressure_flow_factor(0.5 - 1e-9) == pytest.approx(gf.pressure_flow_factor(0.5), rel=1e-8)
    assert gf.shear_flow_factor(1.0, 0.5) == 0.0
    # tol: a linear factor 2 share - 1 = 0.5, exact, times the same law
    assert gf.shear_flow_factor(1.0, 0.75) == pytest.approx(0.5 * gf.shear_flow_factor(1.0), rel=1e-14)


def test_rough_gap_couette_gap_has_a_floor_and_tends_to_the_nominal_gap():
    r = gf.RoughGap(sigma=0.52e-9, disk_share=1.0, wet_gap=0.75e-9)
    s = r.sigma
    assert r.couette_gap(0.0) == pytest.approx(s / np.sqrt(2 * np.pi))  # the floor: h_T, phi_s(0) = 0
    c = r.couette_gap(np.array([1.0, 3.0, 10.0, 30.0]) * s)
    assert np.all(np.diff(c) > 0)
    assert c[-1] / (30 * s) - 1 < 3e-4 and c[0] > 1.8 * s  # the disk's valleys carry air at H = 1
    assert r.air_fraction(0.75e-9) == pytest.approx(0.5)  # half closed at the wetting gap
    assert 1 - r.air_fraction(11e-9) < 1e-60
    with pytest.raises(ValueError, match="disk_share in"):
        gf.RoughGap(sigma=0.5e-9, disk_share=0.3)
    with pytest.raises(ValueError, match="sigma > 0"):
        gf.RoughGap(sigma=0.0)
