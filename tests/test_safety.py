"""Nothing lost, nothing silent (issue 38, the file-system and process half): each test reproduces one probe.

1. planted symbolic links inside a results folder (the lock, ``figures/``, ``.hdi/``, its run log, a
   dataset): refused in one line naming the link, the link's target untouched;
2. a signal caught and lost inside a C library's error check: never an exit 0;
3. forked figure workers outliving a killed ``hdi``;
4. special files (a FIFO, ``/dev/zero``) as inputs, and file contents echoed in messages;
5. a dataset another process holds open for writing: busy, never replaced;
6. a results folder or scene name too long for the file system: one line before any stage runs.
"""

from __future__ import annotations

import errno
import json
import os
import sys
from pathlib import Path

import pytest
import xarray as xr

from pipeline import cli, io, runner
from pipeline.config.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "configs" / "paper-2009.toml"


def _toy(tmp_path: Path) -> tuple:
    """A victim file outside the results folder and the results folder."""
    victim = tmp_path / "victim.txt"
    victim.write_text("a user's file")
    out = tmp_path / "out"
    out.mkdir()
    return victim, out


def _dataset() -> xr.Dataset:
    return xr.Dataset({"x": ("n", [1.0, 2.0], {"units": "1", "long_name": "x"})},
                      coords={"n": ("n", [0, 1], {"units": "1", "long_name": "n"})})


def _link_line(exc: OSError, link: Path) -> str:
    line = io.os_error_line(exc)
    assert "\n" not in line and line.startswith(f"{link}: is a symbolic link (to ")
    assert line.endswith("hdi writes, locks and deletes no file through a link inside its results folder: "
                         "remove the link")
    return line


# ------------------------------------------------------------------------------------ 1. planted links
def test_a_lock_file_that_is_a_link_is_refused_and_its_target_kept(tmp_path):
    """Before: hdi "took over the lock" and unlinked the link's target."""
    victim, out = _toy(tmp_path)
    (out / runner.LOCK_NAME).symlink_to(victim)
    with pytest.raises(io.LinkRefused) as info:
        with runner.folder_lock(out):
            pass
    _link_line(info.value, out.resolve() / runner.LOCK_NAME)
    assert victim.read_text() == "a user's file" and (out / runner.LOCK_NAME).is_symlink()


def test_a_dangling_lock_link_is_refused_and_nothing_is_created(tmp_path):
    _, out = _toy(tmp_path)
    (out / runner.LOCK_NAME).symlink_to(tmp_path / "not-there")
    with pytest.raises(io.LinkRefused):
        with runner.folder_lock(out):
            pass
    assert not (tmp_path / "not-there").exists()


def test_the_cli_refuses_a_planted_lock_link_in_one_line(tmp_path, capsys):
    victim, out = _toy(tmp_path)
    (out / runner.LOCK_NAME).symlink_to(victim)
    assert cli.main(["dmw", str(PAPER), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"hdi dmw: error: {out.resolve() / runner.LOCK_NAME}: is a symbolic link")
    assert victim.read_text() == "a user's file" and sorted(p.name for p in out.iterdir()) == [runner.LOCK_NAME]


def _stage_writing(name: str, out_name: str, metrics: bool = False) -> runner.Stage:
    def compute(scene, inputs):
        if metrics:
            inputs.record(seconds=1.0)
        if out_name.endswith(".nc"):
            return {out_name: _dataset()}
        (inputs.staging / out_name).parent.mkdir(parents=True, exist_ok=True)
        (inputs.staging / out_name).write_text("drawn")
        return {}
    return runner.Stage(name, compute, outputs=(out_name,))


@pytest.mark.parametrize("planted, output, metrics", [
    ("figures", "figures/a.png", False),            # a folder of outputs
    (".hdi", "figures/a.png", False),                # the runner's records (manifests)
    (".hdi/runs.jsonl", "a.nc", True),               # the run log
    (".hdi/toy.json", "figures/a.png", False),       # a manifest
    ("a.nc", "a.nc", False),                         # a dataset
])
def test_a_planted_link_on_the_way_to_an_output_is_refused_before_computing(tmp_path, planted, output, metrics):
    """Before: PNGs, records and run lines were written through the link, outside the folder."""
    victim, out = _toy(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    link = out / planted
    link.parent.mkdir(parents=True, exist_ok=True)
    link.symlink_to(victim if "." in Path(planted).name and planted != ".hdi" else elsewhere)
    computed = []
    stage = _stage_writing("toy", output, metrics)
    stage = runner.Stage("toy", lambda s, i: (computed.append(1), stage.compute(s, i))[1], outputs=stage.outputs)
    with pytest.raises(io.LinkRefused) as info:
        runner.Runner(load_scene(PAPER), out, {"toy": stage}).build(["toy"])
    _link_line(info.value, link)
    assert computed == []
    assert victim.read_text() == "a user's file" and list(elsewhere.iterdir()) == []
    assert link.is_symlink() and not (out / runner.LOCK_NAME).exists()


def test_a_link_planted_while_the_stage_computes_is_refused_at_the_write(tmp_path):
    victim, out = _toy(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()

    def compute(scene, inputs):
        (out / "figures").symlink_to(elsewhere)      # another user, while the stage runs
        (inputs.staging / "figures").mkdir()
        (inputs.staging / "figures" / "a.png").write_text("drawn")
        return {}
    stage = runner.Stage("toy", compute, outputs=("figures/a.png",))
    with pytest.raises(io.LinkRefused):
        runner.Runner(load_scene(PAPER), out, {"toy": stage}).build(["toy"])
    assert list(elsewhere.iterdir()) == []


def test_write_dataset_and_the_run_log_refuse_links_below_a_held_folder(tmp_path):
    victim, out = _toy(tmp_path)
    (out / "d.nc").symlink_to(victim)
    (out / ".hdi").mkdir()
    (out / ".hdi" / runner.RUN_LOG).symlink_to(victim)
    with runner.folder_lock(out):
        with pytest.raises(io.LinkRefused):
            io.write_dataset(_dataset(), out / "d.nc", stage="test")
        with pytest.raises(io.LinkRefused):
            io.append_text(out / ".hdi" / runner.RUN_LOG, "{}\n")
    assert victim.read_text() == "a user's file"
    io.write_dataset(_dataset(), tmp_path / "free.nc", stage="test")   # (outside a held folder: no check)


def test_the_cleaner_removes_no_link_named_like_a_temporary_file(tmp_path):
    victim, out = _toy(tmp_path)
    link = out / f".sweep.nc.hdi-{'0' * 12}.tmp"
    link.symlink_to(victim)
    staging = out / (runner.STAGING_PREFIX + "x")
    staging.symlink_to(tmp_path)
    with runner.folder_lock(out):
        pass
    assert link.is_symlink() and staging.is_symlink() and victim.read_text() == "a user's file"


def test_a_fifo_at_the_lock_name_is_refused_without_blocking(tmp_path):
    _, out = _toy(tmp_path)
    os.mkfifo(out / runner.LOCK_NAME)
    with pytest.raises(OSError) as info:
        with runner.folder_lock(out):
            pass
    assert io.os_error_line(info.value) == (f"{out.resolve() / runner.LOCK_NAME}: is a FIFO (named pipe), not hdi's "
                                            "lock file; remove it")
