"""The slider's kernel: its inputs, the integration loop and the Python entry points.

The model (the slider's equations of motion and forces) is :mod:`pipeline.model.forces`, the
integrator's step (Dormand-Prince 5(4), dense output, events, extremes) :mod:`pipeline.model.stepper`,
the piecewise cubics it reads :mod:`pipeline.model.piecewise`, the names of the state's components
and of the counters :mod:`pipeline.model.state`; how the kernel's cost was measured and brought down:
docs/kernel.md.

Interface
---------
:func:`integrate` ``(y0, grid, p, tables, variants, solver)``:

* ``grid`` (:class:`Grid`): the end time and the output times;
* ``p``: the named parameters, one record of the structured dtype :data:`PARAMS` (numba types it as
  a ``Record``; fields are read as ``p.m``, ``p.k_sigma``...; :func:`params` makes one);
* ``tables`` (:class:`Tables`): the piecewise cubics of the DMW, of the interface laws versus the
  separation and of the tabulated TFC-point law versus the gap, each ``None`` when off;
* ``variants`` (:class:`Variants`): pitch on/off, the rear law, the gap-power parameters, the
  meniscus formation time;
* ``solver`` (:class:`Solver`): tolerances, largest step, step budget.

:func:`rhs` evaluates the right-hand side from Python (the static start, tests).

The slots. The tables and variants are the kernel's *slots*, in the one order :data:`SLOTS`
(``Tables`` then ``Variants``, their fields' order). The compiled functions that take them all take
them as separate arguments, last, in that order and under those names (the helpers a subset, under
the same names):
numba prunes a disabled effect's branch (``if x is None``) only where ``x`` is the compiled
function's own argument, not a tuple's member, and an array taken out of a tuple costs two
reference-count updates per use (measured: 10-30 % of the kernel's time, docs/kernel.md). So
:func:`integrate` unpacks the bundles once (:func:`_slots`) and every compiled function receives the
slots one by one. Disabled effects cost nothing: numba compiles one kernel per combination of slot
types. All kernels are cached on disk (:mod:`pipeline.model.compiled`).

Adding an input: a field of :class:`Tables` or :class:`Variants` (which fixes its place in
:data:`SLOTS`), then the same name at that place in the signatures of the compiled functions that
take the slots (tests/model/test_dynamics.py checks the order of those that take them all).

Adding a variant
----------------
A rear-bearing law is its function of numbers in :mod:`pipeline.physics.air_bearing` and one line in
``REAR_LAWS``: the kernel compiles that function (:func:`pipeline.model.forces.call_rear_law`). A new
force law at the TFC point (the bulge's air bearing, a "reynolds" table F(g, delta), ...) is
tabulated, not compiled: its law is a plain Python function of the gap array and the protrusion in
its physics module, registered with ONE line in its registry
(:data:`pipeline.physics.tfc_laws.TFC_STIFFENING`: ``"name": TfcLaw(force)``). The model assembly
(:func:`pipeline.model.kernel_inputs.tfc_table`) samples it per protrusion on a gap grid into a piecewise
cubic (as the interface tables), which the kernel's one generic slot ``Tables.tfc`` evaluates: force
and stiffness ``-dF/dg`` (the step-size cap) from the same cubic, so the kernel, its argument list and
its compiled cache are untouched. A tabulated law costs one cubic evaluation, like an interface
table, and is exact to the table's interpolation error (:func:`pipeline.model.kernel_inputs.tfc_table`; the
gap-power law tabulated: force within 3e-8 of its range, stiffness 5e-8 relative above 1 nm, a 1-ms
run's separation within 1e-10 nm of the closed form's, tests/scenarios/test_model_variants.py). The closed-form
gap-power law keeps its compiled branch (bit-identical results).

Internal state: the meniscus formation (docs/model.md, section "Meniscus formation") is a
fifth state component (:data:`pipeline.model.state.MENISCUS`), the adhesion pressure ``q`` [Pa]
relaxing towards the table's value, ``q' = (p_a(d) - q) / tau_m``, with the adhesion force
``-A_n q``. It is the slot ``Variants.meniscus`` (``tau_m`` [s], ``None``: off); the state length is
:func:`pipeline.model.state.state_size`, a compile-time constant, so the four-component arithmetic
(error norm over 4 components) and its results are unchanged when it is off. The contact-switch
events and the extremes of ``d`` read only the first four components.

The loop (:func:`_integrate`): adaptive steps (:func:`pipeline.model.stepper.step`); a contact switch
found in an accepted step (:func:`pipeline.model.stepper.switch_point`) is landed on exactly: the step
is redone up to it and integration restarts in the new mode (no FSAL reuse across the switch).
Outputs are sampled on a uniform grid with the step's Hermite interpolant.

Chattering. Where the contact force at the threshold exceeds the pull into contact (a large
``p_c(k sigma)``, e.g. a negative k), the exact solution slides along ``d = k sigma`` (a Filippov
sliding mode) and an exact event method would switch infinitely often. A mode is therefore held
for at least ``p.dwell`` seconds after a switch (``solver.min_dwell_ns``); if the criterion says
otherwise when the dwell ends, the mode switches there. The resulting fast switching averages the
contact force to the sliding-mode value with an error of the order of the dwell; the dwell is an
accuracy knob of the accuracy stage. Crossings further apart than the dwell are located exactly.
The switches at ``t >= p.t_win`` are counted apart (``info[WINDOW_SWITCHES]``): a run reports them per
ms (:func:`pipeline.model.outcomes.contact_switch_rate`), so that a sliding mode held on the criterion
shows in the data (docs/model.md, section "Switched and continuous friction").
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..units import NS
from . import compiled
from .compiled import kernel_jit
from .forces import RearLawRef, rear_law_ref, rhs_slots, separation, separation_of
from .frictional_heating import RETABLE, heat_friction, heat_tables, heat_update
from .state import (ACCEPTED, MAX_STEPS, N_COUNTERS, NOT_FINITE, REJECTED, RHS_CALLS, STATUS, STEP_UNDERFLOW,
                    SWITCHES, THETA, THETA_RATE, WINDOW_SWITCHES, Z, Z_RATE, output_size, state_size)
from .stepper import (cubic_extrema, error_norm, extrema_matter, extrema_slots, first_wrong_side, interp_state,
                      inverse_mass_at_tfc, knot_extrema, knots_in_step, sample_outputs, step, step_points,
                      stiffness_cap, switch_point, track_extremes)

_jit = kernel_jit(__name__)
_inline = kernel_jit(__name__, inline="always")

#: What a compile of the kernel (:func:`_integrate`) says; then how long it took, measured (15 s of CPU for the
#: main scene's effects on the project's 2-core machine at a load of ~2.5, 19 s at a load of 7: docs/kernel.md,
#: section "Compile time"; no time is promised before).
KERNEL_NOTICE = "the dynamics kernel for this scene's effects"

#: The rear law of :class:`Variants` with ``rear_law=None`` (the scene's default, ``air_bearing.rear_law``).
DEFAULT_REAR_LAW = "power"

#: The kernel's named parameters (all SI), one record (``np.record``; numba: ``Record``). Each comment
#: names the scene keys the field comes from (:func:`pipeline.model.assembly.build_model`); "per run":
#: set for each protrusion (:func:`pipeline.model.kernel_inputs.run_parameters`).
PARAMS = np.dtype((np.record, [
    ("m", "f8"), ("I", "f8"),        # mass [kg], pitch inertia [kg m^2]: slider.*_mm, density_kg_m3
    ("l_f", "f8"), ("l_r", "f8"),    # arms of the front and rear pad [m]: slider.front_arm_mm, rear_arm_mm
    ("l_c", "f8"),                   # arm of the TFC point [m]: slider.length_mm / 2 - tfc_from_trailing_edge_um
    ("friction_arm", "f8"),          # the friction moment's arm [m]: slider.friction_arm (of slider.thickness_mm)
    ("k_f", "f8"), ("k_r", "f8"),    # pad stiffness [N/m]: air_bearing.frequencies_khz, stiffness_root
    ("c_f", "f8"), ("c_r", "f8"),    # pad dampers [N s/m]: air_bearing.damping_ratio
    ("g0", "f8"), ("n", "f8"),       # rear law gap [m], exponent [1]: air_bearing.rear_reference_gap_nm, rear_exponent
    ("F_r0", "f8"),                  # rear law preload [N]: from k_r, g0, n
    ("FH0", "f8"),                   # flying height [m]: air_bearing.flying_height_nm
    ("delta", "f8"),                 # protrusion [m]: per run (tfc.protrusion_nm, sweep.protrusion_nm)
    ("A_n", "f8"),                   # nominal area [m^2]: per run, tfc.half_*_um, contact.section_depth_sigma
    ("k_sigma", "f8"),               # criterion [m]: per run, contact.k (or the calibration) times roughness sigma
    ("c_c", "f8"),                   # contact damper [N s/m]: contact.damping_n_s_m
    ("off_f", "f8"), ("off_r", "f8"),  # disk travel time to the front, rear pad [s]: disk speed of [dmw]
    ("off_c", "f8"),                 # ... to the TFC point [s]: 0
    ("dmw_t0", "f8"), ("dmw_dt", "f8"),  # DMW spline grid: start, step [s]: the DMW record's sample rate
    ("tab_x0", "f8"), ("tab_h", "f8"),  # interface-table grid: start, step [m]: interface.nc
    ("tab_n", "i8"),                 # interface-table pieces: interface.nc
    ("tfc_x0", "f8"), ("tfc_h", "f8"),  # tabulated TFC-point law grid: start, step [m]: per run, the laws' gap range
    ("dwell", "f8"),                 # minimum dwell in a contact mode [s]: solver.min_dwell_ns
    ("t_win", "f8"),                 # start of the steady window [s]: per run, solver.transient_ms
    ("h_stiff", "f8"),               # step cap over 1/omega of the interface spring [1]: solver.stiffness_step
    ("y_s", "f8"),                   # summit mean height over the surface mean [m]: interface.nc or [roughness]
]), align=True)

#: Parameters of the closed-form gap-power stiffening law at the TFC point (``Variants.gap_power``): stiffness
#: scale ``k_t`` [N/m], exponent ``q`` [1], reference gap ``g0`` [m], potential at the nominal gap ``f0 = G(g_n)``
#: [m] (per protrusion), linear-continuation gap ``g_min`` [m] and stiffness ``k_min`` [N/m] below it.
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
    other's protrusion (tests/model/test_dynamics.py).
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
    """Compiled model variants, each ``None`` when off (the rear law: its default).

    pitch : ``True`` for the pitch degree of freedom (``None`` locks it)
    rear_law : the rear-bearing law (``air_bearing.rear_law``), a :class:`pipeline.model.forces.RearLawRef`
        (:func:`pipeline.model.forces.rear_law_ref`); ``None``: ``"power"``, the scene's default
    gap_power : the closed-form TFC stiffening law's parameters (a :data:`GAP_POWER` record)
    meniscus : the meniscus formation time ``tau_m`` [s] (> 0): the adhesion pressure becomes the fifth
        state component ``q`` [Pa], ``dq/dt = (p_a(d) - q) / tau_m`` (docs/model.md, section "Meniscus
        formation"); the state, ``y0``, the outputs and ``Solver.atol`` then have 5 components
    heating : the frictional heat's protrusion ``(eta_f V [m/N], tau_f [s], step [m], A_n [m^2], TFC tables)``, the
        last two the grid :func:`pipeline.model.kernel_inputs.heat_grid` at ``delta + j step`` (docs/model.md,
        section "Frictional heating"; :mod:`pipeline.model.frictional_heating`): ``y0`` and the outputs get its
        ``delta_f`` [m] as a last column (:func:`pipeline.model.state.output_size`), the loop's own state (not the
        step's: ``Solver.atol`` is unchanged), not in :data:`SLOTS`: the force functions see it as ``p.delta``
    """

    pitch: bool | None = None
    rear_law: RearLawRef | None = None
    gap_power: np.record | None = None
    meniscus: float | None = None
    heating: tuple | None = None


class Solver(NamedTuple):
    """Step control: relative tolerance ``rtol`` [1], per-component absolute tolerances ``atol`` (SI),
    largest step ``h_max`` [s], guard ``max_steps`` against a stalled integration."""

    rtol: float
    atol: np.ndarray
    h_max: float
    max_steps: int


#: The kernel's slots, in the order of the compiled functions' last arguments (module docstring); the loop's
#: own ``Variants.heating`` follows them as :func:`_integrate`'s last argument.
SLOTS = Tables._fields + Variants._fields[:-1]


def _slots(tab: Tables, var: Variants) -> tuple:
    """The slots in the order :data:`SLOTS`, as the compiled functions take them: the gap-power record as
    a one-element array (:func:`_packed`), the default rear law for ``None``."""
    rear = var.rear_law if var.rear_law is not None else rear_law_ref(DEFAULT_REAR_LAW)
    return (*tab, *var._replace(rear_law=rear, gap_power=_packed(var.gap_power))[:-1])


def integrate(y0: np.ndarray, grid: Grid, p: np.record, tab: Tables, var: Variants, solver: Solver
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate from ``t = 0`` to ``grid.t_end`` [s]; sample the state at ``grid.t_out`` (ascending).

    Parameters
    ----------
    y0 : initial state (components: :mod:`pipeline.model.state`)
    grid : :class:`Grid`; p : named parameters (a :data:`PARAMS` record)
    tab : :class:`Tables` (``None`` slots disable their effect); var : :class:`Variants`
    solver : :class:`Solver`

    Returns
    -------
    Y : states at ``t_out`` (n_out, 4), one more column with the meniscus state and one with the heat (last,
        ``delta_f`` [m]); C : contact flag at ``t_out``;
    info : the counters (:data:`pipeline.model.state.STATUS`, ``ACCEPTED``, ...);
    ext : exact minimum and maximum of the separation ``d`` [m] over ``t >= p.t_win``

    Notes
    -----
    A plain Python function that hands the compiled :func:`_integrate` flat arguments, the records as
    one-element arrays (:func:`_packed`): numba's dispatcher types arrays, floats and ``None`` in C,
    but a record scalar and a named tuple through its Python ``typeof`` (docs/kernel.md).
    """
    if compiled.pending():  # (a background compile of the kernel, :func:`compile_kernel_ahead`)
        compiled.wait_ahead()
    return _integrate(*kernel_arguments(y0, grid, p, tab, var, solver))


def kernel_arguments(y0: np.ndarray, grid: Grid, p: np.record, tab: Tables, var: Variants,
                     solver: Solver) -> tuple:
    """The arguments :func:`integrate` hands the compiled :func:`_integrate` (their numba types are its
    signature: one compile per combination of the scene's effects)."""
    return (y0, grid.t_end, grid.t_out, _packed(p), solver.rtol, solver.atol, solver.h_max, solver.max_steps,
            *_slots(tab, var), var.heating)


def compile_kernel_ahead(y0: np.ndarray, grid: Grid, p: np.record, tab: Tables, var: Variants,
                         solver: Solver) -> bool:
    """Start compiling the kernel for these arguments' types in a background process if neither this process
    nor the cache has it (:func:`pipeline.model.compiled.compile_ahead`): a model's first run calls this
    before its static start, which compiles the static solver meanwhile. Only while this process has no
    kernel yet (typing the arguments costs ~1 ms, a run's call no more than a pointer test); a later scene's
    other effects compile in this process at their first call, as before. Returns whether this call started
    the process (:func:`pipeline.model.compiled.compile_ahead`)."""
    if _integrate.overloads or compiled.pending():
        return False
    return compiled.compile_ahead(_integrate, kernel_arguments(y0, grid, p, tab, var, solver), KERNEL_NOTICE)


def leaf_calls(y0: np.ndarray, grid: Grid, p: np.record, tab: Tables, var: Variants,
               solver: Solver) -> list[tuple[Any, tuple]]:
    """The kernel's separately compiled functions that call no other compiled function and that its compile
    asks for last, 3-5 s into it (docs/kernel.md, section "Compile time"): the step's cap
    :func:`pipeline.model.stepper.stiffness_cap` and, with a DMW record, the extrema across its knots
    :func:`pipeline.model.stepper.knot_extrema`; each with stand-in arguments of the types :func:`_integrate`
    calls it with for the arguments of :func:`integrate` (``(dispatcher, args)``), the last asked for first.
    (The switch's bisection :func:`pipeline.model.stepper.switch_point` calls the separation, which the
    background compile compiles first: compiled here too, it would be compiled twice.)

    The process that starts the kernel's background compile compiles these into the on-disk cache at once
    (not when it adopts the console script's early compile), and the background compile then loads them
    instead of compiling them (:func:`pipeline.model.ahead.compile_kernel_ahead`). Machine code and results
    are the same either way; tests/model/test_compiled.py checks that these are the signatures the kernel's
    compile asks for.
    """
    # (the kernel's own values: ``p`` and ``var.gap_power`` are the records it unpacks, its work arrays
    # C-contiguous float64, its flags bool, its counts int)
    v = np.zeros(1)
    calls: list[tuple[Any, tuple]] = [
        (stiffness_cap, (p, False, 0.0, 0.0, 0.0, tab.contact, tab.adhesion, tab.tfc, var.gap_power, var.meniscus))]
    if tab.dmw is not None:  # (the kernel's call is pruned without a DMW record)
        calls.append((knot_extrema, (tab.dmw, 0.0, 0.0, 0.0, 0.0, 0, 0.0, 0.0, 0.0, v, 0)))
    return calls


def rhs(t: float, y: np.ndarray, p: np.record, tab: Tables, var: Variants, in_contact: bool,
        out: np.ndarray) -> None:
    """Write ``dy/dt`` at the time ``t`` [s] and state ``y`` into ``out``, in the contact mode
    ``in_contact`` (the equations: :mod:`pipeline.model.forces`); ``tab``: :class:`Tables`,
    ``var``: :class:`Variants`."""
    _rhs_python(t, y, _packed(p), in_contact, out, *_slots(tab, var))


def _packed(record: np.record | None) -> np.ndarray | None:
    """``record`` as a one-element array of its dtype (a copy; ``None`` stays ``None``): what the
    compiled functions take, typed by numba's dispatcher in C (:func:`integrate`)."""
    if record is None:
        return None
    a = np.empty(1, record.dtype)
    a[0] = record
    return a


@_inline
def _unpacked(a):
    """The record of a one-element array (:func:`_packed`), ``None`` for ``None`` (pruned at compile time)."""
    if a is None:
        return None
    return a[0]


@_jit
def _rhs_python(t, y, params, in_contact, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power_,
                meniscus):
    """:func:`pipeline.model.forces.rhs_slots` called from Python (:func:`rhs`): the records as one-element
    arrays."""
    rhs_slots(t, y, params[0], in_contact, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law,
              _unpacked(gap_power_), meniscus)


#: The relative margin of :func:`_capped` (the rounding of ``pow`` and of the products is ~1e-15 relative)
GROWTH_MARGIN = 1.0 - 1e-6


@_inline
def _capped(e, h, cap):
    """Whether the step ``h`` [s] grown by ``max(0.2, 0.9 e^(-1/5))`` (an accepted step's error norm ``e``) is
    at least ``cap`` [s], without ``pow``: ``e < (0.9 h / cap)^5``, by products only, with the margin
    :data:`GROWTH_MARGIN` (then ``0.9 e^(-1/5) h >= cap (1 + 2e-7)``, past any rounding). Where it holds, the
    grown step's exact size does not matter: the next step is the cap (``min(h, h_max, h_stiff)``), and
    ``5 h`` stands in for it."""
    g = 0.9 * h
    c2 = cap * cap
    g2 = g * g
    return e * (c2 * c2 * cap) < (g2 * g2 * g) * GROWTH_MARGIN


@_inline
def disk_span(p, dmw):
    """The times [s] between which the disk lookups of the step (:func:`pipeline.model.piecewise.disk3`) and of
    the separation (:func:`pipeline.model.piecewise.disk`) take the same piece of the DMW spline: from its start
    to the start of its last piece (every time without a DMW record, both zero)."""
    if dmw is None:
        return -np.inf, np.inf
    return p.dmw_t0, p.dmw_t0 + (dmw.shape[0] - 1) * p.dmw_dt


@_jit
def _integrate(y0, t_end, t_out, params, rtol, atol, h_max, max_steps, dmw, contact, adhesion, friction, tfc,
               pitch, rear_law, gap_power_, meniscus, heating):
    """:func:`integrate` with its bundles unpacked into the slots (``params``, ``gap_power_``: the
    records as one-element arrays, :func:`_packed`).

    Reference counts of the inlined helpers: an ``inline="always"`` helper's array argument becomes a
    new variable whose reference-count pair numba removes only where it can prove it safe; so the
    helpers of this loop end an array's use unconditionally (no ``if cond: a[i] = x`` as its last use,
    no ``break`` out of a loop that reads it, state read before a branch) and call no compiled function
    that takes arrays: the separately compiled ones (:func:`pipeline.model.stepper.step`, the switch's
    bisection :func:`pipeline.model.stepper.switch_point`, the knot-splitting extrema
    :func:`pipeline.model.stepper.knot_extrema`, the step's cap :func:`pipeline.model.stepper.stiffness_cap`,
    the separation :func:`pipeline.model.forces.separation`) are called here, in the loop itself. The step,
    the cap and the separation are compiled without reference counts
    (:data:`pipeline.model.compiled.BORROWING`): the loop keeps none. The measurements and how to check a
    change (``_integrate.inspect_llvm()``): docs/kernel.md.

    Compile time: what runs rarely or would be copied more than once is compiled on its own (the
    bisection, the extrema across DMW knots, the separation), and a step's interior points are found and
    evaluated once for the event search and the window's extremes (docs/kernel.md, section "Compile time").
    """
    p = params[0]
    gap_power = _unpacked(gap_power_)
    ns = state_size(meniscus)
    has_contact = contact is not None
    n_out = t_out.shape[0]
    Y = np.full((n_out, output_size(meniscus, heating)), np.nan)
    C = np.zeros(n_out, dtype=np.bool_)
    info = np.zeros(N_COUNTERS, dtype=np.int64)
    ext = np.array([np.inf, -np.inf])  # min and max of d over t >= p.t_win
    y = y0.copy()
    k1 = np.empty(ns)
    k7 = np.empty(ns)
    ynew = np.empty(ns)
    err = np.empty(ns)
    tmp, k2, k3, k4, k5, k6 = np.empty(ns), np.empty(ns), np.empty(ns), np.empty(ns), np.empty(ns), np.empty(ns)
    ys = np.empty(ns)
    n_max = extrema_slots(p, dmw, h_max)
    buf = np.empty(n_max + 3)  # a step's interior points (extrema, 3 more near the threshold): stepper.step_points
    dex = np.empty(n_max + 3)  # d at those points
    ev_y = np.empty(ns)
    ev_f = np.empty(ns)
    w_end = np.zeros(2)  # the disk at the step's end, from the step's last stage (stepper.step)
    # the step's end within these times: the step's lookup (stepper.step, piecewise.disk3) is the separation's
    # (piecewise.disk), bit for bit (disk3 clamps outside the spline, disk extrapolates; docs/kernel.md)
    t_disk_lo, t_disk_hi = disk_span(p, dmw)
    t = 0.0
    # the frictional heat's protrusion delta_f (frictional_heating), held over a step: the geometry sees it
    # through p.delta (the record's copy of integrate's, _packed), its steady value a0 at the step's start; A_n and
    # the TFC table at delta + delta_f too (heat_tables; re-read when delta_f has moved by RETABLE, at df_tab)
    delta_heater, df, a0, df_tab = p.delta, 0.0, 0.0, 0.0
    if heating is not None:
        df = y0[ns]
        p.delta = delta_heater + df
        p.A_n = heat_tables(tfc, heating, df)
        df_tab = df
    d0, dd0 = separation(p, dmw, t, y)  # d and d' at the current step start (kept step to step)
    # The initial mode follows the criterion at t = 0.
    in_contact = False
    if has_contact:
        in_contact = d0 < p.k_sigma
    a0 = heat_friction(p, friction, in_contact, d0, heating)
    # k1 is evaluated by the next step (the first, and the first after a switch); np.bool_: a run-time bool in
    # every assignment (numba types a literal True or False apart, and would compile the step for each)
    fresh = np.bool_(True)
    if p.t_win <= 0.0:  # the window starts at t = 0: the initial d is one of its values (steps add their ends)
        ext[0] = d0
        ext[1] = d0
    h = min(h_max, 1e-8)
    t_hold = -1.0  # no switch may happen before t_hold (minimum dwell after a switch)
    h_stiff = h_max  # step cap from the local interface stiffness (_stiffness_cap)
    m_eff_inv = inverse_mass_at_tfc(p, pitch)
    j = 0
    while j < n_out and t_out[j] <= t:
        for i in range(ns):  # element by element: a slice assignment compiles numba's shape-error message (~3 s)
            Y[j, i] = y[i]
        if heating is not None:
            Y[j, ns] = df
        C[j] = in_contact
        j += 1
    steps = 0
    while t < t_end:
        if steps >= max_steps:
            info[STATUS] = MAX_STEPS
            return Y, C, info, ext
        steps += 1
        if has_contact and t_hold > 0.0 and t >= t_hold:
            # the dwell has ended: switch now if the criterion disagrees with the mode
            t_hold = -1.0
            if (d0 - p.k_sigma < 0.0) != in_contact:
                in_contact = not in_contact
                info[SWITCHES] += 1
                if t >= p.t_win:
                    info[WINDOW_SWITCHES] += 1
                t_hold = t + p.dwell
                fresh = np.bool_(True)
        h = min(h, h_max, h_stiff)
        if t + 1.01 * h >= t_end:  # land on t_end exactly, never leave a sliver (Hairer's DOPRI5 rule)
            h = t_end - t
        if t_hold > t and t + 1.01 * h >= t_hold:  # land on the end of the dwell, no sliver
            h = t_hold - t
        if h < 1e-12 * max(t, NS) or h < 1e-18:  # (h = t_end - t is never a sliver, see above)
            info[STATUS] = STEP_UNDERFLOW
            return Y, C, info, ext
        info[RHS_CALLS] += step(t, y, k1, h, p, in_contact, fresh, ynew, k7, err, tmp, k2, k3, k4, k5, k6, w_end,
                                dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus)
        fresh = np.bool_(False)
        e = error_norm(y, ynew, err, atol, rtol, ns)
        if not np.isfinite(e):
            h *= 0.1
            info[REJECTED] += 1
            continue
        if e > 1.0:
            h *= max(0.2, 0.9 * e ** -0.2)
            info[REJECTED] += 1
            continue
        # accepted step [t, t + h]
        h_acc = h
        switched = False
        search = has_contact and t_hold < 0.0
        # A contact switch in the step: redo the step exactly up to it (in the old mode); a redone
        # (shorter) step is more accurate than the long step's interpolant and may show the crossing
        # earlier, so the search repeats on the redone step (up to 8 redos). One pass per (re)done step:
        # d at its end, its interior points (the extrema of d, shared by the search and the window's
        # extremes: one copy of each helper in the compiled kernel, docs/kernel.md, section "Compile time").
        d1, dd1 = d0, dd0
        n_ex = 0
        for i_redo in range(9):
            t1 = t + h_acc
            if t_disk_lo <= t1 <= t_disk_hi:  # (the step's own lookup of the disk there)
                d1, dd1 = separation_of(p, ynew[Z], ynew[THETA], ynew[Z_RATE], ynew[THETA_RATE], w_end[0], w_end[1])
            else:
                d1, dd1 = separation(p, dmw, t1, ynew)
            # the next step's cap, from this end, before the extrema and outputs (docs/kernel.md, "The cap ahead of
            # the bookkeeping"); with the heat, taken once the heat has moved d (below: "The heated step's cap, once")
            if heating is None:
                h_stiff = stiffness_cap(p, in_contact, d1, h_max, m_eff_inv, contact, adhesion, tfc, gap_power,
                                        meniscus)
            n_ex = 0
            n_pts = 0
            if search or t + h_acc >= p.t_win:
                # the extrema of d (knot_extrema called here, not in an inlined helper: docs/kernel.md)
                knots, i_a, s3, s2, s1 = knots_in_step(p, dmw, t, h_acc, y, k1, ynew, k7)
                # (skipped where they cannot change the search or the window's extremes: stepper.extrema_matter)
                if extrema_matter(p, dmw, search, in_contact, knots, i_a, s3, s2, t, h_acc, d0, dd0, d1, dd1, ext):
                    if dmw is not None:
                        if knots:
                            n_ex = knot_extrema(dmw, t, h_acc, p.dmw_t0, p.dmw_dt, i_a, s3, s2, s1, buf, n_max)
                    if not knots:
                        n_ex = cubic_extrema(d0, dd0, d1, dd1, h_acc, buf)
                n_pts = step_points(p, search, h_acc, d0, dd0, d1, dd1, buf, n_ex)
                for i in range(n_pts):  # d at them (separation called here: docs/kernel.md, "Compile time")
                    frac = buf[i]
                    interp_state(y, k1, ynew, k7, h_acc, frac, ys)
                    dex[i] = separation(p, dmw, t + frac * h_acc, ys)[0]
            if i_redo == 8 or not search:
                break
            hi = first_wrong_side(p, in_contact, d1, n_pts, buf, dex)
            if hi < 0.0:
                break
            hi = switch_point(p, dmw, in_contact, t, y, k1, ynew, k7, h_acc, hi, ys)
            if not switched:
                info[SWITCHES] += 1
            switched = True
            if hi >= 1.0:
                break  # the switch is at the end of the step
            h_acc = hi * h_acc
            info[RHS_CALLS] += step(t, y, k1, h_acc, p, in_contact, fresh, ev_y, ev_f, err, tmp, k2, k3, k4, k5, k6,
                                    w_end, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus)
            for i in range(ns):
                ynew[i] = ev_y[i]
                k7[i] = ev_f[i]
        t_new = t + h_acc
        if t_new >= p.t_win:
            track_extremes(p, t, h_acc, d1, n_ex, buf, dex, ext)
        j_new = sample_outputs(t, h_acc, y, k1, ynew, k7, in_contact, t_out, j, Y, C, ns)
        df_new = df
        if heating is not None:  # delta_f's exact lag over the step, Q linear between its ends (the step's mode)
            df_new = heat_update(df, a0, heat_friction(p, friction, in_contact, d1, heating), h_acc, heating[1])
            for i in range(j, j_new):  # (linear in the step: (h / tau_f)^2 of the exact lag)
                Y[i, ns] = df + (df_new - df) * ((t_out[i] - t) / h_acc)
        j = j_new
        for i in range(ns):
            y[i] = ynew[i]
            if not np.isfinite(y[i]):
                info[STATUS] = NOT_FINITE
                return Y, C, info, ext
        t = t_new
        d0, dd0 = d1, dd1
        if heating is not None:
            p.delta = delta_heater + df_new
            d0 -= df_new - df  # (d = ... - delta: the next step starts at the new protrusion)
            df = df_new
            if abs(df - df_tab) > RETABLE:
                p.A_n = heat_tables(tfc, heating, df)
                df_tab = df
            # the next step's cap at the new protrusion (the redo loop takes none with the heat)
            h_stiff = stiffness_cap(p, in_contact, d0, h_max, m_eff_inv, contact, adhesion, tfc, gap_power, meniscus)
        info[ACCEPTED] += 1
        if t_hold > 0.0 and abs(t - t_hold) <= 1e-12 * t_hold:
            t = t_hold  # land exactly on the end of the dwell (checked at the top of the loop)
        if switched:
            in_contact = not in_contact
            if t >= p.t_win:  # (the mode changes at the step's end: counted in the window from t_win on)
                info[WINDOW_SWITCHES] += 1
            t_hold = t + p.dwell if p.dwell > 0.0 else -1.0
            fresh = np.bool_(True)
        else:
            for i in range(ns):
                k1[i] = k7[i]
        if heating is not None:
            a0 = heat_friction(p, friction, in_contact, d0, heating)
        # step growth 0.9 e^(-1/5) in [0.2, 5]; e < (0.9/5)^5 gives the cap without calling pow(), and so does an
        # e for which the grown step would exceed the next step's cap, min(h_max, h_stiff): the loop's top then
        # takes the cap whatever the growth (section "The step's growth" of docs/kernel.md)
        h = h * (5.0 if e < 1.889568e-4 or _capped(e, h, min(h_max, h_stiff)) else max(0.2, 0.9 * e ** -0.2))
    return Y, C, info, ext


compiled.announce(_integrate, KERNEL_NOTICE)
