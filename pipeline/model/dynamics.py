"""Numba kernels of the 2-DOF slider: equations of motion and the adaptive integrator.

Equations of motion (SPEC.md section 4), states ``y = (z, theta, z', theta')`` in SI units::

    m z''     = F_f + F_r + F_i
    I theta'' = l_f F_f - l_r F_r - l_c F_i - h_cg Q

* front pad (``l_f`` ahead of the CG), linear:   ``F_f = -k_f (z + l_f theta - w_f) - c_f (...)'``
* rear pad (``l_r`` behind), nonlinear [recon]:  ``F_r = F_r0 [(g0/g_r)^n - 1] - c_r g_r'``,
  ``g_r = g0 + z - l_r theta - w_r``
* interface at the TFC point (``l_c`` behind), gap ``g = FH0 - delta + z - l_c theta - w_c`` to the mean
  of surface heights and ISBL separation ``d = g - y_s`` to the mean of summit heights (SPEC.md 7.2):
  ``F_i = -A_n p_a(d)`` always (adhesion effect), plus ``A_n p_c(d) - c_c d'`` while in contact
  (``d < k sigma``, the paper's criterion)
* friction ``Q = A_n tau(d)`` in contact, along the disk's motion (leading to trailing edge) at the
  air-bearing surface; its moment about the CG is ``-h_cg Q`` (it pitches the leading edge down).
* the disk under each point moves with the DMW ``w(t)`` delayed by the disk's travel time.
* optional, named model variants (SPEC.md 7.4, 4): the rear law ``F_r = k_r (g0 - g_r)`` (``rear_linear``
  not ``None``) instead of the power law; a stiffening spring at the TFC point, force
  ``F_t = k_t [G(g_n) - G(g)]``, ``G(s) = g0^p s^(1-p) / (1-p) - s`` (``g0 ln s - s`` for ``p = 1``),
  whose stiffness is ``-dF_t/dg = k_t [(g0/g)^p - 1]`` (``tfc_stiff`` not ``None``;
  :func:`pipeline.physics.air_bearing.tfc_stiffening_force`).
* the air-bearing laws (rear power and linear laws, the stiffening potential and stiffness) are
  compiled from their one definition in :mod:`pipeline.physics.air_bearing`.

Effects are selected by passing ``None`` for a disabled effect's data: numba compiles one
specialised kernel per combination and prunes the dead branches at compile time (branch pruning of
``arg is None``), so a disabled effect is never evaluated, with no run-time test in the hot loop.
All kernels are cached on disk (``cache=True``).

Integrator: Dormand-Prince 5(4) with PI-free classical step control (Hairer, Norsett & Wanner,
*Solving ODEs I*, II.4 and II.5), local extrapolation, error norm the RMS of the embedded error
scaled by ``atol + rtol |y|``. The contact switch is a discontinuity of the force, handled as an
event: a sign change of ``g = d - k sigma`` over an accepted step (at its ends, or at an interior
extremum of ``g`` when ``g'`` changes sign, so a grazing contact shorter than a step is not missed)
is located by bisection on the cubic Hermite interpolant of the step, the step is redone exactly up to the switch, and
integration restarts in the new mode (no FSAL reuse across the switch). Outputs are sampled on a
uniform grid with the same Hermite interpolant.

Interior extrema of ``d`` in a step (the event search and the exact steady-window extremes) are those
of ``d(t) = const + s(t) - w(t)``: ``s = z - l_c theta`` on the state's Hermite cubic and ``w`` the DMW
spline. Between two DMW knots both are cubics, so the step is split at the knots it contains and each
piece's extrema come in closed form: exact for DMW content up to the Nyquist frequency, where a
500-ns step spans several 250-ns knots (one cubic through the step's ends would miss the peaks in
between).

Chattering. Where the contact force at the threshold exceeds the pull into contact (a large
``p_c(k sigma)``, e.g. a negative k), the exact solution slides along ``d = k sigma`` (a Filippov
sliding mode) and an exact event method would switch infinitely often. A mode is therefore held
for at least ``P_DWELL`` seconds after a switch (``solver.min_dwell_ns``); if the criterion says
otherwise when the dwell ends, the mode switches there. The resulting fast switching averages the
contact force to the sliding-mode value with an error of the order of the dwell; the dwell is an
accuracy knob of the accuracy stage. Crossings further apart than the dwell are located exactly.
"""

