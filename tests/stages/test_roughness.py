"""Tests of the roughness stage: dataset layout, explicit statistics, combination, atomic writes."""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from SurfaceTopography import Topography

from pipeline.io import DatasetError, file_hash
from pipeline.physics import asperity_statistics as st
from pipeline.model import afm_scan
from pipeline.physics import surface as sf
from pipeline.config.scene import scene_from_dict
from pipeline.model import roughness_statistics as rough_model
from pipeline.stages import roughness as rg
from pipeline.runner import ensure

AFM = Path(__file__).resolve().parents[1] / "data" / "afm"  # real scans, kept in the repository


def _open(path: Path) -> xr.Dataset:
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


def _synthetic_file(path: Path, A: float, periods: int, seed: int, n: int = 64) -> Path:
    """A smooth random height map (sum of a few random sinusoids) written as SurfaceTopography NetCDF [nm]."""
    rng = np.random.default_rng(seed)
    x = np.arange(n) * (256.0 / n)
    X, Y = np.meshgrid(x, x, indexing="ij")
    z = np.zeros_like(X)
    for _ in range(6):
        kx, ky = 2 * np.pi * rng.integers(1, periods + 1, size=2) / 256.0
        z += A * np.cos(kx * X + ky * Y + rng.uniform(0, 2 * np.pi))
    Topography(z, (256.0, 256.0), periodic=True, unit="nm").to_netcdf(str(path))
    return path


@pytest.fixture
def two_files(tmp_path: Path) -> list[Path]:
    src = tmp_path / "src"
    src.mkdir()
    return [_synthetic_file(src / "disk.nc", 0.4, 6, seed=1), _synthetic_file(src / "tfc.nc", 0.2, 9, seed=2)]


def _run(files, out, **kw) -> Path:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sf.SurfaceWarning)
        return rg.run_files(files, out, **kw)


def test_layout_units_and_combination(two_files: list[Path], tmp_path: Path) -> None:
    path = _run(two_files, tmp_path / "out", detrend="center")
    assert path == tmp_path / "out" / "roughness.nc"
    ds = _open(path)
    assert list(ds["surface"].values) == ["disk", "tfc", "combined"]
    assert list(ds["route"].values) == ["spectral", "summits"]
    units = {"sigma": "nm", "sigma_s": "nm", "y_s": "nm", "summit_radius": "um", "summit_density": "um-2",
             "bandwidth_alpha": "1", "plasticity_index": "1", "pixel_size": "nm", "m0": "nm2", "m2": "1",
             "m4": "nm-2", "summit_count": "1"}
    for name, unit in units.items():
        assert ds[name].attrs["units"] == unit, name
    for name in list(ds.variables):
        assert ds[name].attrs.get("long_name"), name
    assert ds["sigma"].dims == ("surface", "route") and ds["m0"].dims == ("surface",)
    # per-surface values against the physics module
    for f in two_files:
        s = afm_scan.summarise(afm_scan.read_topography(f, detrend_mode="center"))
        row = ds.sel(surface=f.stem)
        # tol: the same summary of the same scan, through NetCDF float64
        assert float(row["m0"]) == pytest.approx(s.m0, rel=1e-12)
        # tol: the same summary of the same scan, through NetCDF float64
        assert float(row["sigma"].sel({"route": "summits"})) == pytest.approx(s.summits.sigma, rel=1e-12)
        assert float(row["summit_radius"].sel({"route": "spectral"})) == pytest.approx(s.spectral.R * 1e-3)
        assert float(row["summit_density"].sel({"route": "summits"})) == pytest.approx(s.summits.eta * 1e6)
        assert float(row["summit_count"]) == s.summits.count
        assert float(row["pixel_size"]) == pytest.approx(4.0)
    # combined: moments add, so sigma^2 adds
    c = ds.sel(surface="combined")
    for m in ("m0", "m2", "m4"):
        # tol: a sum of two moments, one rounding
        assert float(c[m]) == pytest.approx(float(ds[m].sel(surface=["disk", "tfc"]).sum()), rel=1e-12)
    sig = ds["sigma"].sel({"route": "spectral"})
    # tol: sigma^2 adds: square roots of sums of moments, a few roundings
    assert float(sig.sel(surface="combined")) ** 2 == pytest.approx(
        float(sig.sel(surface="disk")) ** 2 + float(sig.sel(surface="tfc")) ** 2, rel=1e-12)
    assert math.isnan(float(c["summit_density"].sel({"route": "summits"})))
    # provenance and per-file sources
    assert ds.attrs["source_file_disk"] == "disk.nc" and ds.attrs["source_file_tfc"] == "tfc.nc"
    assert "disk.nc" in ds.attrs["source_files"] and str(two_files[0]) in ds.attrs["input_hashes"]
    assert ds.attrs["stage"] == "roughness" and ds.attrs["detrend"] == "center"
    assert "GW" in ds.attrs["plasticity_index_form"]


def test_combined_statistics(two_files: list[Path], tmp_path: Path) -> None:
    path = _run(two_files, tmp_path)
    stats = rough_model.combined_statistics(path)
    ds = _open(path)
    row = ds.sel(surface="combined", route="spectral")
    assert set(stats) == {"sigma_nm", "sigma_s_nm", "y_s_nm", "summit_radius_um", "summit_density_per_um2", "alpha"}
    assert stats["sigma_nm"] == float(row["sigma"]) and stats["summit_radius_um"] == float(row["summit_radius"])
    assert stats["alpha"] == pytest.approx(float(ds["m0"][-1] * ds["m4"][-1] / ds["m2"][-1] ** 2))
    with pytest.raises(DatasetError, match="summit route cannot combine"):
        rough_model.combined_statistics(path, route="summits")
    with pytest.raises(DatasetError, match="does not exist"):
        rough_model.combined_statistics(tmp_path / "nothing.nc")


