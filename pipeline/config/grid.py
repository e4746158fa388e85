"""The sweep's grid: protrusions, labelled roughness sets and damping ratios, validated.

``[sweep] protrusion_nm = {start, stop, step}`` (inclusive of ``stop`` when it falls on the grid),
``roughness = [{label = "...", sigma_nm = ..., ...} | {label = "...", afm = [...]}]`` (keys of
``[roughness]``; missing ones are taken from ``[roughness]``), ``damping_ratio = [...]``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from .scene import SCHEMA, SceneError, _check_value


#: Protrusion labels [nm] are rounded to this many decimals, so a label computed twice is the same
#: float; two protrusions closer than :data:`TOL_NM` are the same grid point (one home of the rule).
DECIMALS = 9
TOL_NM = 10.0 ** -DECIMALS


def label(x: Any) -> Any:
    """A protrusion [nm] (or array of them) rounded as the grid's labels are."""
    return np.round(x, DECIMALS)


def same_point(a: Any, b: Any) -> Any:
    """Whether protrusions ``a`` and ``b`` [nm] are the same grid point (elementwise for arrays)."""
    return np.abs(np.asarray(a) - b) < TOL_NM


def protrusion_grid(scene: Any) -> np.ndarray:
    """Protrusions [nm] of ``[sweep] protrusion_nm``, rounded to 1e-9 nm so labels are exact."""
    return range_grid(scene["sweep"]["protrusion_nm"])


def range_count(g: dict[str, float]) -> int:
    """Number of points of a range table ``{start, stop, step}`` (``stop`` included when on the grid,
    to 1e-9 of a step), without building them (a grid of millions is refused by its count)."""
    return int(np.floor((g["stop"] - g["start"]) / g["step"] + TOL_NM)) + 1


def range_grid(g: dict[str, float]) -> np.ndarray:
    """Points [nm] of a range table ``{start, stop, step}`` (:func:`range_count` of them), rounded to 1e-9."""
    return label(g["start"] + g["step"] * np.arange(range_count(g)))


def damping_grid(scene: Any) -> list[float]:
    """Modal damping ratios [1] of the sweep (default: the scene's ``air_bearing.damping_ratio``)."""
    d = scene["sweep"]["damping_ratio"]
    return list(d) if d else [scene["air_bearing"]["damping_ratio"]]


def roughness_sets(scene: Any) -> dict[str, dict[str, Any]]:
    """Labelled roughness sets: label -> full ``[roughness]`` table (validated).

    Default: one set labelled ``"scene"``, the scene's own ``[roughness]``.
    """
    items = scene["sweep"]["roughness"]
    base = dict(scene["roughness"])
    if not items:
        return {"scene": base}
    where = str(scene.path) if scene.path else "<scene>"
    folder = Path(scene.path).parent if scene.path else None
    sets: dict[str, dict[str, Any]] = {}
    for i, item in enumerate(items):
        if isinstance(item, str):  # a bare label: only "scene" (the scene's own [roughness]) is predefined
            if item != "scene":
                raise SceneError(f"{where}: sweep.roughness[{i}] = {item!r}: unknown roughness label; expected "
                                 "\"scene\" or a table {label = ..., sigma_nm = ..., ...}")
            item = {"label": "scene"}
        label = item.get("label")
        if not isinstance(label, str) or not re.fullmatch(r"[A-Za-z0-9_.+-]+", label):
            raise SceneError(f"{where}: sweep.roughness[{i}].label = {label!r}: expected a label of letters, "
                             "digits, '.', '_', '+' or '-'")
        if label in sets:
            raise SceneError(f"{where}: sweep.roughness[{i}].label = {label!r}: labels must be unique")
        table = dict(base)
        if "afm" in item:  # AFM sets replace the explicit statistics
            table["afm"] = None
        for key, value in item.items():
            if key == "label":
                continue
            if key not in SCHEMA["roughness"]:
                raise SceneError(f"{where}: unknown key sweep.roughness[{i}].{key} (set {label!r}): expected "
                                 "label or one of " + ", ".join(SCHEMA["roughness"]))
            table[key] = _check_value("sweep.roughness", f"{key} (set {label!r})", SCHEMA["roughness"][key],
                                      value, where, folder)
        sets[label] = table
    return sets
