"""Stage ``simulate``: one scene in time (the material of the paper's Figs 3-5).

``hdi simulate CONFIG --set tfc.protrusion_nm=11`` integrates the 2-DOF slider at the scene's
protrusion and writes ``histories.nc``: time series (dims ``protrusion``, ``time``) of separation,
clearance, forces, friction coefficient, mean pressure and shear stress; and ``summary.nc``: the
steady-window scalars (dim ``protrusion``, the variables of ``sweep.nc``) defined in
:mod:`pipeline.slider`. Only the scene's effects are simulated and written.

Inputs come from earlier stages' datasets in the same folder (``interface.nc``, ``dmw.nc``, and
``calibration.nc`` when the scene sets no ``contact.k``), made current first by :mod:`pipeline.runner`.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .. import slider as sl
from ..io import read_dataset
from ..physics.statistics import contact_probabilities, k_from_probability
from ..runner import Inputs, Stage, build, ensure
from ..variables import HISTORIES, coordinate, flag_meaning, history, scalar

log = logging.getLogger(__name__)
NM = 1e-9


def needs_interface(scene: Any) -> bool:
    """Whether a simulation reads ``interface.nc``: for its tables (contact, adhesion) or, with AFM scans,
    for the summit offset y_s of the separation datum (explicit statistics give y_s without it)."""
    return bool(scene.effects & {"contact", "adhesion"} or scene["roughness"]["afm"])


def model_inputs(scene: Any, out: Path) -> tuple[xr.Dataset | None, tuple | None]:
    """Interface tables and DMW record of a scene, from ``out`` (made current first, :func:`pipeline.runner.ensure`).

    Returns ``(interface dataset or None, (displacement [nm], sample rate [Hz]) or None)``; the
    interface is ``None`` when the scene does not need it (:func:`needs_interface`), the DMW ``None``
    without the dmw effect.
    """
    from . import dmw as dmw_stage
    interface = None
    if needs_interface(scene):
        interface = read_dataset(ensure("interface", scene, out), stage="interface")
    record = None
    if scene.has("dmw"):
        _, w_nm, fs = dmw_stage.load(ensure("dmw", scene, out))
        record = (w_nm, fs)
    return interface, record


def resolve_k(scene: Any, out: Path) -> tuple[float | None, str]:
    """The contact criterion constant and where it came from.

    ``contact.k`` when the scene fixes it; else ``k_calibrated`` of ``calibration.nc``; when the
    calibration found no admissible k and the scene gives ``contact.fallback_probability``, the k
    whose two-sided contact probability ``P(|z| > k sigma) = 2 Q(k)`` equals it (the paper's convention,
    SPEC.md 7.1; said in every output). The source names the file, not its folder, so datasets of one
    scene in two folders are identical.
    """
    if not scene.has("contact"):
        return None, "no contact effect"
    c = scene["contact"]
    if c["k"] is not None:
        return float(c["k"]), "scene (contact.k)"
    path = Path(out) / "calibration.nc"
    if not path.is_file():
        raise ValueError(f"no contact criterion k: the scene sets no contact.k and {path} does not exist; "
                         "run `hdi calibrate` first or pass --set contact.k=VALUE")
    cal = read_dataset(path, stage="calibrate")
    k = float(cal["k_calibrated"])
    if np.isfinite(k):
        return k, f"calibration ({path.name})"
    fb = c.get("fallback_probability")
    if fb is None:
        raise ValueError(f"{path}: the calibration found no admissible k ({cal.attrs.get('outcome', '')}); "
                         "set contact.k or contact.fallback_probability")
    k = k_from_probability(fb)
    return k, (f"fallback: no admissible k in {path.name}; k = {k:.4f} from contact.fallback_probability = {fb} "
               f"(two-sided; one-sided {contact_probabilities(k)[1]:.3f})")


def run_scene(scene: Any, out: Path, protrusion_nm: float | None = None,
              damping_ratio: float | None = None) -> tuple[sl.Run, dict, dict, str]:
    """Build and integrate one scene; returns the run, its histories, its scalars and the k source."""
    interface, record = model_inputs(scene, out)
    k, k_source = resolve_k(scene, out)
    model = sl.build_model(scene, interface, record, k, damping_ratio)
    delta = scene["tfc"]["protrusion_nm"] if protrusion_nm is None else protrusion_nm
    run = sl.run_model(model, delta * NM)
    hist = sl.histories(run)
    return run, hist, sl.summarize(run, hist), k_source


def histories_dataset(runs: list[tuple[float, sl.Run, dict, dict]]) -> xr.Dataset:
    """Dataset of time histories for runs ``(protrusion [nm], run, histories, scalars)``."""
    prot = np.array([r[0] for r in runs])
    time = runs[0][1].time
    data = {}
    for name in runs[0][2]:
        data[name] = history(name, np.stack([r[2][name] for r in runs]), ("protrusion", "time"))
    info = np.stack([r[1].info for r in runs])
    for j, name in enumerate(("steps", "rejected_steps", "contact_switches"), start=1):
        data[name] = HISTORIES[name].data(info[:, j], ("protrusion",))
    coords = {"protrusion": coordinate("protrusion", prot), "time": coordinate("time", time)}
    return xr.Dataset(data, coords=coords)


def summary_dataset(runs: list[tuple[float, sl.Run, dict, dict]]) -> xr.Dataset:
    """Dataset of the steady-window scalars (dim ``protrusion``) of runs."""
    prot = np.array([r[0] for r in runs])
    data = {name: scalar(name, np.array([r[3][name] for r in runs]), ("protrusion",)) for name in runs[0][3]}
    return xr.Dataset(data, coords={"protrusion": coordinate("protrusion", prot)})


def model_attrs(model: sl.Model, k_source: str) -> dict[str, Any]:
    """Global attributes describing the assembled model (stiffness roots, damping, k)."""
    info = model.info
    extra: dict[str, Any] = {}
    if model.tfc_stiffening is not None:
        extra = {"tfc_stiffness_n_m": float(model.p[sl.dyn.P_TK]), "tfc_stiffening_exponent": float(model.p[sl.dyn.P_TP])}
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
                                "120/300 kHz modes; 'stiff-rear' takes k_r > k_f (SPEC.md 7.3)",
        "rear_law": info["rear_law"],
        "tfc_stiffening": info["tfc_stiffening"],
        "friction_law": info["friction_law"],
        "summit_offset_y_s_nm": info["y_s"] / NM,
        "separation_datum": "d = FH0 - delta + z - l_c theta - w - y_s: to the mean of summit heights (SPEC.md 7.2)",
        "damping_ratio": info["damping_ratio"],
        "steady_window": f"{model.transient * 1e3:g} ms to {model.duration * 1e3:g} ms",
        "fhm_measure": model.fhm_measure,
    }


def compute(scene: Any, inputs: Inputs) -> dict[str, xr.Dataset]:
    """``histories.nc`` and ``summary.nc`` for the scene's protrusion (module docstring)."""
    run_, hist, scalars, k_source = run_scene(scene, inputs.out)
    runs = [(scene["tfc"]["protrusion_nm"], run_, hist, scalars)]
    attrs = model_attrs(run_.model, k_source)
    histories, summary = histories_dataset(runs), summary_dataset(runs)
    histories.attrs.update(attrs)
    summary.attrs.update(attrs)
    for name in summary.data_vars:
        v = summary[name]
        if "flag_meanings" in v.attrs:  # (a code: its name, not "regime 2 1")
            log.info("  %-22s %12s", name, flag_meaning(v.attrs, float(v[0])))
        else:
            log.info("  %-22s %12.5g %s", name, float(v[0]), v.attrs["units"])
    return {"histories.nc": histories, "summary.nc": summary}


def upstream(scene: Any) -> tuple[str, ...]:
    """The datasets a single simulation reads: interface tables, DMW record, calibration (for k)."""
    up = []
    if needs_interface(scene):
        up.append("interface")
    if scene.has("dmw"):
        up.append("dmw")
    if scene.has("contact") and scene["contact"]["k"] is None:
        up.append("calibrate")
    return tuple(up)


#: Scene keys a single simulation does not read (other stages' settings, names).
NOT_READ = ("sweep", "report", "identify", "sensitivity", "scene.name", "scene.description")

STAGE = Stage(
    "simulate", compute, outputs=("histories.nc", "summary.nc"),
    reads=("*",), excludes=NOT_READ,
    upstream=upstream, order=45, doc="one protrusion in time, histories.nc and summary.nc")


def run(scene: Any, out: Path, **options: Any) -> Path:
    """``histories.nc`` (and ``summary.nc``) in ``out``, recomputed only when their inputs changed."""
    return build("simulate", scene, out, **options)["simulate"][0]
