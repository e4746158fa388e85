"""Checks of the command line and of derived material parameters, before anything runs.

:func:`check_options` validates the options of ``hdi STAGE`` against the stage and the scene, so a
mistake ends in one line naming the option (exit 2, :class:`pipeline.options.OptionError`; how a message
names an option: :mod:`pipeline.options`) before any stage starts and before anything is written:
``--workers`` must be a positive integer, ``--scheduler`` must answer as a dask scheduler with workers
(:func:`pipeline.scheduler.check_scheduler`), ``--out`` must be a folder we can write in, the sweep grid must
not exceed :data:`MAX_SCENES` unless ``--yes``, the report's history protrusions must lie on the sweep grid,
and an option the stage does not use is an error naming the option and the stages that use it.

:func:`one_line_warnings` prints the :class:`~pipeline.physics.material_bounds.PhysicsWarning` of
derived material parameters as one line. The checks of this module decide what runs, not what a
stage computes: :mod:`pipeline.code_version` leaves this module out of the stages' code keys.
"""

from __future__ import annotations

import math
import os
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .config.grid import label, range_count, roughness_sets, same_point
from .config.schema import SCHEMA
from .file_errors import is_read_only
from .paths import looked_for, special_kind
from . import sizing
from .config import limits
from .physics.material_bounds import PhysicsWarning
from .options import OptionError, first_line, command, flag, given, switch
from .scheduler import check_scheduler


#: Largest sweep grid (protrusions x roughness sets x damping ratios) run without ``--yes``:
#: about 30 CPU-minutes at ~20 ms per 2 ms scene on one core (docs/performance.md, "Tests and benchmarks");
#: the other sizes are bounded in :mod:`pipeline.config.limits`.
MAX_SCENES = limits.MAX_SCENES

#: Options and the stages that use them (``run`` uses those of all its stages; ``--force`` and
#: ``--out`` apply to every stage). ``--channel``/``--detrend`` act only on AFM files given directly.
OPTION_STAGES: dict[str, tuple[str, ...]] = {
    # (the ensemble fans out its realisations; the report makes sweep, calibrate and ensemble current first)
    "scheduler": ("sweep", "run", "calibrate", "ensemble", "report", "identify", "sensitivity"),
    "workers": ("sweep", "run", "calibrate", "ensemble", "report", "identify", "sensitivity"),
    "yes": ("sweep", "run", "dmw", "interface", "calibrate", "simulate", "accuracy", "report", "identify",
            "sensitivity"),
    "readme": ("report", "run"),
    "write_scene": ("identify",),
    "channel": ("roughness FILE...",),
    "detrend": ("roughness FILE...",),
}
_SCENE_KEY = {"channel": "roughness.channel", "detrend": "roughness.detrend"}


