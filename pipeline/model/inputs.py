"""A simulation's inputs in one object, with one caching rule.

What one simulation of a scene reads besides the scene (which ones: the rule
:func:`pipeline.model.scene_inputs.input_stages`): the interface tables (``interface.nc``), the DMW
record (``dmw.nc``), the bulge table (``bulge.nc``, with the tabulated bulge bearing) and the contact
criterion k with its source (:func:`pipeline.model.scene_inputs.contact_k`). :class:`SimulationInputs`
holds them; each dataset is a :class:`Source`, either in memory or a file of a results folder that is
read on first use.

The caching rule (:func:`cached`): in one process, a dataset is read (or made) once per *identity*,
``(stage, inputs key)``, the inputs key being the runner's key of the stage that made it (equal keys,
equal data: :mod:`pipeline.runner`); the least recently used are dropped beyond :data:`CACHE_SIZE`. So
the batches of a threaded sweep, the tasks of a calibration and the candidates of a parameter study share
one copy of what they read, whether it came from a file or was made in memory for the same key. A file
whose key is not given is identified by the key it carries (attribute ``inputs_key``), else by its
path, modification time and size.

A :class:`SimulationInputs` is small and picklable (paths and keys; in-memory datasets travel with it),
so fan-out tasks take it and read what they need on their worker.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np
import xarray as xr

from ..io import KEY_ATTR, DatasetError, read_attrs, read_dataset
from . import dmw_record, scene_inputs
from . import assembly

#: How many datasets (tables, records) one process keeps: a study's base inputs and its candidates'
#: varied ones, an ensemble's records (8 by default) and a sweep's roughness sets.
CACHE_SIZE = 32

#: Prefix of the identity of a file that carries no inputs key (its path, modification time and size).
_FILE_ID = "file:"

#: The file of each stage's dataset in a results folder.
FILES = {"interface": "interface.nc", "dmw": dmw_record.FILENAME, "bulge": "bulge.nc"}


@dataclass(frozen=True)
class _Made:
    """A dataset identified by its stage and inputs key alone; ``make`` makes it (not compared)."""

    stage: str
    key: str
    make: Callable[[], Any] = field(compare=False)


@lru_cache(maxsize=CACHE_SIZE)
def _made(what: _Made) -> Any:
    return what.make()


def cached(stage: str, key: str, make: Callable[[], Any]) -> Any:
    """The dataset of ``stage`` with inputs ``key``: ``make()`` the first time in this process, the same
    object afterwards (the module's caching rule; thread-safe)."""
    return _made(_Made(stage, key, make))


def _read(stage: str, path: str, key: str | None) -> Any:
    """The dataset of ``stage`` in the file ``path``, refusing one that carries another inputs key than
    ``key``; a DMW record as ``(displacement [nm], sample rate [Hz])`` (read-only: shared)."""
    ds = read_dataset(path, stage=stage, variables=dmw_record.VARIABLES if stage == "dmw" else ())
    have = ds.attrs.get(KEY_ATTR)
    if key is not None and not key.startswith(_FILE_ID) and have != key:
        raise DatasetError(f"{path}: made from other inputs (inputs_key {str(have)[:12]}) than this run's "
                           f"{stage} stage (inputs_key {key[:12]})")
    if stage != "dmw":
        return ds
    _, w_nm, fs = dmw_record.from_dataset(ds)
    w_nm.setflags(write=False)  # shared by every simulation of this process that reads it
    return w_nm, fs


@dataclass(frozen=True)
class Source:
    """One dataset a simulation reads: a file (``path``, read on first use) or ``data`` in memory.

    Attributes
    ----------
    stage : the stage that makes it (``"interface"``, ``"dmw"``, ``"bulge"``)
    path : its file, or ``None`` in memory
    key : the stage's inputs key it was made for (its identity in the cache), or ``None``
    data : the dataset in memory (a DMW record: ``(displacement [nm], sample rate [Hz])``)
    """

    stage: str
    path: str | None = None
    key: str | None = None
    data: Any = field(default=None, compare=False, repr=False)

    @classmethod
    def file(cls, stage: str, path: str | Path, key: str | None = None) -> "Source":
        """The dataset of ``stage`` in ``path``; ``key``: the inputs key the runner expects (checked when
        read), else the one the file carries, else the file's path, modification time and size."""
        path = str(path)
        if key is None:
            try:
                key = read_attrs(path)[0].get(KEY_ATTR)
            except OSError:
                key = None  # (a missing file: reading it says so, with the stage to run)
            if key is None and os.path.isfile(path):
                st = os.stat(path)
                key = f"{_FILE_ID}{path}:{st.st_mtime_ns}:{st.st_size}"
            return cls(stage, path, key and str(key))
        return cls(stage, path, key)

    @classmethod
    def memory(cls, stage: str, data: Any, key: str | None = None) -> "Source":
        """A dataset already in memory (``key``: the inputs key it was made for, when known)."""
        return cls(stage, None, key, data)

    def load(self) -> Any:
        """The dataset (:func:`cached` under its identity when it is a file)."""
        if self.path is None:
            return self.data
        return cached(self.stage, str(self.key or self.path), lambda: _read(self.stage, self.path, self.key))


def _load(source: Source | None) -> Any:
    return None if source is None else source.load()


@dataclass(frozen=True)
class SimulationInputs:
    """What one simulation of a scene reads besides the scene (module docstring).

    Attributes
    ----------
    interface, dmw, bulge : the interface tables, the DMW record and the bulge table, each a
        :class:`Source` or ``None`` when the scene reads none
    k : the contact criterion constant [1] (``None``: no contact effect, or not resolved: a parameter study
        takes each candidate's own, :func:`pipeline.model.scene_inputs.contact_k`)
    k_source : where ``k`` came from
    bulge_pads : a study's bulge tables at a few pad pressures (``bulge_pads.nc``, :mod:`pipeline.stages.bulge_pads`),
        from which each candidate's bulge table is interpolated (:func:`pipeline.candidates.candidate_inputs`);
        ``None``: each candidate solves its own
    """

    interface: Source | None = None
    dmw: Source | None = None
    bulge: Source | None = None
    k: float | None = None
    k_source: str = "not resolved"
    bulge_pads: Source | None = None

    @classmethod
    def of(cls, interface: xr.Dataset | None = None, record: tuple[np.ndarray, float] | None = None,
           bulge: xr.Dataset | None = None, k: float | None = None, k_source: str = "given") -> "SimulationInputs":
        """Inputs in memory: interface dataset, DMW record ``(displacement [nm], sample rate [Hz])``, bulge
        dataset, k [1]."""
        def mem(stage: str, data: Any) -> Source | None:
            return None if data is None else Source.memory(stage, data)
        return cls(mem("interface", interface), mem("dmw", record), mem("bulge", bulge), k, k_source)

    def tables(self) -> xr.Dataset | None:
        """The interface tables (``interface.nc``), or ``None``."""
        return _load(self.interface)

    def record(self) -> tuple[np.ndarray, float] | None:
        """The DMW record ``(displacement [nm], sample rate [Hz])``, or ``None``."""
        return _load(self.dmw)

    def bulge_table(self) -> xr.Dataset | None:
        """The bulge table (``bulge.nc``), or ``None``."""
        return _load(self.bulge)

    def with_record(self, dmw: Source | None) -> "SimulationInputs":
        """The same inputs with another DMW record (a realisation of an ensemble)."""
        return replace(self, dmw=dmw)

    def identity(self) -> tuple:
        """What identifies these inputs' data (each source's stage key or file; k), for caches of models."""
        def ident(s: Source | None) -> Any:
            return None if s is None else (s.key or s.path or id(s.data))
        return ident(self.interface), ident(self.dmw), ident(self.bulge), self.k

    def model(self, scene: Any, k: float | None = None, damping_ratio: float | None = None) -> assembly.Model:
        """The model of ``scene`` on these inputs (:func:`pipeline.model.assembly.build_model`); ``k`` [1]
        overrides :attr:`k`, ``damping_ratio`` [1] the scene's (sweeps)."""
        return assembly.build_model(scene, self.tables(), self.record(), self.k if k is None else k,
                              damping_ratio=damping_ratio, bulge=self.bulge_table())


def for_stage(scene: Any, stage_inputs: Any, calibration: bool = True, k: float | None = None) -> SimulationInputs:
    """:func:`from_folder` of a stage's :class:`pipeline.runner.Inputs` (``stage_inputs``): its results folder
    and the keys of its upstream stages, which the runner made current."""
    return from_folder(scene, stage_inputs.out, stage_inputs.upstream, calibration, k)


def from_folder(scene: Any, out: str | Path, keys: Mapping[str, str | None] | None = None,
                calibration: bool = True, k: float | None = None) -> SimulationInputs:
    """The inputs of one simulation of ``scene`` from the datasets in the results folder ``out``.

    ``keys``: the runner's inputs key of each upstream stage (checked when a dataset is read; none: the
    keys the files carry). ``calibration``: resolve k by :func:`pipeline.model.scene_inputs.contact_k`,
    with ``calibration.nc`` when the scene fixes no k (``False``: a parameter study or the calibration
    itself, k left unresolved); ``k``: an explicit k (an option) that overrides the scene's.

    Raises
    ------
    pipeline.io.DatasetError
        When ``calibration.nc`` is missing or was made from other inputs than ``keys`` say.
    ValueError
        When no rule gives a k (:func:`pipeline.model.scene_inputs.contact_k`).
    """
    out, keys = Path(out), dict(keys or {})
    wanted = scene_inputs.input_stages(scene, calibration)
    sources = {stage: Source.file(stage, out / name, keys.get(stage)) if stage in wanted else None
               for stage, name in FILES.items()}
    if not calibration:
        return SimulationInputs(**sources)
    cal = None
    if "calibrate" in wanted and k is None:
        cal = _read("calibrate", str(out / "calibration.nc"), keys.get("calibrate"))
    k_value, k_source = scene_inputs.contact_k(scene, cal, override=k)
    return SimulationInputs(**sources, k=k_value, k_source=k_source)
