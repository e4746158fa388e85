"""The package's layers import downward only, and no import inside a function dodges a cycle.

Layers, lowest first (README, "Architecture"): the base modules every layer may use (units table,
dataset schema and I/O, code keys, the fan-out), ``physics`` (pure laws in SI), ``config`` (scene
schema, loading, validation, grids), ``model`` (scene to model, kernel, outcome rules), ``analyses``
(calibration, studies, optimum, figures), the stages with their runner and the study evaluations,
and the command line. The imports are read from the source with :mod:`ast`, at module level and
inside functions alike.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "pipeline"

#: Rank of each module or package prefix (longest prefix wins).
LAYERS = {
    "pipeline": 0, "pipeline.units": 0, "pipeline.code_version": 0, "pipeline.io": 0,
    "pipeline.variables": 0, "pipeline.fanout": 0, "pipeline.validity": 0,
    "pipeline.physics": 1,
    "pipeline.config": 2,
    "pipeline.model": 3,
    "pipeline.analyses": 4,
    "pipeline.stages": 5, "pipeline.runner": 5, "pipeline.evaluations": 5,
    "pipeline.validation": 6, "pipeline.cli": 6, "pipeline.sizing": 6,
}
NAMES = {0: "base", 1: "physics", 2: "config", 3: "model", 4: "analyses", 5: "stages", 6: "cli"}

#: Imports inside a function that are allowed, with why (none may dodge a cycle of module-level imports).
LAZY_ALLOWED = {
    ("pipeline.runner", "pipeline.stages"): "plug-in discovery: the runner finds every stage module (registry)",
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def rank(module: str) -> int:
    best = max((p for p in LAYERS if module == p or module.startswith(p + ".")), key=len)
    return LAYERS[best]


def imports(path: Path, module: str | None = None) -> list[tuple[str, bool, int]]:
    """``(imported pipeline module, at module level, line)`` for every import of ``path`` (read as the
    module ``module``, default the one its place in the package names)."""
    module = module or module_name(path)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    tree = ast.parse(path.read_text())
    top = {id(n) for n in tree.body}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            elif node.module and node.module.split(".")[0] == "pipeline":
                target = node.module
            else:
                continue
            # ``from pipeline.x import y``: y may be a module
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                is_module = (ROOT.parent / Path(*sub.split("."))).with_suffix(".py").exists() or \
                    (ROOT.parent / Path(*sub.split("."))).is_dir()
                found.append((sub if is_module else target, id(node) in top, node.lineno))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "pipeline":
                    found.append((alias.name, id(node) in top, node.lineno))
    return found


MODULES = sorted(ROOT.rglob("*.py"))


def test_every_module_has_a_layer():
    assert MODULES
    for path in MODULES:
        rank(module_name(path))  # raises ValueError (max of nothing) for a module in no layer


@pytest.mark.parametrize("path", MODULES, ids=lambda p: module_name(p))
def test_imports_go_downward_only(path):
    me = module_name(path)
    up = [(target, line) for target, _, line in imports(path) if rank(target) > rank(me)]
    assert not up, (f"{me} ({NAMES[rank(me)]}) imports from a layer above it: "
                    + ", ".join(f"{t} ({NAMES[rank(t)]}, line {ln})" for t, ln in up))


def test_function_level_imports_are_the_allowed_ones():
    lazy = {(module_name(p), t) for p in MODULES for t, at_top, _ in imports(p) if not at_top}
    assert lazy <= set(LAZY_ALLOWED), f"imports inside functions: {sorted(lazy - set(LAZY_ALLOWED))}"


def test_the_checker_sees_an_upward_import(tmp_path):
    """The test can fail: a physics module importing the model layer is reported (the probe is parsed
    from a temporary file under a physics module's name, never written into the package)."""
    probe = tmp_path / "probe.py"
    probe.write_text("from ..model import slider\n\ndef f():\n    from ..stages import sweep\n")
    module = "pipeline.physics.probe"
    found = imports(probe, module)
    assert ("pipeline.model.slider", True, 1) in found and ("pipeline.stages.sweep", False, 4) in found
    assert all(rank(t) > rank(module) for t, _, _ in found)
