"""hdi from Python: load a scene, build its model, simulate protrusions, run stages, open their datasets.

The package's front door (README, "From Python"; runnable examples in ``docs/examples/``)::

    import pipeline as hdi

    scene = hdi.load_scene("configs/paper-2009.toml", ["contact.k=0.5"])
    model = hdi.build_model(scene, "results/paper")          # its inputs made current in the folder
    ds = hdi.simulate(model, [10.0, 11.0], histories=[11.0])  # an xarray.Dataset
    hdi.run_stage("sweep", scene, "results/paper")           # as `hdi sweep ... --out results/paper`
    sweep = hdi.open_dataset("results/paper", "sweep")

Every function here is a call the stages and the ``hdi`` command make, not a second path to the
results: a scene is :func:`pipeline.config.scene.load_scene` (``--set`` overrides), a model is
:meth:`pipeline.model.inputs.SimulationInputs.model` of the inputs the runner made current
(:func:`pipeline.runner.simulation_inputs`), a simulation is :func:`pipeline.model.simulation.simulate`,
a stage is run by :class:`pipeline.runner.Runner` after the command line's checks
(:func:`pipeline.cli_checks.check_options`), a dataset is read by :func:`pipeline.io.read_dataset`. So a
model built here simulates exactly as the ``simulate`` and ``sweep`` stages do.

Bad input raises the exception the command line turns into its one-line error:
:class:`pipeline.config.scene.SceneError` (a scene or an override), :class:`pipeline.io.DatasetError` (a
missing or foreign dataset), :class:`pipeline.cli_checks.OptionError` (an option), ``ValueError``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Iterable, Mapping

import xarray as xr

from . import runner
from .cli_checks import check_options
from .config.scene import Scene, load_scene as _load_scene
from .io import read_dataset, results_dir
from .model.inputs import SimulationInputs
from .model.simulation import histories_of, simulate
from .model.slider import Model

__all__ = ["load_scene", "simulation_inputs", "build_model", "simulate", "histories_of", "open_dataset",
           "run_stage", "run"]

#: A scene, or the path of its TOML file.
SceneLike = Scene | str | Path


def load_scene(path: str | Path, overrides: Iterable[str] = ()) -> Scene:
    """Read, override and validate a scene file, as ``hdi STAGE PATH --set ...`` does.

    Parameters
    ----------
    path : the TOML scene file (e.g. ``configs/paper-2009.toml``)
    overrides : ``"section.key=value"`` strings, values in TOML syntax (``"contact.k=0.5"``,
        ``"sweep.protrusion_nm={start=9.5, stop=10.5, step=0.5}"``), applied in order; units are those of
        the key names (``solver.duration_ms`` [ms])

    Returns
    -------
    pipeline.config.scene.Scene
        The validated scene, every default filled in (``scene["tfc"]["protrusion_nm"]`` [nm]).

    Raises
    ------
    pipeline.config.scene.SceneError
        A missing file, bad TOML or an invalid key, naming the file, the key and what was expected.
    """
    return _load_scene(path, overrides)


def _scene(scene: SceneLike) -> Scene:
    return scene if isinstance(scene, Scene) else _load_scene(scene)


def simulation_inputs(scene: SceneLike, results: str | Path | None = None, *,
                      k: float | None = None) -> SimulationInputs:
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

    Returns
    -------
    pipeline.model.inputs.SimulationInputs
        The inputs, with ``k`` [1] and ``k_source`` (where k came from); ``.model(scene)`` is the model.
    """
    scene = _scene(scene)
    if results is not None:
        return runner.simulation_inputs(scene, results, calibration=True, k=k)
    with tempfile.TemporaryDirectory(prefix="hdi-inputs-") as tmp:
        sim = runner.simulation_inputs(scene, tmp, calibration=True, k=k)
        # read now, before the folder goes (read_dataset loads each dataset fully into memory)
        return SimulationInputs.of(sim.tables(), sim.record(), sim.bulge_table(), sim.k, sim.k_source)


def build_model(scene: SceneLike, results: str | Path | None = None, *, k: float | None = None) -> Model:
    """The model of ``scene`` with its inputs resolved: what the ``simulate`` and ``sweep`` stages run.

    Parameters
    ----------
    scene : a scene (:func:`load_scene`) or the path of its file
    results : the results folder whose datasets the model reads, made current first (``None``: made in
        memory; :func:`simulation_inputs`)
    k : the contact criterion constant [1] (``None``: the scene's, else calibrated; :func:`simulation_inputs`)

    Returns
    -------
    pipeline.model.slider.Model
        The assembled model in SI units (``model.k`` [1]); run it with :func:`simulate`.
    """
    scene = _scene(scene)
    return simulation_inputs(scene, results, k=k).model(scene)


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
        When the file is missing (naming the stage to run) or not a readable dataset.
    """
    file, stage = _stage_of(name)
    return read_dataset(Path(results) / file, stage=stage)


def _build(target: str, scene: SceneLike, out: str | Path | None, force: bool, scheduler: str | None,
           workers: int | None, yes: bool) -> dict[str, tuple[Path, ...]]:
    """Make ``target`` (a stage, or ``"run"``: the main job) current, as ``hdi TARGET`` does."""
    scene = _scene(scene)
    stages = runner.registry()
    if target != "run" and target not in stages:
        raise ValueError(f"unknown stage {target!r}; expected one of {', '.join(stages)}")
    scheduler = check_options(target, scene, out=out, scheduler=scheduler, workers=workers, yes=yes, force=force)
    targets = runner.main_job(scene, stages) if target == "run" else [target]
    return runner.Runner(scene, results_dir(scene, out), stages, scheduler=scheduler,
                         workers=workers).build(targets, force=force)


def run_stage(stage: str, scene: SceneLike, out: str | Path | None = None, *, force: bool = False,
              scheduler: str | None = None, workers: int | None = None, yes: bool = False) -> Path:
    """Make one stage current in a results folder, with everything upstream of it: ``hdi STAGE``.

    Parameters
    ----------
    stage : the stage (``hdi --help`` lists them: ``"simulate"``, ``"sweep"``, ``"ensemble"``, ...)
    scene : a scene (:func:`load_scene`) or the path of its file
    out : the results folder (``None``: ``results/<scene name>/``, relative to the working directory)
    force : recompute the stage even when its outputs are current (``--force``)
    scheduler, workers : the fan-out of sweep, calibrate, ensemble, identify and sensitivity (``--scheduler``,
        ``--workers``; ``None``: local threads, one per core)
    yes : allow a big job beyond the limits of :mod:`pipeline.config.limits` (``--yes``)

    Returns
    -------
    pathlib.Path
        The stage's primary output (``sweep.nc`` for ``"sweep"``); :func:`open_dataset` reads it.
    """
    return _build(stage, scene, out, force, scheduler, workers, yes)[stage][0]


def run(scene: SceneLike, out: str | Path | None = None, *, force: bool = False, scheduler: str | None = None,
        workers: int | None = None, yes: bool = False) -> Mapping[str, Path]:
    """Make the main job current (``hdi run``): the stages of the report, in order.

    Parameters are those of :func:`run_stage` (``force`` recomputes every stage of the main job).

    Returns
    -------
    dict of str to pathlib.Path
        Each stage's primary output.
    """
    return {name: paths[0] for name, paths in _build("run", scene, out, force, scheduler, workers, yes).items()}
