"""Where a run starts: the static equilibrium of the model, or the nominal attitude.

A simulation's start state is part of the model (docs/model.md, section "Start state"). With a lift
at the TFC point (the bulge's air bearing) or a strong adhesion, the nominal attitude ``z = theta = 0``
is not where the slider sits: starting there puts it in a transient, and near touchdown inside the
adhesion basin. ``solver.start`` (:data:`STARTS`):

* ``"static"``: the static equilibrium of the same forces the kernel integrates (the kernel's
  own right-hand side at zero velocity on the mean disk, ``w = 0``, so the laws have one home),
  continued in the protrusion from the nominal attitude at zero protrusion
  (:func:`pipeline.physics.equilibrium.static_equilibrium`); past the adhesion fold, where no flying
  equilibrium exists, the contact-branch equilibrium (from the TFC point at zero separation), and the
  run says so in its ``start`` note; if neither exists, the nominal attitude, said likewise;
* ``"nominal"`` (default for now, bit-identical to the model before the start state was part of it):
  the nominal attitude. Scenes with the bulge's air bearing set ``"static"``
  (``configs/paper-2009-bulge.toml``).

The contact law in the static balance follows the paper's criterion: on where ``d < k sigma``.
"""

from __future__ import annotations

import numpy as np

from ..physics.equilibrium import STARTS, static_equilibrium
from ..units import NM, URAD
from . import dynamics as dyn

#: Typical sizes of the static state (z [m], theta [rad]) for the equilibrium solver's scaling and steps.
SCALE = np.array([NM, URAD])

#: Continuation steps from zero protrusion (halved near the fold by the solver): the flying branch is smooth.
STEPS = 6

#: How closely the fold is bracketed [m]: past it the contact branch is taken; finer is never used.
FOLD_TOL = 1e-3 * NM


def static_forces(run_parameters):
    """``(R, flying)``: ``R(y, mu) -> (F_z [N], M_theta [N m])``, the static force and moment on the slider
    at ``y = (z, theta)`` for the protrusion ``mu`` [m], from the kernel's right-hand side at zero velocity
    and ``w = 0``; ``flying(y)``: whether ``y`` is out of contact (``d >= k sigma``) at the protrusion
    ``R`` was last evaluated at (the flying branch admits only such states).

    ``run_parameters(mu) -> (p, tables, variants)`` gives the kernel's inputs at a protrusion
    (:func:`pipeline.model.slider.run_parameters`). With the pitch locked the moment is replaced by
    ``theta`` (it stays at zero).
    """
    cache: dict[float, tuple] = {}
    out = np.empty(4)
    y4 = np.zeros(4)

    def inputs(mu: float):
        if mu not in cache:
            p, tables, variants = run_parameters(mu)
            cache.clear()  # (continuation: one protrusion at a time)
            # the meniscus state at rest is at its equilibrium q = p_a(d): the static forces are those
            # without it (docs/model.md, section "Meniscus formation"); the run appends q
            cache[mu] = (p, tables._replace(dmw=None), variants._replace(meniscus=None))
        return cache[mu]

    def R(y: np.ndarray, mu: float) -> np.ndarray:
        p, tables, variants = inputs(float(mu))
        y4[0], y4[1] = y[0], y[1]
        contact = bool(dyn.separation_at(p, y4[0], y4[1], 0.0) < p["k_sigma"])
        dyn.rhs(0.0, y4, p, tables, variants, contact, out)
        moment = p["I"] * out[3] if variants.pitch is not None else y[1]
        return np.array([p["m"] * out[2], moment])

    def flying(y: np.ndarray) -> bool:
        p = next(iter(cache.values()))[0]
        return bool(dyn.separation_at(p, y[0], y[1], 0.0) >= p["k_sigma"])

    return R, flying


def start_state(run_parameters, protrusion: float, rule: str, contact_start_z: float) -> tuple[np.ndarray, str]:
    """The start state ``(z, theta, z', theta')`` of a run at ``protrusion`` [m] by the rule ``rule``
    (:data:`STARTS`), and a note saying which state it is.

    ``contact_start_z`` [m]: the z of the contact-branch start (the TFC point at zero separation).
    """
    if rule == "nominal":
        return np.zeros(4), "nominal attitude"
    if rule != "static":
        raise ValueError(f"solver.start = {rule!r}: expected one of {STARTS}")
    R, flying = static_forces(run_parameters)
    st = static_equilibrium(R, protrusion, mu_start=0.0, y_start=np.zeros(2), scale=SCALE, accept=flying,
                            contact_start=np.array([contact_start_z, 0.0]), contact_max_step=0.05 * SCALE,
                            steps=STEPS, mu_tol=FOLD_TOL)
    if st.equilibrium is None:
        return np.zeros(4), f"nominal attitude ({st.message})"
    z, theta = st.equilibrium.y
    note = f"static {st.kind} equilibrium (z = {z / NM:.4g} nm, theta = {theta / URAD:.4g} urad)"
    if st.kind == "contact":
        note += f": {st.message}"
    return np.array([z, theta, 0.0, 0.0]), note
