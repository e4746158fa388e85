"""The sweep's grid: protrusions, labelled roughness sets and damping ratios, validated.

``[sweep] protrusion_nm = {start, stop, step}`` (inclusive of ``stop`` when it falls on the grid),
``roughness = [{label = "...", sigma_nm = ..., ...} | {label = "...", afm = [...]} | "scene"]`` (keys of
``[roughness]``; missing ones are taken from ``[roughness]``; without ``label``, a label made from the
set's values, :func:`roughness_label`), ``damping_ratio = [...]``.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path
from typing import Any

import numpy as np

from .labels import DECIMALS, TOL_NM, label, range_count, range_grid, same_point
from .schema import SCHEMA, SceneError
from .validation import check_value

__all__ = ["DECIMALS", "TOL_NM", "damping_grid", "label", "protrusion_grid", "range_count", "range_grid",
           "roughness_label", "roughness_sets", "same_point", "scene_label"]


def protrusion_grid(scene: Any) -> np.ndarray:
    """Protrusions [nm] of ``[sweep] protrusion_nm``, rounded to 1e-9 nm so labels are exact."""
    return range_grid(scene["sweep"]["protrusion_nm"])


def damping_grid(scene: Any) -> list[float]:
    """Modal damping ratios [1] of the sweep (default: the scene's ``air_bearing.damping_ratio``)."""
    d = scene["sweep"]["damping_ratio"]
    return list(d) if d else [scene["air_bearing"]["damping_ratio"]]


#: A roughness label: letters, digits, '.', '_', '+' or '-' (it names a folder of ``sweep.parts``).
LABEL = re.compile(r"[A-Za-z0-9_.+-]+")


def _number(x: float) -> str:
    """``x`` as its shortest decimal that reads back as the same float (``0.52``, ``5``, ``13.3``)."""
    return np.format_float_positional(float(x), trim="-")


def roughness_label(table: dict[str, Any]) -> str:
    """The default label of a roughness set (a full ``[roughness]`` table), made from what sets it apart.

    Explicit statistics: ``sigma<sigma_nm>nm_R<summit_radius_um>um_eta<summit_density_per_um2>``
    (``sigma0.52nm_R5um_eta13.3``), each number written exactly, so that two different sets never share
    a label. AFM scans: ``afm-<file stems joined by +>`` (``afm-di-3+mi-1``) and ``-<route>`` when the
    route is not the spectral one; a name longer than 64 characters keeps its first stem and a hash of
    all the paths. Deterministic: the same table gives the same label in every run.
    """
    if table.get("afm"):
        stems = [re.sub(r"[^A-Za-z0-9_.+-]", "_", Path(f).stem) for f in table["afm"]]
        name = "afm-" + "+".join(stems)
        if len(name) > 64:
            digest = hashlib.sha256("\n".join(map(str, table["afm"])).encode()).hexdigest()[:8]
            name = f"afm-{stems[0][:40]}+{len(stems) - 1}-{digest}"
        return name + ("" if table.get("route", "spectral") == "spectral" else f"-{table['route']}")
    return (f"sigma{_number(table['sigma_nm'])}nm_R{_number(table['summit_radius_um'])}um"
            f"_eta{_number(table['summit_density_per_um2'])}")


def scene_label(scene: Any) -> str:
    """The label of the scene's own ``[roughness]`` (:func:`roughness_label`)."""
    return roughness_label(dict(scene["roughness"]))


def roughness_sets(scene: Any) -> dict[str, dict[str, Any]]:
    """Labelled roughness sets: label -> full ``[roughness]`` table (validated).

    Default: one set, the scene's own ``[roughness]``. An entry ``"scene"`` is that set too; a set
    without ``label`` (and the scene's own) is labelled by :func:`roughness_label`, from its values, so
    runs with different roughness never share a label and their datasets combine on ``roughness``.
    """
    items = scene["sweep"]["roughness"]
    base = dict(scene["roughness"])
    if not items:
        return {roughness_label(base): base}
    where = str(scene.path) if scene.path else "<scene>"
    folder = Path(scene.path).parent if scene.path else None
    sets: dict[str, dict[str, Any]] = {}
    for i, item in enumerate(items):
        if isinstance(item, str):  # a bare name: only "scene" (the scene's own [roughness]) is predefined
            if item != "scene":
                raise SceneError(f"{where}: sweep.roughness[{i}] = {item!r}: unknown roughness label; expected "
                                 "\"scene\" or a table {label = ..., sigma_nm = ..., ...}")
            item = {}
        table = dict(base)
        if "afm" in item:  # AFM sets replace the explicit statistics
            table["afm"] = None
        name = item.get("label")
        for key, value in item.items():
            if key == "label":
                continue
            if key not in SCHEMA["roughness"]:
                raise SceneError(f"{where}: unknown key sweep.roughness[{i}].{key} (set {name!r}): expected "
                                 "label or one of " + ", ".join(SCHEMA["roughness"]))
            table[key] = check_value("sweep.roughness", f"{key} (set {name!r})", SCHEMA["roughness"][key],
                                      value, where, folder)
        label = roughness_label(table) if "label" not in item else name
        if not isinstance(label, str) or not LABEL.fullmatch(label):
            raise SceneError(f"{where}: sweep.roughness[{i}].label = {label!r}: expected a label of letters, "
                             "digits, '.', '_', '+' or '-'")
        if label in sets:
            raise SceneError(f"{where}: sweep.roughness[{i}]: label {label!r} is used twice: labels must be "
                             "unique (two sets without a label have the same values)")
        sets[label] = table
    return sets
