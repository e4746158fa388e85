"""Parameter studies over scene keys: free parameters, candidates, targets, residuals (the analysis).

Shared by ``hdi identify`` (:mod:`pipeline.stages.identify`) and ``hdi sensitivity``
(:mod:`pipeline.stages.sensitivity`). Both vary numeric scene keys within bounds and evaluate every
candidate as a small sweep over protrusions:

* a **free parameter** (:class:`pipeline.analyses.free_parameters.Parameter`) is any numeric scene key ``section.key`` or an element of
  a list key ``section.key[i]`` (``air_bearing.frequencies_khz[0]``), with bounds; keys added to
  :data:`pipeline.config.scene.SCHEMA` later need no change here;
* a **candidate** is the base scene with the parameters set
  (:func:`pipeline.analyses.free_parameters.with_values`), evaluated as a
  small sweep over the protrusions the targets need (:mod:`pipeline.evaluations`: its inputs, the
  fan-out and the resumable store); the contact criterion k is ``contact.k`` when the scene (or the
  candidate) sets it, else the k whose **two-sided** contact probability ``P(|z| > k sigma)`` is
  ``contact.fallback_probability`` (docs/model.md, section "Contact criterion": the paper's 32.8 % is
  two-sided, k = 0.978). A calibration per candidate would make the touchdown target trivially true;
  with k fixed, touchdown at 9.8 nm is a property of the parameters, as in the paper.

Targets (:func:`targets`) are declared once, in :data:`pipeline.physics.paper.TARGETS` (published value,
tolerance, how each is measured, where the paper states it), with their values and tolerances in the
scene's ``[identify]`` (keys generated from the declarations); :data:`MEASUREMENTS` interprets each kind
of measurement. Each gives a value from a candidate's outputs and a residual normalised by its tolerance
(inequality targets are zero inside their admissible side); a target the candidate cannot produce (no
contact where contact is needed, a failed run) gets the residual ``identify.missing_residual``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Sequence

import numpy as np
import xarray as xr

from . import ensemble_rules as en
from .ensemble_comparison import SPREAD_STD
from ..config.grid import TOL_NM, label, range_grid
from ..config.fields import fields
from ..config.schema import target_keys
from ..model.outcomes import touched_in_summary
from ..physics import paper
from ..variables import SCALARS

#: The scene keys of the targets' definitions (:func:`targets`, :func:`headline`): which targets, their values,
#: tolerances and where they are measured (the ``[identify]`` keys :func:`pipeline.config.schema.target_keys`
#: generates), and the residual of a missing value; not the optimiser's settings.
TARGET_FIELDS = fields("identify.targets", "identify.missing_residual", *(f"identify.{key}" for key in target_keys()))


# ------------------------------------------------------------------------------------------ targets
class Table:
    """A candidate's outputs versus protrusion, read from its record."""

    def __init__(self, record: dict[str, Any]):
        self.protrusions = np.asarray(record["protrusions"], float)
        self.outputs = {k: np.asarray(v, float) for k, v in record["outputs"].items()}

    def values(self, name: str, at: Iterable[float]) -> np.ndarray:
        """``name`` at the protrusions ``at`` [nm] (NaN where not evaluated or absent)."""
        col = self.outputs.get(name)
        out = []
        for x in at:
            i = np.flatnonzero(np.abs(self.protrusions - x) < 1e-6)
            out.append(float(col[i[0]]) if col is not None and i.size else float("nan"))
        return np.asarray(out)

    def value(self, name: str, at: float) -> float:
        return float(self.values(name, [at])[0])

    def touching(self, at: Iterable[float]) -> np.ndarray:
        """Contact in the steady window at the protrusions ``at`` [nm]: the exact minimum clearance below
        zero, the rule of the calibration and of the regime (:func:`pipeline.model.outcomes.summarize`), which
        also counts a contact shorter than the output step. False where not evaluated."""
        return touched_in_summary(self.values("min_clearance", at))

    def touchdown(self) -> float:
        """First evaluated protrusion [nm] with contact in the steady window (NaN if none)."""
        order = np.sort(self.protrusions)
        hit = order[self.touching(order)]
        return float(hit[0]) if hit.size else float("nan")

    def flying_mean(self, name: str, at: Iterable[float]) -> float:
        """Mean of ``name`` over the protrusions of ``at`` [nm] where the slider flies (NaN if none)."""
        at = np.asarray(list(at), float)
        v = self.values(name, at)
        fly = v[np.isfinite(v) & ~self.touching(at)]
        return float(np.mean(fly)) if fly.size else float("nan")


