"""Stage ``sweep``: protrusion x roughness x damping, fanned out over dask.

Each dask task runs a *batch* of scenes (``[sweep] batch_size`` protrusions of one roughness set
and one damping ratio) and writes its own part file, atomically, into ``sweep.parts/``. The DMW
record and the interface tables reach the workers by file path (``dmw.nc``,
``sweep.parts/interface-<label>.nc``), not inside the task graph. When every batch is done the
parts are assembled, one at a time, into ``sweep.nc`` (dims ``protrusion``, ``roughness``,
``damping``) and ``sweep_histories.nc`` (time histories of the protrusions in ``histories_nm``).

Resuming: a part is kept when it carries the sweep's inputs key (:mod:`pipeline.runner`: the scene,
the bytes of every AFM scan of every roughness set, the DMW and calibration datasets), its own batch
index and its batch's coordinates (roughness label, damping ratio, protrusions), so an interrupted
sweep (Ctrl-C, kill, a lost worker) picks up where it stopped and gives a dataset identical to an
uninterrupted run (every batch is a deterministic function of its inputs; no timings or folder paths
are stored in the datasets: the batch-phase wall time goes to the run log, ``.hdi/runs.jsonl``). A part
copied to another batch's name, or made for other inputs, is recomputed. The interface tables in
``sweep.parts`` carry the same key.

Scheduler: by default a ``distributed.LocalCluster`` with one single-threaded worker process per
core and no dashboard; ``scheduler="ADDRESS"`` attaches to a running dask.distributed cluster;
``scheduler="synchronous"`` runs the batches in this process (tests, debugging).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import xarray as xr

from .. import slider as sl
from ..io import read_dataset, write_dataset
from ..runner import KEY_ATTR, Inputs, Stage, build
from ..variables import HISTORIES, SCALARS, coordinate, history, scalar
from .interface import build_tables, roughness_statistics
from .simulate import model_attrs, resolve_k, upstream
from .sweep_grid import damping_grid, protrusion_grid, roughness_sets

log = logging.getLogger(__name__)
NM = 1e-9
PARTS = "sweep.parts"


@dataclass(frozen=True)
class Batch:
    """One task: protrusions ``indices`` of roughness set ``label`` at damping ``damping``."""

    index: int
    label: str
    damping: float
    indices: tuple[int, ...]
    protrusions: tuple[float, ...]


def plan(scene: Any) -> tuple[np.ndarray, dict[str, dict], list[float], list[Batch]]:
    """The grid and its batches (roughness-major, then damping, then protrusion)."""
    prot = protrusion_grid(scene)
    sets = roughness_sets(scene)
    damp = damping_grid(scene)
    size = scene["sweep"]["batch_size"]
    batches = []
    for label in sets:
        for dz in damp:
            for start in range(0, len(prot), size):
                idx = tuple(range(start, min(start + size, len(prot))))
                batches.append(Batch(len(batches), label, float(dz), idx, tuple(float(prot[i]) for i in idx)))
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
        with xr.open_dataset(path, engine="netcdf4") as ds:
            attrs = ds.attrs
            prot = np.asarray(ds["protrusion"].values, float) if "protrusion" in ds.coords else np.array([])
    except (OSError, ValueError) as exc:
        return f"unreadable ({exc})"
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


def run_batch(scene: Any, batch: Batch, interface_path: str | None, dmw_path: str | None, k: float | None,
              part_path: str, key: str, history_nm: tuple[float, ...]) -> str:
    """Run one batch and write its part file (executed on a worker). Returns the part's path."""
    from .dmw import load as load_dmw
    interface = read_dataset(interface_path, stage="interface") if interface_path else None
    record = None
    if dmw_path:
        _, w_nm, fs = load_dmw(dmw_path)
        record = (w_nm, fs)
    model = sl.build_model(scene, interface, record, k, damping_ratio=batch.damping)
    rows, hist_rows = [], []
    for delta in batch.protrusions:
        run = sl.run_model(model, delta * NM)
        hist = sl.histories(run)
        rows.append(sl.summarize(run, hist))
        if any(abs(delta - h) < 1e-9 for h in history_nm):
            hist_rows.append((delta, run.time, hist))
    data = {name: scalar(name, np.array([r[name] for r in rows]), ("protrusion",)) for name in rows[0]}
    coords = {"protrusion": coordinate("protrusion", np.array(batch.protrusions))}
    ds = xr.Dataset(data, coords=coords)
    if hist_rows:
        coords_h = {"hist_protrusion": coordinate("hist_protrusion", np.array([h[0] for h in hist_rows])),
                    "time": coordinate("time", hist_rows[0][1])}
        for name in hist_rows[0][2]:
            if name in HISTORIES:
                ds["h_" + name] = history(name, np.stack([h[2][name] for h in hist_rows]),
                                          ("hist_protrusion", "time"))
        ds = ds.assign_coords(coords_h)
    ds.attrs.update({KEY_ATTR: key, "roughness_label": batch.label, "damping_ratio": batch.damping,
                     "batch": batch.index})
    write_dataset(ds, part_path, scene, stage="sweep-part")
    return part_path