from __future__ import annotations

import os

import numba
import numpy as np
from numba import njit

from ..code_version import code_key
from ..physics import air_bearing as ab

# numba's on-disk cache of a jitted function checks the timestamp of the file that holds it, not of
# the files whose functions it inlines (the air-bearing laws of pipeline.physics.air_bearing): with an
# edited law the kernel would load its old machine code while the runner (which keys on the code)
# recomputes the results. So the functions of this module are cached in a folder named by the code
# key of this module and of what it imports; the folder is set while they are decorated (numba picks
# a function's cache folder then) and numba's setting is restored at the end of the module.
_NUMBA_CACHE_DIR = numba.config.CACHE_DIR
numba.config.CACHE_DIR = os.path.join(_NUMBA_CACHE_DIR or os.path.join(os.path.dirname(__file__), "__pycache__"),
                                      f"numba-{code_key(__name__)[:16]}")

# Layout of the parameter vector ``p`` (all SI).
(P_M, P_I, P_LF, P_LR, P_LC, P_HCG, P_KF, P_KR, P_CF, P_CR, P_G0, P_N, P_FR0, P_FH0, P_DELTA, P_AN,
 P_KSIG, P_CC, P_OFF_F, P_OFF_R, P_OFF_C, P_DMW_T0, P_DMW_DT, P_TAB_X0, P_TAB_H, P_DWELL,
 P_TWIN, P_HSTIFF, P_TAB_N, P_YS, P_TK, P_TP, P_TG0, P_TF0, P_TGMIN, P_TKMIN) = range(36)
N_PARAMS = 36

# Status codes returned by :func:`integrate`.
OK, MAX_STEPS, STEP_UNDERFLOW, NOT_FINITE = 0, 1, 2, 3
STATUS_TEXT = {OK: "ok", MAX_STEPS: "too many steps", STEP_UNDERFLOW: "step size underflow",
               NOT_FINITE: "state became non-finite"}


# ---------------------------------------------------------------------------------------------
# piecewise cubics on a uniform grid (interface tables, DMW record)

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
        from scipy.interpolate import CubicSpline
        x = h * np.arange(y.size)
        return np.ascontiguousarray(CubicSpline(x, y).c.T)
    raise ValueError(f"interpolation order {order}: expected 1 or 3")


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _ppval(c, x0, h, x):
    """Value and slope of the piecewise cubic at ``x`` (linear extrapolation below, constant above)."""
    n = c.shape[0]
    u = (x - x0) / h
    if u < 0.0:
        return c[0, 3] + c[0, 2] * (x - x0), c[0, 2]
    i = int(u)
    if i >= n:
        i = n - 1
        return ((c[i, 0] * h + c[i, 1]) * h + c[i, 2]) * h + c[i, 3], 0.0
    s = x - (x0 + i * h)
    c0, c1, c2, c3 = c[i, 0], c[i, 1], c[i, 2], c[i, 3]
    return ((c0 * s + c1) * s + c2) * s + c3, (3.0 * c0 * s + 2.0 * c1) * s + c2


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _ppindex(n, x0, h, x):
    """Piece ``i`` and offset ``s`` of ``x`` on a uniform grid of ``n`` pieces (``i = -1`` below the
    grid, ``i = n`` above it): computed once and shared by the tables of one grid."""
    u = (x - x0) / h
    if u < 0.0:
        return -1, x - x0
    i = int(u)
    if i >= n:
        return n, h
    return i, x - (x0 + i * h)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _ppat(c, i, s):
    """Value of a piecewise cubic at a point located by :func:`_ppindex` (as :func:`_ppval`)."""
    if i < 0:
        return c[0, 3] + c[0, 2] * s
    if i >= c.shape[0]:
        j = c.shape[0] - 1
        return ((c[j, 0] * s + c[j, 1]) * s + c[j, 2]) * s + c[j, 3]
    return ((c[i, 0] * s + c[i, 1]) * s + c[i, 2]) * s + c[i, 3]


