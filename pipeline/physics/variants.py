"""One shape for the named model variants a scene key chooses (docs/model.md, section "Model variants").

A model variant is an entry of a :class:`Registry`: one registry per scene key (``contact.friction_law``,
``air_bearing.rear_law``, ...), name -> entry. Every entry carries

* ``summary``: one line saying what it does (``hdi --help-keys`` and the variants table of docs/model.md
  show it);
* ``source``: where the law is stated (the docs/model.md section, the paper or the reference);
* ``parameters``: ``(keyword, "section.name")`` pairs, the scene values in SI units
  (:func:`pipeline.config.si.to_si`) the model passes the behaviour as those keywords; the behaviour
  itself reads no scene;
* ``behaviour``: what the choice does: a function (a friction law, an FHM measure), a value (a friction
  arm's fraction of the thickness) or an object (a compiled rear law's :class:`RearLaw
  <pipeline.physics.air_bearing.RearLaw>`, a TFC-point law's :class:`TfcLaw
  <pipeline.physics.tfc_laws.TfcLaw>`); ``None`` for an option that switches a part of the model off.

Every entry type is an :class:`Entry`: :class:`Variant` is the entry whose behaviour is one function or
value; the rear and TFC-point laws (:class:`RearLaw <pipeline.physics.air_bearing.RearLaw>`,
:class:`TfcLaw <pipeline.physics.tfc_laws.TfcLaw>`) put the kernel's fields first and are their own
behaviour. :meth:`Registry.lookup` is the one lookup
of a name (one line naming the scene key, the value and the names registered). The registry is the
scene key's list of choices, read live (:mod:`pipeline.config.schema`): a registered entry is a choice.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Generic, TypeVar


@dataclass(frozen=True, kw_only=True)
class Entry:
    """What every registry entry carries (keywords only, so an entry type puts its own fields first).

    Attributes
    ----------
    summary : one line for ``hdi --help-keys`` and the variants table of docs/model.md
    source : where the law is stated (a section of docs/model.md, a paper)
    parameters : ``(keyword, "section.name")`` pairs: the scene values in SI units the model passes the
        behaviour as these keywords (:func:`pipeline.model.assembly.law_parameters`)
    """

    summary: str = ""
    source: str = ""
    parameters: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True, kw_only=True)
class Variant(Entry):
    """A registry entry whose behaviour is one function or value.

    Attributes
    ----------
    behaviour : what the option does: a function or a value (the registry's comment says which form),
        ``None`` for an option that leaves a part of the model as it is without it
    """

    behaviour: Any = None


E = TypeVar("E")


class Registry(dict, Generic[E]):
    """The named options of one scene key: name -> entry (an :class:`Entry`),
    in the order they are listed (the first is not necessarily the default: the schema says which is).

    A dict, so a test registers an entry with ``monkeypatch.setitem`` and every reader sees it at once.

    Parameters
    ----------
    key : the scene key that chooses among the entries, ``"section.name"``
    entries : name -> entry
    """

    def __init__(self, key: str, entries: dict[str, E]):
        super().__init__(entries)
        self.key = key

    def lookup(self, name: str) -> E:
        """The entry named ``name``.

        Parameters
        ----------
        name : the scene key's value (``air_bearing.rear_law = "power"``: ``"power"``)

        Returns
        -------
        Entry
            The registered entry [-]: its summary, source and (a :class:`Variant`) behaviour.

        Raises
        ------
        ValueError
            For a name not registered: ``"<key> = 'name': expected one of [...]"``.

        References
        ----------
        docs/architecture.md, section "Where to add things" (a model variant's registry); each entry's own
        ``source``.
        """
        try:
            return self[name]
        except (KeyError, TypeError):
            raise ValueError(f"{self.key} = {name!r}: expected one of {list(self)}") from None

    def __repr__(self) -> str:
        return f"Registry({self.key!r}, {list(self)})"
