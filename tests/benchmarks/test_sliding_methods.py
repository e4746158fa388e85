"""The formulas of benchmarks/sliding_methods.py, whose numbers docs/kernel.md quotes: the phi functions against
their closed forms, DP5 and its Lawson and ETDRK4 forms exact or at their orders on linear test problems, and the
interpolants at their orders (the quintic Hermite exact on quintics)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from benchmarks import sliding_methods as sm


class _Linear:
    """``y' = L y + g(t)``: the methods' case (its ``f``), with a solution in closed form."""

    def __init__(self, L: np.ndarray, g=lambda t: 0.0):
        self.L, self.g = L, g

    def f(self, t: float, y: np.ndarray) -> np.ndarray:
        return self.L @ y + self.g(t)


def test_the_phi_functions_are_their_closed_forms():
    """For a scalar ``z``: ``phi_1 = (e^z - 1)/z``, ``phi_2 = (e^z - 1 - z)/z^2``,
    ``phi_3 = (e^z - 1 - z - z^2/2)/z^3``."""
    for z in (-2.0, -0.3, 0.7):
        e, p1, p2, p3 = (float(m[0, 0]) for m in sm._phi(np.array([[z]]), 3))
        ez = np.exp(z)
        closed = [ez, (ez - 1) / z, (ez - 1 - z) / z ** 2, (ez - 1 - z - z ** 2 / 2) / z ** 3]
        # tol: scipy's expm (Pade, ~1e-15) against closed forms whose cancellation costs up to |z|^-3 roundings
        assert [e, p1, p2, p3] == pytest.approx(closed, rel=1e-10)


def _oscillator(omega: float) -> np.ndarray:
    return np.array([[0.0, 1.0], [-omega ** 2, 0.0]])


def test_the_exponential_forms_are_exact_on_their_linear_part():
    """With ``L`` the whole (linear) right-hand side the Lawson and ETDRK4 steps are the exact flow ``e^(hL) y``,
    at ``h omega = 3``, where DP5 itself grows by 44 % a step."""
    L = _oscillator(2.0)
    case = _Linear(L)
    y0, h = np.array([1.0, 0.5]), 1.5
    exact = expm(h * L) @ y0
    np.testing.assert_allclose(sm.dp5_step(case, 0.0, y0, case.f(0.0, y0), h, L)[0], exact, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sm.etdrk4_step(case, 0.0, y0, h, L), exact, rtol=0, atol=1e-12)


def test_dp5_grows_on_the_undamped_spring_as_docs_kernel_md_says():
    """One step of the kernel's DP5 tableau on ``z'' = -z`` at ``h omega = y`` grows the oscillation's amplitude by
    ``|R(iy)| - 1``, ``R(z) = 1 + z + ... + z^5/120 + z^6/600`` (Hairer & Wanner, *Solving ODEs II*, IV.2, DOPRI5):
    the values docs/kernel.md quotes for the contact cap (section "Fewer steps in sliding")."""
    case = _Linear(_oscillator(1.0))
    quoted = {0.5: -3.2e-6, 1.0: 1.4e-6, 1.2: 3.1e-4, 1.5: 3.0e-3, 2.0: 3.2e-2, 3.0: 0.44}
    for y, growth in quoted.items():
        y0 = np.array([1.0, 0.0])
        y1 = sm.dp5_step(case, 0.0, y0, case.f(0.0, y0), y)[0]
        amplitude = float(np.hypot(*y1))  # (|(z, z')| is conserved by the exact flow at omega = 1)
        R = sum((1j * y) ** k / math.factorial(k) for k in range(6)) + (1j * y) ** 6 / 600
        assert amplitude - 1 == pytest.approx(abs(R) - 1, rel=1e-6, abs=1e-13)
        assert amplitude - 1 == pytest.approx(growth, rel=0.05)


def _order(step, h0: float) -> float:
    """Observed order of a one-step method from its global error at ``t = 1`` with ``h0`` and ``h0 / 2``, on
    ``y' = -y + sin(3 t)`` (``L = -1`` where the method takes one)."""
    L = np.array([[-1.0]])
    case = _Linear(L, lambda t: np.array([np.sin(3 * t)]))

    def exact(t):  # y(0) = 1
        return (np.exp(-t) * (1 + 3 / 10) + (np.sin(3 * t) - 3 * np.cos(3 * t)) / 10)

    errs = []
    for h in (h0, h0 / 2):
        y, t = np.array([1.0]), 0.0
        for _ in range(round(1 / h)):
            y = step(case, t, y, h, L)
            t += h
        errs.append(abs(y[0] - exact(1.0)))
    return float(np.log2(errs[0] / errs[1]))