def record_dataset(record: dict[str, Any]) -> xr.Dataset:
    """The outputs of an ensemble record (:func:`pipeline.evaluations.evaluate` with realisations > 1) as a
    dataset of dims ``(protrusion, realisation)`` in dataset units (``units`` attribute of each variable)."""
    prot = np.asarray(record["protrusions"], float)
    n = int(record.get("realisations", 1))
    data = {}
    for name, v in record["outputs"].items():
        a = np.asarray(v, float).reshape(len(prot), n)
        data[name] = xr.DataArray(a, dims=("protrusion", en.DIM),
                                  attrs={"units": SCALARS[name].units} if name in SCALARS else {})
    return xr.Dataset(data, coords={"protrusion": prot, en.DIM: np.arange(n)})


class Ensemble:
    """A candidate's outputs over its DMW realisations as numpy arrays: what the targets' ensemble statistics
    read (:attr:`ObjectiveTerm.ensemble`), from an evaluation record (:meth:`of_record`, without building a
    dataset: the identification scores every racing stage of every candidate) or from a dataset of dims
    ``(protrusion, realisation)`` (:meth:`of`: :func:`record_dataset`, ``ensemble.nc``).

    Attributes
    ----------
    protrusions : the evaluated protrusions [nm]
    realisations : the number of DMW realisations [1]
    """

    def __init__(self, protrusions: np.ndarray, realisations: int, columns: Any):
        self.protrusions = np.asarray(protrusions, float)
        self.realisations = int(realisations)
        self._columns = columns  # name -> array (protrusion, realisation), dataset units; a mapping or a Dataset

    @classmethod
    def of_record(cls, record: dict[str, Any]) -> "Ensemble":
        """The outputs of an evaluation record (the arrays :func:`record_dataset` holds)."""
        prot = np.asarray(record["protrusions"], float)
        n = realisations_of(record)
        return cls(prot, n, {name: np.asarray(v, float).reshape(len(prot), n)
                             for name, v in record["outputs"].items()})

    @classmethod
    def of(cls, data: Any) -> "Ensemble":
        """``data`` itself if an :class:`Ensemble`, else one over a dataset of dims ``(protrusion,
        realisation)`` (its variables read when asked for)."""
        if isinstance(data, Ensemble):
            return data
        return cls(data["protrusion"].values, data.sizes.get(en.DIM, 1), data)

    def at(self, name: str, at: Iterable[float]) -> np.ndarray:
        """``name`` at the protrusions ``at`` [nm], shape ``(len(at), realisations)``; NaN where not
        evaluated or absent (the first evaluated protrusion within 1e-6 nm of each)."""
        at = np.asarray(list(at), float)
        out = np.full((at.size, self.realisations), np.nan)
        if name in self._columns:
            col = self._columns[name]
            values = col.values if isinstance(col, xr.DataArray) else col
            near = np.abs(self.protrusions[None, :] - at[:, None]) < 1e-6
            hit = near.any(axis=1)
            out[hit] = np.reshape(values[near.argmax(axis=1)[hit]], (int(hit.sum()), self.realisations))
        return out


def at_protrusions(ds: Any, name: str, at: Iterable[float]) -> xr.DataArray:
    """``ds[name]`` at the protrusions ``at`` [nm] (dims ``(protrusion, realisation)``; NaN where not
    evaluated or absent); ``ds``: a dataset of dims ``(protrusion, realisation)`` or an :class:`Ensemble`."""
    at = np.asarray(list(at), float)
    return xr.DataArray(Ensemble.of(ds).at(name, at), dims=("protrusion", en.DIM), coords={"protrusion": at})


#: How a target's ensemble spread is given: the 10-90 % range of the realisations (medians, the
#: touchdown protrusion) or mean +- one sample standard deviation (the light-contact state).
SPREAD_QUANTILES = f"{100 * en.SPREAD[0]:g}-{100 * en.SPREAD[1]:g} % of the realisations"


