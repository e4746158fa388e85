"""Numba kernels of the 2-DOF slider: equations of motion and the adaptive integrator.

Equations of motion (docs/model.md, section "Slider dynamics"), states ``y = (z, theta, z', theta')``
in SI units::

    m z''     = F_f + F_r + F_i
    I theta'' = l_f F_f - l_r F_r - l_c F_i - h_cg Q

* front pad (``l_f`` ahead of the CG), linear:   ``F_f = -k_f (z + l_f theta - w_f) - c_f (...)'``
* rear pad (``l_r`` behind), nonlinear [recon]:  ``F_r = F_r0 [(g0/g_r)^n - 1] - c_r g_r'``,
  ``g_r = g0 + z - l_r theta - w_r``
* interface at the TFC point (``l_c`` behind), gap ``g = FH0 - delta + z - l_c theta - w_c`` to the mean
  of surface heights and ISBL separation ``d = g - y_s`` to the mean of summit heights (docs/model.md,
  section "Separation datum"): ``F_i = -A_n p_a(d)`` always (adhesion effect), plus
  ``A_n p_c(d) - c_c d'`` while in contact (``d < k sigma``, the paper's criterion)
* friction ``Q = A_n tau(d)`` in contact, along the disk's motion (leading to trailing edge) at the
  air-bearing surface; its moment about the CG is ``-h_cg Q`` (it pitches the leading edge down).
* the disk under each point moves with the DMW ``w(t)`` delayed by the disk's travel time.
* named model variants (docs/model.md, section "Model variants"): the rear law ``F_r = k_r (g0 - g_r)``
  (``Variants.rear_linear``) instead of the power law; an air-bearing force at the TFC point, either
  the closed-form stiffening spring ``F_t = k_t [G(g_n) - G(g)]``, ``G(s) = g0^p s^(1-p) / (1-p) - s``
  (``g0 ln s - s`` for ``p = 1``), stiffness ``-dF_t/dg = k_t [(g0/g)^p - 1]``
  (``Variants.gap_power``, :func:`pipeline.physics.air_bearing.tfc_stiffening_force`), or any law
  tabulated versus the gap ``g`` (``Tables.tfc``, see "Adding a variant" below), or both.
* the closed-form air-bearing laws (rear power and linear laws, the stiffening potential and
  stiffness) are compiled from their one definition in :mod:`pipeline.physics.air_bearing`.

Interface
---------
:func:`integrate` ``(y0, grid, p, tables, variants, solver)``:

* ``grid`` (:class:`Grid`): the end time and the output times;
* ``p``: the named parameters, one record of the structured dtype :data:`PARAMS` (numba types it as
  a ``Record``; fields are read as ``p.m``, ``p.k_sigma``...; :func:`params` makes one);
* ``tables`` (:class:`Tables`): the piecewise cubics of the DMW, of the interface laws versus the
  separation and of the tabulated TFC-point law versus the gap, each ``None`` when off;
* ``variants`` (:class:`Variants`): pitch on/off, the linear rear law, the gap-power parameters;
* ``solver`` (:class:`Solver`): tolerances, largest step, step budget.

Disabled effects cost nothing: an effect is off when its slot holds ``None``, and numba compiles one
specialised kernel per combination of slot types and prunes the dead branches at compile time
(branch pruning of ``arg is None``). That pruning sees only a compiled function's own arguments
(and the ``inline="always"`` functions inlined into it), not a tuple's members, and an array taken
out of a tuple costs two reference-count updates per use; so :func:`integrate` unpacks the bundles
once into :func:`_integrate`, and the inner functions (:func:`_step`, :func:`_rhs` and their inlined
helpers) take the slots one by one and compile to the code of a flat kernel. All kernels are cached
on disk (``cache=True``).

Adding a variant
----------------
A new force law at the TFC point (the bulge's air bearing of the physics issue, a "reynolds" table
F(g, delta), ...) is tabulated, not compiled: its law is a plain Python function of the gap array
and the protrusion in its physics module, registered with ONE line in its registry
(:data:`pipeline.physics.air_bearing.TFC_STIFFENING`: ``"name": TfcLaw(force)``). The model assembly
(:func:`pipeline.model.slider.tfc_table`) samples it per protrusion on a gap grid into a piecewise cubic
(as the interface tables), which the kernel's one generic slot ``Tables.tfc`` evaluates: force and
stiffness ``-dF/dg`` (the step-size cap) from the same cubic, so the kernel, its argument list and
its compiled cache are untouched. The alternative, numba first-class functions (the ``@njit`` law
passed as an argument), specialises the kernel on the law's dispatcher object, whose type is not the
same in the next process: measured (numba 0.68, a kernel taking a law and ``cache=True``), the
on-disk cache missed in every new process, so every ``hdi`` command would compile the kernel again
(20-27 s of CPU for the paper scene's specialisation, measured cold). A tabulated law costs one cubic
evaluation, like an interface table, and is exact to the table's interpolation error
(:func:`pipeline.model.slider.tfc_table`; the gap-power law tabulated: force within 3e-8 of its range,
stiffness 5e-8 relative above 1 nm, a 1-ms run's separation within 1e-10 nm of the closed form's,
tests/test_model_variants.py). The closed-form gap-power law keeps its compiled branch
(bit-identical results).

Internal state: the meniscus formation of issue 17 (docs/model.md, section "Meniscus formation") is a
fifth state component, the adhesion pressure ``q`` [Pa] relaxing towards the table's value,
``q' = (p_a(d) - q) / tau_m``, with the adhesion force ``-A_n q``. It is the slot ``Variants.meniscus``
(``tau_m`` [s], ``None``: off); the state length is ``4 + (meniscus is not None)``
(:func:`_state_size`), a compile-time constant, so the four-component arithmetic (error norm over
4 components) and its results are unchanged when it is off. The contact-switch events and the
extremes of ``d`` read only the first four components.

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
for at least ``p.dwell`` seconds after a switch (``solver.min_dwell_ns``); if the criterion says
otherwise when the dwell ends, the mode switches there. The resulting fast switching averages the
contact force to the sliding-mode value with an error of the order of the dwell; the dwell is an
accuracy knob of the accuracy stage. Crossings further apart than the dwell are located exactly.
"""

