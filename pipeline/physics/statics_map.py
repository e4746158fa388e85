"""Every static state along a one-parameter path, its stability and the barrier out of it (docs/model.md,
section "Statics map"): the relaxed path of a 2-DOF system, the other coordinate at its equilibrium at each value
of the path coordinate (:func:`relaxed_path`), and every equilibrium of a 1-D force along it with its stability
and the rise of the potential to the next unstable one (:func:`path_equilibria`, :class:`PathState`). The model's
statics map of a scene: :mod:`pipeline.model.statics`; the flying state, its fold and the contact branch:
:mod:`pipeline.physics.equilibrium`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class PathState:
    """One equilibrium on a path of the static force (:func:`path_equilibria`).

    Attributes
    ----------
    u : path coordinate of the state (e.g. the TFC point's displacement [m])
    stable : the path force pushes back towards ``u`` from both sides (it falls through zero)
    switch : the state sits on a break of the force (a jump through zero, e.g. the contact criterion's switch):
        a sliding equilibrium with no finite stiffness
    potential : ``V(u) = -int f du`` from the first state of the path [J when ``u`` is in m and ``f`` in N]
    barrier : the rise of ``V`` from a stable state to the lower of its neighbouring unstable states [J]
        (NaN for an unstable state, and for a stable state with no unstable neighbour: a single well)
    """

    u: float
    stable: bool
    switch: bool
    potential: float = np.nan
    barrier: float = np.nan


def relaxed_path(forces: Callable[[np.ndarray], np.ndarray], a, u_values, s0: float = 0.0, *, s_scale: float,
                 slope: float | None = None, tol: float = 1e-10, max_iter: int = 30
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The static force along the path ``a . y = u`` of a 2-DOF system with the other freedom relaxed.

    The state is held on ``a . y = u`` by an external force conjugate to ``u`` (for ``a = (1, -l_c)``,
    ``u = z - l_c theta`` is the height of a point at ``l_c`` behind the CG and the holding force acts
    there); along ``t = (-a_1 / a_0, 1)`` (``a . t = 0``) the state is free, so it sits where
    ``R(y) . t = 0``. Then ``R = f a`` and the path force ``f(u) = R_0 / a_0`` is the force the state
    exerts on the holder [N]; its zeros are the system's equilibria (the holding force vanishes) and
    ``-int f du`` is the work of the static forces along the path, the potential whose rises between
    equilibria are the barriers: holding one coordinate and relaxing the other is the "drag method" of
    reaction paths (Henkelman, Johannesson & Jonsson 2000, docs/model.md [HJJ00]), whose saddle is the
    true one where the relaxed state is one continuous function of ``u`` (docs/model.md, section
    "Statics map").

    Parameters
    ----------
    forces : ``R(y)`` [N, N m] of the state ``y = (y_0, y_1)``
    a : the path's covector (``a_0 != 0``); u_values : path coordinates, in the order of continuation
    s0 : the relaxed coordinate ``y_1`` at the first ``u`` (a start for the solve)
    s_scale : typical size of ``y_1`` (steps and tolerance ``tol s_scale``)
    slope : ``d(R . t)/dy_1`` to start the secant iteration with (default: a finite difference at the first ``u``)

    Returns
    -------
    f : numpy.ndarray
        The path force [N] at each ``u``.
    s : numpy.ndarray
        The relaxed coordinate ``y_1`` [rad] (the unit of ``y_1``) at each ``u``.
    converged : numpy.ndarray
        Whether the solve met its tolerance [-], at each ``u``.

    References
    ----------
    [HJJ00] (the drag method and where it fails); docs/model.md, section "Statics map".
    """
    a = np.asarray(a, dtype=float)
    us = np.asarray(u_values, dtype=float)
    t = np.array([-a[1] / a[0], 1.0])
    f, s_out, ok = np.full(us.size, np.nan), np.full(us.size, np.nan), np.zeros(us.size, bool)
    s = float(s0)
    for i, u in enumerate(us):
        def g(sv: float) -> tuple[float, np.ndarray]:
            R = forces(np.array([u / a[0], 0.0]) + sv * t)
            return float(R @ t), R
        gs, R = g(s)
        if slope is None or not np.isfinite(slope) or slope == 0:
            h = 1e-3 * s_scale
            slope = (g(s + h)[0] - gs) / h
        for _ in range(max_iter):
            if not (np.isfinite(gs) and np.isfinite(slope) and slope != 0):
                break
            ds = -gs / slope
            if abs(ds) < tol * s_scale:  # (the next update would be below the tolerance: ``s`` is the root)
                ok[i] = True
                break
            gn, Rn = g(s + ds)
            if np.isfinite(gn) and gn != gs:
                slope = (gn - gs) / ds  # secant: the relaxed freedom's stiffness, nearly constant along the path
            s, gs, R = s + ds, gn, Rn
        f[i], s_out[i] = R[0] / a[0], s
    return f, s_out, ok


def path_equilibria(f: Callable[[float], float], u_grid, breaks=(), *, xtol: float = 0.0,
                    epsilon: float | None = None, f_many: Callable[[np.ndarray], np.ndarray] | None = None
                    ) -> list[PathState]:
    """Every equilibrium of a 1-D force ``f(u)`` on ``[u_grid[0], u_grid[-1]]``, with potentials and barriers.

    The force is sampled on ``u_grid`` and on both sides of each break (``b -+ epsilon``, never on it): a sign
    change between samples is an equilibrium, refined by Brent's method to ``xtol``
    (a continuous zero) or placed on the break when it is one of the jump (a *switch* state: with the contact
    law switched on at a criterion, the slider is held on it from both sides, the sliding equilibrium of a
    Filippov system; Filippov, "Differential equations with discontinuous righthand sides", Kluwer 1988).
    Stable: ``f`` falls through zero (it pushes back from both sides), the 1-D reading of the positive
    stiffness ``-df/du > 0``. Two zeros inside one grid cell cancel and are not seen: the grid sets the
    resolution. The potential ``V(u) = -int f du`` between consecutive states is integrated by adaptive
    Gauss-Kronrod quadrature (``scipy.integrate.quad``), split at the breaks; the barrier out of a stable
    state is the rise of ``V`` to the lower of its unstable neighbours (a state at the end of the path has one).

    Parameters
    ----------
    f : the path force [N] (positive: pushing towards larger ``u``)
    u_grid : increasing sample points; breaks : points where ``f`` may jump (inside the grid)
    f_many : ``f`` at an increasing array of points, in one call (default: ``f`` at each): the samples
    xtol : Brent's absolute tolerance on ``u``; epsilon : the offset either side of a break (default ``1e-6`` of the
        smallest grid step)

    Returns
    -------
    list of PathState
        The states in order of ``u``: position [m] (the unit of ``u``), stability, potential [J] and barrier [J].

    References
    ----------
    [HJJ00] (reaction paths), [Filippov88] (the switch states); docs/model.md, section "Statics map".
    """
    from scipy.integrate import quad
    from scipy.optimize import brentq

    u = np.asarray(u_grid, dtype=float)
    if u.ndim != 1 or u.size < 2 or np.any(np.diff(u) <= 0):
        raise ValueError("path_equilibria: u_grid must be increasing, two points or more")
    eps = 1e-6 * float(np.min(np.diff(u))) if epsilon is None else float(epsilon)
    inside = sorted(float(b) for b in breaks if u[0] < b < u[-1])
    near = np.zeros(u.size, bool)  # (a sample within 2 epsilon of a break would split its jump)
    for b in inside:
        near |= np.abs(u - b) < 2 * eps
    # each break sampled on both sides, never on it: there the side a solver lands on is rounding's choice
    sides = {b: (b - eps, b + eps) for b in inside}
    xs = np.sort(np.concatenate([u[~near], [x for pair in sides.values() for x in pair]]))
    fs = np.asarray(f_many(xs), dtype=float) if f_many is not None else np.array([f(x) for x in xs])
    states: list[PathState] = []
    for i in range(xs.size - 1):
        f0, f1 = fs[i], fs[i + 1]
        if not (np.isfinite(f0) and np.isfinite(f1)) or (f0 > 0) == (f1 > 0):
            continue
        at = [b for b in inside if (xs[i], xs[i + 1]) == sides[b]]
        on_break = bool(at)
        x = at[0] if on_break else brentq(f, xs[i], xs[i + 1], xtol=xtol or 4 * np.finfo(float).eps)
        states.append(PathState(float(x), bool(f0 > f1), bool(on_break)))
    if not states:
        return states
    V = [0.0]
    for s0, s1 in zip(states[:-1], states[1:]):
        cuts = [s0.u] + [b for b in inside if s0.u < b < s1.u] + [s1.u]
        work = sum(quad(f, lo, hi, limit=50, epsabs=0.0, epsrel=1e-8)[0] for lo, hi in zip(cuts[:-1], cuts[1:]))
        V.append(V[-1] - work)
    out = []
    for j, s in enumerate(states):
        rises = [V[k] - V[j] for k in (j - 1, j + 1) if 0 <= k < len(states) and not states[k].stable]
        barrier = float(min(rises)) if s.stable and rises else np.nan
        out.append(PathState(s.u, s.stable, s.switch, float(V[j]), barrier))
    return out
