"""Datasets on disk: provenance attributes, atomic writes, explicit-engine reads.

Every stage writes exactly one NetCDF file through :func:`write_dataset`, which

* refuses a variable or coordinate without ``units`` and ``long_name`` (CF conventions),
* adds the global attributes of DESIGN.md (title, history, source, Conventions, package version,
  git revision, config hash, seed, input-file hashes),
* writes to a temporary file in the same folder and renames it into place, so an interrupted
  run never leaves a half-written file and never destroys the previous one.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import subprocess
import tempfile
from functools import lru_cache
from pathlib import Path
from typing import Any, Iterable

import xarray as xr

from . import __version__

ENGINE = "netcdf4"

#: The scene keys each stage's output depends on (``"section"`` or ``"section.key"``): a stage
#: whose dataset carries the same key hash (attribute ``stage_key``) is up to date and not rerun.
STAGE_INPUTS: dict[str, tuple[str, ...]] = {
    "roughness": ("roughness", "materials"),
    "dmw": ("dmw", "solver.duration_ms", "scene.effects", "slider.length_mm", "slider.front_arm_mm"),
    "interface": ("roughness", "materials", "lubricant", "solver.table_step_nm", "solver.table_min_sigma",
                  "solver.table_max_nm", "solver.quadrature_nodes", "solver.quadrature_panels", "scene.effects",
                  "air_bearing.flying_height_nm", "tfc.protrusion_nm", "sweep.protrusion_nm"),
}


class DatasetError(ValueError):
    """A dataset on disk is missing, unreadable, or lacks what a stage needs."""


@lru_cache(maxsize=1)
def git_revision() -> str:
    """The git revision of the package source (``"unknown"`` outside a checkout)."""
    here = Path(__file__).resolve().parent
    try:
        rev = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True,
                             text=True, timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--", "."],
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return rev + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def file_hash(path: str | Path, chunk: int = 1 << 20) -> str:
    """SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            h.update(block)
    return h.hexdigest()


#: Stages that depend on the whole scene except these keys.
STAGE_EXCLUDES: dict[str, tuple[str, ...]] = {
    "calibrate": ("tfc.protrusion_nm", "sweep", "report", "identify", "sensitivity", "scene.name",
                  "scene.description"),
}


def stage_key(scene: Any, stage: str) -> str:
    """SHA-256 of the scene keys a stage depends on (:data:`STAGE_INPUTS`, :data:`STAGE_EXCLUDES`);
    the whole config otherwise."""
    items = STAGE_INPUTS.get(stage)
    if items is None and stage in STAGE_EXCLUDES:
        cfg = json.loads(json.dumps(scene.config, default=str))
        for item in STAGE_EXCLUDES[stage]:
            section, _, key = item.partition(".")
            if key:
                cfg.get(section, {}).pop(key, None)
            else:
                cfg.pop(section, None)
        return hashlib.sha256(json.dumps(cfg, sort_keys=True).encode()).hexdigest()
    if items is None:
        return scene.hash
    picked = {}
    for item in items:
        section, _, key = item.partition(".")
        picked[item] = scene.config[section][key] if key else scene.config[section]
    return hashlib.sha256(json.dumps(picked, sort_keys=True, default=str).encode()).hexdigest()


def is_current(path: str | Path, scene: Any, stage: str) -> bool:
    """Whether ``path`` exists and was written by ``stage`` from the same inputs (by hash)."""
    path = Path(path)
    if not path.is_file():
        return False
    try:
        with xr.open_dataset(path, engine=ENGINE) as ds:
            return ds.attrs.get("stage_key") == stage_key(scene, stage)
    except (OSError, ValueError):
        return False


def check_cf(ds: xr.Dataset, where: str = "dataset") -> None:
    """Raise unless every variable and coordinate has ``units`` and ``long_name`` attributes."""
    missing = [name for name in list(ds.data_vars) + list(ds.coords)
               if "units" not in ds[name].attrs or "long_name" not in ds[name].attrs]
    if missing:
        raise DatasetError(f"{where}: variables without units/long_name: {missing}")


