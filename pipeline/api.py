"""hdi from Python: load a scene, build its model, simulate protrusions, run stages, open their datasets.

The package's front door (README, "From Python"; runnable examples in ``docs/examples/``)::

    import pipeline as hdi

    scene = hdi.load_scene("configs/paper-2009.toml", ["contact.k=0.5"])  # or "contact.k=0.5", {"contact.k": 0.5}
    scene = scene.replace(tfc={"protrusion_nm": 10.0})       # a scene is read-only: a varied, validated copy
    model = hdi.build_model(scene, "results/paper")          # its inputs made current in the folder
    ds = hdi.simulate(model, [10.0, 11.0], histories=[11.0])  # an xarray.Dataset
    hdi.run_stage("sweep", scene, "results/paper")           # as `hdi sweep ... --out results/paper`
    hdi.run_stage("sweep", scene, "results/paper", scheduler=client)  # a distributed.Client's cluster
    sweep = hdi.open_dataset("results/paper", "sweep")

Every function here is a call the stages and the ``hdi`` command make, not a second path to the
results: a scene is :func:`pipeline.config.scene.load_scene` (``--set`` overrides), a model is
:meth:`pipeline.model.inputs.SimulationInputs.model` of the inputs the runner made current
(:func:`pipeline.runner.current_inputs`), a simulation is :func:`pipeline.model.simulation.simulate`,
a stage is run by :class:`pipeline.runner.Runner` after the command line's checks
(:func:`pipeline.cli_checks.check_options`), a dataset is read by :func:`pipeline.io.read_dataset`. So a
model built here simulates exactly as the ``simulate`` and ``sweep`` stages do.

Progress (module docstring): each call that computes shows what ``hdi`` shows, without any logging set up
by the caller: the stages' messages and, for long work, a ``tqdm.auto`` bar (a widget in a notebook, a bar
on a terminal) or, elsewhere (a script's log), a progress line at the end and every 30 s
(:mod:`pipeline.progress`); ``progress=False`` shows nothing. A caller whose own logging is configured
(``logging.basicConfig``) gets the messages through it, once.

Bad input raises the exception the command line turns into its one-line error, checked as the command
line checks it (:mod:`pipeline.cli_checks`) before anything runs or is written:
:class:`pipeline.config.scene.SceneError` (a scene, its path or an override), :class:`pipeline.io.DatasetError`
(a missing or foreign dataset), :class:`pipeline.options.OptionError` (an option or argument of the wrong
type or range: ``workers="2"``, a results folder that is a file or cannot be written, a negative or NaN
protrusion, a protrusion given twice, a history not among the protrusions), ``ValueError``; all are
``ValueError``, and each names the argument of the call (``out = '...': is a file``, ``workers = 'two'``,
``yes=True``), not the command line's option (:func:`pipeline.options.python_call`). A run whose integration fails raises
:class:`pipeline.model.running.IntegrationError` in one line naming the scene, the protrusion and what to
change (the command line's message); a file system that fails mid-run (a full disk) raises ``OSError``.
"""

from __future__ import annotations

import json
import math
import numbers
import re
import sys
import tempfile
from pathlib import Path
from typing import Any, Iterable, Mapping

import xarray as xr

import os
from collections.abc import MutableMapping

from . import progress as _progress, runner
from .cli_checks import (check_flag, check_options, check_out, check_path_option, check_protrusions,
                         check_stage_options, integration_line)
from .options import OptionError, python_call
from .config.grid import same_point
from .config.loading import load_scene as _load_scene
from .config.schema import SCHEMA, SceneError
from .config.validation import Scene, check_value
from .io import DatasetError, read_dataset, results_dir
from .model.inputs import SimulationInputs
from .model.ahead import compile_kernel_ahead
from .model.simulation import histories_of as _histories_of, run_count, simulate as _simulate
from .model.assembly import Model
from .model.running import IntegrationError

__all__ = ["load_scene", "simulation_inputs", "build_model", "simulate", "histories_of", "open_dataset",
           "run_stage", "run"]

