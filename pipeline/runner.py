"""One stage runner: declared inputs hashed by content, current outputs kept, atomic writes, one lock.

A stage is a declaration, :class:`Stage` (:mod:`pipeline.stage`), bound to the name ``STAGE`` in its module
of :mod:`pipeline.stages`; :func:`registry` discovers every such module, so a new stage plugs in by
declaring itself (no list to edit). A declaration says

* what the stage reads: scene keys (``reads``: schema keys, the union of the fields its model builders
  declare and its own, :func:`pipeline.config.fields.fields`), files named by scene keys (``files``, e.g.
  ``roughness.afm`` or ``dmw.source``) and other stages' datasets (``upstream``);
* what it writes (``outputs``, paths relative to the results folder);
* how it computes: a pure ``compute(scene, inputs) -> xr.Dataset | {output: xr.Dataset | None}``
  that reads only what it declared (through :class:`Inputs`) and writes nothing itself, except
  non-NetCDF outputs (figures, tables) which it writes under ``inputs.staging``. ``compute`` reads the
  scene through :class:`pipeline.config.fields.DeclaredScene`: a key outside ``reads`` (and ``unkeyed``)
  raises :class:`~pipeline.config.fields.UndeclaredRead`, naming the stage and the key. A dataset complete
  before the computation ends (the sweep's histories, while the last batches run) may be handed to
  :meth:`Inputs.write_early`: the runner writes it then, into the staging folder, and moves it into place
  with the others (the stage still returns it).

The runner gives each stage an *inputs key*: the SHA-256 of the scene keys it reads, the bytes of
the files it reads, the keys of its upstream stages (so a change propagates downstream), the options
that change its result and its code (the source of its module and of the ``pipeline`` modules that
module imports, :func:`pipeline.code_version.code_key`). Every dataset it writes carries that key (attribute
``inputs_key``); every stage's outputs are listed in ``.hdi/<stage>.json`` with the key, the scene's name and the
SHA-256 of each file. A stage whose outputs carry the key of its current inputs, and whose datasets read back
equal to their checksums (:func:`pipeline.io.stored_problem`: not damaged or edited since), is not recomputed;
otherwise it is, and everything downstream of it too. Outputs replace only files hdi wrote there for the same
scene (:meth:`Runner.check_owners`; ``force`` lifts it), and never an input file (:meth:`Runner.check_inputs_apart`). Datasets are written through :func:`pipeline.io.write_dataset` (temporary file
and rename), other outputs are renamed into place from the staging folder.

A results folder is used by one ``hdi`` process at a time: the runner builds while holding
:func:`pipeline.folder_lock.folder_lock` (``.hdi.lock``: a second process is refused, naming the first; a
lock whose process is gone is taken over; an interrupted run's temporary files are removed). While the
lock is held no symbolic link inside the folder is followed for a file the runner or a stage writes or
deletes (:func:`pipeline.paths.refuse_links`): the outputs, manifests and run log are checked before a
stage computes and again at each write. Before any stage runs, the longest path the build
writes is checked against the file system's limits (:meth:`Runner.check_lengths`).
"""

from __future__ import annotations

import datetime as _dt
import errno
import json
import logging
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any, Iterable, Mapping

import xarray as xr

from . import interrupts
from .code_version import code_key
from .cluster import shared_folder
from .stage import Inputs, Stage, main_job, registry
from .stage_keys import OUTPUTS_ATTR, SYNTHESIS_ONLY, dataset_key, digest, scene_part, unused_keys
from .progress import stage as progress_stage
from .model.inputs import SimulationInputs, from_folder
from .model import compiled
from .model.ahead import compile_kernel_ahead
from .model.scene_inputs import input_stages
from .folder_lock import LOCK_NAME, STAGING_PREFIX, folder_lock
from .io import (KEY_ATTR, DatasetBusy, DatasetError, RUN_ID, file_hash, move_dataset, read_attrs, stored_problem,
                 temporary_path, write_dataset)
