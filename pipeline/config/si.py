"""The scene in SI units: frozen, named parameter groups, one per section (``to_si``).

A scene key carries its unit in its name (``flying_height_nm``, ``frequencies_khz``); :func:`to_si`
returns each section as a frozen group whose fields drop the suffix and hold SI values
(``to_si(scene).air_bearing.flying_height`` [m], ``.frequencies`` [Hz]), by the one units table
(:func:`pipeline.units.to_si_value`). Keys without a unit keep their name and value; lists of
numbers convert elementwise; tables and strings are kept as they are. ``dmw.rpm`` has no unit suffix and
stays in rev/min: the disk speed is its one conversion (:func:`pipeline.model.dmw_record.disk_speed_m_s`).

Two keys of one section that differ only by their unit suffix get distinct SI names from
:data:`SI_NAMES` (``dmw.sample_rate_mhz``, the synthesis rate, and ``dmw.sample_rate_hz``, a measured
record's own rate); any other collision is a schema error and raises rather than overwrite.
"""

from __future__ import annotations

from typing import Any, Mapping

from ..units import si_factor, to_si_value
from .schema import strip_unit


#: SI names of keys that would collide with another key of their section once the suffix is dropped.
SI_NAMES = {("dmw", "sample_rate_hz"): "record_sample_rate", ("touchdown", "onset_mw"): "onset_power",
            ("touchdown", "previous_mw"): "previous_power"}


class Group(Mapping):
    """One section in SI units (or, with an empty name, the scene as a group of sections): read-only,
    by attribute (``group.flying_height``) or item. Values are converted when read, from the scene's own
    mapping, so a reader is seen reading exactly the keys it uses (tests/structure/test_stage_reads.py)."""

    __slots__ = ("_section", "_values", "_convert")

    def __init__(self, section: str, values: Mapping[str, Any], convert=None):
        object.__setattr__(self, "_section", section)
        object.__setattr__(self, "_values", values)
        object.__setattr__(self, "_convert", convert)

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            if not self._section:  # the scene itself: a group of sections
                raise AttributeError(f"the scene has no section [{name}]") from None
            raise AttributeError(f"[{self._section}] has no key {name!r} in SI form; "
                                 f"it has {sorted(self._values)}") from None

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"[{self._section or 'scene'}] in SI form is read-only")

    def __getitem__(self, name: str) -> Any:
        return self._values[name] if self._convert is None else self._convert(name)

    def __iter__(self):
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"Group({self._section!r}, {sorted(self._values)!r})"


def _convert(value: Any, suffix: str) -> Any:
    if isinstance(value, bool) or value is None:
        return value
    if isinstance(value, (int, float)):
        return to_si_value(value, suffix)
    if isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return tuple(to_si_value(v, suffix) for v in value)
    return value


def section_si(section: str, values: Mapping[str, Any]) -> Group:
    """One scene section in SI units (see the module docstring); each key is read from ``values`` when
    its SI name is read."""
    keys: dict[str, tuple[str, str | None]] = {}
    for key in values.keys():
        name, suffix = strip_unit(key)
        name = SI_NAMES.get((section, key), name)
        if name in keys:
            raise ValueError(f"[{section}] {key}: its SI name {name!r} collides with another key of the section")
        if suffix is not None:
            si_factor(suffix)  # (an unknown suffix fails here, naming the known ones)
        keys[name] = (key, suffix)

    def convert(name: str) -> Any:
        key, suffix = keys[name]
        return values[key] if suffix is None else _convert(values[key], suffix)

    return Group(section, keys, convert)


def to_si(scene: Any) -> Group:
    """The scene's sections as frozen groups in SI units (module docstring): ``to_si(scene).tfc.protrusion``."""
    return Group("", {s: None for s in scene.config}, lambda s: section_si(s, scene[s]))


#: The ``si`` attribute of a scene (:class:`pipeline.config.validation.Scene`,
#: :class:`pipeline.config.fields.DeclaredScene`): the scene in SI units, :func:`to_si` (read through the
#: scene, so a declared scene's SI view reads only its declared keys).
SI_VIEW = property(lambda scene: to_si(scene), doc="The scene in SI units (pipeline.config.si.to_si).")


def si_value(si: Group, field: str) -> Any:
    """The value of the SI view ``si`` (:func:`to_si`) a field names, ``"section.name"`` (the SI name: a
    registry entry's parameter, :attr:`pipeline.physics.variants.Entry.parameters`)."""
    section, _, name = field.partition(".")
    return si[section][name]
