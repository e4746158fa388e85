"""The scene part of a stage's inputs key (:func:`scene_part` of its declared keys), the digest of a key's
payload, and the key a dataset carries: the pieces of the inputs keys of :class:`pipeline.runner.Runner`.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any, Iterable

from .config.fields import expand
from .io import KEY_ATTR, DatasetBusy, read_attrs

Scene = Any

#: Global attribute of a stage's first dataset: JSON list of the outputs this computation produced.
OUTPUTS_ATTR = "stage_outputs"

#: Keys of the synthetic DMW record, which a measured record (``dmw.source`` a file) leaves unused:
#: keyed, ``--set dmw.rms_nm`` recomputed the whole chain to identical results.
SYNTHESIS_ONLY = ("dmw.rms_nm", "dmw.exponent", "dmw.seed")


def unused_keys(scene: Scene, reads: Iterable[str] = ("dmw.source",)) -> tuple[str, ...]:
    """Keys of ``reads`` this scene states but nothing reads: the synthesis keys of a measured DMW record
    (when ``reads`` holds ``dmw.source``, which says which)."""
    if "dmw.source" in reads and scene["dmw"]["source"] != "synthetic":
        return SYNTHESIS_ONLY
    return ()


def scene_part(scene: Scene, reads: Iterable[str]) -> dict[str, Any]:
    """The scene keys ``reads`` (a declaration, :func:`pipeline.config.fields.fields`: a stage's
    :meth:`Stage.keyed`), JSON-normalised, without the :func:`unused_keys` of the scene: ``{"section.key": value}``."""
    reads = expand(reads)
    unused = set(unused_keys(scene, reads))
    picked: dict[str, Any] = {}
    for item in reads:
        section, _, key = item.partition(".")
        if item in unused or key not in scene[section]:
            continue
        picked[item] = json.loads(json.dumps(scene[section][key], default=str))
    return picked


def digest(payload: Any) -> str:
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()


def dataset_key(path: Path) -> tuple[str | None, list[str] | None]:
    """The ``inputs_key`` and produced-outputs list of a dataset (``None`` when unreadable)."""
    try:
        attrs, _ = read_attrs(path)
    except DatasetBusy:  # (not "no inputs key": the dataset would be replaced under its writer)
        raise
    except (OSError, ValueError, RuntimeError):  # (RuntimeError: the HDF5 library's "HDF error", a damaged header)
        return None, None
    outputs = attrs.get(OUTPUTS_ATTR)
    return attrs.get(KEY_ATTR), (json.loads(outputs) if outputs else None)
