"""``ruff check`` runs inside ``make test``'s one pytest session: syntax errors (E9), pyflakes (F: unused
imports, undefined or redefined names, f-strings without placeholders) and indentation (E1), as configured
in pyproject.toml's ``[tool.ruff]``; ruff comes with the ``test`` extra."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: What the project lints: the package, its tests, benchmarks and the docs' example scripts.
LINTED = ("pipeline", "tests", "benchmarks", "docs")


def _ruff() -> list[str]:
    """The ruff of this environment (the ``test`` extra installs it beside the interpreter)."""
    beside = Path(sys.executable).with_name("ruff")
    exe = str(beside) if beside.exists() else shutil.which("ruff")
    assert exe, "ruff is not installed: it is in the test extra (make test installs it)"
    return [exe]


def test_ruff_finds_nothing_in_the_project():
    done = subprocess.run([*_ruff(), "check", "--no-cache", "--output-format", "concise", *LINTED], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, f"ruff check found problems:\n{done.stdout}{done.stderr}"


def test_ruff_is_configured_to_find_the_slips_it_is_there_for(tmp_path):
    """The configuration really selects the rules: a file with an unused import, a redefinition and a
    misindented line fails (the check above cannot pass by checking nothing)."""
    bad = tmp_path / "bad.py"
    bad.write_text("import os\n\n\ndef f(x):\n   y = x\n   return y\n\n\ndef f(x):\n    return x\n")
    done = subprocess.run([*_ruff(), "check", "--no-cache", "--output-format", "json", "--config",
                           str(ROOT / "pyproject.toml"), str(bad)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    found = {(item["code"], item["location"]["row"]) for item in json.loads(done.stdout)}
    assert {("F401", 1), ("E111", 5), ("E111", 6), ("F811", 9)} <= found, found
