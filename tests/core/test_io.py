"""The datasets on disk (pipeline/io.py): a dataset written with its units reads back bit for bit, its time
coordinate ``elapsed_time`` on disk and in memory alike; a variable without units or long_name is refused naming
the file; a missing or unreadable dataset is one error naming the file (and the stage to run); temporary names
are recognised as hdi's own and no other; chunks and compression follow the sizes documented in the module;
an OSError is one line naming the path and what to do."""

from __future__ import annotations

import errno

import netCDF4
import numpy as np
import pytest
import xarray as xr

from pipeline import io
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


def test_compression_follows_the_documented_sizes():
    # under COMPRESS_FROM (4 kB), a scalar or an empty variable: contiguous, no filter
    assert io.compression(("protrusion",), (511,), 8) == {}
    assert io.compression((), (), 8) == {} and io.compression(("protrusion",), (0,), 8) == {}
    # from 4 kB to 64 kB: one chunk
    small = io.compression(("protrusion", "roughness"), (256, 2), 8)
    assert small == {"zlib": True, "complevel": io.ZLIB_LEVEL, "shuffle": True, "chunksizes": (256, 2)}
    # a sweep's scalars: one protrusion row per roughness x damping point
    assert io.compression(("protrusion", "roughness", "damping"), (200, 8, 8), 8)["chunksizes"] == (200, 1, 1)
    # a kept history: the time axis whole per protrusion; halved along it while above CHUNK_MAX (4 MB)
    assert io.compression(("hist_protrusion", TIME), (3, 400_000), 8)["chunksizes"] == (1, 400_000)
    big = io.compression(("hist_protrusion", TIME), (2, 1_200_000), 8)["chunksizes"]
    assert big == (1, 300_000) and big[1] * 8 <= io.CHUNK_MAX < 2 * big[1] * 8


@pytest.mark.parametrize("exc, line", [
    (OSError(errno.ENOSPC, "No space left on device", "out/sweep.nc"),
     "out/sweep.nc: No space left on device; free some space or choose another --out"),
    (IsADirectoryError(errno.EISDIR, "Is a directory", "out/.tmp", None, "out/sweep.nc"),
     "out/sweep.nc: Is a directory; it is a folder where hdi writes a file: remove or rename it"),
    (OSError(errno.EACCES, "already says what to do; chmod it", "x.nc"), "x.nc: already says what to do; chmod it"),
    (OSError(errno.EBADF, "Bad file descriptor"), "Bad file descriptor")],
    ids=["full-disk", "folder-for-a-file", "own-advice", "no-path"])
def test_an_os_error_is_one_line_with_the_path_and_what_to_do(exc, line):
    assert io.os_error_line(exc) == line


def test_var_carries_units_and_long_name_and_no_units_for_a_label():
    v = io.var([1.0], "n", "nm", "gap", standard_name="x")
    assert v.attrs == {"units": "nm", "long_name": "gap", "standard_name": "x"}
    assert "units" not in io.var(["a"], "n", "", "label").attrs
