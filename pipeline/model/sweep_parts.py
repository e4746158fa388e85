"""The sweep's part files: one batch's dataset as written into ``sweep.parts/`` and read back.

A batch (:class:`Batch`: protrusions of one roughness set, damping ratio and DMW realisation) writes its
dataset (:func:`pipeline.model.simulation.simulate`) into its own part file, ``sweep.parts/batch-<index>.nc``
(:func:`part_path`). A part holds the batch's variables stacked by dimensions (:func:`pack_part`: two or three
NetCDF variables instead of ~35, each of which cost ~1 ms to write under the process's NetCDF lock) and is read
back as the batch's dataset itself (:func:`read_part`). A part is kept for resuming when it carries the sweep's
inputs key, its own batch index and its batch's coordinates and its values still match their checksums
(:func:`part_problem`); :func:`kept_parts` reads those of an earlier run.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Iterator

import numpy as np
import xarray as xr

from ..io import KEY_ATTR, read_attrs, read_dataset, stored_problem
from ..variables import PART_STACK, PART_STACKS, is_part_stack

#: The folder of the parts, in the results folder.
PARTS = "sweep.parts"


@dataclass(frozen=True)
class Batch:
    """One task: protrusions ``indices`` of roughness set ``label`` at damping ``damping``.

    ``damping``: modal damping ratio [1]; ``indices``: positions on the protrusion grid;
    ``protrusions``: their values [nm]; ``realisation``: index of the DMW record (0: the scene's).
    """

    index: int
    label: str
    damping: float
    indices: tuple[int, ...]
    protrusions: tuple[float, ...]
    realisation: int = 0


def part_path(parts: Path, b: Batch) -> Path:
    """The part file of batch ``b`` in the folder ``parts`` (``<out>/sweep.parts``)."""
    return parts / f"batch-{b.index:05d}.nc"


def part_problem(path: Path, key: str, batch: Batch) -> str | None:
    """Why a part file cannot be used for ``batch`` of the sweep with inputs ``key`` (``None``: it can).

    A part must exist, be readable, carry the sweep's inputs key, and be the part of this very batch:
    its batch index, roughness label, damping ratio and protrusions.
    """
    if not path.is_file():
        return "missing"
    try:
        attrs, values = read_attrs(path, ("protrusion",))
    except (OSError, ValueError, RuntimeError) as exc:  # (RuntimeError: the HDF5 library's "HDF error")
        return f"unreadable ({exc})"
    prot = np.asarray(values.get("protrusion", []), float)
    if attrs.get(KEY_ATTR) != key:
        return "made from other inputs"
    if attrs.get("batch") != batch.index:
        return f"holds batch {attrs.get('batch')}, not {batch.index}"
    if attrs.get("roughness_label") != batch.label or attrs.get("damping_ratio") != batch.damping:
        return (f"holds roughness {attrs.get('roughness_label')!r}, damping {attrs.get('damping_ratio')}; "
                f"expected {batch.label!r}, {batch.damping}")
    if prot.shape != (len(batch.protrusions),) or not np.array_equal(prot, batch.protrusions):
        return f"holds protrusions {prot.tolist()}, expected {list(batch.protrusions)}"
    return stored_problem(path)  # (damaged or edited since written: its values differ from their checksums)


#: Global attribute of a part file: its variables as :func:`unpack_part` restores them (JSON).
LAYOUT_ATTR = "part_layout"


def _stack_name(dims: tuple[str, ...]) -> str:
    """The stacked variable of a part that holds its variables of dimensions ``dims``."""
    return PART_STACK + "".join("__" + d for d in dims)


def pack_part(ds: xr.Dataset) -> xr.Dataset:
    """A part (a :func:`pipeline.model.simulation.simulate` dataset) as written to its file: the data
    variables of equal dimensions stacked into one float64 variable along a new first dimension
    (``stack__protrusion``: the scalars, ``stack__hist_protrusion__elapsed_time``: the kept histories),
    with the names and units of its rows as coordinates.

    Why: writing a NetCDF variable costs ~1 ms of Python and HDF5 whatever its size (33 variables: ~50 ms
    per part, under the process's NetCDF lock, holding the GIL most of it), which the threads of a sweep
    cannot share. Float64 holds every value of the parts exactly (float32 and int8 flags included), and
    the global attribute :data:`LAYOUT_ATTR` keeps each variable's name, dtype, attributes and encoding in
    order, so :func:`unpack_part` gives back ``ds`` itself (tests/model/test_sweep_parts.py).
    """
    variables = {name: ds.variables[name] for name in ds.data_vars}  # (Variables: no DataArray made per name)
    groups: dict[tuple[str, ...], list[str]] = {}
    for name, v in variables.items():
        groups.setdefault(v.dims, []).append(name)
    data: dict[str, xr.Variable] = {}
    coords = {name: ds.variables[name] for name in ds.coords}
    for dims, names in groups.items():
        stack = _stack_name(dims)
        row = f"{stack}_variable"
        data[stack] = PART_STACKS[PART_STACK].data(np.stack([variables[n].values.astype(np.float64) for n in names]),
                                                   (row, *dims), unit_variable=f"{stack}_units")
        coords[row] = PART_STACKS[PART_STACK + "_variable"].data(names, (row,))
        coords[f"{stack}_units"] = PART_STACKS[PART_STACK + "_units"].data(
            [variables[n].attrs.get("units", "") for n in names], (row,))
    layout = []
    for name, v in variables.items():
        enc = {k: np.dtype(val).str if k == "dtype" else _json_value(val) for k, val in v.encoding.items()
               if k in ("_FillValue", "dtype")}
        layout.append([name, v.dtype.str, {k: _json_value(a) for k, a in v.attrs.items()}, enc])
    out = xr.Dataset(data, coords=coords)
    out.attrs = dict(ds.attrs)
    out.attrs[LAYOUT_ATTR] = json.dumps(layout)
    return out


def _json_value(value: Any) -> Any:
    """An attribute's (or encoding's) value for JSON: an array or numpy scalar as its values and dtype
    (restored by :func:`_attr_value`)."""
    if isinstance(value, (np.ndarray, np.generic)):
        return {"array": np.asarray(value).tolist(), "dtype": np.asarray(value).dtype.str,
                "scalar": isinstance(value, np.generic)}
    return value


def _attr_value(value: Any) -> Any:
    """The attribute value :func:`_json_value` wrote."""
    if isinstance(value, dict) and set(value) == {"array", "dtype", "scalar"}:
        array = np.array(value["array"], dtype=np.dtype(value["dtype"]))
        return array[()] if value["scalar"] else array
    return value


def unpack_part(ds: xr.Dataset) -> xr.Dataset:
    """The part :func:`pack_part` wrote (a part file read back): its variables, in their order, with their
    dtypes, attributes and declared missing values; a dataset without :data:`LAYOUT_ATTR` as it is."""
    if LAYOUT_ATTR not in ds.attrs:
        return ds
    rows: dict[str, tuple[xr.Variable, int]] = {}
    for name in ds.data_vars:
        if is_part_stack(name):
            for i, row in enumerate(ds.variables[f"{name}_variable"].values):
                rows[str(row)] = (ds.variables[name], i)
    data = {}
    for name, dtype, attrs, enc in json.loads(ds.attrs[LAYOUT_ATTR]):
        stack, i = rows[name]
        data[name] = xr.Variable(stack.dims[1:], stack.values[i].astype(np.dtype(dtype)),
                                 attrs={k: _attr_value(a) for k, a in attrs.items()},
                                 encoding={k: np.dtype(val) if k == "dtype" else _attr_value(val)
                                           for k, val in enc.items()})
    stacked = [n for n in ds.variables if is_part_stack(n.removesuffix("_variable").removesuffix("_units"))]
    out = xr.Dataset(data, coords={n: ds.variables[n] for n in ds.coords if n not in stacked})
    out.attrs = {k: v for k, v in ds.attrs.items() if k != LAYOUT_ATTR}
    return out


def read_part(path: str | Path) -> xr.Dataset:
    """A part file read back as the dataset its batch computed (:func:`unpack_part` of the file)."""
    return unpack_part(read_dataset(path))


def kept_parts(parts: Path, batches: Iterable[Batch], key: str, added: set[int]) -> Iterator[tuple[Batch, xr.Dataset]]:
    """``(batch, part)`` of every batch whose index is not in ``added`` (those of an earlier run), read from its
    file in ``parts`` after :func:`part_problem` has accepted it for the sweep with inputs ``key``.

    Raises
    ------
    RuntimeError
        When a part is missing or is not the part of its batch (:func:`part_problem`).
    """
    for b in batches:
        if b.index in added:
            continue
        path = part_path(parts, b)
        why = part_problem(path, key, b)
        if why is not None:
            raise RuntimeError(f"{path}: batch {b.index}: part {why}; run the sweep again")
        yield b, read_part(path)