from __future__ import annotations

import os
from typing import NamedTuple

import numba
import numpy as np
from numba import njit

from ..code_version import code_key
from ..units import NS
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

#: The kernel's named parameters (all SI), one record (``np.record``; numba: ``Record``).
PARAMS = np.dtype((np.record, [
    ("m", "f8"), ("I", "f8"),                        # mass [kg], pitch inertia [kg m^2]
    ("l_f", "f8"), ("l_r", "f8"), ("l_c", "f8"),     # arms of the front pad, rear pad, TFC point [m]
    ("h_cg", "f8"),                                  # CG height over the air-bearing surface [m]
    ("k_f", "f8"), ("k_r", "f8"), ("c_f", "f8"), ("c_r", "f8"),  # pad stiffness [N/m], dampers [N s/m]
    ("g0", "f8"), ("n", "f8"), ("F_r0", "f8"),       # rear law: reference gap [m], exponent [1], preload [N]
    ("FH0", "f8"), ("delta", "f8"),                  # flying height [m], protrusion [m]
    ("A_n", "f8"), ("k_sigma", "f8"), ("c_c", "f8"),  # nominal area [m^2], criterion [m], contact damper [N s/m]
    ("off_f", "f8"), ("off_r", "f8"), ("off_c", "f8"),  # disk travel time to the front pad, rear pad, TFC [s]
    ("dmw_t0", "f8"), ("dmw_dt", "f8"),              # DMW spline grid: start, step [s]
    ("tab_x0", "f8"), ("tab_h", "f8"), ("tab_n", "i8"),  # interface-table grid: start [m], step [m], pieces
    ("tfc_x0", "f8"), ("tfc_h", "f8"),               # tabulated TFC-point law grid: start, step [m]
    ("dwell", "f8"),                                 # minimum dwell in a contact mode [s]
    ("t_win", "f8"),                                 # start of the steady window [s]
    ("h_stiff", "f8"),                               # step cap over 1/omega of the interface spring [1]
    ("y_s", "f8"),                                   # summit mean height over the surface mean [m]
]), align=True)

#: Parameters of the closed-form gap-power stiffening law at the TFC point (``Variants.gap_power``):
#: stiffness scale ``k_t`` [N/m], exponent ``q`` [1], reference gap ``g0`` [m], potential at the
#: nominal gap ``f0 = G(g_n)`` [m] (per protrusion), linear-continuation gap ``g_min`` [m] and stiffness
#: ``k_min`` [N/m] below it.
GAP_POWER = np.dtype((np.record, [("k_t", "f8"), ("q", "f8"), ("g0", "f8"), ("f0", "f8"), ("g_min", "f8"),
                                  ("k_min", "f8")]), align=True)


def params(dtype: np.dtype = PARAMS, **values: float) -> np.record:
    """A record of ``dtype`` (default :data:`PARAMS`) with the given fields set, the others zero."""
    return with_values(np.zeros((), dtype)[()], **values)


def with_values(p: np.record, **values: float) -> np.record:
    """A copy of the record ``p`` with the given fields set (item assignment is 3x faster than attribute
    assignment: run_model makes one per protrusion).

    The copy is a new 0-d array filled from ``p`` (~15 us): ``np.array(p)[()]``, even with
    ``copy=True``, returns a record that shares ``p``'s memory (numpy 2.4), so every run of a model
    wrote its protrusion into the model's own record, and runs in concurrent threads read each
    other's protrusion (tests/test_model_variants.py).
    """
    buf = np.empty((), p.dtype)
    buf[()] = p
    q = buf[()]
    for name, value in values.items():
        q[name] = value
    return q


class Grid(NamedTuple):
    """Time grid: integrate over ``[0, t_end]`` [s], sample the state at ``t_out`` [s] (ascending)."""

    t_end: float
    t_out: np.ndarray


class Tables(NamedTuple):
    """Piecewise-cubic coefficients (:func:`piecewise_coefficients`, rows of 4), ``None`` when off.

    dmw : the disk under the TFC point, the front and the rear pad [m] (:func:`disk_coefficients`),
        grid ``p.dmw_t0``, ``p.dmw_dt``
    contact, adhesion, friction : contact pressure, adhesion pressure, friction stress [Pa] versus the
        separation [m], grid ``p.tab_x0``, ``p.tab_h``, ``p.tab_n``. With the meniscus state
        (``Variants.meniscus``) ``adhesion`` may hold two tables side by side (8 columns): the part the
        state relaxes towards (columns 0-3: the menisci around contacts) and the part that acts at once
        (4-7: the bridges of the two-population model, docs/model.md, section "Two adhesion populations");
        :func:`static_table` sums them where no state is integrated
    tfc : tabulated air-bearing force at the TFC point [N] versus the gap [m], grid ``p.tfc_x0``,
        ``p.tfc_h`` (linear continuation below, constant above)
    """

    dmw: np.ndarray | None = None
    contact: np.ndarray | None = None
    adhesion: np.ndarray | None = None
    friction: np.ndarray | None = None
    tfc: np.ndarray | None = None


