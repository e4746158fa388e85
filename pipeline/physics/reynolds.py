"""The steady compressible Reynolds equation with molecular slip on the TFC bulge's footprint, solved by finite
volumes and Newton's method (:func:`reynolds_solve`), and its table on protrusion x apex gap
(:func:`reynolds_table`), which the ``bulge`` stage writes and :mod:`pipeline.physics.bulge_bearing` reads back.

Dimensional form (steady; disk moving at U along x; slider at rest; the Couette flow rate U h / 2 is
unchanged by symmetric wall slip)::

    div(p h^3 Q(Kn) / (12 mu) grad p) = (U / 2) d(p h)/dx,     Kn = lambda / h,  lambda = lambda_a p_a / p.

Scaled by x = a X, y = b Y, p = p_pad P, h = h_pad H::

    d/dX(C dP/dX) + (a/b)^2 d/dY(C dP/dY) = Lambda d(P H)/dX,   C = P H^3 Q,
    Lambda = 6 mu U a / (p_pad h_pad^2),   Kn = Kn0 / (P H),   Kn0 = lambda_a p_a / (p_pad h_pad).

The gap profiles, the p h = const limit the solve starts from and compares with, and the references:
:mod:`pipeline.physics.bulge_bearing` (docs/model.md, sections "Bulge air bearing", "Slip-corrected Reynolds
equation" and "Rough-gap bulge bearing").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import gas_flow
from .variants import Registry, Variant
from .bulge_bearing import gap_profile, ph_lift


#: Rarefaction (Poiseuille flow factor ``Q`` of the Reynolds equation) by name: ``P H^3 Q`` as
#: ``P H^3 + c1 Kn0 H^2 + c2 Kn0^2 H / P`` -> ``(c1, c2)``.
#:
#: * ``"first-order"`` (default): first-order velocity slip, ``Q = 1 + 6 Kn`` (Burgdorfer, J. Basic Eng.
#:   81 (1959) 94), unit accommodation;
#: * ``"second-order"``: ``Q = 1 + 6 Kn + 6 Kn^2`` (Hsia & Domoto, J. Lubr. Technol. 105 (1983) 120);
#: * ``"none"``: continuum, ``Q = 1``.
#:
#: Under the bulge ``p h ~ p_pad h_pad``, so ``Kn = lambda_a p_a / (p h)`` stays near the pad's ``Kn0``:
#: 0.2-2 for ``p_pad`` 3-0.3 MPa and ``h_pad`` ~ 11 nm. There the linearised-Boltzmann Poiseuille flow
#: rate (Fukui & Kaneko, J. Tribol. 110 (1988) 253; not implemented) lies between the first- and
#: second-order forms (as we read their database), so the two bracket it. The first-order form is the
#: default: the simplest, with exact coefficients, and its flux stays affine in ``p`` (a simple Newton
#: Jacobian). Where compression is incomplete it leaks less than the second-order form and lifts more;
#: at the paper's bearing numbers the two lifts differ by at most 0.6 % (measured at delta 9.6-11 nm, g 1-2 nm).
#: * ``"boltzmann"``: the linearised-Boltzmann flow rate of Fukui & Kaneko (J. Tribol. 110 (1988) 253; the
#:   fit of J. Tribol. 112 (1990) 78, :func:`pipeline.physics.gas_flow.poiseuille_factor`), not of the form
#:   above (``None``); the rarefaction of the rough-gap law (docs/model.md, section "Rough-gap bulge bearing").
#:
#: (``air_bearing.bulge_slip``) The behaviour is ``(c1, c2)`` of ``Q = 1 + c1 Kn + c2 Kn^2``, ``None`` for the
#: Boltzmann flow rate.
SLIP_MODELS: Registry[Variant] = Registry("air_bearing.bulge_slip", {
    "first-order": Variant(behaviour=(6.0, 0.0), summary="Q = 1 + 6 Kn: first-order velocity slip",
                           source='docs/model.md, section "Slip-corrected Reynolds equation" (Burgdorfer 1959)'),
    "second-order": Variant(behaviour=(6.0, 6.0), summary="Q = 1 + 6 Kn + 6 Kn^2: second-order slip",
                            source='docs/model.md, section "Slip-corrected Reynolds equation" (Hsia & Domoto 1983)'),
    "none": Variant(behaviour=(0.0, 0.0), summary="Q = 1: continuum flow",
                    source='docs/model.md, section "Slip-corrected Reynolds equation"'),
    "boltzmann": Variant(summary="the linearised-Boltzmann Poiseuille flow rate (the fit of Fukui & Kaneko 1990)",
                         source='docs/model.md, section "Rough-gap bulge bearing" (Fukui & Kaneko 1988, 1990)'),
})


@dataclass(frozen=True)
class ReynoldsGrid:
    """Numerical settings of the finite-volume Reynolds solve (dimensionless).

    Attributes
    ----------
    cells_per_a : cells per footprint semi-axis ``a`` along the sliding direction
    cells_per_b : cells per semi-axis ``b`` across it (half domain: the problem is symmetric in y)
    margin_a, margin_b : width of the pad ring around the footprint in the domain along and across the
        sliding direction, as fractions of ``a`` and ``b`` (the pressure is ``p_pad`` on the outer boundary)
    tol : Newton stops when the largest pressure update is below ``tol`` (in units of ``p_pad``; the
        convergence is quadratic, so the pressure is then exact to ~tol^2)
    max_iter : Newton iterations before giving up
    """

    cells_per_a: int = 32
    cells_per_b: int = 12
    margin_a: float = 1.0
    margin_b: float = 0.25
    tol: float = 1e-7
    max_iter: int = 40


def _bernoulli(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``B(z) = z / (e^z - 1)`` and ``B'(z) = (e^z - 1 - z e^z) / (e^z - 1)^2``, overflow-free (series near 0)."""
    small = np.abs(z) < 1e-5
    zs = np.where(small, 1.0, z)
    e = np.exp(-np.abs(zs))  # e^{-|z|} <= 1
    em1 = -np.expm1(-np.abs(zs))  # 1 - e^{-|z|} > 0
    pos = zs > 0
    # z > 0: multiply by e^{-z} (resp. e^{-2z}); z < 0: e^z = e directly
    B = np.where(pos, zs * e / em1, -zs / em1)
    dB = np.where(pos, e * (em1 - zs) / em1**2, (e * (1.0 - zs) - 1.0) / em1**2)
    B = np.where(small, 1.0 - z / 2.0 + z * z / 12.0, B)
    dB = np.where(small, -0.5 + z / 6.0, dB)
    return B, dB