@njit(cache=True, nogil=True, error_model="numpy")
def ppval(c, x0, h, x):
    """Vectorised :func:`_ppval` (values only) for post-processing."""
    out = np.empty(x.shape[0])
    for j in range(x.shape[0]):
        out[j] = _ppval(c, x0, h, x[j])[0]
    return out


# ---------------------------------------------------------------------------------------------
# right-hand side

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


@njit(cache=True, nogil=True, error_model="numpy")
def disk_history(dmw, p, t):
    """Disk displacement [m] and velocity [m/s] under the TFC point at the times ``t`` (outputs)."""
    w = np.empty(t.shape[0])
    v = np.empty(t.shape[0])
    for j in range(t.shape[0]):
        w[j], v[j] = _disk(p, dmw, t[j])
    return w, v


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _disk(p, dmw, t):
    """Disk displacement [m] and velocity [m/s] under the TFC point at time ``t``."""
    if dmw is None:
        return 0.0, 0.0
    return _ppval(dmw, p[P_DMW_T0], p[P_DMW_DT], t)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _disk3(p, dmw, t):
    """Disk displacement and velocity under the TFC point, the front and the rear pad at ``t``."""
    if dmw is None:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    h = p[P_DMW_DT]
    n = dmw.shape[0]
    i = int((t - p[P_DMW_T0]) / h)
    i = min(max(i, 0), n - 1)
    s = t - (p[P_DMW_T0] + i * h)
    r = dmw[i]
    return (((r[0] * s + r[1]) * s + r[2]) * s + r[3], (3.0 * r[0] * s + 2.0 * r[1]) * s + r[2],
            ((r[4] * s + r[5]) * s + r[6]) * s + r[7], (3.0 * r[4] * s + 2.0 * r[5]) * s + r[6],
            ((r[8] * s + r[9]) * s + r[10]) * s + r[11], (3.0 * r[8] * s + 2.0 * r[9]) * s + r[10])


@njit(cache=True, nogil=True, error_model="numpy")
def gap_at(p, z, theta, w):
    """Gap [m] at the TFC point to the mean of the disk's surface heights, ``FH0 - delta + z - l_c theta - w``.

    ``FH0`` is measured to the mean of surface heights (SPEC.md 7.2); scalars or arrays of ``z`` [m],
    ``theta`` [rad], ``w`` [m] alike (the one home of the datum, for the kernel and post-processing).
    """
    return p[P_FH0] - p[P_DELTA] + z - p[P_LC] * theta - w


@njit(cache=True, nogil=True, error_model="numpy")
def separation_at(p, z, theta, w):
    """ISBL separation ``d`` [m] to the mean of summit heights: :func:`gap_at` minus ``y_s = p[P_YS]``.

    ``d = FH0 - delta + z - l_c theta - w - y_s`` (SPEC.md 7.2; the ISBL tables are functions of this d).
    """
    return gap_at(p, z, theta, w) - p[P_YS]


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def separation(p, dmw, t, y):
    """TFC separation ``d`` [m] and its rate [m/s] (SPEC.md 4, 7.2)."""
    wc, vc = _disk(p, dmw, t)
    return _separation(p, y, wc, vc)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _separation(p, y, wc, vc):
    return separation_at(p, y[0], y[1], wc), y[2] - p[P_LC] * y[3] - vc


