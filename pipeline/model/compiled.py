"""How the kernel's functions are compiled: numba options and the on-disk cache folder.

numba's on-disk cache of a jitted function checks the timestamp of the file that holds it, not of
the files whose functions it inlines (e.g. the air-bearing laws of :mod:`pipeline.physics.air_bearing`
inlined into the right-hand side): with an edited law the kernel would load its old machine code
while the runner (which keys on the code) recomputes the results. So each kernel module's functions
are cached in a folder named by the code key of that module and of everything it imports
(:func:`pipeline.code_version.code_key`). numba picks a function's cache folder when it is
decorated, so :func:`kernel_jit` sets the folder around the decoration only.

The first run (docs/performance.md, section "The first run"). numba compiles a kernel entry point once per
signature (the scene's effects: which slots are ``None``, the rear law, the meniscus state) and then
loads it from the cache. Compiling takes tens of seconds of CPU, nearly all numba's own front end
(inlining, typing, lowering) under its one compiler lock, so threads cannot share it. Two things here:

* :func:`announce`: an entry point's compile says so, with roughly how long it takes
  (:func:`pipeline.progress.compile_notice`, from numba's ``numba:compile`` event, which fires on a
  compile, not on a cache load);
* :func:`compile_ahead`: a process that is about to need an entry point it has neither compiled nor
  cached (the dynamics kernel, at a model's first run) starts compiling it in a background process
  (:func:`compile_from_file`), while it goes on with what comes first (the static starts, compiled in
  this process), and :func:`wait_ahead` waits for it before the first call, which then loads the kernel
  from the cache. On 2 cores the two compiles overlap. ``HDI_COMPILE_AHEAD=0`` turns it off (the
  process compiles everything itself). Machine code and results are the same either way;
* :func:`while_waiting`: work that would come later (a later stage's imports, its compiles) done by :func:`wait_ahead`
  while the background compile still runs, instead of idling.

Who starts it: the stage runner, before the first stage of a build that computes a stage which simulates
(:meth:`pipeline.runner.Runner.compile_ahead`, from the scene's stand-in arguments,
:func:`pipeline.model.ahead.compile_kernel_ahead`); the Python API's ``build_model``; and a model's
first run, for a model whose kernel nothing started (:func:`pipeline.model.dynamics.compile_kernel_ahead`).
On a first run of the ``hdi`` console script, the kernel's compile starts even before the command line's
imports (:mod:`pipeline.model.first_run`), and the runner adopts it (:func:`adopt_early`).
"""

from __future__ import annotations

import importlib
import logging
import os
import pickle
import subprocess
import tempfile
import threading
import time
from typing import Any, Callable

import numba
from numba import njit
from numba.core import event

from . import first_run
from .. import progress

log = logging.getLogger(__name__)

#: Options of every kernel function: cached on disk, releases the GIL, numpy's error model (a division
#: by zero gives inf/nan, no exception path in the machine code), and of the fast-math flags only ``contract``:
#: LLVM may fuse a product and the sum it feeds into one fused multiply-add (one rounding instead of two, on
#: hosts with FMA), nothing else (no reassociation, no approximate reciprocals, NaN, infinities and signed zeros
#: as IEEE has them). The sliding scene's kernel then takes 11 % less time (docs/kernel.md, section "Fused
#: multiply-adds"); results move in their last bits against unfused code, and are the same run after run on a
#: host (docs/testing.md).
OPTIONS = dict(cache=True, nogil=True, error_model="numpy", fastmath={"contract"})

#: The further option of a kernel function that only reads and writes arrays it is given (allocates none,
#: returns none: the step, the right-hand side, the step's cap, the separation): compiled without numba's
#: reference counting (``_nrt=False``), since its caller holds every array for the whole call. numba otherwise keeps a
#: reference-count pair per array variable past each call's exception exit (41 increments per step with
#: the interface tables; docs/kernel.md, section "The step without reference counts"). An allocation in such
#: a function does not compile (numba: "Only accept returning of array passed into the function as argument"),
#: nor in a compiled function it calls, which numba compiles for it without reference counts too (unless
#: that function sets the option itself); such a function must not call one that returns a new array, whose
#: memory would never be freed.
BORROWING = dict(_nrt=False)


