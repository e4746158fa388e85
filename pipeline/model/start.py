"""Where a run starts: the static equilibrium of the model, or the nominal attitude.

A simulation's start state is part of the model (docs/model.md, section "Start state"). With a lift
at the TFC point (the bulge's air bearing) or a strong adhesion, the nominal attitude ``z = theta = 0``
is not where the slider sits: starting there puts it in a transient, and near touchdown inside the
adhesion basin. ``solver.start`` (:data:`STARTS`):

* ``"static"`` (the default): the static equilibrium of the same forces the kernel integrates (the
  kernel's own right-hand side at zero velocity on the mean disk, ``w = 0``, so the laws have one
  home), continued in the protrusion from the nominal attitude at zero protrusion
  (:func:`pipeline.physics.equilibrium.static_equilibrium`); past the adhesion fold, where no flying
  equilibrium exists, the contact-branch equilibrium (from the TFC point at zero separation), and the
  run says so in its ``start`` note; if neither exists, the nominal attitude, said likewise. The
  flying branch and its fold are found once per model (:func:`pipeline.physics.equilibrium.flying_ladder`,
  kept in the model's ``statics``), so a start past the fold costs one Newton solve on the contact
  branch and a start before it one continuation step from the branch's state below it;
* ``"nominal"``: the nominal attitude (the model before the start state was part of it).

Where one steady state exists the start decides the transient only (tests/model/test_start.py: static,
nominal and previous-heater-step starts agree to 1e-6 nm at 5 and 11 nm); between the take-off and
the fold of the adhesion hysteresis it decides which state a run reaches.

The contact law in the static balance follows the paper's criterion: on where ``d < k sigma``.

Newton's method runs compiled on the kernel's forces (:mod:`pipeline.model.static_solver`, no GIL
held), so the threads of a fan-out compute their starts in parallel; the per-protrusion tables it
needs (the tabulated TFC-point force) are kept on the model (:func:`pipeline.model.kernel_inputs.tfc_table`)
and shared with the run at the same protrusion.
"""

from __future__ import annotations

import numpy as np

from ..physics.equilibrium import STARTS, flying_ladder
from ..units import NM, URAD
from . import dynamics as dyn
from . import static_solver
from .forces import separation_at
from .piecewise import static_table
from .state import N_STATE, THETA, THETA_RATE, Z, Z_RATE

#: Typical sizes of the static state (z [m], theta [rad]) for the equilibrium solver's scaling and steps.
SCALE = np.array([NM, URAD])

#: Continuation steps from zero protrusion (halved near the fold by the solver): the flying branch is smooth.
STEPS = 6

#: How closely the fold is bracketed [m]: past it the contact branch is taken; finer is never used.
FOLD_TOL = 1e-3 * NM

#: Largest continuation step [m] of the search for the fold (once per model), about the steps the
#: continuation of one protrusion takes (:data:`STEPS` over the paper's protrusions).
FOLD_STEP = 1.0 * NM


def static_inputs(run_parameters, mu: float) -> tuple:
    """``(p, tables, variants, slots)``: the kernel's inputs of the static forces at the protrusion ``mu`` [m]
    (:func:`static_forces`), ``slots`` as the compiled functions take them (:func:`pipeline.model.dynamics._slots`)."""
    p, tables, variants = run_parameters(mu)
    # the meniscus state at rest is at its equilibrium q = p_a(d): the static forces are those
    # without it (docs/model.md, section "Meniscus formation"); the run appends q
    tables = tables._replace(dmw=None, adhesion=static_table(tables.adhesion))
    variants = variants._replace(meniscus=None)
    return p, tables, variants, dyn._slots(tables, variants)


def static_forces(run_parameters):
    """``(R, flying, solve)``: ``R(y, mu) -> (F_z [N], M_theta [N m])``, the static force and moment on the
    slider at ``y = (z, theta)`` for the protrusion ``mu`` [m], from the kernel's right-hand side at zero
    velocity and ``w = 0``; ``flying(y)``: whether ``y`` is out of contact (``d >= k sigma``) at the
    protrusion last evaluated (the flying branch admits only such states); ``solve``: Newton's method on
    the same forces, compiled (:data:`pipeline.physics.equilibrium.Solve`,
    :func:`pipeline.model.static_solver.newton`; ``R`` is the same forces from Python, for checks).

    ``run_parameters(mu) -> (p, tables, variants)`` gives the kernel's inputs at a protrusion
    (:func:`pipeline.model.kernel_inputs.run_parameters`). With the pitch locked the moment is replaced by
    ``-theta`` (theta stays at zero): a restoring stand-in of positive stiffness, so a state's stability
    is its heave's (:func:`pipeline.physics.equilibrium.is_stable`; ``+theta`` made every locked state
    unstable, and the start fell back to the nominal attitude).
    """
    cache: dict[float, tuple] = {}
    out = np.empty(N_STATE)
    y4 = np.zeros(N_STATE)

    def inputs(mu: float):
        if mu not in cache:
            cache.clear()  # (continuation: one protrusion at a time)
            cache[mu] = static_inputs(run_parameters, mu)
        return cache[mu]

    def R(y: np.ndarray, mu: float) -> np.ndarray:
        p, tables, variants, _ = inputs(float(mu))
        y4[Z], y4[THETA] = y[0], y[1]  # (y: the static state (z, theta))
        in_contact = bool(separation_at(p, y4[Z], y4[THETA], 0.0) < p["k_sigma"])
        dyn.rhs(0.0, y4, p, tables, variants, in_contact, out)
        moment = p["I"] * out[THETA_RATE] if variants.pitch is not None else -y[1]
        return np.array([p["m"] * out[Z_RATE], moment])

    def flying(y: np.ndarray) -> bool:
        p = next(iter(cache.values()))[0]
        return bool(separation_at(p, y[0], y[1], 0.0) >= p["k_sigma"])

    def solve(mu: float, y0, max_step=None, max_iter: int = 50, tol: float = 1e-10):
        p, _, _, slots = inputs(float(mu))
        return static_solver.newton(y0, p, slots, scale=SCALE, max_step=max_step, tol=tol, max_iter=max_iter)

    return R, flying, solve


