"""Asperity statistics of a Gaussian rough surface (McCool / Nayak) and the plasticity index.

All lengths in SI inside the functions unless the name says otherwise; docstrings give units.

References
----------
.. [Nayak71] P. R. Nayak, "Random process model of rough surfaces", J. Lubr. Technol. 93 (1971) 398-407.
.. [McCool86] J. I. McCool, "Comparison of models for the contact of rough surfaces", Wear 107 (1986) 37-60.
.. [GW66] J. A. Greenwood, J. B. P. Williamson, Proc. R. Soc. Lond. A 295 (1966) 300-319.
.. [KE03] L. Kogut, I. Etsion, "A finite element based elastic-plastic model for the contact of rough
   surfaces", Tribol. Trans. 46 (2003) 383-390 (plasticity index in the CEB/KE form).
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np

#: Lower bound of the bandwidth parameter for which McCool's summit-height variance is positive.
ALPHA_MIN = 0.8968


def moments_from_statistics(sigma: float, eta: float, R: float) -> tuple[float, float, float]:
    """Profile spectral moments that reproduce ``(sigma, eta, R)`` [McCool86].

    Inverts ``eta = m4/(6 pi sqrt(3) m2)`` and ``R = 0.375 sqrt(pi/m4)``.

    Parameters
    ----------
    sigma : rms height [m]
    eta : summit density [m^-2]
    R : mean summit radius [m]

    Returns
    -------
    m0 [m^2], m2 [1], m4 [m^-2]

    References
    ----------
    [McCool86] J. I. McCool, Wear 107 (1986) 37-60; [Nayak71]; docs/model.md, section "Asperity statistics".
    """
    m4 = np.pi * (0.375 / R) ** 2
    m2 = m4 / (6.0 * np.pi * np.sqrt(3.0) * eta)
    return sigma**2, m2, m4


def statistics_from_moments(m0: float, m2: float, m4: float) -> dict[str, float]:
    """Summit density, radius and bandwidth from profile moments [Nayak71, McCool86].

    ``eta = m4 / (6 pi sqrt(3) m2)``, ``R = 0.375 sqrt(pi/m4)``, ``alpha = m0 m4 / m2^2``.

    Parameters
    ----------
    m0 : height variance [m^2]
    m2 : slope variance [1]
    m4 : curvature variance [m^-2]

    Returns
    -------
    dict with ``sigma`` [m], ``eta`` [m^-2], ``R`` [m], ``alpha`` [1]

    References
    ----------
    [McCool86] J. I. McCool, Wear 107 (1986) 37-60; [Nayak71]; docs/model.md, section "Asperity statistics".
    """
    eta = m4 / (6.0 * np.pi * np.sqrt(3.0) * m2)
    R = 0.375 * np.sqrt(np.pi / m4)
    return {"sigma": float(np.sqrt(m0)), "eta": float(eta), "R": float(R), "alpha": float(m0 * m4 / m2**2)}


def bandwidth_alpha(sigma: float, eta: float, R: float) -> float:
    """Nayak bandwidth parameter ``alpha = 2412.74 (sigma eta R)^2`` [McCool86] [1].

    Parameters
    ----------
    sigma : rms height [m]
    eta : summit density [m^-2]
    R : summit radius [m]

    Returns
    -------
    float
        The bandwidth alpha [1].

    References
    ----------
    [McCool86] J. I. McCool, Wear 107 (1986) 37-60; [Nayak71]; docs/model.md, section "Asperity statistics".
    """
    return 2412.74 * (sigma * eta * R) ** 2


def summit_sigma(sigma: float, eta: float, R: float) -> float:
    """Standard deviation of summit heights [m] [McCool86].

    ``sigma_s = sqrt(sigma^2 - 3.717e-4 / (eta R)^2)``; needs ``alpha > 0.8968``.

    Raises
    ------
    ValueError
        When ``alpha <= 0.8968`` (the summit-height variance would be negative): the surface is
        outside the validity of McCool's relations.

    Parameters
    ----------
    sigma : rms height of the combined surface [m]
    eta : summit density [m^-2]
    R : summit radius [m]

    Returns
    -------
    float
        The summit-height standard deviation sigma_s [m].

    References
    ----------
    [McCool86] J. I. McCool, Wear 107 (1986) 37-60; [Nayak71]; docs/model.md, section "Asperity statistics".
    """
    alpha = bandwidth_alpha(sigma, eta, R)
    radicand = sigma**2 - 3.717e-4 / (eta * R) ** 2
    # (the exact limit of these constants is alpha = 3.717e-4 * 2412.74 = 0.8968155; test the radicand)
    if not (alpha > ALPHA_MIN and radicand > 0):
        raise ValueError(f"bandwidth alpha = {alpha:.7g} <= {3.717e-4 * 2412.74:.7g}: McCool's summit statistics "
                         f"need alpha > {ALPHA_MIN} (sigma={sigma:.3g} m, eta={eta:.3g} m^-2, R={R:.3g} m)")
    return float(np.sqrt(radicand))


def summit_offset(sigma: float, eta: float, R: float) -> float:
    """Distance between the mean of surface heights and the mean of summit heights ``y_s`` [m].

    ``y_s = 4 sigma / sqrt(pi alpha)`` [McCool86].

    Parameters
    ----------
    sigma : rms height of the combined surface [m]
    eta : summit density [m^-2]
    R : summit radius [m]

    Returns
    -------
    float
        The summit offset y_s [m] (the mean of summit heights lies y_s above the mean of surface heights).

    References
    ----------
    [McCool86] J. I. McCool, Wear 107 (1986) 37-60; [Nayak71]; docs/model.md, section "Asperity statistics".
    """
    return float(4.0 * sigma / np.sqrt(np.pi * bandwidth_alpha(sigma, eta, R)))


def composite_modulus(E1: float, E2: float, nu1: float, nu2: float | None = None) -> float:
    """Composite (Hertz) modulus ``1/E' = (1-nu1^2)/E1 + (1-nu2^2)/E2`` [any pressure unit].

    docs/model.md, section "Asperity statistics" (Johnson, Contact Mechanics, 1985, eq. 4.22).

    Parameters
    ----------
    E1, E2 : Young's moduli of the two bodies [Pa] (any pressure unit, the same for both)
    nu1 : Poisson ratio of the first body [1]
    nu2 : Poisson ratio of the second body [1] (``None``: ``nu1``)

    Returns
    -------
    float
        The composite modulus E' [Pa] (the unit of ``E1``, ``E2``).

    References
    ----------
    [Johnson85] K. L. Johnson, Contact Mechanics (1985), eq. 4.22; docs/model.md, section "Asperity statistics".
    """
    nu2 = nu1 if nu2 is None else nu2
    return 1.0 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)


def ke_hardness_factor(nu: float) -> float:
    """Hardness coefficient ``K = 0.454 + 0.41 nu`` [1] (Chang-Etsion-Bogy 1987; Kogut-Etsion 2002).

    Parameters
    ----------
    nu : Poisson ratio of the softer body [1]

    Returns
    -------
    float
        The factor K [1].

    References
    ----------
    [CEB87] W. R. Chang, I. Etsion, D. B. Bogy, J. Tribol. 109 (1987) 257-263; [KE02]; docs/model.md,
    section "Single asperity".
    """
    return 0.454 + 0.41 * nu


def plasticity_index_gw(E: float, H: float, sigma_s: float, R: float) -> float:
    """Greenwood-Williamson plasticity index ``psi = (E'/H) sqrt(sigma_s/R)`` [GW66] [1].

    Parameters
    ----------
    E : composite modulus E' [Pa]
    H : hardness [Pa]
    sigma_s : summit-height standard deviation [m]
    R : summit radius [m]

    Returns
    -------
    float
        The plasticity index psi [1].

    References
    ----------
    [GW66] J. A. Greenwood, J. B. P. Williamson, Proc. R. Soc. Lond. A 295 (1966) 300-319; docs/model.md,
    section "Plasticity index".
    """
    return E / H * np.sqrt(sigma_s / R)


def plasticity_index_ke(E: float, H: float, sigma_s: float, R: float, nu: float) -> float:
    """CEB / Kogut-Etsion plasticity index ``psi = (2E'/(pi K H)) sqrt(sigma_s/R)`` [KE03] [1].

    Equals ``sqrt(sigma_s / w_c)`` with the critical interference ``w_c`` of Kogut-Etsion 2002.

    Parameters
    ----------
    E : composite modulus E' [Pa]
    H : hardness [Pa]
    sigma_s : summit-height standard deviation [m]
    R : summit radius [m]
    nu : Poisson ratio [1]

    Returns
    -------
    float
        The plasticity index psi [1].

    References
    ----------
    [KE03] L. Kogut, I. Etsion, Tribol. Trans. 46 (2003) 383-390; [CEB87]; docs/model.md, section
    "Plasticity index".
    """
    return 2.0 * E / (np.pi * ke_hardness_factor(nu) * H) * np.sqrt(sigma_s / R)


def hardness_from_plasticity_gw(psi: float, E: float, sigma_s: float, R: float) -> float:
    """Hardness [Pa] that gives the GW plasticity index ``psi`` (inverse of :func:`plasticity_index_gw`).

    Parameters
    ----------
    psi : GW plasticity index [1]
    E : composite modulus E' [Pa]
    sigma_s : summit-height standard deviation [m]
    R : summit radius [m]

    Returns
    -------
    float
        The hardness H [Pa].

    References
    ----------
    [GW66]; docs/model.md, section "Plasticity index" (the paper's psi = 0.52 sets H).
    """
    return E / psi * np.sqrt(sigma_s / R)


def contact_probabilities(k: float) -> tuple[float, float]:
    """Two-sided ``P(|z| > k sigma) = 2 Q(|k|)`` and one-sided ``P(z > k sigma) = Q(k)`` [1].

    ``z`` Gaussian with rms ``sigma``, ``Q`` the standard normal tail. The two-sided value comes
    first: it is the paper's convention (docs/model.md, section "Contact criterion": its "3 sigma = 0.3 %" is ``2 Q(3) = 0.27 %``,
    so its 32.8 % means ``k = 0.978``).

    Parameters
    ----------
    k : the contact criterion constant [1] (contact where ``d < k sigma``)

    Returns
    -------
    (float, float)
        The two-sided and the one-sided contact probability [1].

    References
    ----------
    [VLP09] (the calibrated 32.8 %, "3 sigma = 0.3 %"); docs/model.md, section "Contact criterion".
    """
    # Q(k) = erfc(k / sqrt 2) / 2 (= scipy.stats.norm.sf, without its ~1 s import on every run)
    return float(math.erfc(abs(k) / math.sqrt(2.0))), float(0.5 * math.erfc(k / math.sqrt(2.0)))


#: The smallest physical contact-criterion constant [1]: ``d < k sigma`` with ``k < 0`` switches contact on
#: only once the separation is below the mean plane of the heights, where more than half of them reach
#: the other surface (one-sided ``P(z > k sigma) = Q(k) > 0.5``): the surfaces are then already in contact
#: over most of the nominal area, not at its first summits. A calibrated ``k`` below it is refused
#: (:func:`unphysical_k`; docs/model.md, section "Contact criterion").
K_PHYSICAL_MIN = 0.0


def unphysical_k(k: float) -> str | None:
    """Why ``k`` [1] is no physical contact-criterion constant, or ``None`` when it is (``k >=``
    :data:`K_PHYSICAL_MIN`, one-sided contact probability ``Q(k) <= 0.5``); a NaN (no k) is not judged.

    Parameters
    ----------
    k : the contact-criterion constant of ``d < k sigma`` [1]

    Returns
    -------
    str or None
        The reason, with k [1] and its one-sided contact probability [1]; ``None`` for a physical k.

    References
    ----------
    docs/model.md, section "Contact criterion" (the physical range of k and why).
    """
    if not k < K_PHYSICAL_MIN:
        return None
    p1 = contact_probabilities(k)[1]
    return (f"k = {k:.4f} is below {K_PHYSICAL_MIN:g}: its one-sided contact probability P(z > k sigma) = "
            f"{p1:.3f} is above {contact_probabilities(K_PHYSICAL_MIN)[1]:g} (more than half of the heights "
            f"touching before contact is declared)")


def k_from_probability(probability: float) -> float:
    """Criterion constant ``k >= 0`` [1] whose two-sided contact probability ``2 Q(k)`` is ``probability``.

    The inverse of the first value of :func:`contact_probabilities` (docs/model.md, section "Contact criterion"); 0.328 gives 0.978.

    Parameters
    ----------
    probability : two-sided contact probability [1], in (0, 1)

    Returns
    -------
    float
        The criterion constant k [1], >= 0.

    Raises
    ------
    ValueError
        For a probability outside (0, 1).

    References
    ----------
    [VLP09] (the calibrated 32.8 %); docs/model.md, section "Contact criterion".
    """
    if not 0.0 < probability < 1.0:
        raise ValueError(f"contact probability {probability}: expected a number in (0, 1)")
    # = scipy.stats.norm.isf(probability / 2) (Wichura's AS241 in the standard library, ~1e-16)
    return float(-NormalDist().inv_cdf(0.5 * probability))


def explicit_statistics(sigma: float, summit_radius: float, summit_density: float) -> dict[str, float]:
    """Summit statistics [SI] of a surface given by ``sigma`` [m], ``R`` [m] and ``eta`` [m^-2] (the
    scene's ``[roughness]`` keys in SI): ``sigma``, ``sigma_s``, ``y_s``, ``R`` [m], ``eta`` [m^-2], ``alpha`` [1]
    by McCool's relations (:func:`summit_sigma`, :func:`summit_offset`, :func:`bandwidth_alpha`; docs/model.md, section "Asperity statistics").

    Parameters
    ----------
    sigma : combined rms roughness [m]
    summit_radius : summit radius [m]
    summit_density : summit density [m^-2]

    Returns
    -------
    dict
        ``sigma``, ``sigma_s``, ``y_s``, ``R`` [m], ``eta`` [m^-2], ``alpha`` [1].

    Raises
    ------
    ValueError
        Where McCool's relations do not hold (:func:`summit_sigma`).

    References
    ----------
    [McCool86]; docs/model.md, section "Asperity statistics".
    """
    R, eta = summit_radius, summit_density
    return {"sigma": sigma, "sigma_s": summit_sigma(sigma, eta, R), "y_s": summit_offset(sigma, eta, R),
            "R": R, "eta": eta, "alpha": bandwidth_alpha(sigma, eta, R)}
