"""A dataset's form on disk: its CF encoding (:func:`cf_encoding`: time units, fill values, strings) and the
compression and chunks of each variable (:func:`compression`), which :func:`pipeline.io.write_dataset` applies.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from .variables import TIME


#: Units of the elapsed time (:data:`pipeline.variables.TIME`) in files written when its coordinate was
#: ``time`` (read back as seconds, under its one name).
OLD_TIME_UNITS = "s since 1970-01-01 00:00:00"


def cf_encoding(ds: xr.Dataset, compress: bool = True) -> tuple[xr.Dataset, dict[str, dict[str, Any]]]:
    """A copy of ``ds`` and its NetCDF encoding, arranged for CF-1.8 (see :mod:`pipeline.variables`).

    Coordinates get no ``_FillValue``; labels (strings) lose ``units`` and are stored as character
    arrays; 64-bit integers are stored as 32-bit (CF 2.2) when their values fit; numeric variables are
    compressed and chunked (:func:`compression`; lossless: the values read back bit for bit), unless
    ``compress`` is false (then stored contiguous). Declared missing values already in a variable's
    encoding (``regime``) are kept.
    """
    out = ds.copy()
    encoding: dict[str, dict[str, Any]] = {}
    for name in list(out.variables):
        v = out[name]
        enc: dict[str, Any] = {k: val for k, val in v.encoding.items() if k == "_FillValue"}
        if name in out.coords:
            enc["_FillValue"] = None
        if v.dtype.kind in "OUS":
            out[name].attrs.pop("units", None)
            enc["dtype"] = "S1"
            enc.pop("_FillValue", None)
        elif v.dtype == "int64" and (v.size == 0 or (abs(v.values).max() < 2**31)):
            enc["dtype"] = "int32"
        if compress and v.dtype.kind not in "OUS":
            enc.update(compression(v.dims, v.shape, v.dtype.itemsize))
        encoding[name] = enc
    return out, encoding


#: zlib level of the numeric variables hdi compresses (on the histories of ``make run``: 0.5 % larger
#: than level 9, in 60 % of its time).
ZLIB_LEVEL = 4
#: Dimensions that index grid points of a study (one roughness set, one damping ratio, one DMW
#: realisation, one pass of a stepping chain): a chunk holds one point, so reading one slice
#: (``sw.fhm_bv.sel(roughness=..., damping=...)``) decompresses only that slice's protrusion rows.
POINT_DIMS = frozenset({"roughness", "damping", "realisation", "direction", "protrusion", "hist_protrusion"})
#: Dimensions a chunk spans whole (a time history, a protrusion row of the sweep's scalars).
ROW_DIMS = (TIME, "protrusion")
#: A variable smaller than this [B] is stored contiguous and uncompressed: HDF5 spends about 3 kB on the
#: chunk index of every chunked variable, more than zlib saves on a few hundred doubles (measured on the
#: datasets of ``make run``: compressing every variable made sweep.nc 105 kB instead of 50 kB).
COMPRESS_FROM = 4 * 1024
#: A variable smaller than this [B] is one chunk.
WHOLE_BELOW = 64 * 1024
#: Largest chunk [B] (reading one value decompresses its whole chunk).
CHUNK_MAX = 4 * 1024 * 1024


def compression(dims: tuple, shape: tuple, itemsize: int) -> dict[str, Any]:
    """NetCDF4 encoding of a numeric variable: zlib (:data:`ZLIB_LEVEL`) with the shuffle filter, and
    chunks fitted to how the datasets are read.

    The chunk spans the variable whole along its row dimension (the first of :data:`ROW_DIMS` it has:
    ``elapsed_time`` for a history, else ``protrusion``) and every dimension not in :data:`POINT_DIMS`,
    and one point along the other :data:`POINT_DIMS`: in ``sweep.nc`` one chunk is the protrusion row
    of one roughness set x damping ratio (x pass x realisation); in ``sweep_histories.nc`` one time
    history. A variable under :data:`WHOLE_BELOW` is one chunk; a chunk above :data:`CHUNK_MAX` is
    halved along its longest side. Variables under :data:`COMPRESS_FROM`, scalars (0-d) and empty
    variables are stored contiguous, uncompressed (HDF5 filters need chunks, which 0-d and empty
    variables cannot have).
    """
    size = int(np.prod(shape)) * itemsize
    if not shape or size < COMPRESS_FROM:
        return {}
    if size < WHOLE_BELOW:
        chunks = list(shape)
    else:
        row = next((d for d in ROW_DIMS if d in dims), None)
        chunks = [n if d == row or d not in POINT_DIMS else 1 for d, n in zip(dims, shape)]
    while int(np.prod(chunks)) * itemsize > CHUNK_MAX:
        j = int(np.argmax(chunks))
        chunks[j] = -(-chunks[j] // 2)
    return {"zlib": True, "complevel": ZLIB_LEVEL, "shuffle": True, "chunksizes": tuple(chunks)}
