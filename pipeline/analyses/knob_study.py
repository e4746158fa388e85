"""The accuracy-knob study: what each accuracy knob costs and what it buys (no file I/O, no model assembly).

Given a callable that runs one configuration of the accuracy settings at every operating point
(``evaluate(values, repeat) -> Result``: the stage :mod:`pipeline.stages.accuracy` builds the model
and integrates), :func:`study` runs the reference, varies each knob on its own, chooses a default per
knob, checks the chosen defaults together and returns ``accuracy.nc`` as an :class:`xarray.Dataset`.
The protocol (reference settings, knob rows, error definition, wall time, choice of defaults) is
described in the stage's module docstring, :mod:`pipeline.stages.accuracy`.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np
import xarray as xr

from ..variables import ACCURACY as ACC
from ..variables import SCALARS

log = logging.getLogger(__name__)

#: Operating points: label -> protrusion [nm].
POINTS: dict[str, float] = {"flying": 5.0, "touchdown": 7.6, "sliding": 11.0}

#: Headline outputs whose error is measured.
HEADLINE = ("fhm_bv", "clearance", "interference", "contact_force", "friction_coefficient",
            "mean_pressure", "shear_stress")

#: Error floors in dataset units: the relative error is taken against max(|reference|, floor).
ERROR_FLOORS: dict[str, float] = {
    "fhm_bv": 0.1,                # [%]   0.011 nm peak-to-peak at FH0 = 11 nm
    "clearance": 0.01,            # [nm]
    "interference": 0.01,         # [nm]
    "contact_force": 1e-3,        # [mN]  1 uN
    "friction_coefficient": 0.01,  # [1]
    "mean_pressure": 1.0,         # [MPa]
    "shear_stress": 1.0,          # [MPa]
}

#: Reference (tightest) settings; keys are ``[solver]`` keys and ``sample_rate_mhz`` of ``[dmw]``.
REFERENCE: dict[str, float] = {
    "rtol": 1e-10, "atol_nm": 1e-8, "max_step_ns": 25.0, "stiffness_step": 0.25, "min_dwell_ns": 1.0,
    "table_step_nm": 0.001, "interpolation_order": 3, "quadrature_nodes": 64, "quadrature_panels": 8,
    "sample_rate_mhz": 16.0, "contact_grid_points": 512,
}

#: ``atol_nm`` follows ``rtol`` along the rtol knob: ``atol_nm = ATOL_PER_RTOL_NM * rtol``.
ATOL_PER_RTOL_NM = 100.0

#: Default tolerance on every headline error when choosing defaults [1].
TOLERANCE = 0.01

#: Settings within this factor of the cheapest passing one count as equally cheap (timing noise).
COST_TIE = 1.10

#: The chosen defaults together must pass ``COMBINED_MARGIN x tolerance`` (0.1 %): headroom for the
#: interactions one-at-a-time rows cannot show and for scenes unlike the three operating points.
COMBINED_MARGIN = 0.1


@dataclass(frozen=True)
class Knob:
    """One accuracy knob.

    Attributes
    ----------
    name : label (the scene key; its suffix is the unit, as in scene files)
    key : the scene key ``(section, key)`` it sets
    settings : values, tightest first
    units, long_name : of the setting
    kind : ``"solver"`` (only the integration), ``"table"`` (interface tables), ``"dmw"`` (record),
        ``"model"`` (model assembly: interpolation order)
    base : other solver keys this row sets away from the reference (see the module docstring)
    """

    name: str
    key: tuple[str, str]
    settings: tuple[float, ...]
    units: str
    long_name: str
    kind: str
    base: dict[str, float] = field(default_factory=dict)

    def solver_values(self, value: float) -> dict[str, float]:
        """The ``[solver]``/``[dmw]`` values of this knob at ``value`` (without the row base)."""
        if self.name == "rtol":
            return {"rtol": float(value), "atol_nm": float(f"{ATOL_PER_RTOL_NM * float(value):.12g}")}
        return {self.key[1]: cast(self.key[1], value)}


def cast(key: str, value: float) -> float | int:
    return int(value) if key in ("interpolation_order", "quadrature_nodes", "quadrature_panels",
                                 "contact_grid_points") else float(value)


#: The knobs, in the order of the dataset's ``knob`` dimension.
KNOBS: tuple[Knob, ...] = (
    Knob("rtol", ("solver", "rtol"), (1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4), "1",
         "relative tolerance (atol_nm = 100 nm x rtol); step caps lifted", "solver",
         base={"max_step_ns": 1e4, "stiffness_step": 1e3}),
    Knob("max_step_ns", ("solver", "max_step_ns"), (25.0, 50.0, 100.0, 250.0, 500.0, 1000.0), "ns",
         "largest time step; tolerance relaxed, stiffness cap lifted", "solver",
         base={"rtol": 1e-2, "atol_nm": 1.0, "stiffness_step": 1e3}),
    Knob("stiffness_step", ("solver", "stiffness_step"), (0.125, 0.25, 0.5, 1.0, 2.0, 4.0), "1",
         "step cap c / omega of the local interface spring; tolerance relaxed, max_step_ns at the scene's",
         "solver", base={"rtol": 1e-2, "atol_nm": 1.0, "max_step_ns": "scene"}),
    Knob("table_step_nm", ("solver", "table_step_nm"), (0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1), "nm",
         "interface-table separation step", "table"),
    Knob("interpolation_order", ("solver", "interpolation_order"), (3, 1), "1",
         "interpolation of tables and DMW record (3 cubic spline, 1 linear)", "model"),
    Knob("quadrature_nodes", ("solver", "quadrature_nodes"), (64, 32, 24, 16, 12, 8, 6, 4), "1",
         "Gauss-Legendre nodes per panel", "table"),
    Knob("quadrature_panels", ("solver", "quadrature_panels"), (8, 4, 2, 1), "1",
         "panels per population range", "table"),
    Knob("contact_grid_points", ("solver", "contact_grid_points"), (512, 256, 128, 64), "1",
         "grid points per side of the measured surface solved by the deterministic interface "
         "(interface.model = 'deterministic' only)", "table"),
    Knob("sample_rate_mhz", ("dmw", "sample_rate_mhz"), (16.0, 8.0, 4.0, 2.0), "MHz",
         "DMW record sample rate [MS/s]", "dmw"),
    Knob("min_dwell_ns", ("solver", "min_dwell_ns"), (1.0, 5.0, 20.0, 50.0, 100.0, 200.0, 500.0), "ns",
         "shortest contact-mode dwell after a switch", "solver"),
)

#: The ``[solver]`` keys of the interface tables (a change rebuilds them).
TABLE_KEYS = ("table_step_nm", "quadrature_nodes", "quadrature_panels", "contact_grid_points")


def relative_error(x: np.ndarray, ref: np.ndarray, floor: float) -> np.ndarray:
    """``|x - ref| / max(|ref|, floor)``; NaN where both are NaN, ``inf`` where only one is."""
    x = np.asarray(x, float)
    ref = np.asarray(ref, float)
    with np.errstate(invalid="ignore"):
        err = np.abs(x - ref) / np.maximum(np.abs(ref), floor)
    nx, nr = np.isnan(x), np.isnan(ref)
    err = np.where(nx & nr, np.nan, err)
    return np.where(nx ^ nr, np.inf, err)


@dataclass
class Result:
    """One configuration at every point."""

    values: np.ndarray          # (point, output) in dataset units
    sim_time: np.ndarray        # (point,) [s]
    build: dict[str, float]     # build times [s] of "table", "record", "model"
    info: np.ndarray            # (point, 3): accepted steps, rejected steps, contact switches
    failed: np.ndarray          # (point,) bool
    messages: list[str]

    def setup_time(self, kind: str) -> float:
        """Setup time [s] that counts for a knob of ``kind`` (:mod:`pipeline.stages.accuracy`, "Wall time")."""
        b = self.build
        return {"solver": 0.0, "model": b["model"], "table": b["table"] + b["model"],
                "dmw": b["record"] + b["model"], "all": b["table"] + b["record"] + b["model"]}[kind]


#: ``evaluate(values, repeat)``: one configuration of the accuracy settings run at every operating point.
Evaluate = Callable[[dict[str, float], int], Result]


def errors(res: Result, ref: Result) -> np.ndarray:
    """(point, output) relative errors of ``res`` against ``ref`` (inf for failed points)."""
    floors = np.array([ERROR_FLOORS[o] for o in HEADLINE])
    err = relative_error(res.values, ref.values, floors[None, :])
    err[res.failed] = np.where(np.isnan(ref.values[res.failed]), np.nan, np.inf)
    return err


def max_error(err: np.ndarray) -> np.ndarray:
    """Max over the last axis ignoring NaN (NaN when nothing applies)."""
    with np.errstate(invalid="ignore"):
        filled = np.where(np.isnan(err), -np.inf, err)
        m = filled.max(axis=-1)
    return np.where(np.isneginf(m), np.nan, m)


def passes(err: np.ndarray, tol: float) -> bool:
    """Every applicable error (any shape) below ``tol``."""
    e = err[~np.isnan(err)]
    return bool(np.all(e < tol))


def configuration(reference: dict[str, float], knobs: list[Knob], levels: dict[str, int | None]) -> dict:
    """The reference with every knob at its level (``None``: the reference value)."""
    cfg = dict(reference)
    for kb in knobs:
        if levels.get(kb.name) is not None:
            cfg.update(kb.solver_values(kb.settings[levels[kb.name]]))
    return cfg


def combine(evaluate: Evaluate, knobs: list[Knob], reference: dict[str, float], levels: dict[str, int | None],
            repeat: int, ref: Result, tol: float) -> tuple[dict[str, int | None], dict[str, Result], list[str]]:
    """Check the chosen defaults together; step back until the combination passes ``tol``.

    Knobs interact (the quadrature error depends on nodes x panels; the step on both step-size
    controllers), so a combination of settings that each pass alone may fail. While it fails, every
    knob not at its tightest setting is tried one level tighter (one run each), and the trial that
    passes at the lowest cost is kept -- or, if none passes, the one with the smallest error.

    Returns ``(levels, {"chosen": result}, adjustments)``.
    """
    levels = dict(levels)
    adjustments: list[str] = []
    by_name = {kb.name: kb for kb in knobs}
    res = evaluate(configuration(reference, knobs, levels), repeat)
    for _ in range(sum(len(kb.settings) for kb in knobs)):
        e = errors(res, ref)
        if passes(e, tol):
            break
        trials = []
        for kb in knobs:
            lvl = levels[kb.name]
            if not lvl:
                continue
            lv = {**levels, kb.name: lvl - 1}
            r = evaluate(configuration(reference, knobs, lv), 1)
            er = errors(r, ref)
            worst = float(np.nanmax(np.where(np.isnan(er), -1.0, er)))
            cost = float(np.nansum(r.sim_time) + r.setup_time("all"))
            ok = passes(er, tol)
            trials.append((not ok, cost if ok else worst, kb.name, lv, worst))
        if not trials:
            break
        trials.sort(key=lambda t: (t[0], t[1]))
        _, _, name, levels, worst = trials[0]
        adjustments.append(f"the chosen defaults together missed the combined tolerance {tol:g} (max error "
                           f"{np.nanmax(e):.3g}); {name} stepped back to {by_name[name].settings[levels[name]]:g} "
                           f"(max error then {worst:.3g})")
        log.warning(adjustments[-1])
        res = evaluate(configuration(reference, knobs, levels), repeat)
    return levels, {"chosen": res}, adjustments


def choose(kb: Knob, current: Any, passes: np.ndarray, cost: np.ndarray, max_err: np.ndarray) -> int | None:
    """Level of the chosen setting of one knob (None when none passes); ``current``: the scene's value."""
    ok = [il for il in range(len(kb.settings)) if passes[il] and np.isfinite(cost[il])]
    if not ok:
        return None
    cheapest = min(cost[il] for il in ok)
    tied = [il for il in ok if cost[il] <= COST_TIE * cheapest]
    for il in tied:
        if current is not None and np.isclose(kb.settings[il], current, rtol=1e-12, atol=0):
            return il
    return min(tied, key=lambda il: (np.nanmax(np.where(np.isnan(max_err[:, il]), -1, max_err[:, il])), il))


