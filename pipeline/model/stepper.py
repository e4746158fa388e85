"""The integrator's step: Dormand-Prince 5(4) with dense output, error norm, events and extremes.

Dormand-Prince 5(4) with classical step control (Hairer, Norsett & Wanner, *Solving ODEs I*, II.4
and II.5), local extrapolation, error norm the RMS of the embedded error scaled by
``atol + rtol |y|`` (:func:`error_norm`). The state between a step's ends is the cubic Hermite
interpolant through its end values and derivatives (:func:`_hermite`): the outputs
(:func:`sample_outputs`) and the events are taken on it.

Events. The contact switch is a discontinuity of the force: a sign change of ``g = d - k sigma`` over
an accepted step (at its ends, or at an interior extremum of ``d``, so a grazing contact shorter than
a step is not missed: :func:`first_wrong_side`) is located by bisection on the step's interpolant
(:func:`switch_point`); the driver redoes the step exactly up to it.

Interior extrema of ``d`` in a step (:func:`knot_extrema`, :func:`cubic_extrema`, for the event search and
the exact steady-window extremes, :func:`track_extremes`) are those of ``d(t) = const + s(t) - w(t)``:
``s = z - l_c theta`` on the state's Hermite cubic and ``w`` the DMW spline. Between two DMW knots
both are cubics, so the step is split at the knots it contains and each piece's extrema come in
closed form: exact for DMW content up to the Nyquist frequency, where a 500-ns step spans several
250-ns knots (one cubic through the step's ends would miss the peaks in between).

The inlined helpers here end an array's use unconditionally and call no compiled function, so that
numba can prune the reference counts of their array arguments (docs/kernel.md). The step, and the step's cap
:func:`stiffness_cap`, are compiled without reference counts (:data:`pipeline.model.compiled.BORROWING`).
"""

from __future__ import annotations

import numpy as np

from .compiled import BORROWING, kernel_jit
from .forces import interface_stiffness, rhs_at, separation, tfc_air_force
from .piecewise import disk3
from .state import MENISCUS, N_STATE, THETA, THETA_RATE, Z, Z_RATE, state_size

_jit = kernel_jit(__name__)
_inline = kernel_jit(__name__, inline="always")
_jit_borrowing = kernel_jit(__name__, **BORROWING)  # (no reference counts: pipeline.model.compiled.BORROWING)

# Dormand-Prince 5(4) tableau (Hairer, Norsett & Wanner, Table II.5.2)
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40)