# the air-bearing laws, compiled from their one definition in pipeline.physics.air_bearing
_JIT = dict(cache=True, nogil=True, inline="always", error_model="numpy")
_rear_power = njit(**_JIT)(ab.rear_power_law)
_rear_linear = njit(**_JIT)(ab.rear_linear_law)
_stiffening_potential = njit(**_JIT)(ab.stiffening_potential)
_stiffening_stiffness = njit(**_JIT)(ab.stiffening_stiffness)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _stiffening(p, g):
    """Force [N] (up positive) and stiffness [N/m] of the TFC stiffening spring at the gap ``g`` [m].

    ``k(g) = k_t [(g0/g)^p - 1]``, force its integral from the nominal gap (constant ``P_TF0`` =
    ``G(g_n)``), continued linearly below ``P_TGMIN`` where the law is singular.
    """
    gm = p[P_TGMIN]
    gg = max(g, gm)
    f = p[P_TK] * (p[P_TF0] - _stiffening_potential(gg, p[P_TG0], p[P_TP]))
    if g < gm:
        return f + p[P_TKMIN] * (gm - g), p[P_TKMIN]
    return f, _stiffening_stiffness(gg, p[P_TG0], p[P_TK], p[P_TP])


@njit(cache=True, nogil=True, error_model="numpy")
def rhs(t, y, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, out):
    """Write ``dy/dt`` into ``out`` (see the module docstring for the equations).

    ``tfs``: any array to enable the TFC stiffening spring, ``None`` to disable it; ``rlin``: any array
    for the linear rear law, ``None`` for the power law (compile-time choices, see the module docstring).
    """
    z, th, vz, vth = y[0], y[1], y[2], y[3]
    wc, vc, wf, vf, wr, vr = _disk3(p, dmw, t)
    lf, lr = p[P_LF], p[P_LR]
    F_f = -p[P_KF] * (z + lf * th - wf) - p[P_CF] * (vz + lf * vth - vf)
    g_r = p[P_G0] + z - lr * th - wr
    if rlin is not None:
        F_r = _rear_linear(g_r, p[P_G0], p[P_KR])
    else:
        g_r = max(g_r, 1e-3 * p[P_G0])  # the rear law is singular at zero gap; never reached in practice
        F_r = _rear_power(g_r, p[P_G0], p[P_N], p[P_FR0])
    F_r -= p[P_CR] * (vz - lr * vth - vr)
    F_i = 0.0
    Q = 0.0
    if tfs is not None:
        F_i += _stiffening(p, gap_at(p, z, th, wc))[0]
    if pa is not None or cp is not None:
        d, dd = _separation(p, y, wc, vc)
        # one index for every table (they share the separation grid)
        i, s = _ppindex(int(p[P_TAB_N]), p[P_TAB_X0], p[P_TAB_H], d)
        if pa is not None:
            F_i -= p[P_AN] * _ppat(pa, i, s)
        if cp is not None:
            if contact:
                F_i += p[P_AN] * max(_ppat(cp, i, s), 0.0) - p[P_CC] * dd
                if ft is not None:
                    Q = p[P_AN] * max(_ppat(ft, i, s), 0.0)
    out[0] = vz
    out[2] = (F_f + F_r + F_i) / p[P_M]
    if pitch is None:
        out[1] = 0.0
        out[3] = 0.0
    else:
        out[1] = vth
        out[3] = (lf * F_f - lr * F_r - p[P_LC] * F_i - p[P_HCG] * Q) / p[P_I]


# ---------------------------------------------------------------------------------------------
# Dormand-Prince 5(4) tableau (Hairer, Norsett & Wanner, Table II.5.2)
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40)


