"""Running the model at one protrusion: the start state (:func:`start`), the integration
(:func:`run_model`) and its result (:class:`Run`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import dynamics as dyn
from .assembly import Model
from .forces import separation_at
from .kernel_inputs import HEAT_SPAN, heat_grid, interface_tables, run_parameters
from .piecewise import disk_history, ppval
from .frictional_heating import heat_fixed_point
from .start import start_state, static_forces
from .state import ACCEPTED, MAX_STEPS as MAX_STEPS_STATUS, N_STATE, NOT_FINITE, OK, REJECTED, STATUS, STATUS_TEXT, \
    STEP_UNDERFLOW, THETA, Z
from ..units import NM


@dataclass
class Run:
    """One integrated protrusion: states and contact flags sampled at ``time``.

    ``d_extremes``: exact minimum and maximum of the separation [m] over the steady window, tracked by
    the integrator (step ends and interior extrema), free of aliasing by the output grid.
    ``p``: the parameters the kernel ran with (the model's record with this protrusion, ``A_n``,
    ``k sigma``, ...: :data:`pipeline.model.dynamics.PARAMS`).
    """

    model: Model
    protrusion: float
    p: np.record
    nominal_area: float
    time: np.ndarray
    state: np.ndarray
    contact: np.ndarray
    info: np.ndarray
    d_extremes: tuple[float, float] = (np.nan, np.nan)
    start: str = "given"
    #: the heated run's nominal areas [m^2] at ``delta + j HEAT_STEP`` (the kernel's heat grid,
    #: :func:`pipeline.model.kernel_inputs.heat_grid`): its histories' ``A_n`` at ``delta + delta_f``
    heat_areas: np.ndarray | None = None


class IntegrationError(RuntimeError):
    """The integrator failed (too many steps, step underflow, or a non-finite state); its one line names
    the protrusion, the integrator's status and the scene keys to change (:data:`HINTS`)."""


#: What to change after a failed integration, by the integrator's status (:data:`pipeline.model.state.STATUS_TEXT`):
#: the scene keys, in every message of the failure (the command line's, a calibration's log, a sweep's
#: ``errors`` attribute).
HINTS = {
    MAX_STEPS_STATUS: "shorten solver.duration_ms, or hold contact modes longer against chattering on the contact "
                      "criterion (solver.min_dwell_ns), or loosen solver.rtol or solver.atol_nm, or move the "
                      "protrusion (tfc.protrusion_nm, sweep.protrusion_nm) or contact.k off the touchdown edge",
    STEP_UNDERFLOW: "the forces change faster than any step resolves: loosen solver.rtol or solver.atol_nm, "
                    "or check the interface keys (lubricant.work_of_adhesion_j_m2, contact.k)",
    NOT_FINITE: "a force overflowed: check the interface keys (lubricant.work_of_adhesion_j_m2, "
                "contact.k) and the protrusion against air_bearing.flying_height_nm",
}


def start(model: Model, protrusion: float) -> tuple[np.ndarray, str]:
    """The start state of a run at ``protrusion`` [m] by the model's ``solver.start`` rule, and its note
    (:func:`pipeline.model.start.start_state`), kept in the model's ``statics`` once found (a copy is
    returned): the flying runs of a calibration and the realisations of an ensemble ask again."""
    starts = model.statics.setdefault("starts", {})
    key = (model.start, float(protrusion))
    if key not in starts:
        y_s, fh0 = model.p["y_s"], model.p["FH0"]
        # (the fold is searched up to twice the flying height: past FH0 the TFC point is at the disk anyway)
        starts[key] = start_state(lambda mu: run_parameters(model, mu), protrusion, model.start,
                                  contact_start_z=protrusion + y_s - fh0, statics=model.statics, fold_max=2 * fh0)
    y, note = starts[key]
    return y.copy(), note