@_jit_borrowing
def step(t, y, k1, h, p, in_contact, fresh, ynew, k7, err, tmp, k2, k3, k4, k5, k6, w_end,
         dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus):
    """One Dormand-Prince step: ``ynew``, its derivative ``k7`` and the error estimate ``err``
    (``tmp``, ``k2``...``k6``: work arrays, passed one by one), and the disk under the TFC point at the step's
    end, ``w_end[0]`` [m] and ``w_end[1]`` [m/s] (its last stage's lookup: the separation at the end reuses
    it, :func:`pipeline.model.forces.separation_of`); the slots as in
    :data:`pipeline.model.dynamics.SLOTS`. With ``fresh``, the step first evaluates ``k1``, the derivative at
    ``(t, y)`` (the first step, and the first after a contact switch; otherwise ``k1`` is the last step's
    ``k7``: FSAL). Returns how many times it evaluated the right-hand side (6, or 7 with ``fresh``).
    Compiled without reference counts (:data:`pipeline.model.compiled.BORROWING`): it allocates nothing.

    The right-hand side (:func:`pipeline.model.forces.rhs_at`) is inlined once, in a loop over the six
    stages (one copy: its compile), and so is the disk under the three points at the stage's time
    (:func:`pipeline.model.piecewise.disk3`, looked up at the top of each stage but the last, which shares
    ``t + h`` with the one before): it depends on the time alone, not on the stage before, so the core looks it
    up beside that stage's chain, and no stage pays a call with the slots' ~60 words of arguments
    (docs/kernel.md, sections "The right-hand side in the step" and "The disk in the stage loop"). The same
    operations in the same order as :func:`pipeline.model.forces.rhs_slots` at each stage: results those of six
    calls of it to their last bits (LLVM fuses products and sums in each compiled function on its own,
    :data:`pipeline.model.compiled.OPTIONS`).
    """
    ns = state_size(meniscus)
    # the disk at the stage's time t + c_i h (c = 0 when fresh, 1/5, 3/10, 4/5, 8/9, 1, 1): the last stage's is the
    # one before's (one copy of the lookup, inlined: docs/kernel.md, section "The disk in the stage loop")
    w = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for stage in range(0 if fresh else 1, 7):
        src = tmp
        dst = k7
        ts = t + h
        if stage == 0:
            src = y
            dst = k1
            ts = t
        elif stage == 1:
            for i in range(ns):
                tmp[i] = y[i] + h * A21 * k1[i]
            dst = k2
            ts = t + h / 5
        elif stage == 2:
            for i in range(ns):
                tmp[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i])
            dst = k3
            ts = t + 3 * h / 10
        elif stage == 3:
            for i in range(ns):
                tmp[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i])
            dst = k4
            ts = t + 4 * h / 5
        elif stage == 4:
            for i in range(ns):
                tmp[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i])
            dst = k5
            ts = t + 8 * h / 9
        elif stage == 5:
            for i in range(ns):
                tmp[i] = y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i])
            dst = k6
        else:
            for i in range(ns):
                ynew[i] = y[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i])
            src = ynew
        if stage != 6:
            w = disk3(p, dmw, ts)
        q = 0.0
        if meniscus is not None:
            q = src[MENISCUS]
        dst[Z], dst[THETA], dst[Z_RATE], dst[THETA_RATE], dq = rhs_at(
            p, in_contact, src[Z], src[THETA], src[Z_RATE], src[THETA_RATE], q, w[0], w[1], w[2], w[3], w[4], w[5],
            contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus)
        if meniscus is not None:
            dst[MENISCUS] = dq
    for i in range(ns):
        err[i] = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i])
    w_end[0] = w[0]
    w_end[1] = w[1]
    return 7 if fresh else 6


@_inline
def _hermite(y0, f0, y1, f1, h, frac, i):
    """Cubic Hermite interpolant of component ``i`` at ``t0 + frac h`` (``frac``: fraction of the step)."""
    t2 = frac * frac
    t3 = t2 * frac
    return ((2 * t3 - 3 * t2 + 1) * y0[i] + (t3 - 2 * t2 + frac) * h * f0[i]
            + (-2 * t3 + 3 * t2) * y1[i] + (t3 - t2) * h * f1[i])


@_inline
def _dcubic(d0, dd0, d1, dd1, h):
    """Coefficients ``(a, b, c, e)`` of the cubic Hermite ``d(frac) = a frac^3 + b frac^2 + c frac + e``
    through ``d0, d1`` with slopes ``dd0, dd1`` [per unit time] over a step ``h``: locates the interior
    extrema of ``d`` in closed form (their values are then taken on the state interpolant)."""
    return (2.0 * d0 + h * dd0 - 2.0 * d1 + h * dd1,
            -3.0 * d0 - 2.0 * h * dd0 + 3.0 * d1 - h * dd1,
            h * dd0, d0)


@_inline
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


@_inline
def knots_in_step(p, dmw, t, h, y, k1, ynew, k7):
    """Whether the step ``[t, t + h]`` contains a knot of the DMW spline, the piece ``i_a`` of ``t`` and the
    coefficients ``A, B, C`` of ``s = z - l_c theta`` on the state's Hermite cubic (``A frac^3 + B frac^2 +
    C frac + const`` [m]): what :func:`knot_extrema` needs. Without a knot ``d`` is one cubic over the step
    (:func:`cubic_extrema`)."""
    if dmw is None:
        return False, 0, 0.0, 0.0, 0.0
    # the arrays read before the branch (their last use unconditional: docs/kernel.md)
    z0, th0, vz0, vth0 = y[Z], y[THETA], k1[Z], k1[THETA]
    z1, th1, vz1, vth1 = ynew[Z], ynew[THETA], k7[Z], k7[THETA]
    t0, hd = p.dmw_t0, p.dmw_dt
    i_a = int((t - t0) / hd)
    first_knot = t0 + (i_a + 1) * hd
    if first_knot < t + h:
        lc = p.l_c
        A, B, C, E = _dcubic(z0 - lc * th0, vz0 - lc * vth0, z1 - lc * th1, vz1 - lc * vth1, h)
        return True, i_a, A, B, C
    return False, i_a, 0.0, 0.0, 0.0


