"""A failed file-system operation as one line (pipeline.file_errors): the path, what happened, what to do."""

from __future__ import annotations

import errno

import pytest

from pipeline import file_errors


@pytest.mark.parametrize("exc, line", [
    (OSError(errno.ENOSPC, "No space left on device", "out/sweep.nc"),
     "out/sweep.nc: No space left on device; the disk is full: free some space or choose another --out"),
    (IsADirectoryError(errno.EISDIR, "Is a directory", "out/.tmp", None, "out/sweep.nc"),
     "out/sweep.nc: Is a directory; it is a folder where hdi writes a file: remove or rename it"),
    (OSError(errno.EACCES, "already says what to do; chmod it", "x.nc"), "x.nc: already says what to do; chmod it"),
    (OSError(errno.EBADF, "Bad file descriptor"), "Bad file descriptor")],
    ids=["full-disk", "folder-for-a-file", "own-advice", "no-path"])
def test_an_os_error_is_one_line_with_the_path_and_what_to_do(exc, line):
    assert file_errors.os_error_line(exc) == line