def test_single_file_combined_is_the_file(two_files: list[Path], tmp_path: Path) -> None:
    ds = _open(_run(two_files[:1], tmp_path))
    assert list(ds["surface"].values) == ["disk", "combined"]
    for name in ("sigma", "sigma_s", "summit_radius", "summit_density", "pixel_size", "summit_count"):
        np.testing.assert_array_equal(ds[name].sel(surface="disk").values, ds[name].sel(surface="combined").values)
    stats = rough_model.combined_statistics(tmp_path / "roughness.nc", route="summits")
    assert stats["summit_density_per_um2"] == float(ds["summit_density"].sel({"surface": "disk", "route": "summits"}))


def test_explicit_statistics_use_mccool(tmp_path: Path) -> None:
    # H = 1.683 GPa: the hardness psi = 0.52 gives with the corrected statistics (docs/model.md, section "Separation datum")
    scene = scene_from_dict({"scene": {"name": "paper"}, "materials": {"hardness_gpa": 1.683}})
    ds = _open(ensure("roughness", scene, tmp_path))
    assert list(ds["surface"].values) == ["explicit", "combined"]
    sp = ds.sel({"surface": "combined", "route": "spectral"})
    sigma, eta, R = 0.52, 13.3e-6, 5000.0  # nm, nm^-2, nm (the paper scene's defaults, docs/model.md, section "Separation datum")
    assert float(sp["sigma"]) == pytest.approx(sigma)
    assert float(sp["summit_radius"]) == pytest.approx(5.0)
    assert float(sp["summit_density"]) == pytest.approx(13.3)
    assert float(sp["bandwidth_alpha"]) == pytest.approx(st.bandwidth_alpha(sigma, eta, R), rel=1e-5)
    assert float(sp["sigma_s"]) == pytest.approx(st.summit_sigma(sigma, eta, R), rel=1e-5)
    assert float(sp["y_s"]) == pytest.approx(st.summit_offset(sigma, eta, R), rel=1e-5)
    E = st.composite_modulus(150.0, 200.0, 0.3)
    assert ds.attrs["composite_modulus_gpa"] == pytest.approx(E)
    assert float(sp["plasticity_index"]) == pytest.approx(E / 1.683 * math.sqrt(st.summit_sigma(sigma, eta, R) / R),
                                                          rel=1e-5)
    assert float(sp["plasticity_index"]) == pytest.approx(0.52, abs=0.01)  # the paper's psi [paper]
    assert np.isnan(ds["sigma"].sel({"route": "summits"}).values).all()
    assert ds.attrs["scene_name"] == "paper"
    # without a hardness, the plasticity index is not defined
    ds2 = _open(ensure("roughness", scene_from_dict({}), tmp_path / "nohardness"))
    assert np.isnan(ds2["plasticity_index"].values).all()


def test_scene_with_afm_files_and_up_to_date_skip(two_files: list[Path], tmp_path: Path) -> None:
    scene = scene_from_dict({"roughness": {"afm": [str(f) for f in two_files], "detrend": "center"}})
    out = tmp_path / "res"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sf.SurfaceWarning)
        path = ensure("roughness", scene, out)
        stamp = path.stat().st_mtime_ns
        # inputs unchanged: not recomputed
        assert ensure("roughness", scene, out) == path and path.stat().st_mtime_ns == stamp
        os.utime(path, ns=(stamp - 10**9, stamp - 10**9))
        ensure("roughness", scene, out, force=True)
    assert path.stat().st_mtime_ns != stamp - 10**9
    assert list(_open(path)["surface"].values) == ["disk", "tfc", "combined"]
    # an input file changed in place (same path, new bytes) is recomputed
    m0 = float(_open(path)["m0"].sel(surface="disk"))
    _synthetic_file(two_files[0], 0.8, 6, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sf.SurfaceWarning)
        ensure("roughness", scene, out)
    # tol: a record scaled by 2: its moment by 4, up to ~log2(n) roundings of the mean
    assert float(_open(path)["m0"].sel(surface="disk")) == pytest.approx(4 * m0, rel=1e-12)


def test_failing_input_leaves_existing_output_untouched(two_files: list[Path], tmp_path: Path) -> None:
    out = tmp_path / "out"
    path = _run(two_files[:1], out)
    before = file_hash(path)
    bad = tmp_path / "broken.di"
    bad.write_text("not a Nanoscope file\n")
    with pytest.raises(afm_scan.AFMError, match="broken.di"):
        _run(two_files + [bad], out)
    assert file_hash(path) == before
    assert sorted(p.name for p in out.iterdir()) == ["roughness.nc"]  # no temporary leftovers


def test_unique_labels() -> None:
    labels = rough_model._unique_labels([Path("a/x.di"), Path("b/x.di"), Path("c/combined.nc"), Path("x.mi")])
    assert labels == ["x", "x-2", "combined-file", "x-3"]


def test_shared_afm_files(tmp_path: Path) -> None:
    files = [AFM / "di-3.di", AFM / "mi-1.mi"]
    ds = _open(_run(files, tmp_path))
    assert ds.attrs["channels"] == '{"di-3": "ZSensor", "mi-1": "Topography"}'
    # tol: the pixel size is a size over a count, one rounding
    np.testing.assert_allclose(ds["pixel_size"].values[:2], [10000 / 256, 20000 / 256])
    s = ds["sigma"].sel({"route": "spectral"}).values
    # tol: sigma^2 adds: square roots of sums of moments, a few roundings
    assert s[2] ** 2 == pytest.approx(s[0] ** 2 + s[1] ** 2, rel=1e-12)
    assert "mi-1: summit density eta differs" in ds.attrs["warnings"]
