"""The free parameters of a parameter study (``hdi identify``, ``hdi sensitivity``): any numeric scene key
``section.key`` or an element of a list key ``section.key[i]`` (``air_bearing.frequencies_khz[0]``), with bounds
(:class:`Parameter`, read from a scene's list by :func:`parse_parameters`); its value in a scene (:func:`scene_value`)
and a candidate, the base scene with the parameters set (:func:`with_values`). Keys added to
:data:`pipeline.config.scene.SCHEMA` later need no change here; the rest of a study: :mod:`pipeline.analyses.study`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, Sequence


from ..config.schema import SCHEMA, SceneError, unit_suffix
from ..units import cf_unit


_KEY_RE = re.compile(r"([a-z_]+)\.([a-z0-9_]+)(?:\[(\d+)\])?")


# ------------------------------------------------------------------------------------ parameters
@dataclass(frozen=True)
class Parameter:
    """A free scene key with bounds.

    Attributes
    ----------
    name : ``"section.key"`` or ``"section.key[i]"``
    low, high : bounds, in the key's own unit (the unit is part of the key's name)
    """

    name: str
    low: float
    high: float

    @property
    def parts(self) -> tuple[str, str, int | None]:
        m = _KEY_RE.fullmatch(self.name)
        assert m is not None  # checked by parse_parameters
        return m.group(1), m.group(2), None if m.group(3) is None else int(m.group(3))

    @property
    def doc(self) -> str:
        section, key, _ = self.parts
        return SCHEMA[section][key].doc

    @property
    def units(self) -> str:
        """The CF (UDUNITS) unit of the key, from its unit suffix by the units table (``"1"`` without one)."""
        return cf_unit(unit_suffix(self.parts[1]))

    @property
    def var_name(self) -> str:
        """NetCDF-safe variable name: ``air_bearing.frequencies_khz[0]`` -> ``air_bearing__frequencies_khz_0``."""
        return re.sub(r"\[(\d+)\]", r"_\1", self.name).replace(".", "__")


def parse_parameters(items: Any, where: str, field: str) -> list[Parameter]:
    """Validate a list of ``{key = "section.key[i]", low = ..., high = ...}`` tables.

    Raises
    ------
    SceneError
        Naming ``where`` (the scene file) and ``field`` (``identify.parameters``) for a key that is not
        a numeric scene key, an index outside the list, bounds that are not numbers with low < high,
        or a repeated key.
    """
    if not isinstance(items, list) or not items:
        raise SceneError(f"{where}: {field}: expected a non-empty list of tables "
                         "{key = \"section.key\", low = ..., high = ...}")
    out: list[Parameter] = []
    for i, item in enumerate(items):
        at = f"{where}: {field}[{i}]"
        if not isinstance(item, dict) or set(item) != {"key", "low", "high"}:
            raise SceneError(f"{at} = {item!r}: expected a table {{key = \"section.key\", low = ..., high = ...}}")
        name = item["key"]
        m = _KEY_RE.fullmatch(name) if isinstance(name, str) else None
        if m is None:
            raise SceneError(f"{at}.key = {name!r}: expected \"section.key\" or \"section.key[i]\"")
        section, key, index = m.group(1), m.group(2), m.group(3)
        spec = SCHEMA.get(section, {}).get(key)
        if spec is None:
            raise SceneError(f"{at}.key = {name!r}: not a scene key (no {section}.{key} in the schema)")
        if index is None and spec.kind != "float":
            raise SceneError(f"{at}.key = {name!r}: {section}.{key} is a {spec.kind!r} key; expected a number "
                             "key (or an element of a list of numbers, section.key[i])")
        if index is not None and (spec.kind != "floats" or (spec.length is not None and int(index) >= spec.length)):
            raise SceneError(f"{at}.key = {name!r}: expected an index into a list of numbers "
                             f"(length {spec.length})")
        lo, hi = item["low"], item["high"]
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in (lo, hi)) \
                or not lo < hi:
            raise SceneError(f"{at}: low = {lo!r}, high = {hi!r}: expected finite numbers with low < high")
        if any(p.name == name for p in out):
            raise SceneError(f"{at}.key = {name!r}: repeated")
        out.append(Parameter(name, float(lo), float(hi)))
    return out


def scene_value(scene: Any, p: Parameter) -> float:
    """The current value of parameter ``p`` in ``scene`` (NaN when the key is unset)."""
    section, key, index = p.parts
    v = scene[section][key]
    if v is None:
        return float("nan")
    return float(v[index] if index is not None else v)


def with_values(scene: Any, params: Sequence[Parameter], values: Sequence[float]) -> Any:
    """A validated copy of ``scene`` with the parameters set to ``values``."""
    changes: dict[str, dict[str, Any]] = {}
    for p, v in zip(params, values):
        section, key, index = p.parts
        sec = changes.setdefault(section, {})
        if index is None:
            sec[key] = float(v)
        else:
            lst = list(sec.get(key, scene[section][key]))
            lst[index] = float(v)
            sec[key] = lst
    return scene.replace(**changes)