@dataclass(frozen=True)
class ObjectiveTerm:
    """A paper target (:class:`pipeline.physics.paper.Target`) resolved for one scene: a term of the
    identification objective, with its value from a candidate and its normalised residual.

    ``kind``: ``"equal"`` (residual (v - target)/tol), ``"above"`` (zero when v >= target, else
    (target - v)/tol), ``"below"`` (zero when v <= target), ``"touchdown"`` (see :func:`targets`).
    ``ensemble``: the value over DMW realisations and its spread, ``(value, low, high)`` of an
    :class:`Ensemble` (or of a dataset :meth:`Ensemble.of` reads); ``spread``: what ``low``/``high`` are
    (:data:`SPREAD_QUANTILES`, :data:`SPREAD_STD`).
    """

    name: str
    long_name: str
    units: str
    kind: str
    target: float
    tolerance: float
    protrusions: tuple[float, ...]
    value: Callable[[Table], float]
    paper: str
    ensemble: Callable[[Any], tuple[float, float, float]] | None = None
    spread: str = SPREAD_QUANTILES

    def residual(self, table: Table, missing: float) -> float:
        if self.kind == "touchdown":
            onset, prev = self.protrusions[-1], self.protrusions[0]
            lo_on, lo_prev = table.value("min_clearance", onset), table.value("min_clearance", prev)
            return self._touchdown_residual(lo_on, lo_prev, missing)
        return self._residual_of(self.value(table), missing)

    def ensemble_residual(self, ds: Any, missing: float) -> float:
        """The residual judged over the realisations of ``ds`` (an :class:`Ensemble`, or a dataset
        :meth:`Ensemble.of` reads: :func:`record_dataset`).

        Touchdown: the residual of :meth:`residual` on the *median* minimum clearance over the
        realisations, which is below zero exactly when more than half of them touch (touchdown
        probability > 0.5), and continuous in the parameters; the others: on the ensemble value.
        """
        if self.kind == "touchdown":
            onset, prev = self.protrusions[-1], self.protrusions[0]
            med = en.median_spread_values(Ensemble.of(ds).at("min_clearance", (onset, prev)))[0]
            return self._touchdown_residual(float(med[0]), float(med[1]), missing)
        return self._residual_of(self.ensemble(ds)[0] if self.ensemble else float("nan"), missing)

    def _touchdown_residual(self, lo_on: float, lo_prev: float, missing: float) -> float:
        if not (np.isfinite(lo_on) and np.isfinite(lo_prev)):
            return missing
        return (max(0.0, lo_on) + max(0.0, -lo_prev)) / self.tolerance

    def _residual_of(self, v: float, missing: float) -> float:
        if not np.isfinite(v):
            return missing
        if self.kind == "equal":
            return (v - self.target) / self.tolerance
        if self.kind == "above":
            return max(0.0, self.target - v) / self.tolerance
        return max(0.0, v - self.target) / self.tolerance


def _grid(lo: float, hi: float, step: float, open_low: bool = False) -> tuple[float, ...]:
    """Protrusions ``lo, lo + step, ... <= hi`` [nm] (without ``lo`` when ``open_low``)."""
    pts = tuple(float(x) for x in range_grid({"start": lo, "stop": hi, "step": step}))
    return pts[1:] if open_low else pts


def _key(scene: Any, key: str) -> Any:
    """The value of ``key``: ``"section.key"``, or a key of ``[identify]``."""
    section, _, name = key.rpartition(".")
    return scene[section or "identify"][name]


def _median(values: np.ndarray) -> tuple[float, float, float]:
    """Median and 10-90 % range of 1-D ``values`` over the realisations."""
    m, lo, hi = en.median_spread_values(values)
    return float(m), float(lo), float(hi)


#: What a measurement gives :class:`ObjectiveTerm`: its protrusions [nm], the value of a candidate's
#: :class:`Table`, the ensemble statistic of an :class:`Ensemble` (or a dataset), the spread's meaning and
#: the template fields of its protrusions.
_Measured = tuple[tuple[float, ...], Callable[[Table], float], Callable[[Any], tuple[float, float, float]],
                  str, dict[str, float]]


