"""Piecewise cubics on a uniform grid (pipeline.model.piecewise): linear interpolation is exact for a line
and the not-a-knot spline for a cubic, the spline converges at fourth order on a smooth function, a table
continues linearly below its grid and constantly above it, the sum of two tables' coefficients is the
table of the summed data (a spline is linear in its data), and the DMW record's pad columns are the record
shifted by the pads' travel times."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.model import piecewise as pw


def _grid(n: int, h: float, x0: float = 0.0) -> np.ndarray:
    return x0 + h * np.arange(n)


@pytest.mark.parametrize("order, f", [(1, lambda x: 2.0 - 0.5 * x),
                                      (3, lambda x: x**3 - 2.0 * x**2 + 0.25 * x - 1.0)])
def test_exact_for_its_polynomials(order, f):
    h, x0 = 0.1, -0.3
    c = pw.piecewise_coefficients(f(_grid(21, h, x0)), h, order)
    assert c.shape == (20, 4) and c.flags.c_contiguous
    x = np.linspace(x0, x0 + 2.0, 97)
    # tol: a polynomial of degree <= order is the spline itself: the solve's rounding (condition ~ 3)
    np.testing.assert_allclose(pw.ppval(c, x0, h, x), f(x), rtol=1e-12, atol=1e-12)


def test_spline_converges_at_fourth_order():
    errors = []
    for n in (17, 33, 65):
        h = np.pi / (n - 1)
        c = pw.piecewise_coefficients(np.sin(_grid(n, h)), h, 3)
        x = np.linspace(0.0, np.pi, 2001)
        errors.append(np.max(np.abs(pw.ppval(c, 0.0, h, x) - np.sin(x))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 3.7), orders


def test_linear_below_constant_above():
    h = 0.5
    y = np.array([1.0, 3.0, 4.0, 4.5])
    c = pw.piecewise_coefficients(y, h, 1)
    # below: the first piece continued (slope 4); above: the last value
    # tol: linear pieces of exact binary data, exact or an ulp
    np.testing.assert_allclose(pw.ppval(c, 0.0, h, np.array([-1.0, -0.25, 1.5, 2.0, 100.0])),
                               [1.0 - 4.0, 1.0 - 1.0, 4.5, 4.5, 4.5], rtol=1e-14)
    value, slope = pw._ppval(c, 0.0, h, 10.0)
    assert (value, slope) == (4.5, 0.0)
    value, slope = pw._ppval(c, 0.0, h, -1.0)
    assert value == pytest.approx(-3.0) and slope == pytest.approx(4.0)


def test_unknown_order_is_an_error():
    with pytest.raises(ValueError, match=r"^interpolation order 2: expected 1 or 3$"):
        pw.piecewise_coefficients(np.ones(5), 1.0, 2)


def test_static_table_is_the_table_of_the_summed_data():
    h = 0.2
    x = _grid(30, h)
    a, b = np.exp(-x), 0.3 * np.cos(3.0 * x)
    two = np.hstack([pw.piecewise_coefficients(a, h, 3), pw.piecewise_coefficients(b, h, 3)])
    np.testing.assert_allclose(pw.static_table(two), pw.piecewise_coefficients(a + b, h, 3), rtol=0, atol=1e-12)
    one = pw.piecewise_coefficients(a, h, 3)
    assert pw.static_table(one) is one and pw.static_table(None) is None


def test_disk_columns_are_the_record_shifted_by_the_pads_travel_times():
    dt = 1e-3
    t = _grid(200, dt)
    w = np.sin(2 * np.pi * 3.0 * t)                     # [m], smooth on the grid (~330 samples a period)
    offsets = (0.0, 5 * dt, 12.5 * dt)                  # the TFC point; a pad on the grid; one between samples
    c = pw.disk_coefficients(w, dt, 3, offsets)
    n = w.size - int(np.ceil(max(offsets) / dt)) - 1
    assert c.shape == (n - 1, 12)
    tt = np.linspace(0.0, (n - 2) * dt, 301)
    for j, off in enumerate(offsets):
        col = np.ascontiguousarray(c[:, 4 * j:4 * j + 4])
        np.testing.assert_allclose(pw.ppval(col, 0.0, dt, tt), np.sin(2 * np.pi * 3.0 * (tt + off)), atol=1e-9)
    with pytest.raises(ValueError, match="DMW record shorter than the pad-to-TFC travel time"):
        pw.disk_coefficients(w[:10], dt, 3, (0.0, 9 * dt, 0.0))


@pytest.mark.parametrize("n", [2, 3, 4, 5, 17, 1000, 4001])
def test_the_spline_is_scipy_s_not_a_knot_spline_bit_for_bit(n):
    """The cubic of order 3 is ``scipy.interpolate.CubicSpline``'s (its arithmetic, without its checks and
    objects: piecewise._not_a_knot) to the last bit, on any grid step, for rough data over 15 decades and a
    smooth steep law (1 / g^2, as the TFC-point tables); 2-3 points are scipy's own special cases."""
    from scipy.interpolate import CubicSpline
    rng = np.random.default_rng(n)
    for h in (1e-10, 2.5e-11, 0.37, 1.0 / 3.0):
        x = h * np.arange(n)
        for y in (rng.standard_normal(n) * 10.0 ** rng.uniform(-12, 3), 1.0 / (x + 0.5 * h) ** 2):
            # exact on any host: both sides are numpy's elementwise arithmetic and the same LAPACK dgtsv,
            # which calls no CPU-dispatched BLAS kernel
            np.testing.assert_array_equal(pw.piecewise_coefficients(y, h, 3),
                                          np.ascontiguousarray(CubicSpline(x, y).c.T))


def test_the_spline_refuses_values_that_are_not_finite():
    with pytest.raises(ValueError, match="finite"):
        pw.piecewise_coefficients(np.array([0.0, 1.0, np.nan, 2.0, 3.0]), 1.0, 3)


@pw._jit
def _pieces(dx, h):
    out = np.empty(dx.shape[0], dtype=np.int64)
    for j in range(dx.shape[0]):
        out[j] = pw.grid_piece(dx[j], h)
    return out


@pytest.mark.parametrize("h", [5e-11, 2.5e-7, 1.0 / 3.0, 0.1])
def test_the_piece_without_the_division_is_the_division_s(h):
    """``grid_piece`` is ``int(dx / h)`` bit for bit: on random offsets over the kernel's range of quotients, on
    offsets a few ulps either side of every knot (where the product and the quotient may round apart), and past
    the product's range; the knots' neighbours do straddle pieces, so the test can tell a wrong piece."""
    rng = np.random.default_rng(7)
    knots = np.arange(0, 9000) * h
    near = np.concatenate([np.nextafter(knots, np.inf * s) for s in (1, -1)] + [knots]
                          + [knots * (1 + e) for e in (-4e-16, 4e-16, -1e-15, 1e-15)])
    dx = np.concatenate([rng.uniform(0, 9000 * h, 100_000), near[near >= 0], rng.uniform(0, 3e6 * h, 1000)])
    exact = (dx / h).astype(np.int64)
    assert np.array_equal(_pieces(dx, h), exact)
    assert len(np.unique(exact[: 100_000])) > 8000  # (the offsets span the pieces)
    ne = dx[100_000:-1000]
    assert np.any((ne / h).astype(np.int64) < np.rint(ne / h))  # (some neighbours of a knot are in the piece below)
