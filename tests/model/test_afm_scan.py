"""Tests of pipeline.model.afm_scan on real AFM files kept in the repository (tests/data/afm): the height
channel picked, the heights equal to SurfaceTopography's own reading, and each bad file reported by name.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from SurfaceTopography import open_topography

from pipeline.model import afm_scan
from pipeline.physics import surface as sf

AFM = Path(__file__).resolve().parents[1] / "data" / "afm"  # real scans, kept in the repository


# ---------------------------------------------------------------------------------------------------
# Shared AFM files
# ---------------------------------------------------------------------------------------------------

#: file -> the channel our rule must pick
SHARED = {"di-3.di": "ZSensor", "di-5.di": "ZSensor", "mi-1.mi": "Topography",
          "nid-1.nid": "Scan forward (Z-Axis)", "spot_1-1000nm.ibw": "HeightTrace"}


def _shared(name: str) -> Path:
    return AFM / name


@pytest.mark.parametrize("name", sorted(SHARED))
def test_shared_afm_rms_height_equals_surfacetopography(name: str) -> None:
    path = _shared(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sf.SurfaceWarning)
        s = afm_scan.summarise_file(path)
    assert s.channel == SHARED[name]
    reader = open_topography(str(path))
    index = [c.name for c in reader.channels].index(SHARED[name])
    ref = reader.topography(channel_index=index).to_unit("nm").detrend(detrend_mode="height")
    # tol: SurfaceTopography's rms against ours: sums of n^2 heights in another order, < n eps
    assert s.spectral.sigma == pytest.approx(ref.Sq(), rel=1e-10)
    # tol: SurfaceTopography's rms against ours: sums of n^2 heights in another order, < n eps
    assert s.summits.sigma == pytest.approx(ref.Sq(), rel=1e-10)
    # tol: a square root of a product of the same pixel sizes, a few roundings
    assert s.pixel_size == pytest.approx(float(np.sqrt(np.prod(ref.pixel_size))), rel=1e-12)
    assert s.summits.count > 100
    assert np.isfinite([s.spectral.eta, s.spectral.R, s.spectral.alpha, s.summits.eta, s.summits.R]).all()


def test_named_channel_and_detrend_option() -> None:
    path = _shared("di-3.di")
    t = afm_scan.read_topography(path, channel="Height", detrend_mode="curvature")
    assert t.info["channel_name"] == "Height" and t.unit == "nm"
    ref = open_topography(str(path)).topography(channel_index=3).to_unit("nm").detrend(detrend_mode="curvature")
    # tol: SurfaceTopography's rms against ours: sums of n^2 heights in another order, < n eps
    assert t.Sq() == pytest.approx(ref.Sq(), rel=1e-10)
    with pytest.raises(afm_scan.AFMError, match=r"di-3\.di: no channel named 'Nope'.*'ZSensor'"):
        afm_scan.read_topography(path, channel="Nope")


def test_no_height_channel_is_reported() -> None:
    """The real channel lists of shared files without their height channels."""
    for name in ("di-5.di", "spot_1-1000nm.ibw"):
        path = _shared(name)
        others = [c for c in open_topography(str(path)).channels
                  if not afm_scan.HEIGHT_NAME.search(c.name)]
        with pytest.raises(afm_scan.AFMError, match=rf"{name}: no height channel.*expected a 2-D map"):
            afm_scan.select_height_channel(others, path)


# ---------------------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------------------

def test_errors_name_the_file(tmp_path: Path) -> None:
    empty = tmp_path / "empty.di"
    empty.write_bytes(b"")
    text = tmp_path / "notes.di"
    text.write_text("hello world\nthis is not an AFM file\n")
    line = tmp_path / "line.txt"
    line.write_text("1 2 3\n4 5 6\n7 8 9\n")
    nosize = tmp_path / "nosize.txt"
    nosize.write_text("\n".join(" ".join(["1.0", "2.0", "3.0", "4.5"]) for _ in range(5)))
    cases = [(tmp_path / "missing.di", "does not exist"), (empty, "empty"),
             (text, "cannot be read as a .di file"), (line, "line scan"), (nosize, "no lateral scan size")]
    for path, what in cases:
        with pytest.raises(afm_scan.AFMError, match=what) as info:
            afm_scan.summarise_file(path)
        assert str(path) in str(info.value)
        assert isinstance(info.value, ValueError)


def test_truncated_file_is_reported_as_corrupt(tmp_path: Path) -> None:
    src = _shared("spot_1-1000nm.ibw")
    bad = tmp_path / "cut.ibw"
    bad.write_bytes(src.read_bytes()[:4000])
    with pytest.raises(afm_scan.AFMError, match=r"cut\.ibw: cannot be read as a \.ibw file.*truncated"):
        afm_scan.read_topography(bad)


# ---------------------------------------------------------------------------------------------------
# Maps beyond the bounds of pipeline.physics.surface
# ---------------------------------------------------------------------------------------------------

def _map(path: Path, heights: np.ndarray, size: tuple[float, float] = (256.0, 256.0), unit: str = "nm") -> Path:
    from SurfaceTopography import Topography
    Topography(heights, size, periodic=True, unit=unit).to_netcdf(str(path))
    return path


def _rough(n: int = 32) -> np.ndarray:
    x = np.arange(n) * 2 * np.pi / n
    return 0.5 * np.cos(3 * x)[:, None] * np.cos(2 * x)[None, :] + 0.2 * np.sin(5 * x)[:, None]


@pytest.mark.parametrize("name, heights, size, unit, bound", [
    # heights of 1e80 nm overflowed the moments (a traceback); of 3e38 nm gave statistics with exit 0
    ("huge", 1e80 * _rough(), (256.0, 256.0), "nm",
     re.escape(f"heights reach {1e80 * np.abs(_rough()).max():.4g} nm: expected heights within +-100000 nm")),
    ("float32-max", 3e38 * _rough(), (256.0, 256.0), "nm", re.escape(f"heights reach {3e38 * np.abs(_rough()).max():.4g} nm")),
    # every pixel undefined: filled with zeros by the interpolation and summarised as a flat surface
    ("undefined", np.full((32, 32), np.nan), (256.0, 256.0), "nm", r"every height is undefined"),
    # a lateral size of 1e-30 um: summit densities of 1e61 um^-2 written with exit 0
    ("tiny-size", _rough(), (1e-30, 1e-30), "um", r"pixel size 3\.125e-29 nm \(lateral size 1e-27 x 1e-27 nm over "
                                                   r"32 x 32 points\): expected 0\.001 to 1e\+06 nm"),
    ("huge-size", _rough(), (1e30, 1e30), "um", r"lateral size 1e\+33 x 1e\+33 nm: expected at most 1e\+08 nm"),
    # a zero or negative lateral size: ZeroDivisionError and 'math domain error'
    ("zero-size", _rough(), (0.0, 256.0), "nm", r"lateral size 0 x 256 nm: expected positive finite sizes"),
    ("negative-size", _rough(), (-256.0, 256.0), "nm", r"lateral size -256 x 256 nm: expected positive finite sizes"),
    # flat maps: statistics of NaN written with exit 0
    ("constant", np.full((32, 32), 3.0), (256.0, 256.0), "nm", r"rms height .* nm after detrending: expected at least "
                                                              r"0\.001 nm .*\(detrend 'plane'\)"),
    ("plane", np.add.outer(np.arange(32.0), np.arange(32.0)), (256.0, 256.0), "nm", r"rms height .* after detrending"),
    ("sub-atomic", 1e-30 * _rough(), (256.0, 256.0), "nm", r"rms height .* after detrending"),
])
def test_a_map_beyond_physical_bounds_is_refused_naming_the_file_and_the_bound(tmp_path: Path, name, heights, size,
                                                                                unit, bound) -> None:
    path = _map(tmp_path / f"{name}.nc", heights, size, unit)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(afm_scan.AFMError, match=rf"^{path}: channel 'Default': {bound}") as exc:
            afm_scan.summarise_file(path)
    assert "\n" not in str(exc.value)


def test_a_map_within_the_bounds_is_summarised(tmp_path: Path) -> None:
    """The bounds refuse nothing a scan of a disk holds: a 0.3-nm map with some undefined pixels, 256 nm wide."""
    h = _rough()
    h[3, 4] = np.nan
    path = _map(tmp_path / "ok.nc", h)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = afm_scan.summarise_file(path)
    assert s.pixel_size == pytest.approx(8.0) and 0.1 < s.spectral.sigma < 1.0


def test_reading_a_netcdf_map_says_nothing_of_its_memory_map(tmp_path: Path) -> None:
    """SciPy's NetCDF reader warned "Cannot close a netcdf_file opened with mmap=True" when the reader was
    dropped with the heights still sharing its memory map: a second line after every one-line error."""
    import gc
    h = _rough()
    h[3, 4] = np.nan
    for path in (_map(tmp_path / "part.nc", h), _map(tmp_path / "none.nc", np.full((32, 32), np.nan))):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            try:
                topo = afm_scan.read_topography(path)
            except afm_scan.AFMError:
                topo = None
            gc.collect()
        assert [str(w.message) for w in seen if issubclass(w.category, RuntimeWarning)] == []
        if topo is not None:
            assert np.isfinite(topo.heights()).all()