from .paths import append_text, looked_for, refuse_links

log = logging.getLogger(__name__)

#: The names of the declaration and keys modules, used as ``runner.X`` by the stages and the tests.
__all__ = ["Inputs", "KEY_ATTR", "LOCK_NAME", "OUTPUTS_ATTR", "OutputRefused", "RUN_LOG", "Runner", "STATE_DIR",
           "SYNTHESIS_ONLY", "Stage", "build", "current_inputs", "ensure", "last_run", "main_job", "registry",
           "scene_part", "unused_keys"]

#: Hidden folder of the runner inside a results folder (manifests of non-NetCDF outputs, run log).
STATE_DIR = ".hdi"
#: The run log in :data:`STATE_DIR`: one JSON line of timings per computed stage.
RUN_LOG = "runs.jsonl"
#: The longest file name of the common file systems [B] (ext4, XFS, btrfs, tmpfs), for a folder name checked
#: before the file system can be asked (:meth:`Runner.check_lengths`).
_NAME_MAX_FALLBACK = 255

Scene = Any


class OutputRefused(DatasetError):
    """An output would replace a file hdi did not write there, another scene's results, or an input file."""


# -------------------------------------------------------------------------------------- the runner
class Runner:
    """Makes stages of one scene current in one results folder (see the module docstring)."""

    def __init__(self, scene: Scene, out: str | Path, stages: Mapping[str, Stage] | None = None,
                 in_memory: bool = False, **options: Any):
        self.scene = scene
        self.out = Path(out)
        #: ``out`` is a temporary folder whose datasets are read into memory and removed (the Python API's
        #: ``results=None``): the log says what is computed, and claims no file
        self.in_memory = in_memory
        self.stages = dict(registry() if stages is None else stages)
        self.options = options
        self._keys: dict[str, str] = {}
        self._files: dict[str, dict[str, Path]] = {}
        self._hashes: dict[Path, str] = {}
        self._done: set[str] = set()

    # ---- planning
    def stage(self, name: str) -> Stage:
        try:
            return self.stages[name]
        except KeyError:
            raise ValueError(f"unknown stage {name!r}; expected one of {', '.join(self.stages)}") from None

    def plan(self, targets: Iterable[str]) -> list[str]:
        """``targets`` and everything upstream of them, upstream first."""
        order: list[str] = []
        visiting: set[str] = set()

        def visit(name: str) -> None:
            if name in order:
                return
            if name in visiting:
                raise RuntimeError(f"stage {name!r} depends on itself")
            visiting.add(name)
            for up in self.stage(name).upstream_names(self.scene):
                visit(up)
            visiting.discard(name)
            order.append(name)

        for t in targets:
            visit(t)
        return order

    # ---- keys
    def files(self, name: str) -> dict[str, Path]:
        if name not in self._files:
            files = {role: Path(p) for role, p in self.stage(name).files(self.scene).items()}
            for role, p in files.items():
                if not p.is_file():
                    raise FileNotFoundError(f"{name}: input file {p} ({role}) does not exist{looked_for(p)}")
            self._files[name] = files
        return self._files[name]

    def _hash(self, path: Path) -> str:
        if path not in self._hashes:  # each file hashed once per run (a run does not edit its inputs)
            self._hashes[path] = file_hash(path)
        return self._hashes[path]

    def key(self, name: str) -> str:
        """The inputs key of a stage (module docstring)."""
        if name not in self._keys:
            st = self.stage(name)
            payload = {
                "stage": name, "code": code_key(st.compute.__module__),
                "scene": scene_part(self.scene, st.keyed()),
                "files": {role: self._hash(p) for role, p in self.files(name).items()},
                "upstream": {u: self.key(u) for u in st.upstream_names(self.scene)},
                "options": {o: self.options.get(o) for o in st.options},
                "derived": dict(st.derived(self.scene)),
                "optional": self.optional(name),
            }
            self._keys[name] = digest(payload)
        return self._keys[name]

    def optional(self, name: str) -> dict[str, str | None]:
        """The optional stages of ``name`` (see :class:`Stage`): inputs key when current, else ``None``."""
        return {o: None if o not in self.stages or self.stale_reason(o) else self.key(o)
                for o in self.stage(name).optional}

    # ---- state of the outputs
    def _manifest(self, name: str) -> Path:
        return self.out / STATE_DIR / f"{name}.json"

    def stale_reason(self, name: str) -> str | None:
        """Why a stage must be computed (``None``: its outputs are current)."""
        st, key = self.stage(name), self.key(name)
        outputs = st.output_names(self.scene)
        datasets = [o for o in outputs if o.endswith(".nc")]
        others = [o for o in outputs if not o.endswith(".nc")]
        produced: list[str] | None = None
        try:
            manifest = json.loads(self._manifest(name).read_text())
            if not isinstance(manifest, dict):
                raise ValueError
        except (OSError, ValueError):
            manifest = None
        # the datasets' bytes as written, when recorded for these inputs (stored_problem: read back only if changed)
        files = manifest.get("files", {}) if manifest is not None and manifest.get("key") == key else {}
        if others:
            if manifest is None:
                return "no record of its outputs"
            if manifest.get("key") != key:
                return "inputs changed"
            produced = manifest.get("outputs", [])
            for o, digest in manifest.get("hashes", {}).items():
                p = self.out / o
                if not p.is_file() or self._hash(p) != digest:
                    return f"{o} missing or changed"
        for i, o in enumerate(datasets):
            if produced is not None and o not in produced:
                continue
            p = self.out / o
            if not p.is_file():
                return f"{o} missing"
            have, listed = dataset_key(p)
            if have != key:
                return f"{o} made from other inputs" if have else f"{o} has no inputs key"
            problem = stored_problem(p, files.get(o))  # (a damaged chunk, a hand edit: recomputed, never reused)
            if problem is not None:
                return f"{o}: {problem}"
            if i == 0 and listed is not None:
                produced = listed
        return None

    # ---- making
    def build(self, targets: Iterable[str], force: bool = False) -> dict[str, tuple[Path, ...]]:
        """Make ``targets`` current (and everything upstream); returns each target's output paths.

        ``force`` recomputes the targets themselves even when current (not their upstream stages).
        """
        targets = list(targets)
        for name in targets:  # (before the folder is made: a refused scene writes nothing)
            if self.stage(name).check is not None:
                self.stage(name).check(self.scene)
        self.check_lengths(targets)
        self.check_inputs_apart(targets)
        with folder_lock(self.out):
            self.check_owners(targets, force)
            self.compile_ahead(targets, force)
            for name in self.plan(targets):
                self._make(name, force and name in targets)
            for name in targets:
                if self.stage(name).finish is not None:
                    self.stage(name).finish(self.scene, self.out, {**self.options, "force": force})
        return {t: tuple(self.out / o for o in self.stage(t).output_names(self.scene)) for t in targets}

    def check_inputs_apart(self, targets: Iterable[str]) -> None:
        """Refuse, before anything is written, an input file of a stage of the build (``dmw.source``, an AFM
        scan) that is a file some stage writes in the results folder (``results/x/dmw.nc`` given as the
        record): the output would overwrite it. No option lifts this.

        Raises
        ------
        OutputRefused
            Naming the scene key, the file and the output it would become.
        """
        written: dict[str, tuple[str, str]] = {}
        for st in self.stages.values():
            try:
                names = st.output_names(self.scene)
            except (KeyError, TypeError, ValueError):  # (a stage this scene cannot declare outputs for)
                continue
            for o in names:
                written[os.path.realpath(self.out / o)] = (st.name, o)
        for name in self.plan(targets):
            for role, p in self.files(name).items():
                hit = written.get(os.path.realpath(p))  # (a link there resolved: its target is the output's path)
                if hit is not None:
                    raise OutputRefused(f"{role} = {p}: is the file {hit[1]} the {hit[0]} stage writes in the results "
                                        f"folder {self.out}; an input is never overwritten by an output: move it out "
                                        "of the results folder, or choose another --out")

    def check_owners(self, targets: Iterable[str], force: bool = False) -> None:
        """Refuse, before any stage computes, to replace a file at an output path that hdi did not write
        there, or that holds another scene's results; ``force`` (``--force``) replaces them.

        hdi wrote a file at an output path of a stage when the stage's record (``.hdi/<stage>.json``) lists
        it, or, for a dataset, when its provenance (:func:`pipeline.io.provenance`) names the stage (attribute
        ``stage``; ``hdi roughness FILE... --out DIR`` writes one without an inputs key).
        Its scene is the dataset's ``scene_name``, else the record's ``scene``; results of a scene of another
        name are another scene's (``results/<scene name>/`` is each scene's own folder). Only the stages this
        build computes are checked (those forced or not current).

        Raises
        ------
        OutputRefused
            Naming the file, whose it is, and what to do.
        """
        if force:
            return
        targets = list(targets)
        for name in self.plan(targets):
            if self.stale_reason(name) is None:
                continue
            st = self.stage(name)
            try:
                record = json.loads(self._manifest(name).read_text())
                if not isinstance(record, dict):
                    record = {}
            except (OSError, ValueError):
                record = {}
            listed = {*record.get("outputs", []), *record.get("hashes", {})}
            for o in st.output_names(self.scene):
                p = self.out / o
                if not p.is_file() or p.is_symlink():  # (a folder, a link: refused by _check_outputs)
                    continue
                attrs: dict[str, Any] = {}
                if o.endswith(".nc"):
                    try:
                        attrs = read_attrs(p)[0]
                    except DatasetBusy:
                        raise
                    except (OSError, ValueError, RuntimeError):  # (unreadable: the record says whose it is)
                        attrs = {}
                ours = attrs.get("stage") == name and "pipeline_version" in attrs  # (hdi's provenance, io.provenance)
                if not ours and o not in listed:
                    raise OutputRefused(f"{p}: not written by hdi (no {name} stage's record of it), and the {name} "
                                        f"stage would replace it: move it away, choose another --out, or pass --force "
                                        "to replace it")
                scene = attrs.get("scene_name") if ours else record.get("scene")
                if scene is not None and scene != self.scene.name:
                    raise OutputRefused(f"{p}: results of the scene {scene!r}, not of this run's {self.scene.name!r}; "
                                        "run each scene into its own folder (--out; the default is results/<scene "
                                        "name>/), or pass --force to replace them")

    def compile_ahead(self, targets: Iterable[str], force: bool = False) -> None:
        """Start compiling the scene's dynamics kernel in a background process when a stage this build
        computes simulates (:attr:`Stage.simulates`), before the first stage runs: on a first run (no kernel
        in the on-disk cache) the compile then overlaps the upstream stages and the static solver's compile
        instead of starting at the first integration; the modules the stages to compute import lazily
        (:attr:`Stage.lazy_imports`) are imported while the process waits for it (docs/performance.md,
        section "The first run"). Nothing when every such stage is current."""
        targets = list(targets)
        todo = []
        for name in self.plan(targets):
            try:
                if force and name in targets or self.stale_reason(name) is not None:
                    todo.append(self.stage(name))
            except (OSError, ValueError):  # (the build meets it again, and says it in its own words)
                continue
        if not any(st.simulates for st in todo):
            return
        compile_kernel_ahead(self.scene)
        modules = tuple(dict.fromkeys(m for st in todo for m in st.lazy_imports))
        if modules:
            compiled.while_waiting(compiled.import_modules(modules))

    def written_paths(self, targets: Iterable[str]) -> list[str]:
        """The paths, relative to the results folder, a build of ``targets`` may write, each with the
        longest temporary name hdi gives it (:func:`pipeline.io.temporary_prefix` and ``mkstemp``'s 8
        characters): outputs, their staging copies, the runner's records and what stages keep."""
        probe = f".hdi-{RUN_ID}.{'x' * 8}.tmp"
        staging = STAGING_PREFIX + "x" * 8
        paths = [LOCK_NAME, f"{STATE_DIR}/.{RUN_LOG}{probe}"]
        for name in self.plan(targets):
            st = self.stage(name)
            paths.append(f"{STATE_DIR}/.{name}.json{probe}")
            outputs = st.output_names(self.scene)
            for o in (*outputs, *st.keeps(self.scene)):
                folder, _, base = o.rpartition("/")
                tmp = f"{folder}/.{base}{probe}" if folder else f".{base}{probe}"
                paths.append(tmp)
                if o in outputs:  # (drawn, or a dataset written early, in the staging folder, then moved)
                    paths.append(f"{staging}/{tmp}")
        return paths

    def check_lengths(self, targets: Iterable[str]) -> None:
        """Refuse, before any stage runs, a results folder or scene name that makes a path the build writes
        longer than the file system allows (``PC_NAME_MAX`` for one name, ``PC_PATH_MAX`` for the whole
        path): such a write failed only when it came, after the stages before it (a 250-character scene
        name after the whole identification, a 4030-byte ``--out`` at the report, naming a temporary file).

        Raises
        ------
        OSError
            ``ENAMETOOLONG``, naming the results folder, the longest name or length and the limit.
        """
        out = Path(os.path.abspath(self.out))
        for part in out.parts[1:]:  # (checked first: a path with too long a name cannot even be looked up)
            if len(os.fsencode(part)) > _NAME_MAX_FALLBACK:
                raise OSError(errno.ENAMETOOLONG, f"a folder name of {len(os.fsencode(part))} bytes in it, the "
                              f"file system allows {_NAME_MAX_FALLBACK}; choose a shorter --out or scene name",
                              str(self.out))
        existing = next(p for p in (out, *out.parents) if p.exists())
        try:
            name_max = os.pathconf(existing, "PC_NAME_MAX")
            path_max = os.pathconf(existing, "PC_PATH_MAX")
        except (OSError, ValueError):  # (not POSIX, or the file system does not say)
            return
        paths = self.written_paths(targets)
        for rel in paths:
            for part in Path(rel).parts:
                if len(os.fsencode(part)) > name_max:
                    raise OSError(errno.ENAMETOOLONG, f"the file name {part!r} this run writes (its temporary "
                                  f"name) is {len(os.fsencode(part))} bytes long, the file system allows {name_max}; "
                                  "choose a shorter scene name (scene.name)", str(self.out))
        longest = max(paths, key=lambda rel: len(os.fsencode(rel)))
        size = len(os.fsencode(str(out / longest)))
        if size >= path_max:  # (PC_PATH_MAX counts the terminating NUL)
            raise OSError(errno.ENAMETOOLONG, f"the longest path this run writes, {longest} (a temporary name) in "
                          f"it, is {size} bytes long, the file system allows {path_max - 1}; choose a shorter --out",
                          str(self.out))

    def _make(self, name: str, force: bool) -> None:
        if name in self._done:
            return
        reason = "forced" if force else self.stale_reason(name)
        key = self.key(name)
        if reason is None:
            log.info("%s: up to date (inputs %s)", name, key[:12])
            self._done.add(name)
            return
        st = self.stage(name)
        self._check_outputs(st)
        log.info("%s: computing (%s)", name, "in memory" if self.in_memory else reason)
        t0 = time.perf_counter()
        staging = Path(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=self.out.absolute()))
        try:
            # the folder as an absolute path: the stage's tasks carry paths under it to dask workers, which
            # resolve a relative path from their own working directory; they check they see it (fanout)
            inputs = Inputs(out=self.out.absolute(), key=key, files=dict(self.files(name)),
                            upstream={u: self.key(u) for u in st.upstream_names(self.scene)},
                            optional=self.optional(name), options={**self.options, "force": force},
                            staging=staging)
            inputs.writer = lambda output, ds: self._write_one(st, key, inputs, output, ds, staging / output)
            with shared_folder(inputs.out), progress_stage(name):  # (its progress lines carry its name)
                result = st.compute(st.view(self.scene), inputs)
            interrupts.check()  # (a signal a library swallowed during the computation: nothing is written)
            written = self._write(st, key, inputs, result, staging)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
        seconds = time.perf_counter() - t0
        if self.in_memory:
            log.info("%s: computed in memory, no file kept: %s (%.1f s)", name,
                     st.doc.rsplit(", ", 1)[0] if st.doc else "its datasets", seconds)
        else:
            log.info("%s: wrote %s (%.1f s)", name, ", ".join(written) or "nothing", seconds)
        self._log_run(name, key, written, seconds, inputs.metrics)
        self._done.add(name)

    def _check_outputs(self, st: Stage) -> None:
        """Refuse, before the stage computes, an output path that is a folder or lies below a file
        (``sweep.nc`` a folder, ``figures`` a file): the write would fail only after the computation; and
        a symbolic link on the way to an output or to the runner's records (:func:`pipeline.paths.refuse_links`)."""
        refuse_links(self._manifest(st.name))
        refuse_links(self.out / STATE_DIR / RUN_LOG)
        for o in st.output_names(self.scene):
            target = refuse_links(self.out / o)  # (a planted link: refused before the stage computes)
            if target.is_dir():
                raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(target))
            for parent in list(Path(o).parents)[:-1]:
                if (self.out / parent).exists() and not (self.out / parent).is_dir():
                    raise FileExistsError(errno.EEXIST, "is a file, not a folder", str(self.out / parent))

    def _write(self, st: Stage, key: str, inputs: Inputs, result: Any, staging: Path) -> list[str]:
        outputs = st.output_names(self.scene)
        if isinstance(result, xr.Dataset):
            result = {outputs[0]: result}
        result = dict(result or {})
        unknown = [o for o in result if o not in outputs]
        if unknown:
            raise RuntimeError(f"stage {st.name} produced undeclared outputs {unknown}; declared {list(outputs)}")
        others = [o for o in outputs if not o.endswith(".nc")]
        produced = [o for o in outputs if (result.get(o) is not None if o.endswith(".nc")
                                           else (staging / o).is_file())]
        first = True
        for o in outputs:
            if not o.endswith(".nc"):
                continue
            ds = result.get(o)
            if ds is None:
                # not produced this time: no stale file of an older run
                refuse_links(self.out / o).unlink(missing_ok=True)
                continue
            early = inputs.early.get(o)
            if first:  # (the list of outputs goes into the first dataset: known only now)
                self._write_one(st, key, inputs, o, ds, self.out / o, {OUTPUTS_ATTR: json.dumps(produced)})
                first = False
            elif early is not None and early[0] is ds:  # (written while the stage computed: moved into place)
                move_dataset(early[1], self.out / o)
            else:
                self._write_one(st, key, inputs, o, ds, self.out / o)
        hashes = {}
        for o in others:
            target = refuse_links(self.out / o)
            if (staging / o).is_file():
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(staging / o, target)
                hashes[o] = file_hash(target)
                self._hashes[target] = hashes[o]
            else:
                target.unlink(missing_ok=True)
        # the record of what the stage wrote here, for which scene (whose files the outputs are: check_owners) and
        # the SHA-256 of each dataset's bytes (a dataset whose bytes are unchanged is not read back: stale_reason)
        manifest = refuse_links(self._manifest(st.name))
        manifest.parent.mkdir(parents=True, exist_ok=True)
        refuse_links(manifest)
        tmp = temporary_path(manifest)
        files = {o: file_hash(self.out / o) for o in produced if o.endswith(".nc")}
        tmp.write_text(json.dumps({"key": key, "outputs": produced, "hashes": hashes, "files": files,
                                   "scene": self.scene.name}, indent=1))
        os.replace(tmp, manifest)
        return produced

    def _write_one(self, st: Stage, key: str, inputs: Inputs, name: str, ds: xr.Dataset, path: Path,
                   extra: dict[str, str] | None = None) -> Path:
        """Write the output dataset ``name`` of stage ``st`` to ``path`` with the runner's attributes (the
        inputs key, the upstream keys, ``extra``) and provenance (the hashes of the declared input files)."""
        if name not in st.output_names(self.scene) or not name.endswith(".nc"):
            raise ValueError(f"stage {st.name} wrote {name!r} early; its dataset outputs are "
                             f"{[o for o in st.output_names(self.scene) if o.endswith('.nc')]}")
        attrs = {KEY_ATTR: key, "upstream_keys": json.dumps(inputs.upstream, sort_keys=True), **(extra or {})}
        return write_dataset(ds, path, self.scene, stage=st.name,
                             inputs={p: self._hash(p) for p in inputs.files.values()}, extra_attrs=attrs)

    def _log_run(self, name: str, key: str, written: list[str], seconds: float, metrics: dict) -> None:
        """Append the run's timings to ``.hdi/runs.jsonl`` (kept out of the datasets) when it has metrics."""
        if not metrics:
            return
        entry = {"stage": name, "inputs_key": key, "finished": _dt.datetime.now(_dt.timezone.utc).isoformat(),
                 "seconds": round(seconds, 3), "outputs": written, **metrics}
        append_text(self.out / STATE_DIR / RUN_LOG, json.dumps(entry, default=str) + "\n")