def _dataset(points, knobs, setting, error, values, sim_time, setup_time, wall, max_err, steps, failed,
             is_ref, passes, chosen_level, ref: Result, combos: dict[str, Result], tol: float) -> xr.Dataset:
    names = [kb.name for kb in knobs]
    P, K, L, O = ("point",), ("knob",), ("level",), ("output",)
    PKL = ("point", "knob", "level")
    # units and long names: pipeline/variables.py ACCURACY
    data = {
        "setting": ACC["setting"].data(setting, ("knob", "level"), unit_variable="setting_units"),
        "setting_units": ACC["setting_units"].data([kb.units for kb in knobs], K),
        "knob_description": ACC["knob_description"].data([kb.long_name for kb in knobs], K),
        "error": ACC["error"].data(error, PKL + O,
                                   definition="|x - x_ref| / max(|x_ref|, floor); NaN: output does not apply; "
                                              "inf: regime differs or the integration failed"),
        "max_error": ACC["max_error"].data(max_err, PKL),
        "wall_time": ACC["wall_time"].data(wall, PKL),
        "simulation_time": ACC["simulation_time"].data(sim_time, PKL),
        "setup_time": ACC["setup_time"].data(setup_time, ("knob", "level")),
        "steps": ACC["steps"].data(steps[..., 0], PKL),
        "rejected_steps": ACC["rejected_steps"].data(steps[..., 1], PKL),
        "contact_switches": ACC["contact_switches"].data(steps[..., 2], PKL),
        "failed": ACC["failed"].data(failed, PKL),
        "is_reference": ACC["is_reference"].data(is_ref, ("knob", "level")),
        "passes": ACC["passes"].data(passes, ("knob", "level"),
                                     description=f"every headline error below {tol:g} at every point (1) or not (0)"),
        "chosen_level": ACC["chosen_level"].data([chosen_level[n] if chosen_level[n] is not None else -1
                                                  for n in names], K),
        "chosen_setting": ACC["chosen_setting"].data([kb.settings[chosen_level[kb.name]]
                                                      if chosen_level[kb.name] is not None else np.nan
                                                      for kb in knobs], K, unit_variable="setting_units"),
    }
    for j, name in enumerate(HEADLINE):
        data[name] = ACC[name].data(values[..., j], PKL, error_floor=ERROR_FLOORS[name])
        data[f"reference_{name}"] = ACC[f"reference_{name}"].data(ref.values[:, j], P,
                                                                  error_floor=ERROR_FLOORS[name])
    conf = list(combos)
    comb_err = np.stack([errors(combos[c], ref) for c in conf])
    CP = ("configuration",) + P
    data["combined_error"] = ACC["combined_error"].data(comb_err, CP + O)
    data["combined_max_error"] = ACC["combined_max_error"].data(max_error(comb_err), CP)
    data["combined_wall_time"] = ACC["combined_wall_time"].data(
        np.stack([combos[c].sim_time + combos[c].setup_time("all") for c in conf]), CP)
    data["combined_simulation_time"] = ACC["combined_simulation_time"].data(
        np.stack([combos[c].sim_time for c in conf]), CP)
    coords = {
        "point": ACC["point"].data(list(points), P),
        "protrusion": ACC["protrusion"].data(list(points.values()), P),
        "knob": ACC["knob"].data(names, K),
        "level": ACC["level"].data(np.arange(setting.shape[1]), L),
        "output": ACC["output"].data(list(HEADLINE), O),
        "configuration": ACC["configuration"].data(conf, ("configuration",)),
    }
    return xr.Dataset(data, coords=coords)


