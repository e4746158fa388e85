"""Stage ``calibrate``: the contact-criterion constant k from the measured touchdown, ``calibration.nc``.

The analysis (the paper's procedure, both methods, the touchdown-versus-k curve) is
:mod:`pipeline.analyses.calibration`; this stage reads the scene's interface tables and DMW record
through the runner and writes its result.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import xarray as xr

from ..analyses.calibration import OWN_DRIVE_KEYS, calibrate
from ..model import scene_inputs
from ..model.inputs import for_stage
from ..runner import Inputs, Stage

log = logging.getLogger(__name__)


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``calibration.nc`` dataset (module docstring); logs the outcome."""
    # the datasets by file and key: the fanned-out flying runs read them on their workers, once per process
    sim = for_stage(scene, inputs, calibration=False)
    ds = calibrate(scene, sim, scheduler=inputs.options.get("scheduler"), workers=inputs.options.get("workers"))
    # timings go to the run log (.hdi/runs.jsonl), not the dataset: equal inputs, equal dataset
    inputs.record(batch_seconds=ds.attrs.pop("batch_seconds"))
    log.info("calibrate: %s", ds.attrs["outcome"])
    if np.isfinite(float(ds["k_calibrated"])):
        log.info("calibrate: k = %.4f; contact probability %.3f (two-sided, the paper's convention), "
                 "%.3f (one-sided)", float(ds["k_calibrated"]), float(ds["contact_probability_two_sided"]),
                 float(ds["contact_probability_one_sided"]))
    return ds


STAGE = Stage(
    "calibrate", compute, simulates=True, outputs=("calibration.nc",),
    # what a simulation reads, the touchdown it is fitted to, the sweep's protrusion grid (on which the
    # touchdown curve is evaluated) and the keys whose difference from the paper's the calibration warns of
    reads=(*scene_inputs.SIMULATION_FIELDS, "touchdown.*", "sweep.protrusion_nm",
           *(key for keys in OWN_DRIVE_KEYS.values() for key in keys)),
    upstream=lambda scene: scene_inputs.input_stages(scene, calibration=False),
    order=40, main_job=True, applies=lambda scene: scene.has("contact"),
    doc="the contact-criterion constant k from the measured touchdown, calibration.nc")
