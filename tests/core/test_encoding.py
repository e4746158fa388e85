"""A dataset's form on disk (pipeline.encoding): the compression and chunks of a variable by its size and dims."""

from __future__ import annotations

from pipeline import encoding
from pipeline.variables import TIME


def test_compression_follows_the_documented_sizes():
    # under COMPRESS_FROM (4 kB), a scalar or an empty variable: contiguous, no filter
    assert encoding.compression(("protrusion",), (511,), 8) == {}
    assert encoding.compression((), (), 8) == {} and encoding.compression(("protrusion",), (0,), 8) == {}
    # from 4 kB to 64 kB: one chunk
    small = encoding.compression(("protrusion", "roughness"), (256, 2), 8)
    assert small == {"zlib": True, "complevel": encoding.ZLIB_LEVEL, "shuffle": True, "chunksizes": (256, 2)}
    # a sweep's scalars: one protrusion row per roughness x damping point
    assert encoding.compression(("protrusion", "roughness", "damping"), (200, 8, 8), 8)["chunksizes"] == (200, 1, 1)
    # a kept history: the time axis whole per protrusion; halved along it while above CHUNK_MAX (4 MB)
    assert encoding.compression(("hist_protrusion", TIME), (3, 400_000), 8)["chunksizes"] == (1, 400_000)
    big = encoding.compression(("hist_protrusion", TIME), (2, 1_200_000), 8)["chunksizes"]
    assert big == (1, 300_000) and big[1] * 8 <= encoding.CHUNK_MAX < 2 * big[1] * 8
