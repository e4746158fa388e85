"""Geometry of the TFC protrusion: an ellipsoidal bulge and its nominal contact area.

The bulge is half an ellipsoid with semi-axes ``a`` (sliding direction), ``b`` (across the track)
and height ``delta`` (the protrusion) (docs/model.md, section "Nominal area", [paper]). The nominal contact area is its
section by a plane a depth ``s_n`` above the lowest point.
"""

from __future__ import annotations

import numpy as np


def section_fraction(delta: np.ndarray, s_n: float) -> np.ndarray:
    """``u = s_n / delta`` capped at 1 [1] (``1`` when ``delta = 0``: the whole footprint)."""
    delta = np.asarray(delta, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(delta > 0, np.minimum(s_n / np.where(delta > 0, delta, 1.0), 1.0), 1.0)


def nominal_area(delta: np.ndarray, a: float, b: float, s_n: float) -> np.ndarray:
    """Nominal contact area ``A_n = pi a b (2u - u^2)``, ``u = min(s_n/delta, 1)`` [m^2].

    Section of the ellipsoid ``(x/a)^2 + (y/b)^2 + ((h - delta)/delta)^2 = 1`` at height ``s_n``
    above its apex (docs/model.md, section "Nominal area"). The paper's 62 um^2 at ``delta = 11 nm`` follows for
    ``s_n = 1.56 nm``. For ``u -> 0`` it tends to the paraboloid value ``2 pi a b s_n / delta``.

    Parameters
    ----------
    delta : protrusion [m]
    a, b : semi-axes along and across the sliding direction [m]
    s_n : section depth [m]
    """
    u = section_fraction(delta, s_n)
    return np.pi * a * b * (2.0 * u - u * u)


def effective_radius(delta: np.ndarray, a: float, s_n: float) -> np.ndarray:
    """Radius of the circular arc through the apex and both ends of the section chord [m].

    The half-chord in the sliding direction is ``c = a sqrt(2u - u^2)`` at height
    ``h = min(s_n, delta)``; the arc through ``(0, 0)`` and ``(+-c, h)`` has radius
    ``(c^2 + h^2) / (2h)`` (docs/model.md, section "Nominal area"). As ``u -> 0`` it tends to the apex radius of
    curvature of the ellipse, ``a^2 / delta``. Infinite for ``delta = 0`` (a flat slider).

    Parameters
    ----------
    delta : protrusion [m]
    a : semi-axis along the sliding direction [m]
    s_n : section depth [m]
    """
    delta = np.asarray(delta, dtype=float)
    u = section_fraction(delta, s_n)
    c2 = a * a * (2.0 * u - u * u)
    h = np.minimum(s_n, delta)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(h > 0, (c2 + h * h) / (2.0 * np.where(h > 0, h, 1.0)), np.inf)


def lowest_point_offset(delta: float, a: float, theta: float) -> tuple[float, float]:
    """Where the lowest point of a pitched bulge lies, relative to its apex.

    Pitching the slider by ``theta`` (trailing edge down positive) moves the lowest point of the
    ellipse ``x = a sin(phi)``, ``h = delta (1 - cos(phi))`` to where its slope equals ``theta``:
    ``tan(phi) = a theta / delta``. Exact for the ellipse; for sub-milliradian pitch the height
    change is ``~ -a^2 theta^2 / (2 delta)``, picometres for the paper's bulge (docs/model.md, section "Nominal area").

    Parameters
    ----------
    delta : protrusion [m] (> 0)
    a : semi-axis along sliding [m]
    theta : pitch angle [rad]

    Returns
    -------
    (x_shift [m], dz [m]) : shift of the lowest point along sliding, and its height change
        relative to the apex in the pitched frame (``<= 0``: the lowest point is lower).
    """
    if delta <= 0:
        return 0.0, 0.0
    phi = np.arctan(a * theta / delta)
    x = a * np.sin(phi)
    dz = delta * (1.0 - np.cos(phi)) - theta * x
    return float(x), float(dz)