def cache_folder(module: str) -> str:
    """The numba cache folder of the kernel module ``module`` (a dotted name): named by its code key
    (:func:`pipeline.model.first_run.cache_folder` under numba's cache folder)."""
    return first_run.cache_folder(module, numba.config.CACHE_DIR)


def kernel_jit(module: str, **options) -> Callable[[Callable], Callable]:
    """A decorator compiling a function of the module ``module`` with :data:`OPTIONS` (and ``options``,
    e.g. ``inline="always"``), cached in :func:`cache_folder` of the module."""
    folder = cache_folder(module)

    def decorate(fn: Callable) -> Callable:
        saved = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = folder
        try:
            return njit(**OPTIONS, **options)(fn)
        finally:
            numba.config.CACHE_DIR = saved

    return decorate


#: The announced entry points: ``id(dispatcher)`` -> what is compiled.
_NOTICES: dict[int, str] = {}
#: The announced compiles under way in this process: ``id(dispatcher)`` -> their start (``time.perf_counter``).
_STARTED: dict[int, float] = {}
#: True in the background process of :func:`compile_ahead`: its compiles say nothing.
_QUIET = False


def announce(dispatcher: Any, what: str) -> None:
    """Make a compile of the jitted ``dispatcher`` say that ``what`` is compiling, and then how long it took
    on this machine (:func:`pipeline.progress.compile_notice`; a cache load says nothing)."""
    _NOTICES[id(dispatcher)] = what


class _CompileNotice(event.Listener):
    """numba's ``numba:compile`` event (a compile after a cache miss) of an announced entry point."""

    def on_start(self, ev: event.Event) -> None:
        key = id(ev.data["dispatcher"])
        if key in _NOTICES and not _QUIET:
            _STARTED[key] = time.perf_counter()
            progress.compile_notice(_NOTICES[key])

    def on_end(self, ev: event.Event) -> None:
        start = _STARTED.pop(id(ev.data["dispatcher"]), None)
        if start is not None:
            progress.compile_notice(_NOTICES[id(ev.data["dispatcher"])], time.perf_counter() - start)


event.register("numba:compile", _CompileNotice())


def signature(dispatcher: Any, args: tuple) -> tuple:
    """The numba types of ``args`` as ``dispatcher`` types them on a call (~1 ms: the parameter record)."""
    return tuple(dispatcher.typeof_pyval(a) for a in args)


def is_cached(dispatcher: Any, sig: tuple) -> bool:
    """Whether the on-disk cache holds ``dispatcher`` compiled for the types ``sig`` (its index is read,
    not the machine code; numba's cache internals, numba 0.68)."""
    cache = dispatcher._cache
    index = getattr(cache, "_cache_file", None)
    if index is None:  # (not cached on disk at all)
        return False
    return cache._index_key(sig, dispatcher.targetctx.codegen()) in index._load_index()


#: Background compiles under way: (module, name, signature) -> the process.
_AHEAD: dict[tuple, subprocess.Popen] = {}
#: What each background compile compiles and when this process said so: key -> (what, ``time.perf_counter``).
_AHEAD_SAID: dict[tuple, tuple[str, float]] = {}
_AHEAD_LOCK = threading.Lock()
#: Work for :func:`wait_ahead` to do while a background compile runs (:func:`while_waiting`).
_IDLE: list[Callable[[], None]] = []
#: The console script's first-run compile (:func:`adopt_early`), until :func:`compile_ahead` adopts or
#: stops it, or :func:`stop_early` stops it: one at most.
_EARLY: first_run.Early | None = None
#: How often :func:`compile_ahead` looks for the early process's key while it is still loading the scene [s].
EARLY_POLL_S = 0.02


