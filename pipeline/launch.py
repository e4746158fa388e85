"""The ``hdi`` console script: the first run's kernel compile started, then the command line.

On a first run (numba's on-disk cache holds no kernel yet) the kernel's compile is the run's critical
path, and the command line's own imports (the pipeline, xarray, dask, scipy; with their bytecode written
for the first time in a fresh clone) come before the runner would start it. So this module, which imports
only the standard library and :mod:`pipeline.model.first_run`, starts it first
(:func:`pipeline.model.first_run.start`) and then imports and runs the command line
(:func:`pipeline.cli.entry`), which hands the compile to the runner. docs/performance.md, section
"The first run".
"""

from __future__ import annotations

import sys

from .model import first_run


def entry() -> None:  # pragma: no cover (the console script: tests/model/test_first_run.py runs it as a process)
    """Start the first run's kernel compile for the scene ``sys.argv`` names, then run ``hdi``."""
    early = first_run.start(sys.argv[1:])
    from . import cli  # (after the start: importing it is what the compile overlaps)
    cli.entry(early)
