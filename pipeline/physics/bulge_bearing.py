"""The air bearing of the TFC bulge: extra lift on the slider from the air squeezed under the bulge.

Under the trailing pad of the slider the air is at the pad pressure ``p_pad`` [Pa] in the pad gap
``h_pad`` [m]. The thermal protrusion (TFC bulge, an elliptic footprint with semi-axes ``a`` along the
sliding direction and ``b`` across it, height ``delta`` [m]) narrows the gap to the apex gap ``g`` [m],
so ``h_pad = g + delta`` (the pad moves with the slider). The air under the bulge is compressed and
pushes the slider up at the TFC point with the extra lift ``F_b = int (p - p_pad) dA`` [N]. Two
models (docs/model.md, section "Bulge air bearing"):

* ``"ph-limit"``: the closed form of the high-bearing-number limit (:func:`ph_force_stiffness`);
* ``"reynolds"``: the steady compressible Reynolds equation with molecular slip (first-order by default,
  :data:`SLIP_MODELS`) on the footprint, solved by finite volumes and Newton's method
  (:func:`reynolds_solve`, :func:`reynolds_table`) once per scene by the ``bulge`` stage, and read back by
  the dynamics from that table (:class:`LiftTable`, :func:`table_lift`, :func:`reynolds_force`).

Gap profiles under the footprint, with ``u = (x/a)^2 + (y/b)^2 <= 1`` (``h = h_pad`` outside):

* ellipsoid (the TFC bulge of Vakis, Lee & Polycarpou, IEEE Trans. Magn. 45 (2009) 4966):
  ``h = g + delta (1 - sqrt(1 - u))``;
* paraboloid (its apex approximation): ``h = g + delta u``.

The p h = const limit
---------------------
The steady Reynolds equation scaled by ``p_pad``, ``h_pad``, ``a`` and ``b`` reads
``div(P H^3 Q grad P) = Lambda d(P H)/dX`` with the bearing number ``Lambda = 6 mu U a / (p_pad h_pad^2)``.
As ``Lambda -> inf`` the right-hand side dominates: ``P H`` is constant along the sliding direction,
equal to its value ``1`` at the leading edge of the footprint (the pad), so ``p h = p_pad h_pad`` under
the bulge (the classical high-bearing-number limit of gas bearings, Gross, Gas Film Lubrication, Wiley
1962, ch. 3; molecular slip only changes the Poiseuille term, which drops out in this limit). Outside the
footprint ``h = h_pad`` and the limit gives ``p = p_pad`` again. The extra lift is then

``F_b = int (p - p_pad) dA = p_pad int (h_pad/h - 1) dA = p_pad pi a b [h_pad I - 1]``,

with ``I = <1/h>`` the footprint average of ``1/h``. The area inside the level ``u`` is ``pi a b u``, so
``dA = pi a b du`` and ``I = int_0^1 du / h(u)``:

* paraboloid: ``I = int_0^1 du / (g + delta u) = ln((g + delta)/g) / delta``;
* ellipsoid: with ``s = sqrt(1 - u)`` (``du = -2 s ds``) and ``A = g + delta``,
  ``I = int_0^1 2 s ds / (A - delta s) = (2/delta) int_0^1 [A/(A - delta s) - 1] ds
  = (2/delta) [(A/delta) ln(A/g) - 1]``.

So ``F_b`` is zero at ``delta = 0`` (``h_pad I -> 1``), grows with the protrusion and only
logarithmically as ``g -> 0``: ellipsoid ``F_b ~ p_pad pi a b [2 ln(A/g) - 3]``, paraboloid
``p_pad pi a b [ln(A/g) - 1]``. In terms of ``x = delta/A`` (``A/g = 1/(1 - x)``, ``L = -ln(1 - x)``):
``f = h_pad I - 1 = L/x - 1 = sum_k x^k/(k+1)`` (paraboloid) and
``f = 2 L/x^2 - 2/x - 1 = 2 sum_k x^k/(k+2)`` (ellipsoid), the series used at small ``x`` where the
closed forms cancel. The stiffness is ``k_b = -dF_b/dg = p_pad pi a b f'(x) x / A``
(``dx/dg = -x/A``), positive: the lift grows as the gap closes. Below the floor ``g_min`` (the gap to
the mean surface heights closes only in contact, where the contact force dominates) the force is held
at its value at ``g_min`` and the stiffness is zero.

How far the paper's bulge is from the limit (measured with :func:`reynolds_solve`, first-order slip,
19.5 m/s, air 1.81e-5 Pa s, mean free path 65 nm at 1 atm scaled by ``p_a/p``): the bearing number of
the pad gap is 14-170 for ``p_pad`` 3-0.3 MPa and the Knudsen number of the pad gap 0.2-2, but under
the bulge ``p ~ p_pad h_pad/g`` shortens the mean free path as much as the gap, so the compression is
nearly complete: the Reynolds lift is 1.003-1.027 times the closed form at ``delta`` 9.6-11 nm and
``g`` 1-2 nm (above it: the pressure also spreads ahead of the footprint). The closed form is thus not
an upper bound here; the Reynolds lift falls below it only at bearing numbers a few times lower
(a quarter of the speed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from . import gas_flow
from .air_bearing import NO_TFC_LAW, TfcLaw
from .variants import Registry, Variant

#: Profile codes of the compiled laws (floats, so a kernel can carry them in its parameter vector).
PARABOLOID, ELLIPSOID = 0.0, 1.0
#: Gap profiles under the bulge (``air_bearing.bulge_profile``): the behaviour is the profile's code (the
#: compiled law, :func:`ph_shape`, :func:`gap_profile` and :func:`rough_ph_lift` know these two).
PROFILES: Registry[Variant] = Registry("air_bearing.bulge_profile", {
    "ellipsoid": Variant(behaviour=ELLIPSOID, summary="h = g + delta (1 - sqrt(1 - u)): the TFC bulge's ellipsoid",
                         source='docs/model.md, section "p h = const limit" [paper]'),
    "paraboloid": Variant(behaviour=PARABOLOID, summary="h = g + delta u: the ellipsoid's apex approximation",
                          source='docs/model.md, section "p h = const limit"'),
})

#: Below this ``x = delta/(g + delta)`` the series replaces the closed form (cancellation); 8 terms
#: leave a relative truncation error below ``x^8 < 1e-16``.
_X_SERIES = 0.01
_N_SERIES = 8


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def ph_shape(x: float, profile: float) -> tuple[float, float]:
    """``f(x) = h_pad <1/h> - 1`` [1] and ``f'(x)`` of the p h = const lift, ``x = delta/(g + delta)`` in [0, 1).

    Paraboloid ``f = L/x - 1``, ellipsoid ``f = 2 L/x^2 - 2/x - 1`` with ``L = -ln(1 - x)`` (module
    docstring); their Taylor series below ``x = 0.01``.

    Parameters
    ----------
    x : the protrusion's share ``delta / (g + delta)`` of the pad gap [1], in [0, 1)
    profile : :data:`ELLIPSOID` or :data:`PARABOLOID`

    Returns
    -------
    f, df : tuple of float
        ``f(x)`` [1] and its derivative ``df/dx`` [1].

    References
    ----------
    [Gross62] W. A. Gross, Gas Film Lubrication, Wiley (1962): the high-bearing-number limit ``p h = const``;
    docs/model.md, section "p h = const limit".
    """
    if x < _X_SERIES:
        f = 0.0
        df = 0.0
        xk = 1.0  # x^(k-1)
        for k in range(1, _N_SERIES + 1):
            c = 1.0 / (k + 1.0) if profile == PARABOLOID else 2.0 / (k + 2.0)
            df += k * c * xk
            xk *= x
            f += c * xk
        return f, df
    L = -np.log1p(-x)
    dL = 1.0 / (1.0 - x)
    if profile == PARABOLOID:
        return L / x - 1.0, (dL * x - L) / (x * x)
    return 2.0 * L / (x * x) - 2.0 / x - 1.0, 2.0 * dL / (x * x) - 4.0 * L / (x * x * x) + 2.0 / (x * x)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def ph_force_stiffness(g: float, delta: float, p_pad: float, a: float, b: float, profile: float,
                       g_min: float) -> tuple[float, float]:
    """Extra lift [N] (up) of the bulge's air bearing in the p h = const limit and its stiffness [N/m].

    ``F_b = p_pad pi a b [h_pad <1/h> - 1]`` with ``h_pad = g + delta`` (module docstring), and
    ``k_b = -dF_b/dg`` (positive: the lift grows as the gap closes). Compiled for the kernel.

    Parameters
    ----------
    g : apex gap [m]; delta : protrusion [m] (>= 0)
    p_pad : pad pressure [Pa]; a, b : footprint semi-axes along and across the sliding direction [m]
    profile : :data:`ELLIPSOID` or :data:`PARABOLOID`
    g_min : gap floor [m] (> 0): below it the force is held at ``F_b(g_min)``, the stiffness is 0

    Returns
    -------
    F_b, k_b : tuple of float
        The extra lift ``F_b`` [N] (up positive) and its stiffness ``k_b = -dF_b/dg`` [N m-1].

    References
    ----------
    [Gross62] W. A. Gross, Gas Film Lubrication, Wiley (1962): the high-bearing-number limit ``p h = const``;
    docs/model.md, section "p h = const limit".
    """
    gg = g if g > g_min else g_min
    if delta <= 0.0:
        return 0.0, 0.0
    A = gg + delta
    x = delta / A
    f, df = ph_shape(x, profile)
    P = p_pad * np.pi * a * b
    if g < g_min:
        return P * f, 0.0
    return P * f, P * df * x / A


@njit(cache=True, nogil=True, error_model="numpy")
def _ph_loop(g, delta, p_pad, a, b, profile, g_min, F, k):
    for i in range(g.size):
        F[i], k[i] = ph_force_stiffness(g[i], delta[i], p_pad, a, b, profile, g_min)


def ph_lift(g, delta, p_pad: float, a: float, b: float, profile: str = "ellipsoid",
            g_min: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised :func:`ph_force_stiffness`: lift [N] and stiffness ``-dF/dg`` [N/m] on broadcast ``g, delta`` [m].

    ``profile`` is ``"ellipsoid"`` or ``"paraboloid"``; ``g_min`` [m] the gap floor (0: none, ``g > 0`` then).

    Parameters
    ----------
    g : apex gaps [m]
    delta : protrusions [m], broadcast with ``g``
    p_pad : pad pressure [Pa]
    a, b : the footprint's semi-axes along and across the sliding direction [m]
    profile : a name of :data:`PROFILES`
    g_min : the gap floor [m]

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The lift [N] and the stiffness [N/m], the broadcast shape.

    References
    ----------
    [Gross62] W. A. Gross, Gas Film Lubrication (1962) (the high-bearing-number limit p h = const); docs/model.md,
    section "Bulge air bearing".
    """
    code = PROFILES.lookup(profile).behaviour
    gb, db = np.broadcast_arrays(np.asarray(g, dtype=float), np.asarray(delta, dtype=float))
    F = np.empty(gb.size)
    k = np.empty(gb.size)
    _ph_loop(np.ascontiguousarray(gb).ravel(), np.ascontiguousarray(db).ravel(), float(p_pad), float(a),
             float(b), code, float(g_min), F, k)
    return F.reshape(gb.shape), k.reshape(gb.shape)


