"""The tests mirror the package: a test of ``pipeline/<layer>/<module>.py`` is ``tests/<layer>/test_<module>.py``
(``tests/core/`` for the top-level modules ``pipeline/<module>.py``), a test of the bench's ``benchmarks/<module>.py``
is ``tests/benchmarks/test_<module>.py``, cross-cutting scenarios are in ``tests/scenarios/`` and the structure
tests (layers, docs, lint, registries, this one) in ``tests/structure/``.

Checked here: no test module lies outside those folders (none at ``tests/`` itself, where only the shared helper
modules and ``conftest.py`` live); a test module of a layer folder is named after a module of that layer; no
test module imports another (shared builders live in helper modules); and at least :data:`MIRRORED_SHARE` of the
package's modules have their mirrored test module.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: The share of package modules (``pipeline/**/*.py`` but ``__init__.py``) that must have a mirrored test module.
MIRRORED_SHARE = 0.70
#: Folders of tests that mirror no module: whole-chain scenarios and the checks of the project's structure.
FREE_FOLDERS = ("scenarios", "structure")
#: The folder of the tests of the package's top-level modules (``pipeline/io.py`` -> ``tests/core/test_io.py``).
CORE = "core"
#: The folder of the tests of the bench's modules (``benchmarks/peers.py`` -> ``tests/benchmarks/test_peers.py``).
BENCH = "benchmarks"


def package_modules(package: Path) -> list[Path]:
    """The modules of ``package`` (a folder), relative to it, without the ``__init__.py`` files."""
    return sorted(p.relative_to(package) for p in package.rglob("*.py") if p.name != "__init__.py")


def mirror_of(module: Path) -> Path:
    """The test module, relative to ``tests/``, that mirrors ``module`` (relative to the package folder)."""
    folder = module.parent if module.parent.parts else Path(CORE)
    return folder / f"test_{module.stem}.py"


def find_test_modules(tests: Path) -> list[Path]:
    """Every test module under ``tests``, relative to it (data folders and caches hold none)."""
    return sorted(p.relative_to(tests) for p in tests.rglob("test_*.py") if "__pycache__" not in p.parts)


def misplaced(tests: Path, package: Path, bench: Path | None = None) -> list[str]:
    """One line for each test module outside the layout: outside a layer folder, ``scenarios``, ``structure`` or
    ``benchmarks``, in a layer folder but named after no module of that layer, or in ``benchmarks`` but named
    after no module of the bench (the folder ``bench``, ``benchmarks/`` beside the package by default)."""
    layers = {m.parent for m in package_modules(package) if m.parent.parts} | {Path(CORE)}
    mirrors = {mirror_of(m) for m in package_modules(package)}
    bench = package.parent / BENCH if bench is None else bench
    found = []
    for test in find_test_modules(tests):
        folder = test.parent
        if folder.parts and folder.parts[0] in FREE_FOLDERS and len(folder.parts) == 1:
            continue
        if folder == Path(BENCH):
            if not (bench / f"{test.stem[5:]}.py").is_file():
                found.append(f"tests/{test}: names no module of the bench (benchmarks/{test.stem[5:]}.py does not "
                             "exist)")
            continue
        if folder not in layers:
            found.append(f"tests/{test}: not in a layer folder ({', '.join(sorted(map(str, layers)))}), "
                         f"{' or '.join(FREE_FOLDERS)}")
        elif test not in mirrors:
            where = f"pipeline/{test.stem[5:]}.py" if folder == Path(CORE) else f"pipeline/{folder}/{test.stem[5:]}.py"
            found.append(f"tests/{test}: names no module of the package ({where} does not exist); "
                         f"a cross-cutting test belongs in tests/scenarios/")
    return found


def unmirrored(tests: Path, package: Path) -> list[str]:
    """The package modules (``layer/module.py``) without their mirrored test module."""
    return [str(m) for m in package_modules(package) if not (tests / mirror_of(m)).is_file()]


def imports_of_test_modules(tests: Path) -> list[str]:
    """One line for each import of a test module by a test module under ``tests``."""
    found = []
    for test in find_test_modules(tests):
        for node in ast.walk(ast.parse((tests / test).read_text(encoding="utf-8"))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            found += [f"tests/{test}:{node.lineno}: imports {n}" for n in names
                      if n.split(".")[-1].startswith("test_")]
    return found


def test_every_test_module_is_in_its_place():
    found = misplaced(ROOT / "tests", ROOT / "pipeline")
    assert not found, "test modules outside the layout (docs/architecture.md):\n" + "\n".join(found)


def test_no_test_module_imports_another():
    found = imports_of_test_modules(ROOT / "tests")
    assert not found, "shared builders belong in a helper module of tests/, not in a test module:\n" + \
        "\n".join(found)


def test_most_modules_have_their_mirrored_test_module():
    modules = package_modules(ROOT / "pipeline")
    missing = unmirrored(ROOT / "tests", ROOT / "pipeline")
    share = 1 - len(missing) / len(modules)
    assert share >= MIRRORED_SHARE, (f"{len(modules) - len(missing)} of {len(modules)} package modules "
                                     f"({share:.0%}) have a mirrored test module, fewer than {MIRRORED_SHARE:.0%}; "
                                     "without one: " + ", ".join(missing))


def _tree(root: Path, files: list[str]) -> None:
    for name in files:
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text("")


def test_the_checks_see_a_misplaced_a_misnamed_and_an_importing_test_module(tmp_path):
    """Each check can fail: a fake package and tests folder with a test at the root, one in an unknown folder,
    one in a layer folder named after no module and one importing another are reported, the rest are not."""
    package, tests = tmp_path / "pkg", tmp_path / "tests"
    _tree(package, ["__init__.py", "io.py", "cli.py", "physics/__init__.py", "physics/gas.py", "physics/isbl.py",
                    "stages/__init__.py", "stages/sweep.py"])
    _tree(tests, ["conftest.py", "helpers.py", "test_flat.py", "misc/test_x.py", "core/test_io.py",
                  "physics/test_gas.py", "physics/test_gas_extra.py", "stages/test_sweep.py",
                  "scenarios/test_anything.py", "structure/test_rules.py", "data/afm/scan.txt",
                  "benchmarks/test_peers.py", "benchmarks/test_gone.py"])
    _tree(tmp_path / "benchmarks", ["peers.py"])
    (tests / "stages" / "test_sweep.py").write_text("import helpers\nfrom test_flat import x\nimport physics.test_gas\n")
    found = misplaced(tests, package)
    assert [line.split(":")[0] for line in found] == ["tests/benchmarks/test_gone.py", "tests/misc/test_x.py",
                                                      "tests/physics/test_gas_extra.py", "tests/test_flat.py"]
    assert "benchmarks/gone.py does not exist" in found[0]
    assert "pipeline/physics/gas_extra.py does not exist" in found[2] and "not in a layer folder" in found[3]
    assert unmirrored(tests, package) == ["cli.py", "physics/isbl.py"]
    assert imports_of_test_modules(tests) == ["tests/stages/test_sweep.py:2: imports test_flat",
                                   "tests/stages/test_sweep.py:3: imports physics.test_gas"]
    assert mirror_of(Path("io.py")) == Path("core/test_io.py")
    assert mirror_of(Path("stages/statics.py")) == Path("stages/test_statics.py")

