"""Stage ``identify``: the unknown [recon] parameters from the paper's published targets.

``hdi identify CONFIG`` fits the free parameters of ``[identify] parameters`` (scene keys with bounds)
to the targets of ``[identify]`` (:func:`pipeline.analyses.study.targets`: touchdown at 9.8 nm and not 9.6,
FHM 12.5 % at 4-7 nm and ~9 % at 9 nm, BV > 20 % after touchdown, and the light-contact numbers at
11 nm), each candidate evaluated as a small sweep at the protrusions the targets need
(:mod:`pipeline.analyses.study`) on the fan-out (:mod:`pipeline.fanout`; threads of this process by
default, ``--scheduler processes`` or a dask.distributed address for more). The objective is the
sum of squared residuals, each normalised by its tolerance (docs/model.md, section "Corrections").

Ensembles: each candidate runs on ``identify.realisations`` DMW records (default 8; the seeds of
:func:`pipeline.model.dmw_record.realisation_seeds`, part of the evaluation's key), and every target
is judged on its ensemble statistic (:attr:`pipeline.analyses.study.ObjectiveTerm.ensemble`, the rules
of :mod:`pipeline.analyses.ensemble_rules`): one DMW seed moves the touchdown by a 0.2-nm step, so a fit to
one record fits that record's noise. ``identify.nc`` then also holds each target's spread over the
realisations (``spread(evaluation, target, bound)``). One realisation is the single-record identification.
With ``identify.racing`` (the default) the candidates race over the records
(:class:`pipeline.analyses.identification.Racing`): the evaluator runs and stores an ensemble in parts
(2, 4, then all records; :class:`pipeline.evaluations.Evaluator` ``stages``), and a candidate that has
provably lost stops early; ``records`` in identify.nc says how many each ran on, the attributes
``record_evaluations`` and ``simulations_run`` what the whole cost.

Method (:mod:`pipeline.analyses.identification`, which holds the algorithm; this stage reads the
scene, makes the evaluator, calls it and writes the outputs): a global search by differential evolution
[SP97]_, profiles of each parameter with their intervals, and the Gauss-Newton correlation at the optimum.

Resuming: the stage runs under :mod:`pipeline.runner` (skipped when its inputs did not change); every
evaluation is appended to ``identify.evals.jsonl`` as it finishes
(:class:`pipeline.evaluations.EvaluationStore`); the optimiser is seeded and deterministic, so a rerun
after an interrupt replays the same candidates and reads the finished ones back. ``--force`` starts
afresh.

Outputs: ``identify.nc`` (every evaluation with its parameter values, target values, residuals and
wall time; the best point, intervals, profiles, correlation matrix; dimensions ``evaluation``,
``parameter``, ``target``, ``bound``, ``point``: docs/datasets.md), the scene ``identified.toml`` in the
results folder (``extends`` the scene, which its header names; each identified value with its interval
in a comment; the best evaluation's values, as ``best`` in identify.nc) and ``figures/identify.png``
(residuals per target, parameter profiles).
Nothing is written beside the scene file: a copy of the identified scene goes elsewhere only where the
user names it (``hdi identify --write-scene PATH``, option ``write_scene``), and never over an existing
file of other content unless forced (``--force``).

References
----------
.. [SP97] R. Storn, K. Price, "Differential evolution -- a simple and efficient heuristic for global
   optimization over continuous spaces", J. Global Optim. 11 (1997) 341-359.
"""

from __future__ import annotations

import logging
import os
from dataclasses import replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import xarray as xr

from ..analyses import plots
from ..analyses.feasibility import box_check
from ..config.limits import POLISH_EVALUATIONS
from ..fanout import local_cluster
from ..progress import Progress
from ..io import read_dataset, temporary_path, var
from ..paths import refuse_links
from ..runner import Inputs, Stage
from ..analyses.identification import (GN_STEP, METHODS, PROFILE_GAIN, PROFILE_STEP, ROLES,
                                       Identification, Racing, identify)
from ..analyses.free_parameters import Parameter, parse_parameters, scene_value
from ..analyses.study import target_protrusions, targets
from ..evaluations import Evaluator, evaluate_batch, pad_bounds, setup, upstream
from ..model.inputs import Source
from ..model.scene_inputs import STUDY_FIELDS

