"""The package's layers import downward only, and no import inside a function dodges a cycle.

Layers, lowest first (docs/architecture.md): the base modules every layer may use (units table,
dataset schema and I/O, code keys, the fan-out), ``physics`` (pure laws in SI), ``config`` (scene
schema, loading, validation, grids), ``model`` (scene to model, kernel, outcome rules), ``analyses``
(calibration, studies, optimum, figures), the stages with their runner and the study evaluations,
and the command line. The imports are read from the source with :mod:`ast`, at module level and
inside functions alike.
"""

from __future__ import annotations

import ast
from typing import Callable
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2] / "pipeline"

#: Rank of each module or package prefix (longest prefix wins).
LAYERS = {
    "pipeline": 0, "pipeline.units": 0, "pipeline.code_version": 0, "pipeline.io": 0, "pipeline.encoding": 0,
    "pipeline.file_errors": 0,
    "pipeline.variables": 0, "pipeline.fanout": 0, "pipeline.cluster": 0, "pipeline.scheduler": 0,
    "pipeline.options": 0, "pipeline.progress": 0, "pipeline.validity": 0,
    "pipeline.interrupts": 0, "pipeline.paths": 0, "pipeline.folder_lock": 0, "pipeline.duck_arrays": 0,
    "pipeline.physics": 1,
    "pipeline.config": 2,
    "pipeline.model": 3,
    "pipeline.analyses": 4,
    "pipeline.stages": 5, "pipeline.runner": 5, "pipeline.stage": 5, "pipeline.stage_keys": 5, "pipeline.evaluations": 5,
    "pipeline.candidates": 5,
    "pipeline.cli_checks": 6, "pipeline.cli": 6, "pipeline.launch": 6, "pipeline.sizing": 6, "pipeline.api": 6,
}
NAMES = {0: "base", 1: "physics", 2: "config", 3: "model", 4: "analyses", 5: "stages", 6: "cli"}

#: Imports inside a function that are allowed, with why (none may dodge a cycle of module-level imports).
LAZY_ALLOWED = {
    ("pipeline.stage", "pipeline.stages"): "plug-in discovery: the registry finds every stage module",
    ("pipeline", "pipeline.api"): "the front door: the package re-exports the API on first use (module __getattr__)",
    ("pipeline.launch", "pipeline.cli"): "the console script starts a first run's kernel compile before the "
                                         "command line's imports, which the compile then overlaps",
    # the first run's early compile process imports no xarray (pipeline.model.ahead.NOT_IMPORTED_EARLY): the
    # modules on its path import those that do where they are used
    ("pipeline.model.ahead", "pipeline.model.statics"): "the statics map's entry points, listed in the main "
                                                        "process only; the early compile imports no xarray",
    ("pipeline.model.assembly", "pipeline.model.bulge_table"): "a bulge table read (xarray) when a model is "
                                                               "built, never by the early compile",
    ("pipeline.model.dmw_record", "pipeline.io"): "a DMW record read (xarray) when one is read, never by the "
                                                  "early compile",
}

