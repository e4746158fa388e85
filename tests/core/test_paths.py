"""Files inside a results folder (pipeline/paths.py): below a folder this process holds no symbolic link is
followed on the way to a file hdi writes, locks or deletes, the folder itself may be one, and paths outside
every held folder are not checked; appends never go through a link; a file that is not a regular one is
named for what it is before it is opened."""

from __future__ import annotations

import os
import socket
import stat

import pytest

from pipeline import paths


def test_a_link_below_a_held_folder_is_refused_naming_it_and_its_target(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "figures").symlink_to(elsewhere)
    with paths.guarded(out) as root:
        assert root == out
        assert paths.refuse_links(out / "sweep.nc") == out / "sweep.nc"          # nothing planted there
        with pytest.raises(paths.LinkRefused) as info:
            paths.refuse_links(out / "figures" / "fig6.png")
    exc = info.value
    assert exc.filename == str(out / "figures") and f"(to {elsewhere})" in exc.strerror
    assert exc.strerror.endswith("remove the link") and "\n" not in str(exc)
    # out of the block the folder is no longer held: the same path is not checked
    assert paths.refuse_links(out / "figures" / "fig6.png") == out / "figures" / "fig6.png"
    assert paths._ROOTS == []


def test_the_held_folder_itself_may_be_a_link_and_outside_paths_are_not_checked(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "chosen").symlink_to(real)          # the user's own choice of results folder
    (tmp_path / "page.md").symlink_to(real / "page.md")
    with paths.guarded(tmp_path / "chosen"):
        assert paths.refuse_links(tmp_path / "chosen" / "dmw.nc") == tmp_path / "chosen" / "dmw.nc"
        assert paths.refuse_links(tmp_path / "page.md") == tmp_path / "page.md"   # a --readme page: not held


def test_nested_held_folders_are_checked_from_the_outermost(tmp_path):
    outer = tmp_path / "outer"
    (outer / "run").mkdir(parents=True)
    (tmp_path / "target").mkdir()
    (outer / "run" / ".hdi").symlink_to(tmp_path / "target")
    with paths.guarded(outer), paths.guarded(outer / "run"):
        with pytest.raises(paths.LinkRefused):
            paths.refuse_links(outer / "run" / ".hdi" / "log")
        assert len(paths._ROOTS) == 2
    assert paths._ROOTS == []


def test_append_text_appends_creates_its_folder_and_refuses_a_link(tmp_path):
    log = tmp_path / ".hdi" / "run.log"
    paths.append_text(log, "one\n")
    paths.append_text(log, "two\n", sync=True)
    assert log.read_text() == "one\ntwo\n"
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(log.stat().st_mode) == 0o666 & ~mask
    victim = tmp_path / "victim.txt"
    victim.write_text("a user's file")
    planted = tmp_path / "planted.log"
    planted.symlink_to(victim)
    with pytest.raises(paths.LinkRefused):           # O_NOFOLLOW: even outside a held folder
        paths.append_text(planted, "x")
    assert victim.read_text() == "a user's file"


def test_special_files_are_named_for_what_they_are(tmp_path):
    regular = tmp_path / "record.csv"
    regular.write_text("t,w\n")
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    sock_path = tmp_path / "s.sock"
    with socket.socket(socket.AF_UNIX) as sock:
        sock.bind(str(sock_path))
        assert paths.special_kind(sock_path) == "a socket"
    assert paths.special_kind(regular) is None
    assert paths.special_kind(tmp_path / "missing.csv") is None      # (the reader says "not found")
    assert paths.special_kind(fifo) == "a FIFO (named pipe)"
    assert paths.special_kind("/dev/null") == "a character device"
    assert paths.special_kind(tmp_path) == "a folder"
    (tmp_path / "to-fifo").symlink_to(fifo)                          # a link is followed to what it names
    assert paths.special_kind(tmp_path / "to-fifo") == "a FIFO (named pipe)"
