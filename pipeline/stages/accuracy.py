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

DMW sample rate. :func:`pipeline.physics.microwaviness.synthesize` draws the normals of every ``rfft`` bin
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
statistics (:func:`pipeline.model.simulation.simulate` of the one protrusion: the run, its summary and
its dataset), after
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

The study itself (knobs, errors, choice of defaults, the dataset) is
:func:`pipeline.analyses.knob_study.study`, the figure :func:`pipeline.analyses.plots.fig_work_precision`; this
module assembles and runs the model for each configuration (:func:`_evaluate`, :class:`_RunCache`).

The stage takes ``contact.k`` from the scene, else from ``calibration.nc``, else from
``contact.fallback_probability``. Shorten it with ``--set solver.duration_ms=... --set
solver.transient_ms=...`` (the reference uses the scene's duration, transient and output step).
"""

from __future__ import annotations

import logging
import tempfile
import time
from pathlib import Path
from statistics import median
from typing import Any

import numpy as np
import xarray as xr

from ..analyses import plots
from ..model import assembly, running
from ..analyses import knob_study as knob_study
from ..analyses.knob_study import HEADLINE, POINTS, REFERENCE, TABLE_KEYS, TOLERANCE, Result, cast
from ..model import dmw_record, scene_inputs
from ..model.inputs import for_stage
from ..model.interface_tables import build_tables, roughness_statistics
from ..model.simulation import COUNTERS, simulate
from ..progress import Progress
from ..runner import Inputs, Stage, ensure
from ..units import MHZ

log = logging.getLogger(__name__)


# ---------------------------------------------------------------------------------------------
# scene -> model: tables, records, model assembly and the runs (what the study's ``evaluate`` does)

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
        self.stats = (roughness_statistics(scene, out / "roughness.nc" if scene["roughness"]["afm"] else None)
                      if scene_inputs.needs_interface(scene) else None)
        self.tables: dict[tuple, tuple[xr.Dataset | None, float]] = {}
        self.records: dict[float, tuple[tuple[np.ndarray, float] | None, float]] = {}
        self.record_notes: dict[float, str] = {}
        self.reference_rate: float | None = None
        self.bulge: xr.Dataset | None = None  # the bulge table (bulge.nc) with the tabulated bulge bearing

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
        s = dmw_record.settings(sc)
        if s["source"] == "synthetic":
            return dmw_record.synthetic_record(s)
        with tempfile.TemporaryDirectory() as tmp:
            _, w, _ = dmw_record.load(ensure("dmw", sc, Path(tmp), force=True))
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
        fs = rate * MHZ
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

def _solver_config(scene: Any, values: dict[str, float]) -> Any:
    """The scene with ``[solver]`` values and ``sample_rate_mhz`` applied."""
    solver = {k: cast(k, v) for k, v in values.items() if k != "sample_rate_mhz"}
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
    model, t_model = _timed(lambda: assembly.build_model(sc, tables, record, k, bulge=cache.bulge), 1)
    build = {"table": t_tab, "record": t_rec, "model": t_model}
    n_p = len(points)
    vals = np.full((n_p, len(HEADLINE)), np.nan)
    sim = np.full(n_p, np.nan)
    info = np.zeros((n_p, 3), dtype=np.int64)
    failed = np.zeros(n_p, dtype=bool)
    msgs = []
    for i, prot in enumerate(points.values()):
        t0 = time.perf_counter()
        try:
            ds, sim[i] = _timed(lambda: simulate(model, [prot], counters=True), repeat)
        except running.IntegrationError as exc:
            sim[i] = time.perf_counter() - t0
            failed[i] = True
            msgs.append(str(exc))
            continue
        info[i] = [int(ds[name][0]) for name in COUNTERS]
        for j, name in enumerate(HEADLINE):
            if name in ds:
                vals[i, j] = ds[name].values[0]
    return Result(vals, sim, build, info, failed, msgs)


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
    # the scene's value of every accuracy setting its schema has: the [solver] keys and the DMW rate
    current = {**{key: scene["solver"][key] for key in scene["solver"]},
               "sample_rate_mhz": scene["dmw"]["sample_rate_mhz"]}
    reference = {k_: v for k_, v in {**REFERENCE, **(options.get("reference") or {})}.items() if k_ in current}
    repeat = int(options.get("repeat") or 5)
    tol = float(options.get("tolerance") or TOLERANCE)
    # k: the option, else by the one rule with the calibration (upstream when the scene fixes no k)
    sim = for_stage(scene, inputs, k=options.get("k"))
    k, k_source = sim.k, sim.k_source
    knobs = knob_study.select_knobs(scene.effects, current, options.get("knobs"), options.get("only"),
                                    scene["interface"]["model"])
    t_start = time.perf_counter()
    cache = _RunCache(scene, out, repeat)  # tables and records of the runs, built once per setting
    cache.bulge = sim.bulge_table()  # (the bulge table is no accuracy knob: the scene's, as is)

    # the runs counted: the reference twice, each knob setting once, the chosen defaults together and the
    # scene's settings (each step back of the combination adds runs; settings equal to the reference share one)
    with Progress(2 + sum(len(kb.settings) for kb in knobs) + 2, unit="configuration") as progress:

        def evaluate(values: dict[str, float], n: int) -> Result:
            res = _evaluate(scene, values, cache, k, points, n)
            progress.update()
            return res

        ds, summary = knob_study.study(evaluate, knobs, reference, points, current, repeat=repeat, tol=tol,
                                       combined_tol=options.get("combined_tolerance"), k=k, k_source=k_source,
                                       record_notes=cache.record_notes)
    ds.attrs["stage_wall_time_s"] = time.perf_counter() - t_start
    fig = plots.fig_work_precision(ds, inputs.staging / "figures" / "work_precision.png")
    knob_study.log_summary(ds, summary, fig.name)
    return ds


def _upstream(scene: Any) -> tuple[str, ...]:
    """Roughness scans (statistics), the bulge table with the tabulated bulge bearing, and, when the scene
    fixes no k, the calibration (k by :func:`pipeline.model.inputs.for_stage`)."""
    up = ["roughness"] if scene["roughness"]["afm"] else []
    up.extend(scene_inputs.table_stages(scene))
    if scene_inputs.needs_calibration(scene):
        up.append("calibrate")
    return tuple(up)


STAGE = Stage(
    "accuracy", compute, simulates=True, outputs=("accuracy.nc", "figures/work_precision.png"),
    # (what its simulations read, with the deepest protrusion of the tables it makes at each knob)
    reads=(*scene_inputs.STUDY_FIELDS, "sweep.protrusion_nm"),
    upstream=_upstream,
    options=("points", "reference", "knobs", "only", "repeat", "tolerance", "combined_tolerance", "k"),
    order=55, doc="error and wall time of each accuracy knob, accuracy.nc and figures/work_precision.png")
