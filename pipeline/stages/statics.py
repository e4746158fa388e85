"""Stage ``statics``: every static state of the slider versus protrusion, ``statics.nc``.

At each protrusion of the scene's sweep grid (``sweep.protrusion_nm``) the static equilibria of the slider
(the kernel's forces at zero velocity on the mean disk, as the start state's) are found along the path
where the TFC point is held at a clearance and the pitch relaxed: the clearance of each state, whether it
is stable (the eigenvalues of its static stiffness), the energy barrier out of each stable state, and the
DMW's energy scales beside them (:func:`pipeline.model.statics.statics_map`; docs/model.md, section
"Statics map"). It shows where the model is bistable before any dynamics run: the report draws it
(``statics.png``). It reads what one simulation reads (interface tables, the bulge table, the DMW record
for its energy scale, the calibration for k).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import xarray as xr

from ..config.grid import protrusion_grid
from ..config.heater_power import ACTUATION_FIELDS, power_coordinates
from ..io import read_dataset
from ..model import scene_inputs
from ..model.inputs import for_stage
from ..model.simulation import model_attrs
from ..model.statics import statics_map
from ..runner import Inputs, Stage

log = logging.getLogger(__name__)


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``statics.nc`` dataset (module docstring); logs the bistable protrusions."""
    sim = for_stage(scene, inputs)
    model = sim.model(scene)
    ds = statics_map(model, protrusion_grid(scene), sim.record())
    ds.attrs.update(model_attrs(model, sim.k_source))
    ds = ds.assign_coords(power_coordinates(scene, ds["protrusion"].values))
    multi = ds["protrusion"].values[ds["stable_count"].values > 1]
    log.info("statics: %s", f"more than one stable state at {', '.join(f'{p:g}' for p in multi)} nm" if multi.size
             else "one stable state at every protrusion")
    log.info("statics: DMW energy scale %.3g J (kinetic %.3g J)", float(ds["dmw_energy"]),
             float(ds["dmw_kinetic_energy"]))
    return ds


STAGE = Stage(
    "statics", compute, outputs=("statics.nc",),
    # what a simulation reads, the sweep's protrusion grid (not the single protrusion) and the heater's
    # actuation (power_coordinates)
    reads=(*scene_inputs.SIMULATION_FIELDS, "sweep.protrusion_nm", *ACTUATION_FIELDS),
    upstream=scene_inputs.input_stages, order=47, main_job=True,
    doc="every static state versus protrusion: clearance, stability, barriers, DMW energy, statics.nc")


def load(path: Path) -> xr.Dataset:
    """Read ``statics.nc`` (clear error when missing)."""
    return read_dataset(path, stage="statics")
