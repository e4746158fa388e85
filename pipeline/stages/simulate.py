"""Stage ``simulate``: one scene in time (the material of the paper's Figs 3-5).

``hdi simulate CONFIG --set tfc.protrusion_nm=11`` integrates the 2-DOF slider at the scene's
protrusion and writes ``histories.nc``: time series (dims ``protrusion``, ``time``) of separation,
clearance, forces, friction coefficient, mean pressure and shear stress; and ``summary.nc``: the
steady-window scalars (dim ``protrusion``, the variables of ``sweep.nc``) defined in
:mod:`pipeline.model.slider`. Only the scene's effects are simulated and written.

Inputs come from earlier stages' datasets in the same folder (``interface.nc``, ``dmw.nc``, ``bulge.nc``
with the tabulated bulge bearing, and ``calibration.nc`` when the scene sets no ``contact.k``), made
current first by :mod:`pipeline.runner`.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..model import slider as sl
from ..model import dmw_record, scene_inputs
from ..model.simulation import histories_of, simulate, summary_of
from ..runner import Inputs, Stage, build
from ..variables import flag_meaning
from ..units import MS, NM

log = logging.getLogger(__name__)


def read_inputs(scene: Any, inputs: Inputs) -> tuple[xr.Dataset | None, tuple | None]:
    """Interface tables and DMW record of one simulation of the scene, from a stage's current upstream
    datasets (:class:`pipeline.runner.Inputs`, keys checked; which ones: the rule
    :func:`pipeline.model.scene_inputs.simulation_inputs`).

    Returns ``(interface dataset or None, (displacement [nm], sample rate [Hz]) or None)``.
    """
    wanted = scene_inputs.simulation_inputs(scene)
    interface = inputs.dataset("interface.nc", stage="interface") if "interface" in wanted else None
    record = None
    if "dmw" in wanted:
        _, w_nm, fs = dmw_record.from_dataset(inputs.dataset(dmw_record.FILENAME, stage="dmw",
                                                             variables=dmw_record.VARIABLES))
        record = (w_nm, fs)
    return interface, record


def read_bulge(scene: Any, inputs: Inputs) -> xr.Dataset | None:
    """The bulge table (``bulge.nc``) of one simulation of the scene, when its bulge law reads one
    (:func:`pipeline.model.scene_inputs.simulation_inputs`), else ``None``."""
    if "bulge" not in scene_inputs.simulation_inputs(scene, calibration=False):
        return None
    return inputs.dataset("bulge.nc", stage="bulge")


def read_k(scene: Any, inputs: Inputs) -> tuple[float | None, str]:
    """The contact criterion k [1] and its source, by the one rule :func:`pipeline.model.scene_inputs.contact_k`
    (with ``calibration.nc`` when the scene fixes no k)."""
    wanted = scene_inputs.simulation_inputs(scene)
    calibration = inputs.dataset("calibration.nc", stage="calibrate") if "calibrate" in wanted else None
    return scene_inputs.contact_k(scene, calibration)


def model_inputs(scene: Any, out: Path) -> tuple[xr.Dataset | None, tuple | None]:
    """:func:`read_inputs` of a scene, its upstream made current in ``out`` first (scripts, benchmarks,
    tests; a stage reads through its own :class:`~pipeline.runner.Inputs` instead)."""
    wanted = scene_inputs.simulation_inputs(scene, calibration=False)
    if wanted:
        build(wanted, scene, out)
    return read_inputs(scene, Inputs.folder(out))


def model_attrs(model: sl.Model, k_source: str) -> dict[str, Any]:
    """Global attributes describing the assembled model (stiffness roots, damping, k)."""
    info = model.info
    extra: dict[str, Any] = {}
    if model.tfc_stiffening is not None:
        extra = {"tfc_stiffness_n_m": float(model.tfc_stiffening.k_t), "tfc_stiffening_exponent": float(model.tfc_stiffening.q)}
    if info["friction_law"] == "coefficient":
        extra["friction_coefficient"] = float(info["friction_coefficient"])
    return extra | {
        "k": model.k if np.isfinite(model.k) else "none",
        "k_source": k_source,
        "k_sigma_nm": model.k_sigma / NM,
        "front_stiffness_n_m": info["k_f"], "rear_stiffness_n_m": info["k_r"],
        "front_damper_n_s_m": info["c_f"], "rear_damper_n_s_m": info["c_r"],
        "stiffness_roots": str([{k: float(v) for k, v in r.items()} for r in info["roots"]]),
        "stiffness_root_chosen": info["chosen"],
        "stiffness_roots_note": "node_mode1/2: position ahead of the CG [m] that does not move in the "
                                "120/300 kHz modes; 'stiff-rear' takes k_r > k_f (docs/model.md, section 'Air bearing')",
        "rear_law": info["rear_law"],
        "tfc_stiffening": info["tfc_stiffening"],
        "friction_law": info["friction_law"],
        "summit_offset_y_s_nm": info["y_s"] / NM,
        "separation_datum": "d = FH0 - delta + z - l_c theta - w - y_s: to the mean of summit heights (docs/model.md, section 'Separation datum')",
        "damping_ratio": info["damping_ratio"],
        "steady_window": f"{model.transient / MS:g} ms to {model.duration / MS:g} ms",
        "fhm_measure": model.fhm_measure,
    }


def compute(scene: Any, inputs: Inputs) -> dict[str, xr.Dataset]:
    """``histories.nc`` and ``summary.nc`` for the scene's protrusion (module docstring)."""
    interface, record = read_inputs(scene, inputs)
    k, k_source = read_k(scene, inputs)
    model = sl.build_model(scene, interface, record, k, bulge=read_bulge(scene, inputs))
    delta = scene["tfc"]["protrusion_nm"]
    ds = simulate(model, [delta], histories=[delta], counters=True)
    attrs = model_attrs(model, k_source)
    histories, summary = histories_of(ds), summary_of(ds)
    histories.attrs.update(attrs)
    summary.attrs.update(attrs)
    for name in summary.data_vars:
        v = summary[name]
        if "flag_meanings" in v.attrs:  # (a code: its name, not "regime 2 1")
            log.info("  %-22s %12s", name, flag_meaning(v.attrs, float(v[0])))
        else:
            log.info("  %-22s %12.5g %s", name, float(v[0]), v.attrs["units"])
    return {"histories.nc": histories, "summary.nc": summary}


STAGE = Stage(
    "simulate", compute, outputs=("histories.nc", "summary.nc"),
    reads=("*",), excludes=scene_inputs.SIMULATION_EXCLUDES,
    upstream=scene_inputs.simulation_inputs, order=45, doc="one protrusion in time, histories.nc and summary.nc")


def run(scene: Any, out: Path, **options: Any) -> Path:
    """``histories.nc`` (and ``summary.nc``) in ``out``, recomputed only when their inputs changed."""
    return build("simulate", scene, out, **options)["simulate"][0]
