"""Damaging a written NetCDF dataset the way a disk or a hand does: bytes flipped inside a variable's compressed
chunk (found in the file as the zlib stream HDF5 wrote for it), or a value changed in place."""

from __future__ import annotations

import zlib
from pathlib import Path

import netCDF4
import numpy as np

from pipeline.encoding import ZLIB_LEVEL


def chunk_offset(path: Path, name: str) -> tuple[int, int]:
    """``(offset, length)`` [B] in ``path`` of the first chunk of variable ``name`` (zlib with shuffle, as
    :func:`pipeline.encoding.compression` writes it): that chunk's values shuffled and compressed again at the same
    level give the very bytes HDF5 stored, found in the file."""
    with netCDF4.Dataset(path) as nc:
        v = nc.variables[name]
        filters, chunks = v.filters(), v.chunking()
        assert filters and filters["zlib"] and filters["shuffle"] and chunks != "contiguous", (name, filters)
        v.set_auto_maskandscale(False)
        values = np.ascontiguousarray(v[tuple(slice(0, c) for c in chunks)], dtype=v.dtype)
    shuffled = values.view(np.uint8).reshape(-1, values.itemsize).T.tobytes()
    stream = zlib.compress(shuffled, ZLIB_LEVEL)
    offset = path.read_bytes().find(stream)
    assert offset > 0, f"the chunk of {name} not found in {path}"
    return offset, len(stream)


def damage_chunk(path: Path, name: str) -> None:
    """Flip 16 bytes in the middle of the first compressed chunk of variable ``name`` of ``path``."""
    offset, length = chunk_offset(path, name)
    with open(path, "r+b") as fh:
        fh.seek(offset + length // 2)
        block = fh.read(16)
        fh.seek(offset + length // 2)
        fh.write(bytes(b ^ 0xFF for b in block))


def edit_value(path: Path, name: str, index: tuple, value: float) -> None:
    """Change one value of variable ``name`` of ``path`` in place (netCDF4's append mode: attributes kept)."""
    with netCDF4.Dataset(path, "a") as nc:
        nc.variables[name][index] = value
