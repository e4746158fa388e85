"""HDI dynamics with friction for light-contact recording (Vakis, Lee & Polycarpou 2009).

Stages (``pipeline.stages``) read a scene (``pipeline.config.scene``) and earlier datasets and write one
NetCDF dataset each (``pipeline.io``); the physics lives in pure functions (``pipeline.physics``).
"""

__version__ = "0.1.0"