#: A scene, or the path of its TOML file.
SceneLike = Scene | str | Path

#: What ``scheduler=`` takes: a name or address (``--scheduler``), a ``distributed.Client``, or ``None``.
Scheduler = Any


#: What :func:`load_scene` takes as ``overrides``.
Overrides = Iterable[str] | str | Mapping[str, Any]

#: A bare TOML key (written unquoted in an inline table).
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml(value: Any, where: str) -> str:
    """``value`` in TOML syntax, as a ``--set`` string writes it (floats by ``repr``: read back bit for bit)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):  # (numpy's too: repr(np.float64(0.5)) is no TOML)
        value = float(value)
        if not math.isfinite(value):
            return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
        return repr(value)
    if isinstance(value, (str, os.PathLike)):
        return json.dumps(os.fspath(value))  # (a JSON string is a TOML basic string)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v, where) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k if _BARE_KEY.fullmatch(str(k)) else json.dumps(str(k))} = {_toml(v, where)}"
                               for k, v in value.items()) + "}"
    raise SceneError(f"load_scene: overrides {where} = {value!r}: expected a number, a string, a bool, a list or "
                     f"a dict, got {type(value).__name__}")


def _override_strings(overrides: Overrides) -> list[str]:
    """``overrides`` as ``"section.key=value"`` strings: a list of them, one string, or a dict
    (``{"contact.k": 0.5}`` and ``{"contact": {"k": 0.5}}``, mixed as one likes)."""
    if isinstance(overrides, str):
        return [overrides]
    if isinstance(overrides, Mapping):
        out = []
        for name, value in overrides.items():
            if isinstance(name, str) and "." in name:
                out.append(f"{name}={_toml(value, repr(name))}")
            elif isinstance(name, str) and isinstance(value, Mapping):
                out += [f"{name}.{key}={_toml(v, repr(f'{name}.{key}'))}" for key, v in value.items()]
            else:
                raise SceneError(f"load_scene: overrides[{name!r}] = {value!r}: expected \"section.key\": value or "
                                 f"\"section\": {{key: value}} (e.g. {{\"contact.k\": 0.5}} or {{\"contact\": {{\"k\": 0.5}}}})")
        return out
    if isinstance(overrides, bytes) or not isinstance(overrides, Iterable):
        raise SceneError(f"load_scene: overrides = {overrides!r}: expected a list of \"section.key=value\" strings "
                         "(e.g. [\"contact.k=0.5\"]), one such string, or a dict ({\"contact.k\": 0.5})")
    out = list(overrides)
    for i, text in enumerate(out):
        if not isinstance(text, str):
            raise SceneError(f"load_scene: overrides[{i}] = {text!r}: expected a \"section.key=value\" string, "
                             f"got {type(text).__name__}")
    return out


def load_scene(path: str | Path, overrides: Overrides = ()) -> Scene:
    """Read, override and validate a scene file, as ``hdi STAGE PATH --set ...`` does.

    Parameters
    ----------
    path : the TOML scene file (e.g. ``configs/paper-2009.toml``), or the name of a scene shipped with the
        package (``"paper-2009"``; a file that exists at the path given wins:
        :func:`pipeline.config.loading.find_scene`)
    overrides : the ``--set`` overrides, applied in order, in one of three forms:

        * a list of ``"section.key=value"`` strings, values in TOML syntax (``["contact.k=0.5"]``,
          ``["sweep.protrusion_nm={start=9.5, stop=10.5, step=0.5}"]``);
        * one such string (``"contact.k=0.5"``);
        * a dict, ``{"section.key": value}`` or ``{"section": {"key": value}}`` (both may be mixed:
          ``{"contact.k": 0.5, "tfc": {"protrusion_nm": 9.0}}``), each value a number, string, bool,
          list or dict, written as the ``--set`` string ``section.key=value`` (kept in
          ``scene.overrides``; a float exactly as given).

        Units are those of the key names (``solver.duration_ms`` [ms]).

    Returns
    -------
    pipeline.config.scene.Scene
        The validated scene, every default filled in (``scene["tfc"]["protrusion_nm"]`` [nm]); it is
        read-only: ``scene.replace(contact={"k": 0.5})`` is a new scene, validated as ``--set`` is.

    Raises
    ------
    pipeline.config.scene.SceneError
        A missing file, bad TOML or an invalid key, naming the file, the key and what was expected; a
        ``path`` that is no path (``123``) or ``overrides`` of none of the three forms.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise SceneError(f"load_scene: path = {path!r}: expected the path of a scene file (str or pathlib.Path), "
                         f"got {type(path).__name__}")
    return _load_scene(path, _override_strings(overrides))