def log_summary(ds: xr.Dataset, summary: "Summary", figure: str) -> None:
    """Log the study's table, the chosen defaults and the combined checks."""
    chosen, chosen_err, comb_err = summary.chosen, summary.chosen_errors, summary.combined_errors
    configs, combo_cost = summary.configurations, summary.combined_cost
    points = list(ds["point"].values)
    log.info("accuracy: max relative error (wall time [s]) per setting")
    for ik, kb in enumerate(ds["knob"].values):
        for il in range(ds.sizes["level"]):
            v = ds["setting"].values[ik, il]
            if not np.isfinite(v):
                continue
            cells = "  ".join(f"{ds['max_error'].values[ip, ik, il]:9.2e} ({ds['wall_time'].values[ip, ik, il]:7.3f})"
                              for ip in range(len(points)))
            mark = " *" if ds["chosen_level"].values[ik] == il else ""
            log.info(f"  {kb:>20} {v:<8g} {cells}{mark}")
    log.info("accuracy: chosen defaults (max error at " + ", ".join(points) + "):")
    for name, v in chosen.items():
        e = chosen_err[name]
        log.info(f"  {name:>20} = {v if v is not None else 'none':<8} "
              + ("" if e is None else "  ".join(f"{x:.2e}" for x in e.values())))
    for c, e in comb_err.items():
        log.info(f"  combined {c:>8}: " + "  ".join(f"{p} {x:.2e}" for p, x in e.items())
              + f"   wall time {combo_cost[c]:.3f} s   {configs[c]}")
    log.info("accuracy: figure %s", figure)


