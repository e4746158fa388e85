"""Static equilibria of the slider: the flying state, its fold (touchdown by adhesion), the contact branch.

The slider's static state ``y`` (``(z, theta)``: CG displacement [m], up positive, and pitch [rad],
leading edge up positive; or ``(z,)`` with the pitch locked) balances the generalised forces
``R(y) = (sum of vertical forces [N], pitch moment about the CG [N m])`` of the air bearing, the
interface at the TFC point (adhesion, contact, friction) and the bulge's lift
(docs/model.md, section "Start state"). As the protrusion grows the flying equilibrium approaches the
surface; where the adhesion's negative stiffness cancels the bearing's, the stable flying branch
meets the unstable one and both disappear (a saddle-node fold): beyond it there is no flying
equilibrium and the slider snaps into contact (touchdown by adhesion; Vakis, Lee & Polycarpou, IEEE
Trans. Magn. 45 (2009) 4966 discuss the instability; the fold as touchdown is the project's reading).

Functions (all pure; ``forces(y, mu)`` is the caller's callable, ``mu`` the continuation parameter,
e.g. the protrusion):

* :func:`newton`: one equilibrium from a start, with its stiffness and stability;
* :func:`flying_branch`: natural-parameter continuation of the stable branch from a known state
  (the nominal attitude ``y = 0`` at zero protrusion), step halving near the fold, which it brackets;
* :func:`branch_fold`: where that branch ends, once for all protrusions;
* :func:`static_equilibrium`: the start state of a run at one protrusion: the flying equilibrium if the
  branch reaches it, else (``"no flying equilibrium"``) the contact-branch equilibrium from a start in
  contact.

The statics map (every static state along a path, its stability and barriers): :mod:`pipeline.physics.statics_map`.
The forces are the caller's: the model's static start (:mod:`pipeline.model.start`) passes the kernel's
own right-hand side at zero velocity, so the slider's equations have one home.

A state is *stable* when the stiffness ``K = -dR/dy`` has eigenvalues with positive real parts
(no static divergence; ``K`` is not symmetric with the friction moment).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..units import NM, URAD
from .variants import Registry, Variant


Forces = Callable[[np.ndarray, float], np.ndarray]

#: ``solve(mu, y0, max_step=None, max_iter=50, tol=1e-10) -> Equilibrium``: Newton's method
#: (:func:`newton`) on ``R(., mu)`` from ``y0``; the continuation's one use of the forces. By default
#: :func:`newton` on the caller's ``forces`` (:func:`python_solve`); the model's static start passes a
#: compiled one on the kernel's own forces (:mod:`pipeline.model.static_solver`).
Solve = Callable[..., "Equilibrium"]

@dataclass(frozen=True)
class Equilibrium:
    """One static state.

    Attributes
    ----------
    y : state (``z`` [m], ``theta`` [rad]) or (``z``,)
    stiffness : ``K = -dR/dy`` at ``y`` ([N/m, N], [N m/m, N m/rad])
    converged : Newton met its tolerance; stable : eigenvalues of ``K`` with positive real parts
    iterations : Newton iterations; residual : ``|R(y)|`` scaled by the force scale [1]
    """

    y: np.ndarray
    stiffness: np.ndarray
    converged: bool
    stable: bool
    iterations: int
    residual: float


def jacobian(forces: Callable[[np.ndarray], np.ndarray], y: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """``dR/dy`` by central differences with steps ``1e-6 scale`` (``scale``: typical size of each state).

    Parameters
    ----------
    forces : ``R(y)`` [N, N m]
    y : the state (``z`` [m], ``theta`` [rad])
    scale : typical size of each state component [m, rad]

    Returns
    -------
    numpy.ndarray
        ``dR/dy`` ([N/m, N/rad; N m/m, N m/rad]), ``len(y) x len(y)``.

    References
    ----------
    [VLP09] (the slider's static flying attitude); docs/model.md,
    section "Start state".
    """
    y = np.asarray(y, dtype=float)
    J = np.empty((y.size, y.size))
    for j in range(y.size):
        h = 1e-6 * scale[j]
        e = np.zeros(y.size)
        e[j] = h
        J[:, j] = (forces(y + e) - forces(y - e)) / (2 * h)
    return J


def is_stable(K: np.ndarray) -> bool:
    """Whether a static state of stiffness ``K = -dR/dy`` is stable: every eigenvalue has a positive real part.

    Parameters
    ----------
    K : the stiffness matrix ([N/m, N], [N m/m, N m/rad])

    Returns
    -------
    bool
        Stable [-].

    References
    ----------
    [VLP09] (the slider's static flying attitude); docs/model.md,
    section "Start state".
    """
    return bool(np.all(np.real(np.linalg.eigvals(K)) > 0))


def newton(forces: Callable[[np.ndarray], np.ndarray], y0, *, scale=None, jac=None, tol: float = 1e-10,
           max_iter: int = 50, max_step=None) -> Equilibrium:
    """Equilibrium ``R(y) = 0`` by Newton's method from ``y0``.

    Parameters
    ----------
    forces : ``R(y)`` [N, N m]
    y0 : start state; scale : typical size of each state component (default 1e-9 m and 1e-6 rad), sets
        the finite-difference steps and the convergence test ``|dy_j| < tol scale_j``
    jac : ``dR/dy`` callable (default: central differences)
    max_step : largest update of each component (default ``scale``): a trust bound that keeps Newton on
        the branch it starts from near a fold

    Returns
    -------
    Equilibrium
        The state ``y`` [m, rad], its stiffness [N/m, ...], whether it converged and is stable.

    References
    ----------
    [VLP09] (the slider's static flying attitude); docs/model.md,
    section "Start state".
    """
    y = np.array(y0, dtype=float)
    scale = np.asarray(scale if scale is not None else [NM, URAD][: y.size], dtype=float)
    max_step = scale if max_step is None else np.asarray(max_step, dtype=float)
    jac = jac or (lambda v: jacobian(forces, v, scale))
    converged = False
    it = 0
    for it in range(1, max_iter + 1):
        J = jac(y)
        try:
            dy = np.linalg.solve(J, -forces(y))
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(dy)):
            break
        shrink = np.max(np.abs(dy) / max_step)
        if shrink > 1:
            dy = dy / shrink
        y = y + dy
        if shrink <= 1 and np.all(np.abs(dy) < tol * scale):
            converged = True
            break
    K = -jac(y)
    R = forces(y)
    fscale = np.max(np.abs(K) @ scale) if np.all(np.isfinite(K)) else 1.0
    return Equilibrium(y, K, converged and bool(np.all(np.isfinite(R))), is_stable(K) if np.all(np.isfinite(K))
                       else False, it, float(np.max(np.abs(R)) / fscale) if fscale > 0 else np.inf)


def python_solve(forces: Forces, scale=None) -> Solve:
    """The :data:`Solve` of :func:`newton` on ``forces(y, mu)`` with the state scale ``scale``.

    Parameters
    ----------
    forces : ``R(y, mu)`` [N, N m]
    scale : typical size of each state component [m, rad] (default as :func:`newton`)

    Returns
    -------
    Solve
        ``solve(mu, y0, ...) -> Equilibrium`` (states in [m, rad]).

    References
    ----------
    [VLP09] (the slider's static flying attitude); docs/model.md,
    section "Start state".
    """
    def solve(mu: float, y0, max_step=None, max_iter: int = 50, tol: float = 1e-10) -> Equilibrium:
        return newton(lambda y: forces(y, mu), y0, scale=scale, tol=tol, max_iter=max_iter, max_step=max_step)
    return solve


@dataclass
class Branch:
    """A continued stable branch.

    Attributes
    ----------
    mu : parameter values reached, in order; states : their states (rows)
    fold : parameter where the branch ends, bracketed to ``mu_tol`` (NaN: it reaches the end)
    last : the last equilibrium on the branch
    """

    mu: list = field(default_factory=list)
    states: list = field(default_factory=list)
    fold: float = np.nan
    last: Equilibrium | None = None

    def state_at(self, mu: float) -> np.ndarray | None:
        """The state at ``mu`` (a value the branch reached), or ``None``.

        Parameters
        ----------
        mu : the parameter (a protrusion [m])

        Returns
        -------
        numpy.ndarray or None
            The state (``z`` [m], ``theta`` [rad]), or ``None`` where the branch has none.

        References
        ----------
        [Ono17] (the static unstable region of a TFC slider near contact); docs/model.md, sections "Start state"
        and "Statics map".
        """
        for m, s in zip(self.mu, self.states):
            if np.isclose(m, mu, rtol=0, atol=1e-12 * max(1.0, abs(mu))):
                return s
        return None


def flying_branch(forces: Forces, mu_values, y0=None, *, scale=None, accept: Callable[[np.ndarray], bool] | None = None,
                  mu_tol: float | None = None, tol: float = 1e-10, max_iter: int = 50,
                  solve: Solve | None = None) -> Branch:
    """Continue the stable equilibrium branch through increasing ``mu_values`` from ``y0`` at ``mu_values[0]``.

    Each step starts Newton from the secant predictor; a step is accepted when Newton converges to a
    *stable* state that ``accept`` admits (e.g. "the TFC point is above the contact criterion"), else
    the step is halved; when it falls below ``mu_tol`` the branch has ended: ``fold`` is the first value
    where no admissible stable state continues it (the saddle-node fold, bracketed to ``mu_tol``).

    Parameters
    ----------
    forces : ``R(y, mu)``; mu_values : increasing parameters to report (e.g. protrusions [m])
    y0 : state at ``mu_values[0]`` (default zeros: the nominal attitude) or a start for Newton there
    scale : as :func:`newton`; mu_tol : fold bracket (default ``1e-6`` of the range)
    solve : the Newton solve (:data:`Solve`; default :func:`newton` on ``forces``)

    Returns
    -------
    Branch
        The states [m, rad] at the values of ``mu_values`` it reached and its fold [m] (NaN: none).

    References
    ----------
    [Ono17] (the static unstable region of a TFC slider near contact); docs/model.md, sections "Start state"
    and "Statics map".
    """
    mus = np.asarray(mu_values, dtype=float)
    if mus.ndim != 1 or mus.size < 1 or np.any(np.diff(mus) <= 0):
        raise ValueError("flying_branch: mu_values must be increasing")
    span = float(mus[-1] - mus[0]) if mus.size > 1 else 1.0
    mu_tol = 1e-6 * span if mu_tol is None else mu_tol
    y0 = np.zeros(2 if scale is None else len(scale)) if y0 is None else np.asarray(y0, dtype=float)
    ok = accept or (lambda y: True)
    newton_at = solve or python_solve(forces, scale)

    def solve_at(mu, start):
        return newton_at(mu, start, max_iter=max_iter, tol=tol)

    br = Branch()
    e = solve_at(mus[0], y0)
    if not (e.converged and e.stable and ok(e.y)):
        br.fold = float(mus[0])
        return br
    br.mu.append(float(mus[0]))
    br.states.append(e.y)
    br.last = e
    mu, y, y_prev, mu_prev = float(mus[0]), e.y, None, None
    for target in mus[1:]:
        step = target - mu
        while mu < target:
            step = min(step, target - mu)
            trial = mu + step
            pred = y if y_prev is None else y + (y - y_prev) * (trial - mu) / (mu - mu_prev)
            e = solve_at(trial, pred)
            if e.converged and e.stable and ok(e.y):
                y_prev, mu_prev, y, mu = y, mu, e.y, trial
                br.last = e
                step *= 2.0
            else:
                step /= 2.0
                if step < mu_tol:
                    br.fold = mu + step * 2.0  # the smallest failed trial
                    return br
        br.mu.append(float(target))
        br.states.append(y)
    return br


@dataclass(frozen=True)
class StaticState:
    """The start state of a run at one parameter value.

    Attributes
    ----------
    kind : ``"flying"``, ``"contact"`` or ``"none"`` (neither branch found)
    equilibrium : the state (``None`` for ``"none"``); fold : where the flying branch ended (NaN: not reached)
    message : what was found, in words (``"no flying equilibrium ..."`` past the fold)
    """

    kind: str
    equilibrium: Equilibrium | None
    fold: float
    message: str


def static_equilibrium(forces: Forces, mu: float, *, mu_start: float = 0.0, y_start=None, scale=None,
                       accept: Callable[[np.ndarray], bool] | None = None, contact_start=None,
                       contact_max_step=None, steps: int = 20, mu_tol: float | None = None,
                       fold: float | None = None, solve: Solve | None = None, ladder: Branch | None = None
                       ) -> StaticState:
    """The static state at ``mu``: the flying equilibrium, else the contact-branch equilibrium.

    The flying state is continued from ``y_start`` (default the nominal attitude, zeros) at ``mu_start``
    (default 0: zero protrusion) in ``steps`` equal steps (:func:`flying_branch`). If the branch ends at
    a fold before ``mu``, there is no flying equilibrium; then Newton from ``contact_start`` (a state in
    contact, e.g. the TFC point at zero separation) gives the contact-branch equilibrium, if it converges
    to a stable state. ``contact_max_step`` bounds its updates (default ``scale``): the interface laws
    are piecewise (the contact law switches on at the criterion), and a full Newton step from deep contact
    can leave the contact region, where the adhesion alone has no root; small steps approach the contact
    equilibrium from inside.

    ``fold``: where the flying branch of the same forces, continued from the same start, is known to end
    (:func:`branch_fold`); at or past it the continuation, whose step halving to ``mu_tol`` at the fold
    is most of the cost, is not repeated. ``solve``: the Newton solve (:data:`Solve`; default :func:`newton`
    on ``forces``).

    ``ladder``: the flying branch of the same forces and start, continued once for all protrusions
    (:func:`flying_ladder`): its fold is then ``fold``, and a ``mu`` before it is continued from the
    ladder's last state at or below ``mu`` in one step (the same state to the Newton tolerance as the
    continuation from ``mu_start``: the branch is smooth and both converge to its one state at ``mu``).

    Parameters
    ----------
    forces : ``R(y, mu)`` [N, N m]
    mu : the parameter (a protrusion [m])
    mu_start, y_start : where the flying branch starts ([m]; [m, rad])
    scale : as :func:`newton`; accept : which stable states are flying
    contact_start, contact_max_step : the contact branch's Newton start [m, rad] and step bound
    steps, mu_tol : the continuation's steps and fold bracket [m]
    fold, solve, ladder : as above

    Returns
    -------
    StaticState
        The state [m, rad], its kind (flying, contact or none) and its equilibrium.

    References
    ----------
    [Ono17] (the static unstable region of a TFC slider near contact); docs/model.md, sections "Start state"
    and "Statics map".
    """
    solve = solve or python_solve(forces, scale)
    if ladder is not None:
        fold = ladder.fold
    if fold is not None and np.isfinite(fold) and mu >= fold:
        br = Branch(fold=float(fold))
    elif ladder is not None and ladder.mu and ladder.mu[0] <= mu:
        j = int(np.searchsorted(ladder.mu, mu, side="right")) - 1
        mus = np.array([ladder.mu[j], mu]) if mu > ladder.mu[j] else np.array([mu])
        br = flying_branch(forces, mus, ladder.states[j], scale=scale, accept=accept, mu_tol=mu_tol, solve=solve)
    else:
        mus = np.linspace(mu_start, mu, steps + 1) if mu > mu_start else np.array([mu])
        br = flying_branch(forces, mus, y_start, scale=scale, accept=accept, mu_tol=mu_tol, solve=solve)
    if np.isnan(br.fold):
        return StaticState("flying", br.last, np.nan, f"flying equilibrium at {mu:.6g}")
    msg = f"no flying equilibrium at {mu:.6g} (the flying branch ends at a fold at {br.fold:.6g})"
    if contact_start is None:
        return StaticState("none", None, br.fold, msg + "; no contact start given")
    e = solve(mu, contact_start, max_step=contact_max_step, max_iter=200)
    if e.converged and e.stable:
        return StaticState("contact", e, br.fold, msg + "; contact-branch equilibrium found")
    return StaticState("none", None, br.fold, msg + "; Newton found no stable contact state either")


def flying_ladder(forces: Forces, mu_max: float, *, mu_start: float = 0.0, y_start=None, scale=None,
                  accept: Callable[[np.ndarray], bool] | None = None, step: float, mu_tol: float | None = None,
                  solve: Solve | None = None) -> Branch:
    """The stable flying branch continued from ``y_start`` at ``mu_start`` towards ``mu_max`` through equal
    steps of at most ``step`` (:func:`flying_branch`): its states at those steps (the *ladder*) and where
    it ends (``fold``, bracketed to ``mu_tol``; NaN: not before ``mu_max``). One continuation answers
    :func:`static_equilibrium` at every ``mu``: past the fold there is no flying state, and before it the
    branch is continued from the ladder's state below ``mu`` (argument ``ladder``), at most one step.

    Parameters
    ----------
    forces : ``R(y, mu)`` [N, N m]
    mu_max : the largest parameter [m]
    mu_start, y_start : where the branch starts ([m]; [m, rad])
    scale, accept, solve : as :func:`flying_branch`
    step : the largest step [m]; mu_tol : the fold bracket [m]

    Returns
    -------
    Branch
        The ladder's states [m, rad] and its fold [m] (NaN: not before ``mu_max``).

    References
    ----------
    [Ono17] (the static unstable region of a TFC slider near contact); docs/model.md, sections "Start state"
    and "Statics map".
    """
    n = max(1, int(np.ceil((mu_max - mu_start) / step)))
    return flying_branch(forces, np.linspace(mu_start, mu_max, n + 1), y_start, scale=scale, accept=accept,
                         mu_tol=mu_tol, solve=solve)


def branch_fold(forces: Forces, mu_max: float, *, mu_start: float = 0.0, y_start=None, scale=None,
                accept: Callable[[np.ndarray], bool] | None = None, step: float, mu_tol: float | None = None,
                solve: Solve | None = None) -> float:
    """Where the stable flying branch continued from ``y_start`` at ``mu_start`` ends (NaN: not before
    ``mu_max``): the fold of :func:`flying_ladder` (same arguments).

    Parameters
    ----------
    forces, mu_max, mu_start, y_start, scale, accept, step, mu_tol, solve : as :func:`flying_ladder`

    Returns
    -------
    float
        The fold [m] (the unit of ``mu``), NaN for none before ``mu_max``.

    References
    ----------
    [Ono17] (the static unstable region of a TFC slider near contact); docs/model.md, sections "Start state"
    and "Statics map".
    """
    return flying_ladder(forces, mu_max, mu_start=mu_start, y_start=y_start, scale=scale, accept=accept, step=step,
                         mu_tol=mu_tol, solve=solve).fold


#: Start rules of a run (``solver.start``, :func:`pipeline.model.start.start_state`): the behaviour is the
#: solver of the start state on the model's static forces (:func:`static_equilibrium`), or ``None``: the
#: nominal attitude ``z = theta = 0`` at rest.
STARTS: Registry[Variant] = Registry("solver.start", {
    "static": Variant(behaviour=static_equilibrium,
                      summary="the model's static equilibrium, continued in the protrusion; past the adhesion fold "
                              "the contact branch",
                      source='docs/model.md, section "Start state"'),
    "nominal": Variant(summary="the nominal attitude z = theta = 0 at rest (the model before the start state was "
                               "part of it)",
                       source='docs/model.md, section "Start state"'),
})
