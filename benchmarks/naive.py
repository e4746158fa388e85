"""The naive baseline: the slider model as a competent user would write it first.

Same physics as :func:`pipeline.model.dynamics.rhs` (docs/model.md, section "Slider dynamics"): linear front pad, nonlinear rear
pad ``F_r0 [(g0/g)^n - 1]``, the disk under each point moving with the DMW record delayed by the
travel time, adhesion ``-A_n p_a(d)`` always, contact ``A_n p_c(d) - c_c d'`` and friction
``A_n tau(d)`` (moment ``-friction_arm Q``) while ``d < k sigma``. Written the plain way:

* :func:`scipy.integrate.solve_ivp` with ``RK45`` (the same Dormand-Prince 5(4) pair as the project's
  kernel) at the scene's ``rtol``, per-component ``atol`` and ``max_step`` (the same values the
  project uses, taken from :func:`pipeline.model.assembly.build_model`);
* a Python right-hand side that interpolates the ``interface.nc`` tables with :func:`numpy.interp`;
* the contact switch as a terminal ``solve_ivp`` event on ``g = d - k sigma`` (direction: leaving
  the current mode), integration restarted in the new mode from the event state; after a switch the
  mode is held for ``solver.min_dwell_ns`` (integrated without events), then the criterion is
  checked, exactly as the project's chattering guard does;
* the DMW record: with ``dmw_interpolation="cubic"`` (default) the same not-a-knot cubic spline as
  the project (:class:`scipy.interpolate.CubicSpline` coefficients, evaluated in Python for the
  displacement and its slope), so both integrate exactly the same right-hand side up to the table
  interpolation; ``"linear"``: :func:`numpy.interp` on the record and on its :func:`numpy.gradient`
  (the first thing one writes; slower in Python -- two ``np.interp`` calls per point -- and the
  bouncing vibration at 11 nm moves by ~3 %: 0.0013 nm on the 0.34 % BV of the corrected paper
  scene). The tables are fine with ``np.interp`` (0.01 nm spacing: linear versus cubic changes the
  headline outputs by < 1e-5).

Nothing here is deliberately slow: the model constants are computed once, the right-hand side is
plain scalar Python with no allocation beyond the returned list, and there is no per-step Python
logic other than what ``solve_ivp`` does itself.

:func:`simulate_naive` returns the same steady-window scalars as :func:`pipeline.model.outcomes.summarize`
(SI units, same definitions), computed here directly from the naive run: means over the output grid;
the peak-to-peak (FHM/BV) and minimum of the separation, which the project takes from the exact
extremes tracked by its integrator, from ``solve_ivp``'s dense output sampled 10x finer than the
output grid (:data:`REFINE`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

from pipeline.model.forces import separation_at
from pipeline.model.state import THETA, THETA_RATE, Z, Z_RATE

#: Longest solve_ivp segment [s] with interface tables: the step cap is renewed at each segment start.
SEGMENT = 20e-6
from pipeline.model import assembly, outcomes, running
from pipeline.physics.geometry import effective_radius, nominal_area

NM, UM, MM = 1e-9, 1e-6, 1e-3

#: Samples per output step for the peak-to-peak and minimum of the separation.
REFINE = 10


class _Disk:
    """DMW displacement [m] and velocity [m/s] at time ``t`` [s]."""

    def __init__(self, w_nm: np.ndarray, fs: float, how: str):
        w = np.asarray(w_nm, float) * NM
        self.dt = 1.0 / fs
        self.t = np.arange(w.size) * self.dt
        self.how = how
        if how == "cubic":
            c = CubicSpline(self.t, w).c
            self.c0, self.c1, self.c2, self.c3 = (c[i].tolist() for i in range(4))
            self.last = w.size - 2
        elif how == "linear":
            self.w = w
            self.v = np.gradient(w, self.dt)
        else:
            raise ValueError(f"dmw_interpolation = {how!r}: expected 'cubic' or 'linear'")

    def __call__(self, t: float) -> tuple[float, float]:
        if self.how == "linear":
            return float(np.interp(t, self.t, self.w)), float(np.interp(t, self.t, self.v))
        i = int(t / self.dt)
        i = 0 if i < 0 else (self.last if i > self.last else i)
        s = t - i * self.dt
        c0, c1, c2 = self.c0[i], self.c1[i], self.c2[i]
        return ((c0 * s + c1) * s + c2) * s + self.c3[i], (3.0 * c0 * s + 2.0 * c1) * s + c2

    def many(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised evaluation for post-processing (same interpolant)."""
        t = np.asarray(t, float)
        if self.how == "linear":
            return np.interp(t, self.t, self.w), np.interp(t, self.t, self.v)
        i = np.clip((t / self.dt).astype(int), 0, self.last)
        s = t - i * self.dt
        c0, c1, c2, c3 = (np.asarray(c)[i] for c in (self.c0, self.c1, self.c2, self.c3))
        return ((c0 * s + c1) * s + c2) * s + c3, (3.0 * c0 * s + 2.0 * c1) * s + c2


