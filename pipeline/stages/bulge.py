"""Stage ``bulge``: the lift of the bulge's air bearing versus apex gap and protrusion, ``bulge.nc``.

For ``air_bearing.bulge = "reynolds"`` (and ``"rough-reynolds"``, its rough-gap form down to contact,
docs/model.md, section "Rough-gap bulge bearing") the steady compressible Reynolds equation with molecular slip is
solved on the bulge footprint once per scene, for every tabulated protrusion and apex gap
(:func:`pipeline.model.bulge_table.scene_table`; docs/model.md, section "Slip-corrected Reynolds
equation"). Writes ``bulge.nc``: ``bulge_lift`` [mN], ``bulge_stiffness`` [N/m] (minus its gap
derivative), ``bulge_lift_ph_limit`` [mN] (the p h = const closed form on the same grid),
``bearing_number`` [1] on ``protrusion`` [nm] x ``apex_gap`` [nm], and ``pad_pressure`` [MPa]. The
simulations (simulate, calibrate, sweep and the parameter studies) read it when the scene's bulge law
reads a table (:func:`pipeline.model.scene_inputs.table_stages`); the closed form ``"ph-limit"`` needs
none and is not a reason to run this stage.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import xarray as xr

from ..io import read_dataset
from ..model.bulge_table import DERIVED_FIELDS, FIELDS, scene_table, table_stop_nm
from ..model.scene_inputs import table_stages
from ..runner import Inputs, Stage

def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``bulge.nc`` dataset of the scene (module docstring)."""
    return scene_table(scene)


STAGE = Stage(
    "bulge", compute, outputs=("bulge.nc",), reads=FIELDS, unkeyed=DERIVED_FIELDS,
    derived=lambda scene: {"table_stop_nm": table_stop_nm(scene)},
    order=35, main_job=True, applies=lambda scene: "bulge" in table_stages(scene),
    doc="the bulge's air-bearing lift (Reynolds, slip) versus apex gap and protrusion, bulge.nc")


def load(path: Path) -> xr.Dataset:
    """Read ``bulge.nc`` (clear error when missing)."""
    return read_dataset(path, stage="bulge")
