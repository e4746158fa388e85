"""Nothing lost, nothing silent: each test is one probe of a user's files and the one line it must give.

Relative paths inherited through ``scene.extends``, the leftover cleaner and a user's files, OSError
(a full disk, wrong file types, names too long) as one line, and inputs that were silent or unbounded.
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import tracemalloc
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from pipeline import cli, file_errors, folder_lock, io, runner, sizing
from pipeline.analyses import narrative
from pipeline.model import measured_dmw
from pipeline.physics.microwaviness import DMWError
from pipeline.stages import report
from pipeline.cli_checks import OptionError, check_readme
from pipeline.config.grid import roughness_sets
from pipeline.config.scene import MAX_EXTENDS_DEPTH, SceneError, load_scene
from pipeline.io import is_temporary, temporary_path, temporary_prefix

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"


def _one_line_error(capsys, stage: str = "dmw") -> str:
    """The error line of ``hdi STAGE`` on stderr, asserted to be its only error and its last line, after
    progress lines only (no traceback)."""
    err = capsys.readouterr().err.strip().splitlines()
    errors = [ln for ln in err if "error" in ln.lower() or "Traceback" in ln or ln.startswith(" ")]
    assert len(errors) == 1 and err[-1] == errors[0] and errors[0].startswith(f"hdi {stage}: error: "), err
    return errors[0]


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


# ------------------------------------------------------------------- 6. OSError and others as one line
def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture
def dmw_out(tmp_path):
    """A results folder holding the paper scene's ``dmw.nc``, and the argv of a run that must rewrite it."""
    out = tmp_path / "out"
    assert cli.main(["dmw", str(PAPER), "--out", str(out)]) == 0
    return out, ["dmw", str(PAPER), "--out", str(out), "--set", "dmw.seed=7"]


def _half_write_then(exc_of):
    """A stand-in for the NetCDF writer that writes some bytes to the temporary file, then fails."""
    def write(ds, path, encoding):
        Path(path).write_bytes(b"\x89HDF half written")
        raise exc_of(path)
    return write


def test_a_full_disk_is_one_line_naming_the_dataset_and_nothing_is_half_written(dmw_out, monkeypatch, capsys):
    out, argv = dmw_out
    before = _tree(out)
    capsys.readouterr()
    monkeypatch.setattr(io, "_to_netcdf", _half_write_then(
        lambda tmp: OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), tmp)))
    assert cli.main(argv) == 2
    line = _one_line_error(capsys)
    assert line == (f"hdi dmw: error: {out / 'dmw.nc'}: {os.strerror(errno.ENOSPC)}; the disk is full: free some "
                    "space or choose another --out")
    assert _tree(out) == before                   # the previous dataset kept, no temporary left


def test_the_hdf_error_of_a_full_disk_is_put_down_to_the_free_space(dmw_out, monkeypatch, capsys):
    """netCDF4 reports a full disk as RuntimeError("NetCDF: HDF error"), without an errno."""
    out, argv = dmw_out
    before = _tree(out)
    capsys.readouterr()
    monkeypatch.setattr(io, "_to_netcdf", _half_write_then(lambda tmp: RuntimeError("NetCDF: HDF error")))
    monkeypatch.setattr(file_errors.shutil, "disk_usage", lambda path: shutil._ntuple_diskusage(4_000_000, 4_000_000, 5_000))
    assert cli.main(argv) == 2
    line = _one_line_error(capsys)
    assert line.startswith(f"hdi dmw: error: {out / 'dmw.nc'}: {os.strerror(errno.ENOSPC)} (0.005 MB free, the "
                           "dataset needs about ")
    assert _tree(out) == before


_SMALL_FILES = """
import resource, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)      # (then a write beyond the limit fails with EFBIG)
resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))
from pipeline import cli
sys.exit(cli.main(sys.argv[1:]))
"""


def test_a_write_the_file_system_refuses_inside_hdf5_is_one_line(tmp_path):
    """No fault injected: HDF5 itself fails to write (the file size limit, ``ulimit -f``, stands in for
    a small file system, which a test cannot mount)."""
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-c", _SMALL_FILES, "dmw", str(PAPER), "--out", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2, done.stderr
    err = [ln for ln in done.stderr.splitlines() if "error" in ln.lower() or "Traceback" in ln]
    assert len(err) == 1 and err[0].startswith(f"hdi dmw: error: {out / 'dmw.nc'}: {os.strerror(errno.EFBIG)} "
                                               "(the file size limit is 0.02 MB, the dataset needs about ")
    assert err[0].endswith(" MB); the file size limit (ulimit -f) is too small: raise it")
    assert sorted(p.name for p in out.iterdir()) == []


def test_a_number_that_overflows_is_refused_at_load(tmp_path, capsys):
    assert cli.main(["simulate", str(PAPER), "--set", "solver.duration_ms=1e308", "--out", str(tmp_path)]) == 2
    assert "expected a number of magnitude at most 1e+100" in _one_line_error(capsys, "simulate")
    assert cli.main(["simulate", str(PAPER), "--set", "solver.output_step_ns=1e-320", "--out", str(tmp_path)]) == 2
    assert "history samples per run" in _one_line_error(capsys, "simulate")        # (a size beyond its limit)
    with pytest.raises(SceneError, match=r"dmw\.seed: an integer of about 20 digits; expected an integer of magnitude "
                                         r"at most 2\*\*63 - 1"):
        load_scene(PAPER, ["dmw.seed=9223372036854775808"])


