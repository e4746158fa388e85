"""The static equilibrium's Newton solve, compiled on the kernel's own forces (numba, releases the GIL).

:func:`pipeline.physics.equilibrium.newton` is the method's definition: Newton's method on
``R(y) = 0`` for the static state ``y = (z [m], theta [rad])`` with a central-difference Jacobian
(steps ``1e-6 scale``), a trust bound ``max_step`` on each update, convergence when every update is
below ``tol scale`` (docs/model.md, section "Start state"). Here the same iteration runs in one
compiled call on the kernel's right-hand side at zero velocity on the mean disk
(:func:`pipeline.model.forces.rhs_slots` with ``w = 0``), so a start state costs no Python per force
evaluation and the dask threads of a sweep or a calibration compute their starts in parallel (the
Python Newton holds the GIL; docs/performance.md has the measurements).

It returns the same :class:`pipeline.physics.equilibrium.Equilibrium` as the Python method: the
state, the stiffness ``K = -dR/dy``, convergence, stability, iterations and the scaled residual.
Two details differ in arithmetic only: the 2x2 linear solve is written out (Gaussian elimination
with partial pivoting, the LAPACK ``getrf``/``getrs`` steps), and stability is read from the trace
and determinant of ``K`` (both eigenvalues of a real 2x2 matrix have positive real parts exactly when
``tr K > 0`` and ``det K > 0``) instead of from its eigenvalues. tests/model/test_static_solver.py and
tests/model/test_start.py check that the compiled and the Python solves agree to the Newton tolerance.

The slots follow the kernel's convention (:data:`pipeline.model.dynamics.SLOTS`, last, one by one;
the parameters and the gap-power record as one-element arrays).
"""

from __future__ import annotations

import numpy as np

from ..physics.equilibrium import Equilibrium
from . import dynamics as dyn
from .compiled import announce, kernel_jit
from .forces import rhs_slots, separation_at
from .state import N_STATE, THETA, THETA_RATE, Z, Z_RATE

_jit = kernel_jit(__name__)
_inline = kernel_jit(__name__, inline="always")


@_inline
def static_residual(y0, y1, p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus):
    """``R = (F_z [N], M_theta [N m])`` at the static state ``(y0, y1)`` (``M_theta`` replaced by ``-theta``
    with the pitch locked: a restoring stand-in, zero at ``theta = 0`` with a positive stiffness, so the
    stability test of ``K = -dR/dy`` reads the heave alone): the right-hand side at zero velocity, ``t = 0``,
    in the contact mode the paper's criterion gives (``d < k sigma``)."""
    y4[Z] = y0
    y4[THETA] = y1
    in_contact = separation_at(p, y0, y1, 0.0) < p.k_sigma
    rhs_slots(0.0, y4, p, in_contact, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
              meniscus)
    R[0] = p.m * out[Z_RATE]
    if pitch is None:
        R[1] = -y1
    else:
        R[1] = p.I * out[THETA_RATE]


@_inline
def _jacobian(y, scale, p, J, R, Rp, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
              meniscus):
    """``J = dR/dy`` by central differences with steps ``1e-6 scale`` (as
    :func:`pipeline.physics.equilibrium.jacobian`)."""
    for j in range(2):
        h = 1e-6 * scale[j]
        a0, a1, b0, b1 = y[0], y[1], y[0], y[1]
        if j == 0:
            a0, b0 = y[0] + h, y[0] - h
        else:
            a1, b1 = y[1] + h, y[1] - h
        static_residual(a0, a1, p, Rp, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus)
        static_residual(b0, b1, p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus)
        J[0, j] = (Rp[0] - R[0]) / (2 * h)
        J[1, j] = (Rp[1] - R[1]) / (2 * h)


@_inline
def _solve2(J, b, x):
    """``x = J^-1 b`` for a 2x2 ``J`` by elimination with partial pivoting; ``False`` when a pivot is zero
    (a singular matrix, where LAPACK's ``getrf`` reports one)."""
    if abs(J[1, 0]) > abs(J[0, 0]):
        r0, r1 = 1, 0
    else:
        r0, r1 = 0, 1
    a00, a01, a10, a11 = J[r0, 0], J[r0, 1], J[r1, 0], J[r1, 1]
    if a00 == 0.0:
        return False
    l10 = a10 * (1.0 / a00)
    u11 = a11 - l10 * a01
    if u11 == 0.0:
        return False
    c1 = b[r1] - l10 * b[r0]
    x[1] = c1 / u11
    x[0] = (b[r0] - a01 * x[1]) / a00
    return True


