"""Reading AFM height maps: the file side of the asperity statistics.

:func:`read_topography` opens a measured height map with SurfaceTopography (Bruker ``.di``, ``.mi``,
``.nid``, ``.ibw``, ...), picks its height channel (:func:`select_height_channel`), converts it to
nanometres and detrends it (:func:`detrend`); each problem is an :class:`AFMError` naming the file and
what was expected. :func:`summarise` takes the map's profile moments (:func:`profile_moments`) and heights
to the two routes of :mod:`pipeline.physics.surface` (docs/model.md, section "Asperity statistics"),
which work on numbers only. Everything here is in nanometres.

References
----------
.. [Nayak71] P. R. Nayak, "Random process model of rough surfaces", J. Lubr. Technol. 93 (1971) 398-407.
.. [JJP17] T. D. B. Jacobs, T. Junge, L. Pastewka, "Quantitative characterization of surface topography
   using spectral analysis", Surf. Topogr.: Metrol. Prop. 5 (2017) 013001 (SurfaceTopography).
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..paths import looked_for, special_kind
from ..physics import surface as sf

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
        without a height channel, a lateral size or a height unit, and a map outside the bounds of
        :mod:`pipeline.physics.surface` (:func:`~pipeline.physics.surface.sampling_error`,
        :func:`~pipeline.physics.surface.heights_error`, :func:`~pipeline.physics.surface.roughness_error`:
        sizes, pixel sizes, heights, an all-undefined or flat map), naming the bound.
    """
    from SurfaceTopography import open_topography
    from SurfaceTopography.Exceptions import CannotDetectFileFormat

    path = Path(path)
    expect = "an AFM/profilometer height map in a format SurfaceTopography reads"
    if special_kind(path) is not None:  # (checked before opening: a FIFO or a device never ends)
        raise AFMError(f"{path}: is {special_kind(path)} (expected a regular file, {expect})")
    if not path.is_file():
        raise AFMError(f"{path}: file does not exist{looked_for(path)} (expected {expect})")
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
    try:
        return _height_map(channels, path, channel, detrend_mode)
    finally:
        _close(reader)


def _close(reader: Any) -> None:
    """Close a reader once its map is read. SciPy's NetCDF reader warns when it closes while the heights read
    still share its memory map ("Cannot close a netcdf_file opened with mmap=True"; the map then stays open
    for them): no news to a user, and a second line after a one-line error."""
    close = getattr(reader, "close", None)
    if close is None:
        return
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Cannot close a netcdf_file opened with mmap=True",
                                category=RuntimeWarning)
        close()


def _height_map(channels: Sequence[Any], path: Path, channel: str | int | None, detrend_mode: str) -> Any:
    """The detrended height map [nm] of a reader's ``channels`` (:func:`read_topography`, which names the
    errors)."""
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
    bad = sf.sampling_error(topo.physical_sizes, topo.nb_grid_pts) or \
        sf.heights_error(np.ma.filled(np.ma.masked_invalid(topo.heights()).astype(float), np.nan))
    if bad:
        raise AFMError(f"{path}: channel {info.name!r}: {bad}")
    if topo.has_undefined_data:
        warnings.warn(f"{path}: channel {info.name!r} has undefined pixels; filled by harmonic "
                      f"interpolation (SurfaceTopography interpolate_undefined_data)", sf.SurfaceWarning,
                      stacklevel=3)
        topo = topo.interpolate_undefined_data()
    heights = topo.heights()
    if not np.all(np.isfinite(np.ma.filled(heights, np.nan))):
        raise AFMError(f"{path}: channel {info.name!r} holds non-finite heights; the file is probably corrupt")
    flat = detrend(topo, detrend_mode, info={"channel_name": info.name})
    bad = sf.roughness_error(float(np.std(np.ma.getdata(flat.heights()))))
    if bad:
        raise AFMError(f"{path}: channel {info.name!r}: {bad} (detrend {detrend_mode!r})")
    return flat


# --------------------------------------------------------------------------------------------------
# Profile moments of a map and both routes' statistics
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


def summarise(topography: Any, label: str = "surface", source: str = "", channel: str = "") -> sf.SurfaceSummary:
    """Both routes' statistics of a detrended height map in nm.

    Parameters
    ----------
    topography : uniform SurfaceTopography map in nm (see :func:`read_topography`)
    label, source, channel : bookkeeping (surface name, file, channel)

    Returns
    -------
    SurfaceSummary (:func:`pipeline.physics.surface.summarise_sampled`); every message in ``warnings`` is
    also issued as a :class:`~pipeline.physics.surface.SurfaceWarning`.
    """
    if topography.dim != 2:
        raise ValueError(f"{label}: expected a 2-D height map, got a {topography.dim}-D topography")
    m0, m2, m4 = profile_moments(topography)
    return sf.summarise_sampled(m0, m2, m4, np.ma.getdata(topography.heights()), topography.pixel_size,
                                label=label, source=source, channel=channel)


def summarise_file(path: str | Path, channel: str | int | None = None, detrend_mode: str = "plane",
                   label: str | None = None) -> sf.SurfaceSummary:
    """Read an AFM file (:func:`read_topography`) and summarise it by both routes (:func:`summarise`).

    Raises
    ------
    AFMError
        See :func:`read_topography`.
    """
    path = Path(path)
    topo = read_topography(path, channel=channel, detrend_mode=detrend_mode)
    return summarise(topo, label=label or path.stem, source=str(path), channel=topo.info["channel_name"])