@_jit
def knot_extrema(dmw, t, h, t0, hd, i_a, A, B, C, buf, n_max):
    """Interior extrema of ``d`` in a step ``[t, t + h]`` [s] that contains knots of the DMW spline ``dmw``
    (grid ``t0``, ``hd`` [s]; ``i_a``, ``A``, ``B``, ``C``: :func:`knots_in_step`): their step fractions in
    (0, 1), ascending, into ``buf`` (at most ``n_max``, :func:`extrema_slots`); returns how many.

    The step is split at the knots and on each piece ``d = const + s - w`` (``s = z - l_c theta`` on the
    state's Hermite cubic, ``w`` the spline piece) is a cubic whose Taylor coefficients at the piece's start
    give the extrema in closed form (module docstring). Compiled on its own, not inlined, and called from
    the kernel's loop itself (no inlined helper's arrays live across the call: docs/kernel.md): its copy in
    the kernel was a large part of the kernel's compile (docs/kernel.md, section "Compile time").
    """
    n_b = 0
    n_pieces = dmw.shape[0]
    ta = t
    i = i_a
    while ta < t + h and n_b + 2 <= n_max:
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


#: The margin [m] of :func:`extrema_matter`'s bound, over the rounding of ``d`` at a point (~1e-23 m)
EXTREMA_MARGIN = 1e-18


@_jit_borrowing
def extrema_matter(p, dmw, search, in_contact, knots, i_a, A, B, t, h, d0, dd0, d1, dd1, ext):
    """Whether the interior extrema of ``d`` in the step ``[t, t + h]`` [s] can change anything: an extremum on
    the wrong side of ``k sigma`` (the event search, with ``search``) or outside the window's extremes ``ext``
    (from ``p.t_win`` on). Where not, the kernel skips them (:func:`knot_extrema` or :func:`cubic_extrema`, and
    ``d`` at each): the search and the window's extremes come out bit for bit the same.

    ``d`` over the step (as a function of the step's fraction) is within ``M/8`` of its chord from ``d0`` to ``d1``
    [m], ``M`` a bound of its second derivative: with DMW knots inside (``knots``, :func:`knots_in_step`'s
    ``i_a``, ``A``, ``B``) that of the state's cubic ``s`` plus ``h^2`` times that of each DMW piece the step
    spans (each linear in the time: the larger of its ends), else that of the Hermite cubic of ``d`` through
    ``d0, dd0, d1, dd1`` [m, m/s] (:func:`_dcubic`); a jump ``J`` [m/s] of the DMW's slope at a knot inside (a
    linear record's kinks) adds ``h |J| / 4``, and :data:`EXTREMA_MARGIN` the rounding. (The chord's error is
    ``-int G(f, x) d''(x) dx`` with the linear interpolation's Peano kernel ``0 <= G(f, x) <= f (1 - f)``,
    ``int G dx = f (1 - f) / 2 <= 1/8``: the remainder of linear interpolation, e.g. Burden & Faires, *Numerical
    Analysis*, Thm. 3.3; docs/kernel.md, section "The extrema skipped where they cannot matter".) Compiled on its own without
    reference counts (:data:`pipeline.model.compiled.BORROWING`), called from the kernel's loop.
    """
    kink = 0.0
    if knots and dmw is not None:
        m = max(abs(2.0 * B), abs(6.0 * A + 2.0 * B))
        hd = p.dmw_dt
        n = dmw.shape[0]
        j_end = min(int((t + h - p.dmw_t0) / hd), n - 1)
        w2 = 0.0
        for j in range(min(max(i_a, 0), n - 1), j_end + 1):
            r0, r1, r2 = dmw[j, 0], dmw[j, 1], dmw[j, 2]
            w2 = max(w2, abs(2.0 * r1), abs(6.0 * r0 * hd + 2.0 * r1))
            if j < j_end:  # the slope's jump at the knot after piece j (a linear record's kinks; ~0 for a spline)
                kink += abs(dmw[j + 1, 2] - ((3.0 * r0 * hd + 2.0 * r1) * hd + r2))
        m += h * h * w2
    else:
        ca, cb, cc, ce = _dcubic(d0, dd0, d1, dd1, h)
        m = max(abs(2.0 * cb), abs(6.0 * ca + 2.0 * cb))
    b = m / 8.0 + h * kink / 4.0 + EXTREMA_MARGIN
    lo = min(d0, d1) - b
    hi = max(d0, d1) + b
    ks = p.k_sigma
    # (written so that a NaN bound says they matter)
    if search and (not (hi < ks) if in_contact else not (lo >= ks)):
        return True
    return t + h >= p.t_win and not (lo >= ext[0] and hi <= ext[1])


