"""Evaluating parameter-study candidates: their inputs, the fan-out and the resumable store.

The orchestration half of ``hdi identify`` and ``hdi sensitivity`` (the analysis half, parameters,
targets and residuals, is :mod:`pipeline.analyses.study`):

* a **candidate** is the base scene with the parameters set (validated again, so an impossible
  combination such as ``f1 > f2`` is a recorded failure, not a crash). Its interface tables are
  rebuilt only when a key they depend on changed (the runner's inputs key of ``interface``,
  ~15-45 ms), its DMW record only when a ``[dmw]`` key changed (synthesis, ~0.1 ms); otherwise the
  base scene's ``interface.nc``/``dmw.nc`` are read by path, once per worker process
  (:func:`pipeline.candidates.candidate_inputs`, :class:`pipeline.model.inputs.SimulationInputs` and its one cache);
* it runs at the protrusions the study needs (:func:`pipeline.model.simulation.simulate`) and keeps the
  steady-window outputs of :func:`pipeline.model.outcomes.summarize` in dataset units
  (:data:`pipeline.variables.SCALARS`), with k by the one rule
  :func:`pipeline.model.scene_inputs.contact_k` without a calibration (:func:`evaluate`);
* a racing part of a candidate (its DMW records ``a`` to ``b - 1``) finds in its worker process what an
  earlier part of the same candidate made (:class:`pipeline.candidates.Candidates`): its validated scene, its inputs and their
  keys, its model (each record's is :func:`pipeline.model.assembly.with_record` of it), its static starts,
  which are those of the mean disk and so the same for every record, and, for the candidates run last,
  its tabulated TFC-point forces;
* candidates are fanned out in batches (:func:`evaluate_batch`, via :func:`pipeline.fanout.run_tasks`);
  every finished evaluation is appended to a JSON-lines store (:class:`EvaluationStore`) keyed by the
  hash of the base scene and its inputs, the parameter values and the protrusions, so an interrupted
  study resumes: what was evaluated is read back, not recomputed.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from .analyses.free_parameters import Parameter, parse_parameters
from .analyses.study import head
from .code_version import code_key
from .config.grid import label
from .config.schema import SceneError
from .fanout import LOCAL, local_workers, run_tasks
from .paths import append_text, refuse_links
from .model import dmw_record, scene_inputs
from .model import assembly, copies, running
from .model.bulge_table import DERIVED_FIELDS as BULGE_DERIVED, FIELDS as BULGE_FIELDS
from .model.inputs import SimulationInputs, Source, for_stage
from .model.simulation import scalars
from .runner import current_inputs, scene_part
from .variables import SCALARS
from .candidates import _CANDIDATES, seeded_record


def upstream(scene: Any) -> tuple[str, ...]:
    """The stages a study reads: a single simulation's inputs without the calibration (a study fixes k,
    :func:`pipeline.model.scene_inputs.contact_k` without a calibration)."""
    return scene_inputs.input_stages(scene, calibration=False)


#: The free parameter whose bulge table a study interpolates (:mod:`pipeline.stages.bulge_pads`).
PAD_KEY = "air_bearing.pad_pressure_mpa"


def pad_bounds(scene: Any) -> tuple[float, float] | None:
    """The bounds [MPa] of ``air_bearing.pad_pressure_mpa`` among ``identify.parameters`` when the scene's
    bulge law reads a table and no other free parameter is a key of that table
    (:data:`pipeline.model.bulge_table.FIELDS` and the protrusions of its depth); else ``None`` (the candidates
    solve their own tables, as when the pad pressure is fixed)."""
    if "bulge" not in scene_inputs.table_stages(scene):
        return None
    items = scene["identify"]["parameters"]
    if not items:
        return None
    params = parse_parameters(items, str(scene.path or "<scene>"), "identify.parameters")
    table_keys = set(BULGE_FIELDS) | set(BULGE_DERIVED)
    pad = [p for p in params if p.name == PAD_KEY]
    if not pad or any(p.name in table_keys and p.name != PAD_KEY for p in params):
        return None
    return float(pad[0].low), float(pad[0].high)


# ---------------------------------------------------------------------------------- evaluations
def base_key(scene: Any, inputs: SimulationInputs) -> str:
    """Hash of what an evaluation depends on besides its parameters and protrusions.

    The scene keys a study's simulations read (:data:`pipeline.model.scene_inputs.STUDY_FIELDS`), the
    runner's keys of the base inputs, which hash AFM scans and a measured DMW record by content (a
    rescanned file under the same name is a new base, not a store to read back), and the code of this
    module and of what it imports (:func:`pipeline.code_version.code_key`).
    """
    keys = {stage: getattr(inputs, stage).key if getattr(inputs, stage) is not None else None
            for stage in ("interface", "dmw", "bulge")}
    blob = {"scene": scene_part(scene, scene_inputs.STUDY_FIELDS), "interface": keys["interface"],
            "dmw": keys["dmw"], "code": code_key(__name__)}
    if keys["bulge"] is not None:  # (only with the tabulated bulge bearing: other stores keep their keys)
        blob["bulge"] = keys["bulge"]
    if inputs.bulge_pads is not None:  # (the candidates' tables interpolated in p_pad: their own store)
        blob["bulge_pads"] = inputs.bulge_pads.key
    return hashlib.sha256(json.dumps(blob, sort_keys=True).encode()).hexdigest()


def evaluation_key(base: str, params: Sequence[Parameter], values: Sequence[float],
                   protrusions: Sequence[float], realisations: int = 1,
                   records: tuple[int, int] | None = None) -> str:
    """Identity of one evaluation (values rounded to 12 significant digits).

    ``realisations`` > 1 is part of the identity (the seeds follow from it and ``dmw.seed``, which the
    base or the values hold); one realisation keeps the key of the single-record evaluation, so a
    store written before ensembles existed is still read back. ``records = (a, b)``: a part of the
    ensemble, its DMW records ``a`` to ``b - 1`` (a racing stage, :func:`evaluate`); None or all of them:
    the whole evaluation's key.
    """
    what = {"base": base, "params": {p.name: float(f"{v:.12g}") for p, v in zip(params, values)},
            "protrusions": [float(label(float(x))) for x in protrusions]}
    if realisations > 1:
        what["realisations"] = int(realisations)
    if records is not None and tuple(records) != (0, realisations):
        what["records"] = [int(records[0]), int(records[1])]
    blob = json.dumps(what, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def run_protrusions(model: assembly.Model, protrusions: Sequence[float]) -> tuple[dict[str, list[float]], float, list[str]]:
    """Steady-window summaries of ``model`` at ``protrusions`` [nm], in dataset units (``fhm_bv`` [%],
    ``min_clearance`` [nm], ``contact_force`` [mN], ...), one value per protrusion, NaN where the run
    failed or the quantity does not exist (no contact), by :func:`pipeline.model.simulation.scalars` (:func:`~pipeline.model.simulation.simulate`'s numbers).
    Returns ``(outputs, kernel seconds [s], errors)``."""
    timings = {"kernel_seconds": 0.0}
    # (the dataset's numbers, without the dataset: simulation.scalars)
    values, failed = scalars(model, protrusions, timings=timings)
    errors = ["; ".join(failed)] if failed else []
    outputs: dict[str, list[float]] = {}
    for name, v in values.items():
        fill = SCALARS[name].fill_value  # (a failed protrusion's regime: its fill value, NaN here)
        outputs[name] = [float("nan") if fill is not None and x == fill else float(x) for x in v.astype(float)]
    return outputs, timings["kernel_seconds"], errors


def evaluate_realisations(scene: Any, protrusions: Sequence[float], inputs: SimulationInputs,
                          realisations: Sequence[int], seeds: Sequence[int]) -> list[tuple[int, dict[str, list[float]], float, list[str]]]:
    """One fan-out task of an ensemble of ``scene`` itself (the report's, :mod:`pipeline.stages.ensemble`):
    the realisations ``realisations`` (0: the scene's own record; else :func:`seeded_record` of the
    matching ``seeds``) at ``protrusions`` [nm] with the contact criterion ``inputs.k`` [1]. Returns, per
    realisation, ``(realisation, *run_protrusions(...))``; the task's models share their static starts
    (:func:`pipeline.model.copies.share_statics`).

    ``inputs`` are the scene's own (current upstream datasets of the calling stage, with k), read by path
    once per process under their stage keys (no candidate's keys to compare).
    """
    models = []
    for realisation, seed in zip(realisations, seeds):
        sim = inputs if realisation == 0 else inputs.with_record(Source.memory("dmw", seeded_record(scene, seed)))
        models.append(sim.model(scene))
    copies.share_statics(models)
    return [(r, *run_protrusions(model, protrusions)) for r, model in zip(realisations, models)]


def evaluate(base: Any, params: Sequence[Parameter], values: Sequence[float], protrusions: Sequence[float],
             inputs: SimulationInputs, realisations: int = 1,
             records: tuple[int, int] | None = None) -> dict[str, Any]:
    """Run one candidate at ``protrusions`` [nm]; returns its record (see :class:`EvaluationStore`).

    Outputs: :func:`run_protrusions`, one value per protrusion. With ``realisations`` > 1 the candidate
    runs on that many DMW records (:func:`pipeline.model.dmw_record.realisation_seeds`: its own record
    first, then :func:`seeded_record`); each output is then a list over protrusions of lists over the
    realisations, and the record holds ``realisations`` and ``seeds``. The contact criterion k is
    :func:`pipeline.model.scene_inputs.contact_k` of the candidate (no calibration).

    ``records = (a, b)`` (with ``realisations`` > 1): only the DMW records ``a`` to ``b - 1`` of the
    ensemble, a part of it (identification racing); the record then holds ``realisations = b - a``, their
    ``seeds`` and ``first_record = a``. Each DMW record's run does not depend on the others of its task
    (the static starts are on the mean disk), so the parts joined (:func:`join_parts`) are the whole.
    """
    t0 = time.perf_counter()
    kernel = 0.0
    errors: list[str] = []
    seeds: list[int] = []
    per_seed: list[dict[str, list[float]]] = []
    a, b = (0, realisations) if records is None else (int(records[0]), int(records[1]))
    part = (a, b) != (0, realisations)
    count = b - a
    try:
        cand = _CANDIDATES.get(base, inputs, params, values)
        scene, sim = cand.scene, cand.inputs(inputs)
        records = [sim.record()] if a == 0 else []
        if realisations > 1:
            seeds = dmw_record.realisation_seeds(scene["dmw"]["seed"], realisations)[a:b]
            records += [seeded_record(scene, seed, cand.record_key(seed)) for seed in (seeds[1:] if a == 0 else seeds)]
        # (the candidate's model once, each record's disk on it: assembly.with_record, the same models)
        template = cand.template()
        models = [assembly.with_record(template, record) for record in records]
        # (the static starts are on the mean disk: found once for all records, and for all parts of the
        # ensemble; the tabulated TFC force at the protrusions too, for the candidates run last)
        models[0].statics = cand.statics
        models[0].tfc_tables = dict(cand.tfc_tables)
        copies.share_statics(models)
    except (SceneError, ValueError, running.IntegrationError) as exc:
        errors.append(str(exc))
        models = []
    for r, model in enumerate(models, start=a):
        outputs, seconds, errs = run_protrusions(model, protrusions)
        kernel += seconds
        errors += [f"realisation {r}: {e}" for e in errs] if realisations > 1 else errs
        per_seed.append(outputs)
    if models:
        _CANDIDATES.keep_tables(cand, models[0].tfc_tables, protrusions)
    if realisations == 1:
        outputs = per_seed[0] if per_seed else {}
    else:
        names = sorted({n for o in per_seed for n in o}, key=lambda n: list(SCALARS).index(n))
        nan = [float("nan")] * len(protrusions)
        outputs = {n: [list(v) for v in zip(*(o.get(n, nan) for o in per_seed))] for n in names} \
            if len(per_seed) == count else {}
    rec = {"params": [float(v) for v in values], "protrusions": [float(x) for x in protrusions],
           "outputs": outputs, "seconds": time.perf_counter() - t0, "kernel_seconds": kernel,
           "error": "; ".join(errors) if errors else None}
    if realisations > 1:
        rec.update(realisations=int(count), seeds=seeds)
    if part:
        rec["first_record"] = a
    return rec


def join_parts(parts: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """One record of consecutive parts of an ensemble (:func:`evaluate` with ``records``, in record order):
    the outputs joined along the realisations, the times added, the errors joined. A part without outputs
    (a candidate that could not be built) leaves the joined record without outputs, and its error once (each
    part says it alike; a record's run error names its realisation), as :func:`evaluate` does."""
    first = parts[0]
    n = sum(int(p["realisations"]) for p in parts)
    names = [k for k in first["outputs"]] if all(p["outputs"] for p in parts) else []
    outputs = {k: [sum((list(p["outputs"][k][i]) for p in parts), []) for i in range(len(first["protrusions"]))]
               for k in names}
    errors = list(dict.fromkeys(p["error"] for p in parts if p["error"]))
    rec = {"params": first["params"], "protrusions": first["protrusions"], "outputs": outputs,
           "seconds": sum(p["seconds"] for p in parts), "kernel_seconds": sum(p["kernel_seconds"] for p in parts),
           "error": "; ".join(errors) if errors else None, "realisations": n,
           "seeds": sum((list(p["seeds"]) for p in parts), [])}
    if first.get("first_record", 0):
        rec["first_record"] = first["first_record"]
    return rec


def join_records(records: Sequence[dict[str, Any]], first: int | None) -> dict[str, Any]:
    """One part of an ensemble from its single-record parts (:func:`evaluate` with ``records = (r, r + 1)``, in
    record order): the record :func:`evaluate` gives for the part as a whole, but for the times. ``first``: the
    part's first record (None: the part is the whole ensemble, whose record does not name it: the rule
    :func:`join_parts` cannot apply, not knowing whether its parts make the whole)."""
    rec = join_parts(records)
    rec.pop("first_record", None)
    if first is not None:
        rec["first_record"] = int(first)
    return rec


def evaluate_batch(base: Any, params: Sequence[Parameter], rows: Sequence[tuple[str, Sequence[float]]],
                   protrusions: Sequence[float], inputs: SimulationInputs, realisations: int = 1,
                   records: tuple[int, int] | None = None) -> list[tuple[str, dict[str, Any]]]:
    """One fan-out task: evaluate the candidates ``rows = [(key, values), ...]`` (executed on a worker), on the
    DMW records ``records`` of the ensemble (:func:`evaluate`; None: all)."""
    return [(key, evaluate(base, params, values, protrusions, inputs, realisations, records)) for key, values in rows]


class EvaluationStore:
    """Finished evaluations, appended as JSON lines to ``path`` as they arrive (the resume point).

    Each line is ``{"key": ..., **record}``. A line cut short by a kill is ignored when reading, so
    the store never blocks a resume; a record is written once, flushed and synced.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.records: dict[str, dict[str, Any]] = {}
        text = self.path.read_text() if self.path.is_file() else ""
        for line in text.splitlines():
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(rec, dict) and "key" in rec and rec["key"] not in self.records:
                self.records[rec["key"]] = rec
        # a last line cut short by a kill: the next write ends it first, so new records start on their own line
        self._cut = bool(text) and not text.endswith("\n")

    def __contains__(self, key: str) -> bool:
        return key in self.records

    def __getitem__(self, key: str) -> dict[str, Any]:
        return self.records[key]

    def put(self, items: Iterable[tuple[str, dict[str, Any]]]) -> None:
        """Append ``(key, record)`` pairs not yet stored: one write, flushed and synced."""
        new = {k: {"key": k, **rec} for k, rec in items if k not in self.records}
        if not new:
            return
        lines = "".join(json.dumps(rec, allow_nan=True) + "\n" for rec in new.values())
        append_text(self.path, ("\n" if self._cut else "") + lines, sync=True)
        self._cut = False
        self.records.update(new)


@dataclass
class Evaluator:
    """Evaluates sets of candidates of one base scene on the fan-out, through the store.

    ``scheduler``/``workers`` as in :func:`pipeline.fanout.run_tasks`; ``task`` is the batch function
    (:func:`evaluate_batch`, or a stand-in with its signature for tests of the statistics).
    """

    base: Any
    params: Sequence[Parameter]
    protrusions: Sequence[float]
    inputs: SimulationInputs
    store: EvaluationStore
    batch_size: int = 8
    scheduler: str | None = None
    workers: int | None = None
    task: Callable[..., list] = evaluate_batch
    realisations: int = 1
    #: the racing stages (:class:`pipeline.analyses.identification.Racing`): DMW record counts, the last
    #: ``realisations``; an ensemble is then run and stored in the parts between them, and a call may ask
    #: for its first records only (``upto``). Empty: whole evaluations only.
    stages: tuple[int, ...] = ()
    batch_seconds: float = 0.0
    evaluated: int = 0
    kernel_seconds: float = 0.0
    #: (candidate, DMW record) pairs computed by this evaluator (read back from the store: not counted)
    record_evaluations: int = 0

    def __post_init__(self) -> None:
        self.base_hash = base_key(self.base, self.inputs)

    def key(self, values: Sequence[float], records: tuple[int, int] | None = None) -> str:
        return evaluation_key(self.base_hash, self.params, values, self.protrusions, self.realisations, records)

    def __call__(self, points: Iterable[Sequence[float]], upto: int | None = None) -> list[dict[str, Any]]:
        """Records of ``points`` (each a vector of parameter values), evaluating only what the store lacks.

        ``upto`` (with :attr:`stages`; one of them): each record on its first ``upto`` DMW records only,
        made of the parts between the stages (those the store holds are read back). Every record's ``key``
        is the whole evaluation's, whatever part of it is there."""
        if self.stages:
            return self._parts([[float(v) for v in x] for x in points], upto or self.realisations)
        pts = [[float(v) for v in x] for x in points]
        keys = [self.key(x) for x in pts]
        todo: dict[str, list[float]] = {}
        for k, x in zip(keys, pts):
            if k not in self.store and k not in todo:
                todo[k] = x
        rows = list(todo.items())
        # (the realisations only when > 1: a single-record task keeps the signature of the tests' stand-ins)
        extra = (self.realisations,) if self.realisations > 1 else ()
        tasks = [(self.base, list(self.params), chunk, list(self.protrusions), self.inputs) + extra
                 for chunk in self._batches(rows)]

        if tasks:
            self.batch_seconds += run_tasks(self.task, tasks, scheduler=self.scheduler, workers=self.workers,
                                            on_done=self.store.put)
            self.evaluated += len(rows)
            self.record_evaluations += len(rows) * self.realisations
            self.kernel_seconds += sum(self.store[k]["kernel_seconds"] for k in todo)
        return [self.store[k] for k in keys]

    def _batches(self, rows: list[tuple[str, list[float]]]) -> list[list[tuple[str, list[float]]]]:
        """``rows`` in tasks of at most :attr:`batch_size` candidates; on the local fan-out (threads of this
        process), as many tasks as a multiple of its workers, of near-equal size, so that a short batch (the
        last racing stage's few candidates, a walk's round) keeps every core busy: a candidate's evaluation
        does not depend on the task it runs in (the caches of a process are by key)."""
        if not rows:
            return []
        n = -(-len(rows) // self.batch_size)
        if self.scheduler is None or self.scheduler in LOCAL:
            w = local_workers(self.workers, len(rows))
            n = min(len(rows), w * -(-n // w))
        size, extra = divmod(len(rows), n)
        ends = np.cumsum([size + (i < extra) for i in range(n)])
        return [rows[e - size - (i < extra):e] for i, e in enumerate(ends)]

    def _threads(self, units: int) -> int:
        """The threads of this process that ``units`` (candidate, DMW record) runs would share: the local
        fan-out's workers on threads (None, or ``"threads"``), else 1 (one process, or other processes, where
        a task carries the base scene and inputs and a candidate is not kept between tasks)."""
        if self.scheduler not in (None, "threads") or units < 2:
            return 1
        return local_workers(self.workers, units)

    def _record_tasks(self, todo: dict[tuple[int, int], dict[str, list[float]]]
                      ) -> tuple[list[tuple], Callable[[list], None], Callable[[], None]]:
        """The racing parts ``todo`` (part -> {key: values}) as one task per (candidate, DMW record), for the
        threads of this process: ``(tasks, on_done, finish)``; ``finish()`` stores each part, its records joined
        (:func:`join_records`). A part's records do not depend on the task they run in (the candidate is kept
        between them, :class:`Candidates`), so the parts stored are those of :meth:`_batches`'s tasks, bit for
        bit; but a lone candidate's part (a walk's poll, the last racing stage's survivor) no longer runs on one
        thread while the other idles. Record-major order within blocks of as many candidates as threads: two
        threads start two candidates, not one twice, and a candidate's next record follows within a block, while
        its TFC tables are kept (:data:`TABLES_KEPT`)."""
        n = self.realisations
        threads = self._threads(sum(len(rows) * (b - a) for (a, b), rows in todo.items()))
        block: dict[tuple[float, ...], int] = {}  # (a candidate's block: its first appearance, by threads)
        for rows in todo.values():
            for x in rows.values():
                block.setdefault(tuple(x), len(block) // threads)
        units = sorted(((r, a, b, key, x) for (a, b), rows in todo.items() for key, x in rows.items()
                        for r in range(a, b)), key=lambda u: (block[tuple(u[4])], u[0]))
        tasks = [(self.base, list(self.params), [(key, x)], list(self.protrusions), self.inputs, n, (r, r + 1))
                 for r, a, b, key, x in units]
        pieces: dict[str, list[dict[str, Any]]] = {key: [] for (a, b), rows in todo.items() for key in rows}

        def on_done(result: list) -> None:
            for key, rec in result:
                pieces[key].append(rec)

        def finish() -> None:
            for (a, b), rows in todo.items():
                self.store.put([(key, join_records(sorted(pieces[key], key=lambda r: r["first_record"]),
                                                   a if (a, b) != (0, n) else None)) for key in rows])
        return tasks, on_done, finish

    def _parts(self, pts: list[list[float]], upto: int) -> list[dict[str, Any]]:
        """:meth:`__call__` with racing stages: the parts up to ``upto`` records, one fan-out for all."""
        n = self.realisations
        if upto not in self.stages:
            raise ValueError(f"records {upto}: expected one of the racing stages {self.stages}")
        bounds = [0, *[s for s in self.stages if s <= upto]]
        segments = list(zip(bounds[:-1], bounds[1:]))
        todo: dict[tuple[int, int], dict[str, list[float]]] = {seg: {} for seg in segments}
        for x in pts:
            if self.key(x) in self.store:  # (a whole evaluation, of the full method: its first records are the part)
                continue
            for seg in segments:
                k = self.key(x, seg)
                if k not in self.store:
                    todo[seg][k] = x
        units = sum((len(rows) * (b - a) for (a, b), rows in todo.items()), 0)
        if self._threads(units) > 1:
            tasks, on_done, finish = self._record_tasks(todo)
        else:
            tasks = []
            for (a, b), rows in todo.items():
                tasks += [(self.base, list(self.params), chunk, list(self.protrusions), self.inputs, n, (a, b))
                          for chunk in self._batches(list(rows.items()))]
            on_done, finish = self.store.put, (lambda: None)
        if tasks:
            self.batch_seconds += run_tasks(self.task, tasks, scheduler=self.scheduler, workers=self.workers,
                                            on_done=on_done)
            finish()
            for (a, b), rows in todo.items():
                self.evaluated += len(rows)
                self.record_evaluations += len(rows) * (b - a)
                self.kernel_seconds += sum(self.store[k]["kernel_seconds"] for k in rows)
        out = []
        for x in pts:
            whole = self.key(x)
            if whole in self.store:
                rec = head(self.store[whole], upto)
            else:
                rec = join_parts([self.store[self.key(x, seg)] for seg in segments])
            out.append({**rec, "key": whole})
        return out


def setup(scene: Any, stage_inputs: Any, section: str, force: bool = False) -> tuple[list[Parameter], SimulationInputs, EvaluationStore]:
    """The free parameters of ``[section]``, the base inputs of the study stage (``stage_inputs``, its
    :class:`pipeline.runner.Inputs`: the upstream datasets the runner made current, by file and key; k is
    each candidate's own) and the evaluation store ``<results>/<section>.evals.jsonl`` (emptied first with
    ``force``)."""
    where = str(scene.path) if scene.path else "<scene>"
    params = parse_parameters(scene[section]["parameters"], where, f"{section}.parameters")
    inputs = for_stage(scene, stage_inputs, calibration=False)
    store_path = Path(stage_inputs.out) / f"{section}.evals.jsonl"
    if force:
        refuse_links(store_path).unlink(missing_ok=True)
    return params, inputs, EvaluationStore(store_path)


def prepare_inputs(scene: Any, out: Path) -> SimulationInputs:
    """The base scene's inputs in ``out``, made current by the runner, by file and the inputs keys they
    carry (scripts and tests; a study stage uses :func:`setup`)."""
    return current_inputs(scene, out, calibration=False)