def run_model(model: Model, protrusion: float, y0: np.ndarray | None = None, max_steps: int = 5_000_000) -> Run:
    """Integrate the model at protrusion ``protrusion`` [m] from its start state (``solver.start``:
    :func:`start`), or from ``y0`` when given (the previous heater step, a test)."""
    p, tables, variants = run_parameters(model, protrusion)
    An = p["A_n"]
    n_out = int(round(model.duration / model.output_step)) + 1
    t_out = np.minimum(np.arange(n_out) * model.output_step, model.duration)
    start_note = "given"
    grid = dyn.Grid(model.duration, t_out)
    solver = dyn.Solver(model.rtol, model.atol, model.max_step, max_steps)
    heat = 0.0  # the frictional heat's protrusion of a given start without it
    if y0 is None:
        # the first run of a model whose kernel is neither compiled nor cached: compile it in a background
        # process while this one finds the start state (docs/performance.md, section "The first run")
        dyn.compile_kernel_ahead(np.zeros(N_STATE), grid, p, tables, variants, solver)
        y0, start_note = start(model, protrusion)
        if model.heating is not None:
            y0, heat = heated_start(model, p, y0)
    y0 = np.asarray(y0, float)
    if model.heating is not None:  # the heat's grid (A_n and the TFC table at delta + delta_f), a copy of the table
        heat0 = float(y0[-1]) if y0.size > N_STATE + (model.meniscus is not None) else heat
        variants = variants._replace(heating=heat_grid(model, protrusion, max(HEAT_SPAN, 2.0 * heat0)))
        if tables.tfc is not None:  # (the kernel writes its table at delta + delta_f into it)
            tables = tables._replace(tfc=variants.heating[4][0].copy())
    if model.meniscus is not None and y0.size == 4:  # the meniscus state starts at its equilibrium
        y0 = np.append(y0, meniscus_equilibrium(model, p, y0, heat))
    if model.heating is not None and y0.size == N_STATE + (model.meniscus is not None):
        y0 = np.append(y0, heat)  # (the last column: pipeline.model.state.output_size)
    Y, C, info, ext = dyn.integrate(y0, grid, p, tables, variants, solver)
    if info[STATUS] != OK:
        status = int(info[STATUS])
        hint = f"; {HINTS[status]}" if status in HINTS else ""
        raise IntegrationError(f"integration failed at protrusion {protrusion / NM:.3g} nm: "
                               f"{STATUS_TEXT[status]} (steps {info[ACCEPTED]}, rejected {info[REJECTED]}){hint}")
    return Run(model=model, protrusion=protrusion, p=p, nominal_area=An, time=t_out, state=Y, contact=C, info=info,
               d_extremes=(float(ext[0]), float(ext[1])), start=start_note,
               heat_areas=None if model.heating is None else variants.heating[3])


def meniscus_equilibrium(model: Model, p: np.record, y: np.ndarray, heat: float = 0.0) -> float:
    """The meniscus state's equilibrium ``q = p_a(d)`` [Pa] at the state ``y`` (z [m], theta [rad], ...)
    at ``t = 0``, the disk under the TFC point where the DMW record puts it (docs/model.md, section
    "Meniscus formation"): the start value of ``q``; ``heat``: the frictional heat's protrusion [m] at the
    start (docs/model.md, section "Frictional heating"), which lowers ``d``."""
    w = disk_history(model.dmw, p, np.zeros(1))[0][0] if model.dmw is not None else 0.0
    d = separation_at(p, float(y[Z]), float(y[THETA]), w) - heat
    adhesion = interface_tables(model, p["delta"], p["A_n"]).adhesion
    return float(ppval(adhesion, p.tab_x0, p.tab_h, np.array([d]))[0])


def heated_start(model: Model, p: np.record, y: np.ndarray) -> tuple[np.ndarray, float]:
    """The start of the frictional heat's protrusion ``delta_f`` [m] and the slider's start state with it
    (docs/model.md, section "Frictional heating"): from a static contact state (``d < k sigma`` at ``w = 0``),
    the fixed point ``delta_f = eta_f V Q(delta + delta_f)``
    (:func:`pipeline.model.frictional_heating.heat_fixed_point`) of the static contact state of the kernel's
    forces at ``delta + delta_f`` (``A_n`` and the tables there, as
    :func:`pipeline.analyses.mechanism_statics.heated_contact` takes them) and that state; else (flying, the
    nominal attitude) 0 and ``y``. ``p``: the kernel's parameters at the heater's protrusion. Kept in the
    model's ``statics`` (:func:`start`). A state on the way that is no stable contact state: 0 and ``y``."""
    key = ("heated", float(p["delta"]))
    found = model.statics.get(key)
    if found is None:
        found = model.statics[key] = _heated_start(model, p, y)
    return found[0].copy(), found[1]


def _heated_start(model: Model, p: np.record, y: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`heated_start` computed (the kernel's inputs at each ``delta + x``: :func:`run_parameters`)."""
    if model.start == "nominal" or not separation_at(p, y[Z], y[THETA], 0.0) < p["k_sigma"]:
        return y, 0.0
    delta, per_newton = float(p["delta"]), model.heating[0]
    _, _, solve = static_forces(lambda mu: run_parameters(model, mu))
    states = {0.0: y[:2].copy()}

    def steady(x: float) -> float:
        q, tab, _ = run_parameters(model, delta + x)
        eq = solve(delta + x, states[min(states, key=lambda k: abs(k - x))])
        d = float(separation_at(q, eq.y[0], eq.y[1], 0.0))
        if not (eq.converged and eq.stable and d < q["k_sigma"]):
            return np.nan
        states[x] = eq.y
        return per_newton * static_friction(q, tab.friction, d)

    x, _ = heat_fixed_point(steady)
    if not np.isfinite(x):
        return y, 0.0
    return np.array([states[x][0], states[x][1], 0.0, 0.0]), float(x)


def static_friction(p: np.record, friction: np.ndarray, d: float) -> float:
    """The friction force [N] in contact at the separation ``d`` [m] (:func:`pipeline.model.forces.friction_force`
    from Python: the table's first stress and the lubricant shear beside it, each clipped at 0)."""
    x = np.array([d])
    parts = (friction,) if friction.shape[1] == 4 else (friction[:, :4], friction[:, 4:])
    return float(sum(p["A_n"] * max(float(ppval(np.ascontiguousarray(c), p["tab_x0"], p["tab_h"], x)[0]), 0.0)
                     for c in parts))