class Variants(NamedTuple):
    """Compiled model variants, each ``None`` when off.

    pitch : ``True`` for the pitch degree of freedom (``None`` locks it)
    rear_linear : ``True`` for the linear rear law (``None``: the power law)
    gap_power : the closed-form TFC stiffening law's parameters (a :data:`GAP_POWER` record)
    meniscus : the meniscus formation time ``tau_m`` [s] (> 0): the adhesion pressure becomes the fifth
        state component ``q`` [Pa], ``dq/dt = (p_a(d) - q) / tau_m`` (docs/model.md, section "Meniscus
        formation"); the state, ``y0``, the outputs and ``Solver.atol`` then have 5 components
    """

    pitch: bool | None = None
    rear_linear: bool | None = None
    gap_power: np.record | None = None
    meniscus: float | None = None


class Solver(NamedTuple):
    """Step control: relative tolerance ``rtol`` [1], per-component absolute tolerances ``atol`` (SI),
    largest step ``h_max`` [s], guard ``max_steps`` against a stalled integration."""

    rtol: float
    atol: np.ndarray
    h_max: float
    max_steps: int


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


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _ppat_at(c, i, s, col):
    """:func:`_ppat` of the piecewise cubic in columns ``col..col+3`` of ``c`` (two tables in one array)."""
    if i < 0:
        return c[0, col + 3] + c[0, col + 2] * s
    if i >= c.shape[0]:
        j = c.shape[0] - 1
        return ((c[j, col] * s + c[j, col + 1]) * s + c[j, col + 2]) * s + c[j, col + 3]
    return ((c[i, col] * s + c[i, col + 1]) * s + c[i, col + 2]) * s + c[i, col + 3]


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _ppslope_at(c, x0, h, x, col):
    """Slope of the piecewise cubic in columns ``col..col+3`` of ``c`` at ``x`` (as :func:`_ppval`)."""
    n = c.shape[0]
    u = (x - x0) / h
    if u < 0.0:
        return c[0, col + 2]
    i = int(u)
    if i >= n:
        return 0.0
    s = x - (x0 + i * h)
    return (3.0 * c[i, col] * s + 2.0 * c[i, col + 1]) * s + c[i, col + 2]


def static_table(c: np.ndarray | None) -> np.ndarray | None:
    """The one piecewise cubic of an adhesion slot: ``c`` itself, or, for the two tables of the meniscus
    state (columns 0-3 relaxing, 4-7 at once: :class:`Tables`), their sum (a cubic spline is linear in
    its data, so the sum of the coefficients is the spline of the summed table)."""
    if c is None or c.shape[1] == 4:
        return c
    return np.ascontiguousarray(c[:, :4] + c[:, 4:])


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
    return _ppval(dmw, p.dmw_t0, p.dmw_dt, t)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _disk3(p, dmw, t):
    """Disk displacement and velocity under the TFC point, the front and the rear pad at ``t``."""
    if dmw is None:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    h = p.dmw_dt
    n = dmw.shape[0]
    i = int((t - p.dmw_t0) / h)
    i = min(max(i, 0), n - 1)
    s = t - (p.dmw_t0 + i * h)
    r = dmw[i]
    return (((r[0] * s + r[1]) * s + r[2]) * s + r[3], (3.0 * r[0] * s + 2.0 * r[1]) * s + r[2],
            ((r[4] * s + r[5]) * s + r[6]) * s + r[7], (3.0 * r[4] * s + 2.0 * r[5]) * s + r[6],
            ((r[8] * s + r[9]) * s + r[10]) * s + r[11], (3.0 * r[8] * s + 2.0 * r[9]) * s + r[10])


@njit(cache=True, nogil=True, error_model="numpy")
def gap_at(p, z, theta, w):
    """Gap [m] at the TFC point to the mean of the disk's surface heights, ``FH0 - delta + z - l_c theta - w``.

    ``FH0`` is measured to the mean of surface heights (docs/model.md, section "Separation datum");
    scalars or arrays of ``z`` [m], ``theta`` [rad], ``w`` [m] alike (the one home of the datum, for
    the kernel and post-processing).
    """
    return p.FH0 - p.delta + z - p.l_c * theta - w


@njit(cache=True, nogil=True, error_model="numpy")
def separation_at(p, z, theta, w):
    """ISBL separation ``d`` [m] to the mean of summit heights: :func:`gap_at` minus ``y_s = p.y_s``.

    ``d = FH0 - delta + z - l_c theta - w - y_s`` (docs/model.md, section "Separation datum"; the ISBL
    tables are functions of this d).
    """
    return gap_at(p, z, theta, w) - p.y_s


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def separation(p, dmw, t, y):
    """TFC separation ``d`` [m] and its rate [m/s] (docs/model.md, section "Separation datum").

    The state is read before the DMW lookup's branches: ``y``'s last use is then unconditional, so
    numba prunes the reference-count pair of the inlined argument (see :func:`_integrate`).
    """
    z, th, vz, vth = y[0], y[1], y[2], y[3]
    wc, vc = _disk(p, dmw, t)
    return separation_at(p, z, th, wc), vz - p.l_c * vth - vc


