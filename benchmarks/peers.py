"""The bench's peers: the naive baseline's model (:mod:`benchmarks.naive`) as a numba ``cfunc`` right-hand side
for a library integrator, numbalsoda's DOP853 and LSODA (what a competent user would write instead of the
project's kernel).

The same physics as :func:`benchmarks.naive.right_hand_side` (docs/model.md, section "Slider dynamics"): the
same constants (:func:`benchmarks.naive.physics`), the same interface tables interpolated linearly on their
uniform separation grid (``np.interp``'s values: the end values outside it), the same not-a-knot cubic spline
of the DMW record, the contact force and friction while ``d < k sigma``. numbalsoda locates no events, so the
contact mode is the criterion at each evaluation (neither bench scene switches mode: the kernel's ``switches``
are recorded beside). The constants and tables travel in one float64 array (:func:`pack`, numbalsoda's
``data`` pointer); its slot :data:`COUNT` counts the evaluations.

Tolerances: the scene's ``rtol`` and per-component ``atol`` (:func:`pipeline.model.assembly.tolerances`).
numbalsoda takes one scalar ``atol``, so the integrators step the scaled state ``u = y / atol`` with
``atol = 1``: the same weighted error ``|e_i| / (atol_i + rtol |y_i|)`` per component. The start is the
project's (:func:`pipeline.model.running.start`: the static equilibrium), the samples those of
:func:`benchmarks.naive.fine_grid` with :data:`REFINE` per output step: the kernel's output grid (the kernel
tracks the exact extremes of ``d``; the peers' peak-to-peak of the samples agrees within the limits below,
docs/performance.md, section "The peers: the kernel against numbalsoda").

A peer's run agrees with the kernel's when its FHM/BV is within :data:`FHM_TOL` and its mean clearance within
:data:`CLEARANCE_TOL` of the kernel's (:func:`agreement`); one that does not is void (reported, not timed).
"""

from __future__ import annotations

import functools
import importlib
import shutil
import statistics
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from numba import carray, cfunc, njit, types

from .naive import Physics, fine_grid, summarize_samples

#: The peers: name -> (numbalsoda's function, the factor on the scene's rtol and atol). LSODA at the scene's
#: tolerances does not agree on the sliding scene (its BV 2.6 % off); a tenth of them is what it needs.
METHODS = {"DOP853": ("dop853", 1.0), "LSODA": ("lsoda", 1.0), "LSODA at tolerances / 10": ("lsoda", 0.1)}
#: Samples per output step of a peer's run: the kernel's output grid. It agrees within the limits below on both
#: scenes (FHM/BV 0.6 % / 0.13 % off for DOP853, measured); the naive baseline's 10 per step came within 0.06 %
#: but cost DOP853 +4.7 ms of dense output per 2-ms flying scene (3.6 -> 8.3 ms).
REFINE = 1
#: Agreement with the kernel: FHM/BV within 1 %, mean clearance within 0.1 % (relative).
FHM_TOL = 0.01
CLEARANCE_TOL = 0.001
#: The most steps numbalsoda may take (DOP853: in all; LSODA: between two samples).
MXSTEP = 10_000_000

#: numbalsoda's right-hand side: ``void f(double t, double *u, double *du, double *data)``.
RHS_SIGNATURE = types.void(types.double, types.CPointer(types.double), types.CPointer(types.double),
                           types.CPointer(types.double))

# the slots of the packed data (:func:`pack`): sizes and flags, the constants, the state's scale, then the
# tables (adhesion, contact, friction pressure on the separation grid) and the DMW spline's coefficients
(LENGTH, COUNT, N_TAB, N_DMW, X0, DX, X_LAST, USE_TABLES, HAS_PA, HAS_PC, HAS_FT, PITCH, HAS_DMW, DMW_DT,
 M, INERTIA, LF, LR, LC, HCG, KF, CF, CR, G0, N_EXP, FR0, D_NOM, CC, AN, KSIG, OFF_F, OFF_R, OFF_C,
 S0, S1, S2, S3) = range(37)
