"""Calibration of the contact-criterion constant k against the measured touchdown (the calibrate stage's analysis).

The paper's procedure (docs/model.md, section "Slider dynamics"): contact (``d < k sigma`` at any time of the steady
window) must happen at the measured touchdown protrusion (9.8 nm) and not at the previous
actuation step (9.6 nm). For a protrusion ``delta`` let ``k*(delta)`` be the smallest k that gives
contact (contact for every ``k > k*``); the admissible set is the interval
``k*(onset) < k <= k*(previous)``. The chosen k is the middle of that interval: it keeps the largest
margin to both conditions (the width is the uncertainty the 0.2 nm actuation step leaves); with
``touchdown.k_choice = "paper"``, the paper's own k when it is admissible (:func:`choose_k`). When the
interval is empty within ``touchdown.k_range`` (default [-3, 3], contact probabilities 0.1 % to
99.9 %), no k is written (``k_calibrated = NaN``) and the outcome says why.

The touchdown is the scene's (``touchdown.onset_nm``, ``touchdown.previous_nm``); at their defaults, the
paper's measurement. Which one k is fitted to is logged and written (``touchdown_fitted``), with a warning
(``touchdown_warning``) when it is the paper's while the disk, the roughness or the slider differ from the
paper's (:func:`touchdown_provenance`, :data:`OWN_DRIVE_KEYS`). A chosen k below the physical bound
:data:`pipeline.physics.asperity_statistics.K_PHYSICAL_MIN` (0: one-sided contact probability above 0.5) is
refused before any dataset is written (:func:`check_physical`, :class:`CalibrationError`), in one line naming
the touchdown keys to set or ``contact.k`` to fix.

``touchdown.method`` chooses how ``k*`` is found:

* ``"exact"`` (default): before its first contact the trajectory does not depend on k (the contact
  force is off while ``d >= k sigma``), so one run with the contact law switched off gives every
  ``k*`` at once: ``k* = min(d)/sigma`` over the steady window, with the integrator's exact minimum
  (:attr:`pipeline.model.running.Run.d_extremes`, not the output samples). Two cases need more care:
  (a) when ``d`` over the transient dips below its steady-window minimum, a k in
  ``(min_all/sigma, min_steady/sigma]`` first touches in the transient and the trajectory after
  that depends on k: that interval (where it meets ``k_range``) is resolved by bisection with real
  runs, and only there; (b) a flying run whose separation collapses (adhesive snap-in: ``d`` below
  the start of the interface tables, or the integration fails) is contact for every k
  (``k* = -inf``). One flying run (plus one over the transient alone) per protrusion of the
  ``[sweep]`` grid, fanned out with :func:`pipeline.fanout.run_tasks`, gives the whole curve
  ``k*(protrusion)``.
* ``"bisection"``: bisection on k with full runs (to ``touchdown.k_tolerance``) at each protrusion
  (the method before the exact one; kept as the reference it is tested against).

The contact probabilities of a k are ``P(|z| > k sigma) = 2 Q(|k|)`` (two-sided, the paper's
convention: docs/model.md, section "Contact criterion") and ``P(z > k sigma) = Q(k)`` (one-sided) for Gaussian heights of rms
``sigma`` (the sigma of the criterion); the paper's calibrated k corresponds to 32.8 % two-sided,
k = 0.978.

``calibration.nc`` also holds the touchdown-versus-k curve: for each of ``touchdown.curve_points``
values of k in the range, the first protrusion of the ``[sweep]`` grid that touches, NaN when none
does (exact: the first grid protrusion with ``k*(protrusion) < k``, no monotonicity assumed;
bisection: bisection over the grid, which assumes touching is monotone in protrusion); with the
exact method also ``k_threshold(protrusion)`` [1] and the flying run's ``min_separation(protrusion)`` [nm].
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import xarray as xr

from ..config.grid import label, protrusion_grid
from ..config.schema import SCHEMA
from ..fanout import run_tasks, split
from ..model import assembly, copies, outcomes, running
from ..model.inputs import SimulationInputs
from ..physics.asperity_statistics import K_PHYSICAL_MIN, contact_probabilities, k_from_probability, unphysical_k
from ..units import NM
from ..variables import CALIBRATION

log = logging.getLogger(__name__)
METHODS = ("exact", "bisection")


def touches(model: assembly.Model, delta_nm: float, k: float) -> bool:
    """Whether the scene at protrusion ``delta_nm`` [nm] with criterion ``k`` is in contact in the window.

    ``model``: the scene's model with any criterion (a copy with ``k`` is run: :func:`pipeline.model.copies.with_criterion`;
    from the contact-off model, whose static-start fold bounds every k's, starts past it need no fold search).

    In contact at an output sample of the steady window, or ``d < k sigma`` at the exact minimum of
    the window (a contact shorter than the output step falls between samples).
    """
    return outcomes.touched(running.run_model(copies.with_criterion(model, k), delta_nm * NM))


def _bisection_end(lo: float, hi: float, tol: float, touching: bool) -> float:
    """The last k [1] the bisection of :func:`k_threshold` on ``(lo, hi)`` probes when every probe answers
    ``touching``: the probe nearest ``hi`` (none touch) or ``lo`` (all touch)."""
    mid = lo if not touching else hi
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if touching:
            hi = mid
        else:
            lo = mid
    return mid


def k_threshold(model: assembly.Model, delta_nm: float, k_range: tuple[float, float], tol: float,
                memo: dict[float, bool] | None = None) -> tuple[float, str, int]:
    """Smallest k [1] giving contact at ``delta_nm``, by bisection within ``k_range``.

    Returns ``(k*, status, simulations)`` with status ``"found"``, ``"below range"`` (contact even at
    the lowest k: ``k*`` is below the range, returned as its lower end) or ``"above range"`` (no contact
    even at the highest k: returned as the upper end).

    Where k* lies within one tolerance of an end of the range (past the touchdown it mostly does: the
    window's minimum, or just above it), the last probe of the bisection settles it alone, and it is
    run first: when the probe nearest the upper end does not touch, k* is the upper end; when the
    probe nearest the lower end touches, it is k*. The bisection runs only when neither settles it.
    Where touching is monotone in k (what the bisection assumes) the answer is the bisection's. Where
    it is not, the answer is the threshold nearest the upper end, the one the definition asks for
    (contact for every k above k*), where the bisection returned whichever threshold its probes met:
    on the Reynolds scene (``configs/paper-2009-reynolds.toml``) at 13.2 and 14.8 nm a k 0.009 and 0.005
    below the window's minimum touches (a transient contact moves the window) while the k just below
    the minimum does not; k* is now the minimum there. ``memo``: answers already known,
    ``{k: touches}`` (updated; the simulations returned count the runs not found in it).
    """
    memo = {} if memo is None else memo
    n = 0

    def test(k: float) -> bool:
        nonlocal n
        if k not in memo:
            n += 1
            memo[k] = touches(model, delta_nm, k)
        return memo[k]

    lo, hi = k_range
    if test(lo):
        return lo, "below range", n
    if not test(hi):
        return hi, "above range", n
    if hi - lo > tol:
        if not test(_bisection_end(lo, hi, tol, False)):
            return hi, "found", n
        end = _bisection_end(lo, hi, tol, True)
        if test(end):
            return end, "found", n
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if test(mid):
            hi = mid
        else:
            lo = mid
    return hi, "found", n


def touchdown_protrusion(model: assembly.Model, k: float, grid_nm: np.ndarray) -> float:
    """First protrusion of ``grid_nm`` [nm] that touches with criterion ``k`` (NaN if none), by bisection."""
    if not touches(model, grid_nm[-1], k):
        return np.nan
    if touches(model, grid_nm[0], k):
        return float(grid_nm[0])
    lo, hi = 0, len(grid_nm) - 1  # lo never touches, hi touches
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if touches(model, grid_nm[mid], k):
            hi = mid
        else:
            lo = mid
    return float(grid_nm[hi])


#: The contact law off, within the kernel the sweep runs: a criterion ``d < k sigma`` no separation meets
#: (k sigma ~ -1e290 m). The run is bit-identical to one without the contact tables (contact never on:
#: no contact force, friction or contact step cap is evaluated; checked on the paper scene from 0 to
#: 15 nm), ~30 % slower (the switch search evaluates d), and needs no numba specialisation of its own:
#: a fresh `make run` compiled two kernels, 15-40 s each on the 2-core machine, now one.
CONTACT_OFF_K = -1e300


def flying_minimum(model: assembly.Model, delta_nm: float) -> tuple[float, float, str]:
    """Minimum separation [m] of the run with the contact law off: ``(steady window, whole run, note)``.

    ``model``: the scene's model, or its copy with the contact law off already (``k = CONTACT_OFF_K``:
    used as it is, so that the runs of a batch share one static-start fold search).

    The steady-window minimum is the integrator's exact one; the whole-run minimum adds a run over
    the transient alone (same trajectory: the integration starts from the same state; its window is
    the whole of it, ``t = 0`` included). A collapse (the integration fails, or ``d`` falls below the
    start of the interface tables: adhesive snap-in) returns ``(-inf, -inf, reason)``.
    """
    off = model if model.k == CONTACT_OFF_K else replace(model, k=CONTACT_OFF_K)
    try:
        run = running.run_model(off, delta_nm * NM)
        lo_all = run.d_extremes[0]  # t = 0 included when there is no transient
        if model.transient > 0:
            early = running.run_model(copies.with_solver(off, duration=off.transient, transient=0.0), delta_nm * NM)
            lo_all = min(lo_all, early.d_extremes[0])
    except running.IntegrationError as exc:
        return -math.inf, -math.inf, f"flying run failed ({exc})"
    lo = run.d_extremes[0]
    x0 = model.p.tab_x0
    if lo_all < x0:
        return -math.inf, -math.inf, (f"separation {lo_all / NM:.3g} nm below the interface tables "
                                      f"({x0 / NM:.3g} nm): adhesive snap-in")
    return lo, lo_all, ""


def k_star(model: assembly.Model, delta_nm: float, lo_steady: float, lo_all: float,
           k_range: tuple[float, float], tol: float) -> tuple[float, int]:
    """Smallest k [1] giving contact at ``delta_nm`` from the flying run's minima [m] (module docstring).

    Returns ``(k*, real simulations run)``; ``k* = min_steady/sigma`` unless the transient dips lower
    and the interval it leaves open meets ``k_range``, which is then resolved by bisection.
    """
    sigma = model.sigma
    if not np.isfinite(lo_steady):
        return -math.inf, 0
    ks_steady, ks_all = lo_steady / sigma, lo_all / sigma
    lo, hi = max(ks_all, k_range[0]), min(ks_steady, k_range[1])
    if ks_all >= ks_steady or lo >= hi:
        return ks_steady, 0
    memo: dict[float, bool] = {}
    k, status, n = k_threshold(model, delta_nm, (lo, hi), tol, memo)
    if status == "below range":  # touches even at the lower end: k* below it (only possible at k_range[0])
        return lo - tol, n
    if status == "above range" and hi < k_range[1]:  # the transient contact kept the window clear
        k, status, m = k_threshold(model, delta_nm, (hi, k_range[1]), tol, memo)
        n += m
        if status == "above range":
            return math.inf, n
    return k, n


def threshold_batch(scene: Any, inputs: SimulationInputs, protrusions: tuple[float, ...],
                    k_range: tuple[float, float], tol: float) -> list[tuple[float, float, float, str, int]]:
    """``(protrusion [nm], k* [1], steady minimum of d [nm], note, simulations)`` for each protrusion (a task;
    its inputs travel as :class:`pipeline.model.inputs.SimulationInputs`, by file and key, not in the task)."""
    model = inputs.model(scene, k=0.0)
    off = replace(model, k=CONTACT_OFF_K)  # (one model for the batch's flying runs: one fold search)
    rows = []
    for delta in protrusions:
        lo, lo_all, note = flying_minimum(off, delta)
        # (the bisection's models are copies of `off`, whose fold bounds theirs: copies.with_criterion)
        k, n = k_star(off, delta, lo, lo_all, k_range, tol)
        rows.append((delta, k, lo / NM, note, n))
    return rows


def thresholds(scene: Any, inputs: SimulationInputs, protrusions: np.ndarray,
               k_range: tuple[float, float], tol: float, scheduler: str | None = None,
               workers: int | None = None) -> tuple[dict[float, tuple], float]:
    """``k*`` of every protrusion [nm], fanned out: ``({protrusion: (k*, min d [nm], note, sims)}, seconds)``."""
    chunks = split([float(p) for p in protrusions], scheduler, workers)
    result: dict[float, tuple] = {}

    def keep(rows: list[tuple]) -> None:
        for delta, k, lo, note, sims in rows:
            result[delta] = (k, lo, note, sims)

    seconds = run_tasks(threshold_batch, [(scene, inputs, c, k_range, tol) for c in chunks],
                        scheduler=scheduler, workers=workers, on_done=keep)
    return result, seconds


def _status(k: float, k_range: tuple[float, float]) -> tuple[float, str]:
    """``k*`` as the bisection reports it: the range end and a status when it lies outside the range."""
    if k < k_range[0]:
        return k_range[0], "below range"
    if k >= k_range[1]:
        return k_range[1], "above range"
    return k, "found"


#: How the calibrated k is chosen from the admissible interval (``touchdown.k_choice``).
K_CHOICES = ("middle", "paper")


def choose_k(k_low: float, k_high: float, rule: str, probability: float | None) -> tuple[float, str]:
    """The calibrated k [1] in the admissible interval ``(k_low, k_high]`` and the words that say why.

    ``"middle"``: the middle, the largest margin to both touchdown conditions. ``"paper"``: the k whose
    two-sided contact probability is ``probability`` (``contact.fallback_probability``: the paper's own
    calibrated 32.8 %, k = 0.978) when it is admissible, else the admissible end nearest to it: for an
    interval many sigma wide, where the fold rather than the criterion decides the touchdown, the
    calibration then checks the paper's k instead of replacing it by an arbitrary middle (docs/model.md,
    section "Contact criterion").
    """
    if rule == "middle":
        k = 0.5 * (k_low + k_high)
        return k, f"the middle, {k:.4f}, for the largest margin to both conditions"
    if rule != "paper":
        raise ValueError(f"touchdown.k_choice = {rule!r}: expected one of {K_CHOICES}")
    if probability is None:
        raise ValueError("touchdown.k_choice = 'paper' needs contact.fallback_probability (the paper's two-sided "
                         "32.8 %: 0.328)")
    k_paper = k_from_probability(probability)
    if k_low < k_paper <= k_high:
        return k_paper, (f"the paper's k, {k_paper:.4f} ({100 * probability:g} % two-sided), which is admissible "
                         f"(touchdown.k_choice = 'paper')")
    k = k_high if k_paper > k_high else k_low + 1e-3 * (k_high - k_low)
    return k, (f"{k:.4f}, the admissible end nearest the paper's k {k_paper:.4f}, which is not admissible "
               f"(touchdown.k_choice = 'paper')")


#: The keys that describe one's own drive, by the part of it they describe. Where a scene gives one of them
#: another value than the paper scene's (the schema's default, :data:`pipeline.config.schema.SCHEMA`), the
#: drive is not the paper's, and neither is its touchdown (:func:`touchdown_provenance`).
OWN_DRIVE_KEYS = {
    "disk": ("dmw.source", "dmw.rpm", "dmw.radius_mm"),
    "roughness": ("roughness.afm", "roughness.sigma_nm", "roughness.summit_radius_um",
                  "roughness.summit_density_per_um2"),
    "slider": tuple(f"slider.{key}" for key in ("length_mm", "width_mm", "thickness_mm", "density_kg_m3",
                                                 "front_arm_mm", "rear_arm_mm", "tfc_from_trailing_edge_um"))
    + ("air_bearing.frequencies_khz", "air_bearing.flying_height_nm"),
}


class CalibrationError(ValueError):
    """The calibrated k is not physical (:func:`pipeline.physics.asperity_statistics.unphysical_k`); the one
    line names the touchdown it was fitted to and the keys to set."""


def differing_from_paper(scene: Any) -> dict[str, list[str]]:
    """The keys of :data:`OWN_DRIVE_KEYS` the scene sets to another value than the paper scene's, by part
    (``{"disk": ["dmw.source = 'my.csv'"]}``; parts that are the paper's are left out)."""
    out: dict[str, list[str]] = {}
    for part, keys in OWN_DRIVE_KEYS.items():
        for name in keys:
            section, key = name.split(".")
            value, default = scene[section][key], SCHEMA[section][key].default
            if value != default and not (isinstance(value, (list, tuple)) and list(value) == default):
                out.setdefault(part, []).append(f"{name} = {value!r}")
    return out


def papers_touchdown(scene: Any) -> bool:
    """Whether the scene's touchdown (``touchdown.onset_nm``, ``touchdown.previous_nm``) is the paper's
    measurement, the keys' defaults (9.8 nm, none at 9.6 nm)."""
    td, sch = scene["touchdown"], SCHEMA["touchdown"]
    return td["onset_nm"] == sch["onset_nm"].default and td["previous_nm"] == sch["previous_nm"].default


def touchdown_provenance(scene: Any) -> tuple[str, str]:
    """Which touchdown the calibration fits k to, in words, and a warning (``""``: none).

    The touchdown is the scene's ``touchdown.onset_nm`` (contact) and ``touchdown.previous_nm`` (none);
    at their defaults it is the paper's measurement (9.8 nm, none at 9.6 nm). The warning is given when it
    is the paper's while the disk, the roughness or the slider are not (:func:`differing_from_paper`): k
    then moves this drive's touchdown to the paper's, whatever this drive's is.
    """
    onset, prev = scene["touchdown"]["onset_nm"], scene["touchdown"]["previous_nm"]
    paper_td = papers_touchdown(scene)
    words = (f"contact at touchdown.onset_nm = {onset:g} nm, none at touchdown.previous_nm = {prev:g} nm: "
             + ("the paper's measured touchdown (the keys' defaults)" if paper_td else "this scene's own touchdown"))
    differ = differing_from_paper(scene)
    if not paper_td or not differ:
        return words, ""
    parts = ", ".join(f"the {part} ({', '.join(keys)})" for part, keys in differ.items())
    return words, (f"k is fitted to the paper's touchdown ({onset:g} nm, none at {prev:g} nm) while {parts} "
                   f"{'differ' if len(differ) > 1 else 'differs'} from the paper's: set touchdown.onset_nm and "
                   f"touchdown.previous_nm to the touchdown measured on this drive (docs/my-drive.md), or fix contact.k")


def check_physical(k: float, interval: tuple[float, float], scene: Any) -> None:
    """Refuse a calibrated ``k`` [1] that is not physical (below
    :data:`pipeline.physics.asperity_statistics.K_PHYSICAL_MIN`): one line naming the touchdown it was fitted
    to, the admissible ``interval`` ``(lo, hi]`` and the keys to set.

    Raises
    ------
    CalibrationError
        ``k`` is below the bound.
    """
    why = unphysical_k(k)
    if why is None:
        return
    lo, hi = interval
    onset, prev = scene["touchdown"]["onset_nm"], scene["touchdown"]["previous_nm"]
    if papers_touchdown(scene):
        differ = differing_from_paper(scene)
        what = ("the paper's measured touchdown" + (" on another drive (" + ", ".join(
            k for keys in differ.values() for k in keys) + ")" if differ else ""))
    else:
        what = "this scene's touchdown"
    fix = (f"[{max(lo, K_PHYSICAL_MIN):.4f}, {hi:.4f}] is the physical part of the admissible interval"
           if hi >= K_PHYSICAL_MIN else f"k >= {K_PHYSICAL_MIN:g}")
    raise CalibrationError(f"calibrate: the calibrated {why}; it was fitted to {what} (contact at "
                           f"touchdown.onset_nm = {onset:g} nm, none at touchdown.previous_nm = {prev:g} nm; admissible "
                           f"k ({lo:.4f}, {hi:.4f}]): set touchdown.onset_nm and touchdown.previous_nm to the "
                           f"touchdown measured on this drive, or fix contact.k ({fix})")


def calibrate(scene: Any, inputs: SimulationInputs, scheduler: str | None = None,
              workers: int | None = None) -> xr.Dataset:
    """Run the calibration of a scene; returns ``calibration.nc``'s dataset.

    ``inputs``: its interface tables, DMW record and bulge table (the tabulated bulge bearing), given by
    the calibrate stage (:class:`pipeline.model.inputs.SimulationInputs`; the fanned-out flying runs of the
    exact method take them along and read files by path on their workers, once per process);
    ``scheduler``, ``workers``: where those runs go (:func:`pipeline.fanout.run_tasks`).
    """
    if not scene.has("contact"):
        raise ValueError("calibration needs the contact effect in scene.effects")
    td = scene["touchdown"]
    method = td["method"]
    model = inputs.model(scene, k=0.0)
    k_range = tuple(td["k_range"])
    tol = td["k_tolerance"]
    grid = protrusion_grid(scene)
    ks = np.linspace(k_range[0], k_range[1], td["curve_points"])
    if method == "exact":
        th = _exact_thresholds(scene, inputs, grid, ks, k_range, tol, scheduler, workers)
    elif method == "bisection":
        th = _bisection_thresholds(model, td, grid, ks, k_range, tol)
    else:  # the scene schema admits only METHODS
        raise ValueError(f"touchdown.method = {method!r}: expected one of {METHODS}")
    fitted, warning = touchdown_provenance(scene)
    log.info("calibrate: k is fitted to the touchdown (%s)", fitted)
    if warning:
        log.warning("calibrate: %s", warning)
    log.info("calibrate: k*(%.2f nm) = %.4f (%s), k*(%.2f nm) = %.4f (%s)", td["onset_nm"], th.k_on, th.st_on,
             td["previous_nm"], th.k_prev, th.st_prev)
    k_low, k_high, k_cal, outcome = _admissible(scene, th, k_range)
    finite = th.curve[np.isfinite(th.curve)]
    if finite.size == th.curve.size and np.ptp(finite) == 0:
        outcome += (f". The touchdown protrusion is {finite[0]:g} nm for every k in the range: contact does not "
                    "depend on the criterion here, the slider is pulled into contact (adhesive snap-in) before "
                    "the separation reaches any k sigma of the range")
    ds = _calibration_dataset(th, (k_low, k_high, k_cal), ks, grid, model.sigma)
    onset, prev = td["onset_nm"], td["previous_nm"]
    ds.attrs.update({"outcome": outcome, "touchdown_onset_nm": onset, "touchdown_previous_nm": prev,
                     "k_range": str(list(k_range)), "k_tolerance": tol,
                     "simulations": th.simulations, "touchdown_method": method, "method": th.how,
                     "batch_seconds": round(th.seconds, 3) if np.isfinite(th.seconds) else "n/a",
                     "collapsed_from_nm": th.collapsed[0] if method == "exact" and th.collapsed else "none",
                     "touchdown_fitted": fitted, "touchdown_source": "paper" if papers_touchdown(scene) else "scene",
                     "touchdown_warning": warning or "none",
                     "k_physical_min": K_PHYSICAL_MIN,
                     "paper": "the paper's calibrated k corresponds to a 32.8 % two-sided contact probability (k = 0.978)"})
    return ds


@dataclass
class _Thresholds:
    """What a calibration method found: the threshold k* [1] and its status at the onset and the previous
    protrusion, the touchdown protrusion [nm] per k of the curve, the runs it took and its batch seconds [s],
    how it works, the exact method's per-protrusion variables and the grid protrusions [nm] where the flying run
    collapses."""

    k_on: float
    st_on: str
    k_prev: float
    st_prev: str
    curve: np.ndarray
    simulations: int
    seconds: float
    how: str
    extra: dict[str, Any] = field(default_factory=dict)
    collapsed: list[float] = field(default_factory=list)


def _exact_thresholds(scene: Any, inputs: SimulationInputs, grid: np.ndarray, ks: np.ndarray, k_range: tuple,
                      tol: float, scheduler: str | None, workers: int | None) -> _Thresholds:
    """The exact method: k* of one flying run (contact law off) per protrusion of the grid and of the onset and
    previous protrusions (:func:`thresholds`); the touchdown curve from them."""
    td = scene["touchdown"]
    c = CALIBRATION
    todo = np.union1d(grid, label([td["onset_nm"], td["previous_nm"]]))
    found, seconds = thresholds(scene, inputs, todo, k_range, tol, scheduler, workers)
    k_on, st_on = _status(found[float(label(td["onset_nm"]))][0], k_range)
    k_prev, st_prev = _status(found[float(label(td["previous_nm"]))][0], k_range)
    kstar = np.array([found[float(p)][0] for p in grid])
    # the first grid protrusion with k*(protrusion) < k (no monotonicity in protrusion assumed)
    curve = np.array([grid[np.argmax(kstar < k)] if np.any(kstar < k) else np.nan for k in ks])
    collapsed = [float(p) for p in grid if found[float(p)][2]]
    extra = {
        "k_threshold": c["k_threshold"].data(kstar, ("protrusion",)),
        "min_separation": c["min_separation"].data(np.array([found[float(p)][1] for p in grid]),
                                                   ("protrusion",)),
    }
    simulations = 2 * len(todo) + sum(v[3] for v in found.values())
    how = ("exact: k* = minimum separation / sigma of one flying run (contact law off) per protrusion; "
           "bisection only where the transient dips below the steady window")
    if collapsed:  # (a warning where it decides the touchdown: at or below touchdown.onset_nm)
        (log.warning if collapsed[0] <= td["onset_nm"] else log.info)(
            "calibrate: the flying run (contact law off) collapses from %g nm of the grid on (%s): contact "
            "there for every k", collapsed[0], found[collapsed[0]][2])
    return _Thresholds(k_on, st_on, k_prev, st_prev, curve, simulations, seconds, how, extra, collapsed)


def _bisection_thresholds(model: Any, td: Any, grid: np.ndarray, ks: np.ndarray, k_range: tuple,
                          tol: float) -> _Thresholds:
    """The bisection method: k* by bisection at the onset and previous protrusions, the touchdown curve by
    bisection over the grid."""
    k_on, st_on, n_on = k_threshold(model, td["onset_nm"], k_range, tol)
    k_prev, st_prev, n_prev = k_threshold(model, td["previous_nm"], k_range, tol)
    curve = np.array([touchdown_protrusion(model, k, grid) for k in ks])
    return _Thresholds(k_on, st_on, k_prev, st_prev, curve, n_on + n_prev, float("nan"),
                       "bisection on k for each protrusion; touchdown curve by bisection over the grid")


def _admissible(scene: Any, th: _Thresholds, k_range: tuple) -> tuple[float, float, float, str]:
    """The admissible range ``(k_low, k_high]`` [1] between the thresholds, the chosen k [1] (NaN without a range)
    and the outcome's sentence (why there is none)."""
    td = scene["touchdown"]
    onset, prev = td["onset_nm"], td["previous_nm"]
    k_on, st_on, k_prev, st_prev = th.k_on, th.st_on, th.k_prev, th.st_prev
    if st_on == "found" and st_prev in ("found", "above range") and k_on < k_prev:
        k_low, k_high = k_on, k_prev
        k_cal, why = choose_k(k_low, k_high, td["k_choice"], scene["contact"].get("fallback_probability"))
        outcome = f"admissible k in ({k_low:.4f}, {k_high:.4f}]; chosen {why} (contact at {onset} nm, none at {prev} nm)"
        check_physical(k_cal, (k_low, k_high), scene)  # (before any dataset: nothing is written)
        return k_low, k_high, k_cal, outcome
    reasons = []
    if st_on == "below range":
        reasons.append(f"at {onset} nm contact happens for every k >= {k_range[0]}")
    if st_prev == "below range":
        reasons.append(f"at {prev} nm contact already happens for every k >= {k_range[0]}, so no k in range "
                       f"avoids contact at the previous step")
    if st_on == "above range":
        reasons.append(f"at {onset} nm no k <= {k_range[1]} gives contact")
    if st_on == "found" and st_prev == "found" and k_on >= k_prev:
        reasons.append(f"k*({onset}) = {k_on:.4f} >= k*({prev}) = {k_prev:.4f}: touching is not monotone "
                       "in protrusion here")
    return np.nan, np.nan, np.nan, "no admissible k in the range " + str(list(k_range)) + ": " + "; ".join(reasons)


def _calibration_dataset(th: _Thresholds, ks_found: tuple[float, float, float], ks: np.ndarray, grid: np.ndarray,
                         sigma: float) -> xr.Dataset:
    """``calibration.nc``'s variables (in dataset units; ``sigma`` [m] of the model) without its attributes."""
    c = CALIBRATION
    k_low, k_high, k_cal = ks_found
    p2, p1 = contact_probabilities(k_cal) if np.isfinite(k_cal) else (np.nan, np.nan)  # two-sided first
    data = {
        "touchdown": c["touchdown"].data(th.curve, ("k",)),
        "k_calibrated": c["k_calibrated"].data(k_cal, ()),
        "k_low": c["k_low"].data(k_low, ()),
        "k_high": c["k_high"].data(k_high, ()),
        "k_onset": c["k_onset"].data(th.k_on, (), description=f"{c['k_onset'].sentence} ({th.st_on})"),
        "k_previous": c["k_previous"].data(th.k_prev, (), description=f"{c['k_previous'].sentence} ({th.st_prev})"),
        "contact_probability_one_sided": c["contact_probability_one_sided"].data(p1, ()),
        "contact_probability_two_sided": c["contact_probability_two_sided"].data(p2, ()),
        "sigma": c["sigma"].from_si(sigma, ()),
    }
    data.update(th.extra)
    coords = {"k": c["k"].data(ks, ("k",))}
    if th.extra:
        coords["protrusion"] = c["protrusion"].data(grid, ("protrusion",))
    return xr.Dataset(data, coords=coords)