def rough_ph_lift(g, delta: float, p_pad: float, a: float, b: float, roughness: gas_flow.RoughGap,
                  profile: str = "ellipsoid", nodes: int = 400) -> np.ndarray:
    """Lift [N] of the bulge over a rough gap in the high-bearing-number limit, at apex gaps ``g`` [m].

    The disk's mass flow ``U/2 p (h_T + sigma phi_s)`` is conserved along the flow (the Poiseuille term drops
    out), so ``p c(h) = p_pad c(h_pad)`` with the Couette gap ``c``
    (:meth:`pipeline.physics.gas_flow.RoughGap.couette_gap`), and ``F = p_pad pi a b int_0^1 [(1 - alpha(h)) c(h_pad) / c(h(u)) - 1] du`` with the closed fraction
    ``alpha`` (docs/model.md, section "Rough-gap bulge bearing"). Gauss-Legendre quadrature in
    ``s = sqrt(1 - u)`` (ellipsoid; ``u`` for the paraboloid) with ``nodes`` points. The limit a rough
    Reynolds solve tends to as the bearing number grows (tests/scenarios/test_model_rough_bulge.py).

    Parameters
    ----------
    g : apex gaps [m]
    delta : protrusion [m]
    p_pad : pad pressure [Pa]
    a, b : the footprint's semi-axes [m]
    roughness : the gap's roughness (rms [m], the disk's share, the wetting gap [m])
    profile : a name of :data:`PROFILES`
    nodes : quadrature nodes [-]

    Returns
    -------
    numpy.ndarray
        The lift [N], the shape of ``g``.

    References
    ----------
    [Gross62] (the limit), [PC78]/[PC79] (the rough gap's flow factors); docs/model.md, section "Rough-gap
    bulge bearing".
    """
    x, w = np.polynomial.legendre.leggauss(nodes)
    t, w = 0.5 * (x + 1.0), 0.5 * w  # on [0, 1]
    g = np.asarray(g, dtype=float)[..., None]
    code = PROFILES.lookup(profile).behaviour
    if code == ELLIPSOID:  # u = 1 - s^2, du = 2 s ds, h = g + delta (1 - s)
        h, wu = g + delta * (1.0 - t), 2.0 * t * w
    elif code == PARABOLOID:
        h, wu = g + delta * t, w
    else:
        raise ValueError(f"air_bearing.bulge_profile = {profile!r}: no rough-gap quadrature for its code {code}")
    ratio = roughness.couette_gap(g + delta) / roughness.couette_gap(h)
    return p_pad * np.pi * a * b * ((roughness.air_fraction(h) * ratio - 1.0) * wu).sum(axis=-1)