def provenance(scene: Any = None, *, stage: str, inputs: Iterable[str | Path] = (),
               seed: int | None = None) -> dict[str, str]:
    """Global attributes recording how a dataset was made.

    Parameters
    ----------
    scene
        The :class:`pipeline.scene.Scene` (or ``None``).
    stage
        The stage name (``"interface"``, ...).
    inputs
        Files read by the stage; their SHA-256 is recorded.
    seed
        Random seed used, if any.
    """
    now = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()
    attrs = {
        "title": f"HDI pipeline: {stage}",
        "Conventions": "CF-1.8",
        "source": "pipeline (Vakis, Lee & Polycarpou, IEEE Trans. Magn. 45(11) 4966-4971, 2009, "
                  "DOI 10.1109/TMAG.2009.2029410)",
        "history": f"{now}: hdi {stage}" + (f" {scene.path}" if scene is not None and scene.path else ""),
        "stage": stage,
        "pipeline_version": __version__,
        "git_revision": git_revision(),
    }
    if scene is not None:
        attrs["scene_name"] = scene.name
        attrs["config_hash"] = scene.hash
        attrs["stage_key"] = stage_key(scene, stage)
        attrs["config"] = scene.to_toml_text()
        attrs["effects"] = " ".join(sorted(scene.effects))
        if scene.overrides:
            attrs["overrides"] = " ".join(scene.overrides)
    if seed is not None:
        attrs["seed"] = int(seed)
    hashes = {str(p): file_hash(p) for p in inputs}
    attrs["input_hashes"] = json.dumps(hashes, sort_keys=True)
    return attrs


def write_dataset(ds: xr.Dataset, path: str | Path, scene: Any = None, *, stage: str,
                  inputs: Iterable[str | Path] = (), seed: int | None = None,
                  extra_attrs: dict[str, Any] | None = None) -> Path:
    """Write ``ds`` to ``path`` atomically with provenance.

    Parameters
    ----------
    ds
        The dataset; every variable and coordinate must carry ``units`` and ``long_name``.
    path
        Destination ``.nc`` file; its folder is created.
    scene, stage, inputs, seed
        See :func:`provenance`.
    extra_attrs
        More global attributes (stage-specific).

    Returns
    -------
    Path
        The written file.
    """
    path = Path(path)
    check_cf(ds, str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    out = ds.copy()
    attrs = dict(ds.attrs)
    attrs.update(provenance(scene, stage=stage, inputs=inputs, seed=seed))
    if extra_attrs:
        attrs.update(extra_attrs)
    out.attrs = {k: (json.dumps(v) if isinstance(v, (dict, list, tuple)) else v) for k, v in attrs.items()}
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        out.to_netcdf(tmp, engine=ENGINE)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_dataset(path: str | Path, *, stage: str | None = None, variables: Iterable[str] = ()) -> xr.Dataset:
    """Open a stage dataset fully into memory (the file is closed afterwards).

    Raises
    ------
    DatasetError
        When the file is missing, not NetCDF, or lacks one of ``variables``.
    """
    path = Path(path)
    if not path.is_file():
        hint = f" (run `hdi {stage}` first)" if stage else ""
        raise DatasetError(f"{path}: dataset does not exist{hint}")
    try:
        with xr.open_dataset(path, engine=ENGINE) as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise DatasetError(f"{path}: not a readable NetCDF dataset: {exc}") from None
    missing = [v for v in variables if v not in ds.variables]
    if missing:
        raise DatasetError(f"{path}: missing variables {missing}")
    return ds


def results_dir(scene: Any, out: str | Path | None = None) -> Path:
    """Where a scene's stage outputs go: ``out`` or ``results/<scene name>/``."""
    return Path(out) if out is not None else Path("results") / scene.name


def var(data: Any, dims: Any, units: str, long_name: str, **attrs: Any) -> xr.Variable:
    """An ``xarray.Variable`` with its CF ``units`` and ``long_name``."""
    return xr.Variable(dims, data, attrs={"units": units, "long_name": long_name, **attrs})