def select_knobs(effects: set[str], current: Mapping[str, Any], custom: Mapping[str, Any] | None = None,
                 only: Any = None, interface_model: str = "statistical") -> list[Knob]:
    """The knobs of :data:`KNOBS` that apply to the scene's ``effects``, with their row base resolved
    (``"scene"``: the scene's value in ``current``) and settings replaced by ``custom[name]``.

    ``current`` maps every accuracy setting the scene schema has (the ``[solver]`` keys and
    ``sample_rate_mhz``) to the scene's value; a knob the schema does not have is skipped, as are the
    knobs not named in ``only`` (when given).
    """
    custom = custom or {}
    knobs = []
    for kb in KNOBS:
        if only is not None and kb.name not in only:
            continue
        if kb.kind == "table" and not effects & {"contact", "adhesion"}:
            continue
        if kb.kind == "dmw" and "dmw" not in effects:
            continue
        if kb.name == "min_dwell_ns" and "contact" not in effects:
            continue
        if kb.name == "contact_grid_points" and interface_model != "deterministic":
            continue  # only the deterministic interface solves a height map
        if kb.name == "interpolation_order" and not effects & {"contact", "adhesion", "dmw"}:
            continue
        if kb.key[1] not in current:
            continue  # a knob this version of the scene schema does not have
        base = {k_: (current[k_] if v == "scene" else v) for k_, v in kb.base.items() if k_ in current}
        settings = tuple(custom[kb.name]) if kb.name in custom else kb.settings
        knobs.append(Knob(kb.name, kb.key, settings, kb.units, kb.long_name, kb.kind, base))
    if not knobs:
        raise ValueError("no accuracy knob applies to the scene's effects")
    return knobs