def _no_disk(t: float) -> tuple[float, float]:
    return 0.0, 0.0


@dataclass
class Physics:
    """The naive model's constants for one protrusion (SI units), computed once: the slider's
    (``m`` [kg], ``I`` [kg m^2], pad positions ``lf``, ``lr``, ``lc``, friction arm ``hcg`` [m], pad
    stiffness ``kf`` [N/m], dampings ``cf``, ``cr``, ``cc`` [N s/m], rear-pad gap ``g0`` [m], exponent ``n``
    [1], preload ``Fr0`` [N]), the separation datum ``d_nom`` [m], the DMW record's delays ``off_*`` [s]
    and the interface tables on their separation grid ``x`` [m] (pressures [Pa], area fraction [1]): what
    :func:`simulate_naive` and the bench's peers (:mod:`benchmarks.peers`) integrate."""

    scene: Any
    model: Any
    m: float
    I: float
    lf: float
    lr: float
    lc: float
    hcg: float
    kf: float
    cf: float
    cr: float
    g0: float
    n: float
    Fr0: float
    FH0: float
    delta: float
    p_sep: Any
    d_nom: float
    cc: float
    dwell: float
    t_end: float
    off_f: float
    off_r: float
    off_c: float
    disk: Any
    use_tables: bool
    x: np.ndarray | None
    pa: np.ndarray | None
    pc: np.ndarray | None
    ar: np.ndarray | None
    ft: np.ndarray | None
    sigma: float
    s_n: float
    An: float
    has_contact: bool
    ksig: float
    pitch: bool


