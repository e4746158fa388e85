"""One ``hdi`` process at a time in a results folder: the folder lock, and the temporaries of an interrupted run.

:func:`folder_lock` holds ``.hdi.lock`` (:data:`LOCK_NAME`: pid, host, start time) and refuses a second
process, naming the first (:class:`FolderBusy`); a lock whose process is gone (same host) is taken over, one
process at a time deciding (an exclusive ``flock`` on the folder). Temporary files an interrupted run left
behind (hdi's own names, ``.NAME.hdi-RUNID*.tmp`` of :func:`pipeline.io.temporary_path`, and the staging
folders :data:`STAGING_PREFIX`) are removed when the lock is taken (:func:`clean_orphans`); a user's files,
links and another results folder holding its lock (a run in a sub-folder) are left alone. While the lock is
held no symbolic link inside the folder is followed for a file hdi writes or deletes
(:func:`pipeline.paths.guarded`), and a lock file that is a link is refused, not taken over.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import json
import logging
import os
import shutil
import socket
import stat
from pathlib import Path
from typing import Any, Iterator

from .io import DatasetError, RUN_ID, is_temporary
from .paths import LinkRefused, guarded, refuse_links, special_kind

log = logging.getLogger(__name__)

#: The lock file of a results folder (:func:`folder_lock`).
LOCK_NAME = ".hdi.lock"
#: Prefix of a stage's staging folder inside a results folder (:meth:`pipeline.runner.Runner.build` makes
#: it; :func:`clean_orphans` removes one an interrupted run left).
STAGING_PREFIX = ".hdi-staging-"
#: How deep below a results folder the cleaner looks for orphaned temporary files (``sweep.parts/interface-x/``).
_TMP_DEPTH = 2


class FolderBusy(DatasetError):
    """Another ``hdi`` process is working in the results folder."""


#: The lock files this process holds (a second hold of one is a programming error, :func:`folder_lock`).
_HELD: set[Path] = set()


def _is_pid(value: Any) -> bool:
    """Whether a lock file's ``pid`` is a process id (a positive 32-bit integer, as ``os.kill`` takes)."""
    return isinstance(value, int) and not isinstance(value, bool) and 0 < value < 2**31


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this host (one of another user counts as alive)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def clean_orphans(out: Path) -> list[Path]:
    """Remove the temporary files and staging folders an interrupted run left in ``out``.

    Only hdi's own temporary files (:func:`pipeline.io.is_temporary`) are removed, up to
    :data:`_TMP_DEPTH` folders deep, and never below a sub-folder that holds a :data:`LOCK_NAME`:
    that is another results folder, maybe in use by another run (``--out`` its parent).
    """
    removed = []
    for folder, dirs, names in os.walk(out):
        depth = len(Path(folder).relative_to(out).parts)
        dirs[:] = [] if depth >= _TMP_DEPTH else [d for d in dirs if not (Path(folder, d) / LOCK_NAME).exists()]
        for name in names:
            p = Path(folder, name)
            if is_temporary(name) and p.is_file() and not p.is_symlink():  # (a link: not a file hdi made)
                p.unlink(missing_ok=True)
                removed.append(p)
    for p in out.glob(STAGING_PREFIX + "*"):
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    if removed:
        log.info("%s: removed %d temporary file(s) of an interrupted run", out, len(removed))
    return removed


@contextlib.contextmanager
def _deciding(out: Path) -> Iterator[None]:
    """One process at a time decides who holds ``out``'s lock: an exclusive ``flock`` on the folder
    itself, held while the lock file is read, judged stale, removed and written. Without it two
    processes could both find a dead holder's lock, and the second remove the first's new one."""
    try:
        import fcntl
    except ImportError:  # (not POSIX: the lock file alone)
        yield
        return
    fd = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # (releases the flock)


@contextlib.contextmanager
def folder_lock(out: str | Path) -> Iterator[Path]:
    """Hold ``out/.hdi.lock``; refuse when another live process holds it.

    Not re-entrant: a stage's ``compute`` reads its inputs through :class:`pipeline.runner.Inputs` (made
    current by the runner before it runs) and never builds in its own folder, so a second hold of the same folder
    in one process is a programming error, reported as such.

    Raises
    ------
    FolderBusy
        Naming the other process and the lock file.
    RuntimeError
        When this process already holds the folder.
    """
    out = refuse_links(Path(out))  # (a sub-folder of a held folder, sweep.parts/interface-x: no link either)
    out.mkdir(parents=True, exist_ok=True)
    path = out.resolve() / LOCK_NAME  # (the folder resolved, never the lock file: a planted link is refused)
    if path in _HELD:
        raise RuntimeError(f"{out}: this process already holds the folder; a stage's compute reads its "
                           "inputs through runner.Inputs and does not build in its own folder")
    me = {"pid": os.getpid(), "host": socket.gethostname(), "run": RUN_ID,
          "started": _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()}
    with _deciding(out):
        for _ in range(2):
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                try:
                    other = json.loads(_read_lock(path) or "{}")
                except (UnicodeDecodeError, ValueError):
                    other = {}
                if not isinstance(other, dict) or not _is_pid(other.get("pid")):  # (`[1, 2]`: JSON, but
                    other = {}                                                 # not what a holder writes)
                pid, host = other.get("pid"), other.get("host")
                if not other or (host == me["host"] and not _alive(pid)):
                    # (an empty or unreadable file is garbage: a holder writes its file before it
                    # lets the next process decide)
                    if other:
                        log.warning("%s: taking over the lock of hdi process %s, which is gone", out, pid)
                    else:
                        log.warning("%s: taking over the lock file %s, which names no hdi process", out, path)
                    path.unlink(missing_ok=True)
                    continue
                raise FolderBusy(f"{out}: in use by hdi process {pid} on {host} since {other.get('started')} "
                                 f"(lock file {path}); wait for it to finish, or delete the lock file if that "
                                 "process no longer exists") from None
            try:
                with os.fdopen(fd, "w") as fh:
                    json.dump(me, fh)
            except OSError as exc:  # (a full disk: no empty lock file left for the next run to take over)
                path.unlink(missing_ok=True)
                raise OSError(exc.errno, f"{exc.strerror} (writing the results folder's lock file)", str(path)) from None
            break
        else:
            raise FolderBusy(f"{out}: could not take the lock file {path}")
    _HELD.add(path)
    try:
        with guarded(out):
            clean_orphans(out)
            yield path
    finally:
        _HELD.discard(path)
        path.unlink(missing_ok=True)


def _read_lock(path: Path) -> str:
    """The text of an existing lock file, read without following a link (a link planted at
    :data:`LOCK_NAME` is refused: taking it over would delete the link's target before) and without
    blocking (a FIFO there is refused too)."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        return ""
    except OSError as exc:
        if exc.errno == errno.ELOOP or path.is_symlink():
            raise LinkRefused(path) from None
        raise
    if stat.S_ISDIR(os.fstat(fd).st_mode):  # (a folder opens read-only, but is no file to read)
        os.close(fd)
        raise OSError(errno.EISDIR, "is a folder where hdi keeps the results folder's lock file; remove or rename "
                                    "it (nothing else of hdi's is kept there)", str(path))
    with os.fdopen(fd, "rb") as fh:
        if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
            raise OSError(errno.EINVAL, f"is {special_kind(path) or 'not a regular file'}, not hdi's lock file; "
                                        "remove it", str(path))
        return fh.read(1 << 16).decode("utf-8")