log = logging.getLogger(__name__)


#: The dimensions of ``identify.nc`` and the attribute naming the variable of its values' units.
E, P, T, B, K = ("evaluation",), ("parameter",), ("target",), ("bound",), ("point",)
PU, TU = {"unit_variable": "parameter_units"}, {"unit_variable": "target_units"}


def dataset(ident: Identification, params: Sequence[Parameter], out: dict[str, Any], x_base: np.ndarray,
            ev: Evaluator, progress: Any | None = None) -> xr.Dataset:
    """``identify.nc``: every evaluation of ``ident`` (made by ``ev``) and the result ``out`` of
    :func:`pipeline.analyses.identification.identify`, on the dimensions ``evaluation``, ``parameter``
    (the scene keys), ``target``, ``bound`` (low, high) and ``point`` (of a profile); docs/datasets.md.

    Every variable has its ``long_name`` and ``units``; one whose values are in each parameter's (or
    target's) own unit names the variable that holds those units instead (``unit_variable``:
    ``parameter_units``, ``target_units``), as ``accuracy.nc``'s settings do. ``progress`` (a started
    :class:`pipeline.progress.Progress`) counts the scoring of the evaluations as a phase of its own.
    """
    recs = list(ident.records.values())
    keys = ident.keys
    tl = ident.tlist
    n_real = ev.realisations
    vals = np.array([ident.scores[k][0] for k in keys]).reshape(len(keys), len(tl))
    res = np.array([ident.scores[k][1] for k in keys]).reshape(len(keys), len(tl))
    spr = np.full((len(keys), len(tl), 2), np.nan)
    if progress is not None:
        progress.phase("scoring", len(recs), unit="evaluation")
    for i, k in enumerate(keys):  # (ensembles: the spread of each target over the realisations, scored with it)
        if n_real > 1:
            spr[i] = ident.value_spreads[k]
        if progress is not None:
            progress.update()
    pts = np.array([r["params"] for r in recs], float)
    objective = np.sum(res**2, axis=1)
    i_best = int(out["best_evaluation"])
    data = {**_parameter_variables(params, out, pts, x_base), **_target_variables(tl, vals, spr, n_real),
            **_evaluation_variables(ident, recs, res, objective, out)}
    ds = xr.Dataset(data, coords=_coordinates(params, tl, len(recs), out["profile_value"].shape[1]))
    ds.attrs.update(_attributes(ident, out, ev, len(params), i_best, float(objective[i_best])))
    return ds


def _parameter_variables(params: Sequence[Parameter], out: dict[str, Any], pts: np.ndarray,
                         x_base: np.ndarray) -> dict[str, Any]:
    """The variables of ``identify.nc`` on ``parameter``: each parameter's values, its identified value,
    bounds, interval and profile (with the slices of an optimised profile)."""
    optimised = out["method"] == METHODS["optimised"]
    data: dict[str, Any] = {
        "parameter_value": var(pts, E + P, "", "parameter value",
                               description="value of each free parameter at each evaluation", **PU),
        "best": var(out["best"], P, "", "identified value",
                    description="identified value of each parameter: the best evaluation's "
                    "(best_evaluation, lowest objective)", **PU),
        "reconstructed": var(x_base, P, "", "reconstructed value",
                             description="reconstructed (scene) value of each parameter", **PU),
        "search_bounds": var(np.array([[p.low, p.high] for p in params]), P + B, "",
                             "search bounds of each parameter", **PU),
        "interval": var(out["intervals"], P + B, "", "parameter interval",
                        description=f"interval of each parameter ({out['method']})",
                        criterion=out["criterion"], method=out["method"], **PU),
        "gauss_newton_std": var(out["gn_std"], P, "", "Gauss-Newton std",
                                description="Gauss-Newton standard deviation of each parameter "
                                "(tolerances as 1 sigma)", **PU),
        "profile": var(out["profile_value"], P + K, "", "profile values",
                       description="values of each parameter along its profile "
                       "(NaN past the end of its grid)", **PU),
        "profile_objective": var(out["profile_cost"], P + K, "1", "objective along each parameter's profile"),
        "profile_max_residual": var(out["profile_max"], P + K, "1",
                                    "profile largest |residual|",
                                    description="largest |residual| along each parameter's profile"),
    }
    if optimised:  # (a slice's others are the optimum's: nothing more to say)
        data.update({
            "slice_interval": var(out["slice_intervals"], P + B, "", "slice interval",
                                  description=f"interval of each parameter from its slice ({METHODS['slice']})",
                                  criterion=out["criterion"], method=METHODS["slice"], **PU),
            "slice_objective": var(out["slice_cost"], P + K, "1", "slice objective",
                                   description="objective along each parameter's slice (the "
                                   "other parameters at the optimum)"),
            "profile_parameters": var(out["profile_points_x"], P + K + ("parameter_b",), "",
                                      "profile parameters",
                                      description="every parameter (parameter_b) at each point of each parameter's profile "
                                      "(re-optimised where profile_optimised is 1; the profiled value on its own)",
                                      unit_variable="parameter_b_units"),
            "profile_optimised": var(out["profile_optimised"].astype(np.int8), P + K, "1",
                                     "re-optimised at point",
                                     description="1 where the other parameters were re-optimised at the profile point, 0 where "
                                     "they are held at the optimum (past the walk's end or its budget)",
                                     flag_values=np.array([0, 1], np.int8), flag_meanings="held re_optimised"),
        })
    return data


