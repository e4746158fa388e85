"""Every script of docs/examples/ runs from a clean temporary folder, writes only into it, and gives
plausible numbers (each is a subprocess: the way a user runs it)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def run_example(name: str, folder: Path, tmp_path: Path) -> dict:
    """Run ``docs/examples/<name>.py`` with ``folder`` as its output (HDI_EXAMPLES_OUT), from an empty working
    directory; the JSON line it prints last."""
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    env = {**os.environ, "HDI_EXAMPLES_OUT": str(folder), "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py")], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert list(cwd.iterdir()) == []  # (it wrote only into the folder it was given)
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_example_is_tested():
    assert {p.stem for p in EXAMPLES.glob("*.py")} == {"quickstart", "ensemble", "open_mfdataset"}


def test_an_example_without_a_folder_says_how_to_run_it(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "HDI_EXAMPLES_OUT"}
    done = subprocess.run([sys.executable, str(EXAMPLES / "quickstart.py")], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1 and done.stderr.startswith("usage: python docs/examples/quickstart.py OUT")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_quickstart(tmp_path):
    out = tmp_path / "out"
    got = run_example("quickstart", out, tmp_path)
    assert got["history_samples"] == 2401  # 0.6 ms at 0.25 us, both ends
    assert got["protrusions"] == [9.5, 10.0, 10.5]
    assert all(0.01 < v < 100.0 for v in got["sweep_fhm_bv"])  # BV [%] in light contact
    assert got["sweep_fhm_bv"][1] == got["fhm_bv_10nm"]  # the sweep's 10 nm is the model's: one path
    assert (out / "quickstart.png").stat().st_size > 10_000 and (out / "sweep.nc").is_file()


@pytest.mark.slow
def test_ensemble(tmp_path):
    got = run_example("ensemble", tmp_path / "out", tmp_path)
    assert got["realisations"] == 3 and len(got["fhm_bv"]) == len(got["protrusions"]) == 3
    for row, mean in zip(got["fhm_bv"], got["fhm_bv_mean"]):
        assert len(set(row)) == 3  # three records, three outcomes
        assert 0.01 < min(row) <= mean <= max(row) < 100.0
    assert all(0.0 <= p <= 1.0 for p in got["touchdown_probability"])
    assert (tmp_path / "out" / "ensemble.png").is_file()


@pytest.mark.slow
def test_open_mfdataset(tmp_path):
    got = run_example("open_mfdataset", tmp_path / "out", tmp_path)
    assert got["dims"] == {"rms": 2, "protrusion": 3, "roughness": 1, "damping": 1} and got["units"] == "%"
    low, high = got["fhm_bv"]
    assert all(0.01 < a < b < 100.0 for a, b in zip(low, high))  # a larger DMW, a larger BV
