"""Fewer steps in sliding: what limits DP5 at the contact stiffness cap, measured on the kernel's own sliding case.

The sliding 11 nm case of :mod:`benchmarks.kernel_ab` (the paper scene at ``contact.k = 0.445``, 2 ms, steady
contact: no switch) is integrated with fixed steps ``h = c / omega`` (``omega`` [rad/s] the largest frequency of the
right-hand side's Jacobian at the start: the contact mode at the TFC point), and the separation's peak-to-peak
over the steady window (what FHM/BV measures, [m]) is compared with a tight kernel reference's exact one
(``integrate``'s ``ext``: ``rtol = 1e-11``, the step cap 10 ns and ``stiffness_step = 0.25``). Three measurements
(docs/kernel.md, section "Fewer steps in sliding: what limits DP5 at the cap"):

``interpolant C ...``: at each ``h omega = C``, DP5's steps, the separation's extremes taken on

* the step ends alone;
* the cubic Hermite interpolant through the step's ends and derivatives (the kernel's outputs, extrema and
  event search: :mod:`pipeline.model.stepper`);
* DP5's own continuous extension of order 4 (Hairer, Norsett & Wanner, *Solving ODEs I*, II.6, the dense output
  of Dormand & Prince's pair, Shampine 1986), from the seven stages the step has already evaluated;
* the quintic Hermite interpolant of the positions ``z, theta`` through their values, rates and accelerations at
  the step's ends (the rates and accelerations are rows of the derivative the step has: no evaluation);

each extreme sampled at :data:`SAMPLES` points a step and refined with a bounded scalar search in the
:data:`REFINE` steps of the largest (smallest) samples. Where the separation's extremes fall within their steps
decides much of each interpolant's error (up to 2-4x between two step sizes 0.1 % apart), so each ``C`` is run at
:data:`PHASES` step sizes ``C (1 + j 1e-3)`` and the range over them is reported.

``cap C ...``: the accuracy study's own measure (:mod:`pipeline.stages.accuracy`: the largest headline error of its
three points against its integrator reference, the kernel's exact extremes) at the scene's default settings with
``solver.stiffness_step = C``: what lifting today's cap costs in accuracy, with the kernel's interpolant.

``methods C ...``: DP5 against its Lawson form (Lawson 1967, *SIAM J. Numer. Anal.* 4, 372; the integrating factor
``exp(tau h L)`` of a linear part ``L`` frozen at each step's start) and Cox & Matthews' ETDRK4 (four evaluations a
step), ``L`` the contact's part of the Jacobian (with the contact law minus without it: the spring and damper of the
contact pressure at the TFC point), the interface's part (the Jacobian minus the pads' alone: contact, adhesion,
friction and the TFC point's air bearing; ETDRK4 only), the contact mode's part (the Jacobian's fastest pair of
eigenvalues, :func:`contact_mode`; ETDRK4 only) or the whole Jacobian; the error of ``s = z - l_c theta`` [m] at the
step ends against the reference, over the window's peak-to-peak.

Usage (15 s to a few minutes each; plain Python loops around the compiled right-hand side)::

    .venv/bin/python -m benchmarks.sliding_methods interpolant 1 1.25 1.5
    .venv/bin/python -m benchmarks.sliding_methods methods 1 1.5 2 3
    .venv/bin/python -m benchmarks.sliding_methods cap 1 1.1 1.2 1.35 1.5
"""

from __future__ import annotations

import argparse
import pickle
import tempfile
from pathlib import Path

import numpy as np
from scipy.linalg import expm
from scipy.optimize import minimize_scalar

from pipeline.model import stepper as st
from pipeline.physics.equilibrium import jacobian

from . import kernel_ab

#: The contact criterion of the paper scene in :mod:`benchmarks.kernel_ab`'s cases [1].
K = kernel_ab.K
#: Samples of each interpolant a step (before the refinement).
SAMPLES = 16
#: Steps, of the largest (smallest) samples, in which an extreme is refined.
REFINE = 8
#: Step sizes per ``h omega`` of ``interpolant``, 0.1 % apart: over the 2 ms the steps' phase against the
#: separation's extremes moves by ~13 steps from one to the next.
PHASES = 6