HEADER = 37


def pack(ph: Physics, scale: np.ndarray) -> np.ndarray:
    """The constants and tables of ``ph`` in one float64 array (the slots above), for the state scaled by
    ``scale`` (``u = y / scale``, ``scale`` in the state's units: m, rad, m/s, rad/s)."""
    if np.size(scale) != 4:
        raise ValueError(f"the peers integrate the four-component state; scale has {np.size(scale)} components")
    disk = ph.disk
    has_dmw = hasattr(disk, "how")
    if has_dmw and disk.how != "cubic":
        raise ValueError(f"the peers interpolate the DMW record by its cubic spline; got {disk.how!r}")
    n_tab, x0, dx, x_last = 0, 0.0, 1.0, 0.0
    tabs = []
    if ph.use_tables:
        x = np.asarray(ph.x, float)
        steps = np.diff(x)
        if not np.allclose(steps, steps[0], rtol=1e-9, atol=0.0):
            raise ValueError("the peers interpolate the interface tables on a uniform separation grid; "
                             f"its steps span {steps.min():.6g}-{steps.max():.6g} m")
        n_tab, x0, dx, x_last = x.size, float(x[0]), float(steps.mean()), float(x[-1])
        tabs = [np.zeros(n_tab) if t is None else np.asarray(t, float) for t in (ph.pa, ph.pc, ph.ft)]
    coef = [np.asarray(c, float) for c in (disk.c0, disk.c1, disk.c2, disk.c3)] if has_dmw else []
    n_dmw = coef[0].size if has_dmw else 0
    head = np.zeros(HEADER)
    head[[N_TAB, N_DMW, X0, DX, X_LAST, USE_TABLES, HAS_PA, HAS_PC, HAS_FT, PITCH, HAS_DMW]] = (
        n_tab, n_dmw, x0, dx, x_last, ph.use_tables, ph.pa is not None, ph.pc is not None and ph.has_contact,
        ph.ft is not None, ph.pitch, has_dmw)
    head[DMW_DT] = disk.dt if has_dmw else 1.0
    head[M:OFF_C + 1] = (ph.m, ph.I, ph.lf, ph.lr, ph.lc, ph.hcg, ph.kf, ph.cf, ph.cr, ph.g0, ph.n, ph.Fr0, ph.d_nom,
                         ph.cc, ph.An, ph.ksig, ph.off_f, ph.off_r, ph.off_c)
    head[S0:S3 + 1] = scale
    data = np.concatenate([head, *tabs, *coef])
    data[LENGTH] = data.size
    return data


@njit(inline="always")
def _table(data, k, d):
    """Table ``k`` (0 adhesion, 1 contact, 2 friction [Pa]) at separation ``d`` [m]: ``np.interp`` on the
    uniform grid (the end values outside it)."""
    n = int(data[N_TAB])
    base = HEADER + k * n
    if d <= data[X0]:
        return data[base]
    if d >= data[X_LAST]:
        return data[base + n - 1]
    f = (d - data[X0]) / data[DX]
    i = int(f)
    if i > n - 2:
        i = n - 2
    s = f - i
    return data[base + i] + s * (data[base + i + 1] - data[base + i])


@njit(inline="always")
def _disk(data, t):
    """The DMW displacement [m] and velocity [m/s] at ``t`` [s]: the record's not-a-knot cubic spline."""
    if data[HAS_DMW] == 0.0:
        return 0.0, 0.0
    n = int(data[N_DMW])
    base = HEADER + 3 * int(data[N_TAB])
    dt = data[DMW_DT]
    i = int(t / dt)
    if i < 0:
        i = 0
    elif i > n - 1:
        i = n - 1
    s = t - i * dt
    c0, c1, c2, c3 = data[base + i], data[base + n + i], data[base + 2 * n + i], data[base + 3 * n + i]
    return ((c0 * s + c1) * s + c2) * s + c3, (3.0 * c0 * s + 2.0 * c1) * s + c2


