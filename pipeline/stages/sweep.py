"""Stage ``sweep``: protrusion x roughness x damping, fanned out by :func:`pipeline.fanout.run_tasks`.

Each task runs a *batch* of scenes (``[sweep] batch_size`` protrusions of one roughness set
and one damping ratio) and writes its own part file, atomically, into ``sweep.parts/``. The DMW
record and the interface tables reach the workers by file path (``dmw.nc``, ``interface.nc`` or
``sweep.parts/interface-<label>/interface.nc``, and ``bulge.nc`` with the tabulated bulge bearing), not
inside the task graph. When every batch is done
the parts are assembled into ``sweep.nc`` (dims ``protrusion``, ``roughness``, ``damping``) and
``sweep_histories.nc`` (time histories of the protrusions in ``histories_nm``): the parts computed by
this call from memory (each batch returns its dataset with its path), the parts of an earlier run
from their files.

Resuming: a part is kept when it carries the sweep's inputs key (:mod:`pipeline.runner`: the scene,
the bytes of every AFM scan of every roughness set, the DMW and calibration datasets), its own batch
index and its batch's coordinates (roughness label, damping ratio, protrusions), so an interrupted
sweep (Ctrl-C, kill, a lost worker) picks up where it stopped and gives a dataset identical to an
uninterrupted run (every batch is a deterministic function of its inputs; no timings or folder paths
are stored in the datasets: the batch-phase wall time goes to the run log, ``.hdi/runs.jsonl``). A part
copied to another batch's name, or made for other inputs, is recomputed. The interface tables of
the other roughness sets are kept by the runner under their own inputs keys (:func:`prepare_inputs`).

Execution: :func:`pipeline.fanout.run_tasks` (by default a pool of one thread per core in this
process, the kernels releasing the GIL; ``scheduler="ADDRESS"`` attaches to a running
dask.distributed cluster; ``scheduler="synchronous"`` runs the batches one after the other).
"""

from __future__ import annotations

import functools
import json
import logging
import threading
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
import xarray as xr

from ..model import assembly
from ..fanout import run_tasks
from ..progress import Progress
from ..io import file_hash, read_attrs, read_dataset, write_dataset
from ..paths import refuse_links
from ..runner import KEY_ATTR, Inputs, Stage, ensure
from ..variables import COORDINATES, ENSEMBLE, HISTORIES, SCALARS, STEPPING, TIME, coordinate
from ..model import dmw_record, scene_inputs
from ..model.inputs import SimulationInputs, Source, for_stage
from ..model.interface_tables import used_statistics
from ..model.simulation import DIRECTIONS, GRID_ATTRS, grid_run_values, model_attrs, simulate
from ..analyses import ensemble_rules as ensemble
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
    except (OSError, ValueError) as exc:
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
    return None


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
    write_dataset(ds, part_path, scene, stage="sweep-part")
    return part_path, ds


def _progress(total: int, initial: int) -> Progress:
    """The batches counted (:class:`pipeline.progress.Progress`: a bar on a terminal, periodic lines in a
    log, nothing with ``-q``), those of an earlier run included."""
    return Progress(total, unit="batch", label="sweep", initial=initial).start()


