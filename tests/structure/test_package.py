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
    # (an SPDX expression and the file it names: PEP 639, which the build backend writes into the wheel's metadata)
    assert meta["license"] == "BSD-3-Clause" and meta["license-files"] == ["LICENSE"]
    assert text.startswith("BSD 3-Clause License")
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


def test_distribution_name_and_one_version_source(repo_root):
    """The distribution is ``hdi-dynamics`` (``pipeline`` is taken on PyPI); ``__version__`` is read from
    its installed metadata, which pyproject.toml writes (no second copy in the code)."""
    from importlib.metadata import distribution

    from pipeline import DISTRIBUTION
    meta = tomllib.loads((repo_root / "pyproject.toml").read_text())["project"]
    assert meta["name"] == DISTRIBUTION == "hdi-dynamics"
    dist = distribution(DISTRIBUTION)
    assert dist.version == __version__
    assert any(ep.name == "hdi" and ep.value == "pipeline.launch:entry" for ep in dist.entry_points)
    init = (repo_root / "pipeline" / "__init__.py").read_text()
    assert not re.search(r"__version__\s*=\s*[\"']\d+\.\d+", init)  # no literal version in the package


def test_provenance_names_versions_and_the_papers_doi():
    """Every dataset's provenance: the package version with those of the numerical libraries, and the
    paper's DOI in CF's ``references`` attribute."""
    import netCDF4
    import numba
    import numpy
    import scipy
    import xarray

    from pipeline.io import provenance
    attrs = provenance(stage="interface")
    versions = dict(item.rsplit(" ", 1) for item in attrs["software_versions"].split("; "))
    assert versions == {"hdi-dynamics": __version__, "numpy": numpy.__version__, "scipy": scipy.__version__,
                        "numba": numba.__version__, "xarray": xarray.__version__,
                        "netCDF4": netCDF4.__version__}
    assert "https://doi.org/10.1109/TMAG.2009.2029410" in attrs["references"]
    assert "10.1109" not in attrs["source"]
