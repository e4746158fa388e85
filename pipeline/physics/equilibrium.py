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


# ------------------------------------------------------------------------------------------- statics map
# Every static state along a one-parameter path, its stability and the barrier out of it
# (docs/model.md, section "Statics map").

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
