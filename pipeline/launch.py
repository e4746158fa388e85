"""The ``hdi`` console script: the first run's kernel compile started, then the command line.

On a first run (numba's on-disk cache holds no kernel yet) the kernel's compile is the run's critical
path, and the command line's own imports (the pipeline, xarray, dask, scipy; with their bytecode written
for the first time in a fresh clone) come before the runner would start it. So this module, which imports
only the standard library and :mod:`pipeline.model.first_run`, starts it first
(:func:`pipeline.model.first_run.start`) and then imports and runs the command line
(:func:`pipeline.cli.entry`), which hands the compile to the runner. docs/performance.md, section
"The first run". The signals that end a command are answered from the first instruction
(:func:`pipeline.interrupts.handling`): one during those imports (1-6 s) ends the command with its one line
and 128 + its number, like one later.
"""

from __future__ import annotations

import os
import sys

from . import interrupts
from .model import first_run


def entry() -> None:  # pragma: no cover (the console script: tests/core/test_interrupts.py runs it as a process)
    """Start the first run's kernel compile for the scene ``sys.argv`` names, then run ``hdi``."""
    early = None
    with interrupts.handling():
        try:
            early = first_run.start(sys.argv[1:])
            from . import cli  # (after the start: importing it is what the compile overlaps)
        except KeyboardInterrupt as exc:  # (the early compile dies with this process: first_run.background_process)
            if early is not None:
                early.discard()
            interrupts.say(interrupts.message("hdi", interrupts.signal_of(exc)))
            os._exit(interrupts.exit_code(interrupts.signal_of(exc)))
        cli.entry(early)