def build(targets: str | Iterable[str], scene: Scene, out: str | Path, *, force: bool = False,
          **options: Any) -> dict[str, tuple[Path, ...]]:
    """Make stages current in ``out`` (see :class:`Runner`); returns each target's output paths."""
    if isinstance(targets, str):
        targets = [targets]
    return Runner(scene, out, **options).build(targets, force=force)


def ensure(name: str, scene: Scene, out: str | Path, **options: Any) -> Path:
    """The primary output of stage ``name`` in ``out``, made current first."""
    return build([name], scene, out, **options)[name][0]


def current_inputs(scene: Scene, out: str | Path, calibration: bool = False,
                      k: float | None = None, in_memory: bool = False) -> SimulationInputs:
    """What one simulation of ``scene`` reads, its upstream stages made current in ``out`` first
    (:func:`pipeline.model.scene_inputs.input_stages`; scripts, benchmarks, tests, :mod:`pipeline.api`:
    a stage reads through :func:`pipeline.model.inputs.for_stage`). ``calibration``: also calibrate and
    resolve k; ``k``: an explicit k [1] instead, resolved without a calibration (the ``option k`` of
    :func:`pipeline.model.scene_inputs.contact_k`); ``in_memory``: ``out`` is a temporary folder
    (:attr:`Runner.in_memory`)."""
    wanted = input_stages(scene, calibration and k is None)
    if wanted:
        build(wanted, scene, out, in_memory=in_memory)
    return from_folder(scene, out, calibration=calibration or k is not None, k=k)


def last_run(out: str | Path, stage: str) -> dict[str, Any] | None:
    """The last run-log entry of a stage in ``out`` (``None`` when there is none)."""
    path = Path(out) / STATE_DIR / RUN_LOG
    if not path.is_file():
        return None
    entries = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    entries = [e for e in entries if e.get("stage") == stage]
    return entries[-1] if entries else None
