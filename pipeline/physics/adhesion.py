"""Single-summit adhesion: Lennard-Jones surface law outside the lubricant, meniscus inside.

References
----------
.. [Israelachvili] J. N. Israelachvili, Intermolecular and Surface Forces, 3rd ed. (2011): the
   Lennard-Jones 3-9 surface interaction and the Derjaguin approximation.
.. [Stanley90] H. M. Stanley, I. Etsion, D. B. Bogy, "Adhesion of contacting rough surfaces in the
   presence of sub-boundary lubrication", J. Tribol. 112 (1990) 98-104 (the SBL model).
.. [CML] UC Berkeley Computer Mechanics Laboratory, flying-touchdown (ISBL) code documentation: the
   sub-boundary-lubrication adhesion tables used as the external check of docs/model.md, section "Adhesion".
"""

from __future__ import annotations

import numpy as np


def meniscus_force(R: float, dgamma: float) -> float:
    """Adhesive force of a summit wetted by the lubricant, ``2 pi R dgamma`` [N] [Stanley90].

    Parameters
    ----------
    R : summit radius [m]
    dgamma : work of adhesion [J/m^2]

    Returns
    -------
    float
        The meniscus force [N] (attractive, positive).

    References
    ----------
    [Stanley90] H. M. Stanley, I. Etsion, D. B. Bogy, J. Tribol. 112 (1990) 98-104 (module docstring;
    docs/model.md, section "Adhesion").
    """
    return 2.0 * np.pi * R * dgamma


def lennard_jones_force(s: np.ndarray, R: float, dgamma: float, eps: float) -> np.ndarray:
    """Attractive force [N] of a summit at gap ``s`` [m] (gap measured from the lubricant surface + eps).

    ``F = (8/3) pi dgamma R [(eps/s)^2 - (1/4)(eps/s)^8]`` (LJ 3-9 surface law with the Derjaguin
    approximation, [Israelachvili] ch. 13; form of [Stanley90]). At ``s = eps`` it equals the meniscus
    value ``2 pi R dgamma``: the two join continuously. For ``s < eps`` (not reached by the ISBL
    integrals) the gap is clamped to ``eps`` so the repulsive ``s^-8`` term can never overflow.

    Parameters
    ----------
    s : gap ``d - t - z + eps`` [m]
    R : summit radius [m]
    dgamma : work of adhesion [J/m^2]
    eps : intermolecular distance [m]

    Returns
    -------
    numpy.ndarray
        The force [N] at each gap (attractive, positive), the shape of ``s``.

    References
    ----------
    [Israelachvili] J. N. Israelachvili, Intermolecular and Surface Forces, 3rd ed. (2011), ch. 13;
    [Stanley90] (module docstring); docs/model.md, section "Adhesion".
    """
    r = eps / np.maximum(np.asarray(s, dtype=float), eps)
    r2 = r * r
    return 8.0 / 3.0 * np.pi * dgamma * R * (r2 - 0.25 * r2**4)


def penetration_fraction(penetration: np.ndarray, t: float) -> np.ndarray:
    """How far a summit has pushed through the bonded lubricant layer, ``clip(p / t, 0, 1)`` [1].

    ``p = z - (d - t)`` [m] is the summit's penetration below the lubricant surface (``z`` its height,
    ``d`` the separation, ``t`` [m] the bonded thickness): 0 at the lubricant surface, 1 at the solid and
    beyond (docs/model.md, section "Adhesion rising with penetration"). A film of zero thickness is a step
    at the solid, ``p > 0``.

    Parameters
    ----------
    penetration : ``z - (d - t)`` [m]
    t : bonded lubricant thickness [m], >= 0

    Returns
    -------
    numpy.ndarray
        The fraction of the layer penetrated [1], in [0, 1], the shape of ``penetration``.

    References
    ----------
    docs/model.md, section "Adhesion rising with penetration" (the sources: Vakis & Polycarpou, Tribol. Lett. 45
    (2012) 37-48, and Brunner et al., Tribol. Lett. 40 (2010)).
    """
    p = np.asarray(penetration, dtype=float)
    if t <= 0.0:
        return (p > 0.0).astype(float)
    return np.clip(p / t, 0.0, 1.0)


def penetration_work_of_adhesion(penetration: np.ndarray, t: float, dgamma: float, dgamma_solid: float) -> np.ndarray:
    """Work of adhesion [J/m^2] of a summit that penetrates the bonded lubricant layer.

    ``W(p) = dgamma + (dgamma_solid - dgamma) clip(p / t, 0, 1)``: the lubricant's value at the film surface,
    rising (or falling) linearly across the bonded thickness to the solid value at solid contact, then constant
    [VP11, VP13: the bonded lubricant as a semi-solid layer whose surface energy varies with penetration;
    Brunner10: the adhesion across a molecularly thin PFPE film is linear in the film's surface energy, which
    rises towards the carbon's as the film thins].

    Parameters
    ----------
    penetration : ``z - (d - t)`` [m] (:func:`penetration_fraction`)
    t : bonded lubricant thickness [m]
    dgamma : work of adhesion of the lubricant [J/m^2] (the ISBL's ``dgamma``)
    dgamma_solid : work of adhesion at solid contact through the layer [J/m^2]

    Returns
    -------
    numpy.ndarray
        The work of adhesion W [J/m^2], the shape of ``penetration``.

    References
    ----------
    .. [VP11] A. I. Vakis, A. A. Polycarpou, "Modeling sliding contact of rough surfaces with molecularly thin
       lubricants", Tribol. Lett. 45 (2012) 37-48.
    .. [VP13] A. I. Vakis, A. A. Polycarpou, Tribol. Lett. (2013): the continuum model of the same group with a
       semi-solid bonded layer (volume and pages not verified here).
    .. [Brunner10] R. Brunner, G. W. Tyndall, R. J. Waltman, F. E. Talke, "Adhesion between surfaces separated by
       molecularly thin perfluoropolyether films", Tribol. Lett. 40(1) (2010).
    """
    return dgamma + (dgamma_solid - dgamma) * penetration_fraction(penetration, t)