def _face_flux(PL, PR, H, Lam, Kn0, kappa, dx, slip, Hc=None, phi=None):
    """Scharfetter-Gummel flux ``J = (D/dx) [B(-Pe) P_L - B(Pe) P_R]`` [scaled] across a face and its
    derivatives with respect to ``P_L`` and ``P_R``.

    ``J`` approximates the scaled mass flux ``Lambda H_c P - D dP/dX`` (``Lambda = 0`` across the sliding
    direction), ``D = kappa phi C(P_f, H)`` with ``P_f = (P_L + P_R)/2``; ``Pe = Lambda H_c dx / D``. The
    Couette gap ``H_c`` is ``H`` on a smooth gap and ``(h_T + sigma phi_s) / h_pad`` on a rough one, ``phi``
    the pressure flow factor (1 when ``None``). The exponential fitting is exact for constant coefficients
    in 1-D and stable at any cell Peclet number (Scharfetter & Gummel, IEEE Trans. Electron Devices 16
    (1969) 64; Patankar, Numerical Heat Transfer and Fluid Flow (1980), sec. 5.2).
    """
    Pf = 0.5 * (PL + PR)
    coefficients = SLIP_MODELS.lookup(slip).behaviour
    if coefficients is None:  # Boltzmann: C = P H^3 Q(Kn), Kn = Kn0 / (P H): dC/dP = H^3 (Q - Kn dQ/dKn)
        kn = Kn0 / (Pf * H)
        q, dq = gas_flow.poiseuille_factor(kn)
        D = kappa * Pf * H**3 * q
        dD = kappa * H**3 * (q - kn * dq)
    else:
        c1, c2 = coefficients
        D = kappa * (Pf * H**3 + c1 * Kn0 * H**2 + c2 * Kn0**2 * H / Pf)
        dD = kappa * (H**3 - c2 * Kn0**2 * H / Pf**2)  # dD/dP_f
    if phi is not None:
        D, dD = D * phi, dD * phi
    if np.isscalar(Lam) and Lam == 0.0:  # pure diffusion (across the sliding direction): B = 1
        dJdD = (PL - PR) / dx
        return D / dx * (PL - PR), D / dx + 0.5 * dJdD * dD, -D / dx + 0.5 * dJdD * dD
    Pe = Lam * (H if Hc is None else Hc) * dx / D
    Bm, dBm = _bernoulli(-Pe)
    Bp, dBp = _bernoulli(Pe)
    J = D / dx * (Bm * PL - Bp * PR)
    # dJ/dD at fixed P (dPe/dD = -Pe/D): d/dD [D (Bm PL - Bp PR)] / dx
    dJdD = ((Bm + Pe * dBm) * PL - (Bp - Pe * dBp) * PR) / dx
    return J, D / dx * Bm + 0.5 * dJdD * dD, -D / dx * Bp + 0.5 * dJdD * dD