@njit
def rhs_core(t, u, du, data):
    """The scaled right-hand side: ``du = y'(t, y) / scale`` at ``y = u scale`` (the naive baseline's physics,
    module docstring); one more evaluation in ``data[COUNT]``."""
    data[COUNT] += 1.0
    z, th = u[0] * data[S0], u[1] * data[S1]
    vz, vth = u[2] * data[S2], u[3] * data[S3]
    lf, lr, lc = data[LF], data[LR], data[LC]
    wf, vf = _disk(data, t + data[OFF_F])
    wr, vr = _disk(data, t + data[OFF_R])
    F_f = -data[KF] * (z + lf * th - wf) - data[CF] * (vz + lf * vth - vf)
    g0 = data[G0]
    g_r = g0 + z - lr * th - wr
    if g_r < 1e-3 * g0:
        g_r = 1e-3 * g0
    F_r = data[FR0] * ((g0 / g_r) ** data[N_EXP] - 1.0) - data[CR] * (vz - lr * vth - vr)
    F_i = 0.0
    Q = 0.0
    if data[USE_TABLES] != 0.0:
        wc, vc = _disk(data, t + data[OFF_C])
        d = data[D_NOM] + z - lc * th - wc
        An = data[AN]
        if data[HAS_PA] != 0.0:
            F_i -= An * _table(data, 0, d)
        if data[HAS_PC] != 0.0 and d - data[KSIG] < 0.0:
            F_i += An * max(_table(data, 1, d), 0.0) - data[CC] * (vz - lc * vth - vc)
            if data[HAS_FT] != 0.0:
                Q = An * max(_table(data, 2, d), 0.0)
    du[0] = vz / data[S0]
    du[2] = (F_f + F_r + F_i) / data[M] / data[S2]
    if data[PITCH] != 0.0:
        du[1] = vth / data[S1]
        du[3] = (lf * F_f - lr * F_r - lc * F_i - data[HCG] * Q) / data[INERTIA] / data[S3]
    else:
        du[1] = 0.0
        du[3] = 0.0


@functools.cache
def rhs_address() -> int:
    """The address of :func:`rhs_core` compiled as a C function of :data:`RHS_SIGNATURE` (numbalsoda's
    ``funcptr``; compiled on the first call, cached on disk)."""
    @cfunc(RHS_SIGNATURE, cache=True)
    def rhs(t, u_, du_, data_):
        n = int(carray(data_, (HEADER,))[LENGTH])
        rhs_core(t, carray(u_, (4,)), carray(du_, (4,)), carray(data_, (n,)))
    return rhs.address


def load_peers(import_module: Callable[[str], Any] = importlib.import_module) -> dict[str, Callable | str]:
    """numbalsoda's integrators by peer name (:data:`METHODS`), or for each why it cannot be had (a string):
    numbalsoda builds from source with a Fortran compiler (``make bench-peers-setup``)."""
    try:
        lib = import_module("numbalsoda")
    except (ImportError, OSError) as exc:
        compiler = ("a Fortran compiler (gfortran) is on the PATH" if shutil.which("gfortran") else
                    "no Fortran compiler (gfortran) on the PATH: numbalsoda builds from source with one")
        why = (f"not installed: numbalsoda could not be imported ({type(exc).__name__}: {exc}); {compiler}; "
               "`make bench-peers-setup` installs the compiler where it is missing, then the `bench` extra")
        return {name: why for name in METHODS}
    return {name: getattr(lib, fn) for name, (fn, _) in METHODS.items()}


