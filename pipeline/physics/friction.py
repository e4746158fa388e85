"""The single-asperity friction law.

The paper computes friction from the asperity stresses, with no assumed coefficient of friction.
Our documented default (docs/model.md, section "Friction") is sliding at the shear strength of the softer body:
``Q = tau_y A`` on every elastic and elastic-plastic summit, with the von Mises shear yield stress
``tau_y = Y / sqrt(3)`` and ``H = 2.8 Y`` (Tabor), i.e. ``tau_y = H / (2.8 sqrt(3))``.
Fully plastic summits carry no friction in the ISBL population table (docs/model.md, section "Friction").

docs/model.md, section "Friction": the paper's mu ~ 1.2 at ~400 MPa implies ~480 MPa of shear stress, more than the
``tau_y`` of a 1.7 GPa hardness, so the law is a named choice (:data:`FRICTION_LAWS`,
``contact.friction_law``): ``"shear-strength"`` as above, or ``"coefficient"``, a constant
coefficient ``Q = mu P`` (Amontons) with ``contact.friction_coefficient``. Both act through the
friction-stress table of the dynamics (:func:`friction_stress_table`), so the choice costs nothing
in the kernel.

References
----------
.. [Tabor51] D. Tabor, The Hardness of Metals, Oxford (1951): ``H ~ 2.8 Y``.
.. [Bowden50] F. P. Bowden, D. Tabor, The Friction and Lubrication of Solids (1950): adhesive
   friction as shear strength times real area.
.. [VEP11] A. I. Vakis, M. Eriten, A. A. Polycarpou, "Modeling bearing and shear forces in
   molecularly thin lubricants", Tribol. Lett. 41 (2011) 573-586.
.. [VP11] A. I. Vakis, A. A. Polycarpou, "Modeling sliding contact of rough surfaces with molecularly
   thin lubricants", Tribol. Lett. 45 (2012) 37-48 (online 2011): friction from the solid contacts and
   from the lubricant sheared on the wetted asperities.
.. [CEB88] W. R. Chang, I. Etsion, D. B. Bogy, "Static friction coefficient model for metallic rough
   surfaces", J. Tribol. 110 (1988) 57-63.
.. [KE03b] L. Kogut, I. Etsion, "A semi-analytical solution for the sliding inception of a spherical
   contact", J. Tribol. 125 (2003) 499-506.
.. [KE04] L. Kogut, I. Etsion, "A static friction model for elastic-plastic contacting rough surfaces",
   J. Tribol. 126 (2004) 34-40.
.. [BKE07] V. Brizmer, Y. Kligerman, I. Etsion, "A model for junction growth of a spherical contact
   under full stick condition", J. Tribol. 129 (2007) 783-790; the static friction coefficient of a
   summit under full stick as used by D. Cohen, Y. Kligerman, I. Etsion, J. Tribol. 130 (2008) 031401.

Switched and continuous friction (``contact.friction_switching``, :data:`FRICTION_SWITCHING`; docs/model.md,
section "Switched and continuous friction"). ``"criterion"`` (the default, the paper's model): the whole
friction stress acts while the contact criterion ``d < k sigma`` holds and is off otherwise, like the
contact pressure. ``"continuous"``: the solid friction (the law above) still follows the contact force,
which the criterion switches, but the lubricant shear ``tau_lub a_w(d)`` acts on the wetted summits
wherever they are wetted, a continuous function of ``d`` as ``a_w`` is [VP11]: the criterion is a
threshold of the contact model, not of the lubricant film, which the summits reach before they touch
(:func:`friction_parts`).

Static-friction laws of the Chang-Etsion-Bogy / Kogut-Etsion family (docs/model.md, section "Static
friction of the summits"): ``"kogut-etsion"`` [KE03b, KE04] and ``"brizmer-kligerman-etsion"`` [BKE07]
give each elastic and elastic-plastic summit the largest tangential load ``Q_max`` it sustains at the
inception of sliding, a function of its interference (normalised by ``w_c``) or of its load (normalised by
the critical load ``L_c = P_c``); fully plastic summits carry none. Their friction stress is the ISBL
integral of the per-summit law (:class:`SummitLaw`, :func:`pipeline.physics.isbl.isbl_tables`), not a
function of the shear-strength table, and the friction coefficient stays the paper's, friction force over
contact force. The published models add the DMT-type adhesion force of the summit (``2 pi R dgamma``, the
meniscus force of the contacting summits here) to the external load only, ``mu = Q / (P - F_s)``; the
sliding-inception fits are of the contact without adhesion, so adhesion does not enter ``Q_max``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import asperity
from .variants import Registry, Variant


def shear_strength(H: float) -> float:
    """Shear yield stress of the softer body ``tau_y = H / (2.8 sqrt(3))`` [Pa] [Tabor51].

    Parameters
    ----------
    H : hardness [Pa]

    Returns
    -------
    float
        The shear strength tau_y [Pa].

    References
    ----------
    [Tabor51] D. Tabor, The Hardness of Metals (1951) (H ~ 2.8 Y, von Mises tau_y = Y / sqrt 3);
    docs/model.md, section "Friction".
    """
    return H / (2.8 * np.sqrt(3.0))


def friction_force(area: np.ndarray, H: float, law: str = "shear-strength") -> np.ndarray:
    """Friction force of one sliding summit [N] by the shear-strength law: ``Q = tau_y A`` [Bowden50].

    Parameters
    ----------
    area : real contact area of the summit [m^2]
    H : hardness [Pa]
    law : must be ``"shear-strength"`` (the coefficient law needs the summit's load, not its area)

    Returns
    -------
    numpy.ndarray
        The friction force Q [N] of each summit, the shape of ``area``.

    Raises
    ------
    ValueError
        For any law but ``"shear-strength"``.

    References
    ----------
    [Bowden50] F. P. Bowden, D. Tabor (1950) (friction as the shear of the real area), [Tabor51];
    docs/model.md, section "Friction".
    """
    if law != "shear-strength":
        raise ValueError(f"friction law {law!r}: the per-summit area form exists only for 'shear-strength'")
    return shear_strength(H) * np.asarray(area, dtype=float)


#: The Kogut-Etsion sliding-inception fits [KE03b, KE04] in ``x = w / w_c``, ``Q*_max = Q_max / L_c``:
#: ``(c, e)`` of ``Q*_max = c x^e`` for the elastic summits (``0 < x <= 1``) and ``(a2, a1, a0)`` of
#: ``Q*_max = a2 x^2 + a1 x + a0`` for the elastic-plastic ones (``1 < x``, down to the limiting preload,
#: its root, beyond which a summit sustains no tangential load). NOT CONFIRMED against the paper: the
#: stored sources give no copy of KE03/KE04, and these constants are the values as recalled from KE04's
#: sliding-inception equations (docs/model.md, section "Static friction of the summits", says what rests
#: on them); the tests check the law's limits and structure, not these numbers.
KE_SLIDING_FITS = ((0.52, 0.982), (-0.01, 0.09, 0.4))

#: The Brizmer-Kligerman-Etsion full-stick static friction coefficient of a summit [BKE07],
#: ``(a, e)`` of ``mu = a coth(a (P / L_c)^e)`` (``a`` is also its large-load limit). As cited by CKE08;
#: not confirmed against a stored copy of BKE07 (docs/model.md, section "Static friction of the summits").
BKE_STICK_FIT = (0.27, 0.35)


def ke_limiting_interference() -> float:
    """The limiting preload of the Kogut-Etsion sliding-inception fit [KE03b]: the interference ``x =
    w / w_c`` [1] above which a summit sustains no tangential load (the root of the elastic-plastic fit of
    :data:`KE_SLIDING_FITS`), capped at the fully plastic limit ``x = 110`` [KE02].

    Returns
    -------
    float
        The limiting interference ``x = w / w_c`` [1] (12.26 with the fits of :data:`KE_SLIDING_FITS`).

    References
    ----------
    [KE03b]; [KE02] for the fully plastic limit; docs/model.md, section "Static friction of the summits".
    """
    a2, a1, a0 = KE_SLIDING_FITS[1]
    root = (-a1 - np.sqrt(a1 * a1 - 4.0 * a2 * a0)) / (2.0 * a2)
    return float(min(root, asperity.X_PLASTIC))


def _summit_scales(w: np.ndarray, R: float, E: float, H: float, nu: float) -> tuple[np.ndarray, float, float]:
    """``(w, w_c, L_c)``: the interference as a float array [m], the critical interference [m] and the critical
    load [N] of the summit [KE02], the scales both static-friction laws normalise by."""
    return (np.asarray(w, dtype=float), asperity.critical_interference(R, E, H, nu),
            asperity.critical_load(R, E, H, nu))


def ke_sliding_inception(w: np.ndarray, R: float, E: float, H: float, nu: float) -> np.ndarray:
    """Largest tangential load of one summit at the inception of sliding ``Q_max`` [N] versus its
    interference ``w`` [m], Kogut-Etsion [KE03b, KE04] (:data:`KE_SLIDING_FITS`).

    ``Q_max = L_c c x^e`` for ``0 < x <= 1`` (elastic), ``L_c (a2 x^2 + a1 x + a0)`` for ``1 < x`` up to the
    limiting preload (:func:`ke_limiting_interference`), and 0 beyond it, for ``w <= 0`` and for fully
    plastic summits (``x > 110``), with ``x = w / w_c`` and ``L_c = P_c`` the critical load [KE02].

    Parameters
    ----------
    w : interference [m]
    R : summit radius [m]; E : composite modulus E' [Pa]; H : hardness [Pa]; nu : Poisson ratio [1]

    Returns
    -------
    numpy.ndarray
        ``Q_max`` [N], the shape of ``w``.

    References
    ----------
    [KE03b], [KE04]; docs/model.md, section "Static friction of the summits".
    """
    w, wc, Lc = _summit_scales(w, R, E, H, nu)
    x = np.maximum(w, 0.0) / wc
    (c, e), (a2, a1, a0) = KE_SLIDING_FITS
    return np.select([w <= 0, x <= asperity.X_ELASTIC, x <= ke_limiting_interference()],
                     [0.0, Lc * c * x**e, Lc * ((a2 * x + a1) * x + a0)], 0.0)


def bke_friction_coefficient(load_ratio: np.ndarray) -> np.ndarray:
    """Full-stick static friction coefficient of one summit ``mu = a coth(a P*^e)`` [1] versus its
    normalised load ``P* = P / L_c`` [1] [BKE07] (:data:`BKE_STICK_FIT`): ``P*^(-e)`` at light loads,
    ``a`` at heavy ones, decreasing in between.

    Parameters
    ----------
    load_ratio : ``P* = P / L_c``, the summit's normal load over the critical load [1], > 0

    Returns
    -------
    numpy.ndarray
        The summit's static friction coefficient ``mu`` [1], the shape of ``load_ratio``.

    References
    ----------
    [BKE07], as cited by D. Cohen, Y. Kligerman, I. Etsion, J. Tribol. 130 (2008) 031401; docs/model.md, section "Static friction of the summits".
    """
    a, e = BKE_STICK_FIT
    return a / np.tanh(a * np.asarray(load_ratio, dtype=float) ** e)


def bke_full_stick(w: np.ndarray, R: float, E: float, H: float, nu: float) -> np.ndarray:
    """Largest tangential load of one summit at the inception of sliding under full stick [N] versus its
    interference ``w`` [m], Brizmer-Kligerman-Etsion [BKE07]: ``Q_max = mu(P*) P`` with the summit's load
    ``P`` of the contact law (:func:`pipeline.physics.asperity.contact_load`) and :func:`bke_friction_coefficient`;
    0 for ``w <= 0`` and for fully plastic summits (``x > 110``; the ISBL population table).

    Parameters
    ----------
    w : interference [m]
    R : summit radius [m]; E : composite modulus E' [Pa]; H : hardness [Pa]; nu : Poisson ratio [1]

    Returns
    -------
    numpy.ndarray
        ``Q_max`` [N] under full stick, the shape of ``w``.

    References
    ----------
    [BKE07]; docs/model.md, section "Static friction of the summits".
    """
    w, wc, Lc = _summit_scales(w, R, E, H, nu)
    P = asperity.contact_load(w, R, E, H, nu)
    on = (w > 0) & (w <= asperity.X_PLASTIC * wc)
    ratio = np.where(on, P / Lc, 1.0)
    return np.where(on, bke_friction_coefficient(ratio) * P, 0.0)


@dataclass(frozen=True)
class SummitLaw:
    """A per-summit friction law that the ISBL integral sums over the summit heights
    (:func:`pipeline.physics.isbl.isbl_tables`).

    Attributes
    ----------
    force : ``force(w, R, E, H, nu) -> Q`` [N], the tangential load of one summit at interference ``w`` [m]
        (SI), 0 for fully plastic summits
    breaks : interferences ``x = w / w_c`` [1] inside ``(1, 110)`` where ``force`` has a kink or a jump
        beyond those of the contact law (``x = 1, 6, 110``): the quadrature splits its panels there
    """

    force: Callable[..., np.ndarray]
    breaks: Callable[[], tuple[float, ...]] = tuple


@dataclass(frozen=True, kw_only=True)
class FrictionLaw(Variant):
    """An entry of :data:`FRICTION_LAWS`: the table behaviour of :class:`~pipeline.physics.variants.Variant`
    and, for a law defined per summit, its :class:`SummitLaw`, which the ISBL tables integrate into the
    friction-stress table (``None``: that table is the shear-strength law's, ``eta int tau_y A phi dz``)."""

    summit: SummitLaw | None = None


def _shear_strength_table(contact_pressure: np.ndarray, shear_strength_stress: np.ndarray) -> np.ndarray:
    return shear_strength_stress


def _coefficient_table(contact_pressure: np.ndarray, shear_strength_stress: np.ndarray, mu: float | None) -> np.ndarray:
    if mu is None or not mu >= 0.0:
        raise ValueError(f"the 'coefficient' friction law needs contact.friction_coefficient >= 0 (got {mu})")
    return mu * np.asarray(contact_pressure, dtype=float)


def _summit_table(contact_pressure: np.ndarray, summit_stress: np.ndarray) -> np.ndarray:
    return summit_stress


#: Friction laws a scene may name (``contact.friction_law``): the behaviour is a function of the contact
#: pressure table [Pa] and the friction-stress table of the ISBL integrals [Pa] (the integral of the entry's
#: per-summit law, :attr:`FrictionLaw.summit`, or of the shear-strength law where it has none), with the
#: entry's ``parameters`` as keywords, returning the friction stress per nominal area [Pa] versus separation.
FRICTION_LAWS: Registry[FrictionLaw] = Registry("contact.friction_law", {
    "shear-strength": FrictionLaw(behaviour=_shear_strength_table,
                                  summary="tau = eta int tau_y A phi dz, tau_y = H / (2.8 sqrt 3): sliding at the "
                                          "shear strength of the softer body",
                                  source='docs/model.md, section "Friction" [Tabor51, Bowden50]'),
    "coefficient": FrictionLaw(behaviour=_coefficient_table, parameters=(("mu", "contact.friction_coefficient"),),
                               summary="tau = mu p_c: a constant coefficient (Amontons) with "
                                       "contact.friction_coefficient",
                               source='docs/model.md, section "Friction"'),
    "kogut-etsion": FrictionLaw(behaviour=_summit_table,
                                summit=SummitLaw(ke_sliding_inception, lambda: (ke_limiting_interference(),)),
                                summary="tau = eta int Q_max phi dz: each elastic and elastic-plastic summit's "
                                        "largest tangential load at sliding inception (Kogut-Etsion), none "
                                        "from fully plastic ones",
                                source='docs/model.md, section "Static friction of the summits" [KE03b, KE04]'),
    "brizmer-kligerman-etsion": FrictionLaw(behaviour=_summit_table, summit=SummitLaw(bke_full_stick),
                                            summary="tau = eta int mu(P/L_c) P phi dz, mu = 0.27 coth(0.27 "
                                                    "(P/L_c)^0.35): full-stick sliding inception of each "
                                                    "elastic and elastic-plastic summit",
                                            source='docs/model.md, section "Static friction of the summits" '
                                                   '[BKE07]'),
})


def lubricant_shear_stress(wetted_area_fraction: np.ndarray, tau_lub: float) -> np.ndarray:
    """Friction stress per nominal area of the lubricant sheared on the wetted summits [Pa]:
    ``tau_lub a_w(d)`` [VP11] (docs/model.md, section "Lubricant friction").

    The "lubricant shear" friction term, added to the solid term of the scene's friction law: the
    molecularly thin lubricant in the menisci of the summits (outside their solid contacts) is sheared
    at the disk speed, at a limiting shear stress ``tau_lub`` far below the solid's ``tau_y`` (a confined
    PFPE film at shear rates of 1e10 1/s is shear-thinned to its limiting stress; [VEP11], [VP11]).

    Parameters
    ----------
    wetted_area_fraction : summit surface inside the film and outside solid contact per nominal area
        ``a_w(d)`` [1] (:func:`pipeline.physics.isbl.isbl_tables`)
    tau_lub : limiting shear stress of the lubricant [Pa] (``lubricant.shear_stress_mpa``, recon)

    Returns
    -------
    numpy.ndarray
        The lubricant friction stress per nominal area [Pa], the shape of ``wetted_area_fraction``.

    Raises
    ------
    ValueError
        For a negative or non-finite ``tau_lub``.

    References
    ----------
    [VP11], [VEP11] (module docstring); docs/model.md, section "Lubricant friction".
    """
    if not (np.isfinite(tau_lub) and tau_lub >= 0.0):
        raise ValueError(f"lubricant shear stress {tau_lub!r} Pa: expected a finite number >= 0")
    return tau_lub * np.asarray(wetted_area_fraction, dtype=float)


def friction_stress_table(law: str, contact_pressure: np.ndarray, shear_strength_stress: np.ndarray,
                          **parameters: float | None) -> np.ndarray:
    """Friction stress per nominal area [Pa] versus separation for the named law (:data:`FRICTION_LAWS`).

    Parameters
    ----------
    law : a name of :data:`FRICTION_LAWS` (``"shear-strength"``, ``"coefficient"``, ...)
    contact_pressure : contact pressure table ``p_c(d)`` [Pa]
    shear_strength_stress : the ISBL friction-stress table [Pa]: of the law's per-summit form
        (:attr:`FrictionLaw.summit`) or, for a law without one, of the shear-strength law
    parameters : the numbers the law's entry names (``mu``: friction coefficient [1] of ``"coefficient"``)

    Returns
    -------
    numpy.ndarray
        The friction stress per nominal area [Pa] at each separation of the tables.

    Raises
    ------
    ValueError
        For a law not in :data:`FRICTION_LAWS` (the message lists them).

    References
    ----------
    [Bowden50], [Tabor51] (``"shear-strength"``); [VLP09] (the paper's coefficient mu ~ 1.2,
    ``"coefficient"``); docs/model.md, section "Friction".
    """
    return FRICTION_LAWS.lookup(law).behaviour(contact_pressure, shear_strength_stress, **parameters)


def _switched(solid: np.ndarray, lubricant: np.ndarray) -> tuple[np.ndarray, None]:
    return solid + lubricant, None


def _continuous(solid: np.ndarray, lubricant: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return solid, np.asarray(lubricant, dtype=float)


#: How the friction is switched (``contact.friction_switching``; module docstring): the behaviour splits
#: the solid and lubricant stress tables [Pa] into the part switched with the contact criterion and the
#: part acting at every separation (:func:`friction_parts`).
FRICTION_SWITCHING: Registry[Variant] = Registry("contact.friction_switching", {
    "criterion": Variant(behaviour=_switched,
                         summary="the whole friction stress with the contact criterion d < k sigma (the paper's model)",
                         source='docs/model.md, section "Switched and continuous friction"'),
    "continuous": Variant(behaviour=_continuous,
                          summary="the lubricant shear on the wetted summits at every separation, the solid friction "
                                  "with the contact force",
                          source='docs/model.md, section "Switched and continuous friction" [VP11]'),
})


def friction_parts(switching: str, solid: np.ndarray, lubricant: np.ndarray | None
                   ) -> tuple[np.ndarray, np.ndarray | None]:
    """The friction stress per nominal area [Pa] versus separation split by how it is switched: the
    part that acts only in contact (``d < k sigma``, with the contact force) and the part that acts at
    every separation (``None``: none).

    ``"criterion"``: ``(solid + lubricant, None)``, the paper's switched friction (the sum as
    :func:`lubricant_shear_stress` adds it); ``"continuous"``: ``(solid, lubricant)``: the lubricant
    shear on the wetted summits is continuous in the separation, as the wetted area is [VP11]; the
    solid friction follows the contact force (docs/model.md, section "Switched and continuous friction").

    Parameters
    ----------
    switching : one of :data:`FRICTION_SWITCHING`
    solid : the friction-law stress table (:func:`friction_stress_table`) [Pa]
    lubricant : the lubricant-shear stress table (:func:`lubricant_shear_stress`) [Pa], ``None`` when the
        term is off (``lubricant.shear_stress_mpa = 0``)

    Returns
    -------
    (numpy.ndarray, numpy.ndarray or None)
        The switched part [Pa] and the continuous part [Pa] (``None``: none).

    Raises
    ------
    ValueError
        For a rule not in :data:`FRICTION_SWITCHING`.

    References
    ----------
    [VLP09] (the paper's switched contact forces), [VP11] (the lubricant on the wetted summits);
    docs/model.md, section "Switched and continuous friction".
    """
    rule = FRICTION_SWITCHING.lookup(switching).behaviour
    if lubricant is None:
        return solid, None
    return rule(solid, lubricant)