class _Mesh:
    """Cell-centred grid on ``[-Lx, Lx] x [0, Ly]`` (scaled by ``a``, ``b``), ``Lx = 1 + margin_a``,
    ``Ly = 1 + margin_b``;
    ``P = 1`` on ``X = +-Lx`` and ``Y = Ly``, symmetry at ``Y = 0``."""

    def __init__(self, grid: ReynoldsGrid):
        Lx, Ly = 1.0 + grid.margin_a, 1.0 + grid.margin_b
        self.nx = 2 * int(np.ceil(Lx * grid.cells_per_a))
        self.ny = int(np.ceil(Ly * grid.cells_per_b))
        self.dX, self.dY = 2 * Lx / self.nx, Ly / self.ny
        self.Xc = -Lx + (np.arange(self.nx) + 0.5) * self.dX
        self.Yc = (np.arange(self.ny) + 0.5) * self.dY
        self.Xf = -Lx + np.arange(self.nx + 1) * self.dX
        self.Yf = np.arange(self.ny + 1) * self.dY
        # u = X^2 + Y^2 at the X faces (nx+1, ny), the Y faces (nx, ny+1) and the cell centres (nx, ny)
        self.u_x = self.Xf[:, None] ** 2 + self.Yc[None, :] ** 2
        self.u_y = self.Xc[:, None] ** 2 + self.Yf[None, :] ** 2
        self.u_c = self.Xc[:, None] ** 2 + self.Yc[None, :] ** 2


def _part(couette, phi, where) -> tuple:
    """The Couette gap and pressure flow factor of a rough gap at some faces (``()`` for a smooth gap)."""
    return () if couette is None else (couette[where], phi[where])