def _touchdown(m: paper.Measure, scene: Any, value: float) -> _Measured:
    """Contact at the second protrusion of ``m.where``, none at the first; its value is the first evaluated
    protrusion in contact, over realisations where the touchdown probability crosses 0.5."""
    prots = tuple(_key(scene, k) for k in m.where)

    def ensemble(ds: Any) -> tuple[float, float, float]:
        e = Ensemble.of(ds)
        order = np.sort(e.protrusions)
        return en.touchdown_protrusion_values(order, e.at(m.output, order))

    return prots, lambda t: t.touchdown(), ensemble, SPREAD_QUANTILES, {"lo": prots[0], "hi": prots[-1]}


def _flying_mean(m: paper.Measure, scene: Any, value: float) -> _Measured:
    """The mean of ``m.output`` over the flying points of the range ``m.where`` (every ``m.step``)."""
    fr = _grid(*_key(scene, m.where), _key(scene, m.step))

    def ensemble(ds: Any) -> tuple[float, float, float]:
        e = Ensemble.of(ds)
        return _median(en.flying_mean_values(e.at(m.output, fr), e.at("min_clearance", fr), axis=0))

    return fr, lambda t: t.flying_mean(m.output, fr), ensemble, SPREAD_QUANTILES, {"lo": fr[0], "hi": fr[-1]}


def _band(m: paper.Measure, scene: Any, cap: float) -> _Measured:
    """The graded band (:func:`targets`) over the steps of ``(lo, hi]`` of ``m.where`` (every ``m.step``),
    each step's bouncing BV capped at the target ``cap``."""
    step = _key(scene, m.step)
    band = _grid(*_key(scene, m.where), step, open_low=True)

    def value(t: Table) -> float:
        v = bouncing_bv(t.values(m.output, band), t.values("min_clearance", band))
        return float(np.mean(np.minimum(v, cap))) if v.size and np.all(np.isfinite(v)) else float("nan")

    def ensemble(ds: Any) -> tuple[float, float, float]:
        e = Ensemble.of(ds)
        med, lo, hi = en.median_spread_values(bouncing_bv(e.at(m.output, band), e.at("min_clearance", band)))
        if not (med.size and np.all(np.isfinite(med))):
            return float("nan"), float("nan"), float("nan")
        return tuple(float(np.mean(np.minimum(v, cap))) for v in (med, lo, hi))

    return band, value, ensemble, SPREAD_QUANTILES, {"lo": band[0], "hi": band[-1], "open_lo": band[0] - step}


def _at(m: paper.Measure, scene: Any, value: float) -> _Measured:
    """``m.output`` at the protrusion ``m.where``; over realisations its median (10-90 %) or its mean
    (± 1 standard deviation), by ``m.statistic``."""
    at = _key(scene, m.where)

    def median(ds: Any) -> tuple[float, float, float]:
        return _median(Ensemble.of(ds).at(m.output, (at,))[0])

    def mean(ds: Any) -> tuple[float, float, float]:
        mu, sd = (float(v) for v in en.mean_std_values(Ensemble.of(ds).at(m.output, (at,))[0]))
        return mu, mu - sd, mu + sd

    ensemble, spread = (mean, SPREAD_STD) if m.statistic == "mean" else (median, SPREAD_QUANTILES)
    return (at,), lambda t: t.value(m.output, at), ensemble, spread, {"lo": at, "hi": at, "at": at}


#: The interpretation of each kind of measurement (:data:`pipeline.physics.paper.MEASURES`).
MEASUREMENTS: dict[str, Callable[[paper.Measure, Any, float], _Measured]] = {
    "touchdown": _touchdown, "flying_mean": _flying_mean, "band": _band, "at": _at}


