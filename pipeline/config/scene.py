"""Scene files: load, validate and override a TOML scene (the names users import).

A scene is one TOML file with the sections of docs/model.md and docs/cli.md. Units are part of the key names
(``flying_height_nm``), so a key with the right quantity in another unit (``flying_height_um``)
is reported as a unit error rather than silently misread. Every key has a documented default
(the paper scene's value), so a scene only states what it changes; a disabled effect's inputs
are never required.

Validation errors are :class:`SceneError` and always name the file, the ``section.key`` and
what was expected.

This module gathers the public names of three: the schema (:mod:`pipeline.config.schema`: :data:`SCHEMA`,
:class:`Key`, :class:`SceneError`, ``hdi --help-keys``), validation (:mod:`pipeline.config.validation`:
:class:`Scene`, :func:`validate`) and loading (:mod:`pipeline.config.loading`: :func:`load_scene`,
``extends``, ``--set``).
"""

from __future__ import annotations

from .loading import MAX_EXTENDS_DEPTH, load_scene, parse_override, scene_from_dict
from .schema import (DMW_EXPONENT_BOUNDS, DMW_RMS_BOUNDS_NM, EFFECTS, FREE_LIMITS, PROTOCOLS, SCHEMA, UNIT_SUFFIXES,
                     Key, SceneError, describe_keys, strip_unit, target_keys, unit_suffix)
from .validation import MIN_STEADY_SAMPLES, Scene, check_value, validate

__all__ = [
    "DMW_EXPONENT_BOUNDS", "DMW_RMS_BOUNDS_NM", "EFFECTS", "FREE_LIMITS", "MAX_EXTENDS_DEPTH", "MIN_STEADY_SAMPLES",
    "PROTOCOLS", "SCHEMA", "UNIT_SUFFIXES", "Key", "Scene", "SceneError", "check_value", "describe_keys",
    "load_scene", "parse_override", "scene_from_dict", "strip_unit", "target_keys", "unit_suffix", "validate",
]
