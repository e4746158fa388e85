"""The air bearing of the TFC bulge: extra lift on the slider from the air squeezed under the bulge.

Under the trailing pad of the slider the air is at the pad pressure ``p_pad`` [Pa] in the pad gap
``h_pad`` [m]. The thermal protrusion (TFC bulge, an elliptic footprint with semi-axes ``a`` along the
sliding direction and ``b`` across it, height ``delta`` [m]) narrows the gap to the apex gap ``g`` [m],
so ``h_pad = g + delta`` (the pad moves with the slider). The air under the bulge is compressed and
pushes the slider up at the TFC point with the extra lift ``F_b = int (p - p_pad) dA`` [N]. Two
models (docs/model.md, section "Bulge air bearing"):

* ``"ph-limit"``: the closed form of the high-bearing-number limit (:func:`ph_force_stiffness`);
* ``"reynolds"``: the steady compressible Reynolds equation with molecular slip (first-order by default,
  :data:`pipeline.physics.reynolds.SLIP_MODELS`) on the footprint, solved by finite volumes and Newton's method
  (:func:`pipeline.physics.reynolds.reynolds_solve`,
  :func:`pipeline.physics.reynolds.reynolds_table`) once per scene by the ``bulge`` stage, and read back by
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

How far the paper's bulge is from the limit (measured with :func:`pipeline.physics.reynolds.reynolds_solve`, first-order slip,
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
from .tfc_laws import NO_TFC_LAW, TfcLaw
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
