"""SIGTERM, SIGHUP and Ctrl-C that cannot be lost: recorded when they arrive, raised, and raised again at safe points.

Python runs a signal handler between two bytecodes of the main thread, wherever it is; an exception the
handler raises inside a C library's callback or error check (netCDF4 reading a variable) can be caught
there and dropped, and the run then went on to exit 0. So the handler of :func:`handling` first
*records* the signal, then raises it (:class:`Terminated` for SIGTERM and SIGHUP, ``KeyboardInterrupt``
for SIGINT); :func:`check`, called after every call that may swallow it (each dataset read and write, each
stage, the figure pool) and by the command before it reports success, raises a recorded signal again
until the command has answered it (:func:`answered`). A signal never leaves SIGTERM ignored: a second
one while the first unwinds (the clean-up of the folder lock and staging folder) is recorded and not
raised, so it cannot cut that clean-up short; one after the first was swallowed raises again.

SIGHUP (the terminal closed, an ssh session dropped) is answered like SIGTERM, but only where it would have
killed the process: a command started under ``nohup`` (or by a shell that ignores it) keeps ignoring it.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from typing import Iterator


class Terminated(KeyboardInterrupt):
    """SIGTERM (``timeout``, ``kill``, SLURM's ``scancel`` and requeue) or SIGHUP (the terminal closed)
    arrived: unwound like Ctrl-C, so the folder lock and the staging folder are removed and finished work is
    kept. ``signum``: which of the two."""

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        super().__init__()
        self.signum = int(signum)


#: The signals received and not yet answered by the command (:func:`answered`), oldest first.
_PENDING: list[int] = []
#: SIGHUP where the platform has it (not on Windows).
SIGHUP: int | None = getattr(signal, "SIGHUP", None)
#: The signals :func:`handling` answers (SIGHUP only where it is not ignored already).
SIGNALS = (signal.SIGTERM, signal.SIGINT) + ((SIGHUP,) if SIGHUP is not None else ())
#: What the command's last line says of each signal.
_WORDS = {int(signal.SIGTERM): "terminated (SIGTERM)", int(signal.SIGINT): "interrupted"}
if SIGHUP is not None:
    _WORDS[int(SIGHUP)] = "hung up (SIGHUP: the terminal closed)"


def _exception(signum: int) -> KeyboardInterrupt:
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


def signal_of(exc: KeyboardInterrupt) -> int:
    """The signal an interrupt stands for: its own for :class:`Terminated`, SIGINT for Ctrl-C."""
    return exc.signum if isinstance(exc, Terminated) else int(signal.SIGINT)


def describe(signum: int) -> str:
    """How the command's last line names the signal ``signum`` (``interrupted``, ``terminated (SIGTERM)``, ...)."""
    return _WORDS.get(int(signum), f"ended by signal {int(signum)}")


def _unwinding() -> bool:
    """Whether an interrupt is being handled now (its ``finally`` blocks and ``__exit__`` run)."""
    return isinstance(sys.exc_info()[1], KeyboardInterrupt)


def _handler(signum: int, frame: object) -> None:
    _PENDING.append(signum)
    if not _unwinding():  # (while the first one unwinds, a second must not cut the clean-up short)
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
    """The exit status of a command ended by ``signum`` (128 + its number: 143 SIGTERM, 130 SIGINT)."""
    return 128 + int(signum)


@contextlib.contextmanager
def handling() -> Iterator[None]:
    """Answer SIGTERM, SIGINT and SIGHUP with the recording handler within the block (in the main thread;
    another thread cannot set handlers, and the block then does nothing), the previous handlers restored
    after. SIGHUP only if its handler is the default (under ``nohup`` it is ignored, and stays so)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, _handler) for s in SIGNALS
                if s != SIGHUP or signal.getsignal(s) is signal.SIG_DFL}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def default_in_child(parent: int | None = None) -> None:
    """In a forked worker: SIGTERM (and SIGHUP, if the parent answers it) back to its default (the parent's
    handler would unwind the worker's copy of the parent), Ctrl-C ignored (it reaches the whole process
    group; the parent answers it), and with ``parent`` (its process id) the worker dies with it
    (:func:`die_with_parent`)."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if SIGHUP is not None and signal.getsignal(SIGHUP) is _handler:
        signal.signal(SIGHUP, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _PENDING.clear()
    if parent is not None:
        die_with_parent(parent)


#: ``prctl`` option of Linux: the signal a process gets when the thread that forked it ends.
_PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int) -> None:
    """Make this forked process die (SIGKILL) when its parent ``parent`` does, however the parent ends
    (SIGKILL, SIGHUP of a closed terminal): a worker that outlived it held the parent's stdout and stderr,
    so ``hdi run ... | tee log`` never ended. Linux's ``PR_SET_PDEATHSIG`` (by ctypes); a parent already
    gone before it was set ends the process at once. Elsewhere nothing is set."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover (no libc prctl)
            return
    if os.getppid() != parent:  # (the parent died between the fork and the prctl)
        os._exit(1)