def physics(scene: Any, interface_ds: Any, dmw_tuple: tuple[np.ndarray, float] | None, k: float | None,
            protrusion_nm: float, dmw_interpolation: str = "cubic") -> Physics:
    """The naive model's constants (:class:`Physics`) of ``scene`` at ``protrusion_nm`` [nm] (the arguments
    of :func:`simulate_naive`)."""
    eff = scene.effects
    # The model constants: the same assembly as the project (parameters, not dynamics).
    model = assembly.build_model(scene, interface_ds, dmw_tuple, k)
    if model.tfc_stiffening is not None or model.rear_law.name != "power":
        raise NotImplementedError("the naive baseline implements the default model only (air_bearing.rear_law = "
                                  "'power', air_bearing.tfc_stiffening = 'none')")
    s = model.slider
    a = scene["air_bearing"]
    delta = protrusion_nm * NM
    # the separation datum from its one home (pipeline.model.forces.separation_at, docs/model.md, section "Separation datum"):
    # d = d_nom + z - l_c theta - w with d_nom = FH0 - delta - y_s
    p_sep = model.p.copy()
    p_sep.delta = delta
    dm = scene["dmw"]
    V = 2 * np.pi * dm["radius_mm"] * MM * dm["rpm"] / 60.0
    use_tables = interface_ds is not None and bool(eff & {"contact", "adhesion"})
    if use_tables:
        x = interface_ds["separation"].values * NM
        pa = interface_ds["adhesion_pressure"].values * 1e6 if "adhesion" in eff else None
        pc = interface_ds["contact_pressure"].values * 1e6 if "contact" in eff else None
        ar = interface_ds["real_area_fraction"].values if "contact" in eff else None
        ft = interface_ds["friction_stress"].values * 1e6 if "friction" in eff else None
        sigma = float(interface_ds["sigma"]) * NM
        s_n = scene["contact"]["section_depth_sigma"] * sigma
        An = float(nominal_area(delta, model.half_length, model.half_width, s_n))
    else:
        x = pa = pc = ar = ft = None
        sigma, s_n, An = np.nan, np.nan, 0.0
    has_contact = "contact" in eff
    return Physics(scene=scene, model=model, m=s.m, I=s.I, lf=s.l_f, lr=s.l_r, lc=s.l_c, hcg=s.friction_arm,
                   kf=s.k_f, cf=s.c_f, cr=s.c_r, g0=s.g0, n=s.n, Fr0=s.rear_preload, FH0=a["flying_height_nm"] * NM,
                   delta=delta, p_sep=p_sep, d_nom=float(separation_at(p_sep, 0.0, 0.0, 0.0)),
                   cc=scene["contact"]["damping_n_s_m"], dwell=scene["solver"]["min_dwell_ns"] * 1e-9,
                   t_end=model.duration, off_f=(s.l_f + s.l_c) / V, off_r=(s.l_c - s.l_r) / V, off_c=0.0,
                   disk=_Disk(*dmw_tuple, dmw_interpolation) if "dmw" in eff else _no_disk, use_tables=use_tables,
                   x=x, pa=pa, pc=pc, ar=ar, ft=ft, sigma=sigma, s_n=s_n, An=An, has_contact=has_contact,
                   ksig=k * sigma if has_contact else 0.0, pitch="pitch" in eff)


def right_hand_side(ph: Physics, counter: list[int]) -> Callable[[float, np.ndarray, bool], list[float]]:
    """The naive right-hand side ``rhs(t [s], y, contact) -> y'`` of :class:`Physics` ``ph`` (state ``(z [m],
    theta [rad], z' [m/s], theta' [rad/s])``, docs/model.md, section "Slider dynamics"), plain scalar Python on
    the constants bound as locals; each call adds one to ``counter[0]``."""
    m, I, lf, lr, lc, hcg = ph.m, ph.I, ph.lf, ph.lr, ph.lc, ph.hcg
    kf, cf, cr, g0, n, Fr0 = ph.kf, ph.cf, ph.cr, ph.g0, ph.n, ph.Fr0
    d_nom, cc, off_f, off_r, off_c, disk = ph.d_nom, ph.cc, ph.off_f, ph.off_r, ph.off_c, ph.disk
    use_tables, x, pa, pc, ft, An, pitch = ph.use_tables, ph.x, ph.pa, ph.pc, ph.ft, ph.An, ph.pitch

    def rhs(t: float, y: np.ndarray, contact: bool) -> list[float]:
        counter[0] += 1
        z, th, vz, vth = y
        wf, vf = disk(t + off_f)
        wr, vr = disk(t + off_r)
        F_f = -kf * (z + lf * th - wf) - cf * (vz + lf * vth - vf)
        g_r = g0 + z - lr * th - wr
        if g_r < 1e-3 * g0:
            g_r = 1e-3 * g0
        F_r = Fr0 * ((g0 / g_r) ** n - 1.0) - cr * (vz - lr * vth - vr)
        F_i = 0.0
        Q = 0.0
        if use_tables:
            wc, vc = disk(t + off_c)
            d = d_nom + z - lc * th - wc
            if pa is not None:
                F_i -= An * np.interp(d, x, pa)
            if contact:
                F_i += An * max(np.interp(d, x, pc), 0.0) - cc * (vz - lc * vth - vc)
                if ft is not None:
                    Q = An * max(np.interp(d, x, ft), 0.0)
        if pitch:
            return [vz, vth, (F_f + F_r + F_i) / m, (lf * F_f - lr * F_r - lc * F_i - hcg * Q) / I]
        return [vz, 0.0, (F_f + F_r + F_i) / m, 0.0]

    return rhs


