"""Numbers and tables as the report's Markdown text (pure string functions)."""

from __future__ import annotations

from typing import Any

import numpy as np


def number(v: float | None, digits: int = 4) -> str:
    """``v`` with ``digits`` significant digits, ``–`` when missing or not finite."""
    return "–" if v is None or not np.isfinite(v) else f"{v:.{digits}g}"


def difference(v: float | None, unit: str = "", rel: float | None = None) -> str:
    """A signed difference, rounded to 3 significant digits (``+0`` below 1e-9), with its unit and,
    when given, the relative difference [%] to 2 digits."""
    if v is None or not np.isfinite(v):
        return "–"
    txt = "+0" if abs(v) < 1e-9 else f"{v:+.3g}"
    txt += f" {unit}" if unit else ""
    if rel is not None and np.isfinite(rel):
        txt += f" ({'+0' if abs(rel) < 1e-9 else f'{rel:+.2g}'} %)"
    return txt


def header_cell(label: str, unit: str) -> str:
    """A table header ``label [unit]`` (the label alone without a unit)."""
    return f"{label} [{unit}]" if unit else label


def table(header: list[str], rows: list[list[Any]]) -> str:
    """A Markdown table (cells as ``str``)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)
