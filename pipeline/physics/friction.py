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

Switched and continuous friction (``contact.friction_switching``, :data:`FRICTION_SWITCHING`; docs/model.md,
section "Switched and continuous friction"). ``"criterion"`` (the default, the paper's model): the whole
friction stress acts while the contact criterion ``d < k sigma`` holds and is off otherwise, like the
contact pressure. ``"continuous"``: the solid friction (the law above) still follows the contact force,
which the criterion switches, but the lubricant shear ``tau_lub a_w(d)`` acts on the wetted summits
wherever they are wetted, a continuous function of ``d`` as ``a_w`` is [VP11]: the criterion is a
threshold of the contact model, not of the lubricant film, which the summits reach before they touch
(:func:`friction_parts`).

A third law, Kogut & Etsion's (2004) static friction of a summit at the inception of sliding, is not
offered: it gives the largest tangential load a pre-loaded stationary contact sustains, with its
coefficient defined against the external normal load, while the slider here slides continuously and
the external load at the interface is negative (attractive) in light contact, so that coefficient is
undefined there (docs/model.md, section "Lubricant friction").
"""

from __future__ import annotations

import numpy as np

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


def _shear_strength_table(contact_pressure: np.ndarray, shear_strength_stress: np.ndarray) -> np.ndarray:
    return shear_strength_stress


def _coefficient_table(contact_pressure: np.ndarray, shear_strength_stress: np.ndarray, mu: float | None) -> np.ndarray:
    if mu is None or not mu >= 0.0:
        raise ValueError(f"the 'coefficient' friction law needs contact.friction_coefficient >= 0 (got {mu})")
    return mu * np.asarray(contact_pressure, dtype=float)


#: Friction laws a scene may name (``contact.friction_law``): the behaviour is a function of the contact
#: pressure table [Pa] and the shear-strength friction-stress table of the ISBL integrals [Pa], with the
#: entry's ``parameters`` as keywords, returning the friction stress per nominal area [Pa] versus separation.
FRICTION_LAWS: Registry[Variant] = Registry("contact.friction_law", {
    "shear-strength": Variant(behaviour=_shear_strength_table,
                              summary="tau = eta int tau_y A phi dz, tau_y = H / (2.8 sqrt 3): sliding at the shear "
                                      "strength of the softer body",
                              source='docs/model.md, section "Friction" [Tabor51, Bowden50]'),
    "coefficient": Variant(behaviour=_coefficient_table, parameters=(("mu", "contact.friction_coefficient"),),
                           summary="tau = mu p_c: a constant coefficient (Amontons) with contact.friction_coefficient",
                           source='docs/model.md, section "Friction"'),
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
    law : a name of :data:`FRICTION_LAWS` (``"shear-strength"``, ``"coefficient"``)
    contact_pressure : contact pressure table ``p_c(d)`` [Pa]
    shear_strength_stress : the ISBL friction-stress table of the shear-strength law [Pa]
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