@_jit
def _newton(y_start, scale, max_step, tol, max_iter, params, dmw, contact, adhesion, friction, tfc, pitch,
            rear_law, gap_power_, meniscus):
    """:func:`pipeline.physics.equilibrium.newton` on the kernel's static forces, compiled: returns
    ``(y, K, converged, stable, iterations, residual)``."""
    p = params[0]
    gap_power = dyn._unpacked(gap_power_)
    y = y_start.copy()
    J = np.empty((2, 2))
    R = np.empty(2)
    Rp = np.empty(2)
    rhs_ = np.empty(2)
    dy = np.empty(2)
    y4 = np.zeros(N_STATE)
    out = np.empty(N_STATE)
    converged = False
    it = 0
    for k in range(1, max_iter + 1):
        it = k
        _jacobian(y, scale, p, J, R, Rp, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
                  meniscus)
        static_residual(y[0], y[1], p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
                meniscus)
        rhs_[0] = -R[0]
        rhs_[1] = -R[1]
        if not _solve2(J, rhs_, dy):
            break
        if not (np.isfinite(dy[0]) and np.isfinite(dy[1])):
            break
        shrink = max(abs(dy[0]) / max_step[0], abs(dy[1]) / max_step[1])
        if shrink > 1:
            dy[0] = dy[0] / shrink
            dy[1] = dy[1] / shrink
        y[0] = y[0] + dy[0]
        y[1] = y[1] + dy[1]
        if shrink <= 1 and abs(dy[0]) < tol * scale[0] and abs(dy[1]) < tol * scale[1]:
            converged = True
            break
    _jacobian(y, scale, p, J, R, Rp, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
              meniscus)
    K = -J
    static_residual(y[0], y[1], p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus)
    finite_K = np.all(np.isfinite(K))
    fscale = 1.0
    if finite_K:
        fscale = max(abs(K[0, 0]) * scale[0] + abs(K[0, 1]) * scale[1],
                     abs(K[1, 0]) * scale[0] + abs(K[1, 1]) * scale[1])
    finite_R = np.isfinite(R[0]) and np.isfinite(R[1])
    stable = False
    if finite_K:  # both eigenvalues of a real 2x2 matrix in the right half-plane: tr > 0 and det > 0
        stable = K[0, 0] + K[1, 1] > 0 and K[0, 0] * K[1, 1] - K[0, 1] * K[1, 0] > 0
    residual = max(abs(R[0]), abs(R[1])) / fscale if fscale > 0 else np.inf
    return y, K, converged and finite_R, stable, it, residual


def newton(y_start: np.ndarray, p: np.record, slots: tuple, *, scale: np.ndarray, max_step: np.ndarray | None = None,
           tol: float = 1e-10, max_iter: int = 50) -> Equilibrium:
    """The static equilibrium from ``y_start`` (``(z [m], theta [rad])``) by the compiled Newton solve.

    Parameters
    ----------
    y_start : start state; p : the kernel's parameters at the protrusion (a
        :data:`pipeline.model.dynamics.PARAMS` record)
    slots : the kernel's slots in the order of :data:`pipeline.model.dynamics.SLOTS`
        (:func:`pipeline.model.dynamics._slots`), with the static forces' tables (no DMW, no meniscus state)
    scale, max_step, tol, max_iter : as :func:`pipeline.physics.equilibrium.newton`
    """
    scale = np.asarray(scale, dtype=float)
    max_step = scale if max_step is None else np.asarray(max_step, dtype=float)
    y, K, converged, stable, it, residual = _newton(np.asarray(y_start, dtype=float), scale, max_step, float(tol),
                                                     int(max_iter), dyn._packed(p), *slots)
    return Equilibrium(y, K, bool(converged), bool(stable), int(it), float(residual))


# (6-7 s of CPU for the main scene's effects on the project's 2-core machine: docs/performance.md,
# section "The first run")
announce(_newton, "the static solver for this scene's effects")
