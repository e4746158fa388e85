"""Stage ``sweep``: protrusion x roughness x damping, fanned out by :func:`pipeline.fanout.run_tasks`.

Each task runs a *batch* of scenes (``[sweep] batch_size`` protrusions of one roughness set
and one damping ratio) and writes its own part file, atomically, into ``sweep.parts/``. The DMW
record and the interface tables reach the workers by file path (``dmw.nc``, ``interface.nc`` or
``sweep.parts/interface-<label>/interface.nc``, and ``bulge.nc`` with the tabulated bulge bearing), not
inside the task graph. The parts are assembled into ``sweep.nc`` (dims ``protrusion``, ``roughness``,
``damping``) and ``sweep_histories.nc`` (time histories of the protrusions in ``histories_nm``) by an
:class:`pipeline.analyses.sweep_assembly.Assembler`: the parts computed by this call from memory as each batch
returns its dataset with its path (while the other batches run), the parts of an earlier run from their files at
the end; ``sweep_histories.nc`` is handed to the runner once the batches that keep histories are in
(:func:`history_batches`) and a worker has no batch left to start (:meth:`pipeline.runner.Inputs.write_early`),
so that its write fills that worker's idle end of the fan-out instead of ending the command. The part files'
format and the rule that keeps one are :mod:`pipeline.model.sweep_parts` (a batch's variables stacked by
dimensions, read back as the batch's dataset itself).

Resuming: a part is kept when it carries the sweep's inputs key (:mod:`pipeline.runner`: the scene,
the bytes of every AFM scan of every roughness set, the DMW and calibration datasets), its own batch
index and its batch's coordinates (roughness label, damping ratio, protrusions), so an interrupted
sweep (Ctrl-C, kill, a lost worker) picks up where it stopped and gives a dataset identical to an
uninterrupted run (every batch is a deterministic function of its inputs; no timings or folder paths
are stored in the datasets: the batch-phase wall time goes to the run log, ``.hdi/runs.jsonl``). A part
copied to another batch's name, made for other inputs, or damaged since it was written (its values differ from
their checksums, :func:`pipeline.model.sweep_parts.part_problem`) is recomputed. The interface tables of
the other roughness sets are kept by the runner under their own inputs keys (:func:`table_jobs`).

Execution: :func:`pipeline.fanout.run_tasks` (by default a pool of one thread per core in this
process, the kernels releasing the GIL; ``scheduler="ADDRESS"`` attaches to a running
dask.distributed cluster; ``scheduler="synchronous"`` runs the batches one after the other), in two
rounds (:func:`sweep_task`): the other roughness sets' interface tables as tasks alongside the batches
that do not read them, then the batches of those sets.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import threading
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np
import xarray as xr

from ..model import assembly
from ..fanout import LOCAL, local_cluster, local_workers, run_tasks
from ..progress import Progress
from ..io import write_dataset
from ..paths import refuse_links
from ..runner import KEY_ATTR, Inputs, Stage, ensure
from ..variables import RUN_GRID_DIMS
from ..model import dmw_record, interface_tables, scene_inputs
from ..model.inputs import SimulationInputs, Source, for_stage
from ..model.interface_tables import used_statistics
from ..model.simulation import GRID_ATTRS, grid_run_values, model_attrs, simulate
from ..model.sweep_parts import PARTS, Batch, kept_parts, pack_part, part_path, part_problem
from ..analyses.sweep_assembly import Assembler
from ..config.heater_power import ACTUATION_FIELDS
from ..config.grid import damping_grid, protrusion_grid, roughness_sets, same_point

log = logging.getLogger(__name__)


def plan(scene: Any) -> tuple[np.ndarray, dict[str, dict], list[float], list[Batch]]:
    """The grid and its batches (realisation-major, then roughness, then damping, then protrusion).

    With ``sweep.protocol = "stepping"`` a batch is a whole chain (every protrusion of one roughness
    set, damping ratio and realisation) and ``batch_size`` is ignored.

    Returns ``(protrusions [nm], roughness sets by label, damping ratios [1], batches)``.
    """
    prot = protrusion_grid(scene)
    sets = roughness_sets(scene)
    damp = damping_grid(scene)
    # a heater-stepping chain runs the whole grid in order: one chain, one batch
    size = len(prot) if scene["sweep"]["protocol"] == "stepping" else scene["sweep"]["batch_size"]
    batches = []
    for r in range(scene["sweep"]["realisations"]):
        for label in sets:
            for dz in damp:
                for start in range(0, len(prot), size):
                    idx = tuple(range(start, min(start + size, len(prot))))
                    batches.append(Batch(len(batches), label, float(dz), idx, tuple(float(prot[i]) for i in idx), r))
    return prot, sets, damp, batches

_MODELS: dict[tuple, assembly.Model] = {}
_MODELS_LOCK = threading.Lock()


def batch_model(scene: Any, inputs: SimulationInputs, damping: float) -> assembly.Model:
    """The model of a batch, built once per process for each scene, inputs and damping ratio.

    The batches of one roughness set and damping ratio share it (:func:`pipeline.model.running.run_model`
    only reads a model): building it costs ~28 ms (the DMW record's spline, the modal solution), paid
    by every batch before. Keyed by the scene's content hash and the inputs' identity
    (:meth:`pipeline.model.inputs.SimulationInputs.identity`: their stage keys and k), so changed inputs
    build a new one; the inputs themselves are read once per process (:func:`pipeline.model.inputs.cached`).
    """
    key = (scene.hash, inputs.identity(), damping)
    with _MODELS_LOCK:
        model = _MODELS.get(key)
    if model is None:
        model = inputs.model(scene, damping_ratio=damping)
        with _MODELS_LOCK:
            if len(_MODELS) >= 64:  # (a long-lived worker of many studies: keep the memory bounded)
                _MODELS.clear()
            model = _MODELS.setdefault(key, model)
    return model


def run_batch(scene: Any, batch: Batch, inputs: SimulationInputs, path: str, key: str,
              history_nm: tuple[float, ...]) -> tuple[str, xr.Dataset]:
    """Run one batch and write its part file (executed on a worker). Returns the part's path and dataset.

    The dataset comes back with the path so that the sweep assembles what this run computed from
    memory and reads back only the parts of an earlier, interrupted run.

    ``scene``: the sweep's scene with the batch's roughness set; ``inputs``: its set's interface tables,
    the batch's DMW record, the bulge table and k (by file and key: read on the worker, once per process);
    ``path``: the part file (:func:`pipeline.model.sweep_parts.part_path`); ``history_nm``: protrusions [nm]
    whose time histories the part keeps.
    """
    model = batch_model(scene, inputs, batch.damping)
    ds = simulate(model, batch.protrusions, histories=history_nm, protocol=scene["sweep"]["protocol"])
    ds.attrs.update({KEY_ATTR: key, "roughness_label": batch.label, "damping_ratio": batch.damping,
                     "batch": batch.index, "realisation": batch.realisation})
    # (uncompressed: a part is read back once, if ever, and its zlib ran under the process's NetCDF lock,
    # where the other worker's part waited for it; docs/performance.md, section "The head of a command")
    write_dataset(pack_part(ds), path, scene, stage="sweep-part", compress=False)
    return path, ds

def _progress(total: int, initial: int) -> Progress:
    """The batches counted (:class:`pipeline.progress.Progress`: a bar on a terminal, periodic lines in a
    log, nothing with ``-q``), those of an earlier run included."""
    return Progress(total, unit="batch", label="sweep", initial=initial).start()


def table_jobs(scene: Any, out: Path, sets: dict[str, dict]) -> tuple[dict[str, str | None], dict[str, tuple]]:
    """Where each roughness set's interface tables are read from, and the tables still to be made current.

    The scene's own set uses the interface stage's ``interface.nc`` (upstream of the sweep: current).
    Another set's tables are the interface stage of the scene with that ``[roughness]``, made current
    by the runner in ``sweep.parts/interface-<label>/`` (with its ``roughness.nc`` for an AFM set), so
    they are recomputed only when their own inputs change: for those sets, the arguments of
    :func:`make_tables` (the set's scene and folder), run as tasks of the fan-out.

    Returns ``(paths, jobs)``: label -> path of its ``interface.nc`` (``None``: the set reads no tables);
    label -> ``(scene, folder)``.
    """
    parts = refuse_links(out / PARTS)  # (its parts may be written by worker processes, which hold no folder)
    parts.mkdir(parents=True, exist_ok=True)
    interface_paths: dict[str, str | None] = {}
    jobs: dict[str, tuple] = {}
    for label, table in sets.items():
        if not scene_inputs.needs_interface(scene.replace(roughness=dict(table))):
            interface_paths[label] = None
        elif table == dict(scene["roughness"]):
            interface_paths[label] = str(out / "interface.nc")
        else:
            folder = parts / f"interface-{label}"
            interface_paths[label] = str(folder / "interface.nc")
            jobs[label] = (scene.replace(roughness=dict(table)), str(folder))
    return interface_paths, jobs


def make_tables(scene: Any, folder: str, force: bool = False) -> str:
    """Make a roughness set's interface tables current in ``folder`` (the runner's interface stage of the
    set's ``scene``, under their own inputs key; executed as a task); returns the path of ``interface.nc``."""
    return str(ensure("interface", scene, folder, force=force))


def prepare_inputs(scene: Any, out: Path, sets: dict[str, dict],
                   force: bool = False) -> tuple[dict[str, str | None], str | None]:
    """Interface tables per roughness set and the DMW record, as the paths of files the workers read,
    the tables made current here, one set after the other (:func:`table_jobs`; the sweep itself runs
    them as tasks of its fan-out, :func:`compute`). The records of realisations beyond the first:
    :func:`realisation_inputs`.
    """
    interface_paths, jobs = table_jobs(scene, out, sets)
    for label, (sub, folder) in jobs.items():
        interface_paths[label] = make_tables(sub, folder, force)
    dmw_path = str(out / "dmw.nc") if scene.has("dmw") else None
    return interface_paths, dmw_path


def realisation_record(scene: Any, folder: Path, seed: int, force: bool = False) -> Path:
    """``folder/dmw.nc``: the scene's synthetic record with ``dmw.seed = seed`` (kept when up to date)."""
    if scene["dmw"]["source"] != "synthetic":
        where = str(scene.path) if getattr(scene, "path", None) else "<scene>"
        raise ValueError(f"{where}: sweep.realisations > 1 needs dmw.source = \"synthetic\" (a measured record "
                         f"has one realisation); got dmw.source = {scene['dmw']['source']!r}")
    return ensure("dmw", scene.replace(dmw={"seed": int(seed)}), folder, force=force)


def realisation_inputs(scene: Any, out: Path, dmw_path: str | None, force: bool = False) -> tuple[list[str | None], list[int]]:
    """DMW record paths and seeds of the ``[sweep] realisations`` (realisation 0: the scene's ``dmw.nc``).

    Records of realisations ``r >= 1`` are written once into ``sweep.parts/dmw-<r>/dmw.nc``
    (:func:`pipeline.model.dmw_record.realisation_seeds`); workers read them by path.
    """
    n = scene["sweep"]["realisations"]
    if n == 1:
        return [dmw_path], [scene["dmw"]["seed"]]
    if dmw_path is None:
        where = str(scene.path) if scene.path else "<scene>"
        raise ValueError(f"{where}: sweep.realisations = {n} needs the dmw effect in scene.effects "
                         "(the realisations are DMW records)")
    seeds = dmw_record.realisation_seeds(scene["dmw"]["seed"], n)
    paths: list[str | None] = [dmw_path]
    for r in range(1, n):
        paths.append(str(realisation_record(scene, out / PARTS / f"dmw-{r:05d}", seeds[r], force)))
    return paths, seeds


def batch_inputs(sim: SimulationInputs, interface_path: str | None, dmw_path: str | None) -> SimulationInputs:
    """``sim`` (the scene's own inputs: k, the bulge table) with the interface tables of ``interface_path``
    (a roughness set's, ``None``: the set reads none) and the DMW record of ``dmw_path`` (a realisation's),
    by file: the keys of files beyond the scene's own are those they carry."""
    def source(stage: str, own: Source | None, path: str | None) -> Source | None:
        if path is None:
            return None
        return own if own is not None and own.path == path else Source.file(stage, path)
    return replace(sim, interface=source("interface", sim.interface, interface_path),
                   dmw=source("dmw", sim.dmw, dmw_path))


def compute(scene: Any, inputs: Inputs) -> dict[str, xr.Dataset | None]:
    """Run (or resume) the sweep; returns ``sweep.nc`` and ``sweep_histories.nc`` (module docstring).

    Options (``inputs.options``): ``scheduler``, ``workers``; for tests of resuming and failures,
    ``stop_after`` (raise ``KeyboardInterrupt`` after that many batches finish in this call) and
    ``on_batch`` (called with each finished part's path); ``force`` recomputes every part.
    """
    out, key, opts = inputs.out, inputs.key, inputs.options
    prot, sets, damp, batches = plan(scene)
    sim = for_stage(scene, inputs)  # (k, the bulge table and the scene's own record and tables)
    force = bool(opts.get("force"))
    interface_paths, table_tasks = table_jobs(scene, out, sets)
    dmw_path = str(out / "dmw.nc") if scene.has("dmw") else None
    dmw_paths, seeds = realisation_inputs(scene, out, dmw_path, force)
    todo = batches_to_run(batches, out / PARTS, key, force)
    grid = Assembler(scene, prot, list(sets), damp, len(seeds))
    fan = _Fanout(scene, inputs, sim, (sets, damp), (interface_paths, dmw_paths), (batches, todo), grid)
    batch_seconds = fan.run(table_tasks, force)
    log.info("sweep: batch phase %.2f s for %d batches and %d tables", batch_seconds, len(todo), len(table_tasks))
    inputs.record(compute_seconds=round(batch_seconds, 3), batches_run=len(todo), batches=len(batches))
    for b, part in kept_parts(out / PARTS, batches, key, grid.added):
        grid.add(b, part)
    run, attrs, stats = fan.grid_values()
    return grid.datasets(key, sim.k_source, attrs, seeds, run, statistics=stats)


def batches_to_run(batches: list[Batch], parts: Path, key: str, force: bool) -> list[Batch]:
    """The batches whose part in ``parts`` cannot be kept (:func:`pipeline.model.sweep_parts.part_problem`;
    every batch with ``force``), in batch order; why each part present is recomputed goes to the log."""
    todo = []
    for b in batches:
        why = "forced" if force else part_problem(part_path(parts, b), key, b)
        if why is not None:
            if why != "missing":
                log.info("sweep: batch %d: part %s: recomputed", b.index, why)
            todo.append(b)
    log.info("sweep: %d batches, %d to run", len(batches), len(todo))
    return todo


class _Fanout:
    """One call's fan-out of the sweep (:func:`compute`): the batches' tasks (:meth:`task`), their parts added to
    the :class:`~pipeline.analyses.sweep_assembly.Assembler` as each returns (:meth:`on_done`),
    ``sweep_histories.nc`` handed to the runner once it is complete and a worker is idle, and the run values
    of the datasets (:meth:`grid_values`).

    ``grid_axes``: the roughness sets by label and the damping ratios [1]; ``paths``: the interface tables'
    path per set (filled in as another set's tables are made) and the DMW records' per realisation;
    ``work``: every batch of the grid and those to run.
    """

    def __init__(self, scene: Any, inputs: Inputs, sim: SimulationInputs,
                 grid_axes: tuple[dict[str, dict], list[float]],
                 paths: tuple[dict[str, str | None], list[str | None]],
                 work: tuple[list[Batch], list[Batch]], grid: Assembler):
        self.scene, self.inputs, self.sim, self.grid = scene, inputs, sim, grid
        (self.sets, self.damp), (self.interface_paths, self.dmw_paths) = grid_axes, paths
        self.batches, self.todo = work
        self.parts, opts = inputs.out / PARTS, inputs.options
        # time histories of the first realisation only (the scene's own record)
        self.hist_nm = tuple(scene["sweep"]["histories_nm"] or scene["report"]["histories_nm"])
        # each batch runs the scene with its roughness set: the tables are the set's, and so must be the
        # scene the model reads (y_s of explicit statistics when a set needs no tables)
        self.set_scenes = {label: scene if table == dict(scene["roughness"]) else scene.replace(roughness=dict(table))
                           for label, table in self.sets.items()}
        # each set's and realisation's inputs once (a file's key is read from it: a set's tables once made)
        self.batch_sim = functools.cache(
            lambda label, r: batch_inputs(sim, self.interface_paths[label], self.dmw_paths[r]))
        self.by_path = {str(part_path(self.parts, b)): b for b in self.todo}
        self.stop_after, self.on_batch = opts.get("stop_after"), opts.get("on_batch")
        self.done = 0
        # sweep_histories.nc is complete once the batches that keep histories are in; it is written as soon as a
        # worker also has no batch left to start (fewer batches to finish than local workers), so that its
        # compression (most of the command's final write) fills that worker's idle end of the fan-out instead of
        # following the last batch, without taking a core from a batch earlier (measured: docs/performance.md)
        self.hist_batches = history_batches(self.batches, self.hist_nm)
        # (kept parts come in at the end)
        self.early = not self.hist_batches or not self.hist_batches <= {b.index for b in self.todo}
        self.slots = 1
        self.bar: Progress | None = None

    def task(self, b: Batch) -> tuple:
        """The fan-out task of batch ``b`` (:func:`sweep_task`, ``kind = "batch"``)."""
        return ("batch", self.set_scenes[b.label], b, self.batch_sim(b.label, b.realisation),
                str(part_path(self.parts, b)), self.inputs.key, self.hist_nm if b.realisation == 0 else ())

    def grid_values(self) -> tuple[dict[str, xr.Variable], dict[str, Any], dict[str, dict[str, Any]]]:
        """The run values, attributes and each set's statistics of the datasets (every set's batches run)."""
        labels, damp, k_source = list(self.sets), self.damp, self.sim.k_source
        # the run values of every set and damping ratio (the models the batches built, cached in this process)
        models = {(label, float(d)): batch_model(self.set_scenes[label], self.batch_sim(label, 0), float(d))
                  for label in self.sets for d in damp}
        run = grid_run_values(models, labels, damp, k_source)
        sizes = {"roughness": len(labels), "damping": len(damp)}
        attrs = {name: value for name, value in model_attrs(models[(labels[0], float(damp[0]))], k_source).items()
                 if name not in GRID_ATTRS or sizes[RUN_GRID_DIMS[GRID_ATTRS[name]]] == 1}  # (several: the variable has them)
        # each set's statistics as its interface model used them: its tables' (the scans'), or the given keys
        # (the tables as the batches read them: in this process's cache after a threaded batch phase)
        stats = {label: used_statistics(self.set_scenes[label], self.batch_sim(label, 0).tables()) for label in labels}
        return run, attrs, stats

    def on_done(self, result: tuple[str, Any]) -> None:
        """A task's result, in the calling thread: a set's tables' path, or a batch's part added to the grid
        (while the other batches run); the histories handed over once complete and a worker is idle."""
        kind, value = result
        if kind == "tables":
            label, path = value
            self.interface_paths[label] = path
            return
        path, part = value
        self.grid.add(self.by_path[path], part)
        self.done += 1
        if self.on_batch is not None:
            self.on_batch(path)
        if self.bar is not None:
            self.bar.update(1)
        if not self.early and self.hist_batches <= self.grid.added and len(self.todo) - self.done < self.slots:
            self.early = True
            run, attrs, stats = self.grid_values()
            self.inputs.write_early("sweep_histories.nc",
                                    self.grid.histories(self.sim.k_source, attrs, run, statistics=stats))
        if self.stop_after is not None and self.done >= self.stop_after:
            raise KeyboardInterrupt(f"stopped after {self.done} batches (stop_after)")

    def rounds(self, table_tasks: dict[str, tuple], force: bool) -> tuple[list[tuple], list[Batch]]:
        """The tasks of the first round and the batches of the second; sets :attr:`slots`, the local workers.

        Two rounds of one fan-out each: the other roughness sets' interface tables with the batches that do
        not read them (the tables first: a pool starts tasks in order), then the batches of those sets.
        A table is mostly Python and numpy holding the GIL, a batch mostly the kernel releasing it: the tables
        alternate with batches, so that two threads run a table and a batch rather than two tables.
        """
        opts, todo = self.inputs.options, self.todo
        tables = [("tables", label, sub, folder, force) for label, (sub, folder) in table_tasks.items()]
        workers = opts.get("workers")
        # (one worker runs them in batch order: the order matters only to several)
        where = opts.get("scheduler")
        serial = where == "synchronous" or (where is None and local_workers(workers, max(len(todo), 1)) == 1)
        order = list if serial else costliest_first
        # (a cluster of other machines leaves this process's cores idle: the histories are written at once)
        self.slots = 1 if serial else local_workers(workers, max(len(todo), 1)) if where in LOCAL + (None,) \
            else len(todo) + 1
        ready = [self.task(b) for b in order(b for b in todo if b.label not in table_tasks)]
        first = [t for pair in zip(tables, ready) for t in pair] + tables[len(ready):] + ready[len(tables):]
        return first, order(b for b in todo if b.label in table_tasks)

    def run(self, table_tasks: dict[str, tuple], force: bool) -> float:
        """Run both rounds (:meth:`rounds`) with the progress of the batches; returns their wall time [s]."""
        opts = self.inputs.options
        self.bar = _progress(len(self.batches), len(self.batches) - len(self.todo))
        first, later = self.rounds(table_tasks, force)
        workers, batch_seconds = opts.get("workers"), 0.0
        try:  # (one process cluster for both rounds: its start-up is paid once)
            with local_cluster(opts.get("scheduler"), workers) if first or later else \
                    contextlib.nullcontext(opts.get("scheduler")) as scheduler:
                # (the second round's tasks are made once the tables exist: their inputs carry the tables' key)
                for tasks in (first, lambda: [self.task(b) for b in later]):
                    tasks = tasks() if callable(tasks) else tasks
                    batch_seconds += run_tasks(sweep_task, tasks, scheduler=scheduler, workers=workers,
                                               on_done=self.on_done)
        finally:
            if self.bar is not None:
                self.bar.close()
        return batch_seconds


def history_batches(batches: Iterable[Batch], histories_nm: Iterable[float]) -> set[int]:
    """The indices of the batches whose parts keep time histories: those of the first realisation with a
    protrusion of ``histories_nm`` [nm] (the grid's point rule, :func:`pipeline.config.grid.same_point`, as
    :func:`pipeline.model.simulation.simulate` keeps them)."""
    hist = list(histories_nm)
    return {b.index for b in batches
            if b.realisation == 0 and any(np.any(same_point(np.asarray(b.protrusions), h)) for h in hist)}


def costliest_first(batches: Iterable[Batch]) -> list[Batch]:
    """``batches`` in the order a fan-out round starts them: those reaching the highest protrusion first.

    A run in contact costs the kernel ~3x a flying one (docs/performance.md), and contact comes with the
    protrusion, so the batches of the top of the grid are the longest. Started first, they leave short
    batches for the end of the round, where one worker would otherwise wait for the other's long one
    (twice per sweep: each round ends with all its tasks). The order of the parts does not change the
    datasets (:class:`Assembler`)."""
    return sorted(batches, key=lambda b: -max(b.protrusions, default=0.0))


def sweep_task(kind: str, *args: Any) -> tuple[str, Any]:
    """One task of the sweep's fan-out (executed on a worker): ``kind = "tables"`` with ``(label, scene,
    folder, force)`` makes a roughness set's interface tables current (:func:`make_tables`; returns
    ``("tables", (label, path))``), ``kind = "batch"`` runs :func:`run_batch` with ``args`` (returns
    ``("batch", (part path, part))``)."""
    if kind == "tables":
        label, scene, folder, force = args
        return kind, (label, make_tables(scene, folder, force))
    return kind, run_batch(*args)


def run_sweep(scene: Any, out: Path, scheduler: str | None = None, workers: int | None = None,
              force: bool = False, stop_after: int | None = None,
              on_batch: Callable[[str], None] | None = None) -> Path:
    """Make ``sweep.nc`` current in ``out`` (running, resuming or keeping the sweep); see :func:`compute`."""
    return ensure("sweep", scene, out, force=force, scheduler=scheduler, workers=workers,
                  stop_after=stop_after, on_batch=on_batch)

def _files(scene: Any) -> dict[str, str]:
    """The AFM scans of every roughness set (their bytes are inputs of the sweep)."""
    return {f"sweep.roughness[{label}].afm[{i}]": f
            for label, table in roughness_sets(scene).items() for i, f in enumerate(table.get("afm") or [])}


def _keeps(scene: Any) -> tuple[str, ...]:
    """The longest paths the sweep keeps in the results folder: a part, another set's interface tables
    (with its roughness dataset) and a realisation's DMW record."""
    others = [label for label, table in roughness_sets(scene).items() if table != dict(scene["roughness"])]
    kept = [f"{PARTS}/batch-00000.nc"]
    if others:  # (another set's tables: prepare_inputs)
        longest = max(others, key=len)
        kept += [f"{PARTS}/interface-{longest}/roughness.nc", f"{PARTS}/interface-{longest}/interface.nc"]
    if scene["sweep"]["realisations"] > 1:
        kept.append(f"{PARTS}/dmw-00000/dmw.nc")
    return tuple(kept)


STAGE = Stage(
    "sweep", compute, simulates=True, outputs=("sweep.nc", "sweep_histories.nc"),
    # what a simulation reads, the grid and its histories, the heater's actuation, and what the sweep makes
    # itself: the interface tables of its other roughness sets, the DMW records of its realisations
    reads=(*scene_inputs.SIMULATION_FIELDS, "sweep.*", "report.histories_nm", *ACTUATION_FIELDS,
           *interface_tables.FIELDS, *dmw_record.FIELDS),
    # (the batch size changes how the work is cut, not the result: parts of another cut are rejected; the
    # other sets' tables depend on the single protrusion through the deepest protrusion, which the interface
    # stage's key holds, upstream)
    unkeyed=("sweep.batch_size", "tfc.protrusion_nm"),
    files=_files, upstream=scene_inputs.input_stages, order=50, main_job=True, keeps=_keeps,
    doc="protrusion x roughness x damping, fanned out, sweep.nc and sweep_histories.nc")
