"""The set-up writes the bytecode of what the commands import (the Makefile's ``BYTECODE_IMPORTS`` and
``BYTECODE_LAZY``, two processes at once, with writing on, after every install): whatever the user's
``PYTHONDONTWRITEBYTECODE``, a later process starts from cached bytecode (docs/performance.md, section
"Start-up whatever the shell"). Checked here: every install runs it, after the environment is synced; it
imports every module of the package, every third-party module the package imports inside a function (where a
command's own imports would not reach it at start) and numba's implementations (imported when a process first
loads a kernel)."""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def makefile_variable(name: str, text: str) -> str:
    """The value of the Makefile's ``NAME := ...`` (its continuation lines joined)."""
    m = re.search(rf"^{name} :=(.*?(?:\\\n.*?)*)$", text, re.M)
    assert m is not None, f"Makefile: no '{name} :=' line"
    return " ".join(part.strip() for part in m.group(1).split("\\\n"))


def function_level_imports(package: Path) -> dict[str, str]:
    """Third-party modules imported inside a function of ``package`` (not the package's own, not the standard
    library's): module -> where (``file:line``)."""
    found: dict[str, str] = {}
    for path in sorted(package.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                    [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module else []
                for name in names:
                    top = name.split(".")[0]
                    if top != "pipeline" and top not in sys.stdlib_module_names:
                        found.setdefault(name, f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


def test_every_install_writes_the_bytecode_of_what_runs_after_the_sync():
    text = (ROOT / "Makefile").read_text()
    install = re.search(r"^define install\n(.*?)^endef", text, re.M | re.S).group(1)
    lines = " ".join(ln.strip() for ln in install.split("\\\n")).splitlines()
    # (the two lists in two processes at once; the recipe fails when either fails)
    assert lines[-1].strip() == ("$(BIN)/python -c '$(BYTECODE_LAZY)' & lazy=$$!; $(BIN)/python -c "
                                 "'$(BYTECODE_IMPORTS)'; own=$$?; wait $$lazy && exit $$own")
    assert any("sync --locked" in ln for ln in lines[:-1])
    assert re.search(r"^export PYTHONDONTWRITEBYTECODE :=\s*$", text, re.M)  # (writing on in every recipe)
    for name in ("BYTECODE_IMPORTS", "BYTECODE_LAZY"):
        assert "'" not in makefile_variable(name, text)  # (inside the recipe's single quotes)


def modules_after(code: str) -> set[str]:
    """The modules a fresh process has imported after running ``code`` (without writing bytecode)."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, "-c", code + "; import sys; print('\\n'.join(sorted(sys.modules)))"],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return set(done.stdout.split())


def test_the_set_up_imports_every_package_module_and_every_lazy_third_party_import():
    """The set-up's line, run here without writing: every module of the package and every third-party module
    imported inside a function of it is in the process's modules (a new lazy import not in the list fails);
    so are the modules numba imports when a process first loads a kernel from its cache (its CPU target's
    additional registries: ~70 modules that every command with a kernel compiled again without them)."""
    text = (ROOT / "Makefile").read_text()
    imported = modules_after(makefile_variable("BYTECODE_IMPORTS", text)) | modules_after(
        makefile_variable("BYTECODE_LAZY", text))
    numba_lazy = modules_after("import numba; from numba.core.registry import cpu_target; "
                               "cpu_target.target_context.refresh()") - modules_after("import numba")
    assert {"numba.np.arraymath", "numba.cpython.unicode"} <= numba_lazy  # (the check sees numba's lazy imports)
    assert not numba_lazy - imported, sorted(numba_lazy - imported)
    package = {".".join(("pipeline", *p.relative_to(ROOT / "pipeline").with_suffix("").parts))
               for p in (ROOT / "pipeline").rglob("*.py") if p.name != "__init__.py"}
    assert len(package) > 100 and not package - imported, sorted(package - imported)
    lazy = function_level_imports(ROOT / "pipeline")
    assert {"distributed", "matplotlib.figure", "scipy.optimize"} <= set(lazy)  # (the check reads the sources)
    missing = {m: where for m, where in lazy.items() if m not in imported}
    assert not missing, f"imported inside a function but not by the Makefile's BYTECODE_LAZY: {missing}"