def prepare_inputs(scene: Any, out: Path, sets: dict[str, dict],
                   force: bool = False) -> tuple[dict[str, str | None], str | None]:
    """Interface tables per roughness set and the DMW record, as the paths of files the workers read.

    The scene's own set uses the interface stage's ``interface.nc`` (upstream of the sweep: current).
    Another set's tables are the interface stage of the scene with that ``[roughness]``, made current
    by the runner in ``sweep.parts/interface-<label>/`` (with its ``roughness.nc`` for an AFM set), so
    they are recomputed only when their own inputs change. The records of realisations beyond the
    first: :func:`realisation_inputs`.
    """
    parts = refuse_links(out / PARTS)  # (its parts may be written by worker processes, which hold no folder)
    parts.mkdir(parents=True, exist_ok=True)
    interface_paths: dict[str, str | None] = {}
    for label, table in sets.items():
        if not scene_inputs.needs_interface(scene.replace(roughness=dict(table))):
            interface_paths[label] = None
        elif table == dict(scene["roughness"]):
            interface_paths[label] = str(out / "interface.nc")
        else:
            sub = scene.replace(roughness=dict(table))
            interface_paths[label] = str(ensure("interface", sub, parts / f"interface-{label}", force=force))
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
    interface_paths, dmw_path = prepare_inputs(scene, out, sets, bool(opts.get("force")))
    dmw_paths, seeds = realisation_inputs(scene, out, dmw_path, bool(opts.get("force")))
    parts = out / PARTS
    hist_nm = tuple(scene["sweep"]["histories_nm"] or scene["report"]["histories_nm"])
    todo = []
    for b in batches:
        why = "forced" if opts.get("force") else part_problem(_part_path(parts, b), key, b)
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
    # each set's and realisation's inputs once (a file's key is read from it)
    batch_sim = functools.cache(lambda label, r: batch_inputs(sim, interface_paths[label], dmw_paths[r]))
    tasks = [(set_scenes[b.label], b, batch_sim(b.label, b.realisation), str(_part_path(parts, b)), key,
              hist_nm if b.realisation == 0 else ()) for b in todo]
    bar = _progress(len(batches), len(batches) - len(todo))
    done = [0]
    stop_after, on_batch = opts.get("stop_after"), opts.get("on_batch")
    computed: dict[str, xr.Dataset] = {}  # part path -> its dataset, for the parts run here

    def on_done(result: tuple[str, xr.Dataset]) -> None:
        path, part = result
        computed[path] = part
        done[0] += 1
        if on_batch is not None:
            on_batch(path)
        if bar is not None:
            bar.update(1)
        if stop_after is not None and done[0] >= stop_after:
            raise KeyboardInterrupt(f"stopped after {done[0]} batches (stop_after)")

    try:
        batch_seconds = run_tasks(run_batch, tasks, scheduler=opts.get("scheduler"), workers=opts.get("workers"),
                                  on_done=on_done)
    finally:
        if bar is not None:
            bar.close()
    log.info("sweep: batch phase %.2f s for %d batches", batch_seconds, len(todo))
    inputs.record(compute_seconds=round(batch_seconds, 3), batches_run=len(todo), batches=len(batches))
    # the run values of every set and damping ratio (the models the batches built, cached in this process)
    models = {(label, float(d)): batch_model(set_scenes[label], batch_sim(label, 0), float(d))
              for label in sets for d in damp}
    labels = list(sets)
    run = grid_run_values(models, labels, damp, sim.k_source)
    attrs = {name: value for name, value in model_attrs(models[(labels[0], float(damp[0]))], sim.k_source).items()
             if name not in GRID_ATTRS or run[GRID_ATTRS[name]].size == 1}  # (several values: the variable has them)
    # each set's statistics as its interface model used them: its tables' (the scans'), or the given keys
    stats = {label: used_statistics(set_scenes[label], None if interface_paths[label] is None
                                    else read_dataset(interface_paths[label], stage="interface"))
             for label in labels}
    return assemble(scene, out, prot, labels, damp, batches, key, sim.k_source, attrs, seeds, computed, run,
                    statistics=stats)


def run_sweep(scene: Any, out: Path, scheduler: str | None = None, workers: int | None = None,
              force: bool = False, stop_after: int | None = None,
              on_batch: Callable[[str], None] | None = None) -> Path:
    """Make ``sweep.nc`` current in ``out`` (running, resuming or keeping the sweep); see :func:`compute`."""
    return ensure("sweep", scene, out, force=force, scheduler=scheduler, workers=workers,
                  stop_after=stop_after, on_batch=on_batch)