@dataclass
class Summary:
    """What :func:`study` chose, for the log (:func:`log_summary`).

    Attributes
    ----------
    chosen : knob -> chosen setting (``None``: no setting passes)
    chosen_errors : knob -> {point: max error of the chosen setting} (``None`` likewise)
    combined_errors : configuration (``chosen``, ``scene``) -> {point: max error}
    configurations : configuration -> its settings
    combined_cost : configuration -> summed wall time over the points [s]
    """

    chosen: dict[str, Any]
    chosen_errors: dict[str, dict[str, float] | None]
    combined_errors: dict[str, dict[str, float]]
    configurations: dict[str, dict[str, Any]]
    combined_cost: dict[str, float]


def study(evaluate: Evaluate, knobs: list[Knob], reference: dict[str, float], points: dict[str, float],
          current: Mapping[str, Any], *, repeat: int = 5, tol: float = TOLERANCE, combined_tol: float | None = None,
          k: float | None = None, k_source: str = "", record_notes: Mapping[float, str] | None = None
          ) -> tuple[xr.Dataset, Summary]:
    """The knob study: the ``accuracy.nc`` dataset and what was chosen.

    Parameters
    ----------
    evaluate : runs one configuration at every point of ``points`` (``{label: protrusion [nm]}``)
    knobs : the knobs to vary (:func:`select_knobs`); reference : the reference settings
    current : the scene's value of every accuracy setting (ties go to it; the ``scene`` configuration)
    repeat : timed repeats per run; tol : error tolerance of the defaults [1]; combined_tol : tolerance of
        the chosen defaults together [1] (default :data:`COMBINED_MARGIN` x ``tol``)
    k, k_source : the contact criterion the runs use [1] and where it came from (attributes)
    record_notes : DMW sample rate [MS/s] -> how its record was made; read after the runs (attributes)
    """
    combined_tol = float(combined_tol or COMBINED_MARGIN * tol)
    # the reference (its first run also compiles the kernels: run it once untimed)
    log.info("accuracy: reference %s", reference)
    evaluate(reference, 1)
    ref = evaluate(reference, repeat)
    if ref.failed.any():
        raise RuntimeError(f"the reference run failed: {ref.messages}")

    g = _run_knobs(evaluate, knobs, reference, points, ref, repeat)
    wall = g.sim_time + g.setup_time[None, :, :]
    max_err = max_error(g.error)
    passes_ = np.zeros(g.setup_time.shape, dtype=np.int8)
    for ik, kb in enumerate(knobs):
        for il in range(len(kb.settings)):
            passes_[ik, il] = passes(g.error[:, ik, il], tol)

    # choose defaults, then check them together
    chosen_level = {}
    for ik, kb in enumerate(knobs):
        chosen_level[kb.name] = choose(kb, current[kb.key[1]], passes_[ik], wall[:, ik, :].sum(axis=0),
                                       max_err[:, ik, :])
    chosen_level, combos, adjustments = combine(evaluate, knobs, reference, chosen_level, repeat, ref, combined_tol)
    chosen_cfg = configuration(reference, knobs, chosen_level)
    scene_cfg = {key: current[key] for key in reference}
    combos["scene"] = evaluate(scene_cfg, repeat)
    combo_cost = {c: float(np.nansum(r.sim_time) + r.setup_time("all")) for c, r in combos.items()}
    configs = {"chosen": chosen_cfg, "scene": scene_cfg}

    ds = _dataset(points, knobs, g.setting, g.error, g.values, g.sim_time, g.setup_time, wall, max_err, g.steps,
                  g.failed, g.is_ref, passes_, chosen_level, ref, combos, tol)
    chosen = {kb.name: (kb.settings[chosen_level[kb.name]] if chosen_level[kb.name] is not None else None)
              for kb in knobs}
    chosen_err = {}
    for ik, kb in enumerate(knobs):
        lvl = chosen_level[kb.name]
        chosen_err[kb.name] = ({p: float(max_err[ip, ik, lvl]) for ip, p in enumerate(points)}
                               if lvl is not None else None)
    comb_err = {c: {p: float(max_error(errors(r, ref))[ip]) for ip, p in enumerate(points)}
                for c, r in combos.items()}
    rec_notes = {f"{r:g} MS/s": n for r, n in (record_notes or {}).items()}
    ds.attrs.update(_study_attrs(knobs, reference, points, tol, combined_tol))
    ds.attrs.update({
        "chosen_defaults": {k_: (cast(k_, v) if v is not None else None) for k_, v in chosen.items()},
        "chosen_defaults_errors": chosen_err,
        "chosen_configuration": {k_: cast(k_, v) for k_, v in chosen_cfg.items()},
        "scene_configuration": {k_: cast(k_, v) for k_, v in scene_cfg.items()},
        "combined_max_errors": comb_err,
        "combined_total_wall_time_s": combo_cost,
        "chosen_adjustments": adjustments or "none",
        "timing": f"simulation: median of {repeat} runs of simulate (run, summary, dataset) after compilation; table builds "
                  "longer than 1 s timed once; sequential, one process",
        "cpus": os.cpu_count() or 0,
        "k": float(k) if k is not None else "none",
        "k_source": k_source,
        "dmw_record_method": rec_notes or "no dmw effect",
        "dmw_record_check": "; ".join(f"{r}: {n}" for r, n in rec_notes.items()) or "none",
        "failures": "; ".join(f"{kb.name}={kb.settings[il]:g}: {m}" for (ik, il), r in g.results.items()
                              for kb in [knobs[ik]] for m in r.messages) or "none",
    })
    return ds, Summary(chosen, chosen_err, comb_err, configs, combo_cost)


