"""Stage ``roughness``: AFM scans (or explicit statistics) to asperity statistics, ``roughness.nc``.

Reads ``scene["roughness"]``: either ``afm`` (a list of files in any format SurfaceTopography reads,
already resolved to absolute paths by the scene loader), with ``channel`` and ``detrend``; or, when
``afm`` is absent, the explicit ``sigma_nm``, ``summit_radius_um``, ``summit_density_per_um2``.

Output layout (``out/roughness.nc``)
------------------------------------
coordinates
    ``surface`` : one label per input file (its stem, made unique), then always ``"combined"``, the
    surface the interface stage uses (docs/model.md, section "Asperity statistics": moments add). For explicit statistics the labels are
    ``"explicit"`` and ``"combined"`` (identical rows).
    ``route`` : ``"spectral"`` (McCool/Nayak from profile moments), ``"summits"`` (direct count); the
    scene key ``roughness.route`` picks one of them for the interface model. (Formerly ``method``, which
    collided with the ``method=`` keyword of xarray's ``sel``.)
variables on (surface, route)
    ``sigma`` [nm], ``sigma_s`` [nm], ``y_s`` [nm], ``summit_radius`` [um], ``summit_density`` [um-2],
    ``bandwidth_alpha`` [1], ``plasticity_index`` [1] (GW form), ``plasticity_index_ke`` [1] (CEB/KE).
variables on (surface)
    ``pixel_size`` [nm], ``m0`` [nm2], ``m2`` [1], ``m4`` [nm-2], ``summit_count`` [1].
global attributes
    ``source_files`` (JSON label -> file), ``source_file_<label>`` per file, ``channels`` (JSON label ->
    channel read), ``detrend``, ``plasticity_index_form``, ``composite_modulus_gpa``, ``hardness_gpa``,
    ``combination_rule``, ``warnings`` (JSON list), plus the provenance of :func:`pipeline.io.write_dataset`.

The combined surface: the spectral route uses the summed moments; the summit route cannot be combined
(the scans have different grids), so for several files its row holds only ``sigma`` (quadrature sum) and
NaN elsewhere; for a single file ``combined`` is a copy of that file's rows.

Everything is computed before anything is written, and the write is atomic: a failing input leaves an
existing ``roughness.nc`` untouched. Reads (for :mod:`pipeline.runner`): ``[roughness]``, ``[materials]``
and the bytes of the ``afm`` files.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import xarray as xr

from ..io import write_dataset
from ..model.roughness_statistics import build_dataset, summaries
from ..physics import surface as sf
from ..runner import Inputs, Stage
from ..units import PER_UM2_IN_PER_NM2, UM_IN_NM

FILENAME = "roughness.nc"


def run_files(files: Sequence[Path], out: Path, channel: str | None = None, detrend: str = "plane",
              scene: Any = None) -> Path:
    """Summarise AFM files by both routes and write ``out/roughness.nc`` (see the module docstring).

    Parameters
    ----------
    files : AFM scans (any format SurfaceTopography reads)
    out : output folder
    channel : channel name for every file (``None``: the height channel)
    detrend : ``"plane"``, ``"center"``, ``"height"`` or ``"curvature"``
    scene : optional scene (materials, provenance)

    Raises
    ------
    pipeline.model.afm_scan.AFMError
        For an unusable file; nothing is written then.
    """
    files = [Path(f) for f in files]
    if not files:
        raise ValueError("roughness: expected at least one AFM file")
    ds = build_dataset(summaries(files, channel, detrend), scene, detrend)
    return write_dataset(ds, Path(out) / FILENAME, scene, stage="roughness", inputs=files)


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``roughness.nc`` dataset of ``scene["roughness"]`` (module docstring): the AFM scans of
    ``afm`` by both routes, or the explicit statistics."""
    cfg = scene["roughness"]
    files = [Path(f) for f in (cfg.get("afm") or [])]
    if files:
        detrend = cfg.get("detrend", "plane")
        return build_dataset(summaries(files, cfg.get("channel"), detrend), scene, detrend)
    summary = sf.from_statistics(cfg["sigma_nm"], cfg["summit_density_per_um2"] * PER_UM2_IN_PER_NM2,
                                 cfg["summit_radius_um"] * UM_IN_NM, label="explicit")
    return build_dataset([summary], scene, "")


STAGE = Stage(
    "roughness", compute, outputs=(FILENAME,), reads=("roughness.*", "materials.*"),
    files=lambda scene: {f"roughness.afm[{i}]": f for i, f in enumerate(scene["roughness"]["afm"] or [])},
    order=10, main_job=True, doc="AFM scans (or explicit statistics) to asperity statistics, roughness.nc")
