"""The kernel's state vector, its counters and its status codes, by name.

The names are module-level integers: numba reads a global integer as a compile-time constant, so
``y[THETA]`` compiles to the same code as ``y[1]``.

State ``y`` (SI units), docs/model.md, section "Slider dynamics":

* :data:`Z` vertical displacement of the CG [m] (up positive), :data:`THETA` pitch [rad] (leading edge up),
  :data:`Z_RATE` [m/s], :data:`THETA_RATE` [rad/s];
* :data:`MENISCUS` the adhesion pressure ``q`` [Pa] of the meniscus state (docs/model.md, section
  "Meniscus formation"), present only with a meniscus formation time: the state then has
  :data:`N_STATE` + 1 components (:func:`state_size`);
* the frictional heat's protrusion ``delta_f`` [m] (docs/model.md, section "Frictional heating"), with a
  frictional-heating efficiency: one more column, last, of the kernel's start state and outputs
  (:func:`output_size`), not integrated by the step (the loop updates it exactly per accepted step).

Counters ``info`` of an integration (:func:`pipeline.model.dynamics.integrate`): :data:`STATUS` (one of
the status codes below), :data:`ACCEPTED` steps, :data:`REJECTED` steps, contact :data:`SWITCHES`,
:data:`RHS_CALLS` (right-hand-side evaluations), :data:`WINDOW_SWITCHES` (the contact mode's transitions at
``t >= p.t_win``, the steady window: :func:`pipeline.model.outcomes.summarize` reports them per ms).
"""

from __future__ import annotations

from .compiled import kernel_jit

# the state's components
Z, THETA, Z_RATE, THETA_RATE = 0, 1, 2, 3
MENISCUS = 4
#: length of the state without the meniscus state
N_STATE = 4

# the integration's counters
STATUS, ACCEPTED, REJECTED, SWITCHES, RHS_CALLS, WINDOW_SWITCHES = 0, 1, 2, 3, 4, 5
N_COUNTERS = 6
#: the step counters (accepted, rejected, switches), a slice of ``info``
STEP_COUNTERS = slice(ACCEPTED, SWITCHES + 1)

# status codes (``info[STATUS]``)
OK, MAX_STEPS, STEP_UNDERFLOW, NOT_FINITE = 0, 1, 2, 3
STATUS_TEXT = {OK: "ok", MAX_STEPS: "too many steps", STEP_UNDERFLOW: "step size underflow",
               NOT_FINITE: "state became non-finite"}


@kernel_jit(__name__, inline="always")
def state_size(meniscus):
    """Length of the state: :data:`N_STATE` and, with a meniscus formation time, the meniscus state
    (a compile-time constant: the four-component code is unchanged without the meniscus)."""
    if meniscus is not None:
        return N_STATE + 1
    return N_STATE


@kernel_jit(__name__, inline="always")
def output_size(meniscus, heating):
    """Length of the start state and of the outputs' rows: :func:`state_size` and, with the frictional heat
    (``heating`` not ``None``), its protrusion last (compile-time constant, as :func:`state_size`)."""
    if heating is not None:
        return state_size(meniscus) + 1
    return state_size(meniscus)
