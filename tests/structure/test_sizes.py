"""No module of the package is over :data:`MODULE_LINES` lines and no function over :data:`FUNCTION_LINES` lines
(docs/architecture.md, "Sizes"): a module that grows past the bound holds more than one job and is split along its
seams, a function past it is split into named steps.

The one exception is the numba kernel: a function of :data:`KERNEL_EXEMPT` is one compiled unit on purpose (its
inner loop inlines its callees; a call out of it per step, or a closure, costs the kernel its speed), so it may be
longer. Each exemption names why; the check fails on an exempt function that is no longer decorated by a jit
(a Python function has no such reason) and on one that has shrunk to the bound (the exemption is stale).
Functions are measured from their ``def`` line to their last line, docstring included; modules by their lines.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: The most lines a module of pipeline/ may have.
MODULE_LINES = 600
#: The most lines a function may have, from its ``def`` to its last line.
FUNCTION_LINES = 80
#: ``"path/to/module.py::function"`` -> why this compiled kernel function may be longer than the bound.
KERNEL_EXEMPT = {
    "pipeline/model/dynamics.py::_integrate": "the numba kernel's integration loop (docs/kernel.md): one compiled "
                                              "function whose step, events and output sampling numba inlines; "
                                              "split into calls it would pass its whole state per step",
}


def _functions(tree: ast.AST) -> list[ast.FunctionDef | ast.AsyncFunctionDef]:
    return [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


def _is_jit(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """Decorated by numba's ``njit``/``jit`` or the package's kernel decorator (``_jit``, ``kernel_jit(...)``)."""
    names = [ast.unparse(d.func if isinstance(d, ast.Call) else d) for d in node.decorator_list]
    return any(name.split(".")[-1].lstrip("_").endswith("jit") for name in names)


def oversized(root: Path, package: str = "pipeline", module_lines: int = MODULE_LINES,
              function_lines: int = FUNCTION_LINES, exempt: dict[str, str] | None = None) -> list[str]:
    """One line for each module of ``root/package`` over ``module_lines`` and each function over
    ``function_lines`` that ``exempt`` does not name; and for each exemption that is not a jit function over
    the bound (stale or wrong)."""
    exempt = KERNEL_EXEMPT if exempt is None else exempt
    found, seen = [], set()
    for path in sorted((root / package).rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        text = path.read_text(encoding="utf-8")
        n = len(text.splitlines())
        if n > module_lines:
            found.append(f"{rel}: {n} lines (at most {module_lines}: split it along its seams)")
        for node in _functions(ast.parse(text)):
            length = node.end_lineno - node.lineno + 1
            where = f"{rel}::{node.name}"
            if where in exempt:
                seen.add(where)
                if not _is_jit(node):
                    found.append(f"{where}: exempt as a kernel function, but not compiled by a jit")
                elif length <= function_lines:
                    found.append(f"{where}: {length} lines, within the bound: its exemption is stale")
            elif length > function_lines:
                found.append(f"{rel}:{node.lineno}: {node.name} is {length} lines (at most {function_lines}: "
                             "split it into named steps)")
    found += [f"{where}: exempt, but no such function" for where in sorted(set(exempt) - seen)]
    return found


def test_no_module_is_over_the_bound_and_no_function_outside_the_kernel():
    found = oversized(ROOT)
    assert not found, "too large (docs/architecture.md, \"Sizes\"):\n" + "\n".join(found)


def test_every_exemption_is_a_kernel_function_with_its_reason():
    for where, why in KERNEL_EXEMPT.items():
        path, _, name = where.partition("::")
        assert (ROOT / path).is_file() and path.startswith("pipeline/model/") and len(why) > 40, where


def test_the_check_sees_a_long_module_a_long_function_and_a_stale_or_wrong_exemption(tmp_path):
    """Each rule can fail: on a fake package, a module of 12 lines, a function of 6, an exempt Python function
    and an exempt kernel function within the bound are reported; a long exempt kernel function is not."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "long.py").write_text("\n".join(f"x{i} = {i}" for i in range(12)) + "\n")
    (pkg / "funcs.py").write_text(
        "def short():\n    return 1\n\n\n"
        "def long():\n" + "".join(f"    a{i} = {i}\n" for i in range(5)) + "\n\n"
        "@_jit\ndef kernel():\n" + "".join(f"    b{i} = {i}\n" for i in range(6)) + "\n\n"
        "def python():\n" + "".join(f"    c{i} = {i}\n" for i in range(6)) + "\n\n"
        "@njit(cache=True)\ndef small():\n    return 0\n")
    exempt = {"pkg/funcs.py::kernel": "a kernel", "pkg/funcs.py::python": "not compiled",
              "pkg/funcs.py::small": "shrunk", "pkg/funcs.py::gone": "removed"}
    found = oversized(tmp_path, "pkg", module_lines=10, function_lines=5, exempt=exempt)
    assert found == ["pkg/funcs.py: 34 lines (at most 10: split it along its seams)",
                     "pkg/funcs.py:5: long is 6 lines (at most 5: split it into named steps)",
                     "pkg/funcs.py::python: exempt as a kernel function, but not compiled by a jit",
                     "pkg/funcs.py::small: 2 lines, within the bound: its exemption is stale",
                     "pkg/long.py: 12 lines (at most 10: split it along its seams)",
                     "pkg/funcs.py::gone: exempt, but no such function"]