def reynolds_solve(g, delta, *, p_pad: float, a: float, b: float, speed: float, viscosity: float,
                   mean_free_path: float, ambient_pressure: float, profile: str = "ellipsoid",
                   slip: str = "first-order", grid: ReynoldsGrid = ReynoldsGrid(),
                   fields: bool = False, roughness: gas_flow.RoughGap | None = None) -> dict:
    """Extra lift [N] of the bulge from the steady compressible Reynolds equation with molecular slip.

    Solves ``div(p h^3 Q/(12 mu) grad p) = (U/2) d(p h)/dx`` (slip model :data:`SLIP_MODELS`) on the
    footprint and a ring of pad around it (:class:`ReynoldsGrid`), gap :func:`gap_profile` inside the
    footprint and ``h_pad = g + delta`` outside, ``p = p_pad`` on the outer boundary, by finite volumes
    (:func:`_face_flux`) and Newton's method with the exact Jacobian (damped to keep ``p > 0``), all cases
    at once (one block-diagonal banded system per iteration). The lift is ``int (p - p_pad) dA`` over
    the domain (midpoint rule).

    Parameters
    ----------
    g, delta : apex gaps and protrusions [m], broadcast together (``delta = 0`` gives zero lift exactly)
    p_pad : pad pressure [Pa]; a, b : footprint semi-axes along / across the sliding direction [m]
    speed : disk speed U [m/s]; viscosity : air viscosity mu [Pa s]
    mean_free_path : mean free path of air at ``ambient_pressure`` [m]; ambient_pressure [Pa]
    profile : ``"ellipsoid"`` or ``"paraboloid"``; slip : a key of :data:`SLIP_MODELS`
    fields : also return the scaled pressure ``P = p/p_pad`` (cases x nx x ny, half domain y >= 0)
    roughness : ``None`` (a smooth gap) or the gap's roughness (:class:`pipeline.physics.gas_flow.RoughGap`):
        Patir-Cheng average flow, ``div(phi_x Q p h^3 grad p) = 6 mu U d(p (h_T + sigma phi_s))/dx`` with
        the nominal gap ``h``, and the lift ``int [(1 - alpha) p - p_pad] dA`` with ``alpha`` the closed
        area fraction (docs/model.md, section "Rough-gap bulge bearing")

    Returns
    -------
    dict
        ``lift`` [N] (shape of the broadcast inputs), ``bearing_number`` and ``knudsen_pad`` [1]
        (``Lambda``, ``Kn0`` of each case), ``iterations`` (Newton), and the mass flows through the upstream,
        downstream and lateral boundaries of the full domain ``inflow``, ``outflow``, ``side_flow`` and
        ``outflow + side_flow - inflow`` as ``net_flow`` (scaled [1]: the flux ``Lambda P H - C grad P``
        integrated over ``Y`` or ``X``; the pad's Couette inflow over the width ``2 (1 + margin_b)`` is
        ``Lambda 2 (1 + margin_b)``; one unit is ``p_pad h_pad^3 p_pad b / (12 mu a)`` in ``p`` times volume
        per time, i.e. a mass flow after division by ``R T``); with ``fields`` also ``P``, ``X``, ``Y``.

    References
    ----------
    [Burgdorfer59] (first-order slip), [HsiaDomoto83] (second-order), [FK88]/[FK90] (the Boltzmann flow rate),
    [PC78]/[PC79] (average flow over a rough gap); docs/model.md, sections "Slip-corrected Reynolds equation" and
    "Rough-gap bulge bearing".
    """
    SLIP_MODELS.lookup(slip)  # (a name it has: one line naming the key)
    gb, db = np.broadcast_arrays(np.asarray(g, dtype=float), np.asarray(delta, dtype=float))
    shape = gb.shape
    gv, dv = gb.ravel(), db.ravel()
    if np.any(gv <= 0) or np.any(dv < 0):
        raise ValueError("reynolds_solve: apex gaps must be > 0 and protrusions >= 0 [m]")
    problem = _Problem(gv, dv, p_pad=p_pad, a=a, b=b, speed=speed, viscosity=viscosity, mean_free_path=mean_free_path,
                       ambient_pressure=ambient_pressure, profile=profile, slip=slip, grid=grid, roughness=roughness)
    P, iterations = _newton(problem, problem.start(roughness), dv > 0, grid)  # (delta = 0: P = 1 solves it exactly)
    out = problem.lift_and_flows(P, iterations, roughness, p_pad, a, b, shape)
    if fields:
        out.update(P=P.reshape(shape + (problem.mesh.nx, problem.mesh.ny)), X=problem.mesh.Xc, Y=problem.mesh.Yc)
    return out