# the air-bearing laws, compiled from their one definition in pipeline.physics.air_bearing
_JIT = dict(cache=True, nogil=True, inline="always", error_model="numpy")
_rear_power = njit(**_JIT)(ab.rear_power_law)
_rear_linear = njit(**_JIT)(ab.rear_linear_law)
_stiffening_potential = njit(**_JIT)(ab.stiffening_potential)
_stiffening_stiffness = njit(**_JIT)(ab.stiffening_stiffness)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _stiffening(q, g):
    """Force [N] (up positive) and stiffness [N/m] of the gap-power stiffening spring at the gap ``g`` [m].

    ``k(g) = k_t [(g0/g)^q - 1]``, force its integral from the nominal gap (constant ``q.f0`` =
    ``G(g_n)``), continued linearly below ``q.g_min`` where the law is singular (``q``: a
    :data:`GAP_POWER` record).
    """
    gm = q.g_min
    gg = max(g, gm)
    f = q.k_t * (q.f0 - _stiffening_potential(gg, q.g0, q.q))
    if g < gm:
        return f + q.k_min * (gm - g), q.k_min
    return f, _stiffening_stiffness(gg, q.g0, q.k_t, q.q)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _rear_force(p, rear_linear, z, th, vz, vth, wr, vr):
    """Rear-pad force [N] (up positive): the power law, or the linear one, plus its damper (the state's
    components as scalars: an array handed to an inlined helper costs a reference-count update pair
    per right-hand side, see :func:`_rhs`)."""
    g_r = p.g0 + z - p.l_r * th - wr
    if rear_linear is not None:
        F_r = _rear_linear(g_r, p.g0, p.k_r)
    else:
        g_r = max(g_r, 1e-3 * p.g0)  # the rear law is singular at zero gap; never reached in practice
        F_r = _rear_power(g_r, p.g0, p.n, p.F_r0)
    F_r -= p.c_r * (vz - p.l_r * vth - vr)
    return F_r


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _tfc_air_force(p, gap_power, tfc, g):
    """Air-bearing force [N] (up positive) and stiffness ``-dF/dg`` [N/m] at the TFC point, gap ``g`` [m]:
    the closed-form gap-power law plus the tabulated law (each ``None`` when off; zero without both)."""
    F = 0.0
    k = 0.0
    if gap_power is not None:
        f, kg = _stiffening(gap_power, g)
        F += f
        k += kg
    if tfc is not None:
        f, slope = _ppval(tfc, p.tfc_x0, p.tfc_h, g)
        F += f
        k -= slope
    return F, k


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _interface_force(p, cp, pa, ft, men, F_i, z, th, vz, vth, q, wc, vc, contact):
    """Add the interface forces at the state ``y`` (disk under the TFC point at ``wc`` [m], ``vc`` [m/s])
    to ``F_i`` [N]: adhesion always, contact pressure and damper in contact; returns it, the
    friction force ``Q`` [N] and the rate ``dq/dt`` [Pa/s] of the meniscus state (0 without one).

    With a meniscus formation time ``men`` [s] the adhesion pressure is the state ``q`` [Pa],
    relaxing towards the table's ``p_a(d)``: ``dq/dt = (p_a(d) - q) / men`` (docs/model.md, section
    "Meniscus formation").
    """
    Q = 0.0
    dq = 0.0
    if pa is not None or cp is not None:
        d, dd = separation_at(p, z, th, wc), vz - p.l_c * vth - vc  # (:func:`separation`)
        # one index for every table (they share the separation grid)
        i, s = _ppindex(p.tab_n, p.tab_x0, p.tab_h, d)
        if pa is not None:
            if men is not None:
                F_i -= p.A_n * q
                dq = (_ppat(pa, i, s) - q) / men
                if pa.shape[1] == 8:  # the part that acts at once (two populations: the bridges)
                    F_i -= p.A_n * _ppat_at(pa, i, s, 4)
            else:
                F_i -= p.A_n * _ppat(pa, i, s)
        if cp is not None:
            if contact:
                F_i += p.A_n * max(_ppat(cp, i, s), 0.0) - p.c_c * dd
                if ft is not None:
                    Q = p.A_n * max(_ppat(ft, i, s), 0.0)
    return F_i, Q, dq


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _interface_stiffness(p, cp, pa, men, contact, kk, d):
    """Add the interface tables' stiffness ``-A_n dp/dd`` [N/m] at ``d`` [m] to ``kk`` (contact in contact;
    adhesion unless it is the meniscus state, whose force does not depend on ``d`` at once)."""
    if cp is not None and contact:
        kk -= p.A_n * _ppval(cp, p.tab_x0, p.tab_h, d)[1]
    if pa is not None and men is None:
        kk += p.A_n * _ppval(pa, p.tab_x0, p.tab_h, d)[1]
    if pa is not None and men is not None and pa.shape[1] == 8:  # the part that acts at once
        kk += p.A_n * _ppslope_at(pa, p.tab_x0, p.tab_h, d, 4)
    return kk


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _accelerations(p, pitch, vz, vth, F_f, F_r, F_i, Q):
    """``dy/dt`` (4 components) from the forces [N]; the pitch rows are zero when the pitch is locked."""
    if pitch is None:
        return vz, 0.0, (F_f + F_r + F_i) / p.m, 0.0
    return vz, vth, (F_f + F_r + F_i) / p.m, (p.l_f * F_f - p.l_r * F_r - p.l_c * F_i - p.h_cg * Q) / p.I


def rhs(t: float, y: np.ndarray, p: np.record, tab: Tables, var: Variants, contact: bool, out: np.ndarray) -> None:
    """Write ``dy/dt`` into ``out`` (see the module docstring for the equations).

    ``tab``: :class:`Tables`; ``var``: :class:`Variants`; ``contact``: the contact mode. Flat
    arguments for the compiled function, as :func:`integrate`.
    """
    _rhs_flat(t, y, _packed(p), tab.dmw, tab.contact, tab.adhesion, tab.friction, tab.tfc, var.pitch,
              _packed(var.gap_power), var.rear_linear, var.meniscus, contact, out)


