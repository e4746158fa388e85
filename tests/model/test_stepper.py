"""The integrator's compiled helpers (pipeline.model.stepper): the cubic Hermite interpolant of a step
(exact for cubics), the Hermite coefficients of the separation over a step and their interior extrema in
closed form (the roots of the derivative in (0, 1)), and the scaled RMS error norm of the embedded error
(docs/model.md, section "Integrator")."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.model import stepper


def _cubic(t):
    return 2.0 * t**3 - 3.0 * t**2 + 0.5 * t + 1.0


def _dcubic(t):
    return 6.0 * t**2 - 6.0 * t + 0.5


@pytest.mark.parametrize("t0, h", [(0.0, 1.0), (0.3, 0.25), (-2.0, 1e-3)])
def test_hermite_is_exact_for_a_cubic(t0, h):
    y0, f0 = np.array([_cubic(t0), 0.0]), np.array([_dcubic(t0), 0.0])
    y1, f1 = np.array([_cubic(t0 + h), 0.0]), np.array([_dcubic(t0 + h), 0.0])
    for frac in (0.0, 0.2, 0.5, 0.9, 1.0):
        # tol: a cubic's Hermite interpolant is the cubic: tens of roundings
        assert stepper._hermite(y0, f0, y1, f1, h, frac, 0) == pytest.approx(_cubic(t0 + frac * h), rel=1e-12,
                                                                             abs=1e-12)


def test_separation_coefficients_reproduce_the_cubic():
    # d(t0 + frac h) for frac in [0, 1] as a frac^3 + b frac^2 + c frac + e
    t0, h = 0.1, 0.7
    a, b, c, e = stepper._dcubic(_cubic(t0), _dcubic(t0), _cubic(t0 + h), _dcubic(t0 + h), h)
    for frac in np.linspace(0.0, 1.0, 7):
        # tol: a cubic's Hermite interpolant is the cubic: tens of roundings
        assert ((a * frac + b) * frac + c) * frac + e == pytest.approx(_cubic(t0 + frac * h), rel=1e-12)


@pytest.mark.parametrize("abc, expected", [
    ((1.0, -1.5, 0.5), (2, 0.5 - np.sqrt(3) / 6, 0.5 + np.sqrt(3) / 6)),  # 3x^2 - 3x + 0.5: both inside
    ((0.0, 1.0, -1.0), (1, 0.5, 0.0)),                                   # a quadratic: 2x - 1
    ((0.0, 0.0, 1.0), (0, 0.0, 0.0)),                                    # a line: no extremum
    ((1.0, 0.0, 1.0), (0, 0.0, 0.0)),                                    # 3x^2 + 1 > 0
    ((1.0, -3.0, 0.0), (0, 0.0, 0.0)),                                   # roots 0 and 2: neither inside
    ((1.0, -2.25, 1.5), (1, 0.5, 0.0)),                                  # roots 0.5 and 1: only 0.5 inside
])
def test_interior_extrema_are_the_roots_in_the_open_step(abc, expected):
    n, x1, x2 = stepper._extrema(*abc)
    assert n == expected[0]
    # tol: quadratic roots of exact coefficients, a few roundings and a sqrt
    assert (x1, x2) == pytest.approx(expected[1:], rel=1e-12, abs=1e-15)
    if n:
        a, b, c = abc
        for x in (x1, x2)[:n]:
            assert abs(3 * a * x * x + 2 * b * x + c) < 1e-12


def test_error_norm_is_the_scaled_rms():
    y, ynew = np.array([1.0, -4.0, 0.0]), np.array([3.0, 2.0, 0.0])
    err = np.array([0.1, 0.2, 5.0])
    atol, rtol = np.array([0.01, 0.02, 1.0]), 0.1
    scale = atol + rtol * np.maximum(np.abs(y), np.abs(ynew))   # 0.31, 0.42 (the third is ignored: ns = 2)
    expected = np.sqrt(np.mean((err[:2] / scale[:2]) ** 2))
    # tol: the same rms formula, a few roundings apart
    assert stepper.error_norm(y, ynew, err, atol, rtol, 2) == pytest.approx(expected, rel=1e-14)
    assert stepper.error_norm(y, ynew, np.zeros(3), atol, rtol, 3) == 0.0
