"""The scripts of docs/examples/ as a user meets them: each is tested, and one run without an output folder
says how to run it. Their runs (each script copied out of the clone, on the installed wheel, from an empty
folder, writing only into the folder it is given, with plausible numbers) are
tests/scenarios/test_installed.py's ``test_every_example_runs_from_an_empty_folder_on_the_installed_wheel``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def test_every_example_is_tested():
    assert {p.stem for p in EXAMPLES.glob("*.py")} == {"quickstart", "ensemble", "open_mfdataset"}


def test_an_example_without_a_folder_says_how_to_run_it(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "HDI_EXAMPLES_OUT"}
    done = subprocess.run([sys.executable, str(EXAMPLES / "quickstart.py")], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1 and done.stderr.startswith("usage: python docs/examples/quickstart.py OUT")
    assert list(tmp_path.iterdir()) == []