@njit(cache=True, nogil=True, error_model="numpy")
def _rhs_flat(t, y, params, dmw, cp, pa, ft, tfc, pitch, gap_power_, rlin, men, contact, out):
    """:func:`_rhs` called from Python (:func:`rhs`): the records as one-element arrays."""
    _rhs(t, y, params[0], dmw, cp, pa, ft, tfc, pitch, _unpacked(gap_power_), rlin, men, contact, out)


@njit(cache=True, nogil=True, error_model="numpy")
def _rhs(t, y, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, out):
    """:func:`rhs` with the slots as arguments: what the integrator calls (see :func:`_integrate`).

    The inlined helpers take the state's components as scalars, not ``y`` or ``out`` (the step's
    machine code 1.98 -> 1.92 M instructions per air-bearing-only run by callgrind, results
    bit-identical; benchmarks/kernel_ab.py). It was tested as the source of the out-of-line
    reference-count pair (24,000 per air-bearing-only run, 0.19 M instructions; 3,000 per run in commit
    e6348f9): it is not. callgrind's caller tree (``callgrind_annotate --tree=caller`` on a
    kernel_ab dump) puts the pair's ~6 calls per step in :func:`_integrate`'s own loop, not in
    :func:`_step` (with this function inlined into it by LLVM, called once per step); reading the
    DMW row element by element in :func:`_disk3` instead of through the view ``dmw[i]`` did not remove
    it either (4.66 -> 4.67 M instructions). It was the array arguments of the integrator loop's
    inlined helpers, 8 pairs per step (see :func:`_integrate`, which says how it was removed).

    What is left (kernel_ab's flying 5 nm and sliding 11 nm, the model with interface tables, per
    step; none in the air-bearing-only model): there LLVM keeps this function out of line, called 6
    times by :func:`_step`; numba keeps 4 reference-count pairs per call here (``cp``, ``pa``,
    ``ft``, ``out``: the contact and friction tables are read only in contact, a conditional last
    use, and reading them unconditionally did not remove them) and 15 in :func:`_step` (its array
    arguments, past the calls' exception exits), plus 2 in :func:`_stiffness_cap`: 41 increments per
    step (and as many or more decrements), 1.5 M of flying 5 nm's 18.9 M instructions and 5.1 M of
    sliding 11 nm's 56.0 M (e6348f9 had more: 2.8 M, 8.9 M). Not tried: ``inline="always"`` on this
    function (no calls left in :func:`_step`, at a compile-time cost).
    """
    z, th, vz, vth = y[0], y[1], y[2], y[3]
    wc, vc, wf, vf, wr, vr = _disk3(p, dmw, t)
    lf = p.l_f
    F_f = -p.k_f * (z + lf * th - wf) - p.c_f * (vz + lf * vth - vf)
    F_r = _rear_force(p, rlin, z, th, vz, vth, wr, vr)
    F_i = 0.0
    if gap_power is not None or tfc is not None:
        F_i = _tfc_air_force(p, gap_power, tfc, gap_at(p, z, th, wc))[0]
    q = 0.0
    if men is not None:
        q = y[4]
    F_i, Q, dq = _interface_force(p, cp, pa, ft, men, F_i, z, th, vz, vth, q, wc, vc, contact)
    out[0], out[1], out[2], out[3] = _accelerations(p, pitch, vz, vth, F_f, F_r, F_i, Q)
    if men is not None:
        out[4] = dq


# ---------------------------------------------------------------------------------------------
# Dormand-Prince 5(4) tableau (Hairer, Norsett & Wanner, Table II.5.2)
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40)



@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _state_size(men):
    """Length of the state: ``(z, theta, z', theta')`` and, with a meniscus formation time, ``q`` [Pa]
    (a compile-time constant: the four-component code is unchanged without the meniscus)."""
    if men is not None:
        return 5
    return 4


