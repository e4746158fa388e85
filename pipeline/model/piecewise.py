"""Piecewise cubics on a uniform grid: the interface tables, the TFC-point law's table and the DMW record.

A table is the coefficients ``c`` (shape ``(pieces, 4)``, one row per piece: the four coefficients of a
piece contiguous, one cache line per evaluation) of a piecewise polynomial on a uniform grid
(:func:`piecewise_coefficients`). Below the grid a table continues linearly, above it it is constant.
The compiled evaluators (:func:`_ppval` and the helpers that locate a point once for several tables
of one grid) are inlined into the kernel; :func:`ppval` and :func:`disk_history` evaluate for
post-processing.

The DMW record is three such cubics side by side on one time grid (:func:`disk_coefficients`): the
disk under the TFC point, the front pad and the rear pad.
"""

from __future__ import annotations

import functools

import numpy as np

from .compiled import kernel_jit

_jit = kernel_jit(__name__)
_inline = kernel_jit(__name__, inline="always")


def piecewise_coefficients(y: np.ndarray, h: float, order: int) -> np.ndarray:
    """Coefficients ``c`` (shape ``(n-1, 4)``) of a piecewise polynomial through ``y`` on a grid of step ``h``.

    On piece ``i``, ``f(x_i + s) = c[i,0] s^3 + c[i,1] s^2 + c[i,2] s + c[i,3]``. ``order=1``: linear
    interpolation; ``order=3``: not-a-knot cubic spline (``scipy.interpolate.CubicSpline``, C2).
    The four coefficients of a piece are contiguous in memory: one cache line per evaluation.
    """
    y = np.asarray(y, dtype=float)
    if order == 1:
        c = np.zeros((y.size - 1, 4))
        c[:, 2] = np.diff(y) / h
        c[:, 3] = y[:-1]
        return c
    if order == 3:
        if y.size < 4 or y.ndim != 1:  # (the spline's special cases: scipy's own)
            from scipy.interpolate import CubicSpline
            return np.ascontiguousarray(CubicSpline(h * np.arange(y.size), y).c.T)
        return _not_a_knot(y, h)
    raise ValueError(f"interpolation order {order}: expected 1 or 3")


