"""Stage ``simulate``: one scene in time (the material of the paper's Figs 3-5).

``hdi simulate CONFIG --set tfc.protrusion_nm=11`` integrates the 2-DOF slider at the scene's
protrusion and writes ``histories.nc``: time series (dims ``protrusion``, ``time``) of separation,
clearance, forces, friction coefficient, mean pressure and shear stress; and ``summary.nc``: the
steady-window scalars (dim ``protrusion``, the variables of ``sweep.nc``) defined in
:mod:`pipeline.model.outcomes`. Only the scene's effects are simulated and written.

Inputs come from earlier stages' datasets in the same folder (``interface.nc``, ``dmw.nc``, ``bulge.nc``
with the tabulated bulge bearing, and ``calibration.nc`` when the scene sets no ``contact.k``), made
current first by :mod:`pipeline.runner`.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import xarray as xr

from ..model import scene_inputs
from ..model.inputs import for_stage
from ..model.simulation import histories_of, model_attrs, run_values, simulate, summary_of
from ..runner import Inputs, Stage, current_inputs
from ..variables import flag_meaning

log = logging.getLogger(__name__)


def model_inputs(scene: Any, out: Path) -> tuple[xr.Dataset | None, tuple | None]:
    """Interface tables and DMW record of a scene, its upstream made current in ``out`` first (scripts,
    benchmarks, tests: :func:`pipeline.runner.current_inputs`; a stage reads through
    :func:`pipeline.model.inputs.for_stage` instead)."""
    inputs = current_inputs(scene, out)
    return inputs.tables(), inputs.record()


def compute(scene: Any, inputs: Inputs) -> dict[str, xr.Dataset]:
    """``histories.nc`` and ``summary.nc`` for the scene's protrusion (module docstring)."""
    sim = for_stage(scene, inputs)
    model = sim.model(scene)
    delta = scene["tfc"]["protrusion_nm"]
    ds = simulate(model, [delta], histories=[delta], counters=True)
    attrs = model_attrs(model, sim.k_source)
    histories, summary = histories_of(ds), summary_of(ds)
    histories.attrs.update(attrs)
    summary.attrs.update(attrs)
    for name in summary.data_vars:
        v = summary[name]
        if "flag_meanings" in v.attrs:  # (a code: its name, not "regime 2 1")
            log.info("  %-22s %12s", name, flag_meaning(v.attrs, float(v[0])))
        else:
            log.info("  %-22s %12.5g %s", name, float(v[0]), v.attrs["units"])
    run = run_values(model, sim.k_source)  # (besides the attributes: what combined runs keep apart)
    return {"histories.nc": histories.assign(run), "summary.nc": summary.assign(run)}


STAGE = Stage(
    "simulate", compute, simulates=True, outputs=("histories.nc", "summary.nc"),
    reads=(*scene_inputs.SIMULATION_FIELDS, "tfc.protrusion_nm"),
    upstream=scene_inputs.input_stages, order=45, doc="one protrusion in time, histories.nc and summary.nc")
