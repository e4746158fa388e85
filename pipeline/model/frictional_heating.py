"""The frictional heat's protrusion at the TFC point: its kernel update and its steady state.

The friction power ``Q V`` of the contact heats the pole tip, which protrudes by ``delta_f`` on top of the
heater's protrusion ``delta`` (docs/model.md, section "Frictional heating"), a first-order lag of time
constant ``tau_f`` behind its steady value ``eta_f Q V``::

    d(delta_f)/dt = (eta_f V Q(t) - delta_f) / tau_f

``tau_f`` (0.1-1 ms, measured for TFC heaters) is 10^3-10^5 times the kernel's step, so the kernel does not
put ``delta_f`` in its error-controlled step: after each accepted step it advances ``delta_f`` by the exact
solution of the lag with ``Q`` linear in time between the step's ends (:func:`heat_update`; exact for a
constant ``Q``, second order otherwise), and the next step sees the new protrusion (a splitting: within a
step the mechanics runs at the protrusion of its start). ``Q`` between the step's ends is the force the
step's mode gives at its end separation (:func:`heat_friction`). The heat's protrusion is the pole tip's as the
heater's is: the nominal area ``A_n`` and the tabulated TFC-point force (the bulge's lift) are read at
``delta + delta_f``, linearly between tables a fixed protrusion step apart (:func:`heat_tables`;
:func:`pipeline.model.kernel_inputs.heat_grid`).

The steady state of a static contact, ``delta_f = eta_f V Q(delta + delta_f)``, is one fixed point solved by
one rule, :func:`heat_fixed_point` (the statics map's :func:`pipeline.analyses.mechanism_statics.heated_contact`
and a run's static start, :func:`pipeline.model.running.start`).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .compiled import kernel_jit
from .forces import friction_force
from .piecewise import _ppindex
from ..units import NM

_inline = kernel_jit(__name__, inline="always")

#: The kernel re-reads its tables at ``delta + delta_f`` (:func:`heat_tables`) when ``delta_f`` has moved by more
#: than this [m] since the last read: 1e-4 nm, 2e-4 of the tables' protrusion step (the read costs a pass over
#: the TFC table, ~4000 pieces; ``delta_f`` moves by ~1e-5 nm a step in a transient).
RETABLE = 1e-4 * NM

#: The fixed point of :func:`heat_fixed_point` is solved to this [m]; and at most :data:`MAX_ITER` secant steps.
HEAT_TOL = 1e-6 * NM
MAX_ITER = 40


@kernel_jit(__name__)
def heat_update(delta_f, a0, a1, h, tau):
    """``delta_f`` [m] a time ``h`` [s] later under ``d(delta_f)/dt = (a(t) - delta_f) / tau``, ``a`` [m] the steady
    value ``eta_f V Q`` going linearly from ``a0`` to ``a1`` over ``h`` (the exact solution; ``tau`` [s]).

    ``delta_f(h) = a1 + (delta_f - a0) E - (a1 - a0) (tau / h) (1 - E)``, ``E = exp(-h / tau)`` (the linear
    forcing's particular solution ``a0 + s (t - tau)``, ``s = (a1 - a0) / h``, plus the homogeneous one;
    ``1 - E`` by ``expm1``: ``h / tau`` is ~1e-5 in the kernel).
    """
    x = h / tau
    one_minus = -math.expm1(-x)
    return a1 + (delta_f - a0) * (1.0 - one_minus) - (a1 - a0) * (one_minus / x)


@kernel_jit(__name__)
def heat_tables(tfc, heating, delta_f):
    """The nominal area ``A_n`` [m^2] at ``delta + delta_f`` and the TFC table ``tfc`` (``None``: no tabulated law)
    overwritten with its coefficients there: linear in the protrusion between the grid's tables ``heating[4]``
    and areas ``heating[3]`` at ``delta + j heating[2]`` (:func:`pipeline.model.kernel_inputs.heat_grid`;
    beyond the grid's last protrusion, the last interval's line). At ``delta_f = 0`` the grid's first entry bit
    for bit; a one-entry grid (the statics' slot) is that entry."""
    step, areas, tables = heating[2], heating[3], heating[4]
    n = areas.shape[0]
    if n < 2:
        return areas[0]
    x = delta_f / step
    j = min(max(int(math.floor(x)), 0), n - 2)
    s = x - j
    if tfc is not None:
        for i in range(tfc.shape[0]):
            for c in range(tfc.shape[1]):
                tfc[i, c] = tables[j, i, c] + s * (tables[j + 1, i, c] - tables[j, i, c])
    return areas[j] + s * (areas[j + 1] - areas[j])


def heated_areas(step: float, areas: np.ndarray, delta_f: np.ndarray) -> np.ndarray:
    """:func:`heat_tables`'s ``A_n`` [m^2] at the heat's protrusions ``delta_f`` [m] (array), bit for bit: the
    histories' nominal area of a heated run."""
    x = np.asarray(delta_f, float) / step
    if areas.shape[0] < 2:
        return np.full(x.shape, areas[0])
    j = np.clip(np.floor(x).astype(int), 0, areas.shape[0] - 2)
    s = x - j
    return areas[j] + s * (areas[j + 1] - areas[j])


@_inline
def heat_friction(p, friction, in_contact, d, heating):
    """The steady protrusion ``eta_f V Q`` [m] of the friction force at the separation ``d`` [m] in the mode
    ``in_contact`` (:func:`pipeline.model.forces.friction_force`); 0 without the frictional heat or the table."""
    if heating is None or friction is None:
        return 0.0
    i, s = _ppindex(p.tab_n, p.tab_x0, p.tab_h, d)
    return heating[0] * friction_force(p, friction, in_contact, i, s)


def heat_fixed_point(steady: Callable[[float], float], tol: float = HEAT_TOL, max_iter: int = MAX_ITER
                     ) -> tuple[float, float]:
    """The steady frictional heat's protrusion: the root of ``x = steady(x)`` [m], ``steady(x)`` the steady value
    ``eta_f V Q`` of the static contact state at the protrusion ``delta + x`` (NaN where none continues it),
    by secant steps from ``x = 0`` to ``tol`` [m].

    Returns
    -------
    delta_f : float
        The fixed point [m] (NaN: no contact state on the way, or no convergence in ``max_iter`` steps).
    gain : float
        ``d steady / dx`` at the fixed point [1] (the last secant): below 1 the fixed point is stable, at or
        above 1 a thermal runaway.
    """
    x0, g0 = 0.0, steady(0.0)
    x1 = g0
    g1 = steady(x1) if np.isfinite(g0) else np.nan
    gain = np.nan
    for _ in range(max_iter):
        if not np.isfinite(g1):
            return np.nan, np.nan
        h0, h1 = g0 - x0, g1 - x1
        gain = (g1 - g0) / (x1 - x0) if x1 != x0 else gain
        if abs(h1) < tol:
            return x1, gain
        x2 = x1 - h1 * (x1 - x0) / (h1 - h0) if h1 != h0 else g1
        x0, g0 = x1, g1
        x1 = x2
        g1 = steady(x1)
    return np.nan, gain
