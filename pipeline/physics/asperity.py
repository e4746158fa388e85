"""Single-asperity contact: Hertz and the Kogut-Etsion elastic-plastic fits.

A spherical summit of radius ``R`` pressed by an interference ``w`` against a rigid flat, composite
modulus ``E'`` and hardness ``H`` of the softer body. All functions are vectorised and take SI units.
This module is the one home of the single-summit laws: :mod:`pipeline.physics.isbl` sums the
per-regime functions (:func:`hertz_load`, :func:`ke_fit`, :func:`plastic_load`, ...) over the summits.

References
----------
.. [KE02] L. Kogut, I. Etsion, "Elastic-plastic contact analysis of a sphere and a rigid flat",
   J. Appl. Mech. 69 (2002) 657-662 (the fits below, and ``w_c``, ``P_c``, ``A_c``).
.. [Johnson85] K. L. Johnson, Contact Mechanics, Cambridge (1985), Hertz: eqs. 4.22-4.23.
"""

from __future__ import annotations

import numpy as np

from .asperity_statistics import ke_hardness_factor

#: Boundaries of the Kogut-Etsion regimes in ``x = w / w_c`` [KE02].
X_ELASTIC = 1.0
X_MID = 6.0
X_PLASTIC = 110.0

#: Kogut-Etsion elastic-plastic fits [KE02] in ``x = w / w_c``, ``(c, e)`` of ``P = c P_c x^e`` (load)
#: and ``A = c A_c x^e`` (area), for ``1 < x <= 6`` and ``6 < x <= 110`` in this order.
KE_LOAD_FITS = ((1.03, 1.425), (1.40, 1.263))
KE_AREA_FITS = ((0.93, 1.136), (0.94, 1.146))


def critical_interference(R: float, E: float, H: float, nu: float) -> float:
    """Onset-of-yield interference ``w_c = (pi K H / (2 E'))^2 R`` [m] [KE02].

    Parameters
    ----------
    R : summit radius [m]
    E : composite modulus E' [Pa]
    H : hardness [Pa]
    nu : Poisson ratio [1] (through ``K = 0.454 + 0.41 nu``)

    Returns
    -------
    float
        The critical interference w_c [m].

    References
    ----------
    [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662 (module docstring); docs/model.md, section
    "Single asperity".
    """
    K = ke_hardness_factor(nu)
    return (np.pi * K * H / (2.0 * E)) ** 2 * R


def critical_load(R: float, E: float, H: float, nu: float) -> float:
    """Critical load ``P_c = (2/3) pi K H R w_c`` [N] [KE02].

    Parameters
    ----------
    R : summit radius [m]
    E : composite modulus E' [Pa]
    H : hardness [Pa]
    nu : Poisson ratio [1]

    Returns
    -------
    float
        The critical load P_c [N].

    References
    ----------
    [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662 (module docstring); docs/model.md, section
    "Single asperity".
    """
    K = ke_hardness_factor(nu)
    return 2.0 / 3.0 * np.pi * K * H * R * critical_interference(R, E, H, nu)


def critical_area(R: float, E: float, H: float, nu: float) -> float:
    """Contact area at the onset of yield ``A_c = pi R w_c`` [m^2] [KE02].

    Parameters
    ----------
    R : summit radius [m]
    E : composite modulus E' [Pa]
    H : hardness [Pa]
    nu : Poisson ratio [1]

    Returns
    -------
    float
        The critical area A_c [m^2].

    References
    ----------
    [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662 (module docstring); docs/model.md, section
    "Single asperity".
    """
    return np.pi * R * critical_interference(R, E, H, nu)


def hertz_load(w: np.ndarray, R: float, E: float) -> np.ndarray:
    """Hertz load ``(4/3) E' sqrt(R) w^1.5`` [N] of a sphere at interference ``w >= 0`` [m] [Johnson85 4.23].

    Parameters
    ----------
    w : interference [m], >= 0
    R : summit radius [m]
    E : composite modulus E' [Pa]

    Returns
    -------
    numpy.ndarray
        The load [N], the shape of ``w``.

    References
    ----------
    [Johnson85] K. L. Johnson, Contact Mechanics (1985), eqs. 4.22-4.23; docs/model.md, section "Single asperity".
    """
    return 4.0 / 3.0 * E * np.sqrt(R) * w**1.5


def hertz_area(w: np.ndarray, R: float) -> np.ndarray:
    """Hertz contact area ``pi R w`` [m^2] at interference ``w >= 0`` [m] [Johnson85 4.22].

    Parameters
    ----------
    w : interference [m], >= 0
    R : summit radius [m]

    Returns
    -------
    numpy.ndarray
        The contact area [m^2], the shape of ``w``.

    References
    ----------
    [Johnson85] K. L. Johnson, Contact Mechanics (1985), eqs. 4.22-4.23; docs/model.md, section "Single asperity".
    """
    return np.pi * R * w


