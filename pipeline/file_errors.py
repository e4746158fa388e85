"""A file-system operation that failed, as one line: what happened to which path and what to do
(:func:`os_error_line`); the error of a failed dataset write that names the dataset, never its temporary file,
and tells a full disk or a file size limit from the HDF5 library's errno-less error (:func:`write_failure`);
whether a file is read-only, and the process's umask.
"""

from __future__ import annotations

import errno
import os
import shutil
import stat
from pathlib import Path

try:  # (POSIX: the file size limit, ulimit -f)
    import resource
except ImportError:  # pragma: no cover
    resource = None  # type: ignore[assignment]


def is_read_only(path: str | Path) -> bool:
    """Whether a file is read-only: no write permission bit at all (what ``chmod a-w`` leaves, which
    root could still write over), or not writable by this process."""
    mode = os.stat(path).st_mode
    return not mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH) or not os.access(path, os.W_OK)


#: Spare bytes [B] a write needs beyond a dataset's arrays (HDF5 headers and attributes): with less free
#: space than the arrays and this, a failed write is put down to a full disk.
_WRITE_SLACK = 1 << 20


def write_failure(path: Path, exc: BaseException, size: int) -> OSError:
    """The :class:`OSError` naming ``path`` (never its temporary file) for a failed write of ``size``
    bytes [B]; the HDF5 library's ``NetCDF: HDF error`` says no errno, so the free space of the file
    system decides whether the disk was full."""
    if isinstance(exc, OSError) and exc.errno is not None and not (
            exc.errno in (errno.EACCES, errno.EPERM) and os.access(path.parent, os.W_OK)):
        return OSError(exc.errno, exc.strerror, str(path))
    # (the HDF5 library says "Permission denied" for a file it failed to create in a folder this process
    # writes to, where its temporary file was just made: a full disk, told apart by the free space)
    try:
        free = shutil.disk_usage(path.parent).free
    except OSError:
        free = None
    need = size * 1.1 + _WRITE_SLACK
    if free is not None and free < need:
        return OSError(errno.ENOSPC, f"{os.strerror(errno.ENOSPC)} ({free / 1e6:.3g} MB free, the dataset needs "
                                     f"about {size / 1e6:.3g} MB)", str(path))
    limit = _file_size_limit()
    if limit is not None and limit < need:
        return OSError(errno.EFBIG, f"{os.strerror(errno.EFBIG)} (the file size limit is {limit / 1e6:.3g} MB, "
                                    f"the dataset needs about {size / 1e6:.3g} MB)", str(path))
    return OSError(errno.EIO, f"the dataset could not be written ({exc}; {free / 1e6 if free else 0:.0f} MB free)",
                   str(path))


def _file_size_limit() -> int | None:
    """The largest file [B] this process may write (``ulimit -f``; ``None``: no limit, or not POSIX)."""
    if resource is None:  # pragma: no cover (not POSIX)
        return None
    soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    return None if soft == resource.RLIM_INFINITY else soft


#: What to do about an OSError, by errno (:func:`os_error_line`).
_ADVICE = {
    errno.ENOSPC: "the disk is full: free some space or choose another --out",
    errno.EDQUOT: "the disk quota is used up: free some space or choose another --out",
    errno.EACCES: "make it writable, or choose another --out",
    errno.EPERM: "make it writable, or choose another --out",
    errno.EROFS: "choose another --out",
    errno.ENAMETOOLONG: "choose a shorter --out or scene name",
    errno.EISDIR: "it is a folder where hdi writes a file: remove or rename it",
    errno.ENOTDIR: "a part of it is a file where hdi needs a folder: remove or rename that file",
    errno.EEXIST: "it is a file where hdi needs a folder: remove or rename it",
    errno.EFBIG: "the file size limit (ulimit -f) is too small: raise it",
    errno.EIO: "check the file system (free space, a network mount) and run again",
}


def os_error_line(exc: OSError) -> str:
    """One line for an :class:`OSError` of the file system: the path, what happened, what to do
    (``sweep.nc: Is a directory; it is a folder where hdi writes a file: remove or rename it``)."""
    what = exc.strerror or str(exc) or type(exc).__name__
    where = exc.filename2 if exc.errno == errno.EISDIR and exc.filename2 else exc.filename
    advice = None if ";" in what else _ADVICE.get(exc.errno)  # (a message of hdi's own says what to do)
    return (f"{where}: " if where else "") + what + (f"; {advice}" if advice else "")


def current_umask() -> int:
    """The process's file-mode creation mask (from ``/proc`` on Linux, without changing it; else by
    setting and restoring it)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