@dataclass
class _Grid:
    """Every knob's settings run against the reference, on (point, knob, level[, headline output]): the errors
    [1] and values (dataset units) of the headline outputs, simulation times [s], setup times [s] per (knob,
    level), step counters, failures, whether a row is the reference's, the settings and each run's result."""

    error: np.ndarray
    values: np.ndarray
    sim_time: np.ndarray
    setup_time: np.ndarray
    steps: np.ndarray
    failed: np.ndarray
    is_ref: np.ndarray
    setting: np.ndarray
    results: dict[tuple[int, int], Result]


def _run_knobs(evaluate: Evaluate, knobs: list[Knob], reference: dict[str, float], points: dict[str, float],
               ref: Result, repeat: int) -> _Grid:
    """Run every setting of every knob (the others at the reference; the rows equal to the reference once, a
    fresh run whose zero error checks determinism) and compare each with the reference run ``ref``."""
    n_p, n_k, n_o = len(points), len(knobs), len(HEADLINE)
    n_l = max(len(kb.settings) for kb in knobs)
    shape = (n_p, n_k, n_l)
    g = _Grid(error=np.full(shape + (n_o,), np.nan), values=np.full(shape + (n_o,), np.nan),
              sim_time=np.full(shape, np.nan), setup_time=np.full((n_k, n_l), np.nan),
              steps=np.full(shape + (3,), -1, dtype=np.int64), failed=np.zeros(shape, dtype=np.int8),
              is_ref=np.zeros((n_k, n_l), dtype=np.int8), setting=np.full((n_k, n_l), np.nan), results={})
    rerun: Result | None = None  # the rows equal to the reference: one fresh run, not a copy of ``ref``
    for ik, kb in enumerate(knobs):
        for il, value in enumerate(kb.settings):
            cfg = {**reference, **kb.base, **kb.solver_values(value)}
            g.setting[ik, il] = value
            same = all(cfg[key] == reference[key] for key in reference)
            if same:
                # a new model build and integration, so their zero error checks determinism
                rerun = rerun or evaluate(cfg, repeat)
                res = rerun
            else:
                res = evaluate(cfg, repeat)
            g.is_ref[ik, il] = same
            g.results[ik, il] = res
            e = errors(res, ref)
            g.error[:, ik, il] = e
            g.values[:, ik, il] = res.values
            g.sim_time[:, ik, il] = res.sim_time
            g.setup_time[ik, il] = res.setup_time(kb.kind)
            g.steps[:, ik, il] = res.info
            g.failed[:, ik, il] = res.failed
            me = max_error(e)
            log.info(f"  {kb.name:>20} = {value:<8g} max error " + "  ".join(
                f"{p}: {m:9.3g}" for p, m in zip(points, me))
                + f"   time {np.nansum(res.sim_time) + res.setup_time(kb.kind):7.3f} s"
                + ("  FAILED: " + "; ".join(res.messages) if res.failed.any() else ""))
    return g


