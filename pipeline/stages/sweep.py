"""Stage ``sweep``: protrusion x roughness x damping, fanned out by :func:`pipeline.fanout.run_tasks`.

Each task runs a *batch* of scenes (``[sweep] batch_size`` protrusions of one roughness set
and one damping ratio) and writes its own part file, atomically, into ``sweep.parts/``. The DMW
record and the interface tables reach the workers by file path (``dmw.nc``, ``interface.nc`` or
``sweep.parts/interface-<label>/interface.nc``, and ``bulge.nc`` with the tabulated bulge bearing), not
inside the task graph. The parts are assembled into ``sweep.nc`` (dims ``protrusion``, ``roughness``,
``damping``) and ``sweep_histories.nc`` (time histories of the protrusions in ``histories_nm``) by an
:class:`Assembler`: the parts computed by this call from memory as each batch returns its dataset with
its path (while the other batches run), the parts of an earlier run from their files at the end;
``sweep_histories.nc`` is handed to the runner once the batches that keep histories are in
(:func:`history_batches`) and a worker has no batch left to start (:meth:`pipeline.runner.Inputs.write_early`),
so that its write fills that worker's idle end of the fan-out instead of ending the command. A part
file holds its batch's variables stacked by dimensions (:func:`pack_part`: two or three NetCDF variables
instead of ~35, each of which cost ~1 ms to write under the process's NetCDF lock) and is read back as the
batch's dataset itself (:func:`read_part`).

Resuming: a part is kept when it carries the sweep's inputs key (:mod:`pipeline.runner`: the scene,
the bytes of every AFM scan of every roughness set, the DMW and calibration datasets), its own batch
index and its batch's coordinates (roughness label, damping ratio, protrusions), so an interrupted
sweep (Ctrl-C, kill, a lost worker) picks up where it stopped and gives a dataset identical to an
uninterrupted run (every batch is a deterministic function of its inputs; no timings or folder paths
are stored in the datasets: the batch-phase wall time goes to the run log, ``.hdi/runs.jsonl``). A part
copied to another batch's name, made for other inputs, or damaged since it was written (its values differ from
their checksums, :func:`pipeline.io.stored_problem`) is recomputed. The interface tables of
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
import json
import logging
import threading
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np
import xarray as xr

from ..model import assembly
from ..fanout import LOCAL, local_cluster, local_workers, run_tasks
from ..progress import Progress
from ..io import file_hash, read_attrs, read_dataset, stored_problem, write_dataset
from ..paths import refuse_links
from ..runner import KEY_ATTR, Inputs, Stage, ensure
from ..variables import (COORDINATES, ENSEMBLE, HISTORIES, PART_STACK, PART_STACKS, RUN_GRID_DIMS, SCALARS, STEPPING,
                         TIME, coordinate, is_part_stack)
from ..model import dmw_record, interface_tables, scene_inputs
from ..model.inputs import SimulationInputs, Source, for_stage
from ..model.interface_tables import used_statistics
from ..model.simulation import DIRECTIONS, GRID_ATTRS, grid_run_values, model_attrs, simulate
from ..analyses import ensemble_rules as ensemble
from ..config.heater_power import ACTUATION_FIELDS, power_coordinates
from ..config.grid import damping_grid, protrusion_grid, roughness_sets, same_point, scene_label

log = logging.getLogger(__name__)
PARTS = "sweep.parts"


@dataclass(frozen=True)
class Batch:
    """One task: protrusions ``indices`` of roughness set ``label`` at damping ``damping``.

    ``damping``: modal damping ratio [1]; ``indices``: positions on the protrusion grid;
    ``protrusions``: their values [nm]; ``realisation``: index of the DMW record (0: the scene's).
    """

    index: int
    label: str
    damping: float
    indices: tuple[int, ...]
    protrusions: tuple[float, ...]
    realisation: int = 0


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


def _part_path(parts: Path, b: Batch) -> Path:
    return parts / f"batch-{b.index:05d}.nc"


def part_problem(path: Path, key: str, batch: Batch) -> str | None:
    """Why a part file cannot be used for ``batch`` of the sweep with inputs ``key`` (``None``: it can).

    A part must exist, be readable, carry the sweep's inputs key, and be the part of this very batch:
    its batch index, roughness label, damping ratio and protrusions.
    """
    if not path.is_file():
        return "missing"
    try:
        attrs, values = read_attrs(path, ("protrusion",))
    except (OSError, ValueError, RuntimeError) as exc:  # (RuntimeError: the HDF5 library's "HDF error")
        return f"unreadable ({exc})"
    prot = np.asarray(values.get("protrusion", []), float)
    if attrs.get(KEY_ATTR) != key:
        return "made from other inputs"
    if attrs.get("batch") != batch.index:
        return f"holds batch {attrs.get('batch')}, not {batch.index}"
    if attrs.get("roughness_label") != batch.label or attrs.get("damping_ratio") != batch.damping:
        return (f"holds roughness {attrs.get('roughness_label')!r}, damping {attrs.get('damping_ratio')}; "
                f"expected {batch.label!r}, {batch.damping}")
    if prot.shape != (len(batch.protrusions),) or not np.array_equal(prot, batch.protrusions):
        return f"holds protrusions {prot.tolist()}, expected {list(batch.protrusions)}"
    return stored_problem(path)  # (damaged or edited since written: its values differ from their checksums)


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


def run_batch(scene: Any, batch: Batch, inputs: SimulationInputs, part_path: str, key: str,
              history_nm: tuple[float, ...]) -> tuple[str, xr.Dataset]:
    """Run one batch and write its part file (executed on a worker). Returns the part's path and dataset.

    The dataset comes back with the path so that the sweep assembles what this run computed from
    memory and reads back only the parts of an earlier, interrupted run.

    ``scene``: the sweep's scene with the batch's roughness set; ``inputs``: its set's interface tables,
    the batch's DMW record, the bulge table and k (by file and key: read on the worker, once per process);
    ``history_nm``: protrusions [nm] whose time histories the part keeps.
    """
    model = batch_model(scene, inputs, batch.damping)
    ds = simulate(model, batch.protrusions, histories=history_nm, protocol=scene["sweep"]["protocol"])
    ds.attrs.update({KEY_ATTR: key, "roughness_label": batch.label, "damping_ratio": batch.damping,
                     "batch": batch.index, "realisation": batch.realisation})
    # (uncompressed: a part is read back once, if ever, and its zlib ran under the process's NetCDF lock,
    # where the other worker's part waited for it; docs/performance.md, section "The head of a command")
    write_dataset(pack_part(ds), part_path, scene, stage="sweep-part", compress=False)
    return part_path, ds


#: Global attribute of a part file: its variables as :func:`unpack_part` restores them (JSON).
LAYOUT_ATTR = "part_layout"


def _stack_name(dims: tuple[str, ...]) -> str:
    """The stacked variable of a part that holds its variables of dimensions ``dims``."""
    return PART_STACK + "".join("__" + d for d in dims)


def pack_part(ds: xr.Dataset) -> xr.Dataset:
    """A part (a :func:`pipeline.model.simulation.simulate` dataset) as written to its file: the data
    variables of equal dimensions stacked into one float64 variable along a new first dimension
    (``stack__protrusion``: the scalars, ``stack__hist_protrusion__elapsed_time``: the kept histories),
    with the names and units of its rows as coordinates.

    Why: writing a NetCDF variable costs ~1 ms of Python and HDF5 whatever its size (33 variables: ~50 ms
    per part, under the process's NetCDF lock, holding the GIL most of it), which the threads of a sweep
    cannot share. Float64 holds every value of the parts exactly (float32 and int8 flags included), and
    the global attribute :data:`LAYOUT_ATTR` keeps each variable's name, dtype, attributes and encoding in
    order, so :func:`unpack_part` gives back ``ds`` itself (tests/stages/test_sweep.py).
    """
    variables = {name: ds.variables[name] for name in ds.data_vars}  # (Variables: no DataArray made per name)
    groups: dict[tuple[str, ...], list[str]] = {}
    for name, v in variables.items():
        groups.setdefault(v.dims, []).append(name)
    data: dict[str, xr.Variable] = {}
    coords = {name: ds.variables[name] for name in ds.coords}
    for dims, names in groups.items():
        stack = _stack_name(dims)
        row = f"{stack}_variable"
        data[stack] = PART_STACKS[PART_STACK].data(np.stack([variables[n].values.astype(np.float64) for n in names]),
                                                   (row, *dims), unit_variable=f"{stack}_units")
        coords[row] = PART_STACKS[PART_STACK + "_variable"].data(names, (row,))
        coords[f"{stack}_units"] = PART_STACKS[PART_STACK + "_units"].data(
            [variables[n].attrs.get("units", "") for n in names], (row,))
    layout = []
    for name, v in variables.items():
        enc = {k: np.dtype(val).str if k == "dtype" else _json_value(val) for k, val in v.encoding.items()
               if k in ("_FillValue", "dtype")}
        layout.append([name, v.dtype.str, {k: _json_value(a) for k, a in v.attrs.items()}, enc])
    out = xr.Dataset(data, coords=coords)
    out.attrs = dict(ds.attrs)
    out.attrs[LAYOUT_ATTR] = json.dumps(layout)
    return out


def _json_value(value: Any) -> Any:
    """An attribute's (or encoding's) value for JSON: an array or numpy scalar as its values and dtype
    (restored by :func:`_attr_value`)."""
    if isinstance(value, (np.ndarray, np.generic)):
        return {"array": np.asarray(value).tolist(), "dtype": np.asarray(value).dtype.str,
                "scalar": isinstance(value, np.generic)}
    return value


def _attr_value(value: Any) -> Any:
    """The attribute value :func:`_json_value` wrote."""
    if isinstance(value, dict) and set(value) == {"array", "dtype", "scalar"}:
        array = np.array(value["array"], dtype=np.dtype(value["dtype"]))
        return array[()] if value["scalar"] else array
    return value


def unpack_part(ds: xr.Dataset) -> xr.Dataset:
    """The part :func:`pack_part` wrote (a part file read back): its variables, in their order, with their
    dtypes, attributes and declared missing values; a dataset without :data:`LAYOUT_ATTR` as it is."""
    if LAYOUT_ATTR not in ds.attrs:
        return ds
    rows: dict[str, tuple[xr.Variable, int]] = {}
    for name in ds.data_vars:
        if is_part_stack(name):
            for i, row in enumerate(ds.variables[f"{name}_variable"].values):
                rows[str(row)] = (ds.variables[name], i)
    data = {}
    for name, dtype, attrs, enc in json.loads(ds.attrs[LAYOUT_ATTR]):
        stack, i = rows[name]
        data[name] = xr.Variable(stack.dims[1:], stack.values[i].astype(np.dtype(dtype)),
                                 attrs={k: _attr_value(a) for k, a in attrs.items()},
                                 encoding={k: np.dtype(val) if k == "dtype" else _attr_value(val)
                                           for k, val in enc.items()})
    stacked = [n for n in ds.variables if is_part_stack(n.removesuffix("_variable").removesuffix("_units"))]
    out = xr.Dataset(data, coords={n: ds.variables[n] for n in ds.coords if n not in stacked})
    out.attrs = {k: v for k, v in ds.attrs.items() if k != LAYOUT_ATTR}
    return out


def read_part(path: str | Path) -> xr.Dataset:
    """A part file as the batch's :func:`run_batch` made it (:func:`unpack_part` of the file)."""
    return unpack_part(read_dataset(path))


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
    parts = out / PARTS
    hist_nm = tuple(scene["sweep"]["histories_nm"] or scene["report"]["histories_nm"])
    todo = []
    for b in batches:
        why = "forced" if force else part_problem(_part_path(parts, b), key, b)
        if why is not None:
            if why != "missing":
                log.info("sweep: batch %d: part %s: recomputed", b.index, why)
            todo.append(b)
    log.info("sweep: %d batches, %d to run", len(batches), len(todo))
    # each batch runs the scene with its roughness set: the tables are the set's, and so must be the
    # scene the model reads (y_s of explicit statistics when a set needs no tables)
    set_scenes = {label: scene if table == dict(scene["roughness"]) else scene.replace(roughness=dict(table))
                  for label, table in sets.items()}
    # time histories of the first realisation only (the scene's own record)
    # each set's and realisation's inputs once (a file's key is read from it: a set's tables once made)
    batch_sim = functools.cache(lambda label, r: batch_inputs(sim, interface_paths[label], dmw_paths[r]))

    def task(b: Batch) -> tuple:
        return ("batch", set_scenes[b.label], b, batch_sim(b.label, b.realisation), str(_part_path(parts, b)), key,
                hist_nm if b.realisation == 0 else ())

    bar = _progress(len(batches), len(batches) - len(todo))
    done = [0]
    stop_after, on_batch = opts.get("stop_after"), opts.get("on_batch")
    grid = Assembler(scene, prot, list(sets), damp, len(seeds))
    by_path = {str(_part_path(parts, b)): b for b in todo}
    labels = list(sets)

    def grid_values() -> tuple[dict[str, xr.Variable], dict[str, Any], dict[str, dict[str, Any]]]:
        """The run values, attributes and each set's statistics of the datasets (every set's batches run)."""
        # the run values of every set and damping ratio (the models the batches built, cached in this process)
        models = {(label, float(d)): batch_model(set_scenes[label], batch_sim(label, 0), float(d))
                  for label in sets for d in damp}
        run = grid_run_values(models, labels, damp, sim.k_source)
        sizes = {"roughness": len(labels), "damping": len(damp)}
        attrs = {name: value for name, value in model_attrs(models[(labels[0], float(damp[0]))], sim.k_source).items()
                 if name not in GRID_ATTRS or sizes[RUN_GRID_DIMS[GRID_ATTRS[name]]] == 1}  # (several: the variable has them)
        # each set's statistics as its interface model used them: its tables' (the scans'), or the given keys
        # (the tables as the batches read them: in this process's cache after a threaded batch phase)
        stats = {label: used_statistics(set_scenes[label], batch_sim(label, 0).tables()) for label in labels}
        return run, attrs, stats

    # sweep_histories.nc is complete once the batches that keep histories are in; it is written as soon as a
    # worker also has no batch left to start (fewer batches to finish than local workers), so that its
    # compression (most of the command's final write) fills that worker's idle end of the fan-out instead of
    # following the last batch, without taking a core from a batch earlier (measured: docs/performance.md)
    hist_batches = history_batches(batches, hist_nm)
    early = [not hist_batches or not hist_batches <= {b.index for b in todo}]  # (kept parts come in at the end)

    def on_done(result: tuple[str, Any]) -> None:
        kind, value = result
        if kind == "tables":
            label, path = value
            interface_paths[label] = path
            return
        path, part = value
        grid.add(by_path[path], part)  # (in the calling thread, while the other batches run)
        done[0] += 1
        if on_batch is not None:
            on_batch(path)
        if bar is not None:
            bar.update(1)
        if not early[0] and hist_batches <= grid.added and len(todo) - done[0] < slots:
            early[0] = True
            run, attrs, stats = grid_values()
            inputs.write_early("sweep_histories.nc", grid.histories(sim.k_source, attrs, run, statistics=stats))
        if stop_after is not None and done[0] >= stop_after:
            raise KeyboardInterrupt(f"stopped after {done[0]} batches (stop_after)")

    # Two rounds of one fan-out each: the other roughness sets' interface tables with the batches that do
    # not read them (the tables first: a pool starts tasks in order), then the batches of those sets.
    # A table is mostly Python and numpy holding the GIL, a batch mostly the kernel releasing it: the tables
    # alternate with batches, so that two threads run a table and a batch rather than two tables.
    tables = [("tables", label, sub, folder, force) for label, (sub, folder) in table_tasks.items()]
    workers = opts.get("workers")
    # (one worker runs them in batch order: the order matters only to several)
    where = opts.get("scheduler")
    serial = where == "synchronous" or (where is None and local_workers(workers, max(len(todo), 1)) == 1)
    order = list if serial else costliest_first
    # (a cluster of other machines leaves this process's cores idle: the histories are written at once)
    slots = 1 if serial else local_workers(workers, max(len(todo), 1)) if where in LOCAL + (None,) else len(todo) + 1
    ready = [task(b) for b in order(b for b in todo if b.label not in table_tasks)]
    first = [t for pair in zip(tables, ready) for t in pair] + tables[len(ready):] + ready[len(tables):]
    later = order(b for b in todo if b.label in table_tasks)
    batch_seconds = 0.0
    try:  # (one process cluster for both rounds: its start-up is paid once)
        with local_cluster(opts.get("scheduler"), workers) if first or later else \
                contextlib.nullcontext(opts.get("scheduler")) as scheduler:
            # (the second round's tasks are made once the tables exist: their inputs carry the tables' key)
            for tasks in (first, lambda: [task(b) for b in later]):
                tasks = tasks() if callable(tasks) else tasks
                batch_seconds += run_tasks(sweep_task, tasks, scheduler=scheduler, workers=workers, on_done=on_done)
    finally:
        if bar is not None:
            bar.close()
    log.info("sweep: batch phase %.2f s for %d batches and %d tables", batch_seconds, len(todo), len(table_tasks))
    inputs.record(compute_seconds=round(batch_seconds, 3), batches_run=len(todo), batches=len(batches))
    add_kept_parts(grid, out, batches, key)
    run, attrs, stats = grid_values()
    return grid.datasets(key, sim.k_source, attrs, seeds, run, statistics=stats)


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


class Assembler:
    """``sweep.nc`` and ``sweep_histories.nc`` filled part by part: :meth:`add` as each batch's part arrives
    (the sweep calls it from the fan-out's ``on_done``, so the filling overlaps the batches still running),
    :meth:`datasets` once every part is in.

    A part's values go to its batch's slots (disjoint), and the variables are ordered as they first appear
    in batch order (not in the order the parts arrive), so the datasets do not depend on the order of
    :meth:`add` calls: a 2-worker run gives the file of a 1-worker run.
    """

    def __init__(self, scene: Any, prot: np.ndarray, labels: list[str], damp: list[float], n_real: int = 1):
        self.scene, self.prot, self.labels, self.damp, self.n_real = scene, prot, labels, damp, n_real
        self.stepping = scene["sweep"]["protocol"] == "stepping"
        # (stepping: the scalars per pass, before the realisation, whose statistics reduce the last axis)
        self.shape = (len(prot), len(labels), len(damp)) + ((len(DIRECTIONS),) if self.stepping else ()) \
            + ((n_real,) if n_real > 1 else ())
        self.chain_shape = (len(labels), len(damp)) + ((n_real,) if n_real > 1 else ())
        self.arrays: dict[str, np.ndarray] = {}
        self.chains: dict[str, np.ndarray] = {}
        self.hist: dict[str, np.ndarray] = {}
        self.hist_prot: np.ndarray | None = None
        self.time: np.ndarray | None = None
        self._time_from: int | None = None  # (the batch whose time axis the histories use: the first in batch order)
        self._first: dict[str, tuple[int, int]] = {}  # variable -> (batch index, position) of its first appearance
        self.added: set[int] = set()
        self._histories: xr.Dataset | None = None  # (made by :meth:`histories`, until a part with histories comes)

    def _seen(self, name: str, batch: int, position: int) -> None:
        at = (batch, position)
        if name not in self._first or at < self._first[name]:
            self._first[name] = at

    def add(self, b: Batch, ds: xr.Dataset) -> None:
        """Put the part ``ds`` of batch ``b`` into the arrays."""
        r, d = self.labels.index(b.label), self.damp.index(b.damping)
        real = (b.realisation,) if self.n_real > 1 else ()
        values = {name: ds.variables[name].values for name in ds.variables}  # (no DataArray per name: main thread)
        for i, name in enumerate(ds.data_vars):
            self._seen(name, b.index, i)
            if name.startswith("h_"):
                continue
            if name in STEPPING:  # one value per chain
                self.chains.setdefault(name, np.full(self.chain_shape, np.nan))[(r, d) + real] = values[name]
                continue
            if name not in self.arrays:  # NaN: not computed (regime: its declared _FillValue on disk)
                self.arrays[name] = np.full(self.shape, np.nan)
            at = (list(b.indices), r, d) + ((slice(None),) if self.stepping else ()) + real
            self.arrays[name][at] = values[name]
        if "hist_protrusion" in ds.coords:
            self._histories = None
            if self.hist_prot is None:
                sweep, report = self.scene["sweep"], self.scene["report"]
                self.hist_prot = np.array([h for h in sweep["histories_nm"] or report["histories_nm"]
                                           if np.any(same_point(self.prot, h))])
            if self._time_from is None or b.index < self._time_from:
                self.time, self._time_from = values[TIME], b.index
            for name in ds.data_vars:
                if name.startswith("h_"):
                    base = name[2:]
                    if base not in self.hist:
                        self.hist[base] = np.full((len(self.hist_prot), len(self.labels), len(self.damp),
                                                   values[TIME].size), np.nan)
                    for i, hp in enumerate(values["hist_protrusion"]):
                        j = int(np.argmin(np.abs(self.hist_prot - hp)))
                        self.hist[base][j, r, d] = values[name][i]
        self.added.add(b.index)

    def _ordered(self, values: dict[str, np.ndarray], prefix: str = "") -> dict[str, np.ndarray]:
        """``values`` in the order their variables (``prefix + name``) first appear in batch order."""
        return {name: values[name] for name in sorted(values, key=lambda n: self._first[prefix + n])}

    def datasets(self, key: str, k_source: str, attrs: dict, seeds: list[int] | None = None,
                 run: dict[str, xr.Variable] | None = None, *,
                 statistics: dict[str, dict[str, Any]]) -> dict[str, xr.Dataset | None]:
        """``sweep.nc`` and ``sweep_histories.nc`` from the parts added.

        ``run``: the run's values (:func:`pipeline.model.simulation.grid_run_values`: 0-d, or along
        ``roughness`` or ``damping``), written into both datasets. ``statistics``: each roughness set's
        statistics as its interface model used them (label ->
        :func:`pipeline.model.interface_tables.used_statistics`), which become coordinates along ``roughness``
        (:func:`roughness_coordinates`) and, with the scans' hashes, the JSON attribute ``roughness_sets``
        (:func:`roughness_record`). With more than one realisation the scalars gain a last dimension
        ``realisation`` and the ensemble statistics of :func:`pipeline.analyses.ensemble_rules.statistics`
        are added.
        """
        n_real, stepping = self.n_real, self.stepping
        coords = self._coords(statistics)
        real = ("realisation",) if n_real > 1 else ()
        dims = ("protrusion", "roughness", "damping") + (("direction",) if stepping else ()) + real
        data = {name: SCALARS[name].data(a, dims) for name, a in self._ordered(self.arrays).items()}
        data.update({name: STEPPING[name].data(a, ("roughness", "damping") + real)
                     for name, a in self._ordered(self.chains).items()})
        if n_real > 1:
            data["dmw_seed"] = ENSEMBLE["dmw_seed"].data(np.array(seeds), ("realisation",))
            data.update(ensemble.statistics(data))
        ds = xr.Dataset(data, coords=coords).assign(run or {})
        ds.attrs.update(self._attrs(k_source, attrs, statistics))
        return {"sweep.nc": ds, "sweep_histories.nc": self.histories(k_source, attrs, run, statistics=statistics)}

    def _coords(self, statistics: dict[str, dict[str, Any]]) -> dict[str, xr.Variable]:
        """The coordinates of ``sweep.nc`` (those of the sets' statistics included; see :meth:`datasets`)."""
        coords = {"protrusion": coordinate("protrusion", self.prot),
                  "roughness": coordinate("roughness", self.labels), "damping": coordinate("damping", self.damp)}
        if self.stepping:
            coords["direction"] = coordinate("direction", np.array(DIRECTIONS))
        if self.n_real > 1:
            coords["realisation"] = ENSEMBLE["realisation"].data(np.arange(self.n_real), ("realisation",))
        coords.update(roughness_coordinates([statistics[label] for label in self.labels]))
        coords.update(power_coordinates(self.scene, self.prot))
        return coords

    def _attrs(self, k_source: str, attrs: dict, statistics: dict[str, dict[str, Any]]) -> dict[str, Any]:
        """The global attributes of both datasets (see :meth:`datasets`)."""
        sets = roughness_sets(self.scene)
        # one attribute for all sets: a label made from the values has '.', which CF's attribute names exclude
        out = {"roughness_sets": json.dumps({label: roughness_record(sets[label], statistics[label])
                                             for label in self.labels}, default=str)}
        out.update(attrs)
        out["k_source"] = k_source
        own = scene_label(self.scene)
        if own in self.labels:  # (the report's default slice: the scene's own roughness)
            out["scene_roughness"] = own
        return out

    def histories(self, k_source: str, attrs: dict, run: dict[str, xr.Variable] | None = None, *,
                  statistics: dict[str, dict[str, Any]]) -> xr.Dataset | None:
        """``sweep_histories.nc`` from the parts added (arguments: :meth:`datasets`; ``None``: no part kept
        histories). Made once: the same object until a part with histories is added, so that the sweep can
        have it written while the other batches run (:meth:`pipeline.runner.Inputs.write_early`) and return
        it with ``sweep.nc``."""
        if not self.hist:
            return None
        if self._histories is None:
            hc = {name: c for name, c in self._coords(statistics).items() if name != "realisation"}  # (realisation 0)
            hc["protrusion"] = coordinate("protrusion", self.hist_prot)
            hc.update(power_coordinates(self.scene, self.hist_prot))
            hc[TIME] = coordinate(TIME, self.time)
            hds = xr.Dataset({name: HISTORIES[name].data(a, ("protrusion", "roughness", "damping", TIME))
                              for name, a in self._ordered(self.hist, "h_").items()}, coords=hc).assign(run or {})
            hds.attrs.update(self._attrs(k_source, attrs, statistics))
            self._histories = hds
        return self._histories


def add_kept_parts(grid: Assembler, out: Path, batches: list[Batch], key: str) -> None:
    """Add to ``grid`` the part of every batch not added yet (those of an earlier run), read from its file
    after :func:`part_problem` has accepted it.

    Raises
    ------
    RuntimeError
        When a part is missing or is not the part of its batch (:func:`part_problem`).
    """
    parts = out / PARTS
    for b in batches:
        if b.index in grid.added:
            continue
        path = _part_path(parts, b)
        why = part_problem(path, key, b)
        if why is not None:
            raise RuntimeError(f"{path}: batch {b.index}: part {why}; run the sweep again")
        grid.add(b, read_part(path))


def roughness_coordinates(statistics: list[dict[str, Any]]) -> dict[str, xr.Variable]:
    """``roughness_sigma`` [nm], ``roughness_summit_radius`` [um], ``roughness_summit_density`` [um^-2] and
    ``roughness_plasticity_index`` [1] of each roughness set, from the statistics its interface model used
    (:func:`pipeline.model.interface_tables.used_statistics`, in the order of the ``roughness`` dimension):
    the given keys of explicit statistics, the scans' of an AFM set."""
    return {name: COORDINATES[name].data([float(st[key]) for st in statistics], ("roughness",))
            for name, key in ROUGHNESS_COORDINATES.items()}


#: The coordinates along ``roughness`` and the statistics (:func:`pipeline.model.interface_tables.used_statistics`)
#: they hold.
ROUGHNESS_COORDINATES = {"roughness_sigma": "sigma_nm", "roughness_summit_radius": "summit_radius_um",
                         "roughness_summit_density": "summit_density_per_um2",
                         "roughness_plasticity_index": "plasticity_index"}


def roughness_record(table: dict[str, Any], statistics: dict[str, Any]) -> dict[str, Any]:
    """A roughness set as ``roughness_sets`` records it: its ``[roughness]`` table with the statistics its
    interface model used in place of the keys (an AFM set's ``sigma_nm``, ... are the scans', not the
    scene's unused defaults), the plasticity index, the summit offset ``y_s_nm``, where they came from
    (``statistics_source``) and, for an AFM set, each scan's SHA-256 (``afm_sha256``: path -> hex digest)."""
    record = dict(table)
    record.update({key: value for key, value in statistics.items() if key != "source"})
    record["statistics_source"] = statistics.get("source", "")
    if table.get("afm"):
        record["afm_sha256"] = {str(f): file_hash(f) for f in table["afm"]}
    return record


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

