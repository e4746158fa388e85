"""Flash temperature of sliding contacts: a uniform circular heat source on a half-space moving past it.

The friction power ``P = Q V`` of a contact is released over its real area. Each micro-contact is a heat
source of radius ``a`` and uniform flux ``q`` that the disk's surface moves under at the speed ``V``; the
slider's side of it is stationary. The surface temperature rise of the body it moves over is a function of
the Peclet number ``Pe = V a / (2 kappa)`` alone once scaled by ``q a / k`` (docs/model.md, section "Flash
temperature"):

* ``Pe -> 0`` (a stationary source, [CJ59] 10.5): the centre rises by ``q a / k`` (the maximum) and the
  source's mean by ``8 q a / (3 pi k)``;
* ``Pe -> inf`` (each surface point heats as a 1-D half-space for its dwell under the source, [Jaeger42]):
  ``T = (2 q / k) sqrt(kappa x / (pi V))`` at ``x`` behind the leading edge, so the maximum (the trailing end
  of the central chord, ``x = 2a``) is ``2 q a / (k sqrt(pi Pe))`` and the mean over the disk
  ``C q a / (k sqrt(Pe))``, ``C = 8 B(1/2, 7/4) / (3 pi^(3/2)) = 0.6885``;
* between: Tian & Kennedy's interpolation [TK94], ``T_max = 2 q a / (k sqrt(pi (1.273 + Pe)))``, which has
  both limits (``1.273 = 4 / pi``); the mean is written in the same form,
  ``T_mean = C q a / (k sqrt(b + Pe))`` with ``b = (3 pi C / 8)^2 = 0.658`` so that it has both of its
  limits too (the form is [TK94]'s; its constant here is derived from the limits, not quoted).

:func:`moving_source_temperature` is the exact quasi-steady solution (the point-source solution of
[Rosenthal46] summed over the disk, [Jaeger42]) that the closed forms are tested against.

The heat divides between the bodies so that their mean temperatures over the source agree (Blok's
postulate [Blok37]): the slider, stationary under the source (``Pe = 0``), takes the fraction
:func:`heat_partition`.

References
----------
[CJ59] H. S. Carslaw, J. C. Jaeger, Conduction of Heat in Solids, 2nd ed., Oxford (1959), section 10.5.
[Jaeger42] J. C. Jaeger, "Moving sources of heat and the temperature at sliding contacts", Proc. R. Soc. N.S.W.
76 (1942) 203-224. [TK94] X. Tian, F. E. Kennedy, "Maximum and average flash temperatures in sliding
contacts", J. Tribol. 116 (1994) 167-174. [Blok37] H. Blok, Proc. Gen. Discussion on Lubrication, IMechE 2
(1937) 222-235. [Rosenthal46] D. Rosenthal, Trans. ASME 68 (1946) 849-866. docs/model.md, section "Flash
temperature".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: ``T_mean sqrt(Pe) k / (q a)`` as ``Pe -> inf``: the 1-D half-space solution averaged over the disk [1],
#: ``8 B(1/2, 7/4) / (3 pi^1.5)`` (B the beta function). Written out: scipy.special's import (~0.2-0.5 s with
#: the numpy modules it pulls) would be paid by every ``hdi`` command, whose stage registry imports this module;
#: tests/physics/test_flash_temperature.py checks it against ``scipy.special.beta`` to the last bit.
MEAN_HIGH_PE = 0.6885457813073166
#: ``T_mean k / (q a)`` at ``Pe = 0``: the stationary uniform circular source's mean rise [CJ59] [1].
MEAN_LOW_PE = 8.0 / (3.0 * np.pi)
#: The mean's offset in ``C / sqrt(b + Pe)`` that gives its stationary limit [1].
MEAN_OFFSET = (MEAN_HIGH_PE / MEAN_LOW_PE) ** 2
#: The maximum's offset in [TK94]'s ``2 / sqrt(pi (b + Pe))``: ``4 / pi`` gives the stationary centre's ``q a / k``.
MAX_OFFSET = 4.0 / np.pi


def peclet(speed: float, radius: float, diffusivity: float) -> float:
    """The Peclet number of a heat source, ``Pe = V a / (2 kappa)`` [1] ([TK94]'s definition).

    Parameters
    ----------
    speed : the sliding speed ``V`` [m/s]; radius : the source's radius ``a`` [m]
    diffusivity : the thermal diffusivity ``kappa`` of the body moving under the source [m^2/s]

    Returns
    -------
    float
        ``Pe`` [1].

    References
    ----------
    [TK94]; docs/model.md, section "Flash temperature".
    """
    return float(speed) * float(radius) / (2.0 * float(diffusivity))


def flash_factor(pe, kind: str = "max"):
    """The surface temperature rise of a uniform circular source over ``q a / k`` [1] at the Peclet number ``pe``.

    ``kind = "max"``: [TK94]'s ``2 / sqrt(pi (4/pi + Pe))``; ``"mean"``: ``C / sqrt(b + Pe)`` (module docstring).

    Parameters
    ----------
    pe : the Peclet number ``V a / (2 kappa)`` [1], >= 0
    kind : ``"max"`` or ``"mean"``

    Returns
    -------
    float or numpy.ndarray
        ``T k / (q a)`` [1].

    References
    ----------
    [CJ59], [Jaeger42], [TK94]; docs/model.md, section "Flash temperature".
    """
    pe = np.asarray(pe, dtype=float)
    if np.any(pe < 0):
        raise ValueError(f"flash_factor: the Peclet number must be >= 0 (got {pe})")
    if kind == "max":
        out = 2.0 / np.sqrt(np.pi * (MAX_OFFSET + pe))
    elif kind == "mean":
        out = MEAN_HIGH_PE / np.sqrt(MEAN_OFFSET + pe)
    else:
        raise ValueError(f"flash_factor: kind must be 'max' or 'mean' (got {kind!r})")
    return float(out) if out.ndim == 0 else out


def moving_source_temperature(x: float, y: float, pe: float, nodes: int = 2000) -> float:
    """The exact quasi-steady surface temperature rise over ``q a / k`` [1] at ``(x, y)`` (in units of ``a``,
    the source's centre at the origin, the body moving along ``-x`` under it) of the uniform circular source.

    The point source's solution ``T = P / (2 pi k r) exp(-V (r + xi) / (2 kappa))`` ([Rosenthal46]; ``xi``
    the coordinate along the motion of the source relative to the body, from the source) summed over the
    disk in polar coordinates about the field point, whose radial integral is closed:
    ``T k / (q a) = (1 / 2 pi) int_0^2pi (1 - exp(-beta R)) / beta dtheta``, ``beta = Pe (1 - cos theta)``,
    ``R(theta)`` the distance to the disk's edge along ``theta`` (a field point inside the disk). The
    ``theta`` integral by the midpoint rule on ``nodes`` points (periodic: spectrally accurate where smooth).

    Parameters
    ----------
    x, y : the field point [a], inside the disk (``x^2 + y^2 <= 1``); ``x > 0`` ahead in the source's motion
        relative to the body (the body's surface enters at ``x = 1`` and leaves, hottest, at ``x = -1``)
    pe : the Peclet number [1]; nodes : quadrature points in ``theta``

    Returns
    -------
    float
        ``T k / (q a)`` [1].

    References
    ----------
    [Jaeger42], [Rosenthal46]; docs/model.md, section "Flash temperature".
    """
    if x * x + y * y > 1.0 + 1e-12:
        raise ValueError("moving_source_temperature: the field point must lie inside the source")
    th = (np.arange(nodes) + 0.5) * (2.0 * np.pi / nodes)
    c, s = np.cos(th), np.sin(th)
    # distance from (x, y) along (c, s) to the unit circle: R^2 + 2 R (x c + y s) + x^2 + y^2 - 1 = 0
    bx = x * c + y * s
    R = -bx + np.sqrt(np.maximum(bx * bx - (x * x + y * y - 1.0), 0.0))
    # the source point S = (x, y) + R (c, s); the field point lies at xi = x - x_S = -R c from it along the
    # source's motion (+x), so the exponent -V (r + xi) / (2 kappa) is -Pe R (1 - c) in units of a
    b = pe * (1.0 - c)
    with np.errstate(invalid="ignore", divide="ignore"):
        term = np.where(b * R > 1e-12, -np.expm1(-b * R) / np.where(b > 0, b, 1.0), R)
    return float(term.mean())


def heat_partition(k_slider: float, k_disk: float, pe_disk: float) -> float:
    """The fraction [1] of a contact's friction heat that flows into the slider: the mean temperatures of the
    two bodies over the source equal (Blok's postulate [Blok37]), the slider stationary under it (``Pe = 0``),
    the disk moving at ``pe_disk``: ``beta = (F_d / k_d) / (F_s / k_s + F_d / k_d)``, ``F`` the mean factors of
    :func:`flash_factor`.

    Parameters
    ----------
    k_slider, k_disk : the thermal conductivities [W/(m K)]; pe_disk : the disk's Peclet number [1]

    Returns
    -------
    float
        ``beta`` [1], in (0, 1).

    References
    ----------
    [Blok37], [TK94]; docs/model.md, section "Flash temperature".
    """
    fs = flash_factor(0.0, "mean") / k_slider
    fd = flash_factor(pe_disk, "mean") / k_disk
    return float(fd / (fs + fd))


def contact_temperature(power: float, area: float, count: float, speed: float, k_slider: float, k_disk: float,
                        diffusivity_disk: float) -> dict[str, float]:
    """The temperature rise of a sliding contact that releases the friction power ``power`` over ``count``
    equal circular spots of total area ``area`` (each of radius ``a = sqrt(area / (pi count))``, flux
    ``q = power / area``): the heat partition (:func:`heat_partition`) and the slider's maximum rise
    ``beta q a F_max(0) / k_s`` (stationary source), equal by construction to the disk's mean at the same flux.

    Parameters
    ----------
    power : the friction power ``Q V`` [W]; area : the spots' total area [m^2]; count : their number [1]
    speed : the disk's speed [m/s]; k_slider, k_disk : conductivities [W/(m K)]
    diffusivity_disk : the disk's thermal diffusivity [m^2/s]

    Returns
    -------
    dict
        ``temperature`` [K] (the maximum rise), ``mean_temperature`` [K], ``partition`` [1] (slider's
        share), ``peclet`` [1] (the disk's), ``radius`` [m] (of one spot); NaN without power, area or spots.

    References
    ----------
    [TK94], [Blok37]; docs/model.md, section "Flash temperature".
    """
    if not (power > 0 and area > 0 and count > 0):
        return {"temperature": np.nan, "mean_temperature": np.nan, "partition": np.nan, "peclet": np.nan,
                "radius": np.nan}
    a = float(np.sqrt(area / (np.pi * count)))
    q = power / area
    pe = peclet(speed, a, diffusivity_disk)
    b = heat_partition(k_slider, k_disk, pe)
    scale = b * q * a / k_slider
    return {"temperature": scale * flash_factor(0.0, "max"), "mean_temperature": scale * flash_factor(0.0, "mean"),
            "partition": b, "peclet": pe, "radius": a}


@dataclass(frozen=True)
class Thermal:
    """Thermal properties of the contact for its flash temperature (docs/model.md, section "Flash temperature").

    Attributes
    ----------
    k_slider : the slider's conductivity [W/(m K)] (AlTiC, 20 [recon])
    k_disk : the disk's conductivity [W/(m K)] (a glass substrate, 1.1 [recon]; metal underlayers raise it)
    diffusivity_disk : the disk's diffusivity [m^2/s] (glass, 5.4e-7 [recon])
    """

    k_slider: float = 20.0
    k_disk: float = 1.1
    diffusivity_disk: float = 5.4e-7