def start_state(run_parameters, protrusion: float, rule: str, contact_start_z: float,
                statics: dict | None = None, fold_max: float | None = None, compiled: bool = True
                ) -> tuple[np.ndarray, str]:
    """The start state ``(z, theta, z', theta')`` of a run at ``protrusion`` [m] by the rule ``rule``
    (:data:`STARTS`: the entry's solver on the static forces, or none: the nominal attitude), and a note
    saying which state it is.

    ``contact_start_z`` [m]: the z of the contact-branch start (the TFC point at zero separation).
    ``statics``: a dict owned by the model (one per model: the fold depends on every force and on
    ``k sigma``), where the flying branch up to ``fold_max`` [m] is kept once found: its fold and its
    states on the way (``"ladder"``, :func:`pipeline.physics.equilibrium.flying_ladder`, steps of
    :data:`FOLD_STEP`). Past the fold a start goes to the contact branch without continuing the flying
    one again; before it a start continues the branch from the ladder's state below its protrusion (one
    step, one Newton solve, instead of :data:`STEPS` steps from zero protrusion). The fold is a function of the
    model alone, not of which protrusion asked first, so the starts do not depend on the order of the runs.
    ``statics["bound"]``, when set (:func:`pipeline.model.copies.with_criterion`): an upper bound of the
    fold, that of the same forces under a lower criterion; this model's own fold is then not searched.
    A protrusion at or past the bound starts on the contact branch; one below it continues the flying
    branch to the protrusion from the bounding model's ladder (``statics["bound_ladder"]``), which ends
    on the way exactly when the fold lies before it. Either way
    the state is the one the model's own fold gives (the contact-branch Newton does not depend on
    where the fold is); only the note's fold differs (the bound, or the continuation's own bracket).
    ``compiled``: Newton's method compiled on the kernel's forces (the default,
    :mod:`pipeline.model.static_solver`: no GIL held), else :func:`pipeline.physics.equilibrium.newton`
    on the same forces from Python (the reference, for checks).
    """
    solver = STARTS.lookup(rule).behaviour
    if solver is None:  # ("nominal")
        return np.zeros(4), "nominal attitude"
    R, flying, solve = static_forces(run_parameters)
    solve = solve if compiled else None
    fold = ladder = None
    bound = statics.get("bound") if statics is not None and "fold" not in statics else None
    past_bound = bound is not None and bool(protrusion >= bound)
    if bound is not None:
        # past an upper bound of this model's fold: past the fold. Below it: the continuation to the
        # protrusion (from the bounding model's ladder, whose states before this model's branch ends
        # are this model's: the same forces and steps) finds where this model's branch ends, if before
        fold = bound if past_bound else None
        ladder = statics.get("bound_ladder")
    elif statics is not None and fold_max is not None:
        if "fold" not in statics:
            found = flying_ladder(R, fold_max, y_start=np.zeros(2), scale=SCALE, accept=flying, step=FOLD_STEP,
                                  mu_tol=FOLD_TOL, solve=solve)
            statics["ladder"], statics["fold"] = found, found.fold
        fold, ladder = statics["fold"], statics.get("ladder")
    st = solver(R, protrusion, mu_start=0.0, y_start=np.zeros(2), scale=SCALE, accept=flying,
                contact_start=np.array([contact_start_z, 0.0]), contact_max_step=0.05 * SCALE,
                steps=STEPS, mu_tol=FOLD_TOL, fold=fold, solve=solve, ladder=ladder)
    if st.equilibrium is None:
        return np.zeros(4), f"nominal attitude ({st.message})"
    z, theta = st.equilibrium.y
    note = f"static {st.kind} equilibrium (z = {z / NM:.4g} nm, theta = {theta / URAD:.4g} urad)"
    if st.kind == "contact":
        note += (f": no flying equilibrium at {protrusion:.6g} (past {bound:.6g}, where the flying branch "
                 "without the contact criterion ends, at or beyond this one's fold)" if past_bound
                 else f": {st.message}")
    return np.array([z, theta, 0.0, 0.0]), note
