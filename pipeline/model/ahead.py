"""What a first run compiles ahead, from the scene alone (docs/performance.md, section "The first run").

A first run (no machine code in numba's on-disk cache) compiles the dynamics kernel, ~27 s of CPU, and
waits for it: :func:`compile_kernel_ahead` starts that compile in a background process as soon as the
scene is known (the runner, before a build's first stage; the Python API's ``build_model``), with the
kernel's signature from the scene's stand-in arguments
(:func:`pipeline.model.kernel_inputs.stand_in_arguments`), and compiles at once, into the on-disk cache,
the kernel's leaf callees, which the background compile asks for last and then loads instead of compiling
(:func:`pipeline.model.dynamics.leaf_calls`: the two processes share the kernel's compile; not for the
console script's early compile, which is ahead). While the process then waits for it, it compiles the
entry points that later stages call from Python (:func:`python_entry_points`: the statics map's path, the
right-hand side of the static forces, the separation of a run's histories, the DMW's disk history), which
it would otherwise compile after the wait, on the first run's critical path
(:func:`pipeline.model.compiled.while_waiting`). Machine code and results are the same either way.
"""

from __future__ import annotations

import logging
import os
import pickle
from typing import Any

import numpy as np

from . import compiled
from . import dynamics as dyn
from .forces import separation_at
from .kernel_inputs import stand_in_arguments
from .piecewise import disk_history
from .start import static_inputs
from .state import N_STATE, THETA, Z
from ..config.loading import load_scene
from ..units import URAD

log = logging.getLogger(__name__)

#: What the first run's early compile process (:func:`compile_scene_kernel`) does not import: the command
#: line's process imports them anyway, and in a fresh clone (their bytecode written for the first time)
#: they cost it 2.5-4.5 s of CPU before the kernel's compile could start (docs/performance.md, section
#: "The first run, traced"). The modules on its path import them where they are used;
#: tests/model/test_first_run.py checks it for every shipped scene.
NOT_IMPORTED_EARLY = ("xarray", "pandas", "scipy.interpolate", "scipy.special")


def compile_kernel_ahead(scene: Any) -> None:
    """Start compiling the dynamics kernel for the scene's effects in a background process, unless this
    process has a kernel already, the on-disk cache has this one, or ``HDI_COMPILE_AHEAD=0``
    (:func:`pipeline.model.dynamics.compile_kernel_ahead` of the scene's stand-in arguments). If this call
    started it, the kernel's leaf callees are compiled into the on-disk cache here at once
    (:func:`pipeline.model.dynamics.leaf_calls`): the background compile asks for them last, 3-5 s into it,
    and loads them instead of compiling them. If a compile is under way (started or adopted), the Python
    entry points of :func:`python_entry_points` are compiled while the process waits for it.

    A scene whose stand-ins cannot be made (a rear law that does not compile) starts nothing: the model's
    assembly reports it in its own words when it comes to it.
    """
    try:
        args = stand_in_arguments(scene)
    except ValueError:
        return
    if dyn.compile_kernel_ahead(*args):
        # now, not while waiting: by its first wait this process may still be compiling its static solver
        # (3-5 s), and the background compile would have compiled the leaves itself. Not when the compile is
        # the console script's, adopted: started ~1 s before the command's imports, it is ahead, and the
        # command has its upstream stages to compute (docs/performance.md, section "A notebook's first call,
        # shared")
        try:
            compile_entry_points(dyn.leaf_calls(*args))
        except Exception as exc:  # (only a head start: the background compile compiles what is not cached)
            log.debug("the kernel's leaf callees did not compile ahead: %s", exc)
    # (one by one, and only while the background compile runs: after it, the caller waits for them, and each
    # is compiled anyway where it is first called)
    compiled.while_waiting(lambda: compile_entry_points(python_entry_points(scene), while_compiling=True))


def compile_scene_kernel(scene_path: str, overrides: list[str], key_path: str) -> None:
    """The process :func:`pipeline.model.first_run.start` starts: load the scene (``scene_path`` with the
    ``--set`` strings ``overrides``), write the kernel's key ``(module, name, signature)`` for its stand-in
    arguments to ``key_path`` (whole, by a rename: the waiting process reads it to adopt this compile,
    :func:`pipeline.model.compiled.adopt_early`) and compile the kernel into the on-disk cache. A scene
    that does not load or has no stand-ins (the command line reports it) compiles nothing."""
    try:
        args = dyn.kernel_arguments(*stand_in_arguments(load_scene(scene_path, overrides)))
    except (ValueError, OSError):  # (SceneError is a ValueError)
        return
    sig = compiled.signature(dyn._integrate, args)
    tmp = f"{key_path}.{os.getpid()}.tmp"
    with open(tmp, "wb") as f:
        pickle.dump((dyn._integrate.py_func.__module__, dyn._integrate.py_func.__name__, sig), f)
    os.replace(tmp, key_path)
    compiled.compile_quietly(dyn._integrate, sig)


def python_entry_points(scene: Any) -> list[tuple[Any, tuple]]:
    """The compiled functions the stages after the calibration call from Python, each with stand-in
    arguments of the types of the scene's calls (``(dispatcher, args)``), in this order: what every run's
    summary calls, the separation of its histories (:func:`pipeline.model.forces.separation_at` on the
    columns of the kernel's output: strided arrays) and with a DMW record the disk's history at its output
    times (:func:`pipeline.model.piecewise.disk_history`); then what only the statics map calls, its
    compiled path (:func:`pipeline.model.statics._path`) and its right-hand side of the static forces
    (:func:`pipeline.model.dynamics.rhs`: the slots of :func:`pipeline.model.start.static_inputs`).
    tests/model/test_compiled.py checks that the main scene's runs and statics map compile exactly these
    signatures.
    """
    from .statics import TOL, _path  # (here: xarray, NOT_IMPORTED_EARLY)
    y0, grid, p, tab, var, solver = stand_in_arguments(scene)
    p_static, tab_static, var_static, slots = static_inputs(lambda mu: (p, tab, var), 0.0)
    packed = dyn._packed(p_static)
    Y = np.zeros((2, N_STATE))  # (the kernel's output: the histories read its columns)
    # what every run's summary calls first (the histories), then what only the statics map calls
    points = [(separation_at, (p, Y[:, Z], Y[:, THETA], np.zeros(2)))]
    if tab.dmw is not None:  # (the disk under the TFC point at a run's output times)
        points.append((disk_history, (tab.dmw, p, np.zeros(2))))
    return points + [
        (_path, (np.zeros(1), 1.0, 0.0, 0.0, 0.0, URAD, TOL, 30, packed, *slots)),
        (dyn._rhs_python, (0.0, np.zeros(N_STATE), packed, False, np.zeros(N_STATE), *dyn._slots(tab_static,
                                                                                                var_static))),
    ]


def compile_entry_points(entry_points: list[tuple[Any, tuple]], while_compiling: bool = False) -> None:
    """Compile each ``(dispatcher, args)`` for the types of ``args`` in this process (loaded instead when the
    on-disk cache has it; nothing when the process has it), without calling it; with ``while_compiling``,
    only while a background compile runs (:func:`pipeline.model.compiled.running`): the rest is compiled
    where it is first called, if it is."""
    for dispatcher, args in entry_points:
        if while_compiling and not compiled.running():
            return
        sig = compiled.signature(dispatcher, args)
        if sig not in dispatcher.overloads:
            dispatcher.compile(sig)