#: Imports of a layer above that are allowed, with why: each is also inside a function (LAZY_ALLOWED), so
#: no module below imports it when it is imported.
UPWARD_ALLOWED = {
    ("pipeline", "pipeline.api"): "the package's names of the public API, imported on first use of one",
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
    up = [(target, line) for target, _, line in imports(path)
          if rank(target) > rank(me) and (me, target) not in UPWARD_ALLOWED]
    assert not up, (f"{me} ({NAMES[rank(me)]}) imports from a layer above it: "
                    + ", ".join(f"{t} ({NAMES[rank(t)]}, line {ln})" for t, ln in up))


def test_the_allowed_upward_imports_are_lazy_and_importing_the_package_imports_no_layer():
    """``import pipeline`` loads none of its layers (the API above all of them comes on first use)."""
    assert set(UPWARD_ALLOWED) <= set(LAZY_ALLOWED)
    import subprocess
    import sys
    code = ("import sys, pipeline; print(sorted(m for m in sys.modules if m.startswith('pipeline.')));"
            "pipeline.simulate; print('pipeline.api' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "[]" and out[1] == "True"


def test_function_level_imports_are_the_allowed_ones():
    lazy = {(module_name(p), t) for p in MODULES for t, at_top, _ in imports(p) if not at_top}
    assert lazy <= set(LAZY_ALLOWED), f"imports inside functions: {sorted(lazy - set(LAZY_ALLOWED))}"


def test_the_checker_sees_an_upward_import(tmp_path):
    """The test can fail: a physics module importing the model layer is reported (the probe is parsed
    from a temporary file under a physics module's name, never written into the package)."""
    probe = tmp_path / "probe.py"
    probe.write_text("from ..model import running\n\ndef f():\n    from ..stages import sweep\n")
    module = "pipeline.physics.probe"
    found = imports(probe, module)
    assert ("pipeline.model.running", True, 1) in found and ("pipeline.stages.sweep", False, 4) in found
    assert all(rank(t) > rank(module) for t, _, _ in found)


# ------------------------------------------------------------------------ rules beyond the layers
#: The stage modules: each is a plug-in of the runner; what two stages share lives a layer down (model/,
#: analyses/) or in a non-stage module of the stage layer (runner, evaluations), never in another stage.
STAGES = "pipeline.stages"


def stage_imports(path: Path, module: str | None = None) -> list[tuple[str, int]]:
    """``(stage module, line)`` of every other stage module that the stage module ``path`` imports."""
    me = module or module_name(path)
    return [(t, line) for t, _, line in imports(path, me)
            if t.startswith(STAGES + ".") and t.split(".")[2] != me.split(".")[2]]


def _scene_sections() -> set[str]:
    from pipeline.config.scene import SCHEMA
    return set(SCHEMA)


#: Parameter names that hand a physics function the scene (or a section of it) instead of numbers.
SCENE_PARAMETERS = {"scene", "config", "cfg", "section"}


def scene_reads(source: str, sections: set[str]) -> list[tuple[str, int]]:
    """``(what, line)`` of each place a physics source reads a scene: a function parameter named as a
    scene (:data:`SCENE_PARAMETERS`) or a subscript by a scene section's name (``x["air_bearing"]``)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            a = node.args
            for arg in (*a.posonlyargs, *a.args, *a.kwonlyargs, a.vararg, a.kwarg):
                if arg is not None and arg.arg in SCENE_PARAMETERS:
                    found.append((f"parameter {arg.arg!r}", node.lineno))
        elif isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) \
                and node.slice.value in sections:
            found.append((f"subscript [{node.slice.value!r}]", node.lineno))
    return found


#: Calls that read a file (by the called name: a function or a method), and the readers of pipeline.io.
FILE_READERS = {"open", "read_dataset", "read_attrs", "open_dataset", "open_mfdataset", "load_dataset",
                "open_dataarray", "load", "loadtxt", "genfromtxt", "fromfile", "read_text", "read_bytes",
                "read_csv", "load_record"}
IO_READERS = {"read_dataset", "read_attrs"}


def _calls_and_imports(source: str, calls: set[str],
                       imported: Callable[[ast.Import | ast.ImportFrom], list[str]]) -> list[tuple[str, int]]:
    """``(what, line)`` of each call in ``source`` of a function named in ``calls`` (plain or attribute) and of
    what ``imported`` reports for each ``import`` and ``from ... import``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None
            if name in calls:
                found.append((f"call {name}()", node.lineno))
        elif isinstance(node, ast.Import) or (isinstance(node, ast.ImportFrom) and node.module):
            found += [(what, node.lineno) for what in imported(node)]
    return found


def file_reads(source: str) -> list[tuple[str, int]]:
    """``(what, line)`` of each call in ``source`` that reads a file (:data:`FILE_READERS`, ``np.load``,
    ``path.read_text()``, ...) and each import of a reader of :mod:`pipeline.io`."""
    def io_readers(node: ast.Import | ast.ImportFrom) -> list[str]:
        if isinstance(node, ast.ImportFrom) and node.module.split(".")[-1] == "io" and (node.level or node.module.startswith("pipeline")):
            return [f"import {a.name} from io" for a in node.names if a.name in IO_READERS]
        return []
    return _calls_and_imports(source, FILE_READERS, io_readers)


#: Names by which SurfaceTopography reads a file: its readers' entry points (a call or an import) and its IO package.
TOPOGRAPHY_READERS = {"open_topography", "read_topography", "read_container", "open_container"}


def topography_reads(source: str) -> list[tuple[str, int]]:
    """``(what, line)`` of each call of a SurfaceTopography file reader (:data:`TOPOGRAPHY_READERS`) and each
    import of one or of ``SurfaceTopography.IO``, in ``source``."""
    def readers(node: ast.Import | ast.ImportFrom) -> list[str]:
        if isinstance(node, ast.Import):
            return [f"import {a.name}" for a in node.names if a.name.startswith("SurfaceTopography.IO")]
        if not node.module.startswith("SurfaceTopography"):
            return []
        return ([f"import from {node.module}"] if node.module.startswith("SurfaceTopography.IO") else []) + \
            [f"import {a.name}" for a in node.names if a.name in TOPOGRAPHY_READERS]
    return _calls_and_imports(source, TOPOGRAPHY_READERS, readers)


def _in(package: str) -> list[Path]:
    return [p for p in MODULES if module_name(p).startswith(package + ".")]


@pytest.mark.parametrize("path", _in(STAGES), ids=lambda p: module_name(p))
def test_no_stage_imports_another_stage(path):
    found = stage_imports(path)
    assert not found, (f"{module_name(path)} imports another stage: "
                       + ", ".join(f"{t} (line {ln})" for t, ln in found)
                       + "; move what they share to model/, analyses/ or a non-stage module (runner.py)")


@pytest.mark.parametrize("path", _in("pipeline.physics"), ids=lambda p: module_name(p))
def test_physics_reads_no_scene(path):
    found = scene_reads(path.read_text(), _scene_sections())
    assert not found, (f"{module_name(path)} reads a scene (physics takes numbers in SI; the model layer "
                       "reads the scene): " + ", ".join(f"{w} (line {ln})" for w, ln in found))


@pytest.mark.parametrize("path", _in("pipeline.analyses"), ids=lambda p: module_name(p))
def test_analyses_open_no_files(path):
    found = file_reads(path.read_text())
    assert not found, (f"{module_name(path)} reads a file (an analysis works on data its stage read): "
                       + ", ".join(f"{w} (line {ln})" for w, ln in found))


@pytest.mark.parametrize("path", _in("pipeline.physics"), ids=lambda p: module_name(p))
def test_physics_opens_no_files(path):
    source = path.read_text()
    found = file_reads(source) + topography_reads(source)
    assert not found, (f"{module_name(path)} reads a file (physics is pure functions on numbers; files are read "
                       "in the model layer, e.g. pipeline.model.afm_scan): "
                       + ", ".join(f"{w} (line {ln})" for w, ln in found))


def test_the_rules_see_a_stage_import_a_scene_read_and_a_file_read(tmp_path):
    """Each rule can fail: synthetic offending sources are caught (parsed from temporary files under
    the names of a stage, never written into the package), and clean ones are not."""
    probe = tmp_path / "probe.py"
    probe.write_text("from .sweep import batch_model\nfrom . import simulate\nfrom ..model import running\n"
                     "from .probe import x\n")
    assert stage_imports(probe, "pipeline.stages.probe") == [("pipeline.stages.sweep", 1),
                                                             ("pipeline.stages.simulate", 2)]
    sections = _scene_sections()
    assert scene_reads("def force(g, delta, scene):\n    return g\n", sections) == [("parameter 'scene'", 1)]
    assert scene_reads("def f(g, *, cfg=None):\n    pass\n", sections) == [("parameter 'cfg'", 1)]
    assert scene_reads("def f(s):\n    return s['air_bearing']['flying_height_nm']\n", sections) \
        == [("subscript ['air_bearing']", 2)]
    assert scene_reads("def f(g, g0, k_t):\n    return {'tfc': g}['x'] * g0\n", sections) == []
    bad = ("import numpy as np\nfrom ..io import read_dataset, var\nfrom pathlib import Path\n"
           "def f(p):\n    a = open(p)\n    b = np.load(p)\n    c = Path(p).read_text()\n"
           "    d = xr.open_dataset(p)\n    return read_dataset(p)\n")
    assert sorted(w for w, _ in file_reads(bad)) == sorted(
        ["import read_dataset from io", "call open()", "call load()", "call read_text()", "call open_dataset()",
         "call read_dataset()"])
    assert file_reads("from ..io import temporary_path, var\ndef f(x):\n    return x.sum()\n") == []
    afm = ("from SurfaceTopography import Topography, open_topography\nimport SurfaceTopography.IO\n"
           "def f(p):\n    from SurfaceTopography.IO import readers\n    return open_topography(p)\n")
    assert sorted(w for w, _ in topography_reads(afm)) == sorted(
        ["import open_topography", "import SurfaceTopography.IO", "import from SurfaceTopography.IO",
         "call open_topography()"])
    assert topography_reads("from SurfaceTopography import Topography\nt = Topography(h, (1, 1))\n") == []
