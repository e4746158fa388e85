"""Stage ``accuracy``: what each accuracy knob costs and what it buys.

``hdi accuracy CONFIG`` runs the scene at three operating points -- flying (protrusion 5 nm),
touchdown (7.6 nm: the first protrusion in contact of the paper scene with ``k = 0.445``; at
7.5 nm it still flies with 2.7 nm clearance, then adhesion snaps it into contact) and steady
sliding (11 nm) -- once with the tightest settings (the *reference*) and then with each accuracy
knob varied on its own, and writes ``accuracy.nc`` and ``figures/work_precision.png``.

Reference settings (:data:`REFERENCE`)
--------------------------------------
``rtol = 1e-10``, ``atol_nm = 1e-8``, ``max_step_ns = 25`` (the step cap binds: a fixed 25 ns
DP5 step), ``stiffness_step = 0.25``, ``min_dwell_ns = 1``, ``table_step_nm = 0.001`` with cubic
interpolation, quadrature 64 Gauss-Legendre nodes x 8 panels, DMW record at 16 MS/s. The tightest
entry of the ``rtol`` row (tolerance 1e-10 with the caps lifted: an independent step sequence)
bounds the reference's own time-discretisation error (~1e-7 to 1e-6 relative in the paper scene).

DMW sample rate. :func:`pipeline.physics.dmw.synthesize` draws the normals of every ``rfft`` bin
in bin order, and the record length (``dmw.duration_ms`` or the default 2.1 ms) does not depend on
the rate, so one seed at 2, 4, 8 or 16 MS/s gives the *same* band-limited trigonometric polynomial
sampled more or less densely (checked here: the subsampled 16 MS/s record equals the 4 MS/s one to
1e-15 nm; the attribute ``dmw_record_check`` records the check). The rate therefore only changes how
finely the dynamics' spline resolves the same signal. Should a rate give another signal (a rate
whose Nyquist frequency is the band's edge, a measured record, another record length), the record
at that rate is taken from the reference record by FFT resampling instead (said in
``dmw_record_method``).

Knobs (:data:`KNOBS`), settings from tightest to loosest
---------------------------------------------------------
Each knob is varied with every other knob at its reference value, except the step-size
controllers, which the reference would mask:

* ``rtol`` (with ``atol_nm = 100 nm x rtol``, the ratio of both the reference and the default
  pair): at the reference cap of 25 ns every tolerance from 1e-4 to 1e-10 takes the same 80001
  steps and gives identical results, so this row lifts the cap (``max_step_ns = 1e4``): the
  tolerance alone sets the step.
* ``max_step_ns``: at ``rtol = 1e-10`` the tolerance alone already takes 50-90 ns steps and every
  cap above that changes nothing, so this row relaxes the tolerance (``rtol = 1e-2``,
  ``atol_nm = 1``) and lifts the stiffness cap: the cap alone sets the step.
* ``stiffness_step`` (the integrator's cap ``h <= c / omega`` of the local interface spring): it acts
  only in contact, so something else must hold the flying step: this row relaxes the tolerance and
  keeps ``max_step_ns`` at the scene's value (500 ns by default).
* The ``rtol`` row also lifts the stiffness cap (``stiffness_step = 1e3``), which would otherwise
  set the step in contact at every tolerance.
* ``contact_grid_points`` (scenes with ``interface.model = "deterministic"`` only): the largest
  number of grid points per side of the measured surface the FFT boundary-element solver solves
  (the reference, 512, is every bundled scan at its own resolution); it changes the deterministic
  contact tables the dynamics runs on.

The integrator's step is the smallest of the controllers' steps, so defaults chosen for each alone
are at least as accurate together; the stage checks this by running all chosen defaults at once
(``combined_*`` variables). Knobs the scene schema does not have are skipped.

Errors
------
For headline output ``o`` (:data:`HEADLINE`) at a point, ``error = |x - x_ref| / max(|x_ref|, f_o)``
with the floor ``f_o`` of :data:`ERROR_FLOORS` (in the output's dataset units), which keeps the
error finite where the reference is (near) zero, e.g. the contact force of the flying point.
Both NaN (an output that does not apply: interference, friction coefficient and stresses while
flying): NaN, skipped. One NaN (contact in one run and not in the other) or a failed integration:
``inf``. ``max_error`` is the maximum over the outputs that apply. Rows whose settings equal the
reference (``is_reference``) are not copied from it: they share one fresh run (model build and
integration), so their zero error is a check that the simulation is deterministic.

Wall time
---------
``simulation_time``: median of ``repeat`` (default 5) runs of integration plus steady-window
statistics (:func:`pipeline.slider.run_model` and :func:`~pipeline.slider.summarize`), after
compilation. ``setup_time``: building what the knob changes -- the interface tables
(:func:`pipeline.stages.interface.build_tables`, timed once when a build takes more than 1 s) and
the model (``build_model``: spline coefficients) for the table knobs, the DMW record and the model
for the sample rate, the model for the interpolation order, nothing for the solver knobs.
``wall_time = setup_time + simulation_time``. Table setup is paid once per roughness in a sweep,
not per protrusion: read ``simulation_time`` for the per-scene cost.

Defaults
--------
For each knob, among the settings whose every headline error is below ``tolerance`` (1 %) at all
three points, the cheapest (smallest summed ``wall_time`` over the points); settings within 10 %
of that cost are timing noise and count as equally cheap, and among those the scene's current value
is kept if it is one of them, else the most accurate. Then all chosen defaults run together and must
pass a tenth of the tolerance (``combined_tolerance``, 0.1 %: headroom for interactions and for
scenes unlike these three points -- e.g. 4 quadrature nodes at 8 panels and 64 nodes at 1 panel
each err by < 1e-6, but 4 nodes x 1 panel by 100 %); while they miss it, every knob not at its
tightest setting is tried one level tighter and the trial that passes most cheaply (else errs least)
is kept. Chosen values and their errors: attributes
``chosen_defaults`` and ``chosen_defaults_errors``, variables ``chosen_setting`` and
``combined_*``.

The stage takes ``contact.k`` from the scene, else from ``calibration.nc``, else from
``contact.fallback_probability``. Shorten it with ``--set solver.duration_ms=... --set
solver.transient_ms=...`` (the reference uses the scene's duration, transient and output step).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from statistics import median
from typing import Any

import numpy as np
import xarray as xr

from .. import slider as sl
from ..runner import Inputs, Stage, build
from ..variables import ACCURACY as ACC
from ..variables import SCALARS
from ..physics.statistics import k_from_probability
from .interface import build_tables, roughness_statistics
from .simulate import NOT_READ, needs_interface, resolve_k

log = logging.getLogger(__name__)
NM = 1e-9

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
        return {self.key[1]: _cast(self.key[1], value)}


def _cast(key: str, value: float) -> float | int:
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

TABLE_KEYS = ("table_step_nm", "quadrature_nodes", "quadrature_panels", "contact_grid_points")


# ---------------------------------------------------------------------------------------------
# helpers

def _contact_k(scene: Any, out: Path, k: float | None) -> tuple[float | None, str]:
    """``k`` from the option, else as every later stage takes it (:func:`simulate.resolve_k`); without
    ``calibration.nc``, from ``contact.fallback_probability`` (the accuracy study needs some k)."""
    if not scene.has("contact"):
        return None, "no contact effect"
    if k is not None:
        return float(k), "option k"
    try:
        return resolve_k(scene, out)
    except ValueError:
        fb = scene["contact"]["fallback_probability"]
        if fb is None:
            raise
        return k_from_probability(fb), f"contact.fallback_probability = {fb} (two-sided; no calibration.nc)"


def relative_error(x: np.ndarray, ref: np.ndarray, floor: float) -> np.ndarray:
    """``|x - ref| / max(|ref|, floor)``; NaN where both are NaN, ``inf`` where only one is."""
    x = np.asarray(x, float)
    ref = np.asarray(ref, float)
    with np.errstate(invalid="ignore"):
        err = np.abs(x - ref) / np.maximum(np.abs(ref), floor)
    nx, nr = np.isnan(x), np.isnan(ref)
    err = np.where(nx & nr, np.nan, err)
    return np.where(nx ^ nr, np.inf, err)


def _timed(fn, repeat: int) -> tuple[Any, float]:
    """Result of ``fn()`` and the median wall time [s] of ``repeat`` calls."""
    times = []
    result = None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return result, median(times)


class _RunCache:
    """Builds and caches interface tables and DMW records, with their build times."""

    def __init__(self, scene: Any, out: Path, repeat: int):
        self.scene = scene
        self.out = out
        self.repeat = repeat
        self.stats = roughness_statistics(scene, out) if needs_interface(scene) else None
        self.tables: dict[tuple, tuple[xr.Dataset | None, float]] = {}
        self.records: dict[float, tuple[tuple[np.ndarray, float] | None, float]] = {}
        self.record_notes: dict[float, str] = {}
        self.reference_rate: float | None = None

    def table(self, sc: Any) -> tuple[xr.Dataset | None, float]:
        if self.stats is None:
            return None, 0.0
        key = tuple(sc["solver"][k] for k in TABLE_KEYS)
        if key not in self.tables:
            times = []
            ds = None
            while len(times) < max(1, self.repeat) and (not times or sum(times) < 1.0):
                t0 = time.perf_counter()
                ds = build_tables(sc, self.stats)
                times.append(time.perf_counter() - t0)
            self.tables[key] = (ds, median(times))
        return self.tables[key]

    def _synth(self, sc: Any) -> np.ndarray:
        from . import dmw as dmw_stage
        s = dmw_stage.settings(sc)
        if s["source"] == "synthetic":
            return dmw_stage.synthetic_record(s)
        import tempfile
        with tempfile.TemporaryDirectory() as tmp:
            _, w, _ = dmw_stage.load(dmw_stage.run(sc, Path(tmp), force=True))
        return w

    def record(self, sc: Any) -> tuple[tuple[np.ndarray, float] | None, float]:
        """``((displacement [nm], rate [Hz]), build time [s])`` at the scene's rate.

        The first call must be the reference rate; other rates are checked against the reference
        record (same continuous signal) and replaced by its FFT resampling when they differ.
        """
        if not sc.has("dmw"):
            return None, 0.0
        rate = float(sc["dmw"]["sample_rate_mhz"])
        if rate in self.records:
            return self.records[rate]
        w, dt = _timed(lambda: self._synth(sc), self.repeat)
        fs = rate * 1e6
        if self.reference_rate is None:
            self.reference_rate = rate
            self.record_notes[rate] = "reference record"
        else:
            (w_ref, fs_ref), _ = self.records[self.reference_rate]
            n = w.size
            from scipy.signal import resample
            same_length = abs(n / fs - w_ref.size / fs_ref) < 0.5 / fs
            resampled = resample(w_ref, int(round(w_ref.size * fs / fs_ref))) if same_length else None
            if resampled is not None and resampled.size == n:
                diff = float(np.max(np.abs(resampled - w)))
                scale = float(np.sqrt(np.mean(w_ref ** 2))) or 1.0
                if diff <= 1e-9 * scale:
                    self.record_notes[rate] = (f"synthesised at {rate:g} MS/s: equals the FFT resampling of the "
                                               f"reference record to {diff:.2g} nm")
                else:
                    w = resampled
                    self.record_notes[rate] = (f"FFT resampling of the reference record (the record synthesised "
                                               f"at {rate:g} MS/s differs from it by up to {diff:.3g} nm)")
            else:
                self.record_notes[rate] = (f"synthesised at {rate:g} MS/s (record length differs from the "
                                           "reference: not comparable by resampling)")
        self.records[rate] = ((w, fs), dt)
        return self.records[rate]


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
        """Setup time [s] that counts for a knob of ``kind`` (module docstring, "Wall time")."""
        b = self.build
        return {"solver": 0.0, "model": b["model"], "table": b["table"] + b["model"],
                "dmw": b["record"] + b["model"], "all": b["table"] + b["record"] + b["model"]}[kind]


def _solver_config(scene: Any, values: dict[str, float]) -> Any:
    """The scene with ``[solver]`` values and ``sample_rate_mhz`` applied."""
    solver = {k: _cast(k, v) for k, v in values.items() if k != "sample_rate_mhz"}
    sections: dict[str, dict] = {"solver": solver}
    if "sample_rate_mhz" in values:
        sections["dmw"] = {"sample_rate_mhz": float(values["sample_rate_mhz"])}
    return scene.replace(**sections)


def _evaluate(scene: Any, values: dict[str, float], cache: _RunCache, k: float | None,
              points: dict[str, float], repeat: int) -> Result:
    """Run one configuration at every point."""
    sc = _solver_config(scene, values)
    tables, t_tab = cache.table(sc)
    record, t_rec = cache.record(sc)
    model, t_model = _timed(lambda: sl.build_model(sc, tables, record, k), 1)
    build = {"table": t_tab, "record": t_rec, "model": t_model}
    n_p = len(points)
    vals = np.full((n_p, len(HEADLINE)), np.nan)
    sim = np.full(n_p, np.nan)
    info = np.zeros((n_p, 3), dtype=np.int64)
    failed = np.zeros(n_p, dtype=bool)
    msgs = []
    for i, prot in enumerate(points.values()):
        def once() -> tuple[sl.Run, dict]:
            r = sl.run_model(model, prot * NM)
            return r, sl.summarize(r)
        t0 = time.perf_counter()
        try:
            (r, s), sim[i] = _timed(once, repeat)
        except sl.IntegrationError as exc:
            sim[i] = time.perf_counter() - t0
            failed[i] = True
            msgs.append(str(exc))
            continue
        info[i] = r.info[1:4]
        for j, name in enumerate(HEADLINE):
            if name in s:
                vals[i, j] = s[name] / SCALARS[name].si_unit
    return Result(vals, sim, build, info, failed, msgs)


def _errors(res: Result, ref: Result) -> np.ndarray:
    """(point, output) relative errors of ``res`` against ``ref`` (inf for failed points)."""
    floors = np.array([ERROR_FLOORS[o] for o in HEADLINE])
    err = relative_error(res.values, ref.values, floors[None, :])
    err[res.failed] = np.where(np.isnan(ref.values[res.failed]), np.nan, np.inf)
    return err


def _max_error(err: np.ndarray) -> np.ndarray:
    """Max over the last axis ignoring NaN (NaN when nothing applies)."""
    with np.errstate(invalid="ignore"):
        filled = np.where(np.isnan(err), -np.inf, err)
        m = filled.max(axis=-1)
    return np.where(np.isneginf(m), np.nan, m)


def _passes(err: np.ndarray, tol: float) -> bool:
    """Every applicable error (any shape) below ``tol``."""
    e = err[~np.isnan(err)]
    return bool(np.all(e < tol))


# ---------------------------------------------------------------------------------------------
# the stage

def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``accuracy.nc`` dataset; draws ``figures/work_precision.png`` under ``inputs.staging``.

    Options (``inputs.options``; those that change the result are part of the stage's inputs key)
    -------------------------------------------------------------------------------------------------
    points : ``{label: protrusion [nm]}`` (default :data:`POINTS`)
    reference : changes to :data:`REFERENCE`
    knobs : ``{knob name: [settings, tightest first]}`` replacing settings (knobs not named keep
        theirs); ``only`` : names of the knobs to run (default all that apply to the scene's effects)
    repeat : timed repeats per run (default 5); tolerance : error tolerance for the defaults (0.01)
    k : contact criterion (default: scene, calibration, fallback probability)
    """
    out, options = inputs.out, inputs.options
    points = dict(options.get("points") or POINTS)
    present = set(scene["solver"]) | {"sample_rate_mhz"}
    reference = {k_: v for k_, v in {**REFERENCE, **(options.get("reference") or {})}.items() if k_ in present}
    repeat = int(options.get("repeat") or 5)
    tol = float(options.get("tolerance") or TOLERANCE)
    k, k_source = _contact_k(scene, out, options.get("k"))
    eff = scene.effects
    custom = options.get("knobs") or {}
    only = options.get("only")
    knobs = []
    for kb in KNOBS:
        if only is not None and kb.name not in only:
            continue
        if kb.kind == "table" and not eff & {"contact", "adhesion"}:
            continue
        if kb.kind == "dmw" and "dmw" not in eff:
            continue
        if kb.name == "min_dwell_ns" and "contact" not in eff:
            continue
        if kb.name == "contact_grid_points" and scene["interface"]["model"] != "deterministic":
            continue  # only the deterministic interface solves a height map
        if kb.name == "interpolation_order" and not eff & {"contact", "adhesion", "dmw"}:
            continue
        if kb.key[1] not in present:
            continue  # a knob this version of the scene schema does not have
        base = {k_: (scene["solver"][k_] if v == "scene" else v) for k_, v in kb.base.items() if k_ in present}
        settings = tuple(custom[kb.name]) if kb.name in custom else kb.settings
        knobs.append(Knob(kb.name, kb.key, settings, kb.units, kb.long_name, kb.kind, base))
    if not knobs:
        raise ValueError("no accuracy knob applies to the scene's effects")
    t_start = time.perf_counter()
    cache = _RunCache(scene, out, repeat)  # tables and records of the runs, built once per setting

    # the reference (its first run also compiles the kernels: run it once untimed)
    log.info("accuracy: reference %s", reference)
    _evaluate(scene, reference, cache, k, points, 1)
    ref = _evaluate(scene, reference, cache, k, points, repeat)
    if ref.failed.any():
        raise RuntimeError(f"the reference run failed: {ref.messages}")

    n_p, n_k, n_o = len(points), len(knobs), len(HEADLINE)
    n_l = max(len(kb.settings) for kb in knobs)
    shape = (n_p, n_k, n_l)
    error = np.full(shape + (n_o,), np.nan)
    values = np.full(shape + (n_o,), np.nan)
    sim_time = np.full(shape, np.nan)
    setup_time = np.full((n_k, n_l), np.nan)
    steps = np.full(shape + (3,), -1, dtype=np.int64)
    failed = np.zeros(shape, dtype=np.int8)
    is_ref = np.zeros((n_k, n_l), dtype=np.int8)
    setting = np.full((n_k, n_l), np.nan)
    results: dict[tuple[int, int], Result] = {}
    rerun: Result | None = None  # the rows equal to the reference: one fresh run, not a copy of ``ref``
    for ik, kb in enumerate(knobs):
        for il, value in enumerate(kb.settings):
            cfg = {**reference, **kb.base, **kb.solver_values(value)}
            setting[ik, il] = value
            same = all(cfg[key] == reference[key] for key in reference)
            if same:
                # a new model build and integration, so their zero error checks determinism
                rerun = rerun or _evaluate(scene, cfg, cache, k, points, repeat)
                res = rerun
            else:
                res = _evaluate(scene, cfg, cache, k, points, repeat)
            is_ref[ik, il] = same
            results[ik, il] = res
            e = _errors(res, ref)
            error[:, ik, il] = e
            values[:, ik, il] = res.values
            sim_time[:, ik, il] = res.sim_time
            setup_time[ik, il] = res.setup_time(kb.kind)
            steps[:, ik, il] = res.info
            failed[:, ik, il] = res.failed
            me = _max_error(e)
            log.info(f"  {kb.name:>20} = {value:<8g} max error " + "  ".join(
                f"{p}: {m:9.3g}" for p, m in zip(points, me))
                + f"   time {np.nansum(res.sim_time) + res.setup_time(kb.kind):7.3f} s"
                + ("  FAILED: " + "; ".join(res.messages) if res.failed.any() else ""))
    wall = sim_time + setup_time[None, :, :]
    max_err = _max_error(error)
    passes = np.zeros((n_k, n_l), dtype=np.int8)
    for ik, kb in enumerate(knobs):
        for il in range(len(kb.settings)):
            passes[ik, il] = _passes(error[:, ik, il], tol)

    # choose defaults, then check them together
    chosen_level = {}
    for ik, kb in enumerate(knobs):
        chosen_level[kb.name] = _choose(kb, scene, passes[ik], wall[:, ik, :].sum(axis=0), max_err[:, ik, :])
    combined_tol = float(options.get("combined_tolerance") or COMBINED_MARGIN * tol)
    chosen_level, combos, adjustments = _combine(scene, knobs, reference, chosen_level, cache, k, points, repeat,
                                                 ref, combined_tol)
    chosen_cfg = _configuration(reference, knobs, chosen_level)
    scene_cfg = {key: (scene["dmw"]["sample_rate_mhz"] if key == "sample_rate_mhz" else scene["solver"][key])
                 for key in reference}
    combos["scene"] = _evaluate(scene, scene_cfg, cache, k, points, repeat)
    combo_cost = {c: float(np.nansum(r.sim_time) + r.setup_time("all")) for c, r in combos.items()}
    configs = {"chosen": chosen_cfg, "scene": scene_cfg}

    ds = _dataset(points, knobs, setting, error, values, sim_time, setup_time, wall, max_err, steps, failed,
                  is_ref, passes, chosen_level, ref, combos, tol)
    chosen = {kb.name: (kb.settings[chosen_level[kb.name]] if chosen_level[kb.name] is not None else None)
              for kb in knobs}
    chosen_err = {}
    for ik, kb in enumerate(knobs):
        lvl = chosen_level[kb.name]
        chosen_err[kb.name] = ({p: float(max_err[ip, ik, lvl]) for ip, p in enumerate(points)}
                               if lvl is not None else None)
    comb_err = {c: {p: float(_max_error(_errors(r, ref))[ip]) for ip, p in enumerate(points)}
                for c, r in combos.items()}
    rec_notes = {f"{r:g} MS/s": n for r, n in cache.record_notes.items()}
    attrs = {
        "reference_settings": {k_: _cast(k_, v) for k_, v in reference.items()},
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
        "chosen_defaults": {k_: (_cast(k_, v) if v is not None else None) for k_, v in chosen.items()},
        "chosen_defaults_errors": chosen_err,
        "chosen_configuration": {k_: _cast(k_, v) for k_, v in chosen_cfg.items()},
        "scene_configuration": {k_: _cast(k_, v) for k_, v in scene_cfg.items()},
        "combined_max_errors": comb_err,
        "combined_total_wall_time_s": combo_cost,
        "chosen_adjustments": adjustments or "none",
        "timing": f"simulation: median of {repeat} runs of run_model + summarize after compilation; table builds "
                  "longer than 1 s timed once; sequential, one process",
        "cpus": os.cpu_count() or 0,
        "k": float(k) if k is not None else "none",
        "k_source": k_source,
        "dmw_record_method": rec_notes or "no dmw effect",
        "dmw_record_check": "; ".join(f"{r}: {n}" for r, n in rec_notes.items()) or "none",
        "failures": "; ".join(f"{kb.name}={kb.settings[il]:g}: {m}" for (ik, il), r in results.items()
                              for kb in [knobs[ik]] for m in r.messages) or "none",
        "stage_wall_time_s": time.perf_counter() - t_start,
    }
    ds.attrs.update(attrs)
    fig = work_precision_figure(ds, inputs.staging / "figures" / "work_precision.png")
    _log_summary(ds, chosen, chosen_err, comb_err, configs, combo_cost, fig)
    return ds