def _scene(scene: SceneLike) -> Scene:
    """A scene, or the scene of a file (:func:`load_scene`); anything else is a :class:`SceneError`."""
    if isinstance(scene, Scene):
        return scene
    if not isinstance(scene, (str, os.PathLike)):
        raise SceneError(f"scene = {scene!r}: expected a scene (load_scene) or the path of its file, "
                         f"got {type(scene).__name__}")
    return load_scene(scene)


def _k(k: float | None) -> float | None:
    """``k`` [1] checked as the scene key ``contact.k`` is."""
    return None if k is None else check_value("contact", "k", SCHEMA["contact"]["k"], k, "k", None)


def _integration(exc: IntegrationError, scene: Scene | None) -> IntegrationError:
    """The command line's one line of a failed integration (:func:`pipeline.cli_checks.integration_line`)."""
    return IntegrationError(integration_line(exc, scene))


def simulation_inputs(scene: SceneLike, results: str | Path | None = None, *,
                      k: float | None = None, progress: bool = True) -> SimulationInputs:
    """What one simulation of ``scene`` reads: interface tables, DMW record, bulge table and the contact
    criterion k [1], each only when the scene's effects need it.

    Parameters
    ----------
    scene : a scene (:func:`load_scene`) or the path of its file
    results : a results folder: the stages that make the inputs (roughness, interface, dmw, bulge, and
        calibrate for k) are made current there first (computed only when their inputs changed, as by
        ``hdi``) and the datasets stay; ``None``: they are made in a temporary folder and held in memory
    k : the contact criterion constant [1]; ``None``: the scene's ``contact.k``, else the calibration's
        (``hdi calibrate``, a fan-out of flying runs over the sweep's protrusions), else the scene's
        ``contact.fallback_probability`` (:func:`pipeline.model.scene_inputs.contact_k`)
    progress : show the stages' messages and progress (module docstring); ``False``: none

    Returns
    -------
    pipeline.model.inputs.SimulationInputs
        The inputs, with ``k`` [1] and ``k_source`` (where k came from); ``.model(scene)`` is the model.

    Raises
    ------
    pipeline.options.OptionError
        ``results`` is no path, a file, or a folder that cannot be written (the runner locks it and
        keeps its datasets there, even when they are up to date).
    """
    check_flag("progress =", progress)
    scene = _scene(scene)
    check_out(results, "results")
    k = _k(k)
    with _progress.shown(progress):
        if results is not None:
            return runner.current_inputs(scene, results, calibration=True, k=k)
        with tempfile.TemporaryDirectory(prefix="hdi-inputs-") as tmp:
            sim = runner.current_inputs(scene, tmp, calibration=True, k=k, in_memory=True)
            # read now, before the folder goes (read_dataset loads each dataset fully into memory)
            return SimulationInputs.of(sim.tables(), sim.record(), sim.bulge_table(), sim.k, sim.k_source)


