"""Bad input on the command line: one clear line, exit 2, nothing written or lost (pipeline.cli_checks),
and warnings with the numbers for derived material parameters outside physical bounds."""

from __future__ import annotations

import math
import os
import socket
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest

from pipeline import cli
from pipeline.config.scene import SceneError, load_scene
from pipeline.cli_checks import MAX_SCENES, check_grid, check_out, grid_size
from pipeline.cluster import CONNECT_TIMEOUT_S

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"


@pytest.fixture()
def folder(tmp_path):
    """An output folder holding an earlier result that no failed command may touch."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.nc").write_bytes(b"earlier result")
    return out


def _fails(capsys, folder: Path, *argv: str) -> str:
    """Run ``hdi ARGV --out FOLDER``: exit 2, one line on stderr, the folder unchanged. Returns the line."""
    code = cli.main([*argv, "--out", str(folder)] if folder is not None else list(argv))
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    if folder is not None:
        assert sorted(p.name for p in folder.iterdir()) == ["sweep.nc"]
        assert (folder / "sweep.nc").read_bytes() == b"earlier result"
    return err


def test_workers_negative(capsys, folder):
    err = _fails(capsys, folder, "sweep", str(PAPER), "--workers", "-1")
    assert "--workers -1" in err and "positive" in err


def test_workers_zero(capsys, folder):
    err = _fails(capsys, folder, "sweep", str(PAPER), "--workers", "0")
    assert "--workers 0" in err


def test_unreachable_scheduler_fails_fast_with_one_line(capsys, folder):
    with socket.socket() as s:  # a free port nobody listens on once closed
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    err = _fails(capsys, folder, "sweep", str(PAPER), "--scheduler", f"tcp://127.0.0.1:{port}")
    assert f"127.0.0.1:{port}" in err and f"{CONNECT_TIMEOUT_S:g} s connect timeout" in err
    err = _fails(capsys, folder, "sweep", str(PAPER), "--scheduler", "http://127.0.0.1:8786")
    assert "tcp://HOST:PORT" in err


def test_local_schedulers_are_not_addresses():
    """`--scheduler threads|processes|synchronous` name the local fan-outs (pipeline.fanout): accepted
    without a connection attempt (it would fail: no host); anything else must be tcp://HOST:PORT."""
    from pipeline.cli_checks import OptionError, check_scheduler
    for name in ("threads", "processes", "synchronous", None):
        assert check_scheduler(name, timeout=0.01) == name
    with pytest.raises(OptionError, match="tcp://HOST:PORT"):
        check_scheduler("thread", timeout=0.01)


def _free_address() -> str:
    with socket.socket() as s:  # a free port nobody listens on once closed
        s.bind(("127.0.0.1", 0))
        return f"tcp://127.0.0.1:{s.getsockname()[1]}"


def test_a_scheduler_file_is_read_for_its_address_and_a_bad_one_is_one_line(capsys, folder, tmp_path):
    # --scheduler takes a scheduler file as well as a tcp:// address (dask users hand over `dask scheduler --scheduler-file`)
    from pipeline.scheduler import scheduler_address
    good = tmp_path / "scheduler.json"
    good.write_text('{"type": "Scheduler", "address": "tcp://10.1.2.3:8786", "services": {"dashboard": 8787}}')
    assert scheduler_address(str(good)) == ("tcp://10.1.2.3:8786", f"--scheduler {good} (address tcp://10.1.2.3:8786)")
    address = _free_address()
    good.write_text(f'{{"address": "{address}"}}')
    err = _fails(capsys, folder, "sweep", str(PAPER), "--scheduler", str(good))
    assert err.startswith(f"hdi sweep: error: --scheduler {good} (address {address}): no scheduler answers at ")
    for text, expected in (("not json", "not a dask scheduler file (Expecting value: line 1 column 1 (char 0)); "
                                        "expected the JSON file `dask scheduler --scheduler-file FILE` writes"),
                           ('{"id": "Scheduler-1"}', 'field "address": expected the scheduler\'s address '
                                                    "(tcp://HOST:PORT), got None")):
        good.write_text(text)
        err = _fails(capsys, folder, "sweep", str(PAPER), "--scheduler", str(good))
        assert err == f"hdi sweep: error: --scheduler {good}: {expected}"
    err = _fails(capsys, folder, "sweep", str(PAPER), "--scheduler", str(tmp_path / "none.json"))
    assert err == (f"hdi sweep: error: --scheduler {tmp_path / 'none.json'}: no such scheduler file (expected "
                   "tcp://HOST:PORT, or the JSON file `dask scheduler --scheduler-file FILE` writes)")


