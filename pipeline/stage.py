"""What a stage declares (:class:`Stage`), what its ``compute`` reads (:class:`Inputs`), and the stages
there are (:func:`registry`): the declarations the runner (:mod:`pipeline.runner`) makes current.

A stage is a declaration bound to the name ``STAGE`` in its module of :mod:`pipeline.stages`; :func:`registry`
discovers every such module, so a new stage plugs in by declaring itself (no list to edit).
"""

from __future__ import annotations

import importlib
import logging
import pkgutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import xarray as xr

from .config.fields import DeclaredScene, expand, fields
from .io import KEY_ATTR, DatasetError, read_dataset

log = logging.getLogger(__name__)

Scene = Any


def _constant(value: Any) -> Callable[[Scene], Any]:
    return lambda scene: value


@dataclass(frozen=True)
class Stage:
    """Declaration of a stage (bind it to ``STAGE`` in a module of :mod:`pipeline.stages`).

    Attributes
    ----------
    name
        The stage's name on the command line (``hdi NAME CONFIG``).
    compute
        ``compute(scene, inputs) -> xr.Dataset | {output: xr.Dataset | None}``: a dataset for a stage
        with one NetCDF output, else a mapping from output name to dataset (``None``: not produced
        this time, any old file of that name is removed). Non-NetCDF outputs are written by
        ``compute`` under ``inputs.staging`` at their declared relative paths.
    outputs
        Output paths relative to the results folder (a tuple, or a function of the scene). The first
        is the stage's primary output (returned by :func:`build`).
    reads
        The scene keys the result depends on, each a key of the schema (``"section.key"``, checked by
        :func:`pipeline.config.fields.fields`; ``"section.*"``: every key of the section): the fields its model
        builders declare and its own. They make the scene part of the inputs key; ``compute`` may read no other
        (but ``unkeyed``).
    unkeyed
        Scene keys ``compute`` also reads (or keys of ``reads`` left out of the key) whose effect the key
        holds another way: through ``derived`` values
        of them, or because they say how the work is cut, not what it computes (``sweep.batch_size``: parts
        of another batch are recomputed, never mixed).
    files
        ``files(scene) -> {role: path}``: input files named by scene keys (hashed by content).
    upstream
        Stages whose datasets this one reads (a tuple, or a function of the scene); they are made
        current first.
    options
        Options (keyword arguments of :func:`build`) that change the result: part of the key.
    order
        Position in listings and in ``hdi run``.
    main_job
        Part of ``hdi run`` (when :attr:`applies` to the scene).
    applies
        ``applies(scene) -> bool``: whether ``hdi run`` includes the stage for this scene.
    derived
        ``derived(scene) -> {name: value}``: quantities computed from scene keys that the result depends on
        instead of the keys themselves (e.g. the deepest protrusion of the interface tables, the larger
        of two keys): a change of the keys that leaves them equal changes nothing.
    optional
        Stages whose primary dataset this one reads *when it is current* but does not make current
        (e.g. ``identify`` for the report: a minutes-long study is never started by the report). The
        key holds each one's inputs key when its dataset is current, else ``None``; ``compute`` sees
        the same in :attr:`Inputs.optional` and must not read a dataset whose entry is ``None``.
    check
        ``check(scene)``: refuses, before anything is built or written, a scene the stage cannot use (a
        one-line :class:`~pipeline.config.scene.SceneError`; e.g. a study's box the model cannot evaluate,
        :func:`pipeline.analyses.feasibility.check_study`).
    keeps
        ``keeps(scene) -> (path, ...)``: the longest paths, relative to the results folder, of the files
        the stage writes there beyond its outputs (sweep parts, an evaluation store, the identified
        scene); only their lengths matter (:meth:`Runner.check_lengths`).
    finish
        ``finish(scene, out, options)``: run after the stage was asked for and is current (computed or
        not), for side effects outside the results folder (``report --readme``); ``options`` are those
        of :func:`build` and ``force``.
    simulates
        Whether ``compute`` integrates the slider's dynamics (the numba kernel, directly or through a
        study's evaluations): when such a stage is to be computed, the runner starts compiling the scene's
        kernel in a background process before the build's first stage, if neither this process nor the
        on-disk cache has it (:func:`pipeline.model.ahead.compile_kernel_ahead`).
    lazy_imports
        Modules ``compute`` imports only when it runs (matplotlib's, ~0.7 s; several seconds in a fresh
        environment, which writes their bytecode then): imported early, while the process waits for the
        kernel's background compile, when the stage is to be computed (:func:`pipeline.model.compiled.while_waiting`).
    doc
        One line for ``hdi --help``.
    """

    name: str
    compute: Callable[[Scene, "Inputs"], Any]
    outputs: tuple[str, ...] | Callable[[Scene], tuple[str, ...]]
    reads: tuple[str, ...] = ()
    unkeyed: tuple[str, ...] = ()
    files: Callable[[Scene], Mapping[str, str | Path]] = _constant({})
    upstream: tuple[str, ...] | Callable[[Scene], tuple[str, ...]] = ()
    options: tuple[str, ...] = ()
    order: float = 100.0
    main_job: bool = False
    applies: Callable[[Scene], bool] = _constant(True)
    derived: Callable[[Scene], Mapping[str, Any]] = _constant({})
    optional: tuple[str, ...] = ()
    check: Callable[[Scene], None] | None = None
    keeps: Callable[[Scene], tuple[str, ...]] = _constant(())
    finish: Callable[[Scene, Path, dict], None] | None = None
    simulates: bool = False
    lazy_imports: tuple[str, ...] = ()
    doc: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "reads", fields(*self.reads))
        object.__setattr__(self, "unkeyed", fields(*self.unkeyed))

    def keyed(self) -> tuple[str, ...]:
        """The scene keys of the inputs key: ``reads`` but ``unkeyed``, each ``"section.*"`` as the keys the
        section has now (:func:`pipeline.config.fields.expand`)."""
        unkeyed = set(expand(self.unkeyed))
        return tuple(k for k in expand(self.reads) if k not in unkeyed)

    def view(self, scene: Scene) -> DeclaredScene:
        """The scene as ``compute`` reads it: its declared keys only (:class:`pipeline.config.fields.DeclaredScene`)."""
        return DeclaredScene(scene, f"the {self.name} stage", (*self.reads, *self.unkeyed))

    def output_names(self, scene: Scene) -> tuple[str, ...]:
        return tuple(self.outputs(scene) if callable(self.outputs) else self.outputs)

    def upstream_names(self, scene: Scene) -> tuple[str, ...]:
        return tuple(self.upstream(scene) if callable(self.upstream) else self.upstream)