def build_model(scene: SceneLike, results: str | Path | None = None, *, k: float | None = None,
                progress: bool = True) -> Model:
    """The model of ``scene`` with its inputs resolved: what the ``simulate`` and ``sweep`` stages run.

    Parameters
    ----------
    scene : a scene (:func:`load_scene`) or the path of its file
    results : the results folder whose datasets the model reads, made current first (``None``: made in
        memory; :func:`simulation_inputs`)
    k : the contact criterion constant [1] (``None``: the scene's, else calibrated; :func:`simulation_inputs`)
    progress : show the stages' messages and progress (module docstring); ``False``: none

    Returns
    -------
    pipeline.model.assembly.Model
        The assembled model in SI units (``model.k`` [1]); run it with :func:`simulate`.
    """
    check_flag("progress =", progress)
    scene = _scene(scene)
    with _progress.shown(progress):
        # a first call (no kernel compiled or cached for the scene's effects): the kernel compiles in a
        # background process while the inputs are made (docs/performance.md, section "The first run")
        compile_kernel_ahead(scene)
        return simulation_inputs(scene, results, k=k).model(scene)


def simulate(model: Model, protrusions: Iterable[float], *, histories: Iterable[float] = (),
             protocol: str = "independent", counters: bool = False, on_error: str = "raise",
             timings: MutableMapping[str, float] | None = None, progress: bool = True,
             workers: None = None) -> xr.Dataset:
    """Run ``model`` at ``protrusions`` [nm]: :func:`pipeline.model.simulation.simulate`, the call of the
    ``simulate`` and ``sweep`` stages, after the command line's checks of a protrusion.

    Parameters
    ----------
    model : the model of :func:`build_model`
    protrusions : TFC protrusions [nm], a list (``[9.0]`` for one), each as ``tfc.protrusion_nm`` allows:
        finite, >= 0 and at most the flying height + 100 nm (:func:`pipeline.cli_checks.check_protrusions`)
        (each once: a protrusion given twice is refused)
    histories, protocol, counters, on_error, timings : as :func:`pipeline.model.simulation.simulate`
        (``histories``: protrusions [nm] among ``protrusions`` whose time histories are kept, on the
        dimension ``hist_protrusion`` of the result: :func:`histories_of`)
    progress : count the runs as they finish, ``"simulate: k/N runs done, ..."`` (module docstring);
        ``False``: nothing shown
    workers : not taken (``None`` only): the runs go one after another in this process, as ``hdi simulate``
        runs them; a fan-out over local workers or a cluster is a stage's, ``run_stage("sweep", scene, out,
        workers=2)`` over ``sweep.protrusion_nm``

    Returns
    -------
    xarray.Dataset
        The steady-window scalars on ``protrusion`` (and the kept histories), in dataset units.

    Raises
    ------
    pipeline.options.OptionError
        A protrusion that is no number, NaN, negative or beyond the flying height + 100 nm, given twice, or a
        protrusion list that is a single number; a history protrusion not among ``protrusions``; ``workers``
        given; ``ValueError`` for the other arguments.
    pipeline.model.running.IntegrationError
        A run failed (``on_error="raise"``), in one line naming the scene, the protrusion and what to change.
    """
    if not isinstance(model, Model):
        raise ValueError(f"model = {model!r:.80}: expected the model of build_model, got {type(model).__name__}")
    fh0 = model.scene["air_bearing"]["flying_height_nm"]
    prot = check_protrusions(protrusions, fh0, "protrusions")
    if not prot:
        raise OptionError("protrusions = []: expected at least one protrusion [nm]")
    # (to the grid tolerance the runs match histories with: pipeline.config.grid.same_point)
    twice = sorted({p for i, p in enumerate(prot) if any(same_point(p, q) for q in prot[:i])})
    if twice:
        raise OptionError(f"protrusions: {', '.join(f'{p:g}' for p in twice)} nm given more than once; expected each "
                          "protrusion once (the result is indexed by protrusion)")
    kept = check_protrusions(histories, fh0, "histories")
    off = [h for h in kept if not any(same_point(h, p) for p in prot)]
    if off:
        raise OptionError(f"histories: {', '.join(f'{h:g}' for h in off)} nm not among the protrusions "
                          f"({', '.join(f'{p:g}' for p in prot)} nm); expected protrusions that are simulated")
    if workers is not None:
        raise OptionError(f"workers = {workers!r}: simulate runs its protrusions one after another in this process "
                          "(as `hdi simulate`); fan them out with run_stage(\"sweep\", scene, out, workers=...) over "
                          "sweep.protrusion_nm")
    check_flag("counters =", counters)
    check_flag("progress =", progress)
    if timings is not None and not isinstance(timings, MutableMapping):
        raise ValueError(f"timings = {timings!r}: expected a dict (or None), got {type(timings).__name__}")
    try:
        with _progress.shown(progress), _progress.Progress(run_count(protocol, len(prot)), unit="run",
                                                           label="simulate") as shown:
            return _simulate(model, prot, histories=kept, protocol=protocol, counters=counters, on_error=on_error,
                             timings=timings, on_run=shown.update)
    except IntegrationError as exc:
        raise _integration(exc, model.scene) from None