def ph_limit_force(g: np.ndarray, delta: float, p_pad: float, a: float, b: float, profile: str) -> np.ndarray:
    """Lift [N] of the bulge's air bearing in the p h = const limit at the TFC gaps ``g`` [m] for the
    protrusion ``delta`` [m] (:func:`ph_lift`): pad pressure ``p_pad`` [Pa], the bulge's semi-axes ``a``,
    ``b`` [m] and its ``profile`` (docs/model.md, section "Bulge air bearing"). Zero at zero protrusion.

    Parameters
    ----------
    g : TFC gaps [m]
    delta : protrusion [m]
    p_pad : pad pressure [Pa]
    a, b : the footprint's semi-axes [m]
    profile : a name of :data:`PROFILES`

    Returns
    -------
    numpy.ndarray
        The lift [N], the shape of ``g``.

    References
    ----------
    [Gross62] W. A. Gross, Gas Film Lubrication (1962) (the high-bearing-number limit p h = const); docs/model.md,
    section "Bulge air bearing".
    """
    return ph_lift(g, delta, p_pad, a, b, profile)[0]


# --------------------------------------------------------------------------------------------------
# The Reynolds equation with molecular slip on the bulge footprint
# --------------------------------------------------------------------------------------------------
#
# Dimensional form (steady; disk moving at U along x; slider at rest; the Couette flow rate U h / 2 is
# unchanged by symmetric wall slip):
#     div(p h^3 Q(Kn) / (12 mu) grad p) = (U / 2) d(p h)/dx,     Kn = lambda / h,  lambda = lambda_a p_a / p.
# Scaled by x = a X, y = b Y, p = p_pad P, h = h_pad H:
#     d/dX(C dP/dX) + (a/b)^2 d/dY(C dP/dY) = Lambda d(P H)/dX,   C = P H^3 Q,
#     Lambda = 6 mu U a / (p_pad h_pad^2),   Kn = Kn0 / (P H),   Kn0 = lambda_a p_a / (p_pad h_pad).

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