def test_the_methods_have_their_orders():
    """DP5 and its Lawson form of order 5, ETDRK4 of order 4 (Cox & Matthews 2002), on a forced linear problem."""
    dp5 = _order(lambda c, t, y, h, L: sm.dp5_step(c, t, y, c.f(t, y), h)[0], 0.1)
    lawson = _order(lambda c, t, y, h, L: sm.dp5_step(c, t, y, c.f(t, y), h, L)[0], 0.1)
    etd = _order(sm.etdrk4_step, 0.1)
    assert 4.5 < dp5 < 5.6 and 4.5 < lawson < 5.6  # (measured: 4.71, 4.99)
    assert 3.7 < etd < 4.6  # (measured: 4.00)


def test_the_interpolants_have_their_orders():
    """On ``z'' = -z`` (``z = cos t``) through one exact DP5-like step's ends: the cubic Hermite errs ``O(h^4)``,
    the quintic Hermite of the positions ``O(h^6)``; DP5's continuous extension from DP5's stages ``O(h^5)``; and the
    quintic is exact on a quintic polynomial."""
    case = _Linear(np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0]]))
    y0 = np.array([1.0, 0.0, 0.0, 1.0])  # z = cos t, theta = sin t

    def errors(h):
        y1, k = sm.dp5_step(case, 0.0, y0, case.f(0.0, y0), h)
        x = 0.37
        exact = np.cos(x * h)
        return (abs(sm._hermite(y0, k[0], y1, k[6], h, x)[0] - exact),
                abs(sm._quintic(y0, k[0], y1, k[6], h, x)[0] - exact),
                abs(sm._continuous(y0, y1, k, h, x)[0] - exact))

    e1, e2 = np.array(errors(0.4)), np.array(errors(0.2))
    orders = np.log2(e1 / e2)
    assert 3.6 < orders[0] < 4.4  # cubic Hermite: local error O(h^4)
    assert orders[2] > 4.6  # DP5's continuous extension: O(h^5)
    assert orders[1] > 5.5  # the quintic: O(h^6) in the interpolation, on DP5's O(h^6) ends (measured 5.97)
    # exact on a quintic z(t) (its rate and acceleration given exactly at the ends)
    c = np.array([0.3, -1.0, 0.5, 2.0, -0.7, 0.9])  # z = sum c_i t^i
    z = np.polynomial.Polynomial(c)
    h = 0.8
    ya = np.array([z(0.0), 0.0, z.deriv()(0.0), 0.0])
    yb = np.array([z(h), 0.0, z.deriv()(h), 0.0])
    fa = np.array([z.deriv()(0.0), 0.0, z.deriv(2)(0.0), 0.0])
    fb = np.array([z.deriv()(h), 0.0, z.deriv(2)(h), 0.0])
    for x in (0.1, 0.5, 0.93):
        assert sm._quintic(ya, fa, yb, fb, h, x)[0] == pytest.approx(z(x * h), abs=1e-13)


def test_the_contact_mode_is_the_fast_pair_of_the_jacobian():
    """On two coupled undamped oscillators (``M x'' = -K x``, frequencies far apart) the contact mode's part acts as
    the Jacobian on the fast mode's two eigenvectors and as zero on the slow mode's."""
    K = np.array([[4.0e4 + 1.0, -1.0], [-1.0, 2.0]])
    J = np.block([[np.zeros((2, 2)), np.eye(2)], [-K, np.zeros((2, 2))]])
    lam, V = np.linalg.eig(J)
    L = sm.contact_mode(J)
    fast = np.abs(lam) > 100.0
    assert fast.sum() == 2
    np.testing.assert_allclose(L @ V[:, fast], J @ V[:, fast], atol=1e-9 * np.abs(lam).max())
    np.testing.assert_allclose(L @ V[:, ~fast], 0.0, atol=1e-9 * np.abs(lam).max())