def histories_of(ds: xr.Dataset) -> xr.Dataset:
    """The time histories of a :func:`simulate` result as ``histories.nc`` holds them
    (:func:`pipeline.model.simulation.histories_of`).

    Raises
    ------
    ValueError
        ``ds`` is not a result of :func:`simulate` with ``histories``.
    """
    if not isinstance(ds, xr.Dataset) or "hist_protrusion" not in ds.dims:
        raise ValueError(f"histories_of: expected the dataset of simulate(model, ..., histories=[...]) with its "
                         f"kept histories (dim hist_protrusion), got {type(ds).__name__}")
    return _histories_of(ds)


def _stage_of(name: str) -> tuple[str, str | None]:
    """``(file, stage)`` of a stage's first dataset or of a dataset's file name (``stage`` ``None``: no
    stage declares that file)."""
    stages = runner.registry()
    if name in stages:
        files = [o for o in stages[name].output_names(None) if o.endswith(".nc")]
        if not files:
            raise ValueError(f"stage {name!r} writes no dataset (its outputs are figures and tables)")
        return files[0], name
    if not name.endswith(".nc"):
        raise ValueError(f"{name!r}: expected a stage ({', '.join(stages)}) or a dataset's file name (*.nc)")
    owner = next((s for s, st in stages.items() if name in st.output_names(None)), None)
    return name, owner


def open_dataset(results: str | Path, name: str) -> xr.Dataset:
    """A dataset of a results folder, loaded into memory (the file is closed).

    Parameters
    ----------
    results : the results folder (``hdi ... --out``, default ``results/<scene name>/``)
    name : a stage (its first dataset: ``"sweep"`` -> ``sweep.nc``, ``"simulate"`` -> ``histories.nc``)
        or a file name in the folder (``"summary.nc"``)

    Returns
    -------
    xarray.Dataset
        The dataset in the units its variables' ``units`` attributes name (docs/datasets.md).

    Raises
    ------
    pipeline.io.DatasetError
        When the file is missing (naming the stage to run) or not a readable dataset;
        :class:`pipeline.io.DatasetDamaged` when a variable of a stage's output cannot be read back or differs
        from the checksum written with it (docs/datasets.md, section "Stored datasets checked when read"; a file
        no stage writes is read unchecked).
    """
    check_path_option(results, "results")
    if not isinstance(name, str):
        raise ValueError(f"name = {name!r}: expected a stage or a dataset's file name (str), got {type(name).__name__}")
    if Path(results).is_file():
        raise DatasetError(f"{results}: is a file; expected a results folder (hdi ... --out)")
    file, stage = _stage_of(name)
    # (a stage's output is checked against its checksums; a file of the user's own, a subset saved, is not)
    return read_dataset(Path(results) / file, stage=stage, check=stage is not None)


def _client_address(scheduler: Any) -> str | None:
    """The scheduler address of a ``distributed.Client`` (``None``: ``scheduler`` is no client).

    Raises
    ------
    pipeline.options.OptionError
        The client is closed.
    """
    distributed = sys.modules.get("distributed")  # (a client's module is imported; never import it here)
    if distributed is None or not isinstance(scheduler, distributed.Client):
        return None
    if scheduler.status != "running":
        raise OptionError(f"scheduler = {scheduler!r}: the client is {scheduler.status}; expected a running "
                          "distributed.Client (or a scheduler address)")
    return scheduler.scheduler.address