class _Problem:
    """The scaled Reynolds problem of every case at once (:func:`reynolds_solve`) on one :class:`_Mesh`: the gaps
    ``H = h / h_pad`` at the X faces, the Y faces and the cell centres, the bearing and pad Knudsen numbers of each
    case, a rough gap's Couette gaps and pressure flow factors at the faces, and the Jacobian's banded layout."""

    def __init__(self, gv: np.ndarray, dv: np.ndarray, *, p_pad: float, a: float, b: float, speed: float,
                 viscosity: float, mean_free_path: float, ambient_pressure: float, profile: str, slip: str,
                 grid: ReynoldsGrid, roughness: gas_flow.RoughGap | None):
        self.mesh = mesh = _Mesh(grid)
        self.slip = slip
        nx, ny = mesh.nx, mesh.ny
        self.nc = nc = gv.size
        self.hp = hp = gv + dv
        self.Lam = (6.0 * viscosity * speed * a / (p_pad * hp**2))[:, None, None]
        self.Kn0 = (mean_free_path * ambient_pressure / (p_pad * hp))[:, None, None]
        self.kappa = (a / b) ** 2

        def H(u):
            return gap_profile(u[None], gv[:, None, None], dv[:, None, None], profile) / hp[:, None, None]

        self.Hx, self.Hy, self.Hc = H(mesh.u_x), H(mesh.u_y), H(mesh.u_c)
        # rough gap: the Couette gap (h_T + sigma phi_s)/h_pad and phi_x at the faces, the air's share at the centres
        self.Cx = self.Cy = self.phx = self.phy = None
        if roughness is not None:
            hps = hp[:, None, None]
            self.Cx, self.Cy = (roughness.couette_gap(Hf * hps) / hps for Hf in (self.Hx, self.Hy))
            self.phx, self.phy = (roughness.pressure_factor(Hf * hps) for Hf in (self.Hx, self.Hy))
        # sparsity: cell index, and the four neighbour couplings of each interior face
        idx = np.arange(nc * nx * ny).reshape(nc, nx, ny)
        xl, xr = idx[:, :-1, :].ravel(), idx[:, 1:, :].ravel()  # interior X faces
        yl, yr = idx[:, :, :-1].ravel(), idx[:, :, 1:].ravel()  # interior Y faces
        rows = np.concatenate([xl, xl, xr, xr, yl, yl, yr, yr, idx[:, 0, :].ravel(), idx[:, -1, :].ravel(),
                               idx[:, :, -1].ravel()])
        cols = np.concatenate([xl, xr, xl, xr, yl, yr, yl, yr, idx[:, 0, :].ravel(), idx[:, -1, :].ravel(),
                               idx[:, :, -1].ravel()])
        self.N = N = nc * nx * ny
        self.band_index = (ny + rows - cols) * N + cols

    def fluxes(self, P: np.ndarray) -> tuple:
        """Face fluxes (with derivatives) of the X faces (incl. both boundaries) and the Y faces (outer)."""
        nc, nx, ny, dX, dY = self.nc, self.mesh.nx, self.mesh.ny, self.mesh.dX, self.mesh.dY
        Hx, Hy, Lam, Kn0, kappa, slip = self.Hx, self.Hy, self.Lam, self.Kn0, self.kappa, self.slip
        Cx, Cy, phx, phy = self.Cx, self.Cy, self.phx, self.phy
        one = np.ones(1)
        # X faces: boundary P = 1 at half a cell
        Jx = np.empty((nc, nx + 1, ny))
        dLx = np.empty_like(Jx)
        dRx = np.empty_like(Jx)
        Jx[:, 1:-1], dLx[:, 1:-1], dRx[:, 1:-1] = _face_flux(P[:, :-1], P[:, 1:], Hx[:, 1:-1], Lam, Kn0, 1.0, dX, slip,
                                                             *_part(Cx, phx, np.s_[:, 1:-1]))
        Jx[:, :1], dLx[:, :1], dRx[:, :1] = _face_flux(one, P[:, :1], Hx[:, :1], Lam, Kn0, 1.0, dX / 2, slip,
                                                       *_part(Cx, phx, np.s_[:, :1]))
        Jx[:, -1:], dLx[:, -1:], dRx[:, -1:] = _face_flux(P[:, -1:], one, Hx[:, -1:], Lam, Kn0, 1.0, dX / 2, slip,
                                                          *_part(Cx, phx, np.s_[:, -1:]))
        # Y faces: zero flux at Y = 0 (symmetry), P = 1 at Y = Ly
        Jy = np.zeros((nc, nx, ny + 1))
        dLy = np.zeros_like(Jy)
        dRy = np.zeros_like(Jy)
        Jy[:, :, 1:-1], dLy[:, :, 1:-1], dRy[:, :, 1:-1] = _face_flux(P[:, :, :-1], P[:, :, 1:], Hy[:, :, 1:-1], 0.0,
                                                                      Kn0, kappa, dY, slip,
                                                                      *_part(Cy, phy, np.s_[:, :, 1:-1]))
        Jy[:, :, -1:], dLy[:, :, -1:], dRy[:, :, -1:] = _face_flux(P[:, :, -1:], one, Hy[:, :, -1:], 0.0, Kn0, kappa,
                                                                   dY / 2, slip, *_part(Cy, phy, np.s_[:, :, -1:]))
        return Jx, dLx, dRx, Jy, dLy, dRy

    def residual(self, P: np.ndarray) -> tuple:
        """The finite-volume residual of each cell, the Jacobian's entries (in the order of ``band_index``) and
        the face fluxes ``(Jx, Jy)``."""
        dX, dY = self.mesh.dX, self.mesh.dY
        Jx, dLx, dRx, Jy, dLy, dRy = self.fluxes(P)
        R = (Jx[:, 1:] - Jx[:, :-1]) * dY + (Jy[:, :, 1:] - Jy[:, :, :-1]) * dX
        data = np.concatenate([
            (dLx[:, 1:-1] * dY).ravel(), (dRx[:, 1:-1] * dY).ravel(),
            (-dLx[:, 1:-1] * dY).ravel(), (-dRx[:, 1:-1] * dY).ravel(),
            (dLy[:, :, 1:-1] * dX).ravel(), (dRy[:, :, 1:-1] * dX).ravel(),
            (-dLy[:, :, 1:-1] * dX).ravel(), (-dRy[:, :, 1:-1] * dX).ravel(),
            (-dRx[:, 0] * dY).ravel(), (dLx[:, -1] * dY).ravel(), (dLy[:, :, -1] * dX).ravel()])
        return R, data, (Jx, Jy)

    def start(self, roughness: gas_flow.RoughGap | None) -> np.ndarray:
        """Newton's start: the p h = const limit, or on a rough gap its form ``p (h_T + sigma phi_s) = const``."""
        if roughness is None:
            return 1.0 / self.Hc
        hps = self.hp[:, None, None]
        return (roughness.couette_gap(hps) / hps) / (roughness.couette_gap(self.Hc * hps) / hps)

    def lift_and_flows(self, P: np.ndarray, iterations: np.ndarray, roughness: gas_flow.RoughGap | None,
                       p_pad: float, a: float, b: float, shape: tuple) -> dict:
        """The lift [N] of the solved pressure ``P``, the bearing and pad Knudsen numbers, the Newton
        ``iterations`` and the scaled mass flows through the boundaries (:func:`reynolds_solve`'s Returns), each
        of the inputs' ``shape``."""
        dX, dY, hp = self.mesh.dX, self.mesh.dY, self.hp
        _, _, (Jx, Jy) = self.residual(P)
        if roughness is None:
            lift = 2.0 * p_pad * a * b * (P - 1.0).sum(axis=(1, 2)) * dX * dY
        else:  # the closed area of the footprint carries no air (its load is the interface's; the pad's is the rear law's)
            air = np.where(self.mesh.u_c[None] < 1.0, roughness.air_fraction(self.Hc * hp[:, None, None]), 1.0)
            lift = 2.0 * p_pad * a * b * (air * P - 1.0).sum(axis=(1, 2)) * dX * dY
        inflow = 2.0 * Jx[:, 0].sum(axis=1) * dY
        outflow = 2.0 * Jx[:, -1].sum(axis=1) * dY
        side = 2.0 * Jy[:, :, -1].sum(axis=1) * dX
        return {"lift": lift.reshape(shape), "bearing_number": self.Lam.ravel().reshape(shape),
                "knudsen_pad": self.Kn0.ravel().reshape(shape), "iterations": iterations.reshape(shape),
                "inflow": inflow.reshape(shape), "outflow": outflow.reshape(shape), "side_flow": side.reshape(shape),
                "net_flow": (outflow + side - inflow).reshape(shape)}