@dataclass
class Inputs:
    """What a stage's ``compute`` may read, and where it writes non-NetCDF outputs.

    Attributes
    ----------
    out
        The results folder (upstream datasets live there, made current by the runner).
    key
        The stage's inputs key (e.g. to tag intermediate files it keeps, like sweep parts).
    files
        The declared input files, role -> path.
    upstream
        Keys of the upstream stages, name -> inputs key.
    optional
        The optional stages (:attr:`Stage.optional`), name -> inputs key when their dataset is current,
        else ``None`` (not to be read).
    options
        Every option given to :func:`build` (the stage uses those it knows), and ``force``: whether
        the stage was forced (it then also remakes what it keeps between runs, like sweep parts).
    staging
        Folder for non-NetCDF outputs (their declared relative paths below it).
    writer
        Set by the runner: writes an output dataset now (:meth:`write_early`); ``None``: no early writes.
    early
        The datasets written early: output name -> (the dataset, its file in the staging folder).
    """

    out: Path
    key: str = ""
    files: dict[str, Path] = field(default_factory=dict)
    upstream: dict[str, str] = field(default_factory=dict)
    optional: dict[str, str | None] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)
    staging: Path | None = None
    metrics: dict[str, Any] = field(default_factory=dict)
    writer: Callable[[str, xr.Dataset], Path] | None = field(default=None, repr=False)
    early: dict[str, tuple[xr.Dataset, Path]] = field(default_factory=dict, repr=False)

    @classmethod
    def folder(cls, out: str | Path, **options: Any) -> "Inputs":
        """Inputs read from ``out`` as they are, outputs written straight into it (tests, scripts).

        No key is checked: the caller vouches for the datasets in ``out``.
        """
        out = Path(out).absolute()  # (tasks carry paths under it to workers, whose working directory is not ours)
        return cls(out=out, options=options, staging=out)

    def path(self, name: str) -> Path:
        """Path of a file in the results folder."""
        return self.out / name

    def dataset(self, name: str, stage: str | None = None, variables: Iterable[str] = ()) -> xr.Dataset:
        """Read an upstream (or current optional) dataset, refusing one made from other inputs than the
        runner expects."""
        ds = read_dataset(self.out / name, stage=stage, variables=variables)
        want = None if stage is None else self.upstream.get(stage) or self.optional.get(stage)
        if want is not None:
            have = ds.attrs.get(KEY_ATTR)
            if have != want:
                raise DatasetError(f"{self.out / name}: made from other inputs (inputs_key {str(have)[:12]}) than "
                                   f"this run's {stage} stage (inputs_key {want[:12]})")
        return ds

    def record(self, **metrics: Any) -> None:
        """Numbers about this run (timings, counts) for the run log, never for the datasets."""
        self.metrics.update(metrics)

    def write_early(self, name: str, ds: xr.Dataset) -> None:
        """Write the output dataset ``name``, complete before the computation ends, now: into the staging
        folder, with the provenance the runner gives it (:meth:`Runner._write`, which then moves it into
        place instead of writing it, when the stage returns this very ``ds`` for ``name``). The stage still
        returns ``ds``; a dataset changed after this call must not be returned as the same object. The first
        dataset output is written at the end all the same: it carries the list of outputs produced.

        Why: the write (compression of a large dataset) then overlaps work still running, such as the
        sweep's last batches, instead of adding to the command's serial end (docs/performance.md, section
        "The grid's serial part"). Nothing happens without a runner (:meth:`folder`), and a failed early
        write is left to the normal write at the end, which reports it."""
        if self.writer is None:
            return
        try:
            self.early[name] = (ds, self.writer(name, ds))
        except (OSError, RuntimeError) as exc:  # (the write at the end meets it again and names the output)
            log.debug("%s: early write failed (%s); written at the end", name, exc)


def registry() -> dict[str, Stage]:
    """Every stage declared in :mod:`pipeline.stages` (a module-level ``STAGE``), in ``order``."""
    from . import stages as package
    found: dict[str, Stage] = {}
    for info in pkgutil.iter_modules(package.__path__):
        module = importlib.import_module(f"{package.__name__}.{info.name}")
        stage = getattr(module, "STAGE", None)
        if isinstance(stage, Stage):
            if stage.name in found:
                raise RuntimeError(f"stage {stage.name!r} declared twice (pipeline.stages.{info.name})")
            found[stage.name] = stage
    return dict(sorted(found.items(), key=lambda kv: (kv[1].order, kv[0])))


def main_job(scene: Scene, stages: Mapping[str, Stage] | None = None) -> list[str]:
    """The stages of ``hdi run`` for a scene, in order."""
    stages = registry() if stages is None else stages
    return [n for n, s in stages.items() if s.main_job and s.applies(scene)]