def _build(target: str, scene: SceneLike, out: str | Path | None, force: bool, scheduler: Scheduler,
           workers: int | None, yes: bool, progress: bool) -> dict[str, tuple[Path, ...]]:
    """Make ``target`` (a stage, or ``"run"``: the main job) current, as ``hdi TARGET`` does."""
    check_flag("progress =", progress)
    scene = _scene(scene)
    stages = runner.registry()
    if not isinstance(target, str):
        raise ValueError(f"stage = {target!r}: expected a stage name (str), got {type(target).__name__}")
    if target != "run" and target not in stages:
        raise ValueError(f"unknown stage {target!r}; expected one of {', '.join(stages)}")
    address = _client_address(scheduler)
    with python_call():  # (the messages name this call's arguments, not the command line's options)
        if address is None:
            scheduler = check_options(target, scene, out=out, scheduler=scheduler, workers=workers, yes=yes,
                                      force=force)
        else:  # (a connected client's scheduler answers: only whether the stage fans out is checked)
            check_stage_options(target, {"scheduler": address}, afm_files=False)
            check_options(target, scene, out=out, workers=workers, yes=yes, force=force)
            scheduler = address
    targets = runner.main_job(scene, stages) if target == "run" else [target]
    try:
        with _progress.shown(progress):
            return runner.Runner(scene, results_dir(scene, out), stages, scheduler=scheduler,
                                 workers=workers).build(targets, force=force)
    except IntegrationError as exc:
        raise _integration(exc, scene) from None


def run_stage(stage: str, scene: SceneLike, out: str | Path | None = None, *, force: bool = False,
              scheduler: Scheduler = None, workers: int | None = None, yes: bool = False,
              progress: bool = True) -> Path:
    """Make one stage current in a results folder, with everything upstream of it: ``hdi STAGE``.

    Parameters
    ----------
    stage : the stage (``hdi --help`` lists them: ``"simulate"``, ``"sweep"``, ``"ensemble"``, ...)
    scene : a scene (:func:`load_scene`) or the path of its file
    out : the results folder (``None``: ``results/<scene name>/``, relative to the working directory)
    force : recompute the stage even when its outputs are current (``--force``)
    scheduler, workers : the fan-out of sweep, calibrate, ensemble, identify and sensitivity (``--scheduler``,
        ``--workers``; ``None``: local threads, one per core). ``scheduler`` is ``"threads"``,
        ``"processes"``, ``"synchronous"``, a dask scheduler's address (``"tcp://HOST:8786"``), or a running
        ``distributed.Client``, whose scheduler runs the tasks (its address is used: a client of a
        ``LocalCluster(processes=False)`` runs them in this process)
    yes : allow a big job beyond the limits of :mod:`pipeline.config.limits` (``--yes``)
    progress : show the stages' messages and progress as ``hdi`` does (module docstring); ``False``:
        none (``hdi -q``)

    Returns
    -------
    pathlib.Path
        The stage's primary output (``sweep.nc`` for ``"sweep"``); :func:`open_dataset` reads it.
    """
    return _build(stage, scene, out, force, scheduler, workers, yes, progress)[stage][0]


def run(scene: SceneLike, out: str | Path | None = None, *, force: bool = False, scheduler: Scheduler = None,
        workers: int | None = None, yes: bool = False, progress: bool = True) -> Mapping[str, Path]:
    """Make the main job current (``hdi run``): the stages of the report, in order.

    Parameters are those of :func:`run_stage` (``force`` recomputes every stage of the main job).

    Returns
    -------
    dict of str to pathlib.Path
        Each stage's primary output.
    """
    return {name: paths[0] for name, paths in _build("run", scene, out, force, scheduler, workers, yes,
                                                                  progress).items()}