def gap_profile(u: np.ndarray, g, delta, profile: str) -> np.ndarray:
    """Gap ``h`` [m] at the level ``u = (x/a)^2 + (y/b)^2`` of the footprint (``h_pad = g + delta`` outside).

    Ellipsoid ``h = g + delta (1 - sqrt(1 - u))``, paraboloid ``h = g + delta u`` (module docstring).

    Parameters
    ----------
    u : footprint levels ``(x/a)^2 + (y/b)^2`` [1]
    g : apex gap [m]
    delta : protrusion [m]
    profile : a name of :data:`PROFILES`

    Returns
    -------
    numpy.ndarray
        The gap h [m], the broadcast shape.

    References
    ----------
    [VLP09] (the ellipsoidal bulge); docs/model.md, section "Bulge air bearing".
    """
    uc = np.minimum(u, 1.0)
    code = PROFILES.lookup(profile).behaviour
    if code == ELLIPSOID:
        s = 1.0 - np.sqrt(1.0 - uc)
    elif code == PARABOLOID:
        s = uc
    else:
        raise ValueError(f"air_bearing.bulge_profile = {profile!r}: no gap shape for its code {code}")
    return g + delta * s


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
    mesh = _Mesh(grid)
    nx, ny, dX, dY = mesh.nx, mesh.ny, mesh.dX, mesh.dY
    nc = gv.size
    hp = gv + dv
    Lam = (6.0 * viscosity * speed * a / (p_pad * hp**2))[:, None, None]
    Kn0 = (mean_free_path * ambient_pressure / (p_pad * hp))[:, None, None]
    kappa = (a / b) ** 2

    def H(u):
        return gap_profile(u[None], gv[:, None, None], dv[:, None, None], profile) / hp[:, None, None]

    Hx, Hy, Hc = H(mesh.u_x), H(mesh.u_y), H(mesh.u_c)
    # rough gap: the Couette gap (h_T + sigma phi_s)/h_pad and phi_x at the faces, the air's share at the centres
    Cx = Cy = phx = phy = None
    if roughness is not None:
        hps = hp[:, None, None]
        Cx, Cy = (roughness.couette_gap(Hf * hps) / hps for Hf in (Hx, Hy))
        phx, phy = (roughness.pressure_factor(Hf * hps) for Hf in (Hx, Hy))
    # sparsity: cell index, and the four neighbour couplings of each interior face
    idx = np.arange(nc * nx * ny).reshape(nc, nx, ny)
    xl, xr = idx[:, :-1, :].ravel(), idx[:, 1:, :].ravel()  # interior X faces
    yl, yr = idx[:, :, :-1].ravel(), idx[:, :, 1:].ravel()  # interior Y faces
    rows = np.concatenate([xl, xl, xr, xr, yl, yl, yr, yr, idx[:, 0, :].ravel(), idx[:, -1, :].ravel(),
                           idx[:, :, -1].ravel()])
    cols = np.concatenate([xl, xr, xl, xr, yl, yr, yl, yr, idx[:, 0, :].ravel(), idx[:, -1, :].ravel(),
                           idx[:, :, -1].ravel()])
    one = np.ones(1)

    def fluxes(P):
        """Face fluxes (with derivatives) of the X faces (incl. both boundaries) and the Y faces (outer)."""
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

    def residual(P):
        Jx, dLx, dRx, Jy, dLy, dRy = fluxes(P)
        R = (Jx[:, 1:] - Jx[:, :-1]) * dY + (Jy[:, :, 1:] - Jy[:, :, :-1]) * dX
        data = np.concatenate([
            (dLx[:, 1:-1] * dY).ravel(), (dRx[:, 1:-1] * dY).ravel(),
            (-dLx[:, 1:-1] * dY).ravel(), (-dRx[:, 1:-1] * dY).ravel(),
            (dLy[:, :, 1:-1] * dX).ravel(), (dRy[:, :, 1:-1] * dX).ravel(),
            (-dLy[:, :, 1:-1] * dX).ravel(), (-dRy[:, :, 1:-1] * dX).ravel(),
            (-dRx[:, 0] * dY).ravel(), (dLx[:, -1] * dY).ravel(), (dLy[:, :, -1] * dX).ravel()])
        return R, data, (Jx, Jy)

    from scipy.linalg import solve_banded

    N = nc * nx * ny
    band_index = (ny + rows - cols) * N + cols

    if roughness is None:
        P = 1.0 / Hc  # the p h = const limit: Newton's start
    else:  # its rough form, p (h_T + sigma phi_s) = const
        hps = hp[:, None, None]
        P = (roughness.couette_gap(hps) / hps) / (roughness.couette_gap(Hc * hps) / hps)
    active = dv > 0  # delta = 0: P = 1 solves the problem exactly
    iterations = np.zeros(nc, dtype=int)
    for it in range(grid.max_iter):
        R, data, _ = residual(P)
        if not active.any():
            break
        # banded storage (index = (case nx + i) ny + j: bandwidth ny), LAPACK gbsv
        ab = np.bincount(band_index, weights=data, minlength=(2 * ny + 1) * N).reshape(2 * ny + 1, N)
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
        R, data, _ = residual(P)
        if active.any():
            raise RuntimeError(f"reynolds_solve: Newton did not converge in {grid.max_iter} iterations for "
                               f"{int(active.sum())} of {nc} cases (largest update {step[active].max():.3g})")
    _, _, (Jx, Jy) = residual(P)
    if roughness is None:
        lift = 2.0 * p_pad * a * b * (P - 1.0).sum(axis=(1, 2)) * dX * dY
    else:  # the closed area of the footprint carries no air (its load is the interface's; the pad's is the rear law's)
        air = np.where(mesh.u_c[None] < 1.0, roughness.air_fraction(Hc * hp[:, None, None]), 1.0)
        lift = 2.0 * p_pad * a * b * (air * P - 1.0).sum(axis=(1, 2)) * dX * dY
    inflow = 2.0 * Jx[:, 0].sum(axis=1) * dY
    outflow = 2.0 * Jx[:, -1].sum(axis=1) * dY
    side = 2.0 * Jy[:, :, -1].sum(axis=1) * dX
    out = {"lift": lift.reshape(shape), "bearing_number": Lam.ravel().reshape(shape),
           "knudsen_pad": Kn0.ravel().reshape(shape), "iterations": iterations.reshape(shape),
           "inflow": inflow.reshape(shape), "outflow": outflow.reshape(shape), "side_flow": side.reshape(shape),
           "net_flow": (outflow + side - inflow).reshape(shape)}
    if fields:
        out.update(P=P.reshape(shape + (nx, ny)), X=mesh.Xc, Y=mesh.Yc)
    return out


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