@njit(cache=True, nogil=True, error_model="numpy")
def _step(t, y, k1, h, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, ynew, k7, err,
          tmp, k2, k3, k4, k5, k6):
    """One Dormand-Prince step: ``ynew``, its derivative ``k7`` and the error estimate ``err``
    (``tmp``, ``k2``...``k6``: work arrays, passed one by one: see :func:`_rhs`)."""
    ns = _state_size(men)
    for i in range(ns):
        tmp[i] = y[i] + h * A21 * k1[i]
    _rhs(t + h / 5, tmp, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k2)
    for i in range(ns):
        tmp[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i])
    _rhs(t + 3 * h / 10, tmp, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k3)
    for i in range(ns):
        tmp[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i])
    _rhs(t + 4 * h / 5, tmp, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k4)
    for i in range(ns):
        tmp[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i])
    _rhs(t + 8 * h / 9, tmp, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k5)
    for i in range(ns):
        tmp[i] = y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i])
    _rhs(t + h, tmp, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k6)
    for i in range(ns):
        ynew[i] = y[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i])
    _rhs(t + h, ynew, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k7)
    for i in range(ns):
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
        # the arrays read before the branch (their last use unconditional: see :func:`_integrate`)
        z0, th0, vz0, vth0, z1, th1, vz1, vth1 = y[0], y[1], k1[0], k1[1], ynew[0], ynew[1], k7[0], k7[1]
        t0, hd = p.dmw_t0, p.dmw_dt
        i_a = int((t - t0) / hd)
        first_knot = t0 + (i_a + 1) * hd
        if first_knot < t + h:
            lc = p.l_c
            # s(theta) = A theta^3 + B theta^2 + C theta + E over the whole step
            A, B, C, E = _dcubic(z0 - lc * th0, vz0 - lc * vth0, z1 - lc * th1, vz1 - lc * vth1, h)
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
    n_ex, buf[0], buf[1] = _extrema(ca, cb, cc)  # both slots always (unused ones ignored): no branch on buf
    return n_ex


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _interp_state(y0, f0, y1, f1, h, theta, out):
    for i in range(4):
        out[i] = _hermite(y0, f0, y1, f1, h, theta, i)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _first_wrong_side(p, dmw, contact, t, y, k1, ynew, k7, h, d0, dd0, d1, dd1, ys, buf):
    """Smallest ``theta`` in (0, 1] of the step where the criterion disagrees with the mode, or -1.

    Checks the step's end, the interior extrema of ``d`` (closed form, :func:`_d_extrema`) and, when
    ``d`` passes near the threshold, a few interior points; values are taken on the state
    interpolant, the one outputs and the bisection use.
    """
    ks = p.k_sigma
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


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _switch_point(p, dmw, contact, t, y, k1, ynew, k7, h, d0, dd0, d1, dd1, ys, buf):
    """The contact switch in the step ``[t, t + h]``: its ``theta`` in (0, 1], or -1 if the criterion
    agrees with the mode over the whole step.

    The first point where the criterion disagrees (:func:`_first_wrong_side`) is bisected on the
    step's interpolant to 1e-16 s (``(theta_hi - theta_lo) h``); the returned ``theta`` is on the
    side where the criterion disagrees. :func:`_integrate` redoes the step up to it (the call of
    :func:`_step` stays there: a call has an exception exit, past which numba cannot prune the
    reference counts of an inlined helper's arrays). The bisection loop has one exit (a counter, no
    ``break``) for the same reason (see :func:`_integrate`).
    """
    hi = _first_wrong_side(p, dmw, contact, t, y, k1, ynew, k7, h, d0, dd0, d1, dd1, ys, buf)
    lo = 0.0
    n = 60 if hi >= 0.0 else 0
    while n > 0:  # (one exit: see the docstring)
        n -= 1
        mid = 0.5 * (lo + hi)
        _interp_state(y, k1, ynew, k7, h, mid, ys)
        g = separation(p, dmw, t + mid * h, ys)[0] - p.k_sigma
        if (g < 0.0) != contact:
            hi = mid
        else:
            lo = mid
        if (hi - lo) * h < 1e-16:
            n = 0
    return hi


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _track_extremes(p, dmw, t, h, y, k1, ynew, k7, d0, dd0, d1, dd1, ys, buf, ext):
    """Exact extremes of ``d`` over the steady window into ``ext``: at the step's end and at the interior
    extrema of ``d`` on the step's cubic (peak-to-peak free of aliasing by the output grid)."""
    ext[0] = min(ext[0], d1)
    ext[1] = max(ext[1], d1)
    n_ex = _d_extrema(p, dmw, t, h, y, k1, ynew, k7, d0, dd0, d1, dd1, buf)
    for i_ex in range(n_ex):
        th = buf[i_ex]
        if t + th * h >= p.t_win:
            _interp_state(y, k1, ynew, k7, h, th, ys)
            de = separation(p, dmw, t + th * h, ys)[0]
            ext[0] = min(ext[0], de)
            ext[1] = max(ext[1], de)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _sample_outputs(t, h, y, k1, ynew, k7, contact, t_out, j, Y, C, ns):
    """Sample the step ``[t, t + h]`` at the output times from ``t_out[j]`` on; returns the next ``j``."""
    n_out = t_out.shape[0]
    while j < n_out and t_out[j] <= t + h:
        theta = (t_out[j] - t) / h
        for i in range(ns):
            Y[j, i] = _hermite(y, k1, ynew, k7, h, theta, i)
        C[j] = contact
        j += 1
    return j


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _error_norm(y, ynew, err, atol, rtol, ns):
    """RMS of the embedded error scaled by ``atol + rtol max(|y|, |ynew|)`` over the ``ns`` state components."""
    e = 0.0
    for i in range(ns):
        sc = atol[i] + rtol * max(abs(y[i]), abs(ynew[i]))
        e += (err[i] / sc) ** 2
    return np.sqrt(e / float(ns))


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _extrema_slots(p, dmw, h_max):
    """Size of the buffer of interior extrema of ``d``: at most 2 per DMW spline piece a step spans."""
    if dmw is not None:
        return 2 * (int(h_max / p.dmw_dt) + 3)
    return 2


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _inverse_mass_at_tfc(p, pitch):
    """``1/m + l_c^2/I`` [1/kg] (``1/m`` with the pitch locked): the mass the interface spring moves."""
    return 1.0 / p.m + (p.l_c ** 2 / p.I if pitch is not None else 0.0)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _stiffness_cap(p, cp, pa, men, gap_power, tfc, contact, d, h_max, m_eff_inv):
    """Largest step [s] after a step ending at separation ``d`` [m]: ``p.h_stiff`` over the angular
    frequency of the local interface spring (``h_max`` without one).

    A stiff contact would otherwise run the explicit method at its stability limit, where the step
    controller is erratic (Hairer & Wanner, Solving ODEs II, IV.2).
    """
    if pa is None and cp is None and gap_power is None and tfc is None:
        return h_max
    kk = _tfc_air_force(p, gap_power, tfc, d + p.y_s)[1]
    kk = abs(_interface_stiffness(p, cp, pa, men, contact, kk, d))
    return p.h_stiff / np.sqrt(kk * m_eff_inv) if kk > 0.0 else h_max


