"""Stage ``sweep``: protrusion x roughness x damping, fanned out over dask.

Each dask task runs a *batch* of scenes (``[sweep] batch_size`` protrusions of one roughness set
and one damping ratio) and writes its own part file, atomically, into ``sweep.parts/``. The DMW
record and the interface tables reach the workers by file path (``dmw.nc``,
``sweep.parts/interface-<label>.nc``), not inside the task graph. When every batch is done the
parts are assembled, one at a time, into ``sweep.nc`` (dims ``protrusion``, ``roughness``,
``damping``) and ``sweep_histories.nc`` (time histories of the protrusions in ``histories_nm``).

Resuming: a part whose ``sweep_key`` matches the current sweep is not recomputed, so an
interrupted sweep (Ctrl-C, kill, a lost worker) picks up where it stopped and gives the same
dataset as an uninterrupted run: every batch is a deterministic function of its inputs.

Scheduler: by default a ``distributed.LocalCluster`` with one single-threaded worker process per
core and no dashboard; ``scheduler="ADDRESS"`` attaches to a running dask.distributed cluster;
``scheduler="synchronous"`` runs the batches in this process (tests, debugging).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np
import xarray as xr

from .. import slider as sl
from ..io import is_current, read_dataset, var, write_dataset
from ..outputs import HISTORIES, SCALARS, history_variable, scalar_variable
from . import ensure
from .interface import build_tables, roughness_statistics
from .simulate import model_attrs, resolve_k
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


def sweep_key(scene: Any, k: float | None) -> str:
    """Identity of a sweep: the whole scene (protrusion of [tfc] excluded) and k."""
    cfg = json.loads(scene.to_toml_text())
    cfg["tfc"].pop("protrusion_nm", None)
    for section in ("report", "identify", "sensitivity"):  # settings of other stages
        cfg.pop(section, None)
    blob = json.dumps({"config": cfg, "k": k}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def _part_path(parts: Path, b: Batch) -> Path:
    return parts / f"batch-{b.index:05d}.nc"


def part_is_done(path: Path, key: str) -> bool:
    """Whether a part file exists, is readable and belongs to this sweep."""
    if not path.is_file():
        return False
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return ds.attrs.get("sweep_key") == key
    except (OSError, ValueError):
        return False


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
    data = {name: scalar_variable(name, np.array([r[name] for r in rows]), ("protrusion",)) for name in rows[0]}
    coords = {"protrusion": var(np.array(batch.protrusions), "protrusion", "nm", "TFC protrusion")}
    ds = xr.Dataset(data, coords=coords)
    if hist_rows:
        coords_h = {"hist_protrusion": var(np.array([h[0] for h in hist_rows]), "hist_protrusion", "nm",
                                           "protrusion of the kept histories"),
                    "time": var(hist_rows[0][1], "time", "s", "time")}
        for name in hist_rows[0][2]:
            if name in HISTORIES:
                ds["h_" + name] = history_variable(name, np.stack([h[2][name] for h in hist_rows]),
                                                   ("hist_protrusion", "time"))
        ds = ds.assign_coords(coords_h)
    ds.attrs.update({"sweep_key": key, "roughness_label": batch.label, "damping_ratio": batch.damping,
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
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.CRITICAL)  # shutdown races log CommClosedError
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


def prepare_inputs(scene: Any, out: Path, sets: dict[str, dict], force: bool = False) -> tuple[dict[str, str | None], str | None]:
    """Interface tables per roughness set and the DMW record, as files the workers read."""
    parts = out / PARTS
    parts.mkdir(parents=True, exist_ok=True)
    interface_paths: dict[str, str | None] = {}
    for label, table in sets.items():
        if not scene.effects & {"contact", "adhesion"}:
            interface_paths[label] = None
            continue
        sub = scene.replace(roughness={k: v for k, v in table.items()})
        path = parts / f"interface-{label}.nc"
        if force or not is_current(path, sub, "interface"):
            stats = roughness_statistics(sub, parts / f"roughness-{label}" if table.get("afm") else None)
            write_dataset(build_tables(sub, stats), path, sub, stage="interface")
        interface_paths[label] = str(path)
    dmw_path = str(ensure("dmw", scene, out, force)) if scene.has("dmw") else None
    return interface_paths, dmw_path


def run_sweep(scene: Any, out: Path, scheduler: str | None = None, workers: int | None = None,
              force: bool = False, stop_after: int | None = None,
              on_batch: Callable[[str], None] | None = None) -> Path:
    """Run (or resume) the sweep and assemble ``sweep.nc``; see the module docstring.

    ``stop_after``: raise ``KeyboardInterrupt`` after that many batches finish in this call;
    ``on_batch``: called with each finished part's path (both for tests of resuming and failures).
    """
    out = Path(out)
    prot, sets, damp, batches = plan(scene)
    k, k_source = resolve_k(scene, out)
    key = sweep_key(scene, k)
    interface_paths, dmw_path = prepare_inputs(scene, out, sets, force)
    parts = out / PARTS
    hist_nm = tuple(scene["sweep"]["histories_nm"] or scene["report"]["histories_nm"])
    todo = [b for b in batches if force or not part_is_done(_part_path(parts, b), key)]
    log.info("sweep: %d batches, %d to run", len(batches), len(todo))
    tasks = [(scene, b, interface_paths[b.label], dmw_path, k, str(_part_path(parts, b)), key, hist_nm)
             for b in todo]
    bar = _progress(len(batches), len(batches) - len(todo))
    done = [0]

    def on_done(path: str) -> None:
        done[0] += 1
        if on_batch is not None:
            on_batch(path)
        if bar is not None:
            bar.update(1)
        if stop_after is not None and done[0] >= stop_after:
            raise KeyboardInterrupt(f"stopped after {done[0]} batches (stop_after)")

    try:
        batch_seconds = execute(tasks, scheduler, workers, on_done)
    finally:
        if bar is not None:
            bar.close()
    model = sl.build_model(scene, read_dataset(interface_paths[next(iter(sets))]) if interface_paths[next(iter(sets))] else None,
                           _dmw_tuple(dmw_path), k)
    attrs = model_attrs(model, k_source)
    attrs["compute_seconds"] = round(batch_seconds, 3)  # wall time of the batch phase (workers already up)
    attrs["batches_run"] = len(todo)
    return assemble(scene, out, prot, list(sets), damp, batches, key, k_source, attrs,
                    [dmw_path] if dmw_path else [])


def _dmw_tuple(path: str | None):
    if path is None:
        return None
    from .dmw import load as load_dmw
    _, w, fs = load_dmw(path)
    return (w, fs)


def assemble(scene: Any, out: Path, prot: np.ndarray, labels: list[str], damp: list[float], batches: list[Batch],
             key: str, k_source: str, attrs: dict, inputs: Iterable[str]) -> Path:
    """Fill ``sweep.nc`` (and ``sweep_histories.nc``) from the part files, one part at a time."""
    parts = out / PARTS
    shape = (len(prot), len(labels), len(damp))
    arrays: dict[str, np.ndarray] = {}
    hist: dict[str, np.ndarray] = {}
    hist_prot: np.ndarray | None = None
    time: np.ndarray | None = None
    for b in batches:
        path = _part_path(parts, b)
        if not part_is_done(path, key):
            raise RuntimeError(f"{path}: batch {b.index} missing or from another sweep; run the sweep again")
        ds = read_dataset(path)
        r, d = labels.index(b.label), damp.index(b.damping)
        for name in ds.data_vars:
            if name.startswith("h_"):
                continue
            if name not in arrays:
                arrays[name] = np.full(shape, -1 if name == "regime" else np.nan,
                                       dtype=np.int8 if name == "regime" else float)
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
    coords = {"protrusion": var(prot, "protrusion", "nm", "TFC protrusion"),
              "roughness": var(np.array(labels, dtype=object), "roughness", "1", "roughness set label"),
              "damping": var(np.array(damp), "damping", "1", "modal damping ratio of the air bearing")}
    dims = ("protrusion", "roughness", "damping")
    data = {}
    for name, a in arrays.items():
        units, _, long_name = SCALARS[name]
        attrs_v = {"units": units, "long_name": long_name}
        if name == "regime":
            from ..outputs import REGIME_ATTRS
            attrs_v.update(REGIME_ATTRS)
        data[name] = xr.Variable(dims, a, attrs=attrs_v)
    ds = xr.Dataset(data, coords=coords)
    sets = roughness_sets(scene)
    for label in labels:
        ds.attrs[f"roughness_{label}"] = json.dumps(sets[label], default=str)
    extra = dict(attrs)
    extra.update({"sweep_key": key, "batches": len(batches), "k_source": k_source})
    path = write_dataset(ds, out / "sweep.nc", scene, stage="sweep", inputs=inputs, extra_attrs=extra)
    if hist:
        hc = dict(coords)
        hc["protrusion"] = var(hist_prot, "protrusion", "nm", "TFC protrusion")
        hc["time"] = var(time, "time", "s", "time")
        hds = xr.Dataset({name: xr.Variable(("protrusion", "roughness", "damping", "time"), a,
                                            attrs={"units": HISTORIES[name][0], "long_name": HISTORIES[name][2]})
                          for name, a in hist.items()}, coords=hc)
        write_dataset(hds, out / "sweep_histories.nc", scene, stage="sweep", inputs=inputs, extra_attrs=extra)
    return path


def run(scene: Any, out: Path, scheduler: str | None = None, workers: int | None = None, force: bool = False,
        **options: Any) -> Path:
    """Stage entry point (``hdi sweep``)."""
    return run_sweep(scene, Path(out), scheduler=scheduler, workers=workers, force=force)