def _progress(total: int, initial: int):
    """A tqdm bar on an interactive terminal; nothing when piped or in CI."""
    quiet = not sys.stderr.isatty() or os.environ.get("CI")
    if quiet:
        return None
    from tqdm import tqdm
    return tqdm(total=total, initial=initial, unit="batch", desc="sweep", file=sys.stderr)


def _client(scheduler: str | None, workers: int | None):
    from distributed import Client, LocalCluster
    if scheduler:
        return Client(scheduler), None
    n = workers or os.cpu_count() or 1
    # The worker processes inherit an ignored SIGINT: Ctrl-C reaches the whole process group, and only
    # this process should answer it (one line from the CLI, not a traceback per worker).
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.CRITICAL)  # shutdown races log CommClosedError
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    return Client(cluster), cluster


def _warm_worker() -> None:
    """Import the model on a worker (and load its numba cache index) before timing starts."""
    from .. import slider  # noqa: F401


def execute(tasks: list[tuple], scheduler: str | None, workers: int | None,
            on_done: Callable[[str], None]) -> float:
    """Run ``run_batch(*args)`` for every task; call ``on_done(path)`` as each finishes.

    Returns the wall time [s] of the batch phase alone (workers started and warmed before it).
    """
    if scheduler == "synchronous" or not tasks:
        t0 = time.perf_counter()
        for args in tasks:
            on_done(run_batch(*args))
        return time.perf_counter() - t0
    from distributed import as_completed
    client, cluster = _client(scheduler, workers)
    try:
        client.run(_warm_worker)
        t0 = time.perf_counter()
        futures = [client.submit(run_batch, *args, pure=False, retries=2) for args in tasks]
        for fut in as_completed(futures):
            on_done(fut.result())
        return time.perf_counter() - t0
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def prepare_inputs(scene: Any, out: Path, sets: dict[str, dict], key: str,
                   force: bool = False) -> tuple[dict[str, str | None], str | None]:
    """Interface tables per roughness set and the DMW record, as files the workers read.

    A table in ``sweep.parts`` is kept only when it carries the sweep's inputs ``key`` (which covers
    every set's statistics and AFM bytes); an AFM set's ``roughness.nc`` is made current by the runner
    in ``sweep.parts/roughness-<label>`` (the scene's own set: ``roughness.nc`` of ``out``).
    """
    parts = out / PARTS
    parts.mkdir(parents=True, exist_ok=True)
    interface_paths: dict[str, str | None] = {}
    for label, table in sets.items():
        if not scene.effects & {"contact", "adhesion"}:
            interface_paths[label] = None
            continue
        sub = scene.replace(roughness={k: v for k, v in table.items()})
        path = parts / f"interface-{label}.nc"
        current = False
        with contextlib.suppress(OSError, ValueError), xr.open_dataset(path, engine="netcdf4") as old:
            current = old.attrs.get(KEY_ATTR) == key
        if force or not current:
            # the scene's own roughness is the roughness stage's (same key): made once, in ``out``
            folder = out if table == dict(scene["roughness"]) else parts / f"roughness-{label}"
            stats = roughness_statistics(sub, folder if table.get("afm") else None)
            write_dataset(build_tables(sub, stats), path, sub, stage="interface", extra_attrs={KEY_ATTR: key})
        interface_paths[label] = str(path)
    dmw_path = str(out / "dmw.nc") if scene.has("dmw") else None
    return interface_paths, dmw_path


def compute(scene: Any, inputs: Inputs) -> dict[str, xr.Dataset | None]:
    """Run (or resume) the sweep; returns ``sweep.nc`` and ``sweep_histories.nc`` (module docstring).

    Options (``inputs.options``): ``scheduler``, ``workers``; for tests of resuming and failures,
    ``stop_after`` (raise ``KeyboardInterrupt`` after that many batches finish in this call) and
    ``on_batch`` (called with each finished part's path); ``force`` recomputes every part.
    """
    out, key, opts = inputs.out, inputs.key, inputs.options
    prot, sets, damp, batches = plan(scene)
    k, k_source = resolve_k(scene, out)
    interface_paths, dmw_path = prepare_inputs(scene, out, sets, key, bool(opts.get("force")))
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
    tasks = [(scene, b, interface_paths[b.label], dmw_path, k, str(_part_path(parts, b)), key, hist_nm)
             for b in todo]
    bar = _progress(len(batches), len(batches) - len(todo))
    done = [0]
    stop_after, on_batch = opts.get("stop_after"), opts.get("on_batch")

    def on_done(path: str) -> None:
        done[0] += 1
        if on_batch is not None:
            on_batch(path)
        if bar is not None:
            bar.update(1)
        if stop_after is not None and done[0] >= stop_after:
            raise KeyboardInterrupt(f"stopped after {done[0]} batches (stop_after)")

    try:
        batch_seconds = execute(tasks, opts.get("scheduler"), opts.get("workers"), on_done)
    finally:
        if bar is not None:
            bar.close()
    log.info("sweep: batch phase %.2f s for %d batches", batch_seconds, len(todo))
    inputs.record(compute_seconds=round(batch_seconds, 3), batches_run=len(todo), batches=len(batches))
    first = interface_paths[next(iter(sets))]
    model = sl.build_model(scene, read_dataset(first) if first else None, _dmw_tuple(dmw_path), k)
    attrs = model_attrs(model, k_source)
    return assemble(scene, out, prot, list(sets), damp, batches, key, k_source, attrs)


