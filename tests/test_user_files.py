"""Nothing lost, nothing silent (issue 28, items 4-7): each test reproduces one probe that failed before.

Relative paths inherited through ``scene.extends``, the leftover cleaner and a user's files, OSError
(a full disk, wrong file types, names too long) as one line, and inputs that were silent or unbounded.
"""

from __future__ import annotations

import json
import os
import socket
import tempfile
from pathlib import Path

import pytest

from pipeline import cli, runner
from pipeline.config.grid import roughness_sets
from pipeline.config.scene import MAX_EXTENDS_DEPTH, SceneError, load_scene
from pipeline.io import is_temporary, temporary_path, temporary_prefix

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "configs" / "paper-2009.toml"


def _one_line_error(capsys, stage: str = "dmw") -> str:
    """The command's stderr, asserted to be exactly one error line of ``hdi STAGE``."""
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"hdi {stage}: error: "), err
    return err[0]


def _record(path: Path, n: int = 50, rate_hz: float = 4e6) -> Path:
    """A small DMW record (time [s], displacement [nm]) of ``n`` samples."""
    rows = "".join(f"{i / rate_hz!r},{0.1 * ((i * 7) % 5 - 2)!r}\n" for i in range(n))
    path.write_text("time [s],displacement [nm]\n" + rows)
    return path


# ---------------------------------------------------------------- 4. paths inherited through extends
@pytest.fixture
def two_folders(tmp_path):
    """``base/`` holding a base scene and its files, ``derived/`` holding files of the same names."""
    base, derived = tmp_path / "base", tmp_path / "derived"
    base.mkdir()
    derived.mkdir()
    for folder in (base, derived):
        _record(folder / "rec.csv")
        (folder / "scan.txt").write_text("0 1\n1 0\n")
    return base, derived


def test_a_base_scenes_relative_files_are_its_own_not_the_derived_scenes(two_folders):
    base, derived = two_folders
    (base / "base.toml").write_text('[scene]\nname = "b"\n[dmw]\nsource = "rec.csv"\n[roughness]\nafm = ["scan.txt"]\n'
                                    '[sweep]\nroughness = [{label = "afm", afm = ["scan.txt"]}]\n')
    (derived / "d.toml").write_text('[scene]\nname = "d"\nextends = "../base/base.toml"\n')
    scene = load_scene(derived / "d.toml")
    assert scene["dmw"]["source"] == str((base / "rec.csv").resolve())
    assert scene["roughness"]["afm"] == [str((base / "scan.txt").resolve())]
    assert roughness_sets(scene)["afm"]["afm"] == [str((base / "scan.txt").resolve())]


def test_the_derived_scenes_own_relative_files_are_still_beside_it(two_folders):
    base, derived = two_folders
    (base / "base.toml").write_text('[scene]\nname = "b"\n[dmw]\nsource = "rec.csv"\n')
    (derived / "d.toml").write_text('[scene]\nname = "d"\nextends = "../base/base.toml"\n'
                                    '[dmw]\nsource = "rec.csv"\n')
    assert load_scene(derived / "d.toml")["dmw"]["source"] == str((derived / "rec.csv").resolve())


def test_a_base_file_missing_in_its_folder_is_not_found_beside_the_derived_scene(two_folders):
    base, derived = two_folders
    (base / "rec.csv").unlink()
    (base / "base.toml").write_text('[scene]\nname = "b"\n[dmw]\nsource = "rec.csv"\n')
    (derived / "d.toml").write_text('[scene]\nname = "d"\nextends = "../base/base.toml"\n')
    with pytest.raises(SceneError, match="does not exist") as info:
        load_scene(derived / "d.toml")
    assert str(base / "rec.csv") in str(info.value)


def test_a_base_whose_scene_is_not_a_table_is_one_line_naming_the_base(tmp_path, capsys):
    (tmp_path / "base.toml").write_text("scene = 3\n")
    (tmp_path / "d.toml").write_text('[scene]\nextends = "base.toml"\n')
    assert cli.main(["dmw", str(tmp_path / "d.toml"), "--out", str(tmp_path / "out")]) == 2
    line = _one_line_error(capsys)
    assert f"{tmp_path / 'base.toml'}: scene must be a table" in line


def test_a_chain_of_1200_extends_is_one_line_not_a_recursion_error(tmp_path, capsys):
    (tmp_path / "s0.toml").write_text('[scene]\nname = "s"\n')
    for i in range(1, 1200):
        (tmp_path / f"s{i}.toml").write_text(f'[scene]\nextends = "s{i - 1}.toml"\n')
    assert cli.main(["dmw", str(tmp_path / "s1199.toml"), "--out", str(tmp_path / "out")]) == 2
    assert f"more than {MAX_EXTENDS_DEPTH} scenes extending one another" in _one_line_error(capsys)
    assert load_scene(tmp_path / f"s{MAX_EXTENDS_DEPTH - 1}.toml")["scene"]["extends"]  # (the longest chain)
    with pytest.raises(SceneError, match="a chain of more than"):
        load_scene(tmp_path / f"s{MAX_EXTENDS_DEPTH}.toml")


def test_a_cycle_of_extends_is_one_line(tmp_path):
    (tmp_path / "a.toml").write_text('[scene]\nextends = "b.toml"\n')
    (tmp_path / "b.toml").write_text('[scene]\nextends = "c.toml"\n')
    (tmp_path / "c.toml").write_text('[scene]\nextends = "a.toml"\n')
    with pytest.raises(SceneError, match="circular extension"):
        load_scene(tmp_path / "a.toml")


# ------------------------------------------------------------- 5. the cleaner and files hdi did not make
def test_the_cleaner_leaves_a_users_tmp_files_alone(tmp_path):
    mine = [tmp_path / ".notes.tmp", tmp_path / "figures" / ".draft.png.tmp", tmp_path / ".sweep.nc.k2j3h4.tmp"]
    for p in mine:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text("mine")
    ours = tmp_path / "figures" / f".fig6_fhm.png.hdi-{'0' * 12}.tmp"   # (hdi's name, of a killed run)
    ours.write_bytes(b"half written")
    runner.build("dmw", load_scene(PAPER), tmp_path)
    assert all(p.read_text() == "mine" for p in mine)
    assert not ours.exists()


def test_the_cleaner_does_not_reach_into_another_runs_locked_folder(tmp_path):
    other = tmp_path / "paper"                                   # another run works in results/paper ...
    (other / "sweep.parts").mkdir(parents=True)
    (other / runner.LOCK_NAME).write_text(json.dumps({"pid": os.getpid(), "host": socket.gethostname()}))
    its = [other / f".dmw.nc.hdi-{'a' * 12}.x1y2.tmp", other / "sweep.parts" / f".batch-00001.nc.hdi-{'a' * 12}.z.tmp"]
    for p in its:
        p.write_bytes(b"being written")
    runner.build("dmw", load_scene(PAPER), tmp_path)             # ... while this one has --out results/
    assert all(p.read_bytes() == b"being written" for p in its)


def test_every_temporary_name_hdi_writes_is_recognised_as_its_own(tmp_path):
    assert is_temporary(temporary_path(tmp_path / "sweep.nc").name)
    fd, name = tempfile.mkstemp(prefix=temporary_prefix(tmp_path / "sweep.nc"), suffix=".tmp", dir=tmp_path)
    os.close(fd)
    assert is_temporary(Path(name).name)
    assert not any(is_temporary(n) for n in (".notes.tmp", ".sweep.nc.k2j3h4.tmp", "sweep.nc.hdi-0123456789ab.tmp"))
