"""Declared reads: the scene keys a computation reads, named as the schema names them, and a scene that
allows only those.

A model builder declares the keys it reads next to the function that reads them (a module-level
``FIELDS``, built by :func:`fields`: each item a key of :data:`pipeline.config.schema.SCHEMA`, ``"section.key"``
as a scene file writes it, or ``"scene.effects"``); a stage declares the union of its builders' fields and
its own (:attr:`pipeline.runner.Stage.reads`). The runner hashes exactly those keys into the stage's inputs key,
and the stage's ``compute`` reads the scene through :class:`DeclaredScene`: reading a key outside the
declaration raises :class:`UndeclaredRead`, naming the stage and the key, so a declaration cannot fall
behind the code silently (a key read but not hashed would leave a stale result looking current).
"""

from __future__ import annotations

from typing import Any, Iterable, Iterator, Mapping

from .schema import SCHEMA, scene_key
from .si import SI_VIEW


class UndeclaredRead(Exception):
    """A computation read a scene key it did not declare (:class:`DeclaredScene`). No ``KeyError``: a reader
    that takes a default for an absent key must not take one for an undeclared key."""


def fields(*keys: str) -> tuple[str, ...]:
    """``keys`` checked against the schema and without repeats, in order: a declaration of the scene keys
    a computation reads (``"section.key"``; ``"section.*"``: every key the section has when it is read, so
    keys a registry adds to a section, like a target's settings in ``[identify]``, are in it:
    :func:`expand`).

    Raises
    ------
    ValueError
        For an item that is no key of the schema.
    """
    for item in keys:
        section, _, key = item.partition(".")
        if section not in SCHEMA or (key != "*" and key not in SCHEMA[section]):
            raise ValueError(f"declared field {item!r}: no key of the scene schema (pipeline/config/schema.py)")
    return tuple(dict.fromkeys(keys))


def expand(declaration: Iterable[str]) -> tuple[str, ...]:
    """The keys of a declaration (:func:`fields`), each ``"section.*"`` as every key the schema has now."""
    out: list[str] = []
    for item in declaration:
        section, _, key = item.partition(".")
        out.extend(f"{section}.{k}" for k in SCHEMA[section]) if key == "*" else out.append(item)
    return tuple(dict.fromkeys(out))


def section_fields(section: str, *but: str) -> tuple[str, ...]:
    """Every key of ``section`` but the keys ``but`` (names within the section), as :func:`fields` gives them."""
    unknown = [key for key in but if key not in SCHEMA.get(section, {})]
    if unknown:
        raise ValueError(f"section_fields({section!r}): {unknown} are no keys of [{section}]")
    return tuple(f"{section}.{key}" for key in SCHEMA[section] if key not in but)


def union(*declarations: Iterable[str]) -> tuple[str, ...]:
    """The fields of several declarations together (:func:`fields` of all their items)."""
    return fields(*(item for declaration in declarations for item in declaration))


def parameter_fields(entries: Iterable[Any]) -> tuple[str, ...]:
    """The scene keys the registry entries' behaviours take (:attr:`pipeline.physics.variants.Entry.parameters`,
    named by their SI names: :func:`pipeline.config.schema.scene_key`)."""
    return fields(*dict.fromkeys(scene_key(where) for entry in entries for _, where in entry.parameters))


class DeclaredSection(Mapping):
    """One section of a :class:`DeclaredScene`: its declared keys read as the scene's, any other refused."""

    __slots__ = ("_owner", "_section", "_values")

    def __init__(self, owner: "DeclaredScene", section: str, values: Mapping[str, Any]):
        self._owner, self._section, self._values = owner, section, values

    def __getitem__(self, key: str) -> Any:
        self._owner.check(f"{self._section}.{key}")
        return self._values[key]

    def get(self, key: str, default: Any = None) -> Any:
        return self[key] if key in self._values else default

    def __contains__(self, key: object) -> bool:
        return key in self._values

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __eq__(self, other: object) -> bool:
        return dict(self.items()) == other

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"DeclaredSection({self._section!r}, reader={self._owner.reader!r})"


class DeclaredScene:
    """A scene (:class:`pipeline.config.validation.Scene`) as one reader may read it: only the keys it
    declared (``allowed``, :func:`fields`); ``scene.effects`` (and :meth:`has`) is the key ``"scene.effects"``.
    Its name, path, overrides and identity (``hash``, ``to_toml_text``: provenance) are the whole scene's;
    :meth:`replace` gives the varied scene under the same declaration.

    Raises
    ------
    UndeclaredRead
        When a key outside the declaration is read, naming the reader and the key.
    """

    __slots__ = ("scene", "reader", "allowed")

    def __init__(self, scene: Any, reader: str, allowed: Iterable[str]):
        self.scene = scene.scene if isinstance(scene, DeclaredScene) else scene
        self.reader = reader
        self.allowed = frozenset(allowed)

    def __getstate__(self) -> tuple:
        return self.scene, self.reader, self.allowed

    def __setstate__(self, state: tuple) -> None:
        self.scene, self.reader, self.allowed = state

    def check(self, key: str) -> None:
        """Refuse ``key`` (``"section.key"``) when the reader did not declare it (nor its whole section)."""
        if key not in self.allowed and f"{key.partition('.')[0]}.*" not in self.allowed:
            raise UndeclaredRead(f"{self.reader} read the scene key {key}, which it does not declare: add it to "
                                 f"its declared fields (the stage's reads, or its model builders' FIELDS)")

    def __getitem__(self, section: str) -> DeclaredSection:
        return DeclaredSection(self, section, self.scene[section])

    @property
    def effects(self) -> frozenset[str]:
        self.check("scene.effects")
        return self.scene.effects

    def has(self, effect: str) -> bool:
        """Whether the scene asks for ``effect`` (reads ``scene.effects``)."""
        return effect in self.effects

    #: the scene in SI units, read through the declaration (:data:`pipeline.config.si.SI_VIEW`)
    si = SI_VIEW

    @property
    def name(self) -> str:
        return self.scene.name

    @property
    def path(self) -> Any:
        return self.scene.path

    @property
    def overrides(self) -> Any:
        return self.scene.overrides

    @property
    def config(self) -> dict[str, dict[str, Any]]:
        """The declared keys only, ``section -> key -> value`` (a reader hashing what it reads)."""
        picked: dict[str, dict[str, Any]] = {}
        for section, values in self.scene.config.items():
            for key, value in values.items():
                if f"{section}.{key}" in self.allowed or f"{section}.*" in self.allowed:
                    picked.setdefault(section, {})[key] = value
        return picked

    @property
    def hash(self) -> str:
        return self.scene.hash

    def to_toml_text(self) -> str:
        return self.scene.to_toml_text()

    def replace(self, **sections: dict[str, Any]) -> "DeclaredScene":
        """:meth:`pipeline.config.validation.Scene.replace` of the scene, read under the same declaration."""
        return DeclaredScene(self.scene.replace(**sections), self.reader, self.allowed)

    def __eq__(self, other: object) -> bool:
        other = other.scene if isinstance(other, DeclaredScene) else other
        return self.scene == other

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"DeclaredScene({self.name!r}, reader={self.reader!r}, {len(self.allowed)} keys)"


def whole(scene: Any) -> Any:
    """The scene behind a :class:`DeclaredScene` (a scene as it is otherwise)."""
    return scene.scene if isinstance(scene, DeclaredScene) else scene
