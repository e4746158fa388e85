"""Stage ``interface``: ISBL tables versus separation for the scene's roughness and materials.

Writes ``interface.nc``: ``contact_pressure``, ``adhesion_pressure``, ``friction_stress`` [MPa],
``real_area_fraction``, ``contact_fraction`` [1] on a uniform ``separation`` grid [nm] (from the
mean of summit heights; the grid is the solver's ``table_step_nm`` from ``table_min_sigma``
summit sigmas to ``table_max_nm``), plus the interface parameters as scalar variables.

Only what the scene's effects need is computed: no ``adhesion`` effect, no adhesion column;
no ``friction``, no friction column; a scene with neither ``contact`` nor ``adhesion`` (flying only)
gets no tables at all.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import xarray as xr

from ..io import read_dataset
from ..model.interface_tables import (DERIVED_FIELDS, FIELDS, build_tables, deepest_protrusion_nm, lubricant_shear_on, roughness_statistics,
                                     summit_friction_law)
from ..runner import Inputs, Stage


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``interface.nc`` dataset of the scene (see module docstring)."""
    rough = None
    if scene["roughness"]["afm"]:  # upstream: current for these inputs (checked by key), not rebuilt
        inputs.dataset("roughness.nc", stage="roughness")
        rough = inputs.path("roughness.nc")
    return build_tables(scene, roughness_statistics(scene, rough))


def _friction_table(scene: Any) -> dict[str, str]:
    """The per-summit friction law the friction column integrates, when it is not the shear-strength law's
    (:func:`pipeline.model.interface_tables.summit_friction_law`): absent otherwise, so the key of a scene
    whose tables read the shear-strength column is what it was before the per-summit laws existed."""
    law = summit_friction_law(scene)
    return {} if law == "shear-strength" else {"friction_stress_law": law}


STAGE = Stage(
    "interface", compute, outputs=("interface.nc",),
    # (the lubricant shear stress scales wetted_area_fraction, which the tables hold when the term is on; the
    # friction law changes the friction column only when it is a per-summit law: both through `derived`)
    reads=FIELDS, unkeyed=DERIVED_FIELDS,
    derived=lambda scene: {"deepest_protrusion_nm": deepest_protrusion_nm(scene),
                           "lubricant_shear": lubricant_shear_on(scene), **_friction_table(scene)},
    upstream=lambda scene: ("roughness",) if scene["roughness"]["afm"] else (),
    order=30, main_job=True, doc="ISBL tables versus separation, interface.nc")


def load(path: Path) -> xr.Dataset:
    """Read ``interface.nc`` (clear error when missing)."""
    return read_dataset(path, stage="interface")
