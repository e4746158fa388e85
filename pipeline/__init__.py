"""HDI dynamics with friction for light-contact recording (Vakis, Lee & Polycarpou 2009).

The API (:mod:`pipeline.api`; README, "From Python"), imported on first use of one of its names::

    import pipeline as hdi

    scene = hdi.load_scene("paper-2009", {"contact.k": 0.5})  # a shipped scene (or a path): read-only
    scene = scene.replace(tfc={"protrusion_nm": 9.0})                    # a varied copy, validated
    model = hdi.build_model(scene, "results/paper")
    ds = hdi.simulate(model, [9.0, 10.0], histories=[10.0])
    hdi.run_stage("sweep", scene, "results/paper", scheduler="threads")  # or a distributed.Client
    sweep = hdi.open_dataset("results/paper", "sweep")

* ``load_scene(path, overrides)``: read and validate a scene, a file or a shipped scene's name (overrides:
  ``--set`` strings, one string or a dict)
* ``simulation_inputs(scene, results)``: the tables, records and contact criterion one simulation reads
* ``build_model(scene, results)``: the model the ``simulate`` and ``sweep`` stages run
* ``simulate(model, protrusions)``: run it at protrusions [nm], an ``xarray.Dataset``
* ``histories_of(ds)``: the kept time histories of a ``simulate`` result
* ``open_dataset(results, name)``: a stage's dataset from a results folder
* ``run_stage(stage, scene, out)``: make one stage current, as ``hdi STAGE``
* ``run(scene, out)``: make the main job current, as ``hdi run``

Inside, stages (``pipeline.stages``) read a scene (``pipeline.config.scene``) and earlier datasets and write
one NetCDF dataset each (``pipeline.io``); the physics lives in pure functions (``pipeline.physics``).
"""

from importlib.metadata import PackageNotFoundError, version as _version

#: The distribution that installs this package (pyproject.toml ``[project] name``).
DISTRIBUTION = "hdi-dynamics"

try:  # one source: the installed distribution's metadata, written from pyproject.toml
    __version__ = _version(DISTRIBUTION)
except PackageNotFoundError:  # pragma: no cover (a source tree on sys.path without `make setup`)
    __version__ = "0+unknown"

#: The public API (:mod:`pipeline.api`: README, "From Python"), re-exported here. It is imported on first
#: use of one of these names: ``import pipeline`` stays light (no xarray, numba or stage imports) and the
#: layers below the command line, which import this package, never import the API above them.
API = ("load_scene", "simulation_inputs", "build_model", "simulate", "histories_of", "open_dataset",
       "run_stage", "run")

#: ``from pipeline import *`` and ``help(pipeline)`` show the API (its names only: the import stays lazy).
__all__ = [*API]


def __getattr__(name: str):
    """A name of :data:`API`, from :mod:`pipeline.api` (imported now, on first use)."""
    if name in API:
        from . import api  # (the one import of a layer above: tests/structure/test_layers.py, UPWARD_ALLOWED)
        return getattr(api, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The package's names with those of :data:`API`."""
    return sorted({*globals(), *API})
