"""Runs combine: each run's own k, bearing values and roughness survive ``xr.open_mfdataset`` over the
``sweep.nc`` of several runs; and the datasets are compressed (zlib with shuffle, chunked by grid point)."""

from __future__ import annotations

from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from pipeline import encoding, io
from pipeline.config.grid import scene_label
from pipeline.config.scene import load_scene
from pipeline.stages import sweep
from pipeline.variables import RUN

ROOT = Path(__file__).resolve().parents[2]
#: A quick scene: two protrusions, short runs, no DMW record, one history kept.
QUICK = ['scene.effects=["air_bearing","pitch","contact"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
         "sweep.protrusion_nm={start=9.5, stop=10.0, step=0.5}", "sweep.batch_size=2",
         "sweep.histories_nm=[10.0]", "report.histories_nm=[10.0]"]
#: Two runs: contact.k and the scene's roughness differ (each sweeps the scene's own roughness).
RUNS = {"a": ["contact.k=0.5", "roughness.sigma_nm=0.4"], "b": ["contact.k=0.7", "roughness.sigma_nm=0.6"]}

#: How the README combines runs: ``coords``/``compat`` explicit, as xarray's announced defaults
#: (``coords="minimal"``, ``compat="override"``) would keep the first run's ``roughness_sigma`` alone.
COMBINE = {"combine": "nested", "concat_dim": "run", "join": "outer", "coords": "different",
           "compat": "no_conflicts"}


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, tuple]:
    """run name -> (scene, sweep.nc path) of two small sweeps."""
    out = {}
    for name, sets in RUNS.items():
        scene = load_scene(ROOT / "configs" / "paper-2009.toml", QUICK + sets)
        out[name] = scene, sweep.run_sweep(scene, tmp_path_factory.mktemp(name), scheduler="synchronous")
    return out


@pytest.mark.parametrize("new_defaults", [False, True])
def test_open_mfdataset_keeps_each_runs_k_and_roughness(runs, new_defaults):
    """Nested on a new dimension ``run``: each run's k, k_source and bearing stiffnesses (0-d variables,
    where the global attribute ``k`` would keep the first run's), and each roughness set's sigma along
    ``roughness`` (labels made from the values: the two sets do not collide on ``"scene"``). Under
    xarray's present and announced combine defaults alike, with the arguments the README gives."""
    paths = [p for _, p in runs.values()]
    with xr.set_options(use_new_combine_kwarg_defaults=new_defaults), \
            xr.open_mfdataset(paths, engine="netcdf4", **COMBINE) as ds:
        assert ds.attrs["k"] == 0.5  # (what the attribute alone gave: the first run's)
        np.testing.assert_array_equal(ds["k"].values, [0.5, 0.7])
        assert ds["k"].dims == ("run",) and ds["k"].attrs["units"] == RUN["k"].units
        assert list(ds["k_source"].values) == ["scene (contact.k)"] * 2
        assert ds.sizes["roughness"] == 2
        for r, (name, (scene, path)) in enumerate(runs.items()):
            label = scene_label(scene)
            assert float(ds["roughness_sigma"].sel(roughness=label)) == scene["roughness"]["sigma_nm"]
            with xr.open_dataset(path, engine="netcdf4") as one:
                assert one.attrs["scene_roughness"] == label
                assert float(ds["front_stiffness"][r]) == float(one["front_stiffness"]) == one.attrs["front_stiffness_n_m"]
                np.testing.assert_array_equal(ds["fhm_bv"].isel(run=r).sel(roughness=label).values,
                                              one["fhm_bv"].sel(roughness=label).values)
                others = [lab for lab in ds["roughness"].values if lab != label]
                assert np.isnan(ds["fhm_bv"].isel(run=r).sel(roughness=others).values).all()
        # k sigma is a roughness set's: each run's along its own set (NaN for the set it did not run)
        assert ds["k_sigma"].dims == ("run", "roughness")
        for r, ((scene, _), k_sigma) in enumerate(zip(runs.values(), (0.5 * 0.4, 0.7 * 0.6))):
            # tol: the same product 0.5 sigma, through NetCDF float64
            assert float(ds["k_sigma"].isel(run=r).sel(roughness=scene_label(scene))) == pytest.approx(k_sigma, rel=1e-15)


def test_open_mfdataset_by_coords_concatenates_the_roughness_sets(runs):
    """Combined by their coordinates the runs line up along ``roughness``, each set with its own sigma."""
    paths = [p for _, p in runs.values()]
    with xr.open_mfdataset(paths, engine="netcdf4", combine="by_coords", data_vars="all", coords="different",
                           compat="equals", join="outer") as ds:
        labels = [scene_label(scene) for scene, _ in runs.values()]
        assert sorted(ds["roughness"].values) == sorted(labels)
        for scene, _ in runs.values():
            label = scene_label(scene)
            assert float(ds["roughness_sigma"].sel(roughness=label)) == scene["roughness"]["sigma_nm"]
            assert float(ds["k"].sel(roughness=label)) == scene["contact"]["k"]


def _compressed(var: netCDF4.Variable) -> bool:
    filters = var.filters() or {}
    return bool(filters.get("zlib")) and bool(filters.get("shuffle")) and var.chunking() != "contiguous"


def test_every_large_numeric_variable_is_compressed_and_reads_back_bit_for_bit(runs, tmp_path):
    """Every numeric variable of at least encoding.COMPRESS_FROM bytes is stored with zlib and shuffle; smaller
    ones contiguous (HDF5's chunk index would outweigh the saving), strings never compressed."""
    scene, path = runs["a"]
    files = [path, path.with_name("sweep_histories.nc")]
    big = 1.0 + np.arange(2000 * 3 * 2, dtype=float).reshape(2000, 3, 2) / 7.0  # (above encoding.WHOLE_BELOW)
    grid = xr.Dataset({"fhm_bv": (("protrusion", "roughness", "damping"), big, {"units": "%", "long_name": "f"})},
                      coords={"protrusion": ("protrusion", np.arange(2000.0), {"units": "nm", "long_name": "p"}),
                              "roughness": ("roughness", ["a", "b", "c"], {"long_name": "set"}),
                              "damping": ("damping", [0.01, 0.02], {"units": "1", "long_name": "zeta"})})
    files.append(io.write_dataset(grid, tmp_path / "grid.nc", stage="test"))
    seen = 0
    for f in files:
        large = []
        with netCDF4.Dataset(f) as nc:
            for name, v in nc.variables.items():
                nbytes = int(np.prod(v.shape)) * v.dtype.itemsize
                if v.dtype.kind in "fiu" and v.ndim and nbytes >= encoding.COMPRESS_FROM:
                    assert _compressed(v), (f.name, name)
                    large.append(name)
                else:
                    assert not (v.filters() or {}).get("zlib"), (f.name, name)
        with xr.open_dataset(f, engine="netcdf4") as ds:  # (as xarray reports it: encoding read back)
            for name in large:
                assert ds[name].encoding["zlib"] and ds[name].encoding["shuffle"], (f.name, name)
        seen += len(large)
    assert seen >= 5  # (the histories and the large grid variable)
    with netCDF4.Dataset(files[-1]) as nc:  # one protrusion row of one roughness set x damping ratio per chunk
        assert nc.variables["fhm_bv"].chunking() == [2000, 1, 1]
    back = io.read_dataset(files[-1])
    assert back["fhm_bv"].values.tobytes() == big.tobytes()