def target(decl: paper.Target, scene: Any) -> ObjectiveTerm:
    """The target of the declaration ``decl`` (:data:`pipeline.physics.paper.TARGETS`) with the values of
    ``scene``: its published value, tolerance and measurement (:data:`MEASUREMENTS`)."""
    c = scene["identify"]
    v = decl.value
    value = c[v.key] if isinstance(v, paper.Setting) else _key(scene, v) if isinstance(v, str) else v
    prots, of_table, of_ensemble, spread, fields = MEASUREMENTS[decl.measure.how](decl.measure, scene, value)
    where = decl.measure.where if isinstance(decl.measure.where, tuple) else (decl.measure.where,)
    names = {k.rpartition(".")[2]: _key(scene, k) for k in where if k} | {s.key: c[s.key] for s in decl.settings}
    fields = {**names, **fields, "value": value}
    return ObjectiveTerm(decl.name, decl.long_name.format(**fields), decl.units, decl.kind, value,
                         c[decl.tolerance.key], prots, of_table, decl.paper.format(**fields), of_ensemble, spread)


def targets(scene: Any) -> list[ObjectiveTerm]:
    """The targets that ``identify.targets`` selects, in the order of their declarations
    (:data:`pipeline.physics.paper.TARGETS`; docs/model.md, sections "Paper targets" and "Corrections").

    * ``touchdown``: contact at ``touchdown.onset_nm``, none at ``touchdown.previous_nm`` (exact
      minimum clearance of the steady window, which is continuous in the parameters where the
      contact flag is not): residual ``(max(0, c_min(onset)) + max(0, -c_min(previous))) / tol``;
      its value is the first evaluated protrusion in contact.
    * ``fhm_flying``: mean FHM of the flying points of ``fhm_flying_range_nm`` (every
      ``flying_step_nm``); ``fhm_touchdown``: FHM at ``fhm_touchdown_at_nm``.
    * ``bouncing`` (graded): over the steps of ``(lo, hi]`` of ``bouncing_range_nm`` (every
      ``band_step_nm``), the mean of the bouncing BV capped at ``bouncing_min_percent``: a run's BV where
      it touched in the steady window, 0 where it flew (a flying FHM is no bounce). On an ensemble,
      each step's median over the realisations is capped. It reaches the threshold exactly when every
      step bounces above it, and it grows with each step's BV below it, so an optimiser feels a partial
      band (the paper's "smallest BV above 20 %" is flat wherever one step is missing).
    * at ``sliding_at_nm``: BV below ``sliding_bv_max_percent``; interference, contact force, real
      area, mean pressure and friction coefficient equal to the paper's; net force attractive (< 0).
    """
    chosen = scene["identify"]["targets"]
    return [target(decl, scene) for name, decl in paper.TARGETS.items() if name in chosen]


def bouncing_bv(fhm_bv: Any, min_clearance: Any) -> Any:
    """The BV of a bounce [%]: ``fhm_bv`` where the run touched in the steady window (the rule of
    :func:`pipeline.model.outcomes.touched_in_summary`), 0 where it flew, NaN where not evaluated; numpy
    arrays or xarray data of one shape."""
    ok = np.isfinite(np.asarray(min_clearance, float))
    values = np.where(ok, np.where(touched_in_summary(min_clearance), np.asarray(fhm_bv, float), 0.0), np.nan)
    return fhm_bv.copy(data=values) if isinstance(fhm_bv, xr.DataArray) else values


def target_protrusions(tlist: Sequence[ObjectiveTerm]) -> list[float]:
    """Sorted union of the protrusions [nm] the targets need."""
    return sorted({float(label(float(x))) for t in tlist for x in t.protrusions})


def realisations_of(record: dict[str, Any]) -> int:
    """The DMW realisations of an evaluation record (1: the scene's record alone)."""
    return int(record.get("realisations", 1))


def is_ensemble(record: dict[str, Any]) -> bool:
    """An evaluation record of an ensemble over DMW records, or a part of one: it names its ``realisations``
    (:func:`pipeline.evaluations.evaluate` with ``realisations`` > 1, its racing parts, :func:`head`), even a
    part of one record (a first racing stage of ``identify.racing_records = 1``). A scene's record alone (one
    realisation, no racing) does not, and is scored by the single-record rules."""
    return "realisations" in record


def residuals(record: dict[str, Any], tlist: Sequence[ObjectiveTerm],
              missing: float) -> tuple[np.ndarray, np.ndarray]:
    """Values and normalised residuals of the targets for one evaluation record (over its realisations
    for an ensemble record: :attr:`ObjectiveTerm.ensemble`, :meth:`ObjectiveTerm.ensemble_residual`)."""
    return score(record, tlist, missing)[:2]