def _upstream(scene: Any) -> tuple[str, ...]:
    """Roughness scans (statistics) and, when the scene fixes no k, the calibration (:func:`_contact_k`)."""
    up = ["roughness"] if scene["roughness"]["afm"] else []
    if scene.has("contact") and scene["contact"]["k"] is None:
        up.append("calibrate")
    return tuple(up)


STAGE = Stage(
    "accuracy", compute, outputs=("accuracy.nc", "figures/work_precision.png"),
    reads=("*",), excludes=NOT_READ,
    upstream=_upstream,
    options=("points", "reference", "knobs", "only", "repeat", "tolerance", "combined_tolerance", "k"),
    order=55, doc="error and wall time of each accuracy knob, accuracy.nc and figures/work_precision.png")


def run(scene: Any, out: Path, **options: Any) -> Path:
    """``accuracy.nc`` (and the work-precision figure) in ``out``, recomputed when its inputs changed."""
    return build("accuracy", scene, out, **options)["accuracy"][0]


def _configuration(reference: dict[str, float], knobs: list[Knob], levels: dict[str, int | None]) -> dict:
    """The reference with every knob at its level (``None``: the reference value)."""
    cfg = dict(reference)
    for kb in knobs:
        if levels.get(kb.name) is not None:
            cfg.update(kb.solver_values(kb.settings[levels[kb.name]]))
    return cfg


