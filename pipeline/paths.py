"""Files inside a results folder and files hdi reads: no symbolic link followed, no special file opened.

In a shared, group-writable results folder another user can plant a symbolic link where hdi writes
(``figures/``, ``.hdi/``, the lock file): :func:`refuse_links` refuses every link below a folder this
process holds (:func:`guarded`, entered by :func:`pipeline.folder_lock.folder_lock`) on the way to a file hdi
writes, locks or deletes, in one line naming the link (:class:`LinkRefused`). A FIFO or a device as an
input file (``dmw.source = "/dev/zero"``) would block or never end: :func:`special_kind` names what it is,
checked before the file is opened.
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
from pathlib import Path
from typing import Iterator

#: The results folders this process holds (:func:`pipeline.folder_lock.folder_lock` enters :func:`guarded`):
#: below them hdi follows no symbolic link for a file it writes, locks or deletes (:func:`refuse_links`).
_ROOTS: list[Path] = []


class LinkRefused(OSError):
    """A symbolic link inside a results folder where hdi would write, lock or delete a file: in a shared,
    group-writable folder another user can plant one to make hdi write or delete elsewhere."""

    def __init__(self, link: str | Path):
        try:
            target = f" (to {os.readlink(link)})"
        except OSError:
            target = ""
        super().__init__(errno.ELOOP, f"is a symbolic link{target}; hdi writes, locks and deletes no file through "
                                      "a link inside its results folder: remove the link", str(link))


@contextlib.contextmanager
def guarded(folder: str | Path) -> Iterator[Path]:
    """Within the block, :func:`refuse_links` checks every path below ``folder`` (a results folder this
    process holds); ``folder`` itself may be a link (the user chose it)."""
    root = Path(os.path.abspath(folder))
    _ROOTS.append(root)
    try:
        yield root
    finally:
        _ROOTS.remove(root)


def refuse_links(path: str | Path) -> Path:
    """``path``, after checking that neither it nor a folder between it and the outermost held results
    folder (:func:`guarded`) containing it is a symbolic link; a path outside every held folder is not
    checked (a user's ``--readme`` page, a test's file).

    Raises
    ------
    LinkRefused
        Naming the first link found.
    """
    p = Path(os.path.abspath(path))
    roots = [r for r in list(_ROOTS) if p == r or r in p.parents]
    if roots:
        here = min(roots, key=lambda r: len(r.parts))
        for part in p.relative_to(here).parts:
            here = here / part
            try:
                mode = os.lstat(here).st_mode
            except (FileNotFoundError, NotADirectoryError):
                break
            if stat.S_ISLNK(mode):
                raise LinkRefused(here)
    return Path(path)


def append_text(path: str | Path, text: str, sync: bool = False) -> None:
    """Append ``text`` to the file ``path`` (created 0666 less the umask; its folder too), never through a
    symbolic link (:func:`refuse_links`, and ``O_NOFOLLOW`` for the file itself); ``sync``: flushed to
    the disk before returning (a resume point)."""
    path = refuse_links(Path(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    refuse_links(path)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o666)
    except OSError as exc:
        if exc.errno == errno.ELOOP:  # (a link planted since the check)
            raise LinkRefused(path) from None
        raise
    with os.fdopen(fd, "a", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        if sync:
            os.fsync(fh.fileno())


#: What a file that is not a regular file is (:func:`special_kind`), by its ``stat`` type.
_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a folder"))


def looked_for(path: str | Path) -> str:
    """``" (looked for /abs/path)"``: where a relative ``path`` that was not found was looked for (from the
    working directory), for a 'does not exist' message; ``""`` for an absolute path, which says it itself."""
    p = Path(path).expanduser()
    return "" if p.is_absolute() else f" (looked for {p.absolute()})"


def special_kind(path: str | Path) -> str | None:
    """What ``path`` (a link followed) is when it exists but is not a regular file (``"a FIFO (named
    pipe)"``, ``"a character device"``, ...), else ``None``: reading a FIFO or ``/dev/zero`` never ends,
    so a file hdi reads is checked with this before it is opened."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISREG(mode):
        return None
    return next((what for test, what in _KINDS if test(mode)), "not a regular file")
