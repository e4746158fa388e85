"""HDI dynamics with friction for light-contact recording (Vakis, Lee & Polycarpou 2009).

Stages (``pipeline.stages``) read a scene (``pipeline.config.scene``) and earlier datasets and write one
NetCDF dataset each (``pipeline.io``); the physics lives in pure functions (``pipeline.physics``).
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


def __getattr__(name: str):
    """A name of :data:`API`, from :mod:`pipeline.api` (imported now, on first use)."""
    if name in API:
        from . import api  # (the one import of a layer above: tests/test_layers.py, UPWARD_ALLOWED)
        return getattr(api, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The package's names with those of :data:`API`."""
    return sorted({*globals(), *API})