def fine_grid(model: Any, refine: int = REFINE) -> np.ndarray:
    """The output grid of :func:`pipeline.model.running.run_model` [s], refined ``refine`` times (every
    ``refine``-th sample is an output time): where the naive run and the peers sample the state."""
    n_coarse = int(round(model.duration / model.output_step)) + 1
    t_coarse = np.minimum(np.arange(n_coarse) * model.output_step, model.duration)
    t_out = (t_coarse[:, None] + np.arange(refine)[None, :] * (model.output_step / refine)).ravel()
    t_out = t_out[: (n_coarse - 1) * refine + 1]
    t_out[-1] = t_coarse[-1]
    return t_out


def summarize_samples(ph: Physics, t_fine: np.ndarray, Y_fine: np.ndarray, C_fine: np.ndarray,
                      refine: int = REFINE) -> dict[str, float]:
    """The steady-window scalars of :func:`pipeline.model.outcomes.summarize` (SI units) from the states
    ``Y_fine`` and contact modes ``C_fine`` sampled at ``t_fine`` [s] (:func:`fine_grid` with ``refine``)."""
    return _summarize(ph.scene, ph.model, t_fine, Y_fine, C_fine, refine, ph.disk, ph.off_c, ph.x, ph.pa, ph.pc,
                      ph.ar, ph.ft, ph.An, ph.ksig, ph.cc, ph.FH0, ph.p_sep, ph.delta, ph.s_n, ph.has_contact)


