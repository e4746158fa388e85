"""A parameter-study candidate in its worker process (the evaluation of it: :mod:`pipeline.evaluations`): its
inputs, rebuilt only where a key they depend on changed (:func:`candidate_inputs`), its DMW records by seed
(:func:`seeded_record`), and what an earlier racing part of the same candidate made, kept for the later ones
(:class:`Candidates`: its validated scene, its inputs and their keys, its model, its static starts and, for the
candidates run last, its tabulated TFC-point forces).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Sequence

import numpy as np

from .analyses.free_parameters import Parameter, with_values
from .model import dmw_record, scene_inputs
from .model import assembly
from .model import bulge_pads
from .model.bulge_table import scene_table
from .model.inputs import SimulationInputs, Source, cached
from .model.interface_tables import build_tables, roughness_statistics
from .runner import Runner
from .units import NM


def candidate_inputs(scene: Any, inputs: SimulationInputs,
                     key: Callable[[str], str] | None = None) -> SimulationInputs:
    """A candidate's interface tables, DMW record and bulge table: the base files where the candidate's
    stage keys are the base's, else rebuilt (once per process and key). k is not resolved (:func:`evaluate`).
    ``key``: the stage keys of ``scene`` (``Runner(scene, ".").key``, made here when None)."""
    key = key or Runner(scene, ".").key  # (one runner: its file hashes and upstream keys computed once)
    interface = record = bulge = None
    if scene_inputs.needs_interface(scene):
        def tables() -> Any:  # (AFM statistics once per process, not an AFM analysis per candidate)
            stats = cached("roughness", key("roughness"), lambda: roughness_statistics(scene))
            return build_tables(scene, stats)
        interface = _input(inputs.interface, "interface", key("interface"), tables)
    if scene.has("dmw"):
        def synthesise() -> tuple[np.ndarray, float]:
            s = dmw_record.settings(scene)
            if s["source"] != "synthetic":
                raise ValueError("a [dmw] key of a measured record cannot be a free parameter (the record is "
                                 "used as measured)")
            return dmw_record.synthetic_record(s), s["sample_rate_hz"]
        record = _input(inputs.dmw, "dmw", key("dmw"), synthesise)
    if "bulge" in scene_inputs.table_stages(scene):
        if inputs.bulge_pads is not None:  # (a free pad pressure: every candidate's table interpolated, seconds)
            bulge = _pad_table(scene, inputs.bulge_pads)
        else:  # (a changed bulge key solves the table again: ~20 s on one core for the paper scene, per new value)
            bulge = _input(inputs.bulge, "bulge", key("bulge"), lambda: scene_table(scene))
    return SimulationInputs(interface, record, bulge, bulge_pads=inputs.bulge_pads)


def _pad_table(scene: Any, pads: Source) -> Source:
    """The candidate's bulge table interpolated at its ``air_bearing.pad_pressure_mpa`` from the study's node
    tables ``pads`` (:func:`pipeline.model.bulge_pads.table_at`), made once per process and pad pressure. Every
    candidate reads it so, the base scene's pad pressure too: one table law over the whole search."""
    p_pad = float(scene["air_bearing"]["pad_pressure_mpa"])
    key = f"{pads.key or pads.path}@{p_pad!r}"
    return Source.memory("bulge", cached("bulge", key, lambda: bulge_pads.table_at(pads.load(), p_pad)), key)


def _input(base: Source | None, stage: str, key: str, make: Callable[[], Any]) -> Source:
    """The base input when the candidate's stage ``key`` is the base's (read from its file once per
    process), else the candidate's own, made once per process and key (:func:`pipeline.model.inputs.cached`)."""
    if base is not None and base.path and key == base.key:
        return base
    return Source.memory(stage, cached(stage, key, make), key)


