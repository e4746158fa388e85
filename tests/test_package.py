"""The package's metadata: one version everywhere (pyproject, the package, CITATION.cff, `hdi --version`),
the license text that BSD-3-Clause requires to ship, and a citation file naming the paper's DOI."""

from __future__ import annotations

import re

import pytest

from pipeline import __version__
from pipeline.cli import main

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib


def test_version_is_one(repo_root, capsys):
    meta = tomllib.loads((repo_root / "pyproject.toml").read_text())["project"]
    assert meta["version"] == __version__
    cff = (repo_root / "CITATION.cff").read_text()
    assert re.search(r"^version: (\S+)$", cff, re.M).group(1) == __version__
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"hdi {__version__}"


def test_license_and_citation_ship(repo_root):
    meta = tomllib.loads((repo_root / "pyproject.toml").read_text())["project"]
    text = (repo_root / "LICENSE").read_text()
    assert meta["license"]["text"] == "BSD-3-Clause" and text.startswith("BSD 3-Clause License")
    assert "Neither the name of the copyright holder" in text  # the third clause
    cff = (repo_root / "CITATION.cff").read_text()
    assert "cff-version: 1.2.0" in cff and "license: BSD-3-Clause" in cff
    assert "doi: 10.1109/TMAG.2009.2029410" in cff


def test_help_keys_prints_the_schema(capsys):
    """``hdi --help-keys [SECTION]``: every key of the schema with its default, type and doc, on stdout."""
    from pipeline.config.scene import SCHEMA
    with pytest.raises(SystemExit) as exc:
        main(["--help-keys", "lubricant"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("[lubricant]\n")
    for key, spec in SCHEMA["lubricant"].items():
        assert f"  {key} = " in out and spec.doc in out
    assert "  bridge_work_of_adhesion_j_m2 = (no default)  (float)" in out
    with pytest.raises(SystemExit) as exc:
        main(["--help-keys"])
    out = capsys.readouterr().out
    assert exc.value.code == 0 and all(f"[{s}]" in out for s in SCHEMA)
    with pytest.raises(SystemExit) as exc:
        main(["--help-keys", "nope"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and len(err.strip().splitlines()) == 1 and "no section [nope]" in err