def _newton(problem: _Problem, P: np.ndarray, active: np.ndarray, grid: ReynoldsGrid) -> tuple[np.ndarray, np.ndarray]:
    """Newton's method with the exact Jacobian from ``P`` on the ``active`` cases (the others held), damped per
    case to keep ``P`` above a tenth of its value, until every update is below ``grid.tol``: ``(P, iterations)``."""
    from scipy.linalg import solve_banded

    nc, ny, N = problem.nc, problem.mesh.ny, problem.N
    iterations = np.zeros(nc, dtype=int)
    for it in range(grid.max_iter):
        R, data, _ = problem.residual(P)
        if not active.any():
            break
        # banded storage (index = (case nx + i) ny + j: bandwidth ny), LAPACK gbsv
        ab = np.bincount(problem.band_index, weights=data, minlength=(2 * ny + 1) * N).reshape(2 * ny + 1, N)
        dP = solve_banded((ny, ny), ab, -R.ravel(), overwrite_ab=True, check_finite=False).reshape(P.shape)
        dP[~active] = 0.0
        # damping per case: keep P above a tenth of its value
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            lim = np.where(dP < 0, -0.9 * P / dP, np.inf).reshape(nc, -1).min(axis=1)
        alpha = np.minimum(1.0, lim)[:, None, None]
        P = P + alpha * dP
        step = np.abs(dP).reshape(nc, -1).max(axis=1)
        iterations[active] += 1
        active &= step > grid.tol
    else:
        R, data, _ = problem.residual(P)
        if active.any():
            raise RuntimeError(f"reynolds_solve: Newton did not converge in {grid.max_iter} iterations for "
                               f"{int(active.sum())} of {nc} cases (largest update {step[active].max():.3g})")
    return P, iterations