def adopt_early(early: first_run.Early | None) -> None:
    """Hand this process the kernel compile the console script started before its imports
    (:func:`pipeline.model.first_run.start`: the process and the private folder it writes its ``(module,
    name, signature)`` key to): :func:`compile_ahead` waits for it instead of starting one, if it compiles
    the signature asked for; otherwise stops it. None: nothing started."""
    global _EARLY
    if early is not None:
        with _AHEAD_LOCK:
            _EARLY = early


def _read_key(path: str) -> tuple | None:
    """The key an early process wrote to ``path`` (None: not written, or unreadable)."""
    try:
        with open(path, "rb") as f:
            return pickle.load(f)
    except (OSError, EOFError, pickle.UnpicklingError):
        return None


def _adopt(key: tuple) -> subprocess.Popen | None:
    """The early process if it compiles ``key`` (its key file read, waiting while it loads the scene), else
    None, having stopped it (its work would only compete with this process's own compile). Either way its
    folder is removed and it is no longer :data:`_EARLY`."""
    global _EARLY
    if _EARLY is None:
        return None
    early, _EARLY = _EARLY, None
    got = _read_key(early.key_path)
    while got is None and early.proc.poll() is None:
        time.sleep(EARLY_POLL_S)
        got = _read_key(early.key_path)
    got = got if got is not None else _read_key(early.key_path)  # (written just before it ended)
    if got != key:
        _stop(early.proc)
    early.discard()  # (read, or the process ended: nothing writes there any more)
    return early.proc if got == key else None


def _stop(proc: subprocess.Popen) -> None:
    """End a background compile whose machine code nobody will ask for (numba writes a cache entry whole, by
    a rename: an ended compile leaves none, never a torn one)."""
    if proc.poll() is None:
        proc.terminate()
        proc.wait()


def stop_early() -> None:
    """Stop an early compile nothing adopted (a command that did not simulate) and remove its folder: called
    at the command's end, so no process outlives it."""
    global _EARLY
    with _AHEAD_LOCK:
        if _EARLY is not None:
            early, _EARLY = _EARLY, None
            _stop(early.proc)
            early.discard()


def stop_ahead() -> None:
    """Stop the background compiles nobody waited for (:func:`compile_ahead` without :func:`wait_ahead`: the
    command was interrupted or failed before its first integration, or read every result back): called at
    the command's end, so none outlives it. SIGTERM from ``timeout`` or ``kill`` reaches the command's
    process alone (Ctrl-C reaches its whole process group), and a compile left running held a core for up to
    its ~12 s of CPU after the command had answered the signal. Its partial work is lost; a rerun compiles
    again."""
    with _AHEAD_LOCK:
        for key, proc in list(_AHEAD.items()):
            _stop(proc)
            del _AHEAD[key]
        _IDLE.clear()


def compile_ahead(dispatcher: Any, args: tuple, what: str) -> bool:
    """Start compiling ``dispatcher`` (a jitted function of a kernel module) for the types of ``args`` in a
    background process, unless this process has it, the cache has it, one is under way, or
    ``HDI_COMPILE_AHEAD=0``; says so (:func:`pipeline.progress.compile_notice`). :func:`wait_ahead`
    waits for it. The kernel's compile the console script started before its imports (:func:`adopt_early`)
    is that process when it compiles the same signature, and is stopped otherwise. Returns whether this
    call started a process (not: adopted the console script's, or started none)."""
    if os.environ.get("HDI_COMPILE_AHEAD", "1") == "0":
        return False
    sig = signature(dispatcher, args)
    key = (dispatcher.py_func.__module__, dispatcher.py_func.__name__, sig)
    with _AHEAD_LOCK:
        early = _adopt(key) if key[:2] == first_run.KERNEL else None
        if key in _AHEAD or sig in dispatcher.overloads or is_cached(dispatcher, sig):
            if early is not None:  # (done, or done elsewhere: nothing left for it to do)
                _stop(early)
            return False
        if early is not None:  # (the console script's, started before its imports: the same compile)
            _AHEAD[key] = early
            _say_ahead(key, what)
            return False
        fd, path = tempfile.mkstemp(prefix="hdi-compile-", suffix=".pkl")
        with os.fdopen(fd, "wb") as f:
            pickle.dump(key, f)
        code = f"from pipeline.model.compiled import compile_from_file; compile_from_file({path!r})"
        # (silent: a failure there is only a cache miss, and this process then compiles and reports it;
        # a Ctrl-C reaches it too, without a second traceback)
        _AHEAD[key] = first_run.background_process(code)
        _say_ahead(key, what)
        return True


