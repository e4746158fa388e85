"""The first run's kernel compile, started by the ``hdi`` console script before its own imports.

A fresh clone's first ``hdi run`` spends its first seconds importing (and writing the bytecode of) the
pipeline, xarray, dask and scipy, ~3-6 s, before the runner knows the scene's kernel and starts its
background compile (:func:`pipeline.model.ahead.compile_kernel_ahead`); the compile, ~12 s of CPU, is
then the first run's critical path (docs/performance.md, section "The first run"). The console script
(:mod:`pipeline.launch`) therefore starts that compile at once, in a process of its own
(:func:`start`), when the command line names a scene and numba's on-disk cache holds no kernel at all
(:func:`kernel_cached`: a first run; a later scene with other effects is compiled as before). That
process loads the scene, writes the kernel's signature to a file and compiles it into the cache
(:func:`compile_scene_kernel`). The runner's compile-ahead then adopts it instead of starting its own,
when the signatures agree (:func:`pipeline.model.compiled.adopt_early`); otherwise it is stopped.

This module is imported by the console script before anything heavy: the standard library and
:mod:`pipeline.code_version` only (numba, numpy and the scene are imported by the process it starts).
"""

from __future__ import annotations

import glob
import os
import shutil
import subprocess
import sys
import tempfile
import threading
from typing import NamedTuple, Sequence

from ..code_version import code_key

#: The kernel's module and entry point (:func:`pipeline.model.dynamics._integrate`).
KERNEL = ("pipeline.model.dynamics", "_integrate")
#: The options of ``hdi`` that take a value, other than ``--set`` (:func:`scene_arguments` skips them).
_VALUED = ("--out", "--scheduler", "--workers", "--channel", "--detrend", "--write-scene", "--readme")
#: The file, in the early process's private folder, its kernel's key is written to.
KEY_FILE = "key.pkl"


class Early(NamedTuple):
    """The kernel compile :func:`start` started: the process, and the private folder (``mkdtemp``: no other
    process can take its name) where that process writes its kernel's key, :attr:`key_path`."""

    proc: subprocess.Popen
    folder: str

    @property
    def key_path(self) -> str:
        """The file the process writes its ``(module, name, signature)`` key to, whole, by a rename."""
        return os.path.join(self.folder, KEY_FILE)

    def discard(self) -> None:
        """Remove the private folder (with a half-written key of a stopped process): once the process is
        adopted or stopped."""
        shutil.rmtree(self.folder, ignore_errors=True)


def background_process(call: str) -> subprocess.Popen:
    """Start a silent Python process that runs ``call`` (statements importing what they use), then ends at
    once (``os._exit``) without the interpreter's teardown of numba, llvmlite and the rest, 0.34-0.40 s after
    a kernel's compile (docs/performance.md, section "The background compile's exit"): the process that
    waits for it (:func:`pipeline.model.compiled.wait_ahead`) waits for its exit. ``call``'s own files (numba's
    cache entries) are written and closed when it returns; an exception still ends the process the usual way
    (exit code 1, its traceback to the null device: a failed compile is only a cache miss).

    The process leaves Ctrl-C and the other signals a terminal sends its process group to this one, and,
    started from this process's main thread, dies with it however it ends (SIGKILL included:
    :func:`pipeline.interrupts.in_background`); started from another thread (a notebook's, whose end would
    end it too) it ends with its compile."""
    parent = os.getpid() if threading.current_thread() is threading.main_thread() else None
    first = f"from pipeline.interrupts import in_background; in_background({parent!r})\n"
    return subprocess.Popen([sys.executable, "-c", f"{first}{call}\nimport os\nos._exit(0)"], stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def cache_folder(module: str, cache_dir: str | None = None) -> str:
    """The numba cache folder of the kernel module ``module`` (a dotted name), named by its code key, under
    ``cache_dir`` (numba's ``NUMBA_CACHE_DIR``; default: ``pipeline/model/__pycache__``)."""
    base = cache_dir or os.path.join(os.path.dirname(__file__), "__pycache__")
    return os.path.join(base, f"numba-{code_key(module)[:16]}")


def kernel_cached() -> bool:
    """Whether numba's on-disk cache holds the kernel's index for any signature (the code as it is now):
    False on a first run. numba writes an index ``<module>.<function>-<line>.<python>.nbi`` per function in
    a folder of the cache folder (numba 0.68)."""
    module, name = KERNEL
    folder = cache_folder(module, os.environ.get("NUMBA_CACHE_DIR") or None)
    return bool(glob.glob(os.path.join(glob.escape(folder), "*", f"{module.rsplit('.', 1)[1]}.{name}-*.nbi")))


def scene_arguments(argv: Sequence[str]) -> tuple[str, list[str]] | None:
    """The scene and the ``--set`` overrides of ``hdi STAGE SCENE [options]`` (the stage and the scene
    first, as the README writes it), or None when ``argv`` is not of that form: a help or version request,
    an option before the stage, the AFM files of ``hdi roughness``, more than one input. Only a head start:
    what this misses is compiled as before, and what it misreads is stopped (:func:`start`)."""
    if len(argv) < 2 or argv[0].startswith("-") or argv[1].startswith("-"):
        return None
    if argv[0] == "roughness" and not argv[1].endswith(".toml"):
        return None
    overrides: list[str] = []
    rest = list(argv[2:])
    while rest:
        arg = rest.pop(0)
        if arg in ("-h", "--help", "--version") or arg.startswith("--help-keys"):
            return None
        if arg == "--set" and rest:
            overrides.append(rest.pop(0))
        elif arg.startswith("--set="):
            overrides.append(arg[len("--set="):])
        elif arg in _VALUED:
            rest = rest[1:]
        elif not arg.startswith("-"):  # (a second input: the command line reports it)
            return None
    return argv[1], overrides


def start(argv: Sequence[str]) -> Early | None:
    """Start compiling the kernel of the scene ``argv`` names (:func:`scene_arguments`) in a background
    process, on a first run only (:func:`kernel_cached`) and unless ``HDI_COMPILE_AHEAD=0``; returns the
    process and its private folder, where it writes its signature (for
    :func:`pipeline.model.compiled.adopt_early`, which removes the folder), or None. The process says
    nothing: a scene it cannot load is the command line's to report."""
    if os.environ.get("HDI_COMPILE_AHEAD", "1") == "0":
        return None
    found = scene_arguments(argv)
    if found is None or kernel_cached():
        return None
    # (the key file does not exist until the process has written it whole, by a rename in this folder)
    folder = tempfile.mkdtemp(prefix="hdi-kernel-")
    key_path = os.path.join(folder, KEY_FILE)
    code = ("from pipeline.model.ahead import compile_scene_kernel; "
            f"compile_scene_kernel({found[0]!r}, {found[1]!r}, {key_path!r})")
    try:
        proc = background_process(code)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return Early(proc, folder)
