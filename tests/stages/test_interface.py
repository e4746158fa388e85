"""Stage ``interface`` end to end through ``hdi interface`` (docs/datasets.md: interface.nc, provenance,
effects, atomic writes)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import pipeline
from pipeline import cli, io
from pipeline.config.scene import SCHEMA, load_scene
from pipeline.model import interface_tables
from pipeline.stages import interface
from pipeline.runner import ensure

TABLES = ("contact_pressure", "adhesion_pressure", "friction_stress", "real_area_fraction", "contact_fraction")


def _run(config, out, *overrides):
    argv = ["interface", str(config), "--out", str(out)]
    for o in overrides:
        argv += ["--set", o]
    assert cli.main(argv) == 0
    path = out / "interface.nc"
    assert path.is_file()
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


@pytest.fixture(scope="module")
def paper_ds(tmp_path_factory, paper_config):
    return _run(paper_config, tmp_path_factory.mktemp("paper"))


def test_every_variable_has_units_and_long_name(paper_ds):
    for name in list(paper_ds.data_vars) + list(paper_ds.coords):
        assert paper_ds[name].attrs.get("units"), name
        assert paper_ds[name].attrs.get("long_name"), name
    # the README units of interface.nc
    for name, units in [("separation", "nm"), ("contact_pressure", "MPa"), ("adhesion_pressure", "MPa"),
                        ("friction_stress", "MPa"), ("real_area_fraction", "1"), ("contact_fraction", "1")]:
        assert paper_ds[name].attrs["units"] == units


def test_paper_tables_present_and_grid(paper_ds):
    for name in TABLES:
        assert name in paper_ds.data_vars
        assert paper_ds[name].dims == ("separation",)
        assert np.all(np.isfinite(paper_ds[name].values))
    d = paper_ds["separation"].values
    sigma_s = float(paper_ds["sigma_s"])
    # docs/model.md, section "ISBL interface" / the brief: tables span at least -5 sigma_s .. 30 nm, uniform at solver.table_step_nm
    assert d[0] <= -5 * sigma_s
    assert d[-1] >= 30.0
    # tol: steps of the separation grid: rounding of d_i (|d|/step < 1e3) over the step
    np.testing.assert_allclose(np.diff(d), SCHEMA["solver"]["table_step_nm"].default, rtol=1e-9)


def test_paper_scalars(paper_ds):
    # Hand values (tests/physics/test_asperity_statistics.py) for eta = 13.3 um^-2 (docs/model.md, section "Separation datum"): sigma_s = 0.431680 nm,
    # y_s = 0.690889 nm, E' = 94.1915 GPa, H = 1.68308 GPa, psi_GW = 0.52 [paper], psi_KE = 0.573730
    assert float(paper_ds["sigma"]) == pytest.approx(0.52)
    assert float(paper_ds["sigma_s"]) == pytest.approx(0.431680, rel=1e-6)
    assert float(paper_ds["y_s"]) == pytest.approx(0.690889, rel=1e-6)
    assert float(paper_ds["composite_modulus"]) == pytest.approx(94.1915, rel=1e-6)
    assert float(paper_ds["hardness"]) == pytest.approx(1.68308, rel=1e-5)
    # tol: H is set from psi = 0.52: a round trip of a few roundings and a sqrt
    assert float(paper_ds["plasticity_index_gw"]) == pytest.approx(0.52, rel=1e-12)
    assert float(paper_ds["plasticity_index_ke"]) == pytest.approx(0.573730, rel=1e-5)
    assert float(paper_ds["summit_radius"]) == pytest.approx(5.0)
    assert float(paper_ds["summit_density"]) == pytest.approx(13.3)
    # the contact fraction at d = 0 is one half (the separation is from the mean of summit heights)
    assert float(paper_ds["contact_fraction"].interp(separation=0.0)) == pytest.approx(0.5, abs=1e-4)


def test_tables_match_the_physics_module(paper_ds, paper_scene):
    # the stage writes isbl_tables in MPa on its grid
    from pipeline.physics import isbl
    p = interface_tables.interface_parameters(paper_scene, interface_tables.roughness_statistics(paper_scene))
    d = paper_ds["separation"].values[::97] * 1e-9
    ref = isbl.isbl_tables(d, p)
    # tol: the same ISBL integrals of the same numbers, through NetCDF float64
    np.testing.assert_allclose(paper_ds["contact_pressure"].values[::97], ref["contact_pressure"] / 1e6, rtol=1e-12)
    # tol: the same ISBL integrals of the same numbers, through NetCDF float64
    np.testing.assert_allclose(paper_ds["adhesion_pressure"].values[::97], ref["adhesion_pressure"] / 1e6,
                               rtol=1e-12)


def test_provenance(paper_ds, paper_scene):
    attrs = paper_ds.attrs
    assert attrs["config_hash"] == paper_scene.hash
    assert attrs["pipeline_version"] == pipeline.__version__
    assert isinstance(attrs["git_revision"], str) and attrs["git_revision"]
    for key in ("title", "history", "source", "Conventions", "input_hashes", "stage"):
        assert key in attrs, key
    assert attrs["stage"] == "interface"


def test_override_reaches_the_dataset(tmp_path, paper_config, paper_scene):
    ds = _run(paper_config, tmp_path, "lubricant.thickness_nm=1.0")
    assert float(ds["lubricant_thickness"]) == 1.0
    assert ds.attrs["config_hash"] == load_scene(paper_config, ["lubricant.thickness_nm=1.0"]).hash
    assert ds.attrs["config_hash"] != paper_scene.hash
    assert "lubricant.thickness_nm=1.0" in ds.attrs["overrides"]


def test_without_adhesion_no_adhesion_variable(tmp_path, paper_config, paper_ds):
    ds = _run(paper_config, tmp_path, 'scene.effects=["air_bearing", "pitch", "dmw", "contact", "friction"]')
    assert "adhesion_pressure" not in ds.variables
    # the effects choose which tables are written, not their values: those left are the full scene's, bit for bit
    for name in ("contact_pressure", "friction_stress", "real_area_fraction", "contact_fraction"):
        assert np.array_equal(ds[name].values, paper_ds[name].values), name


def test_without_friction_no_friction_variable(tmp_path, paper_config, paper_ds):
    ds = _run(paper_config, tmp_path, 'scene.effects=["air_bearing", "pitch", "dmw", "adhesion", "contact"]')
    assert "friction_stress" not in ds.variables
    for name in ("adhesion_pressure", "contact_pressure"):                # the full scene's tables, bit for bit
        assert np.array_equal(ds[name].values, paper_ds[name].values), name


def test_adhesion_only(tmp_path, paper_config, paper_ds):
    ds = _run(paper_config, tmp_path, 'scene.effects=["air_bearing", "adhesion"]')
    assert np.array_equal(ds["adhesion_pressure"].values, paper_ds["adhesion_pressure"].values)
    for name in ("contact_pressure", "friction_stress", "real_area_fraction", "contact_fraction"):
        assert name not in ds.variables


def test_flying_only_scene_has_no_tables(tmp_path, paper_config):
    ds = _run(paper_config, tmp_path, 'scene.effects=["air_bearing"]')
    assert "separation" not in ds.dims and "separation" not in ds.variables
    for name in TABLES:
        assert name not in ds.variables
    # the interface parameters are still recorded
    assert "sigma_s" in ds.data_vars and "hardness" in ds.data_vars
    assert ds.attrs["effects"] == "air_bearing"


def test_bad_scene_is_a_clean_cli_error(tmp_path, paper_config, capsys):
    rc = cli.main(["interface", str(paper_config), "--out", str(tmp_path), "--set", "lubricant.thickness_nm=-1"])
    assert rc == 2
    err = capsys.readouterr().err
    # the bad value came from --set: the error names the option, not the (valid) file
    assert "--set lubricant.thickness_nm=-1: lubricant.thickness_nm" in err and str(paper_config) not in err
    assert not (tmp_path / "interface.nc").exists()


# (netCDF4's RuntimeError of a failed write is raised as an OSError naming the dataset: pipeline.file_errors.write_failure)
@pytest.mark.parametrize("exc, raised", [(RuntimeError("disk full"), OSError),
                                         (KeyboardInterrupt(), KeyboardInterrupt)])
def test_failed_write_keeps_previous_file(tmp_path, paper_config, monkeypatch, exc, raised):
    _run(paper_config, tmp_path)
    path = tmp_path / "interface.nc"
    before = path.read_bytes()

    def broken(ds, target, encoding):
        with open(target, "wb") as fh:           # a half-written file, then the failure
            fh.write(b"CDF\x01 half written")
        raise exc

    monkeypatch.setattr(io, "_to_netcdf", broken)  # (where write_dataset writes the bytes)
    scene = load_scene(paper_config, ["lubricant.thickness_nm=1.0"])
    with pytest.raises(raised):
        ensure("interface", scene, tmp_path)
    assert path.read_bytes() == before                       # the old file is intact
    # no temporary left (beside the file, the runner's records of the first run in .hdi/)
    assert sorted(p.name for p in tmp_path.iterdir()) == [".hdi", "interface.nc"]
    monkeypatch.undo()
    with xr.open_dataset(path, engine="netcdf4") as ds:
        assert float(ds["lubricant_thickness"]) == 0.75


def test_interrupted_cli_run_keeps_previous_file(tmp_path, paper_config, monkeypatch, capsys):
    _run(paper_config, tmp_path)
    before = (tmp_path / "interface.nc").read_bytes()

    def broken(ds, target, encoding):
        raise KeyboardInterrupt

    monkeypatch.setattr(io, "_to_netcdf", broken)
    assert cli.main(["interface", str(paper_config), "--out", str(tmp_path), "--force"]) == 130
    assert (tmp_path / "interface.nc").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [".hdi", "interface.nc"]  # (.hdi/: the runner's records)


def test_write_dataset_refuses_variables_without_units(tmp_path):
    ds = xr.Dataset({"x": ("n", np.arange(3.0))})
    with pytest.raises(io.DatasetError, match="units/long_name"):
        io.write_dataset(ds, tmp_path / "bad.nc", stage="test")
    assert list(tmp_path.iterdir()) == []


def test_load_missing_interface_dataset(tmp_path):
    with pytest.raises(io.DatasetError, match="hdi interface"):
        interface.load(tmp_path / "interface.nc")


def test_needed_quantities():
    assert interface_tables.needed_quantities(frozenset({"air_bearing"})) == ()
    assert set(interface_tables.needed_quantities(frozenset({"contact", "friction", "adhesion"}))) == set(TABLES)
    # the wetted area only for the lubricant-shear friction term
    assert set(interface_tables.needed_quantities(frozenset({"contact", "friction", "adhesion"}), True)) == \
        set(TABLES) | {"wetted_area_fraction"}
    assert "wetted_area_fraction" not in interface_tables.needed_quantities(frozenset({"contact"}), True)


def test_write_dataset_writes_what_to_netcdf_writes_without_importing_distributed(tmp_path):
    """``io._to_netcdf`` (the store of the netcdf4 engine, opened with our lock) gives the file
    ``Dataset.to_netcdf`` gives: same variables, types, fill values, attributes and values; and
    writing a dataset does not import dask.distributed (0.26 s of every process otherwise)."""
    import subprocess
    import sys
    import netCDF4
    ds = xr.Dataset({"x": ("n", np.array([1.5, np.nan, 3.0]), {"units": "nm", "long_name": "x"}),
                     "code": ("n", np.array([1, 2, -1], dtype="int8"), {"long_name": "code", "units": "1"})},
                    coords={"n": ("n", np.arange(3.0), {"units": "1", "long_name": "n"})})
    ds["code"].encoding["_FillValue"] = -1
    out, enc = io.cf_encoding(ds)
    with io.NETCDF_LOCK:
        io._to_netcdf(out, str(tmp_path / "ours.nc"), enc)
    out.to_netcdf(tmp_path / "xarray.nc", engine="netcdf4", encoding=enc)
    with netCDF4.Dataset(tmp_path / "ours.nc") as a, netCDF4.Dataset(tmp_path / "xarray.nc") as b:
        assert a.data_model == b.data_model == "NETCDF4"
        assert list(a.variables) == list(b.variables) and a.ncattrs() == b.ncattrs()
        for name in b.variables:
            va, vb = a.variables[name], b.variables[name]
            assert va.dtype == vb.dtype and va.dimensions == vb.dimensions
            assert {k: str(va.getncattr(k)) for k in va.ncattrs()} == {k: str(vb.getncattr(k)) for k in vb.ncattrs()}
            np.testing.assert_array_equal(np.ma.filled(va[:], -99), np.ma.filled(vb[:], -99))
    code = ("import sys, numpy as np, xarray as xr; from pipeline import io; "
            "ds = xr.Dataset({'x': ('n', np.arange(3.0), {'units': 'nm', 'long_name': 'x'})}); "
            f"io.write_dataset(ds, {str(tmp_path / 'fresh.nc')!r}, stage='test'); "
            "print('distributed' in sys.modules)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.strip() == "False"


def test_wetted_area_only_with_the_lubricant_shear_and_keyed_on_it_alone(tmp_path, paper_config):
    """The tables hold wetted_area_fraction only when the lubricant-shear term is on; the stage
    recomputes when the term is switched on, not when its stress changes (it only scales the column)."""
    out = tmp_path / "lub"
    assert "wetted_area_fraction" not in _run(paper_config, out)
    with_term = _run(paper_config, out, "lubricant.shear_stress_mpa=19")
    assert "wetted_area_fraction" in with_term
    stamp = (out / "interface.nc").stat().st_mtime_ns
    again = _run(paper_config, out, "lubricant.shear_stress_mpa=25")
    assert (out / "interface.nc").stat().st_mtime_ns == stamp
    np.testing.assert_array_equal(again["wetted_area_fraction"].values, with_term["wetted_area_fraction"].values)


def test_friction_column_of_a_per_summit_law_and_keyed_on_that_law_alone(tmp_path, paper_config):
    """A per-summit friction law (contact.friction_law = "kogut-etsion") makes the friction column its own
    integral, says so in the attributes and recomputes the tables; switching between the laws that read the
    shear-strength column ("shear-strength", "coefficient") leaves them as they are."""
    out = tmp_path / "law"
    plain = _run(paper_config, out)
    assert "friction_stress_law" not in plain.attrs
    stamp = (out / "interface.nc").stat().st_mtime_ns
    _run(paper_config, out, 'contact.friction_law="coefficient"', "contact.friction_coefficient=1.2")
    assert (out / "interface.nc").stat().st_mtime_ns == stamp
    ke = _run(paper_config, out, 'contact.friction_law="kogut-etsion"')
    assert ke.attrs["friction_stress_law"] == "kogut-etsion"
    for name in TABLES:  # only the friction column changes
        same = np.array_equal(ke[name].values, plain[name].values)
        assert same == (name != "friction_stress"), name
    assert np.all(ke["friction_stress"].values >= 0)
    back = _run(paper_config, out)
    assert "friction_stress_law" not in back.attrs
    np.testing.assert_array_equal(back["friction_stress"].values, plain["friction_stress"].values)