def run_sweep(scene: Any, out: Path, scheduler: str | None = None, workers: int | None = None,
              force: bool = False, stop_after: int | None = None,
              on_batch: Callable[[str], None] | None = None) -> Path:
    """Make ``sweep.nc`` current in ``out`` (running, resuming or keeping the sweep); see :func:`compute`."""
    return build("sweep", scene, out, force=force, scheduler=scheduler, workers=workers,
                 stop_after=stop_after, on_batch=on_batch)["sweep"][0]


def _dmw_tuple(path: str | None):
    if path is None:
        return None
    from .dmw import load as load_dmw
    _, w, fs = load_dmw(path)
    return (w, fs)


def assemble(scene: Any, out: Path, prot: np.ndarray, labels: list[str], damp: list[float], batches: list[Batch],
             key: str, k_source: str, attrs: dict) -> dict[str, xr.Dataset | None]:
    """``sweep.nc`` (and ``sweep_histories.nc``) filled from the part files, one part at a time.

    Raises
    ------
    RuntimeError
        When a part is missing or is not the part of its batch (:func:`part_problem`).
    """
    parts = out / PARTS
    shape = (len(prot), len(labels), len(damp))
    arrays: dict[str, np.ndarray] = {}
    hist: dict[str, np.ndarray] = {}
    hist_prot: np.ndarray | None = None
    time: np.ndarray | None = None
    for b in batches:
        path = _part_path(parts, b)
        why = part_problem(path, key, b)
        if why is not None:
            raise RuntimeError(f"{path}: batch {b.index}: part {why}; run the sweep again")
        ds = read_dataset(path)
        r, d = labels.index(b.label), damp.index(b.damping)
        for name in ds.data_vars:
            if name.startswith("h_"):
                continue
            if name not in arrays:  # NaN: not computed (regime: its declared _FillValue on disk)
                arrays[name] = np.full(shape, np.nan)
            arrays[name][list(b.indices), r, d] = ds[name].values
        if "hist_protrusion" in ds.coords:
            if hist_prot is None:
                hist_prot = np.array([h for h in scene["sweep"]["histories_nm"] or scene["report"]["histories_nm"]
                                      if np.any(np.abs(prot - h) < 1e-9)])
                time = ds["time"].values
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
    dims = ("protrusion", "roughness", "damping")
    data = {name: SCALARS[name].data(a, dims) for name, a in arrays.items()}
    ds = xr.Dataset(data, coords=coords)
    sets = roughness_sets(scene)
    for label in labels:
        ds.attrs[f"roughness_{label}"] = json.dumps(sets[label], default=str)
    ds.attrs.update(attrs)
    ds.attrs["k_source"] = k_source
    hds = None
    if hist:
        hc = dict(coords)
        hc["protrusion"] = coordinate("protrusion", hist_prot)
        hc["time"] = coordinate("time", time)
        hds = xr.Dataset({name: HISTORIES[name].data(a, ("protrusion", "roughness", "damping", "time"))
                          for name, a in hist.items()}, coords=hc)
        hds.attrs.update(ds.attrs)
    return {"sweep.nc": ds, "sweep_histories.nc": hds}


def _files(scene: Any) -> dict[str, str]:
    """The AFM scans of every roughness set (their bytes are inputs of the sweep)."""
    return {f"sweep.roughness[{label}].afm[{i}]": f
            for label, table in roughness_sets(scene).items() for i, f in enumerate(table.get("afm") or [])}


def _upstream(scene: Any) -> tuple[str, ...]:
    # the sweep builds its own interface tables per roughness set (sweep.parts), so not "interface"
    return tuple(u for u in upstream(scene) if u != "interface")


STAGE = Stage(
    "sweep", compute, outputs=("sweep.nc", "sweep_histories.nc"),
    reads=("*", "report.histories_nm"),
    # (the batch size changes how the work is cut, not the result: parts of another cut are rejected)
    excludes=("tfc.protrusion_nm", "report", "scene.name", "scene.description", "sweep.batch_size"),
    files=_files, upstream=_upstream, order=50, main_job=True,
    doc="protrusion x roughness x damping on dask, sweep.nc and sweep_histories.nc")


def run(scene: Any, out: Path, **options: Any) -> Path:
    """Stage entry point (``hdi sweep``): :func:`run_sweep`."""
    return build("sweep", scene, out, **options)["sweep"][0]
