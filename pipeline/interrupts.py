"""Signals that end a command, and cannot be lost: recorded when they arrive, raised, and raised again at safe points.

Ctrl-C (SIGINT), SIGTERM (``timeout``, ``kill``, a batch system's cancel or requeue), SIGHUP (the terminal
closed, an ssh session dropped), SIGQUIT (Ctrl-\\) and SIGUSR1 / SIGUSR2 (what some batch systems send
before their time limit) all end a command the same way: it unwinds (the folder lock and the staging
folder removed, finished work kept), says so in one line and exits with 128 + the signal's number
(:func:`exit_code`). Python runs a signal handler between two bytecodes of the main thread, wherever it is;
an exception the handler raises inside a C library's callback or error check (netCDF4 reading a variable)
can be caught there and dropped, and the run then went on to exit 0. So the handler of :func:`handling`
first *records* the signal, then raises it (:class:`Terminated`, or ``KeyboardInterrupt`` for SIGINT);
:func:`check`, called after every call that may swallow it (each dataset read and write, each stage, the
figure pool) and by the command before it reports success, raises a recorded signal again until the
command has answered it (:func:`answered`). A second signal while the first unwinds (the clean-up of the
folder lock and staging folder) is recorded and not raised, so it cannot cut that clean-up short; one
after the first was swallowed raises again; within :func:`deferred` (the command's last clean-up) a signal
is recorded only.

A signal the command was started with ignored stays ignored (SIGHUP under ``nohup``, a batch system's
ignored SIGUSR1), except SIGTERM and SIGINT, which are always answered.

The processes a command starts die with it: :func:`die_with_parent` (Linux's ``PR_SET_PDEATHSIG``) for the
forked figure workers and the background compiles, and :func:`shielded` for dask's worker processes, which
are started with the signals a terminal sends its whole process group (Ctrl-C, Ctrl-\\, a hang-up) blocked:
the command answers those, and closes its workers itself.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from typing import Iterator


class Terminated(KeyboardInterrupt):
    """A signal other than Ctrl-C arrived (SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2): unwound like Ctrl-C, so
    the folder lock and the staging folder are removed and finished work is kept. ``signum``: which one."""

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        super().__init__()
        self.signum = int(signum)


#: The signals received and not yet answered by the command (:func:`answered`), oldest first.
_PENDING: list[int] = []
#: Whether the handler records a signal only (:func:`deferred`).
_DEFERRED: list[bool] = [False]


def _named(*names: str) -> tuple[int, ...]:
    """The signals of ``names`` this platform has (Windows has no SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2)."""
    return tuple(int(getattr(signal, n)) for n in names if hasattr(signal, n))


#: SIGHUP where the platform has it (not on Windows).
SIGHUP: int | None = getattr(signal, "SIGHUP", None)
#: The signals :func:`handling` always answers.
ALWAYS = _named("SIGTERM", "SIGINT")
#: The signals :func:`handling` answers unless the command was started with them ignored (``nohup``).
UNLESS_IGNORED = _named("SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2")
#: Every signal :func:`handling` answers.
SIGNALS = ALWAYS + UNLESS_IGNORED
#: The signals a worker process of the command leaves to the command (:func:`shielded`): what a terminal sends
#: its whole process group (Ctrl-C, Ctrl-\\, a hang-up) and what a batch system may send every process of a
#: job (SIGUSR1, SIGUSR2). Not SIGTERM: dask's nanny stops its worker with it.
SHIELDED = _named("SIGINT", "SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2")
#: What the command's last line says of each signal.
_WORDS = {int(signal.SIGTERM): "terminated (SIGTERM)", int(signal.SIGINT): "interrupted"}
_WORDS.update({s: w for s, w in zip(_named("SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2"),
                                    ("hung up (SIGHUP: the terminal closed)", "quit (SIGQUIT)",
                                     "ended by SIGUSR1", "ended by SIGUSR2"))})


def _exception(signum: int) -> KeyboardInterrupt:
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


def signal_of(exc: KeyboardInterrupt) -> int:
    """The signal an interrupt stands for: its own for :class:`Terminated`, SIGINT for Ctrl-C."""
    return exc.signum if isinstance(exc, Terminated) else int(signal.SIGINT)


def describe(signum: int) -> str:
    """How the command's last line names the signal ``signum`` (``interrupted``, ``terminated (SIGTERM)``, ...)."""
    return _WORDS.get(int(signum), f"ended by signal {int(signum)}")


def message(who: str, signum: int) -> str:
    """The command's last line when ``signum`` ended it (``who``: ``hdi sweep``, or ``hdi`` before the stage
    is known)."""
    return f"{who}: {describe(signum)}; finished work is kept, run again to resume"