def _target_variables(tl: Sequence[Any], vals: np.ndarray, spr: np.ndarray, n_real: int) -> dict[str, Any]:
    """The variables of ``identify.nc`` on ``target``: each target's goal, tolerance and description, its value
    at each evaluation and (over DMW realisations) its spread."""
    data: dict[str, Any] = {
        "goal": var(np.array([t.target for t in tl], float), T, "", "value each target aims at ([identify])",
                    **TU),
        "tolerance": var(np.array([t.tolerance for t in tl], float), T, "", "tolerance of each target", **TU),
        "target_kind": var(np.array([t.kind for t in tl], dtype=object), T, "",
                           "target kind", description="kind of each target: equal, above, below, touchdown"),
        "target_paper": var(np.array([t.paper for t in tl], dtype=object), T, "",
                            "each target as the paper states it"),
        "target_description": var(np.array([t.long_name for t in tl], dtype=object), T, "",
                                  "what each target measures"),
        "value": var(vals, E + T, "", "value of each target at each evaluation", **TU),
    }
    if n_real > 1:  # (ensembles only: a single-record identify.nc has none)
        data["spread"] = var(spr, E + T + B, "", "target spread",
                             description="spread of each target over the DMW realisations "
                             "(target_spread says which)", **TU)
        data["target_spread"] = var(np.array([t.spread for t in tl], dtype=object), T, "",
                                    "what the spread of each target is")
    return data


def _evaluation_variables(ident: Identification, recs: list[dict[str, Any]], res: np.ndarray, objective: np.ndarray,
                          out: dict[str, Any]) -> dict[str, Any]:
    """The variables of ``identify.nc`` of each evaluation: its residuals and objective, its cost, role and
    failure, and the parameters' correlation."""
    keys = ident.keys
    return {
        "residual": var(res, E + T, "1", "normalised residual",
                        description="residual of each target normalised by its tolerance "
                        "(inequality targets: zero on the admissible side)"),
        "objective": var(objective, E, "1", "objective", description="objective: sum of squared normalised residuals"),
        "best_abs_residual": var(np.nanmin(np.abs(res), axis=0), T, "1",
                                 "smallest |residual|",
                                 description="smallest |residual| of each target over all evaluations"),
        "seconds": var(np.array([r["seconds"] for r in recs]), E, "s", "wall time of the evaluation"),
        "records": var(np.array([ident.depth[k] for k in keys], np.int32), E, "1",
                       "DMW records run", description="DMW records the evaluation ran on (fewer than realisations: "
                       "stopped early by racing, its values and residuals those of its first records)"),
        "kernel_seconds": var(np.array([r["kernel_seconds"] for r in recs]), E, "s",
                              "integrator time", description="time in the integrator (run_model) of the evaluation"),
        "role": var(np.array([ident.roles[k] for k in keys], np.int8), E, "1", "role of the evaluation",
                    flag_values=np.array(sorted(ROLES), np.int8),
                    flag_meanings=" ".join(ROLES[k] for k in sorted(ROLES))),
        "failed": var(np.array([r["error"] is not None for r in recs], np.int8), E, "1",
                      "failed",
                      description="1 when a run of the evaluation failed (its message in the evaluation store)"),
        "correlation": var(out["correlation"], ("parameter", "parameter_b"), "1",
                           "parameter correlation",
                           description="correlation of the parameters, Gauss-Newton (J^T J)^+ at the optimum"),
    }