def reynolds_table(gaps, protrusions, *, p_pad: float, a: float, b: float, speed: float, viscosity: float,
                   mean_free_path: float, ambient_pressure: float, profile: str = "ellipsoid",
                   slip: str = "first-order", grid: ReynoldsGrid = ReynoldsGrid(),
                   roughness: gas_flow.RoughGap | None = None) -> dict[str, np.ndarray]:
    """Lift [N] and stiffness [N/m] of the Reynolds bulge bearing tabulated on protrusion x apex gap.

    One :func:`reynolds_solve` per protrusion, all gaps at once. The stiffness ``k = -dF/dg`` comes from
    the ratio ``r = F / F_ph`` to the closed form (:func:`ph_lift`), which is smooth in ``ln g`` where
    ``F`` itself carries the logarithm: ``k = r k_ph - F_ph (dr/d ln g) / g``, with ``dr/d ln g`` from a
    cubic spline through the gaps (so the table needs a few gaps per factor of 2 for an accurate stiffness).

    Parameters
    ----------
    gaps : apex gaps [m], increasing, > 0 (``n_gap``); protrusions : [m], >= 0 (``n_delta``)
    the rest : as :func:`reynolds_solve`

    Returns
    -------
    dict
        ``lift``, ``stiffness``, ``lift_ph``, ``stiffness_ph`` (``n_delta x n_gap``) [N], [N/m],
        ``ratio`` = ``lift / lift_ph`` [1] (NaN at ``delta = 0``), ``bearing_number`` [1] and ``iterations``
        (``n_delta x n_gap``).

    References
    ----------
    [Burgdorfer59] (first-order slip), [HsiaDomoto83] (second-order), [FK88]/[FK90] (the Boltzmann flow rate),
    [PC78]/[PC79] (average flow over a rough gap); docs/model.md, sections "Slip-corrected Reynolds equation" and
    "Rough-gap bulge bearing".
    """
    from scipy.interpolate import CubicSpline

    gaps = np.asarray(gaps, dtype=float)
    protrusions = np.asarray(protrusions, dtype=float)
    if gaps.ndim != 1 or gaps.size < 4 or np.any(np.diff(gaps) <= 0) or gaps[0] <= 0:
        raise ValueError("reynolds_table: gaps must be at least 4 increasing positive values [m]")
    shape = (protrusions.size, gaps.size)
    lift = np.zeros(shape)
    lam = np.zeros(shape)
    its = np.zeros(shape, dtype=int)
    for i, dl in enumerate(protrusions):
        if dl > 0:
            r = reynolds_solve(gaps, dl, p_pad=p_pad, a=a, b=b, speed=speed, viscosity=viscosity,
                               mean_free_path=mean_free_path, ambient_pressure=ambient_pressure, profile=profile,
                               slip=slip, grid=grid, roughness=roughness)
            lift[i], lam[i], its[i] = r["lift"], r["bearing_number"], r["iterations"]
        else:
            lam[i] = 6.0 * viscosity * speed * a / (p_pad * gaps**2)
    F_ph, k_ph = ph_lift(gaps[None, :], protrusions[:, None], p_pad, a, b, profile)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(F_ph > 0, lift / F_ph, np.nan)
    stiffness = np.zeros(shape)
    pos = protrusions > 0
    if pos.any():
        dr = CubicSpline(np.log(gaps), ratio[pos], axis=1)(np.log(gaps), 1)
        stiffness[pos] = ratio[pos] * k_ph[pos] - F_ph[pos] * dr / gaps
    return {"lift": lift, "stiffness": stiffness, "lift_ph": F_ph, "stiffness_ph": k_ph, "ratio": ratio,
            "bearing_number": lam, "iterations": its}
