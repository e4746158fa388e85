"""The pipeline's stages: each module exposes ``run(scene, out, **options) -> Path``.

:func:`ensure` runs a stage only when its dataset is missing or was made from other inputs
(DESIGN.md: stages whose outputs are present and whose inputs have not changed are not recomputed).
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from ..io import is_current


def ensure(stage: str, scene: Any, out: Path, force: bool = False) -> Path:
    """Path of ``out/<stage>.nc``, running the stage first if it is missing or stale."""
    path = Path(out) / f"{stage}.nc"
    if force or not is_current(path, scene, stage):
        importlib.import_module(f"pipeline.stages.{stage}").run(scene, Path(out))
    return path