@_inline
def cubic_extrema(d0, dd0, d1, dd1, h, buf):
    """Interior extrema of ``d`` in a step ``h`` [s] without a DMW knot inside, where ``d`` is one cubic, the
    Hermite through its end values ``d0``, ``d1`` [m] and slopes ``dd0``, ``dd1`` [m/s]: their step fractions
    into ``buf[0]``, ``buf[1]``; returns how many."""
    ca, cb, cc, ce = _dcubic(d0, dd0, d1, dd1, h)
    n_ex, buf[0], buf[1] = _extrema(ca, cb, cc)  # both slots always (unused ones ignored): no branch on buf
    return n_ex


@_inline
def interp_state(y0, f0, y1, f1, h, frac, out):
    """The slider's state (not the meniscus state) at ``t0 + frac h`` into ``out`` (:func:`_hermite`)."""
    for i in range(N_STATE):
        out[i] = _hermite(y0, f0, y1, f1, h, frac, i)


@_inline
def step_points(p, search, h, d0, dd0, d1, dd1, buf, n_ex):
    """The step's interior points where ``d`` is checked: returns ``n_pts``.

    ``buf[:n_ex]``: the interior extrema of ``d`` (:func:`knot_extrema` or :func:`cubic_extrema`, ascending),
    for the event search and the steady-window extremes alike; with ``search`` (the contact switch is looked
    for) and ``d`` passing near the threshold, three more points, ``buf[n_ex:n_pts]`` = 1/4, 1/2, 3/4 (a
    grazing contact between the closed-form extrema and the ends). ``d`` at each (on the state interpolant,
    :func:`interp_state`, then :func:`separation`) is computed once by the kernel's loop for
    :func:`first_wrong_side` and :func:`track_extremes` (``buf``: ``n_max + 3`` slots, :func:`extrema_slots`).
    """
    ks = p.k_sigma
    n_pts = n_ex
    if search and min(abs(d0 - ks), abs(d1 - ks)) < 0.5 * h * max(abs(dd0), abs(dd1)):
        n_pts = n_ex + 3
    for i in range(n_ex, n_pts):
        buf[i] = 0.25 * (i - n_ex + 1)
    return n_pts


@_inline
def first_wrong_side(p, in_contact, d1, n_pts, buf, dex):
    """Smallest fraction ``frac`` in (0, 1] of the step where the criterion disagrees with the mode, or -1.

    Checks the step's end (``d1`` [m]) and the points of :func:`step_points` (their fractions ``buf``,
    ``d`` there ``dex`` [m]), values taken on the state interpolant, the one outputs and the bisection use.
    """
    ks = p.k_sigma
    best = 2.0
    if (d1 - ks < 0.0) != in_contact:
        best = 1.0
    for i in range(n_pts):
        frac = buf[i]
        if frac < best and (dex[i] - ks < 0.0) != in_contact:
            best = frac
    return best if best <= 1.0 else -1.0


