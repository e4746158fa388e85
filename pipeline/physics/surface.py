"""Asperity statistics of sampled height maps: the two routes of docs/model.md, section "Asperity statistics".

Pure functions on numbers: the moments and heights of a map come in as floats and arrays; reading an
AFM file, picking its height channel and detrending it is :mod:`pipeline.model.afm_scan`.
Everything here works in nanometres: heights and lateral sizes [nm], slopes [1], curvatures [nm^-1],
summit densities [nm^-2]. The stage (``pipeline.stages.roughness``) converts to the dataset's units.

A height map is summarised by two independent routes:

* **spectral** (Nayak 1971, McCool 1986): profile moments ``m0, m2, m4`` (variance of height, slope and
  curvature along a profile) give ``eta``, ``R``, ``alpha``, ``sigma_s`` and ``y_s`` through
  :mod:`pipeline.physics.asperity_statistics`;
* **summits** (Greenwood-Williamson 1966, direct count): 8-neighbour local maxima of the sampled map, their
  curvature from the 5-point Laplacian, their heights.

The two agree only for a Gaussian, finely sampled, noise-free surface: the summit count depends on the
sampling interval and on noise, the spectral route on the high-frequency cut-off of ``m2`` and ``m4``.
Both results are reported, with the pixel size.

Surfaces combine (disk + TFC against a smooth flat, docs/model.md, section "Asperity statistics") by adding spectral moments, hence
``sigma^2 = sigma_1^2 + sigma_2^2``; :func:`combine` does that.

References
----------
.. [Nayak71] P. R. Nayak, "Random process model of rough surfaces", J. Lubr. Technol. 93 (1971) 398-407.
.. [McCool86] J. I. McCool, "Comparison of models for the contact of rough surfaces", Wear 107 (1986) 37-60.
.. [GW66] J. A. Greenwood, J. B. P. Williamson, Proc. R. Soc. Lond. A 295 (1966) 300-319.
.. [JJP17] T. D. B. Jacobs, T. Junge, L. Pastewka, "Quantitative characterization of surface topography
   using spectral analysis", Surf. Topogr.: Metrol. Prop. 5 (2017) 013001 (SurfaceTopography).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import Iterable, Sequence

import numpy as np

from . import asperity_statistics as st
from ..units import NM_IN_UM, PER_NM2_IN_PER_UM2


class SurfaceWarning(UserWarning):
    """A surface statistic is unreliable (routes disagree, McCool's relations out of range, no summits)."""


# --------------------------------------------------------------------------------------------------
# Bounds of a sampled height map
# --------------------------------------------------------------------------------------------------

#: Largest magnitude of a height of a map [nm]: 100 um, beyond the z range of any AFM (about 5-20 um) and the
#: roughness scans of a profilometer; heights of 1e80 nm overflowed the moments, 3e38 nm gave statistics.
MAX_HEIGHT_NM = 1e5
#: Smallest rms height of a detrended map [nm]: 1e-3 nm, a thousandth of an atomic spacing and far below the
#: noise floor of any instrument (~0.01-0.05 nm): a flatter map (constant or planar heights) has no asperities.
MIN_RMS_NM = 1e-3
#: Range of a map's lateral pixel size [nm]: from 1e-3 nm (a thousandth of an atomic spacing; a lateral size
#: of 1e-30 um gave summit densities of 1e61 um^-2) to 1e6 nm (1 mm, far coarser than any roughness scan).
PIXEL_SIZE_BOUNDS_NM = (1e-3, 1e6)
#: Largest lateral size of a map [nm]: 1e8 nm = 100 mm, the diameter of a 3.5-inch disk.
MAX_SIZE_NM = 1e8


def sampling_error(physical_sizes: Sequence[float], nb_grid_pts: Sequence[int]) -> str | None:
    """What is wrong with a map's lateral sampling, or ``None``: positive finite sizes at most
    :data:`MAX_SIZE_NM` and pixel sizes within :data:`PIXEL_SIZE_BOUNDS_NM`.

    Parameters
    ----------
    physical_sizes : the map's lateral sizes ``(Lx, Ly)`` [nm]
    nb_grid_pts : its grid points ``(nx, ny)`` [1]

    Returns
    -------
    str or None
        The reason, with the sizes [nm] and pixel sizes [nm] it found; ``None`` when the sampling is physical.

    References
    ----------
    docs/model.md, section "Asperity statistics" (the bounds of a map and why each holds).
    """
    sizes = [float(v) for v in physical_sizes]
    shown = " x ".join(f"{v:.4g}" for v in sizes)
    if not all(math.isfinite(v) and v > 0 for v in sizes):
        return f"lateral size {shown} nm: expected positive finite sizes"
    if max(sizes) > MAX_SIZE_NM:
        return f"lateral size {shown} nm: expected at most {MAX_SIZE_NM:g} nm (100 mm, a disk's diameter)"
    lo, hi = PIXEL_SIZE_BOUNDS_NM
    pixels = [v / n for v, n in zip(sizes, nb_grid_pts)]
    bad = [v for v in pixels if not lo <= v <= hi]
    if bad:
        return (f"pixel size {bad[0]:.4g} nm (lateral size {shown} nm over {' x '.join(map(str, nb_grid_pts))} "
                f"points): expected {lo:g} to {hi:g} nm")
    return None


def heights_error(heights: np.ndarray) -> str | None:
    """What is wrong with a map's heights [nm] (NaN where undefined), or ``None``: some defined, every
    defined one of magnitude at most :data:`MAX_HEIGHT_NM`.

    Parameters
    ----------
    heights : the map's heights [nm], NaN where undefined

    Returns
    -------
    str or None
        The reason, with the largest height [nm] it found; ``None`` when the heights are physical.

    References
    ----------
    docs/model.md, section "Asperity statistics" (the bounds of a map and why each holds).
    """
    h = np.asarray(heights, dtype=float)
    defined = h[~np.isnan(h)]
    if defined.size == 0:
        return "every height is undefined: expected a measured height map"
    top = float(np.max(np.abs(defined)))
    if not top <= MAX_HEIGHT_NM:
        return f"heights reach {top:.4g} nm: expected heights within +-{MAX_HEIGHT_NM:g} nm (100 um, any AFM's z range)"
    return None


def roughness_error(rms: float) -> str | None:
    """What is wrong with the rms height [nm] of a detrended map, or ``None``: at least :data:`MIN_RMS_NM`.

    Parameters
    ----------
    rms : rms height of the detrended map [nm]

    Returns
    -------
    str or None
        The reason, with the rms [nm]; ``None`` when the map is rough enough to have asperities.

    References
    ----------
    docs/model.md, section "Asperity statistics" (the bounds of a map and why each holds).
    """
    if not rms >= MIN_RMS_NM:
        return (f"rms height {rms:.4g} nm after detrending: expected at least {MIN_RMS_NM:g} nm (a flatter map, "
                "constant or planar, has no asperities)")
    return None


@dataclass(frozen=True)
class RouteStatistics:
    """Asperity statistics of one surface by one route (all NaN when the route does not apply).

    Attributes
    ----------
    sigma : rms height [nm]
    sigma_s : standard deviation of summit heights [nm]
    y_s : mean of summit heights minus mean of surface heights [nm]
    eta : summit density [nm^-2]
    R : mean summit radius of curvature [nm]
    alpha : Nayak bandwidth parameter [1]
    count : number of summits counted (summit route only) [1]
    """

    sigma: float = math.nan
    sigma_s: float = math.nan
    y_s: float = math.nan
    eta: float = math.nan
    R: float = math.nan
    alpha: float = math.nan
    count: float = math.nan


@dataclass(frozen=True)
class SurfaceSummary:
    """Everything the roughness stage reports about one surface.

    Attributes
    ----------
    label : name of the surface (file stem, ``"explicit"`` or ``"combined"``)
    source : file it came from (``""`` for explicit or combined surfaces)
    channel : the channel that was read (``""`` when not from a file)
    pixel_size : lateral sampling interval [nm] (geometric mean of x and y; NaN when not sampled)
    m0 : profile height variance [nm^2]
    m2 : profile slope variance [1]
    m4 : profile curvature variance [nm^-2]
    spectral : statistics by the spectral route
    summits : statistics by the summit-count route
    warnings : messages about unreliable results (also issued as :class:`SurfaceWarning`)
    """

    label: str
    source: str
    channel: str
    pixel_size: float
    m0: float
    m2: float
    m4: float
    spectral: RouteStatistics
    summits: RouteStatistics
    warnings: tuple[str, ...] = field(default_factory=tuple)



# --------------------------------------------------------------------------------------------------
# Spectral route (Nayak 1971, McCool 1986)
# --------------------------------------------------------------------------------------------------


def _spectral(m0: float, m2: float, m4: float) -> tuple[RouteStatistics, list[str]]:
    if not (m0 > 0 and m2 > 0 and m4 > 0):
        return RouteStatistics(sigma=math.sqrt(max(m0, 0.0))), [
            f"spectral moments m0={m0:.4g} nm^2, m2={m2:.4g}, m4={m4:.4g} nm^-2 are not all positive "
            f"(a flat or constant-slope surface): no spectral summit statistics"]
    s = st.statistics_from_moments(m0, m2, m4)
    sigma, eta, R, alpha = s["sigma"], s["eta"], s["R"], s["alpha"]
    msgs: list[str] = []
    try:
        sigma_s = st.summit_sigma(sigma, eta, R)
    except ValueError:
        sigma_s = math.nan
        msgs.append(f"bandwidth alpha = m0 m4 / m2^2 = {alpha:.4g} <= {st.ALPHA_MIN}: McCool's summit-height "
                    f"variance sigma^2 (1 - {st.ALPHA_MIN}/alpha) would be negative, so sigma_s is NaN. "
                    f"A Gaussian random surface has alpha >= 1 (m2^2 <= m0 m4); a smaller value means the "
                    f"moments are inconsistent (e.g. finite-difference m4 of a surface with most power near "
                    f"the Nyquist wavelength) or the surface is far from Gaussian")
    y_s = st.summit_offset(sigma, eta, R)
    return RouteStatistics(sigma=sigma, sigma_s=sigma_s, y_s=y_s, eta=eta, R=R, alpha=alpha), msgs


def spectral_statistics(m0: float, m2: float, m4: float) -> RouteStatistics:
    """Summit statistics from profile moments [Nayak71, McCool86].

    ``eta = m4/(6 pi sqrt(3) m2)``, ``R = 0.375 sqrt(pi/m4)``, ``alpha = m0 m4/m2^2``,
    ``sigma_s = sqrt(sigma^2 - 3.717e-4/(eta R)^2)``, ``y_s = 4 sigma/sqrt(pi alpha)``
    (all via :mod:`pipeline.physics.asperity_statistics`).

    Parameters
    ----------
    m0 : height variance [nm^2]
    m2 : slope variance [1]
    m4 : curvature variance [nm^-2]

    Returns
    -------
    RouteStatistics
        In nm units: ``sigma``, ``sigma_s``, ``y_s``, ``R`` [nm], ``eta`` [nm^-2], ``alpha`` [1]. ``sigma_s`` is
        NaN (with a :class:`SurfaceWarning` saying why) when ``alpha <= 0.8968``.

    References
    ----------
    [Nayak71] P. R. Nayak, J. Lubr. Technol. 93 (1971) 398-407; [McCool86]; docs/model.md, section
    "Spectral route".
    """
    stats, msgs = _spectral(m0, m2, m4)
    for msg in msgs:
        warnings.warn(msg, SurfaceWarning, stacklevel=2)
    return stats


# --------------------------------------------------------------------------------------------------
# Summit route (Greenwood-Williamson 1966, direct count)
# --------------------------------------------------------------------------------------------------

def summit_mask(heights: np.ndarray) -> np.ndarray:
    """Summits of a sampled map: interior pixels strictly higher than their 8 neighbours [GW66].

    Parameters
    ----------
    heights : 2-D array [any length unit]

    Returns
    -------
    numpy.ndarray
        Booleans [-] of shape ``(nx - 2, ny - 2)`` over the interior pixels (border pixels, whose
        neighbourhood is incomplete, are never summits).

    References
    ----------
    [GW66] (summits as local maxima); docs/model.md, section "Summit route".
    """
    h = np.asarray(heights, dtype=float)
    nx, ny = h.shape
    centre = h[1:-1, 1:-1]
    mask = np.ones(centre.shape, dtype=bool)
    for i in (-1, 0, 1):
        for j in (-1, 0, 1):
            if i or j:
                mask &= centre > h[1 + i:nx - 1 + i, 1 + j:ny - 1 + j]
    return mask


def mean_curvature(heights: np.ndarray, pixel_size: tuple[float, float]) -> np.ndarray:
    """Mean principal curvature of the interior pixels from the 5-point Laplacian.

    ``kappa = -(d2z/dx2 + d2z/dy2)/2`` (positive at a summit), second-order central differences.

    Parameters
    ----------
    heights : 2-D array, axis 0 along x [nm]
    pixel_size : ``(dx, dy)`` [nm]

    Returns
    -------
    numpy.ndarray
        The mean curvature [nm^-1], shape ``(nx - 2, ny - 2)``.

    References
    ----------
    [GW66] (summit radius as the inverse curvature); docs/model.md, section "Summit route".
    """
    h = np.asarray(heights, dtype=float)
    dx, dy = pixel_size
    c = h[1:-1, 1:-1]
    d2x = (h[2:, 1:-1] - 2.0 * c + h[:-2, 1:-1]) / dx**2
    d2y = (h[1:-1, 2:] - 2.0 * c + h[1:-1, :-2]) / dy**2
    return -0.5 * (d2x + d2y)


def summit_statistics(heights: np.ndarray, pixel_size: tuple[float, float]) -> RouteStatistics:
    """Asperity statistics by direct summit counting [GW66].

    ``eta`` = number of summits / interior area ``(nx-2)(ny-2) dx dy``; ``R = 1/mean(kappa)`` over the
    summits (:func:`mean_curvature`); ``sigma_s`` = standard deviation of summit heights; ``y_s`` = mean
    summit height minus mean surface height; ``alpha`` is the HDI closed form
    ``2412.74 (sigma eta R)^2`` [McCool86] with these ``eta`` and ``R`` (for comparison with the
    spectral route only). Results depend on the sampling interval: report ``pixel_size`` with them.

    Parameters
    ----------
    heights : 2-D array, axis 0 along x, detrended [nm]
    pixel_size : ``(dx, dy)`` [nm]

    Returns
    -------
    RouteStatistics
        In nm units: ``sigma``, ``sigma_s``, ``y_s``, ``R`` [nm], ``eta`` [nm^-2], ``alpha`` [1], ``count`` [-]
        (NaN except ``sigma`` and ``count`` when there is no summit).

    References
    ----------
    [GW66]; [McCool86] (alpha); docs/model.md, section "Summit route".
    """
    h = np.asarray(heights, dtype=float)
    dx, dy = (float(p) for p in pixel_size)
    mask = summit_mask(h)
    n = int(mask.sum())
    sigma = float(np.std(h))
    if n == 0:
        return RouteStatistics(sigma=sigma, count=0.0)
    z = h[1:-1, 1:-1][mask]
    kappa = mean_curvature(h, (dx, dy))[mask]
    area = mask.size * dx * dy
    eta = n / area
    R = 1.0 / float(np.mean(kappa))
    return RouteStatistics(sigma=sigma, sigma_s=float(np.std(z)), y_s=float(np.mean(z) - np.mean(h)),
                           eta=eta, R=R, alpha=st.bandwidth_alpha(sigma, eta, R), count=float(n))


# --------------------------------------------------------------------------------------------------
# Both routes, comparison, combination
# --------------------------------------------------------------------------------------------------

def compare_routes(spectral: RouteStatistics, summits: RouteStatistics, pixel_size: float,
                   label: str = "surface") -> list[str]:
    """Messages for each of ``eta`` and ``R`` on which the two routes differ by more than a factor 2.

    Parameters
    ----------
    spectral, summits : the two routes' statistics (nm units)
    pixel_size : sampling interval [nm] (quoted in the message)
    label : surface name (quoted in the message)

    Returns
    -------
    list of str
        One message [-] per statistic that differs by more than a factor 2 (empty: none).

    References
    ----------
    docs/model.md, sections "Spectral route" and "Summit route" (why the routes differ on measured scans).
    """
    msgs = []
    for name, a, b, unit, fac in (("summit density eta", spectral.eta, summits.eta, "um^-2", PER_NM2_IN_PER_UM2),
                                  ("summit radius R", spectral.R, summits.R, "um", NM_IN_UM)):
        if not (np.isfinite(a) and np.isfinite(b) and a > 0 and b > 0):
            continue
        ratio = max(a, b) / min(a, b)
        if ratio > 2.0:
            msgs.append(
                f"{label}: {name} differs by a factor {ratio:.3g} between the spectral route "
                f"({a * fac:.4g} {unit}) and the summit count ({b * fac:.4g} {unit}). Expected for measured "
                f"scans: the summit count depends on the sampling interval (pixel size {pixel_size:.4g} nm) "
                f"and on measurement noise, which adds pixel-scale summits of high curvature; the spectral "
                f"route depends on the high-frequency cut-off of m2 and m4 (here the Nyquist wavelength "
                f"{2 * pixel_size:.4g} nm) and assumes a Gaussian surface. Neither is the true value; "
                f"compare scans at the same pixel size")
    return msgs


def summarise_sampled(m0: float, m2: float, m4: float, heights: np.ndarray, pixel_size: tuple[float, float],
                      label: str = "surface", source: str = "", channel: str = "") -> SurfaceSummary:
    """Both routes' statistics of a sampled, detrended height map in nm.

    Parameters
    ----------
    m0, m2, m4 : the map's profile moments [nm^2], [1], [nm^-2] (spectral route, :func:`spectral_statistics`)
    heights : 2-D array of the detrended heights, axis 0 along x [nm] (summit route, :func:`summit_statistics`)
    pixel_size : ``(dx, dy)`` [nm]
    label, source, channel : bookkeeping (surface name, file, channel)

    Returns
    -------
    SurfaceSummary
        Both routes' statistics in nm units ([nm], [nm^-2], [1]); every message in ``warnings`` is also
        issued as a :class:`SurfaceWarning`.

    References
    ----------
    [Nayak71], [McCool86] (spectral route), [GW66] (summit route); docs/model.md, section "Asperity statistics".
    """
    px, py = (float(p) for p in pixel_size)
    spectral, msgs = _spectral(m0, m2, m4)
    summits = summit_statistics(heights, (px, py))
    msgs = [f"{label}: {m}" for m in msgs]
    if summits.count == 0:
        msgs.append(f"{label}: no summit (8-neighbour local maximum) found: summit route is NaN")
    pixel = math.sqrt(px * py)
    msgs += compare_routes(spectral, summits, pixel, label)
    for msg in msgs:
        warnings.warn(msg, SurfaceWarning, stacklevel=2)
    return SurfaceSummary(label=label, source=source, channel=channel, pixel_size=pixel, m0=m0, m2=m2, m4=m4,
                          spectral=spectral, summits=summits, warnings=tuple(msgs))


def from_statistics(sigma: float, eta: float, R: float, label: str = "explicit") -> SurfaceSummary:
    """A surface given by its statistics (no height map): moments and McCool's relations [McCool86].

    Parameters
    ----------
    sigma : rms height [nm]
    eta : summit density [nm^-2]
    R : summit radius [nm]
    label : surface name

    Returns
    -------
    SurfaceSummary
        The spectral route's statistics in nm units ([nm], [nm^-2], [1]); no summit route.

    References
    ----------
    [McCool86]; docs/model.md, section "Asperity statistics".
    """
    m0, m2, m4 = st.moments_from_statistics(sigma, eta, R)
    spectral, msgs = _spectral(m0, m2, m4)
    msgs = [f"{label}: {m}" for m in msgs]
    for msg in msgs:
        warnings.warn(msg, SurfaceWarning, stacklevel=2)
    return SurfaceSummary(label=label, source="", channel="", pixel_size=math.nan, m0=m0, m2=m2, m4=m4,
                          spectral=spectral, summits=RouteStatistics(), warnings=tuple(msgs))


def combine_moments(moments: Iterable[tuple[float, float, float]]) -> tuple[float, float, float]:
    """Moments of the sum of independent surfaces: each moment adds (docs/model.md, section "Asperity statistics") [McCool86].

    Parameters
    ----------
    moments : ``(m0 [nm^2], m2 [1], m4 [nm^-2])`` per surface

    Returns
    -------
    (float, float, float)
        The summed moments m0 [nm^2], m2 [1], m4 [nm^-2].

    References
    ----------
    [McCool86]; docs/model.md, section "Combined surface".
    """
    m = np.sum(np.asarray(list(moments), dtype=float).reshape(-1, 3), axis=0)
    return float(m[0]), float(m[1]), float(m[2])


def combine(summaries: Sequence[SurfaceSummary], label: str = "combined") -> SurfaceSummary:
    """The combined rough surface of several surfaces against a smooth flat (docs/model.md, section "Asperity statistics").

    Spectral route: statistics of the summed moments (so ``sigma^2 = sum sigma_i^2``). Summit route: the
    surfaces live on different grids, so no combined height map exists; a single surface is copied,
    several give only ``sigma`` (quadrature sum of the summit-route sigmas) and NaN otherwise.
    ``pixel_size`` is the single surface's, or NaN for several.

    Parameters
    ----------
    summaries : the surfaces (:func:`summarise_sampled`, :func:`from_statistics`), in nm units
    label : the combined surface's name

    Returns
    -------
    SurfaceSummary
        The combined surface's statistics in nm units ([nm], [nm^-2], [1]).

    Raises
    ------
    ValueError
        For no surface.

    References
    ----------
    [McCool86] (moments of independent surfaces add); docs/model.md, section "Combined surface".
    """
    if not summaries:
        raise ValueError("combine: expected at least one surface")
    if len(summaries) == 1:
        return replace(summaries[0], label=label, warnings=())
    m0, m2, m4 = combine_moments((s.m0, s.m2, s.m4) for s in summaries)
    spectral, msgs = _spectral(m0, m2, m4)
    msgs = [f"{label}: {m}" for m in msgs]
    for msg in msgs:
        warnings.warn(msg, SurfaceWarning, stacklevel=2)
    sig = math.sqrt(sum(s.summits.sigma**2 for s in summaries))
    return SurfaceSummary(label=label, source="", channel="", pixel_size=math.nan, m0=m0, m2=m2, m4=m4,
                          spectral=spectral, summits=RouteStatistics(sigma=sig), warnings=tuple(msgs))