@dataclass
class Peer:
    """One peer's problem: ``solve(funcptr, u0, t_eval, data, rtol, atol, mxstep) -> (usol, ok)`` (numbalsoda's
    interface) on the scaled state from the project's start ``y0``, sampled at ``t_eval`` [s]."""

    name: str
    solve: Callable
    ph: Physics
    y0: np.ndarray
    refine: int = REFINE
    #: the factor on the scene's rtol and atol
    tighten: float = 1.0

    def __post_init__(self) -> None:
        model = self.ph.model
        self.scale = self.tighten * np.asarray(model.atol[:4], float)
        self.data = pack(self.ph, self.scale)
        self.u0 = np.asarray(self.y0[:4], float) / self.scale
        self.t_eval = fine_grid(model, self.refine)
        self.rtol = self.tighten * float(model.rtol)

    def call(self) -> tuple[np.ndarray, bool]:
        """One integration (what the bench times)."""
        return self.solve(rhs_address(), self.u0, self.t_eval, self.data, self.rtol, 1.0, MXSTEP)

    def run(self) -> dict[str, Any]:
        """One integration and its steady-window scalars (:func:`benchmarks.naive.summarize_samples`, SI units),
        with ``rhs_evaluations`` and ``ok`` (the integrator's success)."""
        self.data[COUNT] = 0.0
        usol, ok = self.call()
        Y = np.asarray(usol) * self.scale
        ph = self.ph
        d = ph.d_nom + Y[:, 0] - ph.lc * Y[:, 1] - (ph.disk.many(self.t_eval + ph.off_c)[0] if hasattr(ph.disk, "many")
                                                    else 0.0)
        C = (d - ph.ksig < 0.0) if ph.has_contact else np.zeros(d.size, bool)
        out: dict[str, Any] = {"ok": bool(ok), "rhs_evaluations": int(self.data[COUNT])}
        if ok and np.all(np.isfinite(Y)):
            out.update(summarize_samples(ph, self.t_eval, Y, C, self.refine))
        return out


def agreement(peer: dict[str, Any], kernel: dict[str, Any], fhm_tol: float = FHM_TOL,
              clearance_tol: float = CLEARANCE_TOL) -> dict[str, Any]:
    """How a peer's run (``fhm_bv`` [%], ``clearance`` [m], ``ok``) compares with the kernel's: the relative
    differences, ``agrees`` and, where it does not, ``why`` (one line with the numbers)."""
    if not peer.get("ok", True) or "fhm_bv" not in peer:
        return {"agrees": False, "why": "the integrator failed (numbalsoda's success flag false or a non-finite "
                                        "state)"}
    fhm = abs(peer["fhm_bv"] / kernel["fhm_bv"] - 1.0)
    clr = abs(peer["clearance"] / kernel["clearance"] - 1.0)
    out: dict[str, Any] = {"fhm_bv_rel_diff": fhm, "clearance_rel_diff": clr,
                           "agrees": bool(fhm <= fhm_tol and clr <= clearance_tol)}
    if not out["agrees"]:
        out["why"] = (f"disagrees with the kernel: FHM/BV {peer['fhm_bv']:.6g} % against {kernel['fhm_bv']:.6g} % "
                      f"({fhm:.3%}, limit {fhm_tol:.1%}), mean clearance {peer['clearance'] / 1e-9:.6g} nm against "
                      f"{kernel['clearance'] / 1e-9:.6g} nm ({clr:.3%}, limit {clearance_tol:.1%})")
    return out


def alternate(contenders: dict[str, Callable[[], Any]], rounds: int,
              clock: Callable[[], float] = time.thread_time) -> dict[str, list[float]]:
    """CPU times per thread [s] of ``rounds`` calls of each contender, alternated: each round calls every
    contender once, the order rotated by one each round (a load that changes during the rounds hurts all)."""
    names = list(contenders)
    times: dict[str, list[float]] = {n: [] for n in names}
    for r in range(rounds):
        for name in names[r % len(names):] + names[:r % len(names)]:
            t0 = clock()
            contenders[name]()
            times[name].append(clock() - t0)
    return times


def speedup_of_kernel(peer_times: list[float], kernel_times: list[float]) -> float:
    """The peer's median time over the kernel's, both measured in the same rounds [1]: above 1, the kernel
    is faster."""
    return statistics.median(peer_times) / statistics.median(kernel_times)