def _coordinates(params: Sequence[Parameter], tl: Sequence[Any], n_evaluations: int, n_points: int) -> dict[str, Any]:
    """The coordinates of ``identify.nc``: evaluations, parameters (and their units), targets, bounds, profile points."""
    names = np.array([p.name for p in params], dtype=object)
    units = np.array([p.units for p in params], dtype=object)
    return {
        "evaluation": var(np.arange(n_evaluations), E, "1", "evaluation index (request order)"),
        "parameter": var(names, P, "", "free parameter (scene key)"),
        "parameter_b": var(names, ("parameter_b",), "", "free parameter (scene key)"),
        "parameter_units": var(units, P, "", "units of each free parameter (UDUNITS)"),
        "parameter_b_units": var(units, ("parameter_b",), "", "units of each free parameter (UDUNITS)"),
        "parameter_description": var(np.array([p.doc for p in params], dtype=object), P, "",
                                     "what each free parameter is"),
        "target": var(np.array([t.name for t in tl], dtype=object), T, "", "target name"),
        "target_units": var(np.array([t.units for t in tl], dtype=object), T, "", "units of each target (UDUNITS)"),
        "bound": var(np.array(["low", "high"], dtype=object), B, "", "lower/upper end"),
        "point": var(np.arange(n_points), K, "1", "profile point index"),
    }


def _attributes(ident: Identification, out: dict[str, Any], ev: Evaluator, n_params: int, i_best: int,
                best_objective: float) -> dict[str, Any]:
    """The global attributes of ``identify.nc``: the best evaluation, the methods and the identification's cost."""
    optimised = out["method"] == METHODS["optimised"]
    n_real = ev.realisations
    return {
        "best_evaluation": i_best, "best_objective": best_objective,
        "profile_centre_evaluation": int(out["centre_evaluation"]), "reconstructed_evaluation": 0,
        "within_tolerance": int(out["within"]), "interval_criterion": out["criterion"],
        "optimiser": "scipy.optimize.differential_evolution best1bin, latinhypercube + reconstructed x0, "
                     "vectorized (one fan-out per generation), deferred updating, polish=False",
        "optimiser_message": out["de_message"], "generations": out["de_generations"],
        "optimiser_evaluations": out["de_evaluations"], "profile_rounds": out["profile_rounds"],
        "interval_method": out["method"],
        **({"profile_optimiser": f"compass search over the other parameters (steps of {PROFILE_STEP:g} x range) from "
                                 "the neighbouring re-optimised point moved along the Gauss-Newton valley (first step) "
                                 "or the secant of the last two points, walked outward from the optimum; each walk "
                                 "stops past the first point outside the interval criterion",
            "profile_optimiser_evaluations": out["profile_optimiser_evaluations"]} if optimised else {}),
        **_polish_attrs(out["polish"], n_params),
        "correlation_method": f"Gauss-Newton (J^T J)^+ at the optimum, central differences of {GN_STEP:g} x range",
        "racing": _racing_text(ident.racing),
        # the identification's cost: (candidate, DMW record) pairs, and runs (x protrusions), store reads included
        "record_evaluations": ident.record_evaluations,
        "simulations_run": ident.record_evaluations * len(ev.protrusions),
        "protrusions_nm": ev.protrusions,
        **({"realisations": n_real,
            "ensemble_rules": "targets judged over the DMW realisations (pipeline/analyses/ensemble_rules.py): touchdown "
                              "where the touchdown probability crosses 0.5 (residual on the median minimum clearance), "
                              "FHM/BV medians, the light-contact state as means"} if n_real > 1 else {}),
        # (this run's counts and fan-out time go to the run log, .hdi/runs.jsonl, not the dataset)
    }


