"""The datasets on disk (pipeline/io.py): a dataset written with its units reads back bit for bit, its time
coordinate ``elapsed_time`` on disk and in memory alike; a variable without units or long_name is refused naming
the file; a missing or unreadable dataset is one error naming the file (and the stage to run); temporary names
are recognised as hdi's own and no other; chunks and compression follow the sizes documented in the module;
an OSError is one line naming the path and what to do."""

from __future__ import annotations

import errno
import json

import netCDF4
import numpy as np
import pytest
import xarray as xr

from pipeline import file_errors, io
from pipeline.variables import TIME


def _history(n: int = 3000) -> xr.Dataset:
    t = np.arange(n) * 250e-9
    return xr.Dataset({"clearance": io.var(np.sin(t * 1e4) + 1.5, TIME, "nm", "TFC-point clearance")},
                      coords={TIME: io.var(t, TIME, "s", "elapsed simulated time")})


def test_a_dataset_reads_back_bit_for_bit_under_one_time_name(tmp_path):
    ds = _history()
    path = io.write_dataset(ds, tmp_path / "sub" / "histories.nc", stage="simulate", extra_attrs={"k": 0.978})
    assert path == tmp_path / "sub" / "histories.nc"
    with netCDF4.Dataset(path) as nc:
        assert TIME in nc.variables and "time" not in nc.variables      # one name on disk and in memory
        assert nc.variables["clearance"].units == "nm"
    back = io.read_dataset(path, stage="simulate", variables=["clearance"])
    np.testing.assert_array_equal(back[TIME].values, ds[TIME].values)
    np.testing.assert_array_equal(back["clearance"].values, ds["clearance"].values)
    assert back.attrs["k"] == 0.978 and back["clearance"].attrs["long_name"] == "TFC-point clearance"
    attrs, values = io.read_attrs(path, ["clearance", "nothing"])
    assert attrs["k"] == 0.978 and list(values) == ["clearance"]
    assert [p.name for p in path.parent.iterdir()] == ["histories.nc"]      # no temporary left


def test_a_variable_without_units_is_refused_naming_the_file(tmp_path):
    bad = xr.Dataset({"x": ("n", [1.0, 2.0], {"long_name": "x"})}, coords={"n": io.var([0, 1], "n", "1", "n")})
    with pytest.raises(io.DatasetError, match=r"bad\.nc: variables without units/long_name: \['x'\]"):
        io.write_dataset(bad, tmp_path / "bad.nc", stage="report")
    assert not list(tmp_path.iterdir())
    labels = xr.Dataset({"name": ("n", ["a", "b"], {"long_name": "label"})})   # strings carry no units in CF
    io.check_cf(labels)


def test_a_missing_or_unreadable_dataset_is_one_error_naming_it(tmp_path):
    with pytest.raises(io.DatasetError, match=r"dmw\.nc: dataset does not exist \(run `hdi dmw` first\)"):
        io.read_dataset(tmp_path / "dmw.nc", stage="dmw")
    (tmp_path / "junk.nc").write_text("not netcdf")
    with pytest.raises(io.DatasetError, match=r"junk\.nc: not a readable NetCDF dataset"):
        io.read_dataset(tmp_path / "junk.nc")
    path = io.write_dataset(_history(10), tmp_path / "h.nc", stage="simulate")
    with pytest.raises(io.DatasetError, match=r"h\.nc: missing variables \['contact_force'\]"):
        io.read_dataset(path, variables=["clearance", "contact_force"])


def test_temporary_names_are_hdis_own_of_any_run_and_no_other():
    tmp = io.temporary_path("results/paper/sweep.nc")
    assert tmp.parent.as_posix() == "results/paper" and tmp.name == f".sweep.nc.hdi-{io.RUN_ID}.tmp"
    assert io.is_temporary(tmp.name)
    assert io.is_temporary(io.temporary_prefix("dmw.nc") + "k2j3h4.tmp")        # mkstemp's random part
    assert io.is_temporary(".batch-00003.nc.hdi-0123456789ab.x8y.tmp")           # another run's
    for name in ("sweep.nc", "notes.tmp", ".sweep.nc.tmp", ".sweep.nc.hdi-0123.tmp", ".x.hdi-0123456789AB.tmp",
                 "sweep.nc.hdi-0123456789ab.tmp"):
        assert not io.is_temporary(name), name


def test_var_carries_units_and_long_name_and_no_units_for_a_label():
    v = io.var([1.0], "n", "nm", "gap", standard_name="x")
    assert v.attrs == {"units": "nm", "long_name": "gap", "standard_name": "x"}
    assert "units" not in io.var(["a"], "n", "", "label").attrs


# ----------------------------------------------------------------- stored values checked when read back
def _mixed(n: int = 3000) -> xr.Dataset:
    """A dataset of every kind hdi writes: a compressed history, NaN, a flag with a declared missing value,
    booleans, labels and a 64-bit integer stored as 32-bit."""
    ds = _history(n)
    ds["clearance"][5] = np.nan
    ds["regime"] = io.var(np.array([0, 1, 2, -1], dtype="int8"), "point", "1", "regime")
    ds["regime"].encoding["_FillValue"] = np.int8(-1)
    ds["stable"] = io.var(np.array([True, False, True, True]), "point", "1", "stable")
    ds["count"] = io.var(np.arange(4, dtype="int64"), "point", "1", "count")
    ds.coords["label"] = ("point", ["flying", "a", "surfing", "émoi"], {"long_name": "label"})
    return ds