# --------------------------------------------------------------------------------------------------
# The tabulated Reynolds lift, read back at any gap and protrusion
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class LiftTable:
    """The bulge lift of one scene tabulated on protrusion x apex gap, in SI, as the dynamics reads it.

    The lift is stored as its ratio ``r = F / F_ph`` to the closed form (:func:`ph_lift`): ``F`` carries
    the logarithm of the gap (``F_ph ~ ln(1/g)``) and vanishes at zero protrusion, ``r`` is smooth and
    near 1 in both (:func:`table_lift`).

    Attributes
    ----------
    ln_gaps : ``ln(g / 1 m)`` of the tabulated apex gaps (``n_g``, increasing) [1]
    protrusions : the positive tabulated protrusions [m] (``n_d``, increasing, at least 2)
    ratio : ``r = F / F_ph`` (``n_d x n_g``) [1]; dratio : ``dr/d ln g`` (cubic spline in ``ln g``) [1]
    p_pad : pad pressure [Pa]; a, b : footprint semi-axes [m]; profile : ``"ellipsoid"`` or ``"paraboloid"``
    """

    ln_gaps: np.ndarray = field(repr=False)
    protrusions: np.ndarray = field(repr=False)
    ratio: np.ndarray = field(repr=False)
    dratio: np.ndarray = field(repr=False)
    p_pad: float
    a: float
    b: float
    profile: str


