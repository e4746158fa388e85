"""Tests of pipeline.model.afm_scan on real AFM files kept in the repository (tests/data/afm): the height
channel picked, the heights equal to SurfaceTopography's own reading, and each bad file reported by name.
"""

from __future__ import annotations

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