def _pad_attributes(pads: xr.Dataset) -> dict[str, Any]:
    """What identify.nc says of the candidates' bulge tables when they are interpolated in p_pad
    (``bulge_pads.nc``, :mod:`pipeline.stages.bulge_pads`): which table, its nodes and its measured error."""
    nodes = ", ".join(f"{p:.4g}" for p in pads.attrs["pad_nodes_mpa"])
    return {"bulge_table": f"bulge_pads.nc: the {pads.attrs['bulge_model']} bulge table at the pad pressures "
                           f"{nodes} MPa, each candidate's interpolated at its p_pad ({pads.attrs['interpolation']}); "
                           f"largest relative lift error half-way between the nodes "
                           f"{float(pads.attrs['max_lift_error']):.2e}",
            "bulge_pad_nodes_mpa": np.asarray(pads.attrs["pad_nodes_mpa"], float),
            "bulge_pad_check_mpa": np.asarray(pads.attrs["check_pads_mpa"], float),
            "bulge_pad_lift_error": np.asarray(pads.attrs["check_lift_error"], float)}


def identify_upstream(scene: Any) -> tuple[str, ...]:
    """The stages identify reads: a study's (:func:`pipeline.evaluations.upstream`) and ``bulge_pads`` when the
    pad pressure is free on a tabulated bulge law (:func:`pipeline.evaluations.pad_bounds`)."""
    return (*upstream(scene), *(("bulge_pads",) if pad_bounds(scene) is not None else ()))


def _polish_attrs(polish: dict[str, Any] | None, n: int) -> dict[str, Any]:
    """What identify.nc says of the polish of the search's optimum (none when ``identify.polish`` is off:
    the dataset of before)."""
    if polish is None:
        return {}
    return {"polish": f"compass search over every parameter from the search's best point (steps from "
                      f"{polish['first_step']:g} x range, halved after a poll and its parabola vertex found "
                      f"nothing better, down to the first at or below {PROFILE_STEP:g}; at most "
                      f"{POLISH_EVALUATIONS * n} evaluations), polls raced against the current point; units: "
                      "polish_evaluations, polish_polls and polish_moves are counts [1], polish_last_step a fraction "
                      "of each parameter's search range [1], polish_start_objective and polish_objective the "
                      "objective, a sum of squared tolerance-normalised residuals [1]",
            "polish_evaluations": polish["evaluations"], "polish_polls": polish["polls"],
            "polish_moves": polish["moves"], "polish_last_step": polish["last_step"],
            "polish_start_objective": polish["start_objective"], "polish_objective": polish["objective"]}


def _racing_text(racing: Racing | None) -> str:
    """What identify.nc says of the racing (docs/model.md, section "Identification")."""
    if racing is None:
        return "off: every candidate on every DMW record"
    return (f"stages of {', '.join(str(m) for m in racing.stages)} DMW records; a candidate stops when the lower "
            f"bound of its objective (each residual lowered by {racing.z:g} x sqrt(pi/2) x its record-to-record "
            "spread x sqrt((N - n) / (N n))) exceeds the best point's (a profile poll: its walk's current point's); "
            "the best point, slices, Gauss-Newton points and profile points on every record")


def racing_of(cfg: dict[str, Any]) -> Racing | None:
    """The racing of ``[identify]`` (None: off, or one DMW realisation, nothing to race over)."""
    if not cfg["racing"] or cfg["realisations"] < 2:
        return None
    return Racing.doubling(min(cfg["racing_records"], cfg["realisations"]), cfg["realisations"], cfg["racing_z"])