def lift_table(gaps, protrusions, lift, *, p_pad: float, a: float, b: float, profile: str = "ellipsoid") -> LiftTable:
    """A :class:`LiftTable` from a tabulated lift [N] (``n_protrusion x n_gap``) on ``gaps`` [m] (increasing,
    > 0) and ``protrusions`` [m] (>= 0; rows at zero protrusion, where the lift is zero, are dropped).

    Parameters
    ----------
    gaps : apex gaps [m], increasing, > 0
    protrusions : protrusions [m], >= 0
    lift : the tabulated lift [N], ``n_protrusion x n_gap``
    p_pad : pad pressure [Pa]
    a, b : the footprint's semi-axes [m]
    profile : a name of :data:`PROFILES`

    Returns
    -------
    LiftTable
        The table: its gaps [m], protrusions [m] and the ratio to the closed form [1] with its slope.

    Raises
    ------
    ValueError
        Fewer than 2 rows of positive protrusion or 4 gaps, or a lift of another shape.

    References
    ----------
    docs/model.md, section "Slip-corrected Reynolds equation" (the ratio to the closed form).
    """
    from scipy.interpolate import CubicSpline

    gaps, protrusions = np.asarray(gaps, dtype=float), np.asarray(protrusions, dtype=float)
    lift = np.asarray(lift, dtype=float)
    keep = protrusions > 0
    if keep.sum() < 2 or gaps.size < 4 or lift.shape != (protrusions.size, gaps.size):
        raise ValueError(f"bulge lift table: expected >= 2 positive protrusions, >= 4 gaps and a lift of shape "
                         f"(protrusions, gaps); got {int(keep.sum())}, {gaps.size}, {lift.shape}")
    F_ph = ph_lift(gaps[None, :], protrusions[keep, None], p_pad, a, b, profile)[0]
    ratio = lift[keep] / F_ph
    ln_g = np.log(gaps)
    return LiftTable(ln_g, protrusions[keep], ratio, CubicSpline(ln_g, ratio, axis=1)(ln_g, 1), float(p_pad),
                     float(a), float(b), profile)