@pytest.mark.parametrize("garbage", ["[1,2]", '{"pid": 1000000000000000000000000000000}', '"x"', '{"pid": true}'])
def test_a_lock_file_no_hdi_process_wrote_is_taken_over(tmp_path, garbage):
    (tmp_path / runner.LOCK_NAME).write_text(garbage)
    with folder_lock.folder_lock(tmp_path) as path:
        assert json.loads(path.read_text())["pid"] == os.getpid()


def test_a_dataset_path_that_is_a_folder_is_one_line_before_computing(tmp_path, capsys):
    (tmp_path / "dmw.nc").mkdir()
    assert cli.main(["dmw", str(PAPER), "--out", str(tmp_path)]) == 2
    assert _one_line_error(capsys) == (f"hdi dmw: error: {tmp_path / 'dmw.nc'}: {os.strerror(errno.EISDIR)}; it is "
                                       "a folder where hdi writes a file: remove or rename it")
    assert not any(p.name.startswith(".") and p.name != runner.LOCK_NAME for p in tmp_path.iterdir())


def test_an_output_folder_that_is_a_file_is_one_line_before_computing(tmp_path, capsys):
    (tmp_path / "figures").write_text("mine")
    computed = []
    stage = runner.Stage("figs", lambda scene, inputs: computed.append(1), outputs=("figures/a.png",))
    with pytest.raises(FileExistsError) as info:
        runner.Runner(load_scene(PAPER), tmp_path, {"figs": stage}).build(["figs"])
    assert file_errors.os_error_line(info.value) == (f"{tmp_path / 'figures'}: is a file, not a folder; it is a file where "
                                            "hdi needs a folder: remove or rename it")
    assert computed == [] and (tmp_path / "figures").read_text() == "mine"


def test_readme_a_folder_is_one_line_before_anything_runs(tmp_path, capsys):
    (tmp_path / "README.md").mkdir()
    out = tmp_path / "out"
    assert cli.main(["report", str(PAPER), "--readme", str(tmp_path / "README.md"), "--out", str(out)]) == 2
    assert ("README.md: is a folder; expected the page whose generated section the report rewrites "
            "(e.g. docs/results.md)") in _one_line_error(capsys, "report")
    assert not out.exists()


def test_an_out_name_beyond_the_file_systems_limit_is_one_line(tmp_path, capsys):
    out = tmp_path / ("r" * 300) / "x"
    assert cli.main(["dmw", str(PAPER), "--out", str(out)]) == 2
    assert "is 300 bytes, longer than the 255 bytes its file system allows" in _one_line_error(capsys)


# ------------------------------------------------------------------------- 7. silent or unbounded
FLY = ['scene.effects=["air_bearing","pitch","dmw"]', "solver.duration_ms=0.6", "solver.transient_ms=0.2",
       "sweep.protrusion_nm={start=2.0, stop=2.4, step=0.2}", "sweep.batch_size=3"]


def _sets(overrides: list[str]) -> list[str]:
    return [a for s in overrides for a in ("--set", s)]


def test_a_record_longer_than_the_limit_is_one_line_before_it_is_read_and_yes_lifts_it(tmp_path, monkeypatch, capsys):
    rec = _record(tmp_path / "rec.csv", n=12_000, rate_hz=4e6)
    monkeypatch.setattr(sizing, "MAX_RECORD_SAMPLES", 10_000)   # (10 million rows are not written in a test)
    argv = ["dmw", str(PAPER), "--set", f"dmw.source={json.dumps(str(rec))}", "--out", str(tmp_path / "out")]
    assert cli.main(argv) == 2
    line = _one_line_error(capsys)
    assert f"12,001 samples of the measured DMW record (lines of dmw.source = {rec}) exceed 10,000; pass --yes" in line
    assert not (tmp_path / "out" / "dmw.nc").exists()
    assert cli.main(argv + ["--yes"]) == 0 and (tmp_path / "out" / "dmw.nc").is_file()


def test_a_long_record_is_read_without_a_python_object_per_cell(tmp_path):
    """The reader keeps two float arrays, not the rows of strings (600 bytes a sample: 6 GB for 10 million)."""
    rec = _record(tmp_path / "rec.csv", n=200_000)
    tracemalloc.start()
    try:
        r = measured_dmw.load_record(rec)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert r.values.size == 200_000
    assert peak < 100 * r.values.size, f"{peak / r.values.size:.0f} bytes a sample"


def test_a_csv_row_with_an_extra_column_is_refused_naming_file_line_and_columns(tmp_path):
    rec = _record(tmp_path / "rec.csv", n=10)
    lines = rec.read_text().splitlines()
    lines[5] += ",7.5"
    rec.write_text("\n".join(lines) + "\n")
    with pytest.raises(DMWError, match=rf"^{re.escape(str(rec))}: line 6: 3 columns; expected 2 \(time \[s\], "
                                       r"displacement \[nm\]\) as in the first row$"):
        measured_dmw.load_record(rec)