def _combine(scene, knobs, reference, levels, cache, k, points, repeat, ref: Result, tol: float):
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
    res = _evaluate(scene, _configuration(reference, knobs, levels), cache, k, points, repeat)
    for _ in range(sum(len(kb.settings) for kb in knobs)):
        e = _errors(res, ref)
        if _passes(e, tol):
            break
        trials = []
        for kb in knobs:
            lvl = levels[kb.name]
            if not lvl:
                continue
            lv = {**levels, kb.name: lvl - 1}
            r = _evaluate(scene, _configuration(reference, knobs, lv), cache, k, points, 1)
            er = _errors(r, ref)
            worst = float(np.nanmax(np.where(np.isnan(er), -1.0, er)))
            cost = float(np.nansum(r.sim_time) + r.setup_time("all"))
            ok = _passes(er, tol)
            trials.append((not ok, cost if ok else worst, kb.name, lv, worst))
        if not trials:
            break
        trials.sort(key=lambda t: (t[0], t[1]))
        _, _, name, levels, worst = trials[0]
        adjustments.append(f"the chosen defaults together missed the combined tolerance {tol:g} (max error "
                           f"{np.nanmax(e):.3g}); {name} stepped back to {by_name[name].settings[levels[name]]:g} "
                           f"(max error then {worst:.3g})")
        log.warning(adjustments[-1])
        res = _evaluate(scene, _configuration(reference, knobs, levels), cache, k, points, repeat)
    return levels, {"chosen": res}, adjustments


