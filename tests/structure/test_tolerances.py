"""Every tight floating-point tolerance of the suite says why it holds (docs/testing.md).

A relative tolerance below :data:`TIGHT` (``rtol=`` / ``rel=`` of ``numpy.testing.assert_allclose``,
``numpy.isclose``, ``numpy.allclose``, ``math.isclose`` or ``pytest.approx``; ``assert_allclose``
without ``rtol`` nor ``atol``, whose default is 1e-7; an exact ``rtol=0`` with no ``atol``) holds on every host only
when the numbers it compares are bit-identical (the same operations in the same order) or when it follows
a stated error bound (the conditioning of the quantity times the rounding of the operations that made
it). Such a comparison carries the marker ``# tol: <why>`` on one of the lines of its statement or on
the comment lines directly above it; this test lists each one without it as ``file:line``.

The test reads the sources with :mod:`ast`: a tolerance that is a literal number (or an arithmetic
expression of literals, ``2 * 1e-9``) is judged; a tolerance computed at run time (a named bound) is
taken to follow that computation.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: A relative tolerance below this needs the marker: about 4.5e9 units of float64 rounding (2.2e-16),
#: more than any few-operation path's rounding and less than most iterative or tabulated quantities'.
TIGHT = 1e-6
#: The marker of a justified tolerance; the justification follows it on the same comment.
MARKER = re.compile(r"#\s*tol:\s*\S+")
#: The calls whose relative tolerance is read, with its keyword and its default (``None``: no default
#: that could be tight); ``math.isclose`` is read as :data:`MATH_ISCLOSE`.
CALLS = {"assert_allclose": ("rtol", 1e-7), "isclose": ("rtol", None), "allclose": ("rtol", None),
         "approx": ("rel", None)}
MATH_ISCLOSE = ("rel_tol", 1e-9)


def _number(node: ast.AST) -> float | None:
    """The value of a literal number or an arithmetic expression of literals, else ``None``."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return float(node.value)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
        v = _number(node.operand)
        return None if v is None else (v if isinstance(node.op, ast.UAdd) else -v)
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div, ast.Pow)):
        a, b = _number(node.left), _number(node.right)
        if a is None or b is None or (isinstance(node.op, ast.Div) and b == 0):
            return None
        return a * b if isinstance(node.op, ast.Mult) else a / b if isinstance(node.op, ast.Div) else a ** b
    return None


def _name(call: ast.Call) -> str:
    f = call.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""


def tight_calls(tree: ast.AST) -> list[tuple[ast.Call, float]]:
    """Each comparison call of ``tree`` with a literal relative tolerance below :data:`TIGHT`, with it."""
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call) or _name(node) not in CALLS:
            continue
        key, default = CALLS[_name(node)]
        if isinstance(node.func, ast.Attribute) and getattr(node.func.value, "id", "") == "math":
            key, default = MATH_ISCLOSE
        kw = {k.arg: k.value for k in node.keywords if k.arg}
        if key in kw:
            rtol = _number(kw[key])
            if rtol is None:
                continue
            if rtol == 0.0 and any(_number(kw[a]) != 0.0 for a in ("atol", "abs", "abs_tol") if a in kw):
                continue  # an absolute tolerance alone: its bound is in the numbers' own unit, not judged here
        elif default is not None and not {"atol", "abs_tol"} & set(kw):  # (with an atol, the default rtol is not the bound)
            rtol = default
        else:
            continue
        if rtol < TIGHT:
            found.append((node, rtol))
    return found


def _statements(tree: ast.AST) -> list[ast.stmt]:
    return [n for n in ast.walk(tree) if isinstance(n, ast.stmt)]


def unjustified(source: str, name: str) -> list[str]:
    """``name:line`` and the tolerance of each tight comparison of ``source`` without the marker on its
    statement's lines or on the comment lines directly above that statement."""
    tree = ast.parse(source)
    lines = source.splitlines()
    simple = [s for s in _statements(tree) if not hasattr(s, "body")]
    out = []
    for call, rtol in sorted(tight_calls(tree), key=lambda found: found[0].lineno):
        around = [s for s in simple if s.lineno <= call.lineno and call.end_lineno <= s.end_lineno]
        stmt = min(around, key=lambda s: s.end_lineno - s.lineno) if around else call
        first, last = stmt.lineno, stmt.end_lineno
        while first > 1 and lines[first - 2].lstrip().startswith("#"):
            first -= 1
        if not any(MARKER.search(line) for line in lines[first - 1:last]):
            out.append(f"{name}:{call.lineno}: {_name(call)} with a relative tolerance of {rtol:g}")
    return out


def test_every_tight_tolerance_of_the_suite_says_why_it_holds():
    found = []
    for path in sorted((ROOT / "tests").rglob("*.py")):
        if "__pycache__" not in path.parts:
            found += unjustified(path.read_text(), str(path.relative_to(ROOT)))
    assert not found, (f"{len(found)} tolerance(s) below {TIGHT:g} without a '# tol: <why>' comment "
                       "(docs/testing.md):\n" + "\n".join(found))


def test_the_check_finds_a_tight_tolerance_without_its_reason():
    """The check cannot pass by reading nothing: each form is found, each marked one is not, a loose,
    an absolute and a computed tolerance are left alone."""
    source = (
        "import numpy as np, pytest\n"
        "def test_x(a, b, bound):\n"
        "    np.testing.assert_allclose(a, b, rtol=1e-9)\n"           # 3: found
        "    np.testing.assert_allclose(a, b)\n"                      # 4: found (default 1e-7)
        "    assert a == pytest.approx(b, rel=2 * 1e-12)\n"           # 5: found
        "    assert np.isclose(a, b, rtol=0)\n"                        # 6: found (exact)
        "    # tol: the same operations on both sides\n"
        "    assert a == pytest.approx(b, rel=1e-15)\n"               # 8: marked above
        "    np.testing.assert_allclose(a, b,\n"
        "                               rtol=1e-12)  # tol: ten operations of eps\n"  # 9-10: marked on the statement
        "    assert a == pytest.approx(b, rel=1e-3)\n"                # loose
        "    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)\n"   # absolute
        "    np.testing.assert_allclose(a, b, rtol=bound)\n"          # computed
        "    assert a == pytest.approx(b)\n"                          # default 1e-6
        "    # a comment that is no reason\n"
        "    assert a == pytest.approx(b, rel=1e-10)\n"               # 16: found
        "    assert math.isclose(a, b)\n"                              # 17: found (default 1e-9)
        "    np.testing.assert_allclose(a, b, atol=1e-3)\n"            # an absolute bound
    )
    lines = [line.split(":")[1] for line in unjustified(source, "t.py")]
    assert lines == ["3", "4", "5", "6", "16", "17"]