def test_a_byte_order_mark_before_the_header_does_not_hide_the_time_column(tmp_path):
    rec = _record(tmp_path / "rec.csv", n=20)
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + rec.read_bytes())
    a, b = measured_dmw.load_record(rec), measured_dmw.load_record(bom)
    assert b.sample_rate_hz == a.sample_rate_hz == 4e6 and np.array_equal(a.values, b.values)


def test_a_run_too_short_for_a_steady_window_is_refused(tmp_path, capsys):
    assert cli.main(["simulate", str(PAPER), "--set", "solver.duration_ms=1e-6", "--set", "solver.transient_ms=0",
                     "--out", str(tmp_path)]) == 2
    assert "leaves a steady window of 0.004 samples" in _one_line_error(capsys, "simulate")


def test_a_repeated_damping_ratio_is_refused_at_load():
    with pytest.raises(SceneError, match=r"sweep\.damping_ratio = \[0\.05, 0\.02, 0\.05\]: 0\.05 appears more "
                                         r"than once"):
        load_scene(PAPER, ["sweep.damping_ratio=[0.05, 0.02, 0.05]"])


def test_histories_off_the_grid_are_refused_naming_the_nearest_grid_points(tmp_path, capsys):
    assert cli.main(["sweep", str(PAPER), "--set", "sweep.histories_nm=[5.0, 7.05]", "--out", str(tmp_path)]) == 2
    assert _one_line_error(capsys, "sweep").endswith(
        "sweep.histories_nm: 7.05 nm is not on the sweep grid (sweep.protrusion_nm: 0 to 15 nm in steps of 0.2); "
        "the nearest grid points are 7 and 7.2 nm")


def test_a_bad_roughness_set_is_refused_before_any_stage_runs(tmp_path, capsys):
    assert cli.main(["sweep", str(PAPER), "--set", 'sweep.roughness=[{label="a", sigma_nm=-1}]',
                     "--out", str(tmp_path)]) == 2
    assert "sweep.roughness.sigma_nm (set 'a') = -1: expected a number in (0, 1000] nm" in _one_line_error(capsys, "sweep")
    assert not (tmp_path / "dmw.nc").exists()


@pytest.fixture
def readme_report(tmp_path):
    """A results folder with a report and a figure, and a page holding the generated-section markers
    (where ``make readme`` writes: docs/results.md)."""
    out = tmp_path / "out"
    (out / "report").mkdir(parents=True)
    (out / "report" / "comparison.md").write_text("the comparison\n")
    (out / "figures").mkdir()
    (out / "figures" / narrative.README_FIGURES[0]).write_bytes(b"png")
    readme = tmp_path / "docs-repo" / "docs" / "results.md"
    readme.parent.mkdir(parents=True)
    readme.write_text(f"# README\n{narrative.README_BEGIN}\nold\n{narrative.README_END}\nend\n")
    return out, readme


def test_readme_a_symlink_is_written_through_and_stays_a_link(tmp_path, readme_report):
    out, readme = readme_report
    link = tmp_path / "results.md"
    link.symlink_to(readme)
    report._finish(load_scene(PAPER), out, {"readme": link})
    assert link.is_symlink() and link.resolve() == readme
    assert "the comparison" in readme.read_text()


def test_readme_copies_the_figures_to_the_figures_folder_beside_the_page(tmp_path, readme_report):
    out, page = readme_report  # docs/results.md: its image links, and the README's, name docs/figures/
    report._finish(load_scene(PAPER), out, {"readme": page})
    assert (page.parent / "figures" / narrative.README_FIGURES[0]).read_bytes() == b"png"
    assert not (page.parent / "docs").exists()


def test_a_read_only_readme_is_refused_and_left_untouched(tmp_path, readme_report, capsys):
    out, readme = readme_report
    readme.chmod(0o444)
    before = readme.read_bytes()
    with pytest.raises(OptionError, match=r"results\.md: is read-only; make it writable"):
        check_readme(readme)
    with pytest.raises(PermissionError):
        report._finish(load_scene(PAPER), out, {"readme": readme})
    assert readme.read_bytes() == before and readme.stat().st_mode & 0o777 == 0o444


def test_the_readmes_xarray_example_runs_on_what_make_run_writes(tmp_path, monkeypatch):
    scene_file = re.search(r"^SCENE\s*\?=\s*(\S+)", (ROOT / "Makefile").read_text(), re.M).group(1)
    name = load_scene(ROOT / scene_file).name                          # the folder `make run` writes
    block = re.search(r"Post-analysis is plain xarray:\n\n```python\n(.*?)```", (ROOT / "README.md").read_text(),
                      re.S).group(1)
    assert f'"results/{name}/sweep.nc"' in block
    assert cli.main(["sweep", str(PAPER), "--out", str(tmp_path / "results" / name), *_sets(FLY)]) == 0
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {})
    plt.close("all")