def _choose(kb: Knob, scene: Any, passes: np.ndarray, cost: np.ndarray, max_err: np.ndarray) -> int | None:
    """Level of the chosen setting of one knob (None when none passes)."""
    ok = [il for il in range(len(kb.settings)) if passes[il] and np.isfinite(cost[il])]
    if not ok:
        return None
    cheapest = min(cost[il] for il in ok)
    tied = [il for il in ok if cost[il] <= COST_TIE * cheapest]
    current = scene[kb.key[0]][kb.key[1]]
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
                                     long_name=f"every headline error below {tol:g} at every point (1) or not (0)"),
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
    comb_err = np.stack([_errors(combos[c], ref) for c in conf])
    CP = ("configuration",) + P
    data["combined_error"] = ACC["combined_error"].data(comb_err, CP + O)
    data["combined_max_error"] = ACC["combined_max_error"].data(_max_error(comb_err), CP)
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


def work_precision_figure(ds: xr.Dataset, path: Path) -> Path:
    """Max error versus wall time, log-log, one line per knob, one panel per operating point."""
    import matplotlib
    matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
    import matplotlib.pyplot as plt

    lo, hi = 1e-10, 1e3
    points = list(ds["point"].values)
    fig, axes = plt.subplots(1, len(points), figsize=(5.2 * len(points), 4.6), sharey=True, squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    tol = float(ds.attrs.get("tolerance", TOLERANCE)) if "tolerance" in ds.attrs else TOLERANCE
    for ip, (ax, p) in enumerate(zip(axes[0], points)):
        for ik, kb in enumerate(ds["knob"].values):
            sel = ds.isel(point=ip, knob=ik)
            ok = np.isfinite(sel["setting"].values)
            x = sel["wall_time"].values[ok]
            y = np.clip(np.nan_to_num(sel["max_error"].values[ok], nan=lo, posinf=hi), lo, hi)
            c = colors[ik % len(colors)]
            bad = sel["failed"].values[ok].astype(bool) | np.isinf(sel["max_error"].values[ok])
            ax.plot(x[~bad], y[~bad], "-o", color=c, ms=4, lw=1.2, label=str(kb))
            if bad.any():
                ax.plot(x[bad], np.full(bad.sum(), hi), "x", color=c, ms=9, mew=2)
            lvl = int(ds["chosen_level"].values[ik])
            if lvl >= 0:
                ax.plot([sel["wall_time"].values[lvl]], [np.clip(sel["max_error"].values[lvl], lo, hi)], "*",
                        color=c, ms=13, mec="k", mew=0.6)
        ax.axhline(tol, color="k", ls="--", lw=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(lo / 2, hi * 2)
        ax.set_xlabel("wall time [s] (setup + simulation)")
        ax.set_title(f"{p} ({float(ds['protrusion'].values[ip]):g} nm)")
        ax.grid(True, which="major", alpha=0.3)
    axes[0][0].set_ylabel("max relative error of headline outputs [1]")
    axes[0][-1].legend(fontsize=8, loc="upper right")
    fig.suptitle("Work-precision per accuracy knob, others at reference (step-size rows: the other step "
                 "controllers lifted or relaxed, see attribute row_base)\n"
                 f"dashed: {tol:g} tolerance; star: chosen default; x: failed or regime changed; "
                 f"errors < {lo:g} drawn at {lo:g}", fontsize=9)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, path)
    return path


def _log_summary(ds, chosen, chosen_err, comb_err, configs, combo_cost, fig) -> None:
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
    log.info("accuracy: figure %s", fig.name)