def _not_a_knot(y: np.ndarray, h: float) -> np.ndarray:
    """The coefficients of ``scipy.interpolate.CubicSpline(h * np.arange(n), y).c.T`` for a 1-D ``y`` of
    ``n >= 4`` finite values, bit for bit: the same operations in the same order (the end rows of the
    not-a-knot condition, LAPACK's tridiagonal ``gtsv`` for the slopes, then the Hermite coefficients),
    without the checks and wrapper objects of scipy's general path, which cost twice the arithmetic on the
    4001-knot tables of a run (docs/performance.md, section "The Python of a pair"). The grid's bands
    are made once per ``(n, h)`` (:func:`_spline_grid`). tests/model/test_piecewise.py compares it with
    scipy's on random data and on the tables of the shipped scenes."""
    if not np.all(np.isfinite(y)):
        raise ValueError("`y` must contain only finite values.")
    dx, upper, diagonal, lower, d0, d1 = _spline_grid(y.size, float(h))
    slope = np.diff(y) / dx
    b = np.empty(y.size)
    b[1:-1] = 3 * (dx[1:] * slope[:-1] + dx[:-1] * slope[1:])
    b[0] = ((dx[0] + 2 * d0) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d0
    b[-1] = (dx[-1] ** 2 * slope[-2] + (2 * d1 + dx[-1]) * dx[-2] * slope[-1]) / d1
    from scipy.linalg.lapack import dgtsv  # (here: pipeline.model.ahead.NOT_IMPORTED_EARLY)
    _, _, _, s, info = dgtsv(lower.copy(), diagonal.copy(), upper.copy(), b.reshape(-1, 1), True, True, True, True)
    if info != 0:
        from numpy.linalg import LinAlgError
        raise LinAlgError("singular matrix") if info > 0 else ValueError(f"gtsv: illegal argument {-info}")
    s = s.reshape(-1)
    t = (s[:-1] + s[1:] - 2 * slope) / dx
    c = np.empty((y.size - 1, 4))
    c[:, 0] = t / dx
    c[:, 1] = (slope - s[:-1]) / dx - t
    c[:, 2] = s[:-1]
    c[:, 3] = y[:-1]
    return c


@functools.lru_cache(maxsize=16)
def _spline_grid(n: int, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float]:
    """The knots' steps ``dx`` [grid unit] of ``h * np.arange(n)`` (not all exactly ``h``: rounding) and the
    bands of :func:`_not_a_knot`'s tridiagonal system (upper, diagonal, lower) with the not-a-knot end rows,
    as scipy's ``CubicSpline`` builds them; ``d0 = x[2] - x[0]``, ``d1 = x[-1] - x[-3]``. Read only."""
    x = h * np.arange(n)
    dx = np.diff(x)
    if np.any(dx <= 0):
        raise ValueError(f"spline grid step {h}: expected > 0")
    band = np.zeros((3, n))
    band[1, 1:-1] = 2 * (dx[:-1] + dx[1:])
    band[0, 2:] = dx[:-1]
    band[-1, :-2] = dx[1:]
    band[1, 0] = dx[1]
    band[0, 1] = x[2] - x[0]
    band[1, -1] = dx[-2]
    band[-1, -2] = x[-1] - x[-3]
    for a in (dx, band):
        a.flags.writeable = False
    return dx, band[0, 1:], band[1, :], band[2, :-1], x[2] - x[0], x[-1] - x[-3]


#: Where :func:`grid_piece` takes the piece from the reciprocal's product: quotients below this [1] ...
PIECE_PRODUCT_MAX = 1e6
#: ... and farther than this [1] from an integer (the product is within 2.3e-10 of the quotient there)
PIECE_EDGE = 1e-9


@_inline
def grid_piece(dx, h):
    """``int(dx / h)``, the piece of an offset ``dx >= 0`` on a grid of step ``h > 0`` (both in the grid's
    unit), bit for bit, without the division's latency where it can.

    The product ``u = dx (1/h)`` is the quotient to ~2 ulp (two roundings): below
    :data:`PIECE_PRODUCT_MAX` its error is under 2.3e-10, so where ``u`` lies farther than :data:`PIECE_EDGE`
    from an integer the exact quotient and its rounding lie in the same piece as ``u``; elsewhere (within
    1e-9 of a knot, 2e-9 of the lookups, a not-a-number) the division decides, as before. A lookup in the
    kernel waits for its piece, and a division (13-15 cycles) is 3-4 times a product's latency: the step's
    stages and the step's cap each wait for one (docs/kernel.md, section "The piece without the division").
    ``1/h`` depends on the grid alone, computed off the chain of the state.
    """
    u = dx * (1.0 / h)
    i = int(u)
    f = u - i
    if not (PIECE_EDGE < f < 1.0 - PIECE_EDGE and u < PIECE_PRODUCT_MAX):
        i = int(dx / h)
    return i


@_inline
def _ppval(c, x0, h, x):
    """Value and slope of the piecewise cubic at ``x`` (linear extrapolation below, constant above)."""
    n = c.shape[0]
    if x - x0 < 0.0:  # (the sign of the quotient (x - x0) / h: grid steps h > 0 are far above 1e-300)
        return c[0, 3] + c[0, 2] * (x - x0), c[0, 2]
    i = grid_piece(x - x0, h)
    if i >= n:
        i = n - 1
        return ((c[i, 0] * h + c[i, 1]) * h + c[i, 2]) * h + c[i, 3], 0.0
    s = x - (x0 + i * h)
    c0, c1, c2, c3 = c[i, 0], c[i, 1], c[i, 2], c[i, 3]
    return ((c0 * s + c1) * s + c2) * s + c3, (3.0 * c0 * s + 2.0 * c1) * s + c2


@_inline
def _ppindex(n, x0, h, x):
    """Piece ``i`` and offset ``s`` of ``x`` on a uniform grid of ``n`` pieces (``i = -1`` below the
    grid, ``i = n`` above it): computed once and shared by the tables of one grid."""
    if x - x0 < 0.0:
        return -1, x - x0
    i = grid_piece(x - x0, h)
    if i >= n:
        return n, h
    return i, x - (x0 + i * h)


@_inline
def _ppat(c, i, s):
    """Value of a piecewise cubic at a point located by :func:`_ppindex` (as :func:`_ppval`)."""
    if i < 0:
        return c[0, 3] + c[0, 2] * s
    if i >= c.shape[0]:
        j = c.shape[0] - 1
        return ((c[j, 0] * s + c[j, 1]) * s + c[j, 2]) * s + c[j, 3]
    return ((c[i, 0] * s + c[i, 1]) * s + c[i, 2]) * s + c[i, 3]


@_inline
def _ppat_at(c, i, s, col):
    """:func:`_ppat` of the piecewise cubic in columns ``col..col+3`` of ``c`` (two tables in one array)."""
    if i < 0:
        return c[0, col + 3] + c[0, col + 2] * s
    if i >= c.shape[0]:
        j = c.shape[0] - 1
        return ((c[j, col] * s + c[j, col + 1]) * s + c[j, col + 2]) * s + c[j, col + 3]
    return ((c[i, col] * s + c[i, col + 1]) * s + c[i, col + 2]) * s + c[i, col + 3]


@_inline
def _ppslope_at(c, x0, h, x, col):
    """Slope of the piecewise cubic in columns ``col..col+3`` of ``c`` at ``x`` (as :func:`_ppval`)."""
    n = c.shape[0]
    if x - x0 < 0.0:
        return c[0, col + 2]
    i = grid_piece(x - x0, h)
    if i >= n:
        return 0.0
    s = x - (x0 + i * h)
    return (3.0 * c[i, col] * s + 2.0 * c[i, col + 1]) * s + c[i, col + 2]


def static_table(c: np.ndarray | None) -> np.ndarray | None:
    """The one piecewise cubic of an adhesion slot: ``c`` itself, or, for the two tables of the meniscus
    state (columns 0-3 relaxing, 4-7 at once: :class:`pipeline.model.dynamics.Tables`), their sum (a cubic
    spline is linear in its data, so the sum of the coefficients is the spline of the summed table)."""
    if c is None or c.shape[1] == 4:
        return c
    return np.ascontiguousarray(c[:, :4] + c[:, 4:])


@_jit
def ppval(c, x0, h, x):
    """Vectorised :func:`_ppval` (values only) for post-processing."""
    out = np.empty(x.shape[0])
    for j in range(x.shape[0]):
        out[j] = _ppval(c, x0, h, x[j])[0]
    return out


def disk_coefficients(w: np.ndarray, dt: float, order: int, offsets: tuple[float, float, float]) -> np.ndarray:
    """Piecewise polynomials of the disk under the TFC point, the front pad and the rear pad.

    ``w`` [m] is the record under the TFC point, sampled every ``dt`` [s] from ``t = 0``; the pads see
    it ``offsets`` [s] earlier (``w(t + off)``, ``off >= 0``). Each shifted record is resampled on the
    same time grid from the record's own interpolant and interpolated again, so the three share one
    grid: one index computation per evaluation, 12 contiguous coefficients per piece (columns 0-3
    TFC, 4-7 front, 8-11 rear). The resampling error is that of the interpolant itself (the DMW
    sample-rate row of the accuracy stage bounds it: 1.7e-5 of the headline outputs at 4 MS/s).
    """
    w = np.asarray(w, dtype=float)
    base = piecewise_coefficients(w, dt, order)
    n = w.size - int(np.ceil(max(offsets) / dt)) - 1
    if n < 2:
        raise ValueError("DMW record shorter than the pad-to-TFC travel time")
    cols = []
    for off in offsets:
        tt = np.arange(n) * dt + off
        samples = ppval(base, 0.0, dt, tt) if off != 0.0 else w[:n]
        cols.append(piecewise_coefficients(samples, dt, order))
    return np.ascontiguousarray(np.hstack(cols))


@_jit
def disk_history(dmw, p, t):
    """Disk displacement [m] and velocity [m/s] under the TFC point at the times ``t`` (outputs)."""
    w = np.empty(t.shape[0])
    v = np.empty(t.shape[0])
    for j in range(t.shape[0]):
        w[j], v[j] = disk(p, dmw, t[j])
    return w, v


@_inline
def disk(p, dmw, t):
    """Disk displacement [m] and velocity [m/s] under the TFC point at time ``t`` (zero without a DMW)."""
    if dmw is None:
        return 0.0, 0.0
    return _ppval(dmw, p.dmw_t0, p.dmw_dt, t)


@_inline
def disk3(p, dmw, t):
    """Disk displacement [m] and velocity [m/s] under the TFC point, the front and the rear pad at ``t``
    (:func:`disk_coefficients`: one row of 12 coefficients per piece)."""
    if dmw is None:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    h = p.dmw_dt
    n = dmw.shape[0]
    i = grid_piece(t - p.dmw_t0, h) if t - p.dmw_t0 >= 0.0 else 0  # (a negative quotient's piece clamps to 0)
    i = min(max(i, 0), n - 1)
    s = t - (p.dmw_t0 + i * h)
    r = dmw[i]
    return (((r[0] * s + r[1]) * s + r[2]) * s + r[3], (3.0 * r[0] * s + 2.0 * r[1]) * s + r[2],
            ((r[4] * s + r[5]) * s + r[6]) * s + r[7], (3.0 * r[4] * s + 2.0 * r[5]) * s + r[6],
            ((r[8] * s + r[9]) * s + r[10]) * s + r[11], (3.0 * r[8] * s + 2.0 * r[9]) * s + r[10])

