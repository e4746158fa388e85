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
