"""The statics map of a model: every static state of the slider versus protrusion, its stability, the
energy barrier out of it, and the DMW's energy scale beside them (docs/model.md, section "Statics map").

The static forces are those of the start state (:func:`pipeline.model.start.static_forces`: the kernel's
right-hand side at zero velocity on the mean disk, the contact law on where ``d < k sigma``). At each
protrusion the TFC point is held at a clearance ``c = d - k sigma`` by a vertical force there, the pitch
relaxed (:func:`pipeline.physics.statics_map.relaxed_path`, path coordinate ``u = z - l_c theta``); the
zeros of that holding force along a clearance grid are the equilibria, the integral of the force the
potential, its rises the barriers (:func:`pipeline.physics.statics_map.path_equilibria`). The contact
criterion is the path's one break: there the force jumps by the contact law's value at ``k sigma``.
Each smooth state's stiffness ``K = -dR/dy`` (both freedoms, central differences as the start state's)
gives its stability and its eigenvalues.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import xarray as xr

from ..physics.equilibrium import is_stable, jacobian
from ..physics.statics_map import path_equilibria, relaxed_path
from ..units import NM, URAD
from ..variables import STATICS
from . import dynamics as dyn
from . import assembly, kernel_inputs
from .compiled import kernel_jit
from .start import SCALE, static_forces, static_inputs
from .state import N_STATE
from .static_solver import static_residual

_jit = kernel_jit(__name__)

#: Clearance grid [m]: fine (:data:`FINE_STEP`) from :data:`DEPTH` below the criterion to :data:`FINE_TOP`
#: above it, where contact and adhesion act and the states lie close together; coarse
#: (:data:`COARSE_STEP`) above, where only the air bearing and the bulge lift act and a flying state is
#: alone. Two states closer than a step are not resolved (they cancel in the sign test).
FINE_STEP = 0.01 * NM
COARSE_STEP = 0.1 * NM
DEPTH = 2.0 * NM
FINE_TOP = 3.0 * NM
#: The path is extended (by :data:`DEPTH` per try, at most :data:`EXTEND` times) until its force points
#: inwards at both ends: up at the bottom (the contact law), down at the top (the air bearing).
EXTEND = 8

#: Tolerance of the relaxed pitch, relative to 1 urad: its error moves the path force by about
#: ``K_z,theta`` (~100 N/rad) times 1e-14 rad, 1e-12 N, far below the 1e-6-nm resolution of the states
#: (times a stiffness of ~1e6 N/m: 1e-9 N).
TOL = 1e-8

#: State types (the ``state_type`` flag): above the criterion, below it, on it (a switch state).
FLYING, CONTACT, CRITERION = 0, 1, 2


@_jit
def _path(us, a0, a1, s_start, slope_start, s_scale, tol, max_iter, params, dmw, contact, adhesion, friction, tfc,
          pitch, rear_law, gap_power_, meniscus):
    """:func:`pipeline.physics.statics_map.relaxed_path` on the kernel's static forces, compiled (the same secant
    iteration, started from a secant predictor of the two points before): returns ``(f [N], s, slope)``."""
    p = params[0]
    gap_power = dyn._unpacked(gap_power_)
    n = us.size
    f = np.empty(n)
    s_out = np.empty(n)
    R = np.empty(2)
    y4 = np.zeros(N_STATE)
    out = np.empty(N_STATE)
    t0 = -a1 / a0
    tol_s = tol * s_scale
    s = s_start
    slope = slope_start
    for i in range(n):
        u = us[i]
        if i >= 2 and us[i - 1] != us[i - 2]:
            s = s_out[i - 1] + (s_out[i - 1] - s_out[i - 2]) * (u - us[i - 1]) / (us[i - 1] - us[i - 2])
        static_residual(u / a0 + s * t0, s, p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
                meniscus)
        g = R[0] * t0 + R[1]
        if not (slope != 0.0 and np.isfinite(slope)):
            h = 1e-3 * s_scale
            static_residual(u / a0 + (s + h) * t0, s + h, p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch,
                    rear_law, gap_power, meniscus)
            slope = (R[0] * t0 + R[1] - g) / h
            static_residual(u / a0 + s * t0, s, p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law,
                    gap_power, meniscus)
        for _ in range(max_iter):
            if not (np.isfinite(g) and np.isfinite(slope) and slope != 0.0):
                break
            ds = -g / slope
            if abs(ds) < tol_s:
                break
            static_residual(u / a0 + (s + ds) * t0, s + ds, p, R, y4, out, dmw, contact, adhesion, friction, tfc, pitch,
                    rear_law, gap_power, meniscus)
            gn = R[0] * t0 + R[1]
            if np.isfinite(gn) and gn != g:
                slope = (gn - g) / ds
            s = s + ds
            g = gn
        f[i] = R[0] / a0
        s_out[i] = s
    return f, s_out, slope


class PathForce:
    """``f(u)``: the static force [N] at the TFC point held at ``u = z - l_c theta`` [m] (pitch relaxed), at one
    protrusion; the relaxed pitch of the last call starts the next (the callers walk along the path)."""

    def __init__(self, R: Callable[[np.ndarray], np.ndarray], a: np.ndarray, compiled: tuple | None = None):
        self.R, self.a = R, a
        self.s, self.slope = 0.0, None
        self.last: list[tuple[float, float]] = []  # the last two (u, s): a secant predictor of s
        #: ``(params, slots)`` of the kernel's static forces: the path solved compiled (:func:`_path`)
        self.compiled = compiled

    def many(self, us: np.ndarray) -> np.ndarray:
        """The path force [N] at the points ``us``, continued along them in order (one compiled call)."""
        us = np.asarray(us, dtype=float)
        if self.compiled is None:
            return np.array([self(u) for u in us])
        params, slots = self.compiled
        f, s, slope = _path(us, float(self.a[0]), float(self.a[1]), self.s, self.slope or 0.0, URAD, TOL, 30,
                            params, *slots)
        if np.isfinite(s[-1]):
            self.s, self.slope = float(s[-1]), float(slope)
            self.last = [(float(u), float(v)) for u, v in zip(us[-2:], s[-2:])][-2:]
        return f

    def restart(self) -> None:
        """Forget the relaxed state (a jump along the path)."""
        self.s, self.last = 0.0, []

    def solve(self, u: float) -> tuple[float, np.ndarray]:
        """The path force [N] and the relaxed state ``(z, theta)`` at ``u``."""
        s0 = self.s
        if len(self.last) == 2 and self.last[1][0] != self.last[0][0]:
            (u1, s1), (u2, s2) = self.last
            s0 = s2 + (s2 - s1) * (u - u2) / (u2 - u1)
        if self.compiled is not None:
            params, slots = self.compiled
            f, s, slope = _path(np.array([float(u)]), float(self.a[0]), float(self.a[1]), s0, self.slope or 0.0,
                                URAD, TOL, 30, params, *slots)
            self.slope = float(slope) if np.isfinite(slope) and slope != 0 else self.slope
        else:
            f, s, _ = relaxed_path(self.R, self.a, [u], s0, s_scale=URAD, slope=self.slope, tol=TOL)
        if np.isfinite(s[0]):
            self.last = (self.last + [(float(u), float(s[0]))])[-2:]
            if self.slope is None:
                h = 1e-3 * URAD
                t = np.array([-self.a[1] / self.a[0], 1.0])
                y = np.array([u / self.a[0], 0.0]) + s[0] * t
                self.slope = float((self.R(y + h * t) - self.R(y - h * t)) @ t / (2 * h))
            self.s = float(s[0])
        t = np.array([-self.a[1] / self.a[0], 1.0])
        return float(f[0]), np.array([u / self.a[0], 0.0]) + self.s * t

    def __call__(self, u: float) -> float:
        return self.solve(u)[0]


def tfc_point_scales(model: assembly.Model) -> tuple[float, float]:
    """``(k_b [N/m], m_b [kg])``: the air bearing's linear stiffness and the slider's mass at the TFC point.

    A vertical force at the TFC point (arm ``l_c`` behind the CG) moves it by ``a K^-1 a^T`` per newton,
    ``a = (1, -l_c)``, ``K`` the pads' stiffness matrix (docs/model.md, section "Slider dynamics"); its
    inverse is the point stiffness. Likewise ``1 / m_b = a M^-1 a^T = 1/m + l_c^2 / I``. With the pitch
    locked the slider heaves only: ``k_b = k_f + k_r``, ``m_b = m``.
    """
    s = model.slider
    if model.pitch is None:
        return float(s.stiffness_matrix[0, 0]), float(s.m)
    a = np.array([1.0, -s.l_c])
    k_b = 1.0 / float(a @ np.linalg.solve(s.stiffness_matrix, a))
    m_b = 1.0 / float(a @ np.linalg.solve(s.mass_matrix, a))
    return k_b, m_b


def dmw_energies(model: assembly.Model, record: tuple[np.ndarray, float] | None) -> tuple[float, float]:
    """The DMW's energy scales [J] (docs/model.md, section "Statics map"):
    ``0.5 k_b sigma_w^2`` (the bearing's energy at the TFC point displaced by one DMW rms ``sigma_w``) and
    ``0.5 m_b sigma_v^2`` (the kinetic energy of the TFC point's mass moving at the DMW's rms rate
    ``sigma_v``), ``k_b, m_b`` of :func:`tfc_point_scales`; NaN without a record.

    ``record``: ``(displacement [nm], sample rate [Hz])`` (:meth:`pipeline.model.inputs.SimulationInputs.record`).
    """
    if record is None:
        return np.nan, np.nan
    w = np.asarray(record[0], dtype=float) * NM
    rate = float(record[1])
    k_b, m_b = tfc_point_scales(model)
    sigma_w = float(np.std(w))
    sigma_v = float(np.std(np.diff(w) * rate))
    return 0.5 * k_b * sigma_w**2, 0.5 * m_b * sigma_v**2


def states_at(model: assembly.Model, protrusion: float, compiled: bool = True) -> list[dict]:
    """Every static state of ``model`` at ``protrusion`` [m], from the highest clearance down (module docstring).

    Each state: ``clearance`` [m], ``z`` [m], ``theta`` [rad], ``type`` (:data:`FLYING`, :data:`CONTACT`,
    :data:`CRITERION`), ``stable``, ``barrier`` [J], ``potential`` [J] (from the deepest state),
    ``path_stiffness`` [N/m] (``-df/du``, NaN on the criterion) and ``eigenvalues`` [N/m] (of ``D K D``,
    ``D = diag(1, 1/l_c)``: the stiffness in the coordinates ``(z, l_c theta)``, real parts, ascending; the
    second NaN with the pitch locked, both NaN on the criterion). ``compiled``: the path solved compiled on the
    kernel's forces (:func:`_path`, the default), else by :func:`pipeline.physics.statics_map.relaxed_path`
    from Python (the reference).
    """
    R2, _, _ = static_forces(lambda mu: kernel_inputs.run_parameters(model, mu))
    pitch = model.pitch is not None
    l_c = model.slider.l_c
    a = np.array([1.0, -l_c]) if pitch else np.array([1.0, 0.0])

    def R(y: np.ndarray) -> np.ndarray:
        return R2(y, protrusion)

    p = model.p
    k_sigma = model.k_sigma
    u_of_c = float(k_sigma + p["y_s"] + protrusion - p["FH0"])  # u = c + u_of_c (d = FH0 - delta + u - y_s)
    p_, _, _, slots = static_inputs(lambda mu: kernel_inputs.run_parameters(model, mu), protrusion)
    f = PathForce(R, a, (dyn._packed(p_), slots) if compiled else None)
    lo = -DEPTH
    hi = max(FINE_TOP, -u_of_c + FINE_TOP)  # (u = 0: the nominal attitude's clearance)
    for _ in range(EXTEND):  # the bottom: the contact law pushes up there
        if f(lo + u_of_c) > 0:
            break
        lo -= DEPTH
    f.restart()
    for _ in range(EXTEND):  # the top: the bearing pushes down there
        if f(hi + u_of_c) < 0:
            break
        hi += DEPTH
    f.restart()
    top = min(FINE_TOP, hi)
    grid_c = np.concatenate([lo + FINE_STEP * np.arange(int(np.ceil((top - lo) / FINE_STEP - 1e-6))),
                             top + COARSE_STEP * np.arange(int(np.ceil((hi - top) / COARSE_STEP)) + 1)])
    breaks = [u_of_c] if model.contact is not None else []  # the contact law switches on there
    found = path_equilibria(f, grid_c + u_of_c, breaks, xtol=1e-6 * NM, f_many=f.many)
    D = np.diag([1.0, 1.0 / l_c])
    states = []
    for st in reversed(found):
        _, y = f.solve(st.u)
        c = st.u - u_of_c
        if st.switch:
            kind, stable, eig, k_path = CRITERION, st.stable, np.array([np.nan, np.nan]), np.nan
        else:
            K = -jacobian(R, y, SCALE)
            if pitch:
                stable = is_stable(K)
                eig = np.sort(np.real(np.linalg.eigvals(D @ K @ D)))
            else:
                stable, eig = bool(K[0, 0] > 0), np.array([K[0, 0], np.nan])
            h = 1e-4 * NM
            k_path = -(f(st.u + h) - f(st.u - h)) / (2 * h)
            kind = FLYING if c > 0 or model.contact is None else CONTACT  # (no contact law: no criterion)
        states.append({"clearance": c, "z": y[0], "theta": y[1], "type": kind, "stable": bool(stable),
                       "barrier": st.barrier, "potential": st.potential, "path_stiffness": k_path,
                       "eigenvalues": eig})
    return states


def statics_map(model: assembly.Model, protrusions, record: tuple[np.ndarray, float] | None = None) -> xr.Dataset:
    """The ``statics.nc`` dataset: :func:`states_at` at each protrusion [nm] on dims ``(protrusion, state)`` (states
    padded with NaN / the flags' fill to the largest count), the DMW energy scales (:func:`dmw_energies`) and
    the TFC-point scales (:func:`tfc_point_scales`); variables :data:`pipeline.variables.STATICS`."""
    labels = np.asarray(protrusions, dtype=float)  # [nm]: the coordinate as given (the sweep's labels)
    mus = labels * NM
    found = [states_at(model, mu) for mu in mus]
    n = max(1, max(len(s) for s in found))
    shape = (mus.size, n)

    def table(key: str, fill: float = np.nan) -> np.ndarray:
        out = np.full(shape, fill)
        for i, states in enumerate(found):
            for j, st in enumerate(states):
                out[i, j] = st[key]
        return out

    eig = np.full((*shape, 2), np.nan)
    for i, states in enumerate(found):
        for j, st in enumerate(states):
            eig[i, j] = st["eigenvalues"]
    k_b, m_b = tfc_point_scales(model)
    e_w, e_v = dmw_energies(model, record)
    ps = ("protrusion", "state")
    V = STATICS
    ds = xr.Dataset(
        {"clearance": V["clearance"].from_si(table("clearance"), ps),
         "z": V["z"].from_si(table("z"), ps),
         "pitch": V["pitch"].from_si(table("theta"), ps),
         "state_type": V["state_type"].from_si(table("type"), ps),
         "stable": V["stable"].from_si(table("stable"), ps),
         "barrier": V["barrier"].from_si(table("barrier"), ps),
         "potential": V["potential"].from_si(table("potential"), ps),
         "path_stiffness": V["path_stiffness"].from_si(table("path_stiffness"), ps),
         "stiffness_eigenvalue": V["stiffness_eigenvalue"].from_si(eig, (*ps, "mode")),
         "state_count": V["state_count"].from_si([len(s) for s in found], ("protrusion",)),
         "stable_count": V["stable_count"].from_si([sum(st["stable"] for st in s) for s in found], ("protrusion",)),
         "dmw_energy": V["dmw_energy"].from_si(e_w, ()),
         "dmw_kinetic_energy": V["dmw_kinetic_energy"].from_si(e_v, ()),
         "bearing_stiffness_tfc": V["bearing_stiffness_tfc"].from_si(k_b, ()),
         "effective_mass_tfc": V["effective_mass_tfc"].from_si(m_b, ())},
        coords={"protrusion": V["protrusion"].data(labels, ("protrusion",)),
                "state": V["state"].data(np.arange(n), ("state",)),
                "mode": V["mode"].data(np.arange(2), ("mode",))})
    ds.attrs.update({
        "method": "static force at the TFC point held at a clearance, pitch relaxed (z - l_c theta fixed); "
                  "equilibria where it vanishes, barriers from its integral (docs/model.md, section 'Statics map')",
        "clearance_grid_nm": f"step {FINE_STEP / NM:g} from the deepest point to {FINE_TOP / NM:g} above the "
                             f"criterion, {COARSE_STEP / NM:g} above",
        "contact_criterion": "contact law on where d < k sigma (the kernel's static forces, DMW w = 0, meniscus at rest)",
    })
    return ds
