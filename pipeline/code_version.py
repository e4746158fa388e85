"""The code a stage runs, as part of its inputs key: the bytes of the ``pipeline`` modules it imports.

A result depends on the code that computed it as much as on the scene and the files. Keying a stage
on a hand-bumped ``version`` alone let a corrected formula in :mod:`pipeline.physics` leave every old
result "up to date". :func:`code_key` hashes the source of a module and of every ``pipeline`` module it
imports, directly or not, at module level or inside a function (a lazy import is an import): editing
the friction law recomputes the stages that simulate, not the roughness stage; editing a figure
recomputes the report only.

The imports are read from the source text (``from .x import a``, ``from .. import units``,
``from pipeline.x import ...``, ``import pipeline.x``), not by parsing it: the whole package parses in
0.2 s, which every ``hdi`` command would pay. The scan of a text is kept per process, keyed by the text
itself (a file edited while the process runs is scanned again, whatever its size and time), and the files
are found with plain string paths: the keys of the eight stages of ``hdi run`` take ~60 ms (0.35 s when
each stage scanned its modules again; docs/performance.md, section "The head of a command"). The scan is
conservative: an import written in a docstring counts too (a key that changes too often costs a
recomputation; one that changes too rarely returns a wrong result).

Left out: :data:`ORCHESTRATION`, the modules that decide when and where a stage runs, not what it
computes (the runner itself, which every stage imports for :class:`~pipeline.runner.Stage`, the
fan-out with its cluster side and the scheduler's check, the command line, its option checks and how they
name an option) and the Python API (:mod:`pipeline.api`, which calls
the runner as the command line does; the package re-exports it, so without this every stage, through
the package's ``__init__``, would be keyed on the whole package).
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import re
from functools import lru_cache
from pathlib import Path

PACKAGE = "pipeline"
ROOT = Path(__file__).resolve().parent
#: Modules whose code does not change a result (where and when a stage runs, not what it computes).
ORCHESTRATION = frozenset({"pipeline.runner", "pipeline.fanout", "pipeline.cluster", "pipeline.scheduler",
                           "pipeline.options", "pipeline.cli", "pipeline.cli_checks", "pipeline.api"})


@lru_cache(maxsize=None)
def _patterns(package: str) -> tuple[re.Pattern, re.Pattern]:
    """``from X import names`` (X relative or in ``package``; names possibly parenthesised over several
    lines) and ``import package.x``, at any indentation."""
    pkg = re.escape(package)
    return (re.compile(rf"^[ \t]*from[ \t]+(\.+[\w.]*|{pkg}(?:\.[\w.]+)?)[ \t]+import[ \t]+(\([^)]*\)|[^\n#]*)", re.M),
            re.compile(rf"^[ \t]*import[ \t]+({pkg}(?:\.\w+)*)", re.M))


def module_file(name: str, root: Path = ROOT, package: str = PACKAGE) -> Path | None:
    """The source file of module ``name`` of ``package`` (rooted at ``root``), or ``None``."""
    path = _module_path(name, str(root), package)
    return None if path is None else Path(path)


def _module_path(name: str, root: str, package: str) -> str | None:
    """:func:`module_file` as a string (no ``Path`` made: the keys of a command ask this ~4,000 times)."""
    if name != package and not name.startswith(package + "."):
        return None
    base = os.path.join(root, *name.split(".")[1:])
    for path in (base + ".py", os.path.join(base, "__init__.py")):
        if os.path.isfile(path):
            return path
    return None


@lru_cache(maxsize=1024)
def _scan(text: str, here: str, package: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The modules a source ``text`` (of a module whose package is ``here``) may import: the bases of its
    ``from`` imports and the names they import as submodules, then its ``import package.x``; unchecked
    against the files. A function of the text alone, so kept per text: the stages' keys share most modules."""
    from_, import_ = _patterns(package)
    bases, subs = [], []
    for where, names in from_.findall(text):
        base = importlib.util.resolve_name(where, here) if where.startswith(".") else where
        bases.append(base)
        for item in names.strip("()").replace("\n", " ").split(","):
            sub = item.split(" as ")[0].strip()
            if sub and sub != "*":
                subs.append(f"{base}.{sub}")  # (``from .. import units``: a module if its file exists)
    return tuple(bases) + tuple(import_.findall(text)), tuple(subs)


def imports(name: str, root: Path = ROOT, package: str = PACKAGE) -> set[str]:
    """The modules of ``package`` that module ``name`` imports (its source text, see module docstring)."""
    path = _module_path(name, str(root), package)
    if path is None:
        return set()
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    here = name if os.path.basename(path) == "__init__.py" else name.rpartition(".")[0]
    named, maybe = _scan(text, here, package)
    root_ = str(root)
    return {m for m in (*named, *maybe) if _module_path(m, root_, package) is not None}


def modules(name: str, root: Path = ROOT, package: str = PACKAGE) -> tuple[str, ...]:
    """``name`` and every module of ``package`` it imports, transitively, sorted; the
    :data:`ORCHESTRATION` modules (and what only they import) are left out."""
    seen: set[str] = set()
    todo = [name]
    while todo:
        mod = todo.pop()
        if mod in seen or mod in ORCHESTRATION or _module_path(mod, str(root), package) is None:
            continue
        seen.add(mod)
        todo.extend(imports(mod, root, package) - seen)
    return tuple(sorted(seen))


def source_key(name: str, root: Path = ROOT, package: str = PACKAGE) -> str:
    """SHA-256 of the source of module ``name`` and of every module :func:`modules` finds (names and
    bytes); ``""`` for a module outside the package (e.g. a stage declared by a test)."""
    found = modules(name, root, package)
    if not found:
        return ""
    digest = hashlib.sha256()
    for mod in found:
        digest.update(mod.encode() + b"\0" + module_file(mod, root, package).read_bytes() + b"\0")
    return digest.hexdigest()


@lru_cache(maxsize=None)
def code_key(name: str) -> str:
    """:func:`source_key` of a ``pipeline`` module, once per process (the code a process runs is the
    code it imported: a source edited while it runs is the next process's input)."""
    return source_key(name)
