"""Docstrings and comments describe the code, not its history: no docstring or comment of pipeline/, tests/,
benchmarks/ or the scripts of docs/ cites a numbered issue of the project's tracker (a clone does not have it),
opens with "Before:" (the behaviour a change removed: a test states what it checks and why), or cites a source
line by its number (lines move: cite the function). The docs pages themselves are checked by test_docs.py."""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: The folders whose Python files are scanned
FOLDERS = ("pipeline", "tests", "benchmarks", "docs")

#: What tells history, not the code: a tracker's issue number, a "Before:" sentence, a source line's number
#: (``<module>.py:<n>``, ``<module>.py, lines <n>-<m>``, ``line <n>`` of two digits or more). A line of a data
#: file or of a user's scene file ("non-numeric value on line 3") is in a message, not a docstring or comment.
HISTORY = re.compile(r"\bissues? #?\d+|(?:^|[.:;]\s+)Before:|\b[\w/.-]+\.py(?::|,? lines? )\d+|\blines? \d{2,}\b",
                     re.I | re.M)


def comments_and_docstrings(source: str) -> list[tuple[int, str]]:
    """``(line number, text)`` of each comment and each docstring line (module, class, function) of ``source``."""
    found = [(tok.start[0], tok.string) for tok in tokenize.generate_tokens(io.StringIO(source).readline)
             if tok.type == tokenize.COMMENT]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str):
                found += [(first.lineno + i, line) for i, line in enumerate(first.value.value.splitlines())]
    return sorted(found)


def history_citations(source: str) -> list[str]:
    """``"<line>: <match>"`` for each citation of :data:`HISTORY` in the comments and docstrings of ``source``."""
    return [f"{number}: {m.group(0).strip()}" for number, text in comments_and_docstrings(source)
            for m in HISTORY.finditer(text.strip())]


def test_no_docstring_or_comment_tells_history_or_cites_line_numbers():
    # (not what a run writes: `make bench`'s A/B checkout of an older commit lies in benchmarks/results/, which
    # ruff leaves out too: pyproject.toml's extend-exclude)
    files = [p for folder in FOLDERS for p in sorted((ROOT / folder).rglob("*.py"))
             if "results" not in p.relative_to(ROOT).parts]
    assert len(files) > 200
    found = [f"{p.relative_to(ROOT)}:{hit}" for p in files
             for hit in history_citations(p.read_text(encoding="utf-8"))]
    assert not found, "docstrings and comments that cite history or line numbers:\n" + "\n".join(found)


def test_the_check_sees_each_kind_and_leaves_messages_and_prose_alone():
    cited = (f'"""Is{""}sue 36: the table moved."""\n'
             "def f():\n"
             f'    """Bef{""}ore: it hung."""\n'
             f"    # see pipeline/model/dynamics.py:{268} and dynamics.py, lines {292}-294\n"
             f"    return 'issue {12}'  # the step's control, line {1234} of the kernel\n")
    assert [hit.split(": ", 1)[1] for hit in history_citations(cited)] == [
        f"Is{''}sue 36", f"Bef{''}ore:", f"pipeline/model/dynamics.py:{268}", f"dynamics.py, lines {292}",
        f"line {1234}"]
    fine = ('"""What it was before: nothing (a sentence, not a heading); the issue of a magazine."""\n'
            "def f():\n"
            "    raise ValueError('rec.csv: non-numeric value on line 3')  # the message names the file's line\n")
    assert history_citations(fine) == []