def _study_attrs(knobs: list[Knob], reference: dict[str, float], points: dict[str, float], tol: float,
                 combined_tol: float) -> dict[str, Any]:
    """The attributes of ``accuracy.nc`` that describe the study itself: the reference and its note, the rows'
    bases, the error's definition and floors, the tolerances and the rule that chooses the defaults."""
    return {
        "reference_settings": {k_: cast(k_, v) for k_, v in reference.items()},
        "reference_note": "tightest settings; max_step_ns = 25 binds (fixed 25 ns DP5 step); its own "
                          "time-discretisation error is bounded by error(knob='rtol', level=0), an independent "
                          "tolerance-controlled step sequence",
        "row_base": {kb.name: kb.base for kb in knobs if kb.base},
        "row_base_reason": "rtol: at the reference step cap every tolerance takes the same steps, so the caps are "
                           "lifted (tolerance alone sets the step); max_step_ns: at the reference tolerance the "
                           "cap above ~60 ns never binds, so the tolerance is relaxed and the stiffness cap lifted "
                           "(cap alone sets the step); stiffness_step: acts only in contact, tolerance relaxed, "
                           "max_step_ns at the scene's value",
        "atol_rule": f"atol_nm = {ATOL_PER_RTOL_NM:g} nm x rtol along the rtol knob",
        "operating_points": {p: v for p, v in points.items()},
        "error_definition": "|x - x_ref| / max(|x_ref|, floor); NaN if both NaN (output does not apply), inf if "
                            "only one is NaN or the integration failed",
        "error_floors": {o: ERROR_FLOORS[o] for o in HEADLINE},
        "error_floor_units": {o: SCALARS[o].units for o in HEADLINE},
        "tolerance": tol,
        "combined_tolerance": combined_tol,
        "choice_rule": "cheapest setting (summed wall_time over the points) whose every headline error is below "
                       f"the tolerance at every point; settings within {COST_TIE:.2f}x of that cost are ties, "
                       "resolved by keeping the scene's value if among them, else the most accurate; then all chosen "
                       "settings run together and, while that misses combined_tolerance, the one knob whose "
                       "one-level-tighter trial passes most cheaply (else errs least) is stepped back",
    }