def integrate(y0: np.ndarray, grid: Grid, p: np.record, tab: Tables, var: Variants, solver: Solver
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate from ``t = 0`` to ``grid.t_end`` [s]; sample the state at ``grid.t_out`` (ascending).

    Parameters
    ----------
    y0 : initial state ``(z [m], theta [rad], z' [m/s], theta' [rad/s])``
    grid : :class:`Grid`; p : named parameters (a :data:`PARAMS` record)
    tab : :class:`Tables` (``None`` slots disable their effect); var : :class:`Variants`
    solver : :class:`Solver`

    Returns
    -------
    Y : states at ``t_out`` (n_out, 4), (n_out, 5) with the meniscus state; C : contact flag at ``t_out``;
    info : ``[status, accepted steps, rejected steps, contact switches, rhs evaluations]``;
    ext : exact minimum and maximum of the separation ``d`` [m] over ``t >= p.t_win``

    Notes
    -----
    A plain Python function that hands the compiled :func:`_integrate` flat arguments, the records as
    one-element arrays (:func:`_packed`): numba's dispatcher types arrays, floats and ``None`` in C,
    but a record scalar and each named tuple through its Python ``typeof`` (measured: 6.5 us for a
    :data:`PARAMS` record, 2-2.6 us per named tuple; an empty integration 40 us against 10 us now and
    12 us for the positional-vector kernel of commit e6348f9). The rest of issue 16's regression was
    numba's reference counting in the integrator loop (:func:`_integrate`), now removed. By callgrind
    (benchmarks/kernel_ab.py, instructions per integration, one session): air-bearing-only scene at
    11 nm, flying 5 nm, sliding 11 nm: e6348f9 4.40, 21.56, 63.43 M; this kernel before 4.68, 22.12,
    65.24 M; now 4.26, 18.95, 56.02 M (-3 %, -12 %, -12 % against e6348f9), results bit-identical.
    Those totals include the interpreter's share (the Python wrapper, libm, and kernel_ab's polling of
    ``callgrind_control``, which grows with the machine's load: a rerun of the same code under load
    gave 4.31 M); the compiled code alone (callgrind's functions without a symbol): e6348f9 4.27,
    20.90, 61.73 M; before 4.49, 21.44, 63.48 M; now 4.12, 18.24, 54.25 M (identical in both runs).
    Timing (kernel_ab ``time``, medians of 7 x 100 calls, interleaved): air-bearing-only 0.64 ms now,
    0.73-0.75 before, 0.65 e6348f9; sliding 11 nm 10.3-10.9 ms, 13.0-13.1, 12.5-12.6.
    (Earlier air-bearing-only counts: e6348f9 4.32 M, 4.65 M before the flat arguments, 4.64 M with
    them, 4.58 M with the scalar helpers of :func:`_rhs`.) ``inline="never"`` on the kernel's
    functions halves the compile time (25 -> 15 s of CPU, sliding scene, cold cache) with
    bit-identical results but runs 5.35 M instructions (+15 %), so the helpers stay inlined.
    """
    return _integrate(y0, grid.t_end, grid.t_out, _packed(p), tab.dmw, tab.contact, tab.adhesion, tab.friction,
                      tab.tfc, var.pitch, _packed(var.gap_power), var.rear_linear, var.meniscus, solver.rtol,
                      solver.atol, solver.h_max, solver.max_steps)


def _packed(record: np.record | None) -> np.ndarray | None:
    """``record`` as a one-element array of its dtype (a copy; ``None`` stays ``None``): what the
    compiled functions take, typed by numba's dispatcher in C (:func:`integrate`)."""
    if record is None:
        return None
    a = np.empty(1, record.dtype)
    a[0] = record
    return a


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _unpacked(a):
    """The record of a one-element array (:func:`_packed`), ``None`` for ``None`` (pruned at compile time)."""
    if a is None:
        return None
    return a[0]


@njit(cache=True, nogil=True, error_model="numpy")
def _integrate(y0, t_end, t_out, params, dmw, cp, pa, ft, tfc, pitch, gap_power_, rlin, men, rtol, atol,
               h_max, max_steps):
    """:func:`integrate` with its bundles unpacked into the slots (``params``, ``gap_power_``: the
    records as one-element arrays, :func:`_packed`).

    Why the inner functions take the slots one by one: numba prunes a disabled effect's branch
    (``if x is None``) only where ``x`` is the compiled function's own argument (the functions inlined
    into it included), not a tuple's member; and an array taken out of a tuple costs two
    reference-count updates per use. Passing the bundles down cost 10-30 % of the kernel's time
    (measured in one process against the flat kernel); unpacked here, :func:`_step`, :func:`_rhs` and
    their inlined helpers compile to the flat kernel's code.

    Reference counts of the inlined helpers. An ``inline="always"`` helper's array argument becomes a
    new variable: numba increments its reference count on entry and decrements it after its last use,
    and removes the pair only where its pruning pass (llvmlite's ``RefPrunePass``) proves it safe: both
    in one block, or the decrement after every path from the increment (or on every branch, at most 15
    blocks deep) with no other decrement and no call in between (a call's exception exit is a path
    around the decrement). Otherwise the pair stays, two out-of-line calls (~5 instructions each) per
    use, and one unpruned pair inside a helper blocks the pairs of every helper around it. So the
    helpers of this loop end an array's use unconditionally (no ``if cond: a[i] = x`` as its last use,
    no ``break`` out of a loop that reads it, state read before a branch) and call no compiled function
    (:func:`_step` is called here, not in :func:`_switch_point`). Measured (callgrind,
    benchmarks/kernel_ab.py, calls per integration): the air-bearing-only scene's loop made 48,000
    reference-count calls (8 pairs per step in :func:`_track_extremes` and :func:`_d_extrema`), now none
    (6,000 in commit e6348f9); flying 5 nm and sliding 11 nm 0.79 M and 2.51 M, now 0.34 M and 1.18 M
    (e6348f9: 0.63 M, 2.02 M), the rest in the step (:func:`_rhs`). Check a change with the kernel's
    LLVM (``_integrate.inspect_llvm()``: the ``@NRT_incref`` calls in the loop; 2 are left, in
    :func:`_stiffness_cap` with the interface tables).
    """
    p = params[0]
    gap_power = _unpacked(gap_power_)
    ns = _state_size(men)
    has_contact = cp is not None
    n_out = t_out.shape[0]
    Y = np.full((n_out, ns), np.nan)
    C = np.zeros(n_out, dtype=np.bool_)
    info = np.zeros(5, dtype=np.int64)
    ext = np.array([np.inf, -np.inf])  # min and max of d over t >= p.t_win
    y = y0.copy()
    k1 = np.empty(ns)
    k7 = np.empty(ns)
    ynew = np.empty(ns)
    err = np.empty(ns)
    tmp, k2, k3, k4, k5, k6 = np.empty(ns), np.empty(ns), np.empty(ns), np.empty(ns), np.empty(ns), np.empty(ns)
    ys = np.empty(ns)
    buf = np.empty(_extrema_slots(p, dmw, h_max))
    ev_y = np.empty(ns)
    ev_f = np.empty(ns)
    t = 0.0
    # The initial mode follows the criterion at t = 0.
    contact = False
    if has_contact:
        contact = separation(p, dmw, t, y)[0] < p.k_sigma
    _rhs(t, y, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k1)
    info[4] += 1
    d0, dd0 = separation(p, dmw, t, y)  # d and d' at the current step start (kept step to step)
    if p.t_win <= 0.0:  # the window starts at t = 0: the initial d is one of its values (steps add their ends)
        ext[0] = d0
        ext[1] = d0
    h = min(h_max, 1e-8)
    t_hold = -1.0  # no switch may happen before t_hold (minimum dwell after a switch)
    h_stiff = h_max  # step cap from the local interface stiffness (_stiffness_cap)
    m_eff_inv = _inverse_mass_at_tfc(p, pitch)
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
        if has_contact and t_hold > 0.0 and t >= t_hold:
            # the dwell has ended: switch now if the criterion disagrees with the mode
            t_hold = -1.0
            if (d0 - p.k_sigma < 0.0) != contact:
                contact = not contact
                info[3] += 1
                t_hold = t + p.dwell
                _rhs(t, y, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k1)
                info[4] += 1
        h = min(h, h_max, h_stiff)
        if t + 1.01 * h >= t_end:  # land on t_end exactly, never leave a sliver (Hairer's DOPRI5 rule)
            h = t_end - t
        if t_hold > t and t + 1.01 * h >= t_hold:  # land on the end of the dwell, no sliver
            h = t_hold - t
        if h < 1e-12 * max(t, NS) or h < 1e-18:  # (h = t_end - t is never a sliver, see above)
            info[0] = STEP_UNDERFLOW
            return Y, C, info, ext
        _step(t, y, k1, h, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, ynew, k7, err,
              tmp, k2, k3, k4, k5, k6)
        info[4] += 6
        e = _error_norm(y, ynew, err, atol, rtol, ns)
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
        if has_contact and t_hold < 0.0:
            # a contact switch in the step: redo the step exactly up to it (in the old mode); a redone
            # (shorter) step is more accurate than the long step's interpolant and may show the
            # crossing earlier, so the search repeats on the redone step
            for _ in range(8):
                hi = _switch_point(p, dmw, contact, t, y, k1, ynew, k7, h_acc, d0, dd0, d1, dd1, ys, buf)
                if hi < 0.0:
                    break
                if not switched:
                    info[3] += 1
                switched = True
                if hi >= 1.0:
                    break  # the switch is at the end of the step
                h_acc = hi * h_acc
                _step(t, y, k1, h_acc, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, ev_y, ev_f, err,
                      tmp, k2, k3, k4, k5, k6)
                info[4] += 6
                for i in range(ns):
                    ynew[i] = ev_y[i]
                    k7[i] = ev_f[i]
                d1, dd1 = separation(p, dmw, t + h_acc, ynew)
        t_new = t + h_acc
        if t_new >= p.t_win:
            _track_extremes(p, dmw, t, h_acc, y, k1, ynew, k7, d0, dd0, d1, dd1, ys, buf, ext)
        j = _sample_outputs(t, h_acc, y, k1, ynew, k7, contact, t_out, j, Y, C, ns)
        for i in range(ns):
            y[i] = ynew[i]
            if not np.isfinite(y[i]):
                info[0] = NOT_FINITE
                return Y, C, info, ext
        t = t_new
        d0, dd0 = d1, dd1
        info[1] += 1
        h_stiff = _stiffness_cap(p, cp, pa, men, gap_power, tfc, contact, d0, h_max, m_eff_inv)
        if t_hold > 0.0 and abs(t - t_hold) <= 1e-12 * t_hold:
            t = t_hold  # land exactly on the end of the dwell (checked at the top of the loop)
        if switched:
            contact = not contact
            t_hold = t + p.dwell if p.dwell > 0.0 else -1.0
            _rhs(t, y, p, dmw, cp, pa, ft, tfc, pitch, gap_power, rlin, men, contact, k1)
            info[4] += 1
        else:
            for i in range(ns):
                k1[i] = k7[i]
        # step growth 0.9 e^(-1/5) in [0.2, 5]; e < (0.9/5)^5 gives the cap without calling pow()
        h = h * (5.0 if e < 1.889568e-4 else max(0.2, 0.9 * e ** -0.2))
    return Y, C, info, ext


numba.config.CACHE_DIR = _NUMBA_CACHE_DIR  # (the kernels above have their folder: see the imports)