def table_lift(table: LiftTable, g, delta: float, g_min: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Lift [N] and stiffness ``-dF/dg`` [N/m] at apex gaps ``g`` [m] and one protrusion ``delta`` [m] from a table.

    ``F = r F_ph``, ``k = r k_ph - F_ph (dr/d ln g) / g`` (``F_ph``, ``k_ph``: :func:`ph_lift`, exact). In the
    protrusion ``r`` and ``dr/d ln g`` are interpolated linearly between the two neighbouring rows (held at
    the first and last rows outside them: below the first row ``F_ph -> 0`` carries the lift to zero at zero
    protrusion); in the gap, a cubic Hermite interpolant of the row in ``ln g`` (held constant outside
    the table's gaps). Below ``g_min`` [m] (default: the table's smallest gap) the force is held and the
    stiffness is zero. The error of the protrusion interpolation is measured in
    tests/stages/test_bulge.py (docs/model.md, section "Slip-corrected Reynolds equation").

    Parameters
    ----------
    table : the lift table (:func:`lift_table`)
    g : apex gaps [m]
    delta : protrusion [m]
    g_min : the gap floor [m] (``None``: the table's smallest gap)

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The lift [N] and the stiffness [N/m], the shape of ``g``.

    References
    ----------
    docs/model.md, section "Slip-corrected Reynolds equation"; [Gross62] (the closed form).
    """
    from scipy.interpolate import CubicHermiteSpline

    g = np.asarray(g, dtype=float)
    d = table.protrusions
    j = int(np.clip(np.searchsorted(d, delta) - 1, 0, d.size - 2))
    w = float(np.clip((delta - d[j]) / (d[j + 1] - d[j]), 0.0, 1.0))
    r = (1 - w) * table.ratio[j] + w * table.ratio[j + 1]
    dr = (1 - w) * table.dratio[j] + w * table.dratio[j + 1]
    ln_g = table.ln_gaps
    g_min = float(np.exp(ln_g[0])) if g_min is None else g_min
    gg = np.maximum(g, g_min)
    F_ph, k_ph = ph_lift(g, delta, table.p_pad, table.a, table.b, table.profile, g_min)
    x = np.clip(np.log(gg), ln_g[0], ln_g[-1])
    spline = CubicHermiteSpline(ln_g, r, dr)
    inside = (np.log(gg) > ln_g[0]) & (np.log(gg) < ln_g[-1])
    drr = np.where(inside, spline(x, 1), 0.0)
    rr = spline(x)
    return rr * F_ph, rr * k_ph - F_ph * drr / gg * (g >= g_min)


def reynolds_force(g: np.ndarray, delta: float, table: LiftTable) -> np.ndarray:
    """Lift [N] of the bulge's air bearing from the Reynolds equation with molecular slip (the scene's
    table, ``bulge.nc``: :func:`reynolds_table` solved once per scene with the slip model
    ``air_bearing.bulge_slip``) at the TFC gaps ``g`` [m] for the protrusion ``delta`` [m]
    (:func:`table_lift`; docs/model.md, section "Slip-corrected Reynolds equation"). Zero at zero
    protrusion. The table holds everything (the runner keeps it current). The same reader serves the
    rough-gap law ``"rough-reynolds"`` (docs/model.md, section "Rough-gap bulge bearing").

    Parameters
    ----------
    g : TFC gaps [m]
    delta : protrusion [m]
    table : the scene's lift table (:func:`lift_table`)

    Returns
    -------
    numpy.ndarray
        The lift [N], the shape of ``g``.

    References
    ----------
    [Burgdorfer59] (first-order slip), [FK88]/[FK90] and [PC78]/[PC79] (the rough gap); docs/model.md,
    sections "Slip-corrected Reynolds equation" and "Rough-gap bulge bearing".
    """
    return table_lift(table, g, delta)[0]


#: The bulge's air bearing at the TFC point (``air_bearing.bulge``), laws summed with the other TFC-point
#: laws by the model (:data:`pipeline.model.assembly.TFC_POINT_LAWS`); ``"none"``: the model without it.
#: ``"reynolds"`` reads its table from the ``bulge`` stage's dataset (``table="bulge"``).
BULGE_LAWS: Registry[TfcLaw] = Registry("air_bearing.bulge", {
    "none": NO_TFC_LAW,
    "ph-limit": TfcLaw(ph_limit_force, summary="p h = const under the bulge: F = p_pad pi a b [h_pad I(g, delta) - 1]",
                       source='docs/model.md, section "p h = const limit"',
                       parameters=(("p_pad", "air_bearing.pad_pressure"), ("a", "tfc.half_length"),
                                   ("b", "tfc.half_width"), ("profile", "air_bearing.bulge_profile"))),
    "reynolds": TfcLaw(reynolds_force, table="bulge",
                       summary="steady compressible Reynolds equation with molecular slip on the footprint, tabulated",
                       source='docs/model.md, section "Slip-corrected Reynolds equation"'),
    "rough-reynolds": TfcLaw(reynolds_force, table="bulge",
                             summary="Reynolds equation of the rough gap down to contact: Boltzmann flow rate, "
                                     "Patir-Cheng flow factors, closed area out of the film, tabulated",
                             source='docs/model.md, section "Rough-gap bulge bearing"'),
})