def test_dask_scheduler_address_is_the_scheduler_when_none_is_given(capsys, folder, monkeypatch):
    from pipeline.cli_checks import check_scheduler
    address = _free_address()
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", address)
    err = _fails(capsys, folder, "sweep", str(PAPER))
    assert err.startswith(f"hdi sweep: error: DASK_SCHEDULER_ADDRESS={address}: no scheduler answers at ")
    assert err.endswith("or unset DASK_SCHEDULER_ADDRESS (or give --scheduler threads) to run locally")
    assert check_scheduler("threads") == "threads"  # --scheduler comes first
    from pipeline.cli_checks import check_options
    assert check_options("dmw", load_scene(PAPER)) is None  # a stage without a fan-out does not connect
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", " ")
    assert check_scheduler(None) is None  # (blank: unset)


def test_out_is_a_file(capsys, folder):
    err = _fails(capsys, None, "dmw", str(PAPER), "--out", str(folder / "sweep.nc"))
    assert "is a file" in err
    err = _fails(capsys, None, "dmw", str(PAPER), "--out", str(folder / "sweep.nc" / "sub"))
    assert "is a file" in err and "cannot be created" in err
    assert (folder / "sweep.nc").read_bytes() == b"earlier result"


def test_out_read_only(capsys, folder):
    # a folder no process may create files in, root included
    err = _fails(capsys, None, "dmw", str(PAPER), "--out", "/proc/hdi-results")
    assert "not writable" in err and "/proc" in err
    # a folder without write permission: refused exactly when writing there really fails (root may write)
    ro = folder.parent / "read-only"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        try:
            fd, probe = tempfile.mkstemp(dir=ro)
            os.close(fd)
            os.unlink(probe)
            writable = True
        except OSError:
            writable = False
        if writable:
            check_out(ro)  # no error where writing works
        else:
            err = _fails(capsys, None, "dmw", str(PAPER), "--out", str(ro))
            assert "not writable" in err
    finally:
        ro.chmod(0o755)


def test_stop_inf_in_the_scene_file(capsys, folder, write_scene):
    path = write_scene(f'[scene]\nextends = "{PAPER}"\n[sweep]\nprotrusion_nm = {{start = 0.0, stop = inf, step = 0.2}}\n')
    err = _fails(capsys, folder, "sweep", str(path))
    assert err.startswith(f"hdi sweep: error: {path}: sweep.protrusion_nm") and "finite" in err


def test_a_grid_of_millions_is_refused_unless_yes(capsys, folder):
    err = _fails(capsys, folder, "sweep", str(PAPER), "--set", "sweep.protrusion_nm={start=0, stop=100, step=5e-5}",
                 "--set", "sweep.damping_ratio=[0.03, 0.05]")
    assert "4,000,002 scenes (2,000,001 protrusions x 1 roughness sets x 2 damping ratios)" in err
    assert "--yes" in err
    scene = load_scene(PAPER, ["sweep.protrusion_nm={start=0, stop=100, step=5e-5}"])
    assert grid_size(scene) == (2_000_001, 1, 1)
    check_grid(scene, yes=True)  # allowed with --yes
    check_grid(load_scene(PAPER))  # the paper grid: 76 scenes
    assert math.prod(grid_size(load_scene(PAPER))) == 76 < MAX_SCENES


def test_nan_and_inf_inside_lists(capsys, folder, write_scene):
    path = write_scene(f'[scene]\nextends = "{PAPER}"\n[air_bearing]\nfrequencies_khz = [120.0, nan]\n')
    err = _fails(capsys, folder, "dmw", str(path))
    assert f"{path}: air_bearing.frequencies_khz" in err and "finite" in err
    with pytest.raises(SceneError, match=r"sweep.damping_ratio = \[0.05, inf\]: expected a list of finite"):
        load_scene(PAPER, ["sweep.damping_ratio=[0.05, inf]"])


def test_errors_from_set_name_the_set_option_not_the_file(capsys, folder):
    err = _fails(capsys, folder, "dmw", str(PAPER), "--set", "dmw.rms_nm=-1")
    assert err.startswith("hdi dmw: error: --set dmw.rms_nm=-1: dmw.rms_nm = -1") and "expected a number in [0, 1000] nm" in err
    assert str(PAPER) not in err
    err = _fails(capsys, folder, "dmw", str(PAPER), "--set", "dmw.rms_um=0.1")
    assert err.startswith("hdi dmw: error: --set dmw.rms_um=0.1: dmw.rms_um: wrong unit 'um'")


def test_an_option_the_stage_ignores_is_an_error(capsys, folder):
    err = _fails(capsys, folder, "sweep", str(PAPER), "--readme", "README.md")
    assert "--readme: not used by `hdi sweep`; only by report, run" in err
    err = _fails(capsys, folder, "interface", str(PAPER), "--workers", "2")
    assert "--workers: not used by `hdi interface`" in err
    err = _fails(capsys, folder, "dmw", str(PAPER), "--channel", "Height")
    assert "--set roughness.channel=" in err