def seeded_record(scene: Any, seed: int, key: str | None = None) -> tuple[np.ndarray, float]:
    """The scene's synthetic DMW record with ``dmw.seed = seed`` (a realisation of an ensemble), made
    once per process: ``(displacement [nm], sample rate [Hz])``. ``key``: its dmw stage key
    (:func:`seeded_key`, computed here when None).

    Raises
    ------
    ValueError
        For a measured record (it is one realisation) or a scene without the dmw effect.
    """
    where = str(scene.path) if getattr(scene, "path", None) else "<scene>"
    if not scene.has("dmw"):
        raise ValueError(f"{where}: DMW realisations need the dmw effect in scene.effects")
    if scene["dmw"]["source"] != "synthetic":
        raise ValueError(f"{where}: DMW realisations need dmw.source = \"synthetic\" (a measured record has one "
                         f"realisation); got dmw.source = {scene['dmw']['source']!r}")

    def make() -> tuple[np.ndarray, float]:
        # (the scene's settings with the seed: those of the scene with dmw.seed = seed, without validating
        # that scene again, ~1 ms a record; realisation seeds are in the key's range by construction)
        s = {**dmw_record.settings(scene), "seed": int(seed)}
        return dmw_record.synthetic_record(s), s["sample_rate_hz"]
    return cached("dmw", key or seeded_key(scene, seed), make)


def seeded_key(scene: Any, seed: int) -> str:
    """The dmw stage key of ``scene`` with ``dmw.seed = seed`` (:func:`seeded_record`'s identity)."""
    return Runner(scene.replace(dmw={"seed": int(seed)}), ".").key("dmw")


@dataclass
class _Candidate:
    """What :func:`evaluate` keeps of a candidate between the racing parts of its ensemble
    (:class:`Candidates`): its validated scene, the stage keys of its inputs (``key``:
    ``Runner(scene, ".").key``, which computes each once), its contact criterion ``k`` [1], its inputs
    (:func:`candidate_inputs` with ``k``: its own interface tables and DMW record where its keys are not
    the base's, so that they are not made again when the process's dataset cache,
    :func:`pipeline.model.inputs.cached`, dropped them between two parts), the dmw keys of its seeded
    records (:func:`seeded_key`), its models' ``statics`` (the static starts), its model without a DMW
    record (``model``: :meth:`template`) and, while it is among the last :data:`TABLES_KEPT` candidates
    run, its tabulated TFC-point forces at the study's protrusions (``tfc_tables``, ~1.7 MB:
    :meth:`Candidates.keep_tables`)."""

    scene: Any
    key: Callable[[str], str]
    k: float
    statics: dict = field(default_factory=dict)
    records: dict[int, str] = field(default_factory=dict)
    sim: SimulationInputs | None = None
    model: assembly.Model | None = None
    tfc_tables: dict = field(default_factory=dict)

    def inputs(self, base: SimulationInputs) -> SimulationInputs:
        """The candidate's inputs on the base inputs ``base`` (the entry's: :class:`Candidates`), made once."""
        if self.sim is None:
            self.sim = replace(candidate_inputs(self.scene, base, self.key), k=self.k)
        return self.sim

    def template(self) -> assembly.Model:
        """The candidate's model on its inputs (:meth:`inputs`, made first), without its DMW record: each
        record's model is :func:`pipeline.model.assembly.with_record` of it (its interface tables, laws and
        tolerances made once, not once per record, ~7 ms). Made once."""
        if self.model is None:
            model = self.sim.model(self.scene)
            model.dmw = None  # (each record's own: with_record; the template itself is never run)
            self.model = model
        return self.model

    def record_key(self, seed: int) -> str:
        if seed not in self.records:
            self.records[seed] = seeded_key(self.scene, seed)
        return self.records[seed]


