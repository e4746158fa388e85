"""The ISBL rough-surface interface: forces per nominal area versus separation.

Greenwood-Williamson summation of the single-summit laws over a Gaussian distribution of summit
heights, with the populations of docs/model.md, section "ISBL interface" (improved sub-boundary lubrication, ISBL):

====================  ======================  ============  ====================  ========
population            summit height z         contact       adhesion              friction
====================  ======================  ============  ====================  ========
non-contacting        z < d - t               0             Lennard-Jones         0
lubricant-contacting  d - t <= z < d          0             2 pi R dgamma         0
elastic               0 < w <= w_c            Hertz         2 pi R dgamma         tau_y A
elastic-plastic       w_c < w <= 110 w_c      Kogut-Etsion  2 pi R dgamma         tau_y A
fully plastic         w > 110 w_c             H 2 pi R w    0                     0
====================  ======================  ============  ====================  ========

with ``w = z - d``, ``d`` the separation of the flat from the mean of summit heights and ``z``
measured from that mean, Gaussian with standard deviation ``sigma_s``.

Quadrature
----------
Each population's range is clipped to ``|z| <= tail sigma_s`` (``tail = 12``: the Gaussian weight
beyond is below 1e-31 of its peak) and integrated by composite Gauss-Legendre with ``panels`` panels
of ``nodes`` nodes, split at every break of the single-summit laws (``w = 0, w_c, 6 w_c, 110 w_c``
and ``z = d - t``), so each panel integrates a smooth function. In the elastic range the
substitution ``w = (b - a) u^2`` removes the ``w^1.5`` branch point at ``w = 0``. The
Lennard-Jones range, whose law has a pole just ``eps`` beyond its upper end, is split into
sub-ranges graded geometrically towards that end. The integrands are then analytic on every
panel, well away from their singularities, and Gauss-Legendre converges exponentially;
``tests/physics/test_isbl.py`` checks the default against adaptive ``scipy.integrate.quad`` and the closed
forms, and that doubling the nodes changes nothing at the 1e-8 level. Integrals of a constant law against the
Gaussian (meniscus adhesion, summit fractions) use the closed form (``scipy.special.ndtr``).

Friction of the summits
-----------------------
The friction column is ``tau_y A`` per summit (the table the ``"shear-strength"`` and ``"coefficient"`` laws
read), or, for a friction law defined per summit (``Interface.friction_law``, e.g. ``"kogut-etsion"``: the
largest tangential load at sliding inception, :mod:`pipeline.physics.friction`), that law's ``Q(w)``
integrated by the same quadrature, its panels split at the law's own breaks too (``_summit_integral``).

Two adhesion populations
------------------------
The adhesion is written as two parts (docs/model.md, section "Two adhesion populations"): the
**bridges** before solid contact (Lennard-Jones of the non-wetted summits and the menisci of the
summits that reach the lubricant surface but do not touch) and the **menisci around contacts** (the
elastic and elastic-plastic summits). The paper's ISBL (``dgamma_bridge = None``) gives both the one
work of adhesion ``dgamma``. With ``dgamma_bridge`` set, the bridges have their own, smaller work of
adhesion: the bonded layer forms no meniscus, so a summit that reaches the lubricant without touching
is held by the van der Waals attraction across the film and the bridges of the thin mobile fraction
[Ono24], while the lubricant displaced by a solid contact rings it with a full meniscus
``2 pi R dgamma``. The Lennard-Jones law of the non-wetted summits takes ``dgamma_bridge`` too, so
it still joins the bridge value continuously at the lubricant surface.

Adhesion rising with penetration
--------------------------------
With ``dgamma_solid`` set, a summit that pushes into the bonded lubricant layer (thickness ``t``) adheres more
(or less) the deeper it goes: its work of adhesion rises linearly from the lubricant's ``dgamma`` at the film
surface to ``dgamma_solid`` at solid contact and stays there for the touching summits
(:func:`pipeline.physics.adhesion.penetration_work_of_adhesion`; [VP11]: the bonded layer as a semi-solid whose
surface energy varies with penetration). The extra is added to both populations, in closed form
(:func:`penetration_adhesion`), each from its own value at the film surface: the bridges' ``dgamma_bridge`` (with
two populations) and the menisci's ``dgamma``, so that a summit's work of adhesion is ``dgamma_solid`` on both sides
of touching; in the paper's ISBL, with ``dgamma_solid = dgamma``, it is 0 exactly and the tables are those without
it.

Wetted area
-----------
``wetted_area_fraction`` is the summit surface inside the lubricant film and outside the solid contact,
per nominal area, where the lubricant-shear friction term acts (:mod:`pipeline.physics.friction`): the
annulus of a summit's undeformed sphere between the lubricant surface (a height ``t`` above the disk)
and the disk, ``2 pi R (z - d + t)`` for a summit that reaches the film without touching and
``2 pi R t`` for a touching one (the annulus between the sphere's sections at the disk and at the film
surface; the Hertz contact takes the inner part of the section at the disk). In closed form,
``a_w = eta 2 pi R sigma_s [G((d - t)/sigma_s) - G(d/sigma_s)]`` with ``G(u) = phi(u) - u Q(u)``
(``int_a^inf (z - a) phi dz = sigma_s G(a/sigma_s)``).

References
----------
.. [GW66] J. A. Greenwood, J. B. P. Williamson, Proc. R. Soc. Lond. A 295 (1966) 300-319.
.. [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662.
.. [Stanley90] H. M. Stanley, I. Etsion, D. B. Bogy, J. Tribol. 112 (1990) 98-104.
.. [VP11] A. I. Vakis, A. A. Polycarpou, "Modeling sliding contact of rough surfaces with molecularly thin
   lubricants", Tribol. Lett. 45 (2012) 37-48.
.. [Vakis09] A. I. Vakis, S.-C. Lee, A. A. Polycarpou, IEEE Trans. Magn. 45 (2009) 4966-4971.
.. [Ono24] K. Ono, "Physics of the sub-monolayer lubricant in the head-disk interface", Lubricants 12
   (2024) 117: the meniscus of the rarefied mobile film is the interaction force at the HDI; the
   bonded layer does not flow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import asperity
from .adhesion import lennard_jones_force, meniscus_force
from .friction import FRICTION_LAWS, SummitLaw, shear_strength

#: Half-width of the integration window in summit standard deviations.
TAIL = 12.0

#: Quantities the tables can hold (the keys of :func:`isbl_tables`' result).
QUANTITIES = ("contact_pressure", "adhesion_pressure", "friction_stress", "real_area_fraction",
              "contact_fraction", "wetted_area_fraction")


@dataclass(frozen=True)
class Interface:
    """Parameters of the rough interface (SI units).

    Attributes
    ----------
    sigma_s : summit-height standard deviation [m]
    eta : summit density [m^-2]
    R : summit radius [m]
    E : composite modulus E' [Pa]
    H : hardness of the softer body [Pa]
    nu : Poisson ratio [1] (Kogut-Etsion K factor)
    t : lubricant thickness [m]
    dgamma : work of adhesion [J/m^2] (of every summit in the paper's ISBL; of the menisci around
        solid contacts with two populations)
    eps : intermolecular distance [m]
    dgamma_bridge : work of adhesion of the bridges before solid contact [J/m^2] (Lennard-Jones of the
        non-wetted summits, menisci of the wetted non-touching ones); ``None``: ``dgamma`` (the
        paper's ISBL, one population)
    dgamma_solid : work of adhesion at solid contact through the bonded layer [J/m^2]: a summit's work of
        adhesion rises linearly from the lubricant's ``dgamma`` at the film surface to this value at solid
        contact across the thickness ``t``, then stays there (module docstring, "Adhesion rising with
        penetration"); ``None``: off (every summit keeps its population's value)
    friction_law : the friction law whose per-summit form the ``friction_stress`` table integrates (a name
        of :data:`pipeline.physics.friction.FRICTION_LAWS`); a law without one (``"shear-strength"``,
        ``"coefficient"``) gets the shear-strength table ``eta int tau_y A phi dz``
    """

    sigma_s: float
    eta: float
    R: float
    E: float
    H: float
    nu: float
    t: float
    dgamma: float
    eps: float
    dgamma_bridge: float | None = None
    friction_law: str = "shear-strength"
    dgamma_solid: float | None = None

    @property
    def w_c(self) -> float:
        """Critical interference of the summits (:func:`pipeline.physics.asperity.critical_interference`).

        Returns
        -------
        float
            ``w_c = (pi K H / (2 E'))^2 R`` [m].

        References
        ----------
        [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662; docs/model.md, section "Single asperity".
        """
        return asperity.critical_interference(self.R, self.E, self.H, self.nu)

    def __post_init__(self) -> None:
        for name in ("sigma_s", "eta", "R", "E", "H", "eps"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"Interface.{name} = {v!r}: expected a positive finite number")
        for name in ("t", "dgamma", "dgamma_bridge", "dgamma_solid"):
            v = getattr(self, name)
            if v is None and name in ("dgamma_bridge", "dgamma_solid"):
                continue
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"Interface.{name} = {v!r}: expected a finite number >= 0")
        FRICTION_LAWS.lookup(self.friction_law)  # (one line naming the names registered)


def _panels(a: np.ndarray, b: np.ndarray, nodes: int, panels: int, square: bool = False):
    """Composite Gauss-Legendre nodes ``z`` and weights ``wt`` on ``[a_i, b_i]`` for every row i.

    ``square``: map ``z = a + (b - a) u^2`` (u in [0, 1]) to smooth a ``(z - a)^1.5`` branch point.
    Empty ranges (``b <= a``) get zero weights.
    """
    x, w = np.polynomial.legendre.leggauss(nodes)
    edges = np.linspace(0.0, 1.0, panels + 1)
    h = np.diff(edges)
    u = (edges[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)).ravel()
    wu = (0.5 * h[:, None] * w[None, :]).ravel()
    length = np.maximum(b - a, 0.0)[:, None]
    if square:
        z = a[:, None] + length * u**2
        wt = length * 2.0 * u * wu
    else:
        z = a[:, None] + length * u
        wt = length * wu
    return z, wt


def _ndtr(x: np.ndarray) -> np.ndarray:
    """The standard Gaussian's CDF ``Phi(x)`` [1], ``scipy.special.ndtr``, imported at the first call: every
    ``hdi`` command imports this module (the command line's sizing), and scipy.special's import (~0.2-0.5 s
    with the numpy modules it pulls) is paid only by those that make interface tables."""
    from scipy.special import ndtr as cdf
    return cdf(x)


def _G(u: np.ndarray) -> np.ndarray:
    """``G(u) = phi(u) - u Q(u) = int_u^inf (v - u) phi(v) dv`` [1] for the standard Gaussian (module docstring,
    "Wetted area")."""
    return np.exp(-0.5 * u * u) / np.sqrt(2.0 * np.pi) - u * _ndtr(-u)


def _gauss(z: np.ndarray, s: float) -> np.ndarray:
    return np.exp(-0.5 * (z / s) ** 2) / (s * np.sqrt(2.0 * np.pi))


def isbl_tables(d: np.ndarray, p: Interface, *, quantities=QUANTITIES, nodes: int = 24,
                panels: int = 4) -> dict[str, np.ndarray]:
    """ISBL pressures and fractions versus separation ``d`` [docs/model.md, section "ISBL interface"; GW66; KE02; Stanley90].

    Parameters
    ----------
    d : separation of the flat from the mean of summit heights [m] (any sign)
    p : the interface parameters
    quantities : which of :data:`QUANTITIES` to compute (others are not evaluated)
    nodes, panels : Gauss-Legendre nodes per panel, panels per population range

    Returns
    -------
    dict
        ``contact_pressure`` [Pa]: ``eta int P phi dz``; ``adhesion_pressure`` [Pa] (positive =
        attractive); ``friction_stress`` [Pa]: ``eta int tau_y A phi dz`` over elastic and
        elastic-plastic summits, or ``eta int Q phi dz`` of the per-summit law of ``p.friction_law``
        (module docstring, "Friction of the summits"); ``real_area_fraction`` [1]: ``eta int A phi dz``;
        ``contact_fraction`` [1]: fraction of summits in contact ``P(z > d)``;
        ``wetted_area_fraction`` [1]: summit surface inside the lubricant film and outside the solid
        contacts per nominal area (module docstring); when contact is computed,
        ``elastic_fraction``/``plastic_fraction`` [1] of summits in those regimes; with the adhesion,
        its two parts ``adhesion_pressure_bridges`` and ``adhesion_pressure_menisci`` [Pa] (module
        docstring, "Two adhesion populations"), whose sum is ``adhesion_pressure``.

    References
    ----------
    [GW66] (the summit statistics), [KE02] (the single-summit laws), [Stanley90] (the sub-boundary
    adhesion); docs/model.md, sections "ISBL interface", "Two adhesion populations" and "References".
    """
    unknown = set(quantities) - set(QUANTITIES)
    if unknown:
        raise ValueError(f"unknown ISBL quantities {sorted(unknown)}; expected some of {QUANTITIES}")
    d = np.atleast_1d(np.asarray(d, dtype=float))
    s = p.sigma_s
    want = set(quantities)
    out: dict[str, np.ndarray] = {}
    if want & {"contact_pressure", "friction_stress", "real_area_fraction"}:
        _contact_quantities(d, p, want, nodes, panels, out)
    if "adhesion_pressure" in want:
        _adhesion_quantities(d, p, nodes, panels, out)
    if "wetted_area_fraction" in want:  # closed form (module docstring, "Wetted area")
        out["wetted_area_fraction"] = p.eta * 2.0 * np.pi * p.R * s * np.maximum(_G((d - p.t) / s) - _G(d / s), 0.0)
    if "contact_fraction" in want:
        out["contact_fraction"] = _upper(d, s)
    return out


def _cdf(z: np.ndarray, s: float) -> np.ndarray:
    """The Gaussian CDF of summit heights ``P(z' < z)`` [1], ``s = sigma_s`` [m]."""
    return _ndtr(z / s)


def _upper(z: np.ndarray, s: float) -> np.ndarray:
    """The upper tail ``P(z' > z)`` [1] as ``ndtr(-z/s)``, not ``1 - F(z)``: the difference loses all relative
    accuracy (and monotonicity) once ``F(z)`` rounds to 1, i.e. beyond ~8 sigma_s."""
    return _ndtr(-z / s)


def _clip(a: np.ndarray, b: np.ndarray, s: float) -> tuple[np.ndarray, np.ndarray]:
    """A range of summit heights clipped to the tables' ``+- TAIL sigma_s`` [m]."""
    zmax = TAIL * s
    return np.clip(a, -zmax, zmax), np.clip(b, -zmax, zmax)


def _contact_quantities(d: np.ndarray, p: Interface, want: set, nodes: int, panels: int,
                        out: dict[str, np.ndarray]) -> None:
    """The contact pressure [Pa] with the elastic and plastic fractions [1], the friction stress [Pa] and the
    real area fraction [1] of :func:`isbl_tables` (those of ``want``) into ``out``: the summits' laws [KE02]
    integrated over their contacting ranges, elastic, elastic-plastic (two fits), fully plastic."""
    s, eta, R, E, H, nu = p.sigma_s, p.eta, p.R, p.E, p.H, p.nu
    wc = p.w_c
    Pc = asperity.critical_load(R, E, H, nu)
    Ac = asperity.critical_area(R, E, H, nu)
    ranges = {
        "el": _clip(d, d + wc, s),
        "ep1": _clip(d + wc, d + asperity.X_MID * wc, s),
        "ep2": _clip(d + asperity.X_MID * wc, d + asperity.X_PLASTIC * wc, s),
        "pl": _clip(d + asperity.X_PLASTIC * wc, np.full_like(d, np.inf), s),
    }
    load = np.zeros_like(d)
    area_fric = np.zeros_like(d)  # area of summits that carry friction (elastic + EP)
    area_all = np.zeros_like(d)
    for name, (a, b) in ranges.items():
        z, wt = _panels(a, b, nodes, panels, square=(name == "el"))
        w = np.maximum(z - d[:, None], 0.0)
        wt = wt * _gauss(z, s)
        x = w / wc
        # the single-summit laws of the range [KE02] (pipeline.physics.asperity)
        if name == "el":
            P, A = asperity.hertz_load(w, R, E), asperity.hertz_area(w, R)
        elif name in ("ep1", "ep2"):
            fit = int(name == "ep2")
            P = asperity.ke_fit(x, Pc, asperity.KE_LOAD_FITS[fit])
            A = asperity.ke_fit(x, Ac, asperity.KE_AREA_FITS[fit])
        else:
            P, A = asperity.plastic_load(w, R, H), asperity.plastic_area(w, R)
        load += (P * wt).sum(axis=1)
        Aint = (A * wt).sum(axis=1)
        area_all += Aint
        if name != "pl":
            area_fric += Aint
    if "contact_pressure" in want:
        out["contact_pressure"] = eta * load
        out["elastic_fraction"] = np.where(d > 0, _upper(d, s) - _upper(d + wc, s), _cdf(d + wc, s) - _cdf(d, s))
        out["plastic_fraction"] = _upper(d + asperity.X_PLASTIC * wc, s)
    # (The GW sum ignores the interaction of neighbouring summits, so at deep interference the
    # area fraction can exceed 1; the tables keep the model's value, the dynamic outputs clip the
    # real area at the nominal area: pipeline.model.outcomes.histories.)
    if "friction_stress" in want:
        summit = FRICTION_LAWS.lookup(p.friction_law).summit
        if summit is None:
            out["friction_stress"] = eta * shear_strength(H) * area_fric
        else:
            out["friction_stress"] = eta * _summit_integral(d, p, summit, nodes, panels)
    if "real_area_fraction" in want:
        out["real_area_fraction"] = eta * area_all


def _lj_nodes(a: np.ndarray, b: np.ndarray, p: Interface, nodes: int, panels: int) -> tuple[np.ndarray, np.ndarray]:
    """Quadrature nodes [m] and weights of the Lennard-Jones range ``[a, b]`` of summit heights.

    The LJ law ~ (eps/gap)^2 has a pole a distance eps beyond the top of its range (gap = 0), while the range
    spans up to 2 TAIL sigma_s >> eps: on uniform panels Gauss-Legendre converges very slowly (1e-3 relative
    error at sigma_s = 5 nm). The range is graded geometrically towards its top, sub-ranges
    [b - eps (4^(k+1) - 1), b - eps (4^k - 1)], so every sub-range stays well separated from the pole relative
    to its length."""
    zmax = TAIL * p.sigma_s
    levels = max(1, int(np.ceil(np.log(2.0 * zmax / p.eps + 1.0) / np.log(4.0))))
    dist = p.eps * (4.0 ** np.arange(levels + 1) - 1.0)
    parts = []
    for k in range(levels):
        top = np.maximum(b - dist[k], a)
        bot = a if k == levels - 1 else np.maximum(b - dist[k + 1], a)
        parts.append(_panels(bot, top, nodes, panels))
    z = np.concatenate([zz for zz, _ in parts], axis=1)
    wt = np.concatenate([ww for _, ww in parts], axis=1)
    return z, wt


def _adhesion_quantities(d: np.ndarray, p: Interface, nodes: int, panels: int, out: dict[str, np.ndarray]) -> None:
    """The adhesion pressure [Pa] of :func:`isbl_tables` and its two parts, on the bridges and on the menisci
    (module docstring, "Two adhesion populations"), into ``out``."""
    s, eta, R = p.sigma_s, p.eta, p.R
    wc = p.w_c
    fm = meniscus_force(R, p.dgamma)
    # Wetted and elastic/elastic-plastic summits: the constant meniscus force (closed form).
    wetted = _cdf(d + asperity.X_PLASTIC * wc, s) - _cdf(d - p.t, s)
    a, b = _clip(np.full_like(d, -np.inf), d - p.t, s)
    z, wt = _lj_nodes(a, b, p, nodes, panels)
    gap = d[:, None] - p.t - z + p.eps
    dgb = p.dgamma if p.dgamma_bridge is None else p.dgamma_bridge
    lj = (lennard_jones_force(gap, R, dgb, p.eps) * wt * _gauss(z, s)).sum(axis=1)
    # the two populations (module docstring): upper-tail differences above the summit mean, where
    # the CDF's differences would round away
    touching = np.where(d > 0, _upper(d, s) - _upper(d + asperity.X_PLASTIC * wc, s),
                        _cdf(d + asperity.X_PLASTIC * wc, s) - _cdf(d, s))
    reaching = np.where(d - p.t > 0, _upper(d - p.t, s) - _upper(d, s), _cdf(d, s) - _cdf(d - p.t, s))
    out["adhesion_pressure_menisci"] = eta * fm * touching
    out["adhesion_pressure_bridges"] = eta * (meniscus_force(R, dgb) * reaching + lj)
    if p.dgamma_bridge is None:  # the paper's ISBL, summed as it always was
        out["adhesion_pressure"] = eta * (fm * wetted + lj)
    else:
        out["adhesion_pressure"] = out["adhesion_pressure_menisci"] + out["adhesion_pressure_bridges"]
    if p.dgamma_solid is not None:  # (module docstring, "Adhesion rising with penetration")
        extra_bridges, extra_menisci = penetration_adhesion(d, p)
        out["adhesion_pressure_bridges"] = out["adhesion_pressure_bridges"] + extra_bridges
        out["adhesion_pressure_menisci"] = out["adhesion_pressure_menisci"] + extra_menisci
        out["adhesion_pressure"] = out["adhesion_pressure"] + (extra_bridges + extra_menisci)


def penetration_adhesion(d: np.ndarray, p: Interface) -> tuple[np.ndarray, np.ndarray]:
    """The adhesion pressure [Pa] that penetration into the bonded layer adds, on the bridges and on the menisci.

    Every summit that reaches the film and carries adhesion gets the extra work of adhesion
    ``(dgamma_solid - W_0) r``, ``r = clip((z - d + t) / t, 0, 1)``, from its population's value ``W_0`` at the
    film surface (:func:`pipeline.physics.adhesion.penetration_work_of_adhesion`), so the extra force ``2 pi R``
    times that: on the wetted summits that do not touch (``d - t <= z < d``, the bridges' population, ``W_0 =
    dgamma_bridge``, or ``dgamma`` in the paper's ISBL) and on the elastic and elastic-plastic ones (``d < z <= d
    + 110 w_c``, ``r = 1``, the menisci's, ``W_0 = dgamma``); fully plastic summits carry no adhesion, nor do the
    summits outside the film. Each population starting from its own value makes a summit's work of adhesion
    ``dgamma_solid`` on both sides of touching (``z = d``). In closed form, with ``int_a^b (z - a) phi dz =
    sigma_s [G(a / sigma_s) - G(b / sigma_s)] - (b - a) Q(b)`` (module docstring, "Wetted area"):

    ``p_b = eta 2 pi R (dgamma_solid - dgamma_bridge) ({sigma_s [G((d - t)/sigma_s) - G(d/sigma_s)]} / t - Q(d))``,
    ``p_m = eta 2 pi R (dgamma_solid - dgamma) [Q(d) - Q(d + 110 w_c)]``

    (``t = 0``: ``p_b = 0``). Each is 0 exactly when ``dgamma_solid`` is its population's surface value.
    [VP11; docs/model.md, section "Adhesion rising with penetration"]

    Parameters
    ----------
    d : separation [m]
    p : the interface, with ``dgamma_solid`` set

    Returns
    -------
    tuple of numpy.ndarray
        ``(p_b, p_m)``: the extra adhesion pressure [Pa] of the bridges and of the menisci, the shape of ``d``.

    References
    ----------
    docs/model.md, section "Adhesion rising with penetration" (the sources: Vakis & Polycarpou, Tribol. Lett. 45
    (2012) 37-48, and Brunner et al., Tribol. Lett. 40 (2010)).
    """
    d = np.atleast_1d(np.asarray(d, dtype=float))
    s, t = p.sigma_s, p.t
    scale = p.eta * meniscus_force(p.R, p.dgamma_solid - p.dgamma)
    # the bridges rise from their own surface value, so a summit's W is dgamma_solid on both sides of touching
    bridge = p.dgamma if p.dgamma_bridge is None else p.dgamma_bridge
    scale_b = p.eta * meniscus_force(p.R, p.dgamma_solid - bridge)
    Q = lambda x: _ndtr(-x / s)  # noqa: E731 - upper tail P(z > x)
    touching = np.where(d > 0, Q(d) - Q(d + asperity.X_PLASTIC * p.w_c),
                        _ndtr((d + asperity.X_PLASTIC * p.w_c) / s) - _ndtr(d / s))
    if t > 0.0:
        ramp = np.maximum(s * (_G((d - t) / s) - _G(d / s)) / t - Q(d), 0.0)
    else:
        ramp = np.zeros_like(d)
    return scale_b * ramp, scale * touching


def _summit_integral(d: np.ndarray, p: Interface, law: SummitLaw, nodes: int, panels: int) -> np.ndarray:
    """``int Q(z - d) phi(z) dz`` [N] over the elastic and elastic-plastic summits (``0 < w <= 110 w_c``)
    for a per-summit friction law ``Q`` (:class:`pipeline.physics.friction.SummitLaw`), at every ``d`` [m].

    The same composite Gauss-Legendre as the contact integrals, the range split at the breaks of the
    contact law (``x = w / w_c = 0, 1, 6, 110``) and at the law's own (``law.breaks()``), so each panel holds
    one smooth branch; the elastic range maps ``w = w_c u^2`` as for Hertz (the laws there go as ``w^e``
    with ``e`` near 1 or 1.5).
    """
    s, wc = p.sigma_s, p.w_c
    zmax = TAIL * s
    x = sorted({0.0, asperity.X_ELASTIC, asperity.X_MID, asperity.X_PLASTIC}
               | {float(b) for b in law.breaks() if 0.0 < b < asperity.X_PLASTIC})
    total = np.zeros_like(d)
    for k, (lo, hi) in enumerate(zip(x[:-1], x[1:])):
        a, b = np.clip(d + lo * wc, -zmax, zmax), np.clip(d + hi * wc, -zmax, zmax)
        z, wt = _panels(a, b, nodes, panels, square=(k == 0))
        # (each node strictly inside its segment: the law's branch there, whatever its value at the ends)
        w = np.clip(z - d[:, None], lo * wc, hi * wc)
        total += (law.force(w, p.R, p.E, p.H, p.nu) * wt * _gauss(z, s)).sum(axis=1)
    return total


def separation_grid(d_min: float, d_max: float, step: float) -> np.ndarray:
    """Uniform separation grid [m] from ``d_min`` [m] to at least ``d_max`` [m] with spacing ``step`` [m].

    The dynamics interpolates the tables on this grid in O(1) (uniform spacing).

    Parameters
    ----------
    d_min : the grid's first separation [m]
    d_max : the separation the grid reaches or passes [m]
    step : the spacing [m], positive

    Returns
    -------
    numpy.ndarray
        The separations [m], ``d_min + step i`` for ``i = 0 .. ceil((d_max - d_min) / step)``.

    References
    ----------
    docs/model.md, section "Interface tables" (the grid ``solver.table_step_nm``).
    """
    n = int(np.ceil((d_max - d_min) / step)) + 1
    return d_min + step * np.arange(n)