def score(record: dict[str, Any], tlist: Sequence[ObjectiveTerm],
          missing: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`residuals` and :func:`spreads` of one evaluation record at once: values, normalised residuals
    and the ``(low, high)`` spread of each target, each ensemble statistic computed once, on the record's
    arrays (:class:`Ensemble`, no dataset). An ensemble's part of one DMW record (:func:`is_ensemble`) is scored
    by the ensemble's rules too, as a partial ensemble (its medians of one value, its touchdown from the median
    minimum clearance), so that its residuals are those the racing bound compares with the whole ensemble's."""
    if is_ensemble(record):
        ens = Ensemble.of_record(record)
        stats = np.array([t.ensemble(ens) if t.ensemble else (np.nan, np.nan, np.nan) for t in tlist],
                         float).reshape(len(tlist), 3)
        vals = stats[:, 0].copy()
        # (the residual of the value just computed, not the ensemble statistic again)
        res = np.array([t.ensemble_residual(ens, missing) if t.kind == "touchdown" else t._residual_of(v, missing)
                        for t, v in zip(tlist, vals)], float)
        return vals, res, stats[:, 1:].copy()
    table = Table(record)
    vals = np.array([t.value(table) for t in tlist], float)
    res = np.array([t.residual(table, missing) for t in tlist], float)
    return vals, res, np.full((len(tlist), 2), np.nan)


def spreads(record: dict[str, Any], tlist: Sequence[ObjectiveTerm]) -> np.ndarray:
    """``(low, high)`` of each target's ensemble value (:attr:`ObjectiveTerm.spread` says which), shape
    ``(targets, 2)``; NaN for a single-record evaluation (a scene's record alone: :func:`is_ensemble`)."""
    out = np.full((len(tlist), 2), np.nan)
    if is_ensemble(record):
        ens = Ensemble.of_record(record)
        for j, t in enumerate(tlist):
            if t.ensemble:
                out[j] = t.ensemble(ens)[1:]
    return out


def record_inputs(record: dict[str, Any], tlist: Sequence[ObjectiveTerm]) -> np.ndarray:
    """Per target and DMW realisation of an ensemble record, what its residual is made of, in residual units
    [1], shape ``(targets, 2, realisations)``: the single-record value (:attr:`ObjectiveTerm.value`) divided
    by the tolerance (second row NaN); for ``touchdown``, the minimum clearances at the onset and the previous
    protrusion divided by the tolerance. Unclipped: an inequality target's value varies on its admissible
    side too. All NaN for a record without outputs."""
    n = realisations_of(record)
    out = np.full((len(tlist), 2, n), np.nan)
    if not record["outputs"]:
        return out
    prot = np.asarray(record["protrusions"], float)
    cols = {k: np.asarray(v, float).reshape(len(prot), n) for k, v in record["outputs"].items()}
    tables = [Table({"protrusions": prot, "outputs": {k: c[:, r] for k, c in cols.items()}}) for r in range(n)]
    for j, t in enumerate(tlist):
        if t.kind == "touchdown":
            for row, at in enumerate((t.protrusions[-1], t.protrusions[0])):
                out[j, row] = [tb.value("min_clearance", at) for tb in tables]
        else:
            out[j, 0] = [t.value(tb) for tb in tables]
        out[j] /= t.tolerance
    return out