@njit(cache=True, nogil=True, error_model="numpy")
def _step(t, y, k1, h, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, ynew, k7, err, tmp, k2, k3, k4, k5, k6):
    """One Dormand-Prince step: ``ynew``, its derivative ``k7`` and the error estimate ``err``."""
    for i in range(4):
        tmp[i] = y[i] + h * A21 * k1[i]
    rhs(t + h / 5, tmp, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k2)
    for i in range(4):
        tmp[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i])
    rhs(t + 3 * h / 10, tmp, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k3)
    for i in range(4):
        tmp[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i])
    rhs(t + 4 * h / 5, tmp, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k4)
    for i in range(4):
        tmp[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i])
    rhs(t + 8 * h / 9, tmp, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k5)
    for i in range(4):
        tmp[i] = y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i])
    rhs(t + h, tmp, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k6)
    for i in range(4):
        ynew[i] = y[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i])
    rhs(t + h, ynew, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k7)
    for i in range(4):
        err[i] = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i])


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _hermite(y0, f0, y1, f1, h, theta, i):
    """Cubic Hermite interpolant of component ``i`` at ``t0 + theta h``."""
    t2 = theta * theta
    t3 = t2 * theta
    return ((2 * t3 - 3 * t2 + 1) * y0[i] + (t3 - 2 * t2 + theta) * h * f0[i]
            + (-2 * t3 + 3 * t2) * y1[i] + (t3 - t2) * h * f1[i])


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _dcubic(d0, dd0, d1, dd1, h):
    """Coefficients ``(a, b, c, e)`` of the cubic Hermite ``d(theta) = a theta^3 + b theta^2 + c theta + e``
    through ``d0, d1`` with slopes ``dd0, dd1`` [per unit time] over a step ``h``: locates the interior
    extrema of ``d`` in closed form (their values are then taken on the state interpolant)."""
    return (2.0 * d0 + h * dd0 - 2.0 * d1 + h * dd1,
            -3.0 * d0 - 2.0 * h * dd0 + 3.0 * d1 - h * dd1,
            h * dd0, d0)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _extrema(a, b, c):
    """Roots in (0, 1), ascending, of ``3 a x^2 + 2 b x + c`` (the extrema of the cubic): ``(n, x1, x2)``."""
    A, B, C = 3.0 * a, 2.0 * b, c
    r1, r2 = -1.0, -1.0
    if abs(A) <= 1e-14 * (abs(B) + abs(C)):
        if B != 0.0:
            r1 = -C / B
    else:
        disc = B * B - 4.0 * A * C
        if disc >= 0.0:
            q = -0.5 * (B + (np.sqrt(disc) if B >= 0.0 else -np.sqrt(disc)))
            if q != 0.0:
                r1, r2 = q / A, C / q
            else:
                r1 = 0.0
    if r2 < r1:
        r1, r2 = r2, r1
    n = 0
    x1, x2 = 0.0, 0.0
    if 0.0 < r1 < 1.0:
        x1 = r1
        n = 1
    if 0.0 < r2 < 1.0 and r2 != r1:
        if n == 0:
            x1 = r2
        else:
            x2 = r2
        n += 1
    return n, x1, x2


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _d_extrema(p, dmw, t, h, y, k1, ynew, k7, d0, dd0, d1, dd1, buf):
    """Interior extrema of ``d`` in the step ``[t, t + h]``: their ``theta`` in (0, 1) go into ``buf``;
    returns how many.

    Without a knot of the DMW spline inside the step, ``d`` is one cubic, the Hermite through its end
    values and slopes. Otherwise the step is split at the knots and on each piece ``d = const + s - w``
    (``s = z - l_c theta`` on the state's Hermite cubic, ``w`` the spline piece) is a cubic whose
    Taylor coefficients at the piece's start give the extrema in closed form (module docstring).
    """
    n_b = 0
    if dmw is not None:
        t0, hd = p[P_DMW_T0], p[P_DMW_DT]
        i_a = int((t - t0) / hd)
        first_knot = t0 + (i_a + 1) * hd
        if first_knot < t + h:
            lc = p[P_LC]
            # s(theta) = A theta^3 + B theta^2 + C theta + E over the whole step
            A, B, C, E = _dcubic(y[0] - lc * y[1], k1[0] - lc * k1[1], ynew[0] - lc * ynew[1],
                                 k7[0] - lc * k7[1], h)
            n_pieces = dmw.shape[0]
            ta = t
            i = i_a
            while ta < t + h and n_b + 2 <= buf.shape[0]:
                tb = min(t0 + (i + 1) * hd, t + h)
                tha, L = (ta - t) / h, (tb - ta) / h
                if L > 0.0:
                    S1 = (3.0 * A * tha + 2.0 * B) * tha + C
                    S2 = 6.0 * A * tha + 2.0 * B
                    j = min(max(i, 0), n_pieces - 1)
                    sg = ta - (t0 + j * hd)
                    r0, r1, r2 = dmw[j, 0], dmw[j, 1], dmw[j, 2]
                    W1 = (3.0 * r0 * sg + 2.0 * r1) * sg + r2
                    W2 = 6.0 * r0 * sg + 2.0 * r1
                    Lh = L * h
                    n_ex, x1, x2 = _extrema((A * L ** 3 - r0 * Lh ** 3), 0.5 * (S2 * L * L - W2 * Lh * Lh),
                                            S1 * L - W1 * Lh)
                    if n_ex > 0:
                        buf[n_b] = tha + x1 * L
                        n_b += 1
                    if n_ex > 1:
                        buf[n_b] = tha + x2 * L
                        n_b += 1
                ta = tb
                i += 1
            return n_b
    ca, cb, cc, ce = _dcubic(d0, dd0, d1, dd1, h)
    n_ex, th1, th2 = _extrema(ca, cb, cc)
    if n_ex > 0:
        buf[0] = th1
    if n_ex > 1:
        buf[1] = th2
    return n_ex


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _interp_state(y0, f0, y1, f1, h, theta, out):
    for i in range(4):
        out[i] = _hermite(y0, f0, y1, f1, h, theta, i)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _first_wrong_side(p, dmw, cp, contact, t, y, k1, ynew, k7, h, d0, dd0, d1, dd1, ys, buf):
    """Smallest ``theta`` in (0, 1] of the step where the criterion disagrees with the mode, or -1.

    Checks the step's end, the interior extrema of ``d`` (closed form, :func:`_d_extrema`) and, when
    ``d`` passes near the threshold, a few interior points; values are taken on the state
    interpolant, the one outputs and the bisection use.
    """
    ks = p[P_KSIG]
    best = 2.0
    if (d1 - ks < 0.0) != contact:
        best = 1.0
    n_ex = _d_extrema(p, dmw, t, h, y, k1, ynew, k7, d0, dd0, d1, dd1, buf)
    near = min(abs(d0 - ks), abs(d1 - ks)) < 0.5 * h * max(abs(dd0), abs(dd1))
    n_try = n_ex + (3 if near else 0)
    for i_ex in range(n_try):
        if i_ex < n_ex:
            th = buf[i_ex]
        else:
            th = 0.25 * (i_ex - n_ex + 1)
        if th >= best:
            continue
        _interp_state(y, k1, ynew, k7, h, th, ys)
        if (separation(p, dmw, t + th * h, ys)[0] - ks < 0.0) != contact:
            best = th
    return best if best <= 1.0 else -1.0