def test_report_history_protrusion_off_the_grid(capsys, folder):
    err = _fails(capsys, folder, "report", str(PAPER), "--set", "report.histories_nm=[5.0, 11.1]")
    assert "report.histories_nm: 11.1 nm not on the sweep grid" in err and "steps of 0.2" in err
    err = _fails(capsys, folder, "report", str(PAPER), "--set", "report.histories_nm=[16.0]")
    assert "16 nm not on the sweep grid" in err
    # off the grid by less than the old 1e-6 nm tolerance but more than the sweep's 1e-9 nm match:
    # accepted before, then silently without a history
    err = _fails(capsys, folder, "report", str(PAPER), "--set", "report.histories_nm=[5.0000005, 11.0]")
    assert "report.histories_nm: 5.0000005 nm not on the sweep grid" in err


def test_verbose_shows_where_an_error_came_from(tmp_path, capsys):
    """An error is one line; with -v its traceback comes first (a ValueError raised by numerics would
    otherwise be indistinguishable from bad input)."""
    argv = ["interface", str(PAPER), "--out", str(tmp_path), "--set", "lubricant.thickness_nm=-1"]
    assert cli.main(argv) == 2
    quiet = capsys.readouterr().err.strip().splitlines()
    assert cli.main([*argv, "-v"]) == 2
    loud = capsys.readouterr().err.strip().splitlines()
    assert len(quiet) == 1 and "Traceback" not in quiet[0]
    assert loud[0].startswith("Traceback") and loud[-1] == quiet[0]


# ------------------------------------------------------------------ numbers, nesting, --set values, scans
BIG = "1" + "0" * 400


def _scene_file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "probe.toml"
    path.write_text(f'[scene]\nextends = "{PAPER}"\nname = "probe"\n' + text)
    return path


@pytest.mark.parametrize("text, expected", [
    (f"[tfc]\nprotrusion_nm = {BIG}\n", "tfc.protrusion_nm: an integer of about 401 digits"),  # (OverflowError)
    (f"[air_bearing]\nfrequencies_khz = [{BIG}, 300.0]\n", "air_bearing.frequencies_khz: an integer of about 401"),
    ("[tfc]\nprotrusion_nm = " + "[" * 3000 + "]" * 3000 + "\n", "not valid TOML: lists or tables nested too deep"),
    ("[air_bearing]\nflying_height_nm = 1e90\n", "air_bearing.flying_height_nm = 1e+90: expected a number in (0, 10000] nm"),
])
def test_a_scene_file_beyond_its_bounds_is_one_line(capsys, folder, tmp_path, text, expected):
    """Each was a traceback (OverflowError, RecursionError) or a run of an absurd scene with exit 0."""
    path = _scene_file(tmp_path, text)
    err = _fails(capsys, folder, "roughness", str(path))
    assert err.startswith(f"hdi roughness: error: {path}: ") and expected in err


@pytest.mark.parametrize("option, expected", [
    (f"tfc.protrusion_nm={BIG}", "tfc.protrusion_nm: an integer of about 401 digits"),
    ("tfc.protrusion_nm=" + "[" * 3000 + "]" * 3000, "lists or tables nested too deep for the TOML parser"),
    ("tfc.protrusion_nm=5\n[contact]\nk = 0.5", "the value holds more than one TOML value (a newline and 'contact')"),
    ("roughness.summit_density_per_um2=1e90", "expected a number in (0, 1e+06] um^-2"),
])
def test_a_set_beyond_its_bounds_is_one_line(capsys, folder, option, expected):
    err = _fails(capsys, folder, "roughness", str(PAPER), "--set", option)
    assert err.startswith("hdi roughness: error: --set ") and expected in err


def test_an_absurd_scan_is_one_line_and_writes_nothing(capsys, folder, tmp_path):
    """Heights of 1e80 nm ended in OverflowError; of 3e38 nm, all undefined, or over a lateral size of 1e-30 um
    they gave statistics and exit 0."""
    from SurfaceTopography import Topography
    x = np.arange(32) * 2 * np.pi / 32
    rough = np.cos(3 * x)[:, None] * np.cos(2 * x)[None, :]
    cases = {"huge.nc": (1e80 * rough, (256.0, 256.0), "nm", "heights reach 1e+80 nm"),
             "float32.nc": (3e38 * rough, (256.0, 256.0), "nm", "heights reach 3e+38 nm"),
             "undefined.nc": (np.full((32, 32), np.nan), (256.0, 256.0), "nm", "every height is undefined"),
             "tiny.nc": (rough, (1e-30, 1e-30), "um", "pixel size 3.125e-29 nm")}
    for name, (heights, size, unit, expected) in cases.items():
        path = tmp_path / name
        Topography(heights, size, periodic=True, unit=unit).to_netcdf(str(path))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            err = _fails(capsys, folder, "roughness", str(path))
        assert err.startswith(f"hdi roughness: error: {path}: channel 'Default': {expected}"), err