def check_workers(workers: int | None) -> None:
    """``--workers`` is absent or a positive integer (from Python: an ``int``, not ``"2"`` or ``2.0``)."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)):
        raise OptionError(f"{given('workers', workers, text=True)}: expected a positive integer number of local "
                          f"workers (1 or more), got {type(workers).__name__}")
    if workers is not None and workers < 1:
        raise OptionError(f"{given('workers', workers)}: expected a positive number of local workers (1 or more)")


def check_flag(option: str, value: Any) -> None:
    """A switch given from Python (``option``: how an error names it, ``--force``, ``--yes``, or in a Python
    call ``force``, ``progress``) is ``True`` or ``False`` (``"no"`` is truthy)."""
    if not isinstance(value, bool):
        name = option.rstrip(" =")
        shown = f"{name} = {value!r}" if not name.startswith("--") else f"{option} {value!r}"
        raise OptionError(f"{shown}: expected True or False, got {type(value).__name__}")


def check_path_option(value: Any, option: str) -> None:
    """An option naming a file or folder (``option``: ``--out``, or a Python argument ``results``) is absent
    or a path (``str`` or ``os.PathLike``), not ``123``."""
    if value is not None and not isinstance(value, (str, os.PathLike)):
        shown = f"{option} {value!r}" if option.startswith("--") else f"{option} = {value!r}"
        raise OptionError(f"{shown}: expected a path (str or pathlib.Path), got {type(value).__name__}")


def check_protrusions(values: Any, flying_height_nm: float, what: str = "protrusions") -> list[float]:
    """TFC protrusions [nm] given from Python: a sequence of numbers, each as ``tfc.protrusion_nm`` allows
    (finite, >= 0: the scene key's own check, :data:`pipeline.config.scene.SCHEMA`) and at most
    ``flying_height_nm`` + :data:`pipeline.config.limits.MAX_INTERFERENCE_NM` (:func:`pipeline.config.limits.check_physical`).

    Returns
    -------
    list of float
        The protrusions [nm].

    Raises
    ------
    OptionError
        Naming ``what``, the position and the value.
    """
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or getattr(values, "ndim", 1) != 1:
        raise OptionError(f"{what} = {values!r}: expected a list of protrusions [nm] (e.g. [9.0] for one), "
                          f"got {type(values).__name__}")
    pred, expected = SCHEMA["tfc"]["protrusion_nm"].check or (lambda v: True, "")
    out = []
    for i, v in enumerate(values):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise OptionError(f"{what}[{i}] = {v!r}: expected a number [nm], got {type(v).__name__}")
        v = float(v)
        if not math.isfinite(v) or not pred(v):
            raise OptionError(f"{what}[{i}] = {v!r}: expected {expected} [nm], finite (as tfc.protrusion_nm)")
        if v - flying_height_nm > limits.MAX_INTERFERENCE_NM:
            raise OptionError(f"{what}[{i}] = {v:g} nm: expected at most the flying height {flying_height_nm:g} nm "
                              f"+ {limits.MAX_INTERFERENCE_NM:g} nm (as tfc.protrusion_nm)")
        out.append(v)
    return out


def integration_line(exc: BaseException, scene: Any = None) -> str:
    """One line for a failed integration (:class:`pipeline.model.running.IntegrationError`, whose text names
    the protrusion, the integrator's status and the scene keys to change: :data:`pipeline.model.running.HINTS`):
    the scene (its file and name) and that text."""
    text = first_line(exc, 600)
    where = ""
    if scene is not None:
        path = getattr(scene, "path", None)
        where = f"{path} (scene {scene.name}): " if path else f"scene {scene.name}: "
    return f"{where}{text}"


def check_out(out: str | Path | None, option: str | None = None) -> None:
    """``--out`` (``option``: how an error names it; default :func:`flag` of ``out``) is a folder that exists
    or can be created, and that we can write in."""
    if out is None:
        return
    option = flag("out") if option is None else option
    check_path_option(out, option)
    path = Path(out)
    probe = path
    while not _exists(probe):  # the nearest existing ancestor decides whether the folder can be made
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        what = "is a file" if probe == path else f"cannot be created: {probe} is a file"
        raise OptionError(f"{_named(option, out)}: {what}; expected a folder")
    check_name_lengths(path, probe, option)
    try:  # os.access alone misses read-only mounts and says yes to root everywhere
        fd, tmp = tempfile.mkstemp(prefix=".hdi-write-test.", dir=probe)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        where = "" if probe == path else f" (cannot create it in {probe})"
        raise OptionError(f"{_named(option, out)}: not writable{where}: {exc.strerror or exc}") from None


def _named(option: str, value: Any) -> str:
    """An option and its path in a message: ``--out results/x``, or a Python argument ``results = 'results/x'``."""
    return f"{option} {value}" if option.startswith("--") else f"{option} = {os.fspath(value)!r}"


def _exists(path: Path) -> bool:
    """``path.exists()``, false for a path the file system cannot even look up (a name too long: Python
    3.11's ``exists`` raises)."""
    try:
        return path.exists()
    except OSError:
        return False


def check_name_lengths(path: Path, existing: Path, option: str) -> None:
    """Every name of ``path`` below its existing ancestor ``existing`` fits the file system's limit on
    a name (``NAME_MAX``, 255 bytes on most), so making it does not fail with "File name too long"."""
    try:
        limit = os.pathconf(existing if existing.is_dir() else existing.parent, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):  # (no pathconf: not POSIX)
        return
    for part in path.parts[len(existing.parts):] if path != existing else ():
        size = len(os.fsencode(part))
        if limit and size > limit:
            raise OptionError(f"{_named(option, path)}: the name {part[:20]}... is {size} bytes, longer than the "
                              f"{limit} bytes its file system allows; choose a shorter name")


def check_readme(readme: str | Path | None) -> None:
    """``--readme`` is an existing markdown page, the one holding the generated section (``make readme``:
    docs/results.md; a symbolic link to one: the report writes through it)
    that is not read-only: checked before the run, which would otherwise fail, or overwrite a file
    the user protected, only at its end."""
    if readme is None:
        return
    path = Path(readme)
    if path.is_dir():
        raise OptionError(f"--readme {readme}: is a folder; expected the page whose generated "
                          "section the report rewrites (e.g. docs/results.md)")
    if special_kind(path) is not None:  # (a FIFO: reading it would wait forever)
        raise OptionError(f"--readme {readme}: is {special_kind(path)}; expected the page whose generated "
                          "section the report rewrites (e.g. docs/results.md)")
    if not path.is_file():
        raise OptionError(f"--readme {readme}: file does not exist{looked_for(readme)}; expected the page whose generated "
                          "section the report rewrites (e.g. docs/results.md)")
    if is_read_only(path):
        raise OptionError(f"--readme {readme}: is read-only; make it writable (chmod u+w) for the report to "
                          "update it, or leave --readme out")


def check_write_scene(path: str | Path | None, force: bool = False) -> None:
    """``--write-scene PATH`` names a file that can be written in an existing folder, and that does not
    exist unless ``force`` (identify's study runs for minutes: a path it cannot write to is refused
    before it starts, not after)."""
    if path is None:
        return
    path = Path(path)
    if path.is_dir():
        raise OptionError(f"--write-scene {path}: is a folder; expected the path of a scene file (.toml)")
    if path.exists() and not force:
        raise OptionError(f"--write-scene {path}: exists; name a new file, or pass --force to replace it "
                          "(--force also recomputes the identification)")
    folder = path.parent
    if not folder.is_dir():
        raise OptionError(f"--write-scene {path}: folder {folder} does not exist{looked_for(folder)}; expected an "
                          "existing folder")
    try:  # (a read-only folder or mount: found now, not after the study)
        fd, tmp = tempfile.mkstemp(prefix=".hdi-write-test.", dir=folder)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise OptionError(f"--write-scene {path}: folder {folder} is not writable: {exc.strerror or exc}") from None


def grid_size(scene: Any) -> tuple[int, int, int]:
    """Number of protrusions, roughness sets and damping ratios of the sweep (no grid is built)."""
    n_sets = len(scene["sweep"]["roughness"] or [None])   # (no set is validated here: the sweep does)
    n_damp = len(scene["sweep"]["damping_ratio"] or [None])
    return range_count(scene["sweep"]["protrusion_nm"]), n_sets, n_damp


def check_grid(scene: Any, yes: bool = False, limit: int = MAX_SCENES) -> None:
    """Refuse a sweep of more than ``limit`` scenes unless ``yes``."""
    n_prot, n_sets, n_damp = grid_size(scene)
    total = n_prot * n_sets * n_damp
    if total > limit and not yes:
        g = scene["sweep"]["protrusion_nm"]
        raise OptionError(f"sweep.protrusion_nm = {{start={g['start']:g}, stop={g['stop']:g}, step={g['step']:g}}}: "
                          f"{total:,} scenes ({n_prot:,} protrusions x {n_sets} roughness sets x {n_damp} damping "
                          f"ratios) exceed {limit:,}; pass {switch('yes')} to run them anyway")


def check_sweep_histories(scene: Any) -> None:
    """Every protrusion of ``sweep.histories_nm`` is a point of the sweep's grid: one off the grid was
    kept by no batch, silently. The message names the nearest grid points. (Without the key the sweep
    keeps those of ``report.histories_nm`` on its grid; the report checks its own.)"""
    g = scene["sweep"]["protrusion_nm"]
    n = range_count(g)
    for h in scene["sweep"]["histories_nm"] or []:
        j = min(max(round((h - g["start"]) / g["step"]), 0), n - 1)
        if same_point(label(g["start"] + j * g["step"]), h):
            continue
        near = sorted({label(g["start"] + i * g["step"]) for i in (j - 1, j, j + 1) if 0 <= i < n},
                      key=lambda x: abs(x - h))[:2]
        raise OptionError(f"sweep.histories_nm: {h:.10g} nm is not on the sweep grid (sweep.protrusion_nm: "
                          f"{g['start']:g} to {g['stop']:g} nm in steps of {g['step']:g}); the nearest grid points are "
                          + " and ".join(f"{x:.10g}" for x in sorted(near)) + " nm")


def check_report_histories(scene: Any) -> None:
    """Every protrusion of ``report.histories_nm`` is a point of the sweep's protrusion grid, to the
    1e-9 nm the sweep matches them with (:func:`pipeline.config.grid.range_grid`, without
    building the grid)."""
    g = scene["sweep"]["protrusion_nm"]
    n = range_count(g)
    off = []
    for h in scene["report"]["histories_nm"] or []:
        j = round((h - g["start"]) / g["step"])
        if not 0 <= j < n or not same_point(label(g["start"] + j * g["step"]), h):
            off.append(h)
    if off:
        raise OptionError(f"report.histories_nm: {', '.join(f'{h:.10g}' for h in off)} nm not on the sweep grid "
                          f"(sweep.protrusion_nm: {g['start']:g} to {g['stop']:g} nm in steps of {g['step']:g}); "
                          "choose protrusions of the grid")


def check_stage_options(stage: str, given: dict[str, Any], afm_files: bool = False) -> None:
    """An option the stage does not use is an error naming the option and the stages that use it."""
    for name, value in given.items():
        if name not in OPTION_STAGES or value in (None, False):
            continue
        users = OPTION_STAGES[name]
        used = (stage == "roughness" and afm_files) if name in ("channel", "detrend") else stage in users
        if not used:
            hint = f" (for a scene, use --set {_SCENE_KEY[name]}=...)" if name in _SCENE_KEY else ""
            raise OptionError(f"{flag(name)}: not used by {command(stage)}; only by {', '.join(users)}{hint}")


def check_options(stage: str, scene: Any, *, out: str | Path | None = None, scheduler: str | None = None,
                  workers: int | None = None, yes: bool = False, force: bool = False, **given: Any) -> str | None:
    """Every check of this module that applies to ``hdi STAGE`` (``scene`` may be ``None`` for AFM files).

    Returns
    -------
    str or None
        The scheduler the stage's fan-out uses (:func:`check_scheduler`: ``--scheduler``, a scheduler
        file's address or ``DASK_SCHEDULER_ADDRESS``); ``None``: the local default.

    Raises
    ------
    OptionError
        The first problem found, in one line naming the option.
    """
    check_stage_options(stage, {"scheduler": scheduler, "workers": workers, "yes": yes, **given},
                        afm_files=scene is None)
    check_workers(workers)
    check_flag(flag("yes"), yes)
    check_flag(flag("force"), force)
    for name in ("readme", "write_scene"):
        check_path_option(given.get(name), flag(name))
    check_out(out)
    check_readme(given.get("readme"))
    check_write_scene(given.get("write_scene"), force)
    if scene is not None and stage in ("sweep", "run"):
        check_grid(scene, yes)
    if scene is not None:
        try:
            sizing.check_sizes(scene, stage, yes, where=str(scene.path or "scene"), lift=switch("yes"))
        except limits.LimitError as exc:
            raise OptionError(str(exc)) from None
    if scene is not None and stage in ("report", "run"):
        check_report_histories(scene)
    if scene is not None:  # (the sweep's inputs, checked before calibrate runs for minutes ahead of it)
        if stage in ("sweep", "run", "report"):
            check_sweep_histories(scene)
        roughness_sets(scene)
    if stage in OPTION_STAGES["scheduler"]:
        return check_scheduler(scheduler)
    return None


def one_line_warnings() -> None:
    """Show warnings as ``hdi: warning: MESSAGE`` (no file and line: they are about the input)."""
    warnings.formatwarning = lambda message, category, *args, **kw: (
        f"hdi: warning: {message}\n" if issubclass(category, PhysicsWarning)
        else f"{category.__name__}: {message}\n")