def input_spreads(inputs: np.ndarray) -> np.ndarray:
    """Per target, the record-to-record spread of :func:`record_inputs` (or of a difference of two) [1]: the
    sample standard deviation (ddof 1) over the realisations, the two rows' added (touchdown); NaN where a
    row in use has fewer than two finite values."""
    out = np.zeros(inputs.shape[0])
    for row in range(inputs.shape[1]):
        v = inputs[:, row, :]
        used = np.isfinite(v).any(axis=1) | (row == 0)
        finite = np.isfinite(v).sum(axis=1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            sd = np.nanstd(v, axis=1, ddof=1) if v.shape[1] > 1 else np.full(len(v), np.nan)
        out += np.where(used, np.where(finite >= 2, sd, np.nan), 0.0)
    return out


def record_spreads(record: dict[str, Any], tlist: Sequence[ObjectiveTerm]) -> np.ndarray:
    """Per target, the record-to-record spread of an ensemble record in residual units [1]
    (:func:`input_spreads` of :func:`record_inputs`): the scale of the error of a partial ensemble's residual
    (identification racing, docs/model.md, section "Identification"). NaN for one realisation."""
    if realisations_of(record) < 2:
        return np.full(len(tlist), np.nan)
    return input_spreads(record_inputs(record, tlist))


def head(record: dict[str, Any], m: int) -> dict[str, Any]:
    """The first ``m`` DMW records of an ensemble record (its times scaled by the share of the records)."""
    n = realisations_of(record)
    if m >= n:
        return record
    out = {**record, "outputs": {k: [list(v[:m]) for v in col] for k, col in record["outputs"].items()},
           "realisations": m, "seeds": list(record["seeds"][:m])}
    out.update({k: record[k] * m / n for k in ("seconds", "kernel_seconds") if k in record})
    return out


def ensemble_summary(ds: xr.Dataset, tlist: Sequence[ObjectiveTerm]) -> dict[str, tuple[float, float, float, float]]:
    """Per target name: ``(value, low, high, single)`` over the realisations of ``ds`` (dims ``(protrusion,
    realisation)``, dataset units: :func:`record_dataset` or ``ensemble.nc``): :attr:`ObjectiveTerm.ensemble`
    and, as ``single``, :attr:`ObjectiveTerm.value` of realisation 0 (the scene's own record) alone."""
    outputs = {name: np.asarray(ds[name].values, float)[:, 0] for name in ds.data_vars
               if ds[name].dims == ("protrusion", en.DIM)}
    single = Table({"protrusions": ds["protrusion"].values, "outputs": outputs})
    ens = Ensemble.of(ds)
    return {t.name: ((t.ensemble(ens) if t.ensemble else (np.nan, np.nan, np.nan)) + (t.value(single),))
            for t in tlist}


def cost(res: np.ndarray) -> float:
    """The objective: sum of squared normalised residuals."""
    return float(np.sum(np.square(res)))


# ------------------------------------------------------------------------------- headline outputs
#: Headline outputs of ``hdi sensitivity``: name -> (units, long_name).
HEADLINES: dict[str, tuple[str, str]] = {
    "touchdown": ("nm", "touchdown protrusion (first grid protrusion in contact)"),
    "fhm_flying": ("%", "flying FHM, mean over the flying range"),
    "bv_after_touchdown": ("%", "largest BV within the bouncing band after touchdown"),
    "interference": ("nm", "mean interference at the sliding protrusion"),
    "contact_force": ("mN", "contact force at the sliding protrusion"),
    "mean_pressure": ("MPa", "mean contact pressure at the sliding protrusion"),
}


def headline(record: dict[str, Any], scene: Any) -> dict[str, float]:
    """Headline outputs of one evaluation over a protrusion grid (definitions of ``[identify]``).

    ``bv_after_touchdown``: the largest BV in ``(touchdown, touchdown + w]`` with ``w`` the width of
    ``identify.bouncing_range_nm``; the sliding outputs at ``identify.sliding_at_nm``.
    """
    c = scene["identify"]
    t = Table(record)
    td = t.touchdown()
    lo, hi = c["fhm_flying_range_nm"]
    flying_range = t.protrusions[(t.protrusions >= lo - TOL_NM) & (t.protrusions <= hi + TOL_NM)]
    width = c["bouncing_range_nm"][1] - c["bouncing_range_nm"][0]
    if np.isfinite(td):
        band = (t.protrusions > td + TOL_NM) & (t.protrusions <= td + width + TOL_NM)
        bv = t.outputs["fhm_bv"][band]
        bv_after = float(np.nanmax(bv)) if bv.size and np.any(np.isfinite(bv)) else float("nan")
    else:
        bv_after = float("nan")
    at = c["sliding_at_nm"]
    return {"touchdown": td, "fhm_flying": t.flying_mean("fhm_bv", flying_range),
            "bv_after_touchdown": bv_after, "interference": t.value("interference", at),
            "contact_force": t.value("contact_force", at), "mean_pressure": t.value("mean_pressure", at)}