@njit(cache=True, nogil=True, error_model="numpy")
def integrate(y0, t_end, t_out, p, dmw, cp, pa, ft, pitch, tfs, rlin, rtol, atol, h_max, max_steps):
    """Integrate from ``t = 0`` to ``t_end`` [s]; sample the state at ``t_out`` (ascending).

    Parameters
    ----------
    y0 : initial state ``(z [m], theta [rad], z' [m/s], theta' [rad/s])``
    p : parameter vector (layout ``P_*``)
    dmw, cp, pa, ft : piecewise-cubic coefficients of the disk under the TFC point and the pads
        (:func:`disk_coefficients`) [m], and of the contact pressure,
        adhesion pressure and friction stress [Pa] versus separation [m]; ``None`` disables
    pitch : any array to enable the pitch degree of freedom, ``None`` to lock it
    tfs : any array to enable the TFC stiffening spring (parameters ``P_TK``...), ``None`` to disable
    rlin : any array for the linear rear law, ``None`` for the power law
    rtol, atol : relative tolerance [1] and per-component absolute tolerances (SI)
    h_max : largest step [s]; max_steps : guard against a stalled integration

    Returns
    -------
    Y : states at ``t_out`` (n_out, 4); C : contact flag at ``t_out``;
    info : ``[status, accepted steps, rejected steps, contact switches, rhs evaluations]``;
    ext : exact minimum and maximum of the separation ``d`` [m] over ``t >= p[P_TWIN]``
    """
    n_out = t_out.shape[0]
    Y = np.full((n_out, 4), np.nan)
    C = np.zeros(n_out, dtype=np.bool_)
    info = np.zeros(5, dtype=np.int64)
    ext = np.array([np.inf, -np.inf])  # min and max of d over t >= P_TWIN
    y = y0.copy()
    k1 = np.empty(4)
    k7 = np.empty(4)
    ynew = np.empty(4)
    err = np.empty(4)
    tmp = np.empty(4)
    k2, k3, k4, k5, k6 = np.empty(4), np.empty(4), np.empty(4), np.empty(4), np.empty(4)
    ys = np.empty(4)
    # interior extrema of d: at most 2 per DMW spline piece a step spans
    buf = np.empty(2 * (int(h_max / p[P_DMW_DT]) + 3) if dmw is not None else 2)
    ev_y = np.empty(4)
    ev_f = np.empty(4)
    t = 0.0
    # The initial mode follows the criterion at t = 0.
    contact = False
    if cp is not None:
        contact = separation(p, dmw, t, y)[0] < p[P_KSIG]
    rhs(t, y, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k1)
    info[4] += 1
    d0, dd0 = separation(p, dmw, t, y)  # d and d' at the current step start (kept step to step)
    if p[P_TWIN] <= 0.0:  # the window starts at t = 0: the initial d is one of its values (steps add their ends)
        ext[0] = d0
        ext[1] = d0
    h = min(h_max, 1e-8)
    t_hold = -1.0  # no switch may happen before t_hold (minimum dwell after a switch)
    h_stiff = h_max  # step cap from the local interface stiffness (see below)
    m_eff_inv = 1.0 / p[P_M] + (p[P_LC] ** 2 / p[P_I] if pitch is not None else 0.0)
    j = 0
    while j < n_out and t_out[j] <= t:
        Y[j, :] = y
        C[j] = contact
        j += 1
    steps = 0
    while t < t_end:
        if steps >= max_steps:
            info[0] = MAX_STEPS
            return Y, C, info, ext
        steps += 1
        if cp is not None and t_hold > 0.0 and t >= t_hold:
            # the dwell has ended: switch now if the criterion disagrees with the mode
            t_hold = -1.0
            if (d0 - p[P_KSIG] < 0.0) != contact:
                contact = not contact
                info[3] += 1
                t_hold = t + p[P_DWELL]
                rhs(t, y, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k1)
                info[4] += 1
        h = min(h, h_max, h_stiff)
        if t + 1.01 * h >= t_end:  # land on t_end exactly, never leave a sliver (Hairer's DOPRI5 rule)
            h = t_end - t
        if t_hold > t and t + 1.01 * h >= t_hold:  # land on the end of the dwell, no sliver
            h = t_hold - t
        if h < 1e-12 * max(t, 1e-9) or h < 1e-18:  # (h = t_end - t is never a sliver, see above)
            info[0] = STEP_UNDERFLOW
            return Y, C, info, ext
        _step(t, y, k1, h, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, ynew, k7, err, tmp, k2, k3, k4, k5, k6)
        info[4] += 6
        e = 0.0
        for i in range(4):
            sc = atol[i] + rtol * max(abs(y[i]), abs(ynew[i]))
            e += (err[i] / sc) ** 2
        e = np.sqrt(e / 4.0)
        if not np.isfinite(e):
            h *= 0.1
            info[2] += 1
            continue
        if e > 1.0:
            h *= max(0.2, 0.9 * e ** -0.2)
            info[2] += 1
            continue
        # accepted step [t, t + h]
        h_acc = h
        switched = False
        d1, dd1 = separation(p, dmw, t + h, ynew)
        if cp is not None and t_hold < 0.0:
            # Locate a contact switch in the step; a redone (shorter) step is more accurate than the
            # long step's interpolant and may show the crossing earlier, so repeat on the redone step.
            for _ in range(8):
                hi = _first_wrong_side(p, dmw, cp, contact, t, y, k1, ynew, k7, h_acc, d0, dd0, d1, dd1, ys,
                                       buf)
                if hi < 0.0:
                    break
                lo = 0.0
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    _interp_state(y, k1, ynew, k7, h_acc, mid, ys)
                    g = separation(p, dmw, t + mid * h_acc, ys)[0] - p[P_KSIG]
                    if (g < 0.0) != contact:
                        hi = mid
                    else:
                        lo = mid
                    if (hi - lo) * h_acc < 1e-16:
                        break
                if not switched:
                    info[3] += 1
                switched = True
                if hi >= 1.0:
                    break  # the switch is at the end of the step
                # redo the step exactly up to the switch (in the old mode)
                h_acc = hi * h_acc
                _step(t, y, k1, h_acc, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, ev_y, ev_f, err, tmp,
                      k2, k3, k4, k5, k6)
                info[4] += 6
                for i in range(4):
                    ynew[i] = ev_y[i]
                    k7[i] = ev_f[i]
                d1, dd1 = separation(p, dmw, t + h_acc, ynew)
        t_new = t + h_acc
        if t_new >= p[P_TWIN]:
            # exact extremes of d over the steady window: at the step's end and at the interior
            # extrema of d on the step's cubic (peak-to-peak free of aliasing by the output grid)
            ext[0] = min(ext[0], d1)
            ext[1] = max(ext[1], d1)
            n_ex = _d_extrema(p, dmw, t, h_acc, y, k1, ynew, k7, d0, dd0, d1, dd1, buf)
            for i_ex in range(n_ex):
                th = buf[i_ex]
                if t + th * h_acc >= p[P_TWIN]:
                    _interp_state(y, k1, ynew, k7, h_acc, th, ys)
                    de = separation(p, dmw, t + th * h_acc, ys)[0]
                    ext[0] = min(ext[0], de)
                    ext[1] = max(ext[1], de)
        while j < n_out and t_out[j] <= t_new:
            theta = (t_out[j] - t) / h_acc
            _interp_state(y, k1, ynew, k7, h_acc, theta, ys)
            for i in range(4):
                Y[j, i] = ys[i]
            C[j] = contact
            j += 1
        for i in range(4):
            y[i] = ynew[i]
            if not np.isfinite(y[i]):
                info[0] = NOT_FINITE
                return Y, C, info, ext
        t = t_new
        d0, dd0 = d1, dd1
        info[1] += 1
        if pa is not None or cp is not None or tfs is not None:
            # Cap the next step at 1/omega of the local interface spring: a stiff contact would
            # otherwise run the explicit method at its stability limit, where the step controller
            # is erratic (Hairer & Wanner, Solving ODEs II, IV.2).
            d_now = d0
            kk = 0.0
            if tfs is not None:
                kk += _stiffening(p, d_now + p[P_YS])[1]
            if cp is not None and contact:
                kk -= p[P_AN] * _ppval(cp, p[P_TAB_X0], p[P_TAB_H], d_now)[1]
            if pa is not None:
                kk += p[P_AN] * _ppval(pa, p[P_TAB_X0], p[P_TAB_H], d_now)[1]
            kk = abs(kk)
            h_stiff = p[P_HSTIFF] / np.sqrt(kk * m_eff_inv) if kk > 0.0 else h_max
        if t_hold > 0.0 and abs(t - t_hold) <= 1e-12 * t_hold:
            t = t_hold  # land exactly on the end of the dwell (checked at the top of the loop)
        if switched:
            contact = not contact
            t_hold = t + p[P_DWELL] if p[P_DWELL] > 0.0 else -1.0
            rhs(t, y, p, dmw, cp, pa, ft, pitch, tfs, rlin, contact, k1)
            info[4] += 1
        else:
            for i in range(4):
                k1[i] = k7[i]
        # step growth 0.9 e^(-1/5) in [0.2, 5]; e < (0.9/5)^5 gives the cap without calling pow()
        h = h * (5.0 if e < 1.889568e-4 else max(0.2, 0.9 * e ** -0.2))
    return Y, C, info, ext


numba.config.CACHE_DIR = _NUMBA_CACHE_DIR  # (the kernels above have their folder: see the imports)