def write_identified_scene(scene: Any, params: Sequence[Parameter], ds: xr.Dataset, path: Path,
                           replace: bool = True) -> Path:
    """Write ``path``: a scene that ``extends`` the identified one, every identified value commented.

    The file is written whole and renamed into place, and only when its text changes. ``replace=False``:
    an existing ``path`` of other content is left as it is (:class:`ValueError` naming it).
    """
    base = Path(scene.path) if scene.path else None
    rel = os.path.relpath(base, path.parent) if base else "<scene>"
    now = str(ds.attrs.get("history", "")).split(": hdi", 1)[0] or "?"  # when identify.nc was made
    rev = str(ds.attrs.get("git_revision", "unknown"))  # of identify.nc (provenance), "-dirty" kept
    rev = rev[:12] + ("-dirty" if rev.endswith("-dirty") else "")
    cfg = scene["identify"]
    lines = [f"# Identified by `hdi identify {base.name if base else ''}` on {now} (git {rev});",
             f"# the identified scene of {base.name if base else 'a scene given in memory'} (scene "
             f"\"{scene.name}\", the file `extends` names), best evaluation {ds.attrs['best_evaluation']} of "
             f"identify.nc (objective {float(ds.attrs['best_objective']):.4g});",
             "# every value below is [identified]: fitted to the paper's targets ([identify] of the base scene),",
             f"# with its interval ({ds.attrs['interval_criterion']}; "
             f"{ds.attrs.get('interval_method', METHODS['slice'])}).",
             f"# Budget: differential evolution population {cfg['population']} x {len(params)} parameters, at most "
             f"{cfg['generations']} generations ({ds.attrs.get('generations', '?')} run), {cfg['profile_points']} "
             f"profile points, {ds.attrs.get('realisations', 1)} DMW realisation(s) per candidate; "
             f"{ds.sizes['evaluation']} evaluations.",
             f"# Within tolerance on every target: {'yes' if ds.attrs['within_tolerance'] else 'no'} "
             f"(see identify.nc and the report's comparison).", "",
             "[scene]", f'extends = "{rel}"', f'name = "{scene.name}-identified"',
             f'description = "{scene.name} with its free [recon] parameters identified from the paper\'s targets"',
             ""]
    sections: dict[str, list[str]] = {}
    lists: dict[tuple[str, str], list] = {}
    for p in params:
        section, key, index = p.parts
        at = ds.sel(parameter=p.name)
        best = float(at["best"])
        lo_i, hi_i = (float(at["interval"].sel(bound=b)) for b in ("low", "high"))
        note = (f"[identified] interval [{lo_i:.4g}, {hi_i:.4g}]" if np.isfinite(lo_i)
                else "[identified] interval: none (see identify.nc)") + \
            f", bounds [{p.low:g}, {p.high:g}], reconstructed {float(at['reconstructed']):.4g}"
        if index is None:
            sections.setdefault(section, []).append(f"{key} = {best:.6g}  # {note}")
        else:
            lst = lists.setdefault((section, key), list(scene[section][key]))
            lst[index] = best
            sections.setdefault(section, []).append(f"# {key}[{index}]: {note}")
    # the scene's --set options (e.g. the stiffening law switched on) belong to the identified model too;
    # study sections are not part of a simulation scene
    identified = {p.parts[:2] for p in params}
    for text in scene.overrides:
        name, _, value = text.partition("=")
        section, _, key = name.strip().partition(".")
        if section in ("identify", "sensitivity") or (section, key) in identified:
            continue
        sections.setdefault(section, []).append(f"{key} = {value.strip()}  # --set of the identification")
    for (section, key), lst in lists.items():
        sections[section].append(f"{key} = [{', '.join(f'{v:.6g}' for v in lst)}]  # [identified]")
    for section, body in sections.items():
        lines += [f"[{section}]", *body, ""]
    text = "\n".join(lines)
    if path.is_file() and path.read_text() == text:
        return path
    refuse_links(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_path(path)
    try:
        tmp.write_text(text)
        if replace:
            os.replace(tmp, path)
        else:
            _link_new(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def _link_new(tmp: Path, path: Path) -> None:
    """Put the finished file ``tmp`` at ``path`` only if no file is there (a hard link fails on an
    existing name, so a file written meanwhile is never replaced, and ``path`` is never half-written)."""
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise ValueError(f"{path}: exists and differs from the identified scene; it was left as it is (the "
                         "identified scene is in the results folder); pass --force to replace it, or name "
                         "another file") from None


def figure(ds: xr.Dataset, params: Sequence[Parameter], scene: str, path: Path) -> Path:
    """Residuals per target (reconstructed vs identified) and the parameter profiles."""
    n = len(params)
    ncols = min(3, n)
    nrows = 1 + (n + ncols - 1) // ncols
    from matplotlib.figure import Figure
    fig = Figure(figsize=(4.0 * ncols, 3.0 * nrows), layout="constrained")
    gs = fig.add_gridspec(nrows, ncols)
    ax = fig.add_subplot(gs[0, :])
    names = [str(t) for t in ds["target"].values]
    x = np.arange(len(names))
    r0 = ds["residual"].isel(evaluation=int(ds.attrs["reconstructed_evaluation"])).values
    r1 = ds["residual"].isel(evaluation=int(ds.attrs["best_evaluation"])).values
    ax.axhspan(-1, 1, color="0.9", label="within tolerance")
    ax.bar(x - 0.2, r0, 0.4, color=plots.LINE_COLOURS[0], label="reconstructed scene")
    ax.bar(x + 0.2, r1, 0.4, color=plots.LINE_COLOURS[1], label="identified")
    ax.set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel(plots.axis_label("residual / tolerance", "1"))
    lim = max(3.0, float(np.nanmax(np.abs(np.concatenate([r0, r1])))) * 1.1)
    ax.set_ylim(-lim, lim)
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title(plots.title("Residual per target", scene), fontsize=9)
    optimised = "slice_objective" in ds
    for j, p in enumerate(params):
        a = fig.add_subplot(gs[1 + j // ncols, j % ncols])
        at = ds.sel(parameter=p.name)
        xv = at["profile"].values
        ok = np.isfinite(xv)
        if optimised:  # the slice it started from, for comparison (narrower where parameters correlate)
            a.semilogy(xv[ok], np.maximum(at["slice_objective"].values[ok], 1e-3), "s--", ms=2, lw=0.8,
                       color="0.6", label="slice (others at the optimum)")
        a.semilogy(xv[ok], np.maximum(at["profile_objective"].values[ok], 1e-3), "o-", ms=3,
                   color=plots.LINE_COLOURS[2], label="profile (others re-optimised)" if optimised else "slice")
        lo_i, hi_i = at["interval"].values
        if np.isfinite(lo_i):
            a.axvspan(lo_i, hi_i, color="#d5f5d0", label="profile interval" if optimised else "slice interval")
        a.axvline(float(at["best"]), color=plots.LINE_COLOURS[1], lw=1, label="identified")
        a.axvline(float(at["reconstructed"]), color=plots.LINE_COLOURS[0], lw=1, ls="--",
                  label="reconstructed")
        a.set_xlabel(plots.axis_label(p.name, str(at["parameter_units"].values)), fontsize=8)
        a.set_ylabel(plots.axis_label("objective", "1"), fontsize=8)
        if j == 0:
            a.legend(fontsize=7)
    return plots.save(fig, path)


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """``identify.nc`` (module docstring); draws ``figures/identify.png`` under ``inputs.staging``.

    Options (``inputs.options``): ``scheduler``, ``workers`` (the fan-out), ``force`` (forget the
    evaluation store), ``task`` (the batch function, for tests).
    """
    out, opts = inputs.out, inputs.options
    cfg = scene["identify"]
    where = str(scene.path) if scene.path else "<scene>"
    tlist = targets(scene)
    if not tlist:
        raise ValueError(f"{where}: identify.targets is empty: expected at least one target")
    prots = target_protrusions(tlist)
    if cfg["realisations"] > 1 and not (scene.has("dmw") and scene["dmw"]["source"] == "synthetic"):
        raise ValueError(f"{where}: identify.realisations = {cfg['realisations']} needs a synthetic DMW record (the dmw "
                         "effect with dmw.source = \"synthetic\"; a measured record is one realisation): set "
                         "identify.realisations = 1")
    params, base_inputs, store = setup(scene, inputs, "identify", bool(opts.get("force")))
    pads = None
    if "bulge_pads" in inputs.upstream:  # (a free p_pad on a tabulated bulge law: tables interpolated in p_pad)
        pads = read_dataset(Path(out) / "bulge_pads.nc", stage="bulge_pads")
        base_inputs = replace(base_inputs, bulge_pads=Source.file("bulge_pads", Path(out) / "bulge_pads.nc",
                                                                  inputs.upstream["bulge_pads"]))
    x_base = np.array([scene_value(scene, p) for p in params])
    if not np.all(np.isfinite(x_base)):
        bad = [p.name for p, v in zip(params, x_base) if not np.isfinite(v)]
        raise ValueError(f"{where}: identify.parameters {bad}: the scene sets no value for these keys")
    workers = opts.get("workers")
    # one count through the stage, in phases (the search, each round of profiles, the scoring), one clock
    with Progress(cfg["generations"], unit="generation", phase="search") as shown:
        shown = shown if shown.mode != "off" else None
        with local_cluster(opts.get("scheduler"), workers) as address:
            racing = racing_of(cfg)
            ev = Evaluator(scene, params, prots, base_inputs, store, cfg["batch_size"], address, workers,
                           task=opts.get("task") or evaluate_batch, realisations=cfg["realisations"],
                           stages=racing.stages if racing else ())
            ident = Identification(ev, tlist, cfg["missing_residual"], racing)
            result = identify(ident, params, x_base, cfg, progress=shown)
        ds = dataset(ident, params, result, x_base, ev, progress=shown)
    # (its file name: the scene is in the results folder, wherever that folder is)
    ds.attrs["identified_scene"] = identified_scene_path(scene, out).name
    if pads is not None:
        ds.attrs.update(_pad_attributes(pads))
    figure(ds, params, scene.name, inputs.staging / "figures" / "identify.png")
    inputs.record(evaluations=int(ds.sizes["evaluation"]), evaluations_computed=ev.evaluated,
                  record_evaluations=ident.record_evaluations, record_evaluations_computed=ev.record_evaluations,
                  batch_seconds=round(ev.batch_seconds, 3), kernel_seconds=round(ev.kernel_seconds, 3))
    i_best, i_centre = int(ds.attrs["best_evaluation"]), int(ds.attrs["profile_centre_evaluation"])
    if i_centre != i_best:
        gain = float(ds["objective"][i_centre]) - float(ds.attrs["best_objective"])
        log.info("identify: the best point (evaluation %d) is not the profiles' centre (evaluation %d): it is better by "
                 "%.4g in the objective, %s; its intervals are read from the profiles made around the centre",
                 i_best, i_centre, gain, f"less than the {PROFILE_GAIN:g} that makes the profiles again"
                 if gain <= PROFILE_GAIN else "found after the last round of profiles could move the centre")
    log.info("identify: %d evaluations (%d computed; %d candidate x DMW record runs, %d computed) in %.1f s of "
             "fan-out; kernel %.1f s; best objective %.4g (evaluation %d); within tolerance: %s",
             ds.sizes["evaluation"], ev.evaluated, ident.record_evaluations, ev.record_evaluations, ev.batch_seconds,
             ev.kernel_seconds, ds.attrs["best_objective"], i_best, "yes" if result["within"] else "no")
    return ds


#: The file name of the identified scene in the results folder: not ``<scene>-identified.toml``, which
#: reads as a shipped scene of configs/ (the scene it comes from is named in its header).
IDENTIFIED_SCENE = "identified.toml"


def identified_scene_path(scene: Any, out: Path) -> Path:
    """:data:`IDENTIFIED_SCENE` in the results folder ``out`` (``scene``: for callers that name it; the
    file name is the same for every scene, its folder is the scene's)."""
    return Path(out) / IDENTIFIED_SCENE


def _finish(scene: Any, out: Path, options: dict[str, Any]) -> None:
    """Write the identified scene from ``identify.nc`` into the results folder and, with the option
    ``write_scene`` (``--write-scene PATH``), to that path too: never over a file of other content unless
    ``force``. Each is rewritten only when its text changes (its date is that of ``identify.nc``)."""
    ds = read_dataset(Path(out) / "identify.nc", stage="identify")
    params = parse_parameters(scene["identify"]["parameters"], str(scene.path or "<scene>"), "identify.parameters")
    path = write_identified_scene(scene, params, ds, identified_scene_path(scene, out))
    log.info("identified scene: %s", path)
    if options.get("write_scene"):
        copy = write_identified_scene(scene, params, ds, Path(options["write_scene"]),
                                      replace=bool(options.get("force")))
        log.info("identified scene: %s", copy)


STAGE = Stage(
    "identify", compute, simulates=True, outputs=("identify.nc", "figures/identify.png"),
    # (what the candidates' simulations read, with the deepest protrusion their own tables reach)
    reads=(*STUDY_FIELDS, "sweep.protrusion_nm", "identify.*"), unkeyed=("identify.batch_size",),
    upstream=identify_upstream, check=box_check("identify"), finish=_finish, order=80,
    keeps=lambda scene: (identified_scene_path(scene, Path()).name, "identify.evals.jsonl"),
    doc="the free [recon] parameters fitted to the paper's targets, identify.nc and identified.toml "
        "(in the results folder; --write-scene PATH for a copy)")