# Dormand-Prince 5(4): the kernel's tableau (pipeline.model.stepper; Hairer, Norsett & Wanner, Table II.5.2), the
# nodes the stage times of its step; and its dense output of order 4 (ibid., II.6), which the kernel does not use
A = ((), (st.A21,), (st.A31, st.A32), (st.A41, st.A42, st.A43), (st.A51, st.A52, st.A53, st.A54),
     (st.A61, st.A62, st.A63, st.A64, st.A65))
C = (0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0)
B = (st.B1, 0.0, st.B3, st.B4, st.B5, st.B6)
D = (-12715105075 / 11282082432, 0.0, 87487479700 / 32700410799, -10690763975 / 1880347072,
     701980252875 / 199316789632, -1453857185 / 822651844, 69997945 / 29380423)


class Case:
    """The captured sliding case: its right-hand side, separation and reference."""

    def __init__(self):
        from pipeline.model import dynamics as dyn
        from pipeline.model.forces import separation
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "cases.pkl"
            kernel_ab.capture(path)
            self.y0, self.grid, self.p, self.tab, self.var, self.solver = pickle.loads(path.read_bytes())["sliding_11"]
        self.dyn, self._separation = dyn, separation
        self.out = np.empty(self.y0.size)
        self.t_win = float(self.p["t_win"])
        self.l_c = float(self.p["l_c"])
        self.omega = float(np.max(np.abs(np.linalg.eigvals(self.jacobian(0.0, self.y0, True)))))

    def f(self, t: float, y: np.ndarray, contact: bool = True, interface: bool = True) -> np.ndarray:
        """``dy/dt`` (SI) in the contact mode ``contact``; without ``interface``, the pads' forces alone (the
        interface's tables and the TFC point's air-bearing law off)."""
        tab, var = self.tab, self.var
        if not interface:
            tab = tab._replace(contact=None, adhesion=None, friction=None, tfc=None)
            var = var._replace(gap_power=None)
        self.dyn.rhs(t, y, self.p, tab, var, contact, self.out)
        return self.out.copy()

    def d(self, t: float, y: np.ndarray) -> float:
        """Separation [m]."""
        return float(self._separation(self.p, self.tab.dmw, t, y)[0])

    def jacobian(self, t: float, y: np.ndarray, contact: bool, interface: bool = True) -> np.ndarray:
        """Jacobian of :meth:`f` [SI] (:func:`pipeline.physics.equilibrium.jacobian`'s central differences, steps
        ``1e-6`` of each component, ``1e-18`` at least)."""
        return jacobian(lambda yy: self.f(t, yy, contact, interface), y, np.maximum(np.abs(y), 1e-12))

    def reference(self, t_out: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The tight kernel run: states at ``t_out`` [s], and the exact extremes of ``d`` over the window [m]."""
        rec = self.dyn._packed(self.p)
        rec["h_stiff"] = 0.25
        solver = self.solver._replace(rtol=1e-11, atol=self.solver.atol * 1e-5, h_max=10e-9)
        Y, _, _, ext = self.dyn.integrate(self.y0, self.grid._replace(t_out=t_out), rec[0], self.tab, self.var,
                                          solver)
        return Y, ext


def dp5_step(case: Case, t: float, y: np.ndarray, k1: np.ndarray, h: float, L: np.ndarray | None = None):
    """One DP5 step (``L`` None) or Lawson-DP5 step with the linear part ``L``: the new state and the seven
    stage derivatives (the last at the new state; Lawson's are those of the nonlinear rest)."""
    if L is None:
        k = [k1]
        for i in range(1, 6):
            k.append(case.f(t + C[i] * h, y + h * sum(A[i][j] * k[j] for j in range(i))))
        y1 = y + h * sum(B[j] * k[j] for j in range(6))
        k.append(case.f(t + h, y1))
        return y1, k
    E: dict[float, np.ndarray] = {}

    def ex(tau: float) -> np.ndarray:
        if tau not in E:
            E[tau] = expm(tau * h * L)
        return E[tau]

    N: list[np.ndarray] = []
    for i in range(6):
        yi = ex(C[i]) @ y + h * sum(A[i][j] * (ex(C[i] - C[j]) @ N[j]) for j in range(i))
        N.append(case.f(t + C[i] * h, yi) - L @ yi)
    return ex(1.0) @ y + h * sum(B[j] * (ex(1.0 - C[j]) @ N[j]) for j in range(6)), N


def _phi(M: np.ndarray, k: int) -> list[np.ndarray]:
    """``[exp(M), phi_1(M), ..., phi_k(M)]`` from the exponential of the augmented block matrix (Saad 1992;
    Al-Mohy & Higham 2011, eq. 2.11)."""
    n = M.shape[0]
    big = np.zeros((n * (k + 1), n * (k + 1)))
    big[:n, :n] = M
    for i in range(k):
        big[n * i:n * (i + 1), n * (i + 1):n * (i + 2)] = np.eye(n)
    E = expm(big)
    return [E[:n, n * i:n * (i + 1)] for i in range(k + 1)]


def etdrk4_step(case: Case, t: float, y: np.ndarray, h: float, L: np.ndarray) -> np.ndarray:
    """One step of Cox & Matthews' ETDRK4 (*J. Comput. Phys.* 176, 430, 2002, eqs. 26-29) for
    ``y' = L y + N(t, y)``, ``N = f - L y``, ``L`` frozen over the step: four evaluations."""
    def N(tt, yy):
        return case.f(tt, yy) - L @ yy
    e2, p12 = _phi(h / 2 * L, 1)
    e1, p1, p2, p3 = _phi(h * L, 3)
    Nu = N(t, y)
    a = e2 @ y + h / 2 * (p12 @ Nu)
    Na = N(t + h / 2, a)
    b = e2 @ y + h / 2 * (p12 @ Na)
    Nb = N(t + h / 2, b)
    c = e2 @ a + h / 2 * (p12 @ (2 * Nb - Nu))
    Nc = N(t + h, c)
    return e1 @ y + h * ((p1 - 3 * p2 + 4 * p3) @ Nu + 2 * (p2 - 2 * p3) @ (Na + Nb) + (4 * p3 - p2) @ Nc)


def _hermite(y0, f0, y1, f1, h, x):
    """The state at the step's fraction ``x`` on the kernel's cubic Hermite interpolant
    (:func:`pipeline.model.stepper.interp_state`)."""
    out = np.empty(y0.size)
    st.interp_state(y0, f0, y1, f1, h, x, out)
    return out


def _quintic(y0, f0, y1, f1, h, x):
    """The positions ``(z, theta)`` on the quintic Hermite interpolant through their values, rates and
    accelerations at the step's ends (the rates and accelerations are the derivative's rows: no evaluation),
    the rates on the cubic Hermite; the other components on the cubic."""
    y = _hermite(y0, f0, y1, f1, h, x)
    x2, x3 = x * x, x ** 3
    h00 = 1 - 10 * x3 + 15 * x3 * x - 6 * x3 * x2
    h10 = x - 6 * x3 + 8 * x3 * x - 3 * x3 * x2
    h20 = 0.5 * x2 - 1.5 * x3 + 1.5 * x3 * x - 0.5 * x3 * x2
    h01 = 10 * x3 - 15 * x3 * x + 6 * x3 * x2
    h11 = -4 * x3 + 7 * x3 * x - 3 * x3 * x2
    h21 = 0.5 * x3 - x3 * x + 0.5 * x3 * x2
    for i, j in ((0, 2), (1, 3)):  # (position, its rate's row)
        y[i] = (h00 * y0[i] + h10 * h * f0[i] + h20 * h * h * f0[j] + h01 * y1[i] + h11 * h * f1[i]
                + h21 * h * h * f1[j])
    return y


def _continuous(y0, y1, k, h, x):
    r2 = y1 - y0
    r3 = h * k[0] - r2
    r4 = r2 - h * k[6] - r3
    r5 = h * sum(D[j] * k[j] for j in range(7))
    return y0 + x * (r2 + (1 - x) * (r3 + x * (r4 + (1 - x) * r5)))


def _extremes(case: Case, steps: list, interp) -> tuple[float, float]:
    """Min and max of ``d`` [m] over the window on the interpolant ``interp(step, x)`` of each step
    ``(t, h, ...)``: sampled, then refined in the :data:`REFINE` most extreme steps."""
    xs = np.linspace(0.0, 1.0, SAMPLES + 1)
    lo, hi = [], []
    for s in steps:
        t, h = s[0], s[1]
        vals = [case.d(t + x * h, interp(s, x)) for x in xs if t + x * h >= case.t_win]
        lo.append(min(vals))
        hi.append(max(vals))
    def refined(i: int, sign: float) -> float:
        t, h = steps[i][0], steps[i][1]
        r = minimize_scalar(lambda x: sign * case.d(t + x * h, interp(steps[i], x)),
                            bounds=(max(0.0, (case.t_win - t) / h), 1.0), method="bounded", options={"xatol": 1e-9})
        return sign * r.fun

    d_min = min(min(lo), *(refined(i, 1.0) for i in np.argsort(lo)[:REFINE]))
    d_max = max(max(hi), *(refined(i, -1.0) for i in np.argsort(hi)[::-1][:REFINE]))
    return d_min, d_max


def interpolant(case: Case, cs: list[float], phases: int = PHASES) -> None:
    """The ``interpolant`` measurement (module docstring): each interpolant's peak-to-peak error, its range over
    ``phases`` step sizes 0.1 % apart at each ``h omega``."""
    _, ext = case.reference(np.array([case.grid.t_end]))
    bv = ext[1] - ext[0]
    print(f"reference: d over the window {ext[0] * 1e9:.5f} .. {ext[1] * 1e9:.5f} nm (peak-to-peak "
          f"{bv * 1e9:.5f} nm); omega {case.omega:.4g} rad/s")
    interpolants = (("Hermite cubic", lambda s, x: _hermite(s[2], s[4][0], s[3], s[4][6], s[1], x)),
                    ("DP5 continuous extension", lambda s, x: _continuous(s[2], s[3], s[4], s[1], x)),
                    ("quintic Hermite of the positions", lambda s, x: _quintic(s[2], s[4][0], s[3], s[4][6], s[1], x)))
    for c in cs:
        errs: dict[str, list[float]] = {}
        for j in range(phases):
            h = c * (1 + 1e-3 * j) / case.omega
            t, y, k1 = 0.0, case.y0.copy(), case.f(0.0, case.y0)
            steps = []
            while t + h <= case.grid.t_end:
                y1, k = dp5_step(case, t, y, k1, h)
                if t + h >= case.t_win:
                    steps.append((t, h, y, y1, k))
                t, y, k1 = t + h, y1, k[6]
            ends = [case.d(s[0] + s[1], s[3]) for s in steps]
            rows = [("step ends", min(ends), max(ends))] + [(lab, *_extremes(case, steps, fn))
                                                            for lab, fn in interpolants]
            for lab, a, b in rows:
                errs.setdefault(lab, []).append(abs((b - a) - bv) / bv)
        text = "   ".join(f"{lab}: {min(e):.2e}-{max(e):.2e}" for lab, e in errs.items())
        print(f"h omega {c:4.2f} (h {c / case.omega * 1e9:5.1f} ns, {6 * round(case.grid.t_end * case.omega / c)} "
              f"evaluations; {phases} step sizes): peak-to-peak error  {text}", flush=True)


def contact_mode(J: np.ndarray) -> np.ndarray:
    """The part of the Jacobian ``J`` in its fastest pair of eigenvalues (the contact mode, its shape the pads'
    and the interface's stiffness together): ``V diag(lambda) V^-1`` with the other eigenvalues set to zero."""
    lam, V = np.linalg.eig(J)
    fast = np.abs(lam) >= np.sort(np.abs(lam))[-2]
    return np.real(V @ np.diag(np.where(fast, lam, 0.0)) @ np.linalg.inv(V))


def methods(case: Case, cs: list[float], only: str | None = None) -> None:
    """The ``methods`` measurement (module docstring): each method's error at the step ends, by ``h omega``."""
    for c in cs:
        h = c / case.omega
        m = int(case.grid.t_end / h)
        ts = h * np.arange(1, m + 1)
        Y, _ = case.reference(ts)
        s_ref = Y[:, 0] - case.l_c * Y[:, 1]
        win = ts >= case.t_win
        bv = s_ref[win].max() - s_ref[win].min()
        for label, mode in (("DP5", "dp5"), ("Lawson, contact part", "contact"), ("Lawson, whole Jacobian", "full"),
                            ("ETDRK4, contact part", "etd-contact"), ("ETDRK4, interface part", "etd-interface"),
                            ("ETDRK4, contact mode", "etd-mode"), ("ETDRK4, whole Jacobian", "etd-full")):
            if only is not None and only not in label:
                continue
            t, y = 0.0, case.y0.copy()
            s = np.empty(m)
            for i in range(m):
                L = None
                if mode in ("contact", "etd-contact"):
                    L = case.jacobian(t, y, True) - case.jacobian(t, y, False)
                elif mode == "etd-interface":
                    L = case.jacobian(t, y, True) - case.jacobian(t, y, True, interface=False)
                elif mode == "etd-mode":
                    L = contact_mode(case.jacobian(t, y, True))
                elif mode in ("full", "etd-full"):
                    L = case.jacobian(t, y, True)
                if mode.startswith("etd"):
                    y = etdrk4_step(case, t, y, h, L)
                else:
                    y = dp5_step(case, t, y, case.f(t, y), h, L)[0]
                t += h
                s[i] = y[0] - case.l_c * y[1]
            err = np.abs(s - s_ref)[win].max() / bv
            evaluations = (4 if mode.startswith("etd") else 6) * m
            print(f"h omega {c:4.2f} (h {h * 1e9:5.1f} ns, {evaluations} evaluations) {label:24s} "
                  f"max |s - s_ref| over the peak-to-peak {err:.2e}", flush=True)


def cap(cs: list[float]) -> None:
    from pipeline.analyses.knob_study import HEADLINE, POINTS, REFERENCE, errors, max_error
    from pipeline.config.loading import load_scene
    from pipeline.stages.accuracy import _evaluate, _RunCache
    scene = load_scene(kernel_ab.ROOT / "configs" / "paper-2009.toml", [f"contact.k={K}"])
    current = {key: scene["solver"][key] for key in scene["solver"] if key in REFERENCE}
    current["sample_rate_mhz"] = scene["dmw"]["sample_rate_mhz"]
    with tempfile.TemporaryDirectory() as tmp:
        cache = _RunCache(scene, Path(tmp), 1)
        # (the study's reference: its settings of the keys this scene has, as pipeline.stages.accuracy takes them)
        ref = _evaluate(scene, {k: v for k, v in REFERENCE.items() if k in current}, cache, K, POINTS, 1)
        for c in cs:
            res = _evaluate(scene, {**current, "stiffness_step": c}, cache, K, POINTS, 5)
            err = errors(res, ref)
            worst = max_error(err)
            print(f"stiffness_step {c:4.2f}: " + "   ".join(
                f"{point} {worst[i]:.2e} ({HEADLINE[int(np.nanargmax(err[i]))]}, {res.info[i][0]} steps, "
                f"{res.info[i][1]} rejected, {res.sim_time[i] * 1e3:.2f} ms)" for i, point in enumerate(POINTS)),
                flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("interpolant", "methods", "cap"))
    ap.add_argument("--only", default=None, help="methods: only those whose label contains this")
    ap.add_argument("--phases", type=int, default=PHASES, help="interpolant: step sizes 0.1 %% apart per h omega")
    ap.add_argument("c", type=float, nargs="+", help="h omega of the fixed steps")
    args = ap.parse_args()
    if args.what == "cap":
        return cap(args.c)
    case = Case()
    if args.what == "interpolant":
        interpolant(case, args.c, args.phases)
    else:
        methods(case, args.c, args.only)


if __name__ == "__main__":
    main()
