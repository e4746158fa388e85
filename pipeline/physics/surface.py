"""Asperity statistics of measured height maps: AFM reading, detrending, and the two routes of docs/model.md, section "Asperity statistics".

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
import re
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np

from . import asperity_statistics as st
from ..paths import special_kind
from ..units import NM_IN_UM, PER_NM2_IN_PER_UM2

#: Detrend modes accepted here; ``"plane"`` is SurfaceTopography's ``"height"`` (the rms-minimising plane).
DETREND_ALIASES = {"plane": "height"}

#: Names of height channels (``ZSensor``, ``Height``, ``Topography``, ``Scan forward (Z-Axis)``,
#: ``HeightTrace``, ...). Searched case-insensitively.
HEIGHT_NAME = re.compile(r"height|topo|z[-_ ]?(sensor|axis)|^z$|\bz\b", re.IGNORECASE)
#: Names of channels that carry a length unit but are not heights (oscillation amplitude, error signals).
NOT_HEIGHT_NAME = re.compile(r"amplitude|error|phase|deflection|friction|current|potential|force|voltage",
                             re.IGNORECASE)


#: File extensions in common use that SurfaceTopography's readers do not list (extension -> reader).
EXTRA_EXTENSIONS = {"di": "DIReader"}


class AFMError(ValueError):
    """An AFM file cannot be used: missing, empty, corrupt, not a topography, or without a height channel.

    The message always names the file and what was expected.
    """


class SurfaceWarning(UserWarning):
    """A surface statistic is unreliable (routes disagree, McCool's relations out of range, no summits)."""


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
# Reading
# --------------------------------------------------------------------------------------------------

def _is_length_unit(unit: Any) -> bool:
    from SurfaceTopography.Support.UnitConversion import is_length_unit
    return isinstance(unit, str) and is_length_unit(unit)


def _may_hold_heights(info: Any) -> bool:
    """A channel whose data unit is a length, or unknown on a channel SurfaceTopography calls a height."""
    if info.data_unit is None:
        return getattr(info.data_kind, "name", "") == "HEIGHT"
    return _is_length_unit(info.data_unit)


def _describe(channels: Sequence[Any]) -> str:
    return ", ".join(f"{c.name!r} [{c.data_unit if isinstance(c.data_unit, str) else 'no length unit'}]"
                     for c in channels) or "none"


def select_height_channel(channels: Sequence[Any], path: str | Path, channel: str | int | None = None) -> Any:
    """Pick the channel holding the heights.

    Rule (default): among the 2-D channels whose data unit is a length (or not given, on a channel
    SurfaceTopography classes as a height), drop those whose name says they
    are not heights (amplitude, error, phase, deflection, friction, ...); take the first whose name
    mentions height, topography or z (``ZSensor``, ``Height``, ``Topography``, ``Scan forward (Z-Axis)``,
    ``HeightTrace``); failing that, the first remaining one. File order puts the trace/forward scan and
    the closed-loop sensor (``ZSensor``) first in the formats we know.

    Parameters
    ----------
    channels : the :class:`SurfaceTopography.IO.Reader.ChannelInfo` list of a reader
    path : the file (for messages)
    channel : a channel name (exact, then case-insensitive) or index; ``None``: the rule above

    Raises
    ------
    AFMError
        When the named channel does not exist, or no channel holds a 2-D height map.
    """
    if channel is not None:
        if isinstance(channel, int) or (isinstance(channel, str) and channel.isdigit()):
            idx = int(channel)
            hits = [c for c in channels if c.index == idx]
        else:
            hits = [c for c in channels if c.name == channel] or \
                   [c for c in channels if c.name.lower() == str(channel).lower()]
        if not hits:
            raise AFMError(f"{path}: no channel named {channel!r}; the file has {_describe(channels)}")
        return hits[0]
    heights = [c for c in channels if _may_hold_heights(c) and not NOT_HEIGHT_NAME.search(c.name)]
    maps = [c for c in heights if c.dim == 2]
    named = [c for c in maps if HEIGHT_NAME.search(c.name)]
    if named or maps:
        return (named or maps)[0]
    if heights:
        raise AFMError(f"{path}: holds only line scans ({_describe(heights)}); expected a 2-D height map")
    raise AFMError(f"{path}: no height channel: expected a 2-D map with a length unit whose name is not "
                   f"amplitude/error/phase/...; the file has {_describe(channels)}")


def detrend(topography: Any, mode: str = "plane", info: dict | None = None) -> Any:
    """Detrended copy of a topography, heights materialised (SurfaceTopography ``detrend``).

    Parameters
    ----------
    topography : a uniform SurfaceTopography topography
    mode : ``"plane"`` (rms-minimising plane, SurfaceTopography's ``"height"``), ``"center"``,
        ``"curvature"``, or any other SurfaceTopography ``detrend_mode``
    info : entries added to the topography's ``info`` dictionary

    Raises
    ------
    ValueError
        For an unknown mode.
    """
    st_mode = DETREND_ALIASES.get(mode, mode)
    try:
        return topography.detrend(detrend_mode=st_mode, info=info or {}).squeeze()
    except ValueError as exc:
        raise ValueError(f"detrend mode {mode!r}: {exc}; expected 'plane', 'center', 'height' or "
                         f"'curvature'") from None


def _reason_for_suffix(message: str, suffix: str) -> str:
    """The failure reason of the reader for ``suffix`` in SurfaceTopography's "tried ..." report, or ``""``."""
    from SurfaceTopography.IO import readers

    ext = suffix.lower().lstrip(".")
    names = {r.__name__ for r in readers if ext and ext in getattr(r, "_file_extensions", ())}
    names |= {name for e, name in EXTRA_EXTENSIONS.items() if e == ext}
    for name, reason in re.findall(r"tried (\w+): \n (.*?)\n\n", message, re.S):
        if name in names:
            return f"{name}: {reason.strip()}"
    return ""


def read_topography(path: str | Path, channel: str | int | None = None, detrend_mode: str = "plane") -> Any:
    """Read a height map with SurfaceTopography, in nanometres, detrended.

    Parameters
    ----------
    path : any file format SurfaceTopography reads (Bruker ``.di``, ``.mi``, ``.nid``, ``.ibw``, ...)
    channel : channel name or index; ``None`` picks the height channel (:func:`select_height_channel`)
    detrend_mode : see :func:`detrend`

    Returns
    -------
    SurfaceTopography ``Topography`` with unit ``"nm"`` and materialised heights; ``info["channel_name"]``
    holds the channel read.

    Raises
    ------
    AFMError
        For a missing, empty, unreadable or corrupt file, a file that is not a 2-D topography, one
        without a height channel, a lateral size or a height unit.
    """
    from SurfaceTopography import open_topography
    from SurfaceTopography.Exceptions import CannotDetectFileFormat

    path = Path(path)
    expect = "an AFM/profilometer height map in a format SurfaceTopography reads"
    if special_kind(path) is not None:  # (checked before opening: a FIFO or a device never ends)
        raise AFMError(f"{path}: is {special_kind(path)} (expected a regular file, {expect})")
    if not path.is_file():
        raise AFMError(f"{path}: file does not exist (expected {expect})")
    if path.stat().st_size == 0:
        raise AFMError(f"{path}: file is empty (expected {expect})")
    try:
        reader = open_topography(str(path))
        channels = reader.channels
    except CannotDetectFileFormat as exc:
        reason = _reason_for_suffix(str(exc), path.suffix)
        if reason:
            raise AFMError(f"{path}: cannot be read as a {path.suffix} file ({reason}): it is corrupt, "
                           f"truncated or not in that format; expected {expect}") from None
        raise AFMError(f"{path}: not a topography file: none of SurfaceTopography's readers recognises it "
                       f"(expected {expect})") from None
    except Exception as exc:  # SurfaceTopography raises many types for corrupt files
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise AFMError(f"{path}: corrupt or unreadable topography file (expected {expect}): {first}") from None
    info = select_height_channel(channels, path, channel)
    if info.dim != 2:
        raise AFMError(f"{path}: channel {info.name!r} is a {info.dim}-D line scan; expected a 2-D height map")
    if info.nb_grid_pts is None or min(info.nb_grid_pts) < 3:
        raise AFMError(f"{path}: channel {info.name!r} has {info.nb_grid_pts} grid points; expected a 2-D "
                       f"map of at least 3 x 3 points")
    if info.physical_sizes is None:
        raise AFMError(f"{path}: channel {info.name!r} has no lateral scan size; expected a file that "
                       f"stores its physical size")
    try:
        topo = info.topography()
    except Exception as exc:
        raise AFMError(f"{path}: channel {info.name!r} could not be read, the file is probably corrupt: "
                       f"{exc}") from None
    if not _is_length_unit(topo.unit):
        raise AFMError(f"{path}: channel {info.name!r} has unit {topo.unit!r}; expected a length unit")
    topo = topo.to_unit("nm")
    if topo.has_undefined_data:
        warnings.warn(f"{path}: channel {info.name!r} has undefined pixels; filled by harmonic "
                      f"interpolation (SurfaceTopography interpolate_undefined_data)", SurfaceWarning,
                      stacklevel=2)
        topo = topo.interpolate_undefined_data()
    heights = topo.heights()
    if not np.all(np.isfinite(np.ma.filled(heights, np.nan))):
        raise AFMError(f"{path}: channel {info.name!r} holds non-finite heights; the file is probably corrupt")
    return detrend(topo, detrend_mode, info={"channel_name": info.name})


# --------------------------------------------------------------------------------------------------
# Spectral route (Nayak 1971, McCool 1986)
# --------------------------------------------------------------------------------------------------

def profile_moments(topography: Any) -> tuple[float, float, float]:
    """Profile spectral moments ``m0, m2, m4`` of a height map [Nayak71].

    ``m0`` is the height variance of the map (``Sq^2``, about its mean); ``m2`` and ``m4`` are the
    variances of the slope and curvature *along a profile*, averaged over the x and the y profiles
    (for an isotropic surface they are equal). The derivatives are SurfaceTopography's finite
    differences (``derivative``, the same stencils as ``Rdq`` and ``Rddq``: first-order upwind and
    second-order central), so the x terms equal ``Rdq^2`` and ``Rddq^2`` and the y terms those of the
    transposed map. The high-frequency cut-off is therefore the Nyquist wavelength ``2 dx``.

    Parameters
    ----------
    topography : a uniform SurfaceTopography map in nm (already detrended)

    Returns
    -------
    m0 [nm^2], m2 [1], m4 [nm^-2]
    """
    m0 = float(topography.Sq()) ** 2
    dx, dy = topography.derivative(1)
    d2x, d2y = topography.derivative(2)
    m2 = 0.5 * (float(np.mean(dx**2)) + float(np.mean(dy**2)))
    m4 = 0.5 * (float(np.mean(d2x**2)) + float(np.mean(d2y**2)))
    return m0, m2, m4


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
    RouteStatistics in nm units. ``sigma_s`` is NaN (with a :class:`SurfaceWarning` saying why) when
    ``alpha <= 0.8968``.
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
    Boolean array of shape ``(nx - 2, ny - 2)`` over the interior pixels (border pixels, whose
    neighbourhood is incomplete, are never summits).
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
    Array of shape ``(nx - 2, ny - 2)`` [nm^-1]
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
    RouteStatistics in nm units (NaN except ``sigma`` and ``count`` when there is no summit).
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


def summarise(topography: Any, label: str = "surface", source: str = "", channel: str = "") -> SurfaceSummary:
    """Both routes' statistics of a detrended height map in nm.

    Parameters
    ----------
    topography : uniform SurfaceTopography map in nm (see :func:`read_topography`)
    label, source, channel : bookkeeping (surface name, file, channel)

    Returns
    -------
    SurfaceSummary; every message in ``warnings`` is also issued as a :class:`SurfaceWarning`.
    """
    if topography.dim != 2:
        raise ValueError(f"{label}: expected a 2-D height map, got a {topography.dim}-D topography")
    px, py = (float(p) for p in topography.pixel_size)
    m0, m2, m4 = profile_moments(topography)
    spectral, msgs = _spectral(m0, m2, m4)
    summits = summit_statistics(np.ma.getdata(topography.heights()), (px, py))
    msgs = [f"{label}: {m}" for m in msgs]
    if summits.count == 0:
        msgs.append(f"{label}: no summit (8-neighbour local maximum) found: summit route is NaN")
    pixel = math.sqrt(px * py)
    msgs += compare_routes(spectral, summits, pixel, label)
    for msg in msgs:
        warnings.warn(msg, SurfaceWarning, stacklevel=2)
    return SurfaceSummary(label=label, source=source, channel=channel, pixel_size=pixel, m0=m0, m2=m2, m4=m4,
                          spectral=spectral, summits=summits, warnings=tuple(msgs))


def summarise_file(path: str | Path, channel: str | int | None = None, detrend_mode: str = "plane",
                   label: str | None = None) -> SurfaceSummary:
    """Read an AFM file (:func:`read_topography`) and summarise it by both routes (:func:`summarise`).

    Raises
    ------
    AFMError
        See :func:`read_topography`.
    """
    path = Path(path)
    topo = read_topography(path, channel=channel, detrend_mode=detrend_mode)
    return summarise(topo, label=label or path.stem, source=str(path), channel=topo.info["channel_name"])


def from_statistics(sigma: float, eta: float, R: float, label: str = "explicit") -> SurfaceSummary:
    """A surface given by its statistics (no height map): moments and McCool's relations [McCool86].

    Parameters
    ----------
    sigma : rms height [nm]
    eta : summit density [nm^-2]
    R : summit radius [nm]
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
    """
    m = np.sum(np.asarray(list(moments), dtype=float).reshape(-1, 3), axis=0)
    return float(m[0]), float(m[1]), float(m[2])


def combine(summaries: Sequence[SurfaceSummary], label: str = "combined") -> SurfaceSummary:
    """The combined rough surface of several surfaces against a smooth flat (docs/model.md, section "Asperity statistics").

    Spectral route: statistics of the summed moments (so ``sigma^2 = sum sigma_i^2``). Summit route: the
    surfaces live on different grids, so no combined height map exists; a single surface is copied,
    several give only ``sigma`` (quadrature sum of the summit-route sigmas) and NaN otherwise.
    ``pixel_size`` is the single surface's, or NaN for several.
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