def assemble(scene: Any, out: Path, prot: np.ndarray, labels: list[str], damp: list[float], batches: list[Batch],
             key: str, k_source: str, attrs: dict, seeds: list[int] | None = None,
             computed: dict[str, xr.Dataset] | None = None,
             run: dict[str, xr.Variable] | None = None, *,
             statistics: dict[str, dict[str, Any]]) -> dict[str, xr.Dataset | None]:
    """``sweep.nc`` (and ``sweep_histories.nc``) filled from the parts, in batch order.

    ``computed``: the parts run by this call (path -> dataset, as written), used as they are; every
    other part is read from its file after :func:`part_problem` has accepted it. ``run``: the run's
    values (:func:`pipeline.model.simulation.grid_run_values`: 0-d, or along ``roughness`` or ``damping``),
    written into both datasets. ``statistics``: each roughness set's statistics as its interface model
    used them (label -> :func:`pipeline.model.interface_tables.used_statistics`), which become coordinates
    along ``roughness`` (:func:`roughness_coordinates`) and, with the scans' hashes, the JSON attribute
    ``roughness_sets`` (:func:`roughness_record`).

    With more than one realisation the scalars gain a last dimension ``realisation`` and the
    ensemble statistics of :func:`pipeline.analyses.ensemble_rules.statistics` are added.

    Raises
    ------
    RuntimeError
        When a part is missing or is not the part of its batch (:func:`part_problem`).
    """
    parts = out / PARTS
    n_real = len(seeds) if seeds else 1
    stepping = scene["sweep"]["protocol"] == "stepping"
    # (stepping: the scalars per pass, before the realisation, whose statistics reduce the last axis)
    shape = (len(prot), len(labels), len(damp)) + ((len(DIRECTIONS),) if stepping else ()) \
        + ((n_real,) if n_real > 1 else ())
    chain_shape = (len(labels), len(damp)) + ((n_real,) if n_real > 1 else ())
    arrays: dict[str, np.ndarray] = {}
    chains: dict[str, np.ndarray] = {}
    hist: dict[str, np.ndarray] = {}
    hist_prot: np.ndarray | None = None
    time: np.ndarray | None = None
    computed = computed or {}
    for b in batches:
        path = _part_path(parts, b)
        ds = computed.get(str(path))
        if ds is None:
            why = part_problem(path, key, b)
            if why is not None:
                raise RuntimeError(f"{path}: batch {b.index}: part {why}; run the sweep again")
            ds = read_dataset(path)
        r, d = labels.index(b.label), damp.index(b.damping)
        for name in ds.data_vars:
            if name.startswith("h_"):
                continue
            if name in STEPPING:  # one value per chain
                chains.setdefault(name, np.full(chain_shape, np.nan))[(r, d) + ((b.realisation,) if n_real > 1 else ())] \
                    = ds[name].values
                continue
            if name not in arrays:  # NaN: not computed (regime: its declared _FillValue on disk)
                arrays[name] = np.full(shape, np.nan)
            at = (list(b.indices), r, d) + ((slice(None),) if stepping else ()) \
                + ((b.realisation,) if n_real > 1 else ())
            arrays[name][at] = ds[name].values
        if "hist_protrusion" in ds.coords:
            if hist_prot is None:
                hist_prot = np.array([h for h in scene["sweep"]["histories_nm"] or scene["report"]["histories_nm"]
                                      if np.any(same_point(prot, h))])
                time = ds[TIME].values
            for name in ds.data_vars:
                if name.startswith("h_"):
                    base = name[2:]
                    if base not in hist:
                        hist[base] = np.full((len(hist_prot), len(labels), len(damp), len(time)), np.nan)
                    for i, hp in enumerate(ds["hist_protrusion"].values):
                        j = int(np.argmin(np.abs(hist_prot - hp)))
                        hist[base][j, r, d] = ds[name].values[i]
    coords = {"protrusion": coordinate("protrusion", prot), "roughness": coordinate("roughness", labels),
              "damping": coordinate("damping", damp)}
    real = ("realisation",) if n_real > 1 else ()
    dims = ("protrusion", "roughness", "damping") + (("direction",) if stepping else ()) + real
    if stepping:
        coords["direction"] = coordinate("direction", np.array(DIRECTIONS))
    data = {name: SCALARS[name].data(a, dims) for name, a in arrays.items()}
    data.update({name: STEPPING[name].data(a, ("roughness", "damping") + real) for name, a in chains.items()})
    if n_real > 1:
        coords["realisation"] = ENSEMBLE["realisation"].data(np.arange(n_real), ("realisation",))
        data["dmw_seed"] = ENSEMBLE["dmw_seed"].data(np.array(seeds), ("realisation",))
        data.update(ensemble.statistics(data))
    sets = roughness_sets(scene)
    coords.update(roughness_coordinates([statistics[label] for label in labels]))
    ds = xr.Dataset(data, coords=coords).assign(run or {})
    # one attribute for all sets: a label made from the values has '.', which CF's attribute names exclude
    ds.attrs["roughness_sets"] = json.dumps({label: roughness_record(sets[label], statistics[label])
                                             for label in labels}, default=str)
    ds.attrs.update(attrs)
    ds.attrs["k_source"] = k_source
    own = scene_label(scene)
    if own in labels:  # (the report's default slice: the scene's own roughness)
        ds.attrs["scene_roughness"] = own
    hds = None
    if hist:
        hc = {name: c for name, c in coords.items() if name != "realisation"}  # (realisation 0 only)
        hc["protrusion"] = coordinate("protrusion", hist_prot)
        hc[TIME] = coordinate(TIME, time)
        hds = xr.Dataset({name: HISTORIES[name].data(a, ("protrusion", "roughness", "damping", TIME))
                          for name, a in hist.items()}, coords=hc).assign(run or {})
        hds.attrs.update(ds.attrs)
    return {"sweep.nc": ds, "sweep_histories.nc": hds}


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
    "sweep", compute, outputs=("sweep.nc", "sweep_histories.nc"),
    reads=("*", "report.histories_nm"),
    # (the batch size changes how the work is cut, not the result: parts of another cut are rejected)
    excludes=("tfc.protrusion_nm", *(e for e in scene_inputs.SIMULATION_EXCLUDES if e != "sweep"), "sweep.batch_size"),
    files=_files, upstream=scene_inputs.simulation_inputs, order=50, main_job=True, keeps=_keeps,
    doc="protrusion x roughness x damping, fanned out, sweep.nc and sweep_histories.nc")

