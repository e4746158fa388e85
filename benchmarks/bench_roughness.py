"""Benchmark of the roughness stage's physics: summarise a 512 x 512 scan by both routes (target < 2 s).

Uses the Bruker scan ``tests/data/afm/di-5.di`` (512 x 512) when present, else a synthetic 512 x 512 map written to
a temporary SurfaceTopography NetCDF file, so the timing always includes reading and detrending.
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np

from benchmarks.common import record, timeit
from pipeline.model import afm_scan
from pipeline.physics import surface as sf

SCAN = Path(__file__).resolve().parents[1] / "tests/data/afm/di-5.di"


def _synthetic(folder: Path) -> Path:
    from SurfaceTopography.Generation import fourier_synthesis

    t = fourier_synthesis((512, 512), (1000.0, 1000.0), hurst=0.8, rms_height=1.5, short_cutoff=8.0,
                          rng=20090601, unit="nm")
    path = folder / "synthetic-512.nc"
    t.to_netcdf(str(path))
    return path


def run(results: list[dict]) -> None:
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore", sf.SurfaceWarning)  # route disagreement is reported, not timed
        path = SCAN if SCAN.is_file() else _synthetic(Path(tmp))
        topo = afm_scan.read_topography(path)
        heights = np.asarray(topo.heights())
        px = tuple(float(p) for p in topo.pixel_size)
        extra = {"file": path.name, "grid": list(topo.nb_grid_pts)}
        record(results, "roughness: read + detrend + both routes (512x512)",
               timeit(lambda: afm_scan.summarise_file(path), repeat=5), target_s=2.0, **extra)
        record(results, "roughness: read + detrend (512x512)", timeit(lambda: afm_scan.read_topography(path), repeat=5),
               **extra)
        record(results, "roughness: spectral moments (512x512)", timeit(lambda: afm_scan.profile_moments(topo), repeat=5),
               **extra)
        record(results, "roughness: summit count (512x512)",
               timeit(lambda: sf.summit_statistics(heights, px), repeat=5), **extra)
