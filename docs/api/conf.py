"""Sphinx configuration of hdi's API reference: the Python API (pipeline/api.py) and every physics law
(pipeline/physics/), from their numpydoc docstrings, and a gallery of the examples (docs/examples/,
docs/experiments/) with their committed figures. Built by `make docs` (warnings are errors) into
build/docs/; tests/structure/test_api_reference.py builds it inside `make test`."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

project = "hdi"
author = "hdi contributors"
copyright = "the hdi contributors, BSD-3-Clause"
extensions = ["sphinx.ext.autodoc", "numpydoc"]
exclude_patterns = ["_build"]
html_theme = "alabaster"
html_static_path: list[str] = []
# the docstrings' own words (``name : what [unit]`` with no type) are kept as written; numpydoc's checks
# of a docstring's form are tests/structure/test_api_reference.py's (Parameters, Returns with a unit,
# References), not the build's
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
# the paper's references are cited by key ([VLP09], ...) in the docstrings and listed in docs/model.md
# (a References section lists its keys; the text cites them as [KEY], not as reST citation links)
suppress_warnings = ["ref.citation"]


def _functions_and_classes_only(app, what, name, obj, skip, options):
    """The reference documents the modules' functions and classes; their constants and registries are
    described in the module docstrings and docs/model.md (``#:`` comments are written for the source)."""
    import inspect
    if what == "module" and not (inspect.isfunction(obj) or inspect.isclass(obj)):
        return True
    return None


def setup(app):
    app.connect("autodoc-skip-member", _functions_and_classes_only)
