"""Single-summit contact (pipeline.physics.asperity): Hertz / Kogut-Etsion contact (KE02) against hand values,
its regime jumps and monotonicity (docs/model.md, section "Single asperity"). The single-summit adhesion and
friction laws are tested in tests/physics/test_adhesion.py and tests/physics/test_friction.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pipeline.physics import asperity

# Hand-computed case: R = 1 um, E' = 100 GPa, H = 2 GPa, nu = 0.3 (K = 0.454 + 0.41*0.3 = 0.577)
R, E, H, NU = 1e-6, 100e9, 2e9, 0.3
K = 0.577


def test_critical_interference_hand_value():
    # w_c = (pi K H / (2 E'))^2 R = (pi * 0.577 * 0.01)^2 * 1 um = (0.01812699)^2 um = 3.285878e-10 m
    assert asperity.critical_interference(R, E, H, NU) == pytest.approx(3.285878e-10, rel=1e-6)


def test_critical_load_hand_value():
    # P_c = (2/3) pi K H R w_c = (2/3) * 1.812699 * 2e9 * 1e-6 * 3.285878e-10 = 7.941742e-7 N
    assert asperity.critical_load(R, E, H, NU) == pytest.approx(7.941742e-7, rel=1e-6)


def test_hertz_load_at_wc_equals_pc():
    # Identity: (4/3) E' sqrt(R) w_c^1.5 = (2/3) pi K H R w_c since sqrt(w_c) = pi K H sqrt(R) / (2E')
    wc = asperity.critical_interference(R, E, H, NU)
    hertz = 4 / 3 * E * np.sqrt(R) * wc**1.5
    # tol: an identity of a few roundings and sqrt/pow (libm and numpy SIMD: an ulp or two)
    assert hertz == pytest.approx(asperity.critical_load(R, E, H, NU), rel=1e-13)
    # tol: an identity of a few roundings and sqrt/pow (libm and numpy SIMD: an ulp or two)
    assert asperity.contact_load(wc, R, E, H, NU) == pytest.approx(hertz, rel=1e-13)


def test_regimes_hand_values():
    wc = asperity.critical_interference(R, E, H, NU)
    Pc = asperity.critical_load(R, E, H, NU)
    Ac = np.pi * R * wc
    x = np.array([0.5, 3.0, 50.0, 200.0])
    P = asperity.contact_load(x * wc, R, E, H, NU)
    A = asperity.contact_area(x * wc, R, E, H, NU)
    # KE02 fits as written in docs/model.md, section "Single asperity"
    # tol: the fits as written: a few roundings and pow (libm and numpy SIMD pow: a few ulps), 1e-13 = 450 eps
    np.testing.assert_allclose(P, [4 / 3 * E * np.sqrt(R) * (0.5 * wc) ** 1.5, 1.03 * Pc * 3**1.425,
                                   1.40 * Pc * 50**1.263, H * 2 * np.pi * R * 200 * wc], rtol=1e-13)
    # tol: the fits as written: a few roundings and pow (libm and numpy SIMD pow: a few ulps), 1e-13 = 450 eps
    np.testing.assert_allclose(A, [np.pi * R * 0.5 * wc, 0.93 * Ac * 3**1.136, 0.94 * Ac * 50**1.146,
                                   2 * np.pi * R * 200 * wc], rtol=1e-13)


def test_no_contact_no_load():
    w = np.array([-1e-9, -1e-12, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # no 'invalid value in power' from unused branches
        assert np.all(asperity.contact_load(w, R, E, H, NU) == 0)
        assert np.all(asperity.contact_area(w, R, E, H, NU) == 0)


def _ratio(fun, x, rel=1e-12):
    wc = asperity.critical_interference(R, E, H, NU)
    lo, hi = fun(x * wc * (1 - rel), R, E, H, NU), fun(x * wc * (1 + rel), R, E, H, NU)
    return float(hi / lo)


def test_ke_jumps_at_x1():
    # P(1+)/P(1-) = 1.03 (the published fit starts at 1.03 P_c while Hertz gives exactly P_c at w_c)
    # tol: the ratio of the fits at x = 1 +- a tiny step: 1.03 up to the step's first-order change
    assert _ratio(asperity.contact_load, 1.0) == pytest.approx(1.03, rel=1e-9)
    # A(1+)/A(1-) = 0.93 (A_c = pi R w_c is the Hertz area at w_c)
    # tol: the ratio of the fits at x = 1 +- a tiny step: 1.03 up to the step's first-order change
    assert _ratio(asperity.contact_area, 1.0) == pytest.approx(0.93, rel=1e-9)


def test_ke_jumps_at_x6():
    # (1.40/1.03) 6^(1.263-1.425) = 1.016788 ; (0.94/0.93) 6^(1.146-1.136) = 1.029026
    assert _ratio(asperity.contact_load, 6.0) == pytest.approx(1.016788, rel=1e-6)
    assert _ratio(asperity.contact_area, 6.0) == pytest.approx(1.029026, rel=1e-6)


def test_ke_jumps_at_x110():
    # P(110+) = H 2 pi R 110 w_c = (330/K) P_c; P(110-) = 1.40 P_c 110^1.263
    # -> ratio 330 / (0.577 * 1.40 * 110^1.263) = 1.078776 (for nu = 0.3)
    assert _ratio(asperity.contact_load, 110.0) == pytest.approx(1.078776, rel=1e-6)
    # A(110+) = 220 A_c; A(110-) = 0.94 A_c 110^1.146 -> 220 / (0.94 * 110^1.146) = 1.071171
    assert _ratio(asperity.contact_area, 110.0) == pytest.approx(1.071171, rel=1e-6)


def test_load_and_area_increase_within_each_regime():
    wc = asperity.critical_interference(R, E, H, NU)
    for lo, hi in [(0, 1), (1, 6), (6, 110), (110, 1000)]:
        x = np.linspace(lo, hi, 401)[1:-1]
        assert np.all(np.diff(asperity.contact_load(x * wc, R, E, H, NU)) > 0)
        assert np.all(np.diff(asperity.contact_area(x * wc, R, E, H, NU)) > 0)


def test_vectorised_shapes():
    # an array of interferences gives the array of each one's law, element for element, in its shape
    # (the first is a separation: no load, no area)
    w = np.linspace(-1e-9, 1e-7, 12).reshape(3, 4)
    for law in (asperity.contact_load, asperity.contact_area):
        out = law(w, R, E, H, NU)
        assert out.shape == (3, 4) and out[0, 0] == 0.0
        assert np.array_equal(out, [[float(law(x, R, E, H, NU)) for x in row] for row in w])