@_jit_borrowing
def switch_point(p, dmw, in_contact, t, y, k1, ynew, k7, h, hi, ys):
    """The contact switch in the step ``[t, t + h]``, given the first fraction ``hi`` in (0, 1] where the
    criterion disagrees with the mode (:func:`first_wrong_side`): its step fraction, on the side where the
    criterion disagrees.

    Bisection on the step's interpolant to 1e-16 s (``(hi - lo) h``).
    :func:`pipeline.model.dynamics._integrate` redoes the step up to it. Compiled on its own, not inlined:
    it runs only at a switch, and its copy of the interpolant would otherwise be compiled into the kernel
    (docs/kernel.md, section "Compile time"); it calls the compiled :func:`separation`. The bisection loop
    has one exit (a counter, no ``break``): numba then prunes the reference counts of its array arguments.
    Compiled without reference counts (:data:`pipeline.model.compiled.BORROWING`: it allocates nothing): with the
    lookups' piece without the division (:func:`pipeline.model.piecewise.grid_piece`) numba's pruning kept a
    reference-count pair for each of its six arrays (docs/kernel.md, section "The piece without the division").
    """
    lo = 0.0
    n = 60
    while n > 0:  # (one exit: see the docstring)
        n -= 1
        mid = 0.5 * (lo + hi)
        interp_state(y, k1, ynew, k7, h, mid, ys)
        g = separation(p, dmw, t + mid * h, ys)[0] - p.k_sigma
        if (g < 0.0) != in_contact:
            hi = mid
        else:
            lo = mid
        if (hi - lo) * h < 1e-16:
            n = 0
    return hi


@_inline
def track_extremes(p, t, h, d1, n_ex, buf, dex, ext):
    """Exact extremes of ``d`` over the steady window into ``ext``: at the step's end (``d1`` [m]) and at the
    interior extrema of ``d`` (:func:`step_points`: their fractions ``buf[:n_ex]``, ``d`` there ``dex`` [m])
    that lie in the window (peak-to-peak free of aliasing by the output grid)."""
    ext[0] = min(ext[0], d1)
    ext[1] = max(ext[1], d1)
    for i_ex in range(n_ex):
        frac = buf[i_ex]
        if t + frac * h >= p.t_win:
            de = dex[i_ex]
            ext[0] = min(ext[0], de)
            ext[1] = max(ext[1], de)


@_inline
def sample_outputs(t, h, y, k1, ynew, k7, in_contact, t_out, j, Y, C, ns):
    """Sample the step ``[t, t + h]`` at the output times from ``t_out[j]`` on; returns the next ``j``."""
    n_out = t_out.shape[0]
    while j < n_out and t_out[j] <= t + h:
        frac = (t_out[j] - t) / h
        for i in range(ns):
            Y[j, i] = _hermite(y, k1, ynew, k7, h, frac, i)
        C[j] = in_contact
        j += 1
    return j


@_inline
def error_norm(y, ynew, err, atol, rtol, ns):
    """RMS of the embedded error scaled by ``atol + rtol max(|y|, |ynew|)`` over the ``ns`` state components."""
    e = 0.0
    for i in range(ns):
        sc = atol[i] + rtol * max(abs(y[i]), abs(ynew[i]))
        e += (err[i] / sc) ** 2
    return np.sqrt(e / float(ns))


@_inline
def extrema_slots(p, dmw, h_max):
    """Size of the buffer of interior extrema of ``d``: at most 2 per DMW spline piece a step spans."""
    if dmw is not None:
        return 2 * (int(h_max / p.dmw_dt) + 3)
    return 2


@_inline
def inverse_mass_at_tfc(p, pitch):
    """``1/m + l_c^2/I`` [1/kg] (``1/m`` with the pitch locked): the mass the interface spring moves."""
    return 1.0 / p.m + (p.l_c ** 2 / p.I if pitch is not None else 0.0)


@_jit_borrowing
def stiffness_cap(p, in_contact, d, h_max, m_eff_inv, contact, adhesion, tfc, gap_power, meniscus):
    """Largest step [s] after a step ending at separation ``d`` [m]: ``p.h_stiff`` over the angular
    frequency of the local interface spring (``h_max`` without one).

    A stiff contact would otherwise run the explicit method at its stability limit, where the step
    controller is erratic (Hairer & Wanner, Solving ODEs II, IV.2). Compiled on its own without reference
    counts (:data:`pipeline.model.compiled.BORROWING`), called once per accepted step from the kernel's loop:
    inlined there, its tables kept a reference-count pair each (docs/kernel.md, section "The step without
    reference counts").
    """
    if adhesion is None and contact is None and gap_power is None and tfc is None:
        return h_max
    kk = tfc_air_force(p, gap_power, tfc, d + p.y_s)[1]
    kk = abs(interface_stiffness(p, contact, adhesion, meniscus, in_contact, kk, d))
    return p.h_stiff / np.sqrt(kk * m_eff_inv) if kk > 0.0 else h_max