def simulate_naive(scene: Any, interface_ds: Any, dmw_tuple: tuple[np.ndarray, float] | None, k: float | None,
                   protrusion_nm: float, *, dmw_interpolation: str = "cubic",
                   return_history: bool = False) -> dict[str, Any]:
    """Integrate one protrusion the naive way and return its steady-window scalars.

    Parameters
    ----------
    scene : the validated scene (effects, solver settings)
    interface_ds : the ``interface.nc`` dataset (or ``None`` without contact and adhesion)
    dmw_tuple : ``(displacement [nm], sample rate [Hz])`` or ``None`` without the dmw effect
    k : contact criterion constant [1]
    protrusion_nm : TFC protrusion [nm]
    dmw_interpolation : ``"cubic"`` (as the project) or ``"linear"`` (``np.interp``)
    return_history : also return ``time``, ``state``, ``contact`` arrays

    Returns
    -------
    dict
        The keys of :func:`pipeline.model.outcomes.summarize` (SI units) plus ``rhs_evaluations``,
        ``segments`` (``solve_ivp`` calls) and ``contact_switches``.
    """
    ph = physics(scene, interface_ds, dmw_tuple, k, protrusion_nm, dmw_interpolation)
    model, x, pa, pc, An, ksig, disk, d_nom, lc = ph.model, ph.x, ph.pa, ph.pc, ph.An, ph.ksig, ph.disk, ph.d_nom, ph.lc
    off_c, has_contact, dwell, t_end, eff = ph.off_c, ph.has_contact, ph.dwell, ph.t_end, scene.effects
    counter = [0]
    rhs = right_hand_side(ph, counter)

    def gap(t: float, y: np.ndarray) -> float:
        return d_nom + y[0] - lc * y[1] - disk(t + off_c)[0] - ksig

    # output grid, as pipeline.model.running.run_model, refined REFINE times for the peak-to-peak of d (the
    # project tracks the exact extremes of d; sampling 10x finer than the output grid comes within
    # ~0.3 % of them for the content of these runs, while the output grid alone aliases by a few %)
    t_out = fine_grid(model)
    n_out = t_out.size
    Y = np.full((n_out, 4), np.nan)
    C = np.zeros(n_out, dtype=bool)
    opts = dict(method="RK45", rtol=model.rtol, atol=model.atol, max_step=model.max_step)
    m_eff_inv = 1.0 / model.slider.m + (model.slider.l_c ** 2 / model.slider.I if "pitch" in eff else 0.0)
    dpa = np.gradient(pa, x) if x is not None and pa is not None else None
    dpc = np.gradient(pc, x) if x is not None and pc is not None else None

    t, y = 0.0, np.zeros(4)
    contact = bool(has_contact and gap(t, y) < 0.0)
    hold_until = -1.0
    j = 0
    segments = switches = 0
    while t < t_end and j < n_out:
        holding = hold_until > t
        t_stop = min(hold_until, t_end) if holding else t_end
        if x is not None:
            # short segments, so the step cap below follows the local interface stiffness as the
            # project's per-step cap does
            t_stop = min(t_stop, t + SEGMENT)
        jj = j
        while jj < n_out and t_out[jj] <= t_stop:
            jj += 1
        events = None
        if has_contact and not holding:
            def ev(tt, yy, _mode):  # solve_ivp passes the rhs's args to events too
                return gap(tt, yy)
            ev.terminal = True
            ev.direction = 1.0 if contact else -1.0  # leaving contact: g rises through 0; entering: falls
            events = ev
        # the output samples of this segment, plus its end (for the state to continue from)
        t_eval = t_out[j:jj]
        if not (t_eval.size and t_eval[-1] == t_stop):
            t_eval = np.append(t_eval, t_stop)
        if x is not None:
            # a competent user resolves the interface spring: max_step <= stiffness_step / omega at
            # the segment's start (the project caps every step the same way)
            d_here = gap(t, y) + ksig
            kk = abs(An * np.interp(d_here, x, dpa)) if pa is not None else 0.0
            if pc is not None and contact:
                kk = abs(kk - An * np.interp(d_here, x, dpc))
            if kk > 0:
                opts["max_step"] = min(model.max_step, model.p.h_stiff / np.sqrt(kk * m_eff_inv))
            else:
                opts["max_step"] = model.max_step
        sol = solve_ivp(rhs, (t, t_stop), y, t_eval=t_eval, events=events, args=(contact,), **opts)
        segments += 1
        if sol.status < 0:
            raise running.IntegrationError(f"naive solve_ivp failed at t = {t:.6g} s: {sol.message}")
        got = min(np.size(sol.t), jj - j)  # (sol.t is an empty list when no t_eval point was reached)
        if got:
            Y[j:j + got] = np.asarray(sol.y)[:, :got].T
        C[j:j + got] = contact
        j += got
        if sol.status == 0 and t_stop < t_end and not holding and abs(float(sol.t[-1]) - t_stop) < 1e-18:
            t, y = float(t_stop), sol.y[:, -1].copy()
            continue
        if sol.status == 1:  # contact event: switch and hold the new mode
            t, y = float(sol.t_events[0][0]), sol.y_events[0][0].copy()
            contact = not contact
            switches += 1
            hold_until = t + dwell if dwell > 0 else -1.0
        else:
            t, y = float(t_stop), sol.y[:, -1].copy()
            if holding:
                hold_until = -1.0
                if (gap(t, y) < 0.0) != contact:  # the dwell has ended: switch now if the criterion disagrees
                    contact = not contact
                    switches += 1
                    hold_until = t + dwell
    out = summarize_samples(ph, t_out, Y, C)
    out.update(rhs_evaluations=counter[0], segments=segments, contact_switches=switches)
    if return_history:
        out.update(time=t_out[::REFINE], state=Y[::REFINE], contact=C[::REFINE])
    return out


