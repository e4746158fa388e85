"""A scene that records every key read from it (``recording``) and the keys a stage declares it reads
(``declared``): the instruments of the stage-reads tests."""

from __future__ import annotations

from typing import Any
from pipeline import runner
from pipeline.config.scene import Scene


class _Section(dict):
    """A scene section that records the keys read from it."""

    def __init__(self, data: dict, name: str, log: set):
        super().__init__(data)
        self._name, self._log = name, log

    def __getitem__(self, key):
        self._log.add(f"{self._name}.{key}")
        return super().__getitem__(key)

    def get(self, key, default=None):
        self._log.add(f"{self._name}.{key}")
        return super().get(key, default)

    def __iter__(self):
        self._log.add(f"{self._name}.*")
        return super().__iter__()

    def items(self):
        self._log.add(f"{self._name}.*")
        return super().items()

    def values(self):
        self._log.add(f"{self._name}.*")
        return super().values()

    def __eq__(self, other):
        self._log.add(f"{self._name}.*")
        return dict(self) == other

    __hash__ = None


class RecordingScene(Scene):
    """A :class:`Scene` whose section reads (and ``effects``) are recorded while ``log`` is set.

    ``log`` is no field of the (frozen) scene: it is set and cleared on the scene the stage reads."""

    def __init__(self, path: Any, config: Any, overrides: Any = (), log: set | None = None) -> None:
        super().__init__(path, config, list(overrides))
        self.log = log

    @property
    def effects(self) -> frozenset[str]:
        if self.log is not None:
            self.log.add("scene.effects")
        return frozenset(self.config["scene"]["effects"])

    def __getitem__(self, section: str) -> dict[str, Any]:
        if self.log is None:
            return self.config[section]
        return _Section(self.config[section], section, self.log)

    def replace(self, **sections: dict[str, Any]) -> "RecordingScene":
        # a stage's variant of the scene (a roughness set, a seed) still reads through the log
        new = super().replace(**sections)
        for item in (f"{s}.{k}" for s, keys in sections.items() for k in keys):
            if self.log is not None:
                self.log.discard(item)
        return RecordingScene(new.path, new.config, new.overrides, log=self.log)


def recording(scene: Scene) -> RecordingScene:
    return RecordingScene(scene.path, scene.config, scene.overrides)


def declared(stage: runner.Stage, scene: Scene) -> set[str]:
    """The ``section.key`` items the runner hashes for a stage (``section.*``: the whole section)."""
    part = runner.scene_part(scene, stage.reads, stage.excludes)
    items: set[str] = set()
    for name, value in part.items():
        if name == "*":
            items |= {f"{s}.{k}" for s, keys in value.items() for k in keys}
            items |= {f"{s}.*" for s, keys in value.items()
                      if all(f"{s}.{k}" not in stage.excludes for k in scene.config[s])}
        elif "." in name:
            items.add(name)
        else:
            items |= {f"{name}.{k}" for k in value}
            if all(f"{name}.{k}" not in stage.excludes for k in scene.config[name]):
                items.add(f"{name}.*")
    return items
