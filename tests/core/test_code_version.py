"""The code in a stage's inputs key (pipeline.code_version): which modules a stage's code is, and a
changed source recomputes the stages that run it and only those."""

from __future__ import annotations

from pathlib import Path

import pytest

from pipeline import code_version as cv
from pipeline import runner
from pipeline.config.scene import load_scene

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"


@pytest.fixture()
def package(tmp_path):
    """A small package ``pkg`` with module-level, lazy, parenthesised and absolute imports."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    files = {
        "__init__.py": "",
        "a.py": "import math\nfrom .b import f\n\n\ndef g():\n    from . import c  # lazy\n    return c\n",
        "b.py": "from . import (\n    sub,\n    e as ee,\n)\nVALUE = 1\n",
        "c.py": "from pkg.sub.d import x\n",
        "e.py": "",
        "unused.py": "from .a import g\n",
        "sub/__init__.py": "",
        "sub/d.py": "import pkg.e\nx = 2\n",
    }
    for name, text in files.items():
        (pkg / name).write_text(text)
    return pkg


def test_modules_follow_every_kind_of_import_and_nothing_else(package):
    found = cv.modules("pkg.a", package, "pkg")
    assert found == ("pkg", "pkg.a", "pkg.b", "pkg.c", "pkg.e", "pkg.sub", "pkg.sub.d")
    assert "pkg.unused" not in found                      # imports a, is not imported by it
    assert cv.modules("pkg.nope", package, "pkg") == () and cv.source_key("math", package, "pkg") == ""


def test_an_edited_module_changes_the_key_of_the_modules_that_import_it(package):
    before = {m: cv.source_key(m, package, "pkg") for m in ("pkg.a", "pkg.c", "pkg.b")}
    (package / "sub" / "d.py").write_text("import pkg.e\nx = 3  # a corrected constant\n")
    after = {m: cv.source_key(m, package, "pkg") for m in before}
    assert after["pkg.a"] != before["pkg.a"] and after["pkg.c"] != before["pkg.c"]  # a -> c -> sub.d
    assert after["pkg.b"] == before["pkg.b"]                 # b imports sub, not sub.d


def test_an_import_edited_in_at_the_same_size_and_time_is_followed(package):
    """The import scan is kept per source text, not per file: an edit that keeps the file's size and
    modification time (a same-length line, the time set back) still changes what the module imports."""
    import os
    e = package / "e.py"
    e.write_text("x = 100  # nothing imported here\n")
    assert cv.modules("pkg.e", package, "pkg") == ("pkg.e",)
    stat = e.stat()
    e.write_text("from pkg import unused  # now it\n")
    os.utime(e, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert e.stat().st_size == stat.st_size and e.stat().st_mtime_ns == stat.st_mtime_ns
    assert cv.modules("pkg.e", package, "pkg") == ("pkg", "pkg.a", "pkg.b", "pkg.c", "pkg.e", "pkg.sub",
                                                   "pkg.sub.d", "pkg.unused")


def test_each_stage_is_keyed_on_the_code_it_runs():
    """The simulating stages on the integrator and the friction law, the report on its figures, the
    roughness stage on neither; the runner's own code on none (orchestration)."""
    sweep = cv.modules("pipeline.stages.sweep")
    report = cv.modules("pipeline.stages.report")
    rough = cv.modules("pipeline.stages.roughness")
    for mod in ("pipeline.model.dynamics", "pipeline.model.running", "pipeline.model.assembly", "pipeline.model.outcomes",
                "pipeline.physics.friction", "pipeline.physics.air_bearing"):
        assert mod in sweep and mod in cv.modules("pipeline.stages.calibrate") and mod not in rough
    assert "pipeline.physics.asperity" in cv.modules("pipeline.stages.interface")
    assert "pipeline.analyses.plots" in report and "pipeline.analyses.plots" not in sweep and "pipeline.model.dynamics" not in report
    assert "pipeline.physics.surface" in rough and "pipeline.model.afm_scan" in rough
    # the stages import the orchestration (the runner for Stage, the fan-out) and the code key leaves it
    # out, with the command line's option checks; the material bounds the interface stage runs are in
    assert {"pipeline.runner", "pipeline.fanout"} <= cv.imports("pipeline.stages.sweep")
    assert "pipeline.physics.material_bounds" in cv.modules("pipeline.stages.interface")
    assert not any(m in cv.ORCHESTRATION for m in sweep + report + rough + cv.modules("pipeline.stages.interface"))


def test_changed_code_recomputes_its_stage_and_what_is_downstream(tmp_path, monkeypatch):
    """A dataset made by other code is not current: with the DMW stage's code changed, dmw.nc is
    recomputed and so is everything that reads it; the roughness stage's result is kept."""
    scene = load_scene(PAPER)
    runner.Runner(scene, tmp_path).build(["dmw", "roughness"])
    keys = {s: runner.Runner(scene, tmp_path).key(s) for s in ("dmw", "roughness", "sweep")}
    real = runner.code_key
    monkeypatch.setattr(runner, "code_key", lambda name: real(name) + ("-edited" if name == "pipeline.stages.dmw" else ""))
    r = runner.Runner(scene, tmp_path)
    assert r.key("dmw") != keys["dmw"] and r.key("sweep") != keys["sweep"] and r.key("roughness") == keys["roughness"]
    assert r.stale_reason("dmw") is not None and r.stale_reason("roughness") is None
    r.build(["dmw"])
    assert runner.Runner(scene, tmp_path).stale_reason("dmw") is None
