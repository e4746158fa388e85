"""Protrusion labels and range grids: the one rule by which a protrusion [nm] is a grid point.

Here, apart from :mod:`pipeline.config.grid` (which re-exports these names), because validation uses them
too (a touchdown given in mW becomes a label, :mod:`pipeline.config.heater_power`) and the grid's roughness
sets are validated by :mod:`pipeline.config.validation`: this module imports neither.
"""

from __future__ import annotations

from typing import Any

import numpy as np


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


def range_count(g: dict[str, float]) -> int:
    """Number of points of a range table ``{start, stop, step}`` (``stop`` included when on the grid,
    to 1e-9 of a step), without building them (a grid of millions is refused by its count)."""
    return int(np.floor((g["stop"] - g["start"]) / g["step"] + TOL_NM)) + 1


def range_grid(g: dict[str, float]) -> np.ndarray:
    """Points [nm] of a range table ``{start, stop, step}`` (:func:`range_count` of them), rounded to 1e-9."""
    return label(g["start"] + g["step"] * np.arange(range_count(g)))
