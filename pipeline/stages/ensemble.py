"""Stage ``ensemble``: the paper's checks over ``report.realisations`` DMW realisations, for the report.

One DMW seed moves the touchdown by a 0.2-nm step, so the report judges the paper's targets over an
ensemble (:mod:`pipeline.analyses.ensemble_rules`). Running the whole sweep ``N`` times would multiply the
main job's time by ``N``; this stage runs only the protrusions the checks read:

* the protrusions of the paper's targets (:func:`pipeline.analyses.study.target_protrusions` of
  ``[identify]``: the flying FHM range, the FHM before touchdown, 9.6 and 9.8 nm, the bouncing band,
  the light-contact case at 11 nm), judged as ``hdi identify`` judges them;
* the sweep's grid points within :data:`WINDOW_NM` of the sweep's first contact (the scene's own
  record, default roughness and damping), where the touchdown probability rises from 0 to 1 in this
  model (its touchdown need not be the paper's).

Every realisation runs the scene with the sweep's k (``calibration.nc`` or the scene's rule,
:func:`pipeline.model.inputs.for_stage`) on its own DMW record (realisation 0: the scene's ``dmw.nc``;
``r >= 1``: :func:`pipeline.model.dmw_record.realisation_seeds`, the seeds of ``[sweep] realisations``),
one fan-out task per local worker or cluster thread (:func:`pipeline.fanout.split`), whose realisations share their
static starts (:func:`pipeline.evaluations.evaluate_realisations`). Writes ``ensemble.nc``: the steady-window scalars on
``(protrusion, realisation)`` in dataset units, ``dmw_seed``, and the sweep's ensemble summaries
(``<name>_mean``/``_std``, ``touchdown_probability``; :func:`pipeline.analyses.ensemble_rules.statistics`).

Part of ``hdi run`` when ``report.realisations`` > 1 and the scene has a synthetic DMW record.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import xarray as xr

from ..analyses import ensemble_rules as en
from ..analyses.report_settings import wants_ensemble
from ..analyses.study import TARGET_FIELDS, bouncing_bv, ensemble_summary, target_protrusions, targets
from ..analyses.sweep_slices import combinations, first_contact, split_ensemble
from ..config.grid import label
from ..config.heater_power import ACTUATION_FIELDS, power_coordinates
from ..evaluations import evaluate_realisations
from ..fanout import run_tasks, split
from ..io import var
from ..model import dmw_record, scene_inputs
from ..model.inputs import for_stage
from ..runner import Inputs, Stage
from ..variables import ENSEMBLE, RUN, SCALARS, coordinate

log = logging.getLogger(__name__)

#: Half-width [nm] of the protrusion window around the sweep's first contact: five 0.2-nm actuation
#: steps, several times the touchdown's spread over DMW seeds (about one step: docs/model.md, section
#: "Ensembles"; the report states the spread it finds).
WINDOW_NM = 1.0


def applies(scene: Any) -> bool:
    """Whether the report asks for an ensemble the scene can make (a synthetic DMW record)."""
    return wants_ensemble(scene)


def protrusions(scene: Any, sweep: xr.Dataset) -> list[float]:
    """The protrusions [nm] of the ensemble: the targets' and the sweep's grid within :data:`WINDOW_NM`
    of its first contact (default combination), sorted."""
    pts = set(target_protrusions(targets(scene)))
    _, ds = combinations(split_ensemble(sweep)[0], scene["air_bearing"]["damping_ratio"])[0]
    fc = first_contact(ds)
    if fc is not None:
        x = ds["protrusion"].values
        pts |= {float(label(float(v))) for v in x[np.abs(x - fc) <= WINDOW_NM + 1e-9]}
    return sorted(pts)


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """``ensemble.nc`` (module docstring). Options: ``scheduler``, ``workers`` (the fan-out)."""
    n = scene["report"]["realisations"]
    if not applies(scene):
        where = str(scene.path) if scene.path else "<scene>"
        raise ValueError(f"{where}: the ensemble stage needs report.realisations > 1 (got {n}) and a synthetic DMW "
                         "record (the dmw effect with dmw.source = \"synthetic\")")
    sweep = inputs.dataset("sweep.nc", stage="sweep")
    prot = protrusions(scene, sweep)
    sim = for_stage(scene, inputs)  # (k: the sweep's, calibration.nc or the scene's rule)
    seeds = dmw_record.realisation_seeds(scene["dmw"]["seed"], n)
    results: dict[int, tuple[dict[str, list[float]], float, list[str]]] = {}

    def done(rows: list[tuple]) -> None:
        for res in rows:
            results[res[0]] = res[1:]

    scheduler, workers = inputs.options.get("scheduler"), inputs.options.get("workers")
    # (a task's realisations share their static starts)
    tasks = [(scene, prot, sim, c, tuple(seeds[r] for r in c)) for c in split(range(n), scheduler, workers)]
    seconds = run_tasks(evaluate_realisations, tasks, scheduler=scheduler, workers=workers, on_done=done)
    errors = [f"realisation {r}: {e}" for r in range(n) for e in results[r][2]]
    for e in errors:
        log.warning("ensemble: %s", e)
    inputs.record(compute_seconds=round(seconds, 3), runs=n * len(prot),
                  kernel_seconds=round(sum(results[r][1] for r in range(n)), 3))
    ds = dataset(prot, seeds, [results[r][0] for r in range(n)],
                 {"k": sim.k if sim.k is not None else "none", "k_source": sim.k_source, "realisations": n,
                  "window_nm": WINDOW_NM, "errors": "; ".join(errors) or "none",
                  "protrusions_note": "the paper targets' protrusions ([identify]) and the sweep's grid within "
                                      f"{WINDOW_NM:g} nm of its first contact"})
    ds = ds.assign_coords(power_coordinates(scene, ds["protrusion"].values))
    run = {"k": RUN["k"].data(sim.k if sim.k is not None and np.isfinite(sim.k) else np.nan, ()),
           "k_source": RUN["k_source"].data(np.array(sim.k_source, dtype=object), ())}
    return ds.assign(judged(ds, scene)).assign(run)


#: The longest paper target's ``long_name`` [characters] that labels the target's variables of ``ensemble.nc``;
#: a longer one (a sentence) is their ``description``, and the target's name their label.
SHORT_TARGET = 28


def judged(ds: xr.Dataset, scene: Any) -> dict[str, xr.Variable]:
    """The paper's targets judged over the realisations of ``ds``, for the report (which only formats them).

    Per target ``t`` of :func:`pipeline.analyses.study.targets`: ``value_t``, ``spread_t`` (low, high; what
    they are in its ``spread`` attribute) and ``single_t`` (the scene's record alone), by
    :func:`pipeline.analyses.study.ensemble_summary`; ``bv_exceedance_probability`` [1], P(bouncing BV >
    ``identify.bouncing_min_percent``) (:func:`pipeline.analyses.study.bouncing_bv`: 0 where the run flew) versus protrusion; ``nominal_area_mean``/``_std`` [um2] versus
    protrusion (:mod:`pipeline.analyses.ensemble_rules`).
    """
    tlist = targets(scene)
    out: dict[str, xr.Variable] = {}
    for name, (v, lo, hi, single) in ensemble_summary(ds, tlist).items():
        t = next(t for t in tlist if t.name == name)
        # (a short long_name for a plot's label, the target's sentence as the description)
        label = t.long_name if len(t.long_name) <= SHORT_TARGET else name.replace("_", " ")
        out[f"value_{name}"] = var(v, (), t.units, label, description=f"{t.long_name} over the DMW realisations",
                                   paper=t.paper, spread=t.spread, protrusions_nm=np.asarray(t.protrusions, float))
        out[f"spread_{name}"] = var(np.array([lo, hi]), ("bound",), t.units, f"{label}, spread",
                                    description=f"spread of the {t.long_name} over the DMW realisations ({t.spread})")
        out[f"single_{name}"] = var(single, (), t.units, f"{label}, own record",
                                    description=f"{t.long_name}, the scene's own record alone")
    out["bound"] = var(np.array(["low", "high"], dtype=object), ("bound",), "", "lower/upper end of a spread")
    threshold = float(scene["identify"]["bouncing_min_percent"])
    if "nominal_area" in ds:
        mean, std = en.mean_std(ds["nominal_area"])
        unit = SCALARS["nominal_area"].units
        out["nominal_area_mean"] = var(mean.values, ("protrusion",), unit, "nominal contact area, mean",
                                       description="ensemble mean of the nominal contact area")
        out["nominal_area_std"] = var(std.values, ("protrusion",), unit, "nominal contact area, std",
                                      description="ensemble standard deviation (ddof 1) of the nominal contact area")
    if "min_clearance" not in ds:  # (no contact law: nothing bounces, as nothing touches)
        return out
    bouncing = bouncing_bv(ds["fhm_bv"], ds["min_clearance"])  # (a flying FHM above it is no bounce)
    out["bv_exceedance_probability"] = var(en.exceedance_probability(bouncing, threshold).values, ("protrusion",),
                                           "1", f"P(BV > {threshold:g} %)",
                                           description=f"fraction of the DMW realisations in contact with BV above "
                                                       f"{threshold:g} %", threshold_percent=threshold)
    # the band's statistics for the report's band.png (which reads them, and imports no model code)
    unit = SCALARS["fhm_bv"].units
    out["bouncing_bv"] = var(bouncing.transpose("protrusion", "realisation").values, ("protrusion", "realisation"),
                             unit, "bouncing BV",
                             description="bouncing BV: FHM/BV of a run in contact in the steady window, 0 where it flew")
    for name, values, units, what in (("bouncing_bv", bouncing, unit, "bouncing BV"),
                                      ("contact_fraction", ds.get("contact_fraction"), "1", "contact fraction")):
        if values is None:
            continue
        med, lo, hi = en.median_spread(values.fillna(0.0) if name == "contact_fraction" else values)
        out[f"{name}_median"] = var(med.values, ("protrusion",), units, f"{what}, median",
                                    description=f"median over the DMW realisations of the {what}")
        out[f"{name}_spread"] = var(np.stack([lo.values, hi.values], axis=-1), ("protrusion", "bound"), units,
                                    f"{what}, 10-90 % range",
                                    description=f"10-90 % range over the DMW realisations of the {what}")
    return out


def dataset(prot: list[float], seeds: list[int], outputs: list[dict[str, list[float]]], attrs: dict) -> xr.Dataset:
    """The realisations' outputs (dataset units, one dict per realisation) on ``(protrusion, realisation)``,
    with ``dmw_seed`` and :func:`pipeline.analyses.ensemble_rules.statistics`."""
    dims = ("protrusion", "realisation")
    names = [name for name in SCALARS if any(name in o for o in outputs)]
    nan = [float("nan")] * len(prot)
    data = {name: SCALARS[name].data(np.array([o.get(name, nan) for o in outputs], float).T, dims)
            for name in names}
    data.update(en.statistics(data))
    data["dmw_seed"] = ENSEMBLE["dmw_seed"].data(np.array(seeds), ("realisation",))
    coords = {"protrusion": coordinate("protrusion", np.array(prot)),
              "realisation": ENSEMBLE["realisation"].data(np.arange(len(seeds)), ("realisation",))}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(attrs)
    return ds


def _upstream(scene: Any) -> tuple[str, ...]:
    return scene_inputs.input_stages(scene) + ("sweep",)


STAGE = Stage(
    "ensemble", compute, simulates=True, outputs=("ensemble.nc",),
    # what a simulation reads, the DMW records of the realisations, report.realisations and the targets'
    # definitions in [identify] (not the optimiser's settings)
    reads=(*scene_inputs.SIMULATION_FIELDS, *dmw_record.FIELDS, *ACTUATION_FIELDS, "touchdown.*",
           "report.realisations", *TARGET_FIELDS),
    upstream=_upstream, applies=applies, order=57, main_job=True,
    doc="the paper's checks over report.realisations DMW realisations (ensemble.nc, for the report)")