def say(line: str) -> None:
    """Write a command's last line to stderr; a stderr that is gone (a closed terminal: EIO; the reader of
    ``hdi ... 2>&1 | tee log``, ended by the same hang-up: a broken pipe) changes nothing else (the exit
    code still says what happened)."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):  # (ValueError: a closed file object)
        pass


def _unwinding() -> bool:
    """Whether an interrupt is being handled now (its ``finally`` blocks and ``__exit__`` run)."""
    return isinstance(sys.exc_info()[1], KeyboardInterrupt)


def _handler(signum: int, frame: object) -> None:
    _PENDING.append(signum)
    # (while the first one unwinds, a second must not cut the clean-up short; nor one during the last clean-up)
    if not _DEFERRED[0] and not _unwinding():
        raise _exception(signum)


def pending() -> int | None:
    """The first signal received and not yet answered (``None``: none)."""
    return _PENDING[0] if _PENDING else None


def check() -> None:
    """The safe point: raise the recorded signal again (it may have been swallowed where it was raised),
    unless it is being handled now. In the main thread only, where signals are handled: a fan-out's
    worker thread that finishes its task while the main thread unwinds still writes its output (a sweep
    part kept for the resume)."""
    if _PENDING and not _unwinding() and threading.current_thread() is threading.main_thread():
        raise _exception(_PENDING[0])


def answered() -> None:
    """The command has answered the recorded signals (its one line and exit code)."""
    _PENDING.clear()


def exit_code(signum: int) -> int:
    """The exit status of a command ended by ``signum`` (128 + its number: 143 SIGTERM, 130 SIGINT, 129 SIGHUP)."""
    return 128 + int(signum)


@contextlib.contextmanager
def handling() -> Iterator[None]:
    """Answer the signals of :data:`SIGNALS` with the recording handler within the block (in the main thread;
    another thread cannot set handlers, and the block then does nothing), the previous handlers restored
    after. Those of :data:`UNLESS_IGNORED` only if they are not ignored (under ``nohup`` SIGHUP is, and stays
    so). Blocks may nest (the console script's around the command's)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, _handler) for s in SIGNALS
                if s in ALWAYS or signal.getsignal(s) in (signal.SIG_DFL, _handler)}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Within the block a signal is recorded (:func:`pending`) and not raised: the command's last clean-up
    (stopping its background compiles, flushing its output) is not cut short, and the command then answers
    the signal."""
    before, _DEFERRED[0] = _DEFERRED[0], True
    try:
        yield
    finally:
        _DEFERRED[0] = before


@contextlib.contextmanager
def shielded() -> Iterator[None]:
    """Within the block, the calling thread has the signals of :data:`SHIELDED` blocked, and so has every
    thread and process it starts, for their whole life (a blocked signal mask is inherited by a new thread
    and across ``fork`` and ``exec``): around the start of dask's local process cluster, whose event-loop
    thread starts the worker processes and multiprocessing's resource tracker. A terminal's Ctrl-C or
    hang-up then reaches only this process, which answers it and closes the cluster; a worker killed by it
    first (and restarted by its nanny, and the resource tracker relaunched: a traceback per shared-memory
    name) no longer races the clean-up. No signal is lost meanwhile: a blocked one stays pending, or is
    taken by another thread of this process and handled in the main thread as always. Nothing happens
    where ``pthread_sigmask`` does not exist (Windows)."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    before = signal.pthread_sigmask(signal.SIG_BLOCK, SHIELDED)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def default_in_child(parent: int | None = None) -> None:
    """In a forked worker: the keyboard's signals ignored (Ctrl-C and Ctrl-\\ reach the whole process group;
    the parent answers them and stops the pool), the others the parent answers back to their default (the
    parent's handler would unwind the worker's copy of the parent), and with ``parent`` (its process id)
    the worker dies with it (:func:`die_with_parent`)."""
    for s in SIGNALS:
        if signal.getsignal(s) is _handler or s == signal.SIGINT:
            signal.signal(s, signal.SIG_IGN if s in _named("SIGINT", "SIGQUIT") else signal.SIG_DFL)
    _PENDING.clear()
    if parent is not None:
        die_with_parent(parent)


def in_background(parent: int | None) -> None:
    """In a background process a command started (a kernel's compile): the signals of :data:`SHIELDED`
    ignored (the command answers them and stops the process), and with ``parent`` (the command's process
    id, given when the process was started from the command's main thread) it dies with the command
    (:func:`die_with_parent`)."""
    for s in SHIELDED:
        signal.signal(s, signal.SIG_IGN)
    if parent is not None:
        die_with_parent(parent)


#: ``prctl`` option of Linux: the signal a process gets when the thread that forked it ends.
_PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int) -> None:
    """Make this process die (SIGKILL) when its parent ``parent`` does, however the parent ends (SIGKILL,
    SIGHUP of a closed terminal): a worker that outlived it held the parent's stdout and stderr, so
    ``hdi run ... | tee log`` never ended, and a background compile held a core. Linux's ``PR_SET_PDEATHSIG``
    (by ctypes): it fires when the *thread* that started this process ends, so the parent starts such a
    process from its main thread only; a parent already gone before it was set ends the process at once.
    Elsewhere nothing is set."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover (no libc prctl)
            return
    if os.getppid() != parent:  # (the parent died between the fork and the prctl)
        os._exit(1)