def _summarize(scene, model, t_fine, Y_fine, C_fine, refine, disk, off_c, x, pa, pc, ar, ft, An, ksig, cc, FH0,
               p_sep, delta, s_n, has_contact) -> dict[str, float]:
    """The steady-window scalars of :func:`pipeline.model.outcomes.summarize`, from the naive run.

    Means over the output grid (every ``refine``-th sample); the peak-to-peak and the minimum of ``d``
    over all samples of the window (``refine`` per output step).
    """
    def sep(tt, YY):
        w, v = disk.many(tt + off_c) if hasattr(disk, "many") else (np.zeros_like(tt), np.zeros_like(tt))
        return separation_at(p_sep, YY[:, Z], YY[:, THETA], w), v

    d_fine = sep(t_fine, Y_fine)[0][t_fine >= model.transient - 1e-15]
    t, Y, C = t_fine[::refine], Y_fine[::refine], C_fine[::refine]
    d, vc = sep(t, Y)
    c = d - ksig
    win = t >= model.transient - 1e-15
    dw, cw = d[win], c[win]
    spread = np.ptp(d_fine) if model.fhm_measure == "peak-to-peak" else 3.0 * np.std(dw)
    out: dict[str, float] = {
        "fhm_bv": float(100.0 * spread / FH0),
        "clearance": float(np.mean(cw)),
        "min_clearance": float(np.min(d_fine) - ksig),
        "nominal_area": An,
        "protrusion_radius": float(effective_radius(delta, model.half_length, s_n)) if np.isfinite(s_n) else np.nan,
    }
    net = np.zeros_like(t)
    if pa is not None:
        adh = An * np.interp(d, x, pa)
        out["adhesion_force"] = float(np.mean(adh[win]))
        net -= adh
    if has_contact:
        inc = C[win]
        fc = np.where(C, An * np.maximum(np.interp(d, x, pc), 0.0), 0.0)
        area = np.where(C, An * np.maximum(np.interp(d, x, ar), 0.0), 0.0)
        ddot = Y[:, Z_RATE] - model.slider.l_c * Y[:, THETA_RATE] - vc
        net += fc + np.where(C, -cc * ddot, 0.0)
        frac = float(np.mean(inc))
        out["contact_fraction"] = frac
        out["regime"] = outcomes.FLYING if frac == 0 else (outcomes.SURFING if frac >= outcomes.SURFING_FRACTION else outcomes.BOUNCING)
        fcw, aw = fc[win], area[win]
        out["contact_force"] = float(np.mean(fcw))
        out["interference"] = float(np.mean(-cw[inc])) if inc.any() else np.nan
        out["real_area"] = float(np.mean(aw[inc])) if inc.any() else np.nan
        out["mean_pressure"] = float(fcw.sum() / aw.sum()) if aw.sum() > 0 else np.nan
        if ft is not None:
            ff = np.where(C, An * np.maximum(np.interp(d, x, ft), 0.0), 0.0)[win]
            out["friction_force"] = float(np.mean(ff))
            out["friction_coefficient"] = float(ff.sum() / fcw.sum()) if fcw.sum() > 0 else np.nan
            out["shear_stress"] = float(ff.sum() / aw.sum()) if aw.sum() > 0 else np.nan
    if pa is not None or has_contact:
        out["net_force"] = float(np.mean(net[win]))
    return out


def time_naive(scene, interface_ds, dmw_tuple, k, protrusion_nm, repeat: int = 3, **kw) -> tuple[list[float], dict]:
    """Wall times [s] of ``repeat`` naive runs and the last result."""
    times, res = [], {}
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = simulate_naive(scene, interface_ds, dmw_tuple, k, protrusion_nm, **kw)
        times.append(time.perf_counter() - t0)
    return times, res