def ke_fit(x: np.ndarray, scale: float, fit: tuple[float, float]) -> np.ndarray:
    """A Kogut-Etsion fit ``c scale x^e`` [KE02] (``fit = (c, e)`` from :data:`KE_LOAD_FITS` with
    ``scale = P_c``, or :data:`KE_AREA_FITS` with ``scale = A_c``) at ``x = w / w_c >= 0``.

    Parameters
    ----------
    x : interference over the critical one, w / w_c [1], >= 0
    scale : P_c [N] (a load fit) or A_c [m^2] (an area fit)
    fit : the pair ``(c, e)`` of the fit [1]

    Returns
    -------
    numpy.ndarray
        The load [N] or area [m^2] (the unit of ``scale``), the shape of ``x``.

    References
    ----------
    [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662 (module docstring); docs/model.md, section
    "Single asperity".
    """
    c, e = fit
    return c * scale * x**e


def plastic_area(w: np.ndarray, R: float) -> np.ndarray:
    """Fully plastic contact area ``2 pi R w`` [m^2] (Abbott-Firestone truncation) [KE02].

    Parameters
    ----------
    w : interference [m], >= 0
    R : summit radius [m]

    Returns
    -------
    numpy.ndarray
        The contact area [m^2], the shape of ``w``.

    References
    ----------
    [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662 (module docstring); docs/model.md, section
    "Single asperity".
    """
    return 2.0 * np.pi * R * w


def plastic_load(w: np.ndarray, R: float, H: float) -> np.ndarray:
    """Fully plastic load ``H 2 pi R w`` [N]: the hardness times :func:`plastic_area` [KE02].

    Parameters
    ----------
    w : interference [m], >= 0
    R : summit radius [m]
    H : hardness [Pa]

    Returns
    -------
    numpy.ndarray
        The load [N], the shape of ``w``.

    References
    ----------
    [KE02] L. Kogut, I. Etsion, J. Appl. Mech. 69 (2002) 657-662 (module docstring); docs/model.md, section
    "Single asperity".
    """
    return H * plastic_area(w, R)


def contact_load(w: np.ndarray, R: float, E: float, H: float, nu: float) -> np.ndarray:
    """Load on one summit [N] versus interference ``w`` [m] (0 for ``w <= 0``).

    Hertz ``(4/3) E' sqrt(R) w^1.5`` for ``x = w/w_c <= 1``; ``1.03 P_c x^1.425`` for ``1 < x <= 6``;
    ``1.40 P_c x^1.263`` for ``6 < x <= 110``; fully plastic ``H 2 pi R w`` beyond [KE02, docs/model.md, section "Single asperity"].
    The fits jump by a few per cent at ``x = 1`` and ``x = 110`` (as published).

    Parameters
    ----------
    w : interference [m] (any sign)
    R : summit radius [m]
    E : composite modulus E' [Pa]
    H : hardness [Pa]
    nu : Poisson ratio [1]

    Returns
    -------
    numpy.ndarray
        The load [N], the shape of ``w``.

    References
    ----------
    [KE02] (the elastic-plastic fits), [Johnson85] (Hertz); docs/model.md, section "Single asperity".
    """
    w = np.asarray(w, dtype=float)
    wc = critical_interference(R, E, H, nu)
    Pc = critical_load(R, E, H, nu)
    wp = np.maximum(w, 0.0)
    x = wp / wc  # not w / wc: np.select evaluates every branch, and (negative x)**1.425 warns
    return np.select(
        [w <= 0, x <= X_ELASTIC, x <= X_MID, x <= X_PLASTIC],
        [0.0, hertz_load(wp, R, E), ke_fit(x, Pc, KE_LOAD_FITS[0]), ke_fit(x, Pc, KE_LOAD_FITS[1])],
        plastic_load(wp, R, H),
    )


def contact_area(w: np.ndarray, R: float, E: float, H: float, nu: float) -> np.ndarray:
    """Real contact area of one summit [m^2] versus interference ``w`` [m] (0 for ``w <= 0``).

    ``pi R w`` (elastic); ``0.93 A_c x^1.136`` and ``0.94 A_c x^1.146`` (elastic-plastic);
    ``2 pi R w`` (fully plastic), with ``A_c = pi R w_c`` [KE02].

    Parameters
    ----------
    w : interference [m] (any sign)
    R : summit radius [m]
    E : composite modulus E' [Pa]
    H : hardness [Pa]
    nu : Poisson ratio [1]

    Returns
    -------
    numpy.ndarray
        The real contact area [m^2], the shape of ``w``.

    References
    ----------
    [KE02] (the elastic-plastic fits), [Johnson85] (Hertz); docs/model.md, section "Single asperity".
    """
    w = np.asarray(w, dtype=float)
    wc = critical_interference(R, E, H, nu)
    Ac = critical_area(R, E, H, nu)
    wp = np.maximum(w, 0.0)
    x = wp / wc  # not w / wc: np.select evaluates every branch, and (negative x)**1.425 warns
    return np.select(
        [w <= 0, x <= X_ELASTIC, x <= X_MID, x <= X_PLASTIC],
        [0.0, hertz_area(wp, R), ke_fit(x, Ac, KE_AREA_FITS[0]), ke_fit(x, Ac, KE_AREA_FITS[1])],
        plastic_area(wp, R),
    )
