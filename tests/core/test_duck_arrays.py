"""pipeline.duck_arrays: xarray's duck-array checks answered without importing dask, dask.array or pint, and
the same answers as xarray's own once they are imported."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

#: Run in a fresh interpreter (``defer`` or ``plain``): the modules imported by making a dataset and reading
#: one (a file written with netCDF4 alone, then opened, indexed and loaded by xarray), then xarray's handling
#: of a written and read dataset, of a masked dask array and of a pint quantity after their imports.
SCRIPT = r"""
import json, sys, tempfile, warnings
from pathlib import Path
warnings.simplefilter("ignore")
if sys.argv[1] == "defer":
    from pipeline import io
    from pipeline.duck_arrays import defer
    has_cache = defer()
import netCDF4, numpy as np, xarray as xr
ds = xr.Dataset({"a": ("x", np.arange(3.0), {"units": "nm", "long_name": "a"})},
                coords={"x": ("x", [1.0, 2.0, 3.0], {"units": "nm", "long_name": "x"})})
with tempfile.TemporaryDirectory() as tmp:
    with netCDF4.Dataset(Path(tmp) / "n.nc", "w") as nc:
        nc.createDimension("x", 3)
        nc.createVariable("x", "f8", ("x",))[:] = [1.0, 2.0, 3.0]
        nc.createVariable("a", "f8", ("x",))[:] = [0.0, 1.0, 2.0]
    read = xr.open_dataset(Path(tmp) / "n.nc", engine="netcdf4").load()
    selected = float(read["a"].sel(x=2.0))
    before = {m: m in sys.modules for m in ("dask", "dask.array", "pint")}
    ds.to_netcdf(Path(tmp) / "a.nc", engine="netcdf4")
    back = xr.open_dataset(Path(tmp) / "a.nc", engine="netcdf4").load()
import dask.array as da
masked = xr.DataArray(da.from_array(np.ma.masked_array([1.0, 2.0, 3.0], mask=[0, 1, 0]), chunks=1), dims="y")
chunked = xr.DataArray(da.ones(4, chunks=2), dims="z")
import pint
q = xr.Variable("q", pint.UnitRegistry().Quantity(np.array([1.0, 2.0]), "m"))
print(json.dumps({"before": before, "back": back["a"].values.tolist(), "selected": selected,
                  "masked": [None if v != v else v for v in masked.values.tolist()],
                  "chunks": [list(c) for c in chunked.chunks], "sum": float(chunked.sum().compute()),
                  "quantity": type(q.data).__name__, "magnitude": np.asarray(q.data.magnitude).tolist(),
                  "has_cache": has_cache if sys.argv[1] == "defer" else None}))
"""


def _run(mode: str) -> dict:
    out = subprocess.run([sys.executable, "-c", SCRIPT, mode], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def runs() -> dict[str, dict]:
    return {mode: _run(mode) for mode in ("defer", "plain")}


def test_this_xarray_has_the_cache_and_a_dataset_imports_none_of_the_modules(runs):
    assert runs["defer"]["has_cache"] is True
    assert runs["defer"]["before"] == {"dask": False, "dask.array": False, "pint": False}
    # without the stand-ins, xarray imports dask and dask.array for the same datasets
    assert runs["plain"]["before"]["dask"] is True and runs["plain"]["before"]["dask.array"] is True


def test_xarray_s_answers_are_its_own_once_the_modules_are_imported(runs):
    defer, plain = runs["defer"], runs["plain"]
    for key in ("back", "selected", "masked", "chunks", "sum", "quantity", "magnitude"):
        assert defer[key] == plain[key], key
    assert defer["masked"] == [1.0, None, 3.0]  # a masked dask array: its mask turned into NaN
    assert defer["quantity"] == "Quantity" and defer["chunks"] == [[2, 2]]


def test_a_stand_in_hands_over_to_xarray_s_entry():
    from xarray.namedarray import pycompat
    from pipeline.duck_arrays import _Deferred
    cache: dict = {}
    stand_in = _Deferred("dask", "dask.array", cache, pycompat.DuckArrayModule)
    cache["dask"] = stand_in
    import dask.array as da  # (imported by now in this test session anyway)
    assert stand_in.type == (da.Array,)
    assert isinstance(cache["dask"], pycompat.DuckArrayModule)  # replaced in the cache
    absent = _Deferred("nosuch", "pipeline_no_such_module", {}, pycompat.DuckArrayModule)
    assert absent.type == ()


def test_the_dask_collection_check_answers_as_dask_does():
    """Without ``__dask_graph__`` the answer is no, without asking xarray (which would import dask); with it,
    xarray's function answers (here: dask's own verdict on a dask array and on a look-alike)."""
    from xarray.namedarray import utils
    from pipeline.duck_arrays import _dask_collection_check
    asked = []
    original = getattr(utils.is_dask_collection, "__wrapped__", utils.is_dask_collection)  # (xarray's own)

    def xarray_check(x: object) -> bool:
        asked.append(x)
        return original(x)

    check = _dask_collection_check(xarray_check)
    import dask.array as da

    class LookAlike:  # the protocol's method, returning no graph: dask says no
        def __dask_graph__(self):
            return None

    for x in (np.arange(3.0), 1.0, "a", None):
        assert check(x) is False
    assert asked == []
    assert check(da.ones(2)) is True and check(LookAlike()) is False and len(asked) == 2
    # xarray's own homes of the function hold the check once pipeline.io is imported
    import pipeline.io  # noqa: F401
    from xarray.core import utils as core_utils
    assert utils.is_dask_collection is core_utils.is_dask_collection
    assert getattr(utils.is_dask_collection, "__wrapped_by_hdi__", False)
