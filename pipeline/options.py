"""How a check's message names an option: the command line's (``--out results/x``, ``--yes``, ```hdi dmw```)
or, within :func:`python_call` (a call of :mod:`pipeline.api`), the Python argument's (``out = 'results/x'``,
``yes=True``, stage ``'dmw'``); the error of a bad one (:class:`OptionError`, one line naming it, exit 2 on the
command line). The checks themselves: :mod:`pipeline.cli_checks`, and the scheduler's :mod:`pipeline.scheduler`.
"""

from __future__ import annotations

import contextlib
import contextvars
from typing import Any, Iterator




class OptionError(ValueError):
    """A command-line option is invalid for this stage or scene (one line, names the option)."""

#: Within :func:`python_call`: the checks name the arguments of a Python call (``out = '...'``), not the
#: command line's options (``--out ...``).
_PYTHON: contextvars.ContextVar[bool] = contextvars.ContextVar("hdi_python_call", default=False)


@contextlib.contextmanager
def python_call() -> Iterator[None]:
    """Within the block (a call of :mod:`pipeline.api`), every message of these checks names the Python
    argument (``workers = 'two'``, ``yes=True``, stage ``'dmw'``) where the command line names its option
    (``--workers two``, ``--yes``, ```hdi dmw```): :func:`flag`, :func:`given`, :func:`switch`."""
    token = _PYTHON.set(True)
    try:
        yield
    finally:
        _PYTHON.reset(token)


def flag(name: str) -> str:
    """How a message names the option ``name`` (``"write_scene"``): ``--write-scene``, or in a Python call the
    argument ``write_scene``."""
    return name if _PYTHON.get() else "--" + name.replace("_", "-")


def given(name: str, value: Any, text: bool = False) -> str:
    """The option ``name`` with its ``value`` in a message: ``--out results/x`` (``text``: the value's repr,
    ``--workers 'two'``), or in a Python call ``out = 'results/x'``."""
    if _PYTHON.get():
        return f"{name} = {value!r}"
    return f"{flag(name)} {value!r}" if text else f"{flag(name)} {value}"


def switch(name: str) -> str:
    """How a message asks for the switch ``name``: ``--yes``, or in a Python call ``yes=True``."""
    return f"{name}=True" if _PYTHON.get() else flag(name)


def command(stage: str) -> str:
    """How a message names a stage's command: ```hdi sweep```, or in a Python call the stage ``'sweep'``."""
    return f"stage {stage!r}" if _PYTHON.get() else f"`hdi {stage}`"


def first_line(exc: BaseException, width: int = 120) -> str:
    """The first line of an exception's text, at most ``width`` characters (an error quoting what a server
    sent must stay one line)."""
    text = (str(exc).strip().splitlines() or [""])[0]
    return text if len(text) <= width else text[:width] + "..."