def _say_ahead(key: tuple, what: str) -> None:
    """Say that ``what`` compiles in a background process (:func:`wait_ahead` says how long it took)."""
    _AHEAD_SAID[key] = (f"{what} in a background process", time.perf_counter())
    progress.compile_notice(_AHEAD_SAID[key][0])


def while_waiting(work: Callable[[], None]) -> None:
    """Have :func:`wait_ahead` call ``work()`` (once) if a background compile is still running when this
    process comes to wait for it: work the process would do later anyway (importing what a later stage
    needs) done while it would otherwise idle. Dropped when no compile is under way, and when the compile
    is over by the time of the wait. ``work`` must not change a result: it only comes earlier."""
    with _AHEAD_LOCK:
        if _AHEAD:
            _IDLE.append(work)


def import_modules(names: tuple[str, ...]) -> Callable[[], None]:
    """Work for :func:`while_waiting`: import the modules ``names`` (dotted names)."""
    def work() -> None:
        for name in names:
            importlib.import_module(name)
    return work


def wait_ahead() -> None:
    """Wait for the background compiles (:func:`compile_ahead`), doing the work of :func:`while_waiting`
    meanwhile: the next call loads their machine code from the cache. A failed one is only a cache miss:
    this process then compiles it itself."""
    with _AHEAD_LOCK:
        while _IDLE and running():
            work = _IDLE.pop(0)
            try:
                work()
            except Exception as exc:  # (only a head start: the stage does it again and reports it in its words)
                log.debug("work while waiting for a compile failed: %s", exc)
        _IDLE.clear()
        for key, proc in list(_AHEAD.items()):
            running_then = proc.poll() is None
            proc.wait()
            del _AHEAD[key]
            what, start = _AHEAD_SAID.pop(key, (None, 0.0))
            if what is not None and proc.returncode == 0:  # (its time from the notice, measured here)
                progress.compile_notice(what if running_then else f"{what} (done before it was needed)",
                                        time.perf_counter() - start)


def pending() -> bool:
    """Whether a background compile (:func:`compile_ahead`) was started and not waited for."""
    return bool(_AHEAD)


def running() -> bool:
    """Whether a background compile (:func:`compile_ahead`) is still running: work done while waiting stops
    when none is, since from then on it delays the caller. Takes no lock: the work :func:`wait_ahead` runs
    under it asks."""
    return any(proc.poll() is None for proc in _AHEAD.values())


def compile_from_file(path: str) -> None:
    """The background process of :func:`compile_ahead`: compile the function and signature pickled in
    ``path`` (deleted) into the on-disk cache."""
    with open(path, "rb") as f:
        module, name, sig = pickle.load(f)
    os.unlink(path)
    compile_quietly(getattr(importlib.import_module(module), name), sig)


def compile_quietly(dispatcher: Any, sig: tuple) -> None:
    """Compile ``dispatcher`` for ``sig`` into the on-disk cache (loaded instead if it is there), saying
    nothing: the body of a background compile, whose starter has said it."""
    global _QUIET
    _QUIET = True
    dispatcher.compile(sig)