class Candidates:
    """The candidates a worker process evaluated last (:func:`evaluate`), kept between the racing parts of
    their ensemble (:class:`_Candidate`). A part runs other DMW records of the same candidate, so its scene
    is not validated again, its input keys are not hashed again, and the static equilibria, those of the
    mean disk (:func:`pipeline.model.copies.share_statics`: the flying branch, its fold and the start
    states, ``Model.statics``) are found once per candidate, not once per part. All are functions of the
    candidate alone (the starts do not depend on the order of the runs, :func:`pipeline.model.start.start_state`),
    so the results are the same, bit for bit. Of the datasets only the candidate's own inputs are kept
    (:meth:`_Candidate.inputs`: in a racing fan-out of 24 candidates the process's dataset cache of 32 held
    their records and tables for one part, not the next, and the interface tables, ~45 ms, were made again
    for every part); the seeded DMW records (~0.1 ms each) stay in that cache under the kept keys.

    Entries are keyed by the base scene and inputs objects (held by the entry, so their ``id`` is not
    reused while it lives: the tasks of a study in one process share them) and the parameters' names
    and values; at most ``size`` entries, the least recently used dropped first. Thread-safe: two
    threads that make one candidate at once keep one of the two (the same numbers).
    """

    def __init__(self, size: int):
        self.size = size
        self._entries: OrderedDict[tuple, tuple[Any, Any, _Candidate]] = OrderedDict()
        #: the candidates whose TFC tables are kept (:meth:`keep_tables`), by ``id``, the last run last
        self._tables: OrderedDict[int, _Candidate] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, base: Any, inputs: Any, params: Sequence[Parameter], values: Sequence[float]) -> _Candidate:
        """The candidate ``values`` of ``params`` on ``base`` and ``inputs``: the kept one, else made
        (:func:`pipeline.analyses.free_parameters.with_values`, :func:`pipeline.model.scene_inputs.contact_k`; their
        errors are raised, nothing kept)."""
        key = (id(base), id(inputs), tuple(p.name for p in params), tuple(float(v) for v in values))
        with self._lock:
            hit = self._entries.get(key)
            if hit is not None and hit[0] is base and hit[1] is inputs:
                self._entries.move_to_end(key)
                return hit[2]
        scene = with_values(base, params, values)
        made = _Candidate(scene, Runner(scene, ".").key, scene_inputs.contact_k(scene)[0])
        with self._lock:
            self._entries[key] = (base, inputs, made)
            self._entries.move_to_end(key)
            while len(self._entries) > self.size:
                self._entries.popitem(last=False)
        return made

    def clear(self) -> None:
        """Forget every candidate."""
        with self._lock:
            self._entries.clear()
            self._tables.clear()

    def keep_tables(self, cand: _Candidate, tables: dict, protrusions: Sequence[float]) -> None:
        """Keep on ``cand`` the tabulated TFC-point forces ``tables`` (a model's ``tfc_tables``,
        :func:`pipeline.model.kernel_inputs.tfc_table`) at ``protrusions`` [nm], for its next records, and
        drop those of the candidates run before the last :data:`TABLES_KEPT`. A table is a function of the
        candidate's laws and the protrusion alone, so a record's run with a kept table is the same, bit for bit;
        each costs ~0.4 ms a run to make (a 4001-knot spline), 128 kB to keep."""
        keys = [float(float(x) * NM) for x in protrusions]  # (the key of a run's table: its protrusion [m])
        kept = {k: tables[k] for k in keys if k in tables}
        with self._lock:
            cand.tfc_tables = {**cand.tfc_tables, **kept}  # (a new dict: a task may be reading the old one)
            self._tables[id(cand)] = cand
            self._tables.move_to_end(id(cand))
            while len(self._tables) > TABLES_KEPT:
                self._tables.popitem(last=False)[1].tfc_tables = {}


#: Candidates a worker process keeps (:class:`Candidates`): more than one racing fan-out holds (the
#: default budget's generation is 60 candidates, a round of profile walks up to ~130 points); up to ~130 kB
#: each (the bulge scene's own interface tables, 56 kB, and DMW record, 67 kB), ~32 MB in all.
CANDIDATES_KEPT = 256
#: Candidates whose tabulated TFC-point forces are kept (:meth:`Candidates.keep_tables`): the local threads
#: run a racing stage's records in blocks of as many candidates as threads (:meth:`Evaluator._record_tasks`),
#: so a candidate's next record comes within a few candidates; ~1.7 MB each for the bulge scene's 13 protrusions.
TABLES_KEPT = 16
_CANDIDATES = Candidates(CANDIDATES_KEPT)
