"""The results folder's lock (pipeline.folder_lock): a folder a live hdi process holds is refused in one line
naming its pid, by the runner and the command line, and its lock is taken over once the holder is gone; two
processes taking over a stale lock at once never both hold it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from pipeline import cli, folder_lock, runner
from pipeline.config.scene import load_scene

ROOT = Path(__file__).resolve().parents[2]


def test_second_process_on_a_folder_is_refused(tmp_path, paper_config, capsys):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / runner.LOCK_NAME).write_text(json.dumps({"pid": sleeper.pid, "host": os.uname().nodename,
                                                             "started": "2026-01-01T00:00:00+00:00"}))
        with pytest.raises(folder_lock.FolderBusy, match=rf"in use by hdi process {sleeper.pid}"):
            runner.build("dmw", load_scene(paper_config), tmp_path)
        assert cli.main(["dmw", str(paper_config), "--out", str(tmp_path)]) == 2
        assert f"in use by hdi process {sleeper.pid}" in capsys.readouterr().err
        assert not (tmp_path / "dmw.nc").exists()
    finally:
        sleeper.kill()
        sleeper.wait()
    # the holder is gone: its lock is stale and taken over
    runner.build("dmw", load_scene(paper_config), tmp_path)
    assert (tmp_path / "dmw.nc").is_file() and not (tmp_path / runner.LOCK_NAME).exists()


_CONTENDER = """
import sys, time
from pipeline import folder_lock as lock
alive = lock._alive
lock._alive = lambda pid: (time.sleep(0.5), alive(pid))[1]   # widen the check-and-take window
try:
    with lock.folder_lock(sys.argv[1]):
        print("HOLDS", flush=True)
        time.sleep(1.5)
except lock.FolderBusy:
    print("REFUSED", flush=True)
"""


def test_two_processes_taking_over_a_stale_lock_do_not_both_hold_it(tmp_path):
    """Two processes start on a folder whose lock a dead process left: exactly one takes it over and
    the other is refused (before, both could find it stale, and the second removed the first's)."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (tmp_path / runner.LOCK_NAME).write_text(json.dumps({"pid": dead.pid, "host": os.uname().nodename,
                                                         "started": "2026-01-01T00:00:00+00:00"}))
    procs = [subprocess.Popen([sys.executable, "-c", _CONTENDER, str(tmp_path)], cwd=ROOT, stdout=subprocess.PIPE,
                              text=True) for _ in range(2)]
    said = sorted(p.communicate(timeout=60)[0].strip() for p in procs)
    assert said == ["HOLDS", "REFUSED"]
    assert not (tmp_path / runner.LOCK_NAME).exists()


def test_a_folder_at_the_lock_path_is_one_line_saying_so(tmp_path, paper_config, capsys):
    (tmp_path / runner.LOCK_NAME).mkdir()
    assert cli.main(["dmw", str(paper_config), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"hdi dmw: error: {tmp_path / runner.LOCK_NAME}: is a folder where hdi keeps the results folder's "
                   "lock file; remove or rename it (nothing else of hdi's is kept there)")   # ("4: Is a directory")
    assert (tmp_path / runner.LOCK_NAME).is_dir() and not (tmp_path / "dmw.nc").exists()


def test_a_full_disk_writing_the_lock_leaves_no_empty_lock(tmp_path, paper_config, capsys, monkeypatch):
    import errno

    def full(obj, fh):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(folder_lock.json, "dump", full)
    assert cli.main(["dmw", str(paper_config), "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err.strip() == (
        f"hdi dmw: error: {tmp_path / runner.LOCK_NAME}: No space left on device (writing the results folder's lock "
        "file); the disk is full: free some space or choose another --out")
    assert list(tmp_path.iterdir()) == []                  # (an empty lock, taken over with a warning, before)
