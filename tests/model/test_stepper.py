"""The integrator's compiled helpers (pipeline.model.stepper): the cubic Hermite interpolant of a step
(exact for cubics), the Hermite coefficients of the separation over a step and their interior extrema in
closed form (the roots of the derivative in (0, 1)), the scaled RMS error norm of the embedded error, and one
step against the Dormand-Prince sums of the right-hand side called on its own (docs/model.md, section
"Integrator")."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.model import dynamics as dyn, kernel_inputs, piecewise, running, stepper
from slider_scenes import ALL, NM, build, make_scene


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


def _dormand_prince(f, t, y, k1, h):
    """One Dormand-Prince 5(4) step from the right-hand side ``f(t, y)``, in numpy, the tableau's sums in the
    order the step writes them: ``ynew``, ``k7``, ``err``."""
    s = stepper
    k2 = f(t + h / 5, y + h * s.A21 * k1)
    k3 = f(t + 3 * h / 10, y + h * (s.A31 * k1 + s.A32 * k2))
    k4 = f(t + 4 * h / 5, y + h * (s.A41 * k1 + s.A42 * k2 + s.A43 * k3))
    k5 = f(t + 8 * h / 9, y + h * (s.A51 * k1 + s.A52 * k2 + s.A53 * k3 + s.A54 * k4))
    k6 = f(t + h, y + h * (s.A61 * k1 + s.A62 * k2 + s.A63 * k3 + s.A64 * k4 + s.A65 * k5))
    ynew = y + h * (s.B1 * k1 + s.B3 * k3 + s.B4 * k4 + s.B5 * k5 + s.B6 * k6)
    k7 = f(t + h, ynew)
    return ynew, k7, h * (s.E1 * k1 + s.E3 * k3 + s.E4 * k4 + s.E5 * k5 + s.E6 * k6 + s.E7 * k7)


@pytest.mark.parametrize("in_contact", [False, True])
def test_a_step_makes_the_right_hand_sides_operations_at_each_stage(in_contact):
    # the step's right-hand side, inlined in its loop over the stages with the disk looked up before the first
    # stage, against the Python entry's (dynamics.rhs: forces.rhs_slots, compiled on its own) in the tableau's
    # sums: the same operations in the same order, in and out of contact, with k1 given (FSAL) and evaluated by
    # the step (fresh). Equal to their last bits: the kernel fuses products and sums (compiled.OPTIONS), each
    # compiled function where LLVM finds them, numpy's sums do not
    model = build(make_scene(ALL, dmw={"rms_nm": 0.163}))
    p, tab, var = kernel_inputs.run_parameters(model, 11 * NM)
    slots = (*tab, *var._replace(rear_law=dyn._slots(tab, var)[6])[:-1])  # (heating: the loop's slot, not the step's)

    def f(t, y):
        out = np.empty(y.size)
        dyn.rhs(t, y, p, tab, var, in_contact, out)
        return out

    y = running.start(model, 11 * NM)[0] + np.array([0.3, -2e-5, 1e-4, 0.2]) * NM
    t, h = 3.7e-4, 4.3e-7  # (a step across a DMW knot: the disk of its stages on two pieces)
    ynew, k7, err, tmp, k2, k3, k4, k5, k6 = (np.empty(4) for _ in range(9))
    w_end = np.empty(2)
    for fresh in (False, True):
        k1 = f(t, y) if not fresh else np.full(4, np.nan)
        n = stepper.step(t, y, k1, h, p, in_contact, np.bool_(fresh), ynew, k7, err, tmp, k2, k3, k4, k5, k6,
                         w_end, *slots)
        # the disk at the step's end: the separation's lookup there, bit for bit (inside the spline)
        np.testing.assert_array_equal(w_end, np.concatenate(piecewise.disk_history(tab.dmw, p, np.array([t + h]))))
        assert n == (7 if fresh else 6)
        # tol: a few roundings of each term apart (fused or not); the states' and rates' sums do not cancel here
        np.testing.assert_allclose(k1, f(t, y), rtol=1e-13, atol=0)
        want = _dormand_prince(f, t, y, k1, h)
        for got, expected in zip((ynew, k7), want[:2]):
            np.testing.assert_allclose(got, expected, rtol=1e-13, atol=0)  # tol: as above
        # the error estimate cancels (its weights sum to zero): its rounding is that of its terms, h |E_i k_i|
        terms = h * np.abs(np.array([stepper.E1, stepper.E3, stepper.E4, stepper.E5, stepper.E6, stepper.E7]))[:, None]
        scale = (terms * np.abs(np.array([k1, k3, k4, k5, k6, k7]))).sum(axis=0)
        assert np.all(np.abs(err - want[2]) <= 64 * np.finfo(float).eps * scale)
        assert np.all(np.abs(err) > 1e3 * np.finfo(float).eps * scale)  # (an estimate above its rounding)
    assert np.all(err != 0.0) and not np.array_equal(k7, k1)  # (a step that moved the state)


@pytest.mark.parametrize("order", [1, 3])
def test_the_extrema_are_skipped_only_where_they_lie_within_the_bound(order):
    """``extrema_matter`` says the interior extrema of ``d`` cannot matter only where ``d`` over the step, sampled
    finely on the state's Hermite cubic and the DMW record (a spline, and a linear record with kinks), stays within
    the window's extremes and on the mode's side of ``k sigma``; and it does skip where the window's extremes are
    wide (so a bound that is too loose, or one without the linear record's kinks, fails here)."""
    rng = np.random.default_rng(3)
    hd = 250e-9
    w = 1e-9 * np.cumsum(rng.normal(size=400)) / 10
    dmw = piecewise.disk_coefficients(w, hd, order, (0.0, 0.0, 0.0))
    p = dyn.params(dmw_t0=0.0, dmw_dt=hd, l_c=1e-3, k_sigma=0.0, t_win=0.0)
    f = np.linspace(0.0, 1.0, 4001)
    skipped = wrong = 0
    for _ in range(400):
        t, h = rng.uniform(0, 300 * hd), rng.uniform(20e-9, 500e-9)
        y, ynew = rng.normal(size=4) * [1e-9, 1e-7, 1e-3, 1e-1], rng.normal(size=4) * [1e-9, 1e-7, 1e-3, 1e-1]
        k1, k7 = np.r_[y[2:], 0.0, 0.0], np.r_[ynew[2:], 0.0, 0.0]
        s = np.array([stepper._hermite(y, k1, ynew, k7, h, x, 0) - p.l_c * stepper._hermite(y, k1, ynew, k7, h, x, 1)
                      for x in f])
        d = s - piecewise.ppval(dmw[:, :4], 0.0, hd, t + f * h)
        wdot = [piecewise._ppval(dmw[:, :4], 0.0, hd, x)[1] for x in (t, t + h)]
        dd0, dd1 = k1[0] - p.l_c * k1[1] - wdot[0], k7[0] - p.l_c * k7[1] - wdot[1]
        knots, i_a, A, B, C = stepper.knots_in_step(p, dmw, t, h, y, k1, ynew, k7)
        for lo, hi in ((d.min() - np.ptp(d), d.max() + np.ptp(d)), (d.min() + 1e-3 * np.ptp(d), d.max())):
            ext = np.array([lo, hi])
            matter = stepper.extrema_matter(p, dmw, False, True, knots, i_a, A, B, t, h, d[0], dd0, d[-1], dd1, ext)
            skipped += not matter
            wrong += (not matter) and not (lo <= d.min() and d.max() <= hi)
        # the search: in contact, with k sigma just above the sampled maximum the extrema matter only if it is not
        p["k_sigma"] = d.max() - 1e-3 * np.ptp(d)
        wrong += not stepper.extrema_matter(p, dmw, True, True, knots, i_a, A, B, t, h, d[0], dd0, d[-1], dd1,
                                            np.array([-1.0, 1.0]))
        p["k_sigma"] = 0.0
    assert wrong == 0
    assert skipped > 100