def test_every_variable_carries_a_checksum_and_reads_back_equal_to_it(tmp_path):
    path = io.write_dataset(_mixed(), tmp_path / "h.nc", stage="simulate")
    written = json.loads(io.read_attrs(path)[0][io.CHECKSUM_ATTR])
    assert sorted(written) == sorted(["clearance", TIME, "regime", "stable", "count", "label"])
    back = io.read_dataset(path)                      # (checked: no variable differs from its checksum)
    assert np.isnan(back.regime.values[3]) and back.label.values[3] == "émoi"
    assert io.data_checksums(back) == written        # what is read back is what was written
    assert io.stored_problem(path) is None
    plain = tmp_path / "plain.nc"                      # a dataset written without them reads unchecked ...
    _history(10).to_netcdf(plain, engine="netcdf4")
    assert float(io.read_dataset(plain).clearance[0]) == 1.5
    assert io.stored_problem(plain) == "has no data checksums"   # ... but is never reused by the runner


def test_a_damaged_chunk_is_one_line_naming_the_file_and_the_variable(tmp_path):
    from damage import damage_chunk
    path = io.write_dataset(_mixed(), tmp_path / "h.nc", stage="simulate")
    damage_chunk(path, "clearance")
    with pytest.raises(RuntimeError, match="HDF error"):   # (what netCDF4 says of it: a traceback before)
        with netCDF4.Dataset(path) as nc:
            nc.variables["clearance"][:]
    with pytest.raises(io.DatasetDamaged, match=r"h\.nc: variable 'clearance': its data cannot be read back "
                                                r"\(NetCDF: HDF error\); run `hdi simulate` again") as info:
        io.read_dataset(path, stage="simulate")
    assert "\n" not in str(info.value)
    assert io.stored_problem(path).startswith("variable 'clearance': its data cannot be read back")


def test_a_value_edited_by_hand_is_refused_naming_the_variable(tmp_path):
    from damage import edit_value
    path = io.write_dataset(_mixed(), tmp_path / "h.nc", stage="simulate")
    io.read_dataset(path)
    edit_value(path, "count", (2,), 7)            # (in place, every attribute kept: an inputs key still equal)
    with pytest.raises(io.DatasetDamaged, match=r"h\.nc: variable 'count': values differ from the checksum "
                                                r"written with them \(damaged, or edited since hdi wrote it\)"):
        io.read_dataset(path)
    path = io.write_dataset(_mixed(), tmp_path / "g.nc", stage="simulate")
    ds = xr.open_dataset(path, engine="netcdf4").load()   # an edit through xarray, the attributes carried over
    ds["clearance"] = ds.clearance * 2
    ds.to_netcdf(tmp_path / "g2.nc", engine="netcdf4")
    assert "variable 'clearance': values differ" in io.stored_problem(tmp_path / "g2.nc")
    ds = xr.open_dataset(path, engine="netcdf4").load()
    ds["extra"] = ds.clearance
    ds.to_netcdf(tmp_path / "g3.nc", engine="netcdf4")
    assert io.stored_problem(tmp_path / "g3.nc") == "variable 'extra': not written by hdi (added since)"


def test_a_full_disk_is_said_so_naming_the_dataset(tmp_path, monkeypatch):
    """The HDF5 library reports a file it could not create for want of space as "Permission denied"
    (EACCES), in a folder where the temporary file was just made: said to be a full disk, by the free space."""
    def denied(ds, path, encoding):
        raise PermissionError(errno.EACCES, "Permission denied", path)
    monkeypatch.setattr(io, "_to_netcdf", denied)
    monkeypatch.setattr(file_errors.shutil, "disk_usage", lambda p: _usage(4096))
    with pytest.raises(OSError) as info:
        io.write_dataset(_history(), tmp_path / "h.nc", stage="simulate")
    line = file_errors.os_error_line(info.value)
    assert line.startswith(f"{tmp_path / 'h.nc'}: No space left on device (0.0041 MB free") and \
        line.endswith("the disk is full: free some space or choose another --out"), line
    assert list(tmp_path.iterdir()) == []                                     # no temporary left

    def full(ds, path, encoding):
        raise OSError(errno.ENOSPC, "No space left on device", path)
    monkeypatch.setattr(io, "_to_netcdf", full)
    with pytest.raises(OSError) as info:
        io.write_dataset(_history(), tmp_path / "h.nc", stage="simulate")
    assert file_errors.os_error_line(info.value) == (f"{tmp_path / 'h.nc'}: No space left on device; the disk is full: "
                                            "free some space or choose another --out")
    monkeypatch.setattr(file_errors.shutil, "disk_usage", lambda p: _usage(10**9))  # (space enough: denied it is)
    monkeypatch.setattr(io, "_to_netcdf", denied)
    monkeypatch.setattr(file_errors.os, "access", lambda p, mode: False)
    with pytest.raises(PermissionError, match="Permission denied"):
        io.write_dataset(_history(), tmp_path / "h.nc", stage="simulate")


def _usage(free: int):
    """A disk of 1 GB with `free` bytes [B] free (what shutil.disk_usage returns)."""
    import shutil
    return shutil._ntuple_diskusage(10**9, 10**9 - free, free)
