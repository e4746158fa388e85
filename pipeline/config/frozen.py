"""The read-only containers of a loaded scene: its sections and the tables inside them
(:class:`FrozenSection`, a ``dict``), its lists (:class:`FrozenList`, a ``list``), at any depth; every change
in place raises a ``TypeError`` that names the way to vary a scene
(:meth:`pipeline.config.validation.Scene.replace`)."""

from __future__ import annotations

import copy
from typing import Any


class _ReadOnly:
    """What the read-only containers of a scene share: the section they belong to (named in the error) and
    the change that raises the ``TypeError`` naming the way to vary a scene, :meth:`pipeline.config.validation.Scene.replace`."""

    __slots__ = ()
    _name: str | None

    def __init__(self, items: Any = (), name: str | None = None) -> None:
        super().__init__(items)  # type: ignore[call-arg]
        self._name = name

    def _readonly(self, *args: Any, **kwargs: Any) -> None:
        sec = self._name or "section"
        raise TypeError(f"a loaded scene is read-only: scene[{sec!r}] cannot be changed in place; vary it with "
                        f"scene.replace({sec}={{key: value}}), which returns a new scene validated like --set")


class FrozenSection(_ReadOnly, dict):
    """A read-only ``dict``: a section of a :class:`pipeline.config.validation.Scene` (and the table of its sections, and the tables
    inside a section's lists: ``identify.parameters``, ``sweep.roughness``).

    Reading is a ``dict``'s (same speed, same JSON, ``isinstance(..., dict)``); every change raises a
    ``TypeError`` that names the way to vary a scene, :meth:`pipeline.config.validation.Scene.replace`. ``dict(section)`` is a
    mutable copy.
    """

    __slots__ = ("_name",)
    __setitem__ = __delitem__ = update = pop = popitem = clear = setdefault = __ior__ = _ReadOnly._readonly  # type: ignore

    def __reduce__(self) -> tuple:
        # (pickled to dask workers and deep-copied: rebuilt whole, never item by item through __setitem__)
        return (type(self), (dict(self), self._name))


class FrozenList(_ReadOnly, list):
    """A read-only ``list``: a list inside a :class:`pipeline.config.validation.Scene` (``scene.effects``, ``air_bearing.frequencies_khz``,
    the tables of ``identify.parameters``), at any depth.

    Reading is a ``list``'s (same JSON, ``== [...]``, ``isinstance(..., list)``, so every reader and the scene's
    hash and text are those of a list); every change in place raises the ``TypeError`` of
    :class:`FrozenSection`. ``list(value)`` is a mutable copy; ``value + [...]`` a new (mutable) list.
    """

    __slots__ = ("_name",)
    __setitem__ = __delitem__ = __iadd__ = __imul__ = append = extend = insert = pop = remove = clear = \
        sort = reverse = _ReadOnly._readonly  # type: ignore

    def __reduce__(self) -> tuple:
        # (rebuilt whole: a list subclass's default pickling and deepcopy restore the items through extend)
        return (type(self), (list(self), self._name))

    def __reduce_ex__(self, protocol: Any) -> tuple:
        return self.__reduce__()


def freeze(value: Any, name: str | None = None) -> Any:
    """``value`` with every ``dict`` in it (at any depth) a :class:`FrozenSection` and every ``list`` a
    :class:`FrozenList`: nothing of a scene changes in place."""
    if isinstance(value, dict):
        return FrozenSection({k: freeze(v, k if name is None else name) for k, v in value.items()}, name)
    if isinstance(value, list):
        return FrozenList([freeze(v, name) for v in value], name)
    return value


def thaw(value: Any) -> Any:
    """A mutable deep copy of a (frozen) configuration: plain ``dict``s and ``list``s."""
    if isinstance(value, dict):
        return {k: thaw(v) for k, v in value.items()}
    if isinstance(value, list):
        return [thaw(v) for v in value]
    return copy.deepcopy(value)
