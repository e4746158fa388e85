"""Loading a scene: find its file (a path, or the name of a scene shipped with the package), read the
TOML, merge the base scenes it ``extends``, apply ``--set`` overrides and validate
(:func:`pipeline.config.validation.validate`).

A base scene's relative file paths are made absolute from the base's own folder before the merge, and a
``--set`` override's from the working directory, where the user typed it (a scene file's own relative
paths stay relative to the scene's folder); an override names itself in the errors of the keys it set.
"""

from __future__ import annotations

import copy
import json
import os
import re
from importlib import resources
from pathlib import Path
from typing import Any, Iterable

from ..paths import looked_for, special_kind
from .schema import SCHEMA, SceneError
from .limits import MAX_NESTING
from .validation import Scene, check_plain, validate

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]


def _toml_error(exc: Exception) -> str | None:
    """What TOML text the parser could not read was, in words (``None``: a valid document).

    Beside bad syntax (:class:`tomllib.TOMLDecodeError`), the parser meets lists and tables nested a few
    hundred deep with Python's ``RecursionError`` and an integer of more than 4,300 digits with a
    ``ValueError`` (Python's limit on converting digits): both are text no scene writes."""
    if isinstance(exc, RecursionError):
        return (f"lists or tables nested too deep for the TOML parser; expected at most {MAX_NESTING} levels "
                "(docs/cli.md, section 'Scenes')")
    if isinstance(exc, tomllib.TOMLDecodeError):
        return (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    return ("an integer of more than 4,300 digits; expected an integer of magnitude at most 2**63 - 1 (TOML's "
            "64-bit integers; write a number as a float, e.g. 1e3)")


def parse_override(text: str) -> tuple[str, str, Any]:
    """Parse ``section.key=value`` (value in TOML syntax; bare words are strings).

    The value is one TOML value: text that TOML reads as more than that (a newline and a second key or
    table, ``5\n[contact]\nk = 0.5``) is refused, never applied in part; so are a bare word over several
    lines and a value no TOML file could hold (:func:`_toml_error`).
    """
    m = re.fullmatch(r"\s*([A-Za-z_]+)\.([A-Za-z0-9_]+)\s*=\s*(.*)", text, re.S)
    if not m:
        raise SceneError(f"--set {text!r}: expected section.key=value")
    section, key, value = m.groups()
    try:
        doc = tomllib.loads(f"v = {value}")
    except tomllib.TOMLDecodeError:
        if "\n" in value.strip() or "\r" in value.strip():
            raise SceneError(f"--set {text!r}: {section}.{key}: the value runs over several lines and is no TOML "
                             "value; expected one value (a bare word is one line; quote a string)") from None
        return section, key, value.strip()
    except (RecursionError, ValueError) as exc:
        raise SceneError(f"--set {section}.{key}=...: {_toml_error(exc)}") from None
    if set(doc) != {"v"}:
        extra = sorted(set(doc) - {"v"})
        raise SceneError(f"--set {text!r}: {section}.{key}: the value holds more than one TOML value (a newline and "
                         f"{extra[0]!r}); expected one value: one --set per key")
    return section, key, doc["v"]


#: The folder of the package that holds the shipped scenes (package data; in the repository
#: ``pipeline/scenes/`` holds a link per scene of ``configs/``, their one home).
SCENES_FOLDER = "scenes"


def shipped_scenes() -> dict[str, Path]:
    """The scenes shipped with the package, by name (the file name without ``.toml``), sorted.

    Found through :mod:`importlib.resources` in the installed package (a wheel's files, or the clone's
    ``configs/`` in an editable install); each path resolved, so a base scene's ``extends`` is read
    beside it.
    """
    folder = resources.files("pipeline").joinpath(SCENES_FOLDER)
    if not folder.is_dir():
        return {}
    names = sorted(item.name[:-len(".toml")] for item in folder.iterdir() if item.name.endswith(".toml"))
    return {name: Path(str(folder.joinpath(f"{name}.toml"))).resolve() for name in names}


def _bare_name(text: str) -> bool:
    """Whether ``text`` is a name and not a path: no folder separator, not ``.``/``..``, no ``~``."""
    seps = {"/", os.sep, os.altsep} - {None}
    return bool(text) and not any(sep in text for sep in seps) and text not in (".", "..") \
        and not text.startswith("~")


def find_scene(path: str | Path, folder: Path | None = None) -> Path:
    """The scene file that ``path`` names: a file, else the shipped scene of that name.

    Precedence (docs/cli.md, "Scenes by name"): a file that exists at ``path`` (relative to ``folder``,
    else to the working directory) wins; a bare name (no folder separator) that is no file there is the
    shipped scene of that name, with or without ``.toml`` (:func:`shipped_scenes`).

    Parameters
    ----------
    path
        A path, or the name of a shipped scene (``"paper-2009"``).
    folder
        The folder a relative path is read from (a scene's own folder, for its ``extends``); ``None``:
        the working directory.

    Raises
    ------
    SceneError
        When neither exists: naming the path tried and the shipped scenes.
    """
    text = os.fspath(path)
    tried = Path(folder, text) if folder is not None else Path(text)
    if tried.exists() or tried.is_symlink():
        return tried  # (a folder or a broken link too: the reader says what it is)
    shipped = shipped_scenes()
    name = text[:-len(".toml")] if text.endswith(".toml") else text
    if _bare_name(text) and name in shipped:
        return shipped[name]
    raise SceneError(f"{text}: scene file does not exist (looked for {tried.absolute()}); expected a scene "
                     f"file or the name of a shipped scene: {', '.join(shipped) or '(none)'}")


def load_scene(path: str | Path, overrides: Iterable[str] = ()) -> Scene:
    """Find, read, override and validate a scene file.

    Parameters
    ----------
    path
        The TOML scene, or the name of a scene shipped with the package (``"paper-2009"``,
        :func:`find_scene`).
    overrides
        ``section.key=value`` strings applied after reading (``--set`` on the command line); a relative
        file path in one (``roughness.afm``, ``dmw.source``, a set's ``afm``) is taken from the working
        directory.

    Raises
    ------
    SceneError
        For a missing or unreadable file, bad TOML, or any invalid field (see :func:`validate`).
    """
    path = find_scene(path)
    raw = _read_raw(path)
    overrides = list(overrides)
    blame: dict[tuple[str, str], str] = {}
    for text in overrides:
        section, key, value = parse_override(text)
        if (section, key) == ("scene", "extends"):  # (it was applied while reading: a --set came too late)
            raise SceneError(f"--set {text}: scene.extends cannot be set on the command line; write "
                             f"`extends = {json.dumps(str(value))}` in the [scene] section of a scene file "
                             f"(or give the base scene itself with --set for the keys that differ)")
        # (a path typed on the command line means what it means there, not beside the scene file)
        value = _anchor_paths({section: {key: value}}, Path.cwd())[section][key]
        raw.setdefault(section, {})
        if not isinstance(raw[section], dict):
            raise SceneError(f"{path}: --set {text!r}: [{section}] is not a table")
        raw[section][key] = value
        blame[(section, key)] = f"--set {text}"
    return validate(raw, path, overrides=overrides, blame=blame)


#: Deepest chain of ``scene.extends`` a scene may build on (a scene, its base, the base's base, ...):
#: far beyond any real chain (the identified scene extends the paper scene: 2), and far below Python's
#: recursion limit, which a chain of 1,200 files reached with a traceback.
MAX_EXTENDS_DEPTH = 32


def _read_raw(path: Path, seen: tuple[Path, ...] = ()) -> dict[str, Any]:
    """Parse a scene file, merging in the base scene it ``extends`` (keys of this file win).

    The base's relative file paths are made absolute from the base's own folder (:func:`_anchor_paths`)
    before the merge: a path means what it meant in the file that wrote it, not beside the derived scene.
    """
    if path.is_dir():
        raise SceneError(f"{path}: is a folder; expected a scene file (TOML), e.g. configs/paper-2009.toml")
    if special_kind(path) is not None:  # (reading a FIFO or a device never ends)
        raise SceneError(f"{path}: is {special_kind(path)}; expected a scene file (TOML)")
    if not path.is_file():
        raise SceneError(f"{path}: scene file does not exist{looked_for(path)}")
    try:  # (utf-8-sig: a byte-order mark, as some Windows editors write, is not part of the TOML)
        raw = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except UnicodeDecodeError as exc:
        raise SceneError(f"{path}: not UTF-8 text (byte {exc.start}); expected a TOML file in UTF-8") from None
    except (tomllib.TOMLDecodeError, RecursionError, ValueError) as exc:
        raise SceneError(f"{path}: not valid TOML: {_toml_error(exc)}") from None
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file: {exc.strerror or exc}") from None
    for section, table in raw.items():  # (bounded here, where the file is known: a base's number names the base)
        for key, value in (table.items() if isinstance(table, dict) else [("", table)]):
            check_plain(value, f"{section}.{key}" if key else section, str(path))
    for section, table in raw.items():  # (here, where the file is known: a base's error names the base)
        if section in SCHEMA and not isinstance(table, dict):
            raise SceneError(f"{path}: {section} must be a table [{section}]")
    base_name = raw.get("scene", {}).get("extends")
    if base_name is None:
        return raw
    if not isinstance(base_name, str):
        raise SceneError(f"{path}: scene.extends = {base_name!r}: expected a file name")
    try:  # (a file beside the scene, else a shipped scene of that name)
        base_path = find_scene(base_name, path.parent).resolve()
    except SceneError as exc:
        raise SceneError(f"{path}: scene.extends: {exc}") from None
    if base_path in seen or base_path == path.resolve():
        raise SceneError(f"{path}: scene.extends = {base_name!r}: circular extension")
    if len(seen) + 1 >= MAX_EXTENDS_DEPTH:
        raise SceneError(f"{path}: scene.extends = {base_name!r}: a chain of more than {MAX_EXTENDS_DEPTH} "
                         f"scenes extending one another; expected at most {MAX_EXTENDS_DEPTH} (write the keys "
                         "into fewer files)")
    if not base_path.is_file():
        raise SceneError(f"{path}: scene.extends: file {base_name!r} does not exist (looked for {base_path})")
    base = _anchor_paths(_read_raw(base_path, seen + (path.resolve(),)), base_path.parent)
    base.get("scene", {}).pop("name", None)
    for section, table in raw.items():
        if isinstance(table, dict) and isinstance(base.get(section), dict):
            base[section].update(table)
        else:
            base[section] = table
    base["scene"]["extends"] = str(base_path)
    return base


def _anchor(value: Any, folder: Path) -> Any:
    """A relative file path (a string) made absolute from ``folder``; anything else unchanged."""
    if not isinstance(value, str):
        return value
    p = Path(value).expanduser()
    return value if p.is_absolute() else str((folder / p).resolve())


def _anchor_paths(raw: dict[str, Any], folder: Path) -> dict[str, Any]:
    """``raw`` with the relative file paths it names made absolute from ``folder`` (the folder of the
    file that wrote them): the keys with ``path=True`` in :data:`SCHEMA`, a measured ``dmw.source``
    and the AFM scans of ``sweep.roughness`` sets. Values of the wrong type are left to
    :func:`validate` to report."""
    for section, keys in SCHEMA.items():
        table = raw.get(section)
        if not isinstance(table, dict):
            continue
        for key, spec in keys.items():
            if spec.path and key in table:
                v = table[key]
                table[key] = [_anchor(x, folder) for x in v] if isinstance(v, list) else _anchor(v, folder)
    dmw = raw.get("dmw")
    if isinstance(dmw, dict) and dmw.get("source", "synthetic") != "synthetic":
        dmw["source"] = _anchor(dmw["source"], folder)
    sets = raw["sweep"].get("roughness") if isinstance(raw.get("sweep"), dict) else None
    for item in sets if isinstance(sets, list) else []:
        if isinstance(item, dict) and isinstance(item.get("afm"), list):
            item["afm"] = [_anchor(x, folder) for x in item["afm"]]
    return raw


def scene_from_dict(raw: dict[str, Any], base: Path | None = None) -> Scene:
    """Validate a scene given as a dict (for tests and notebooks)."""
    raw = copy.deepcopy(raw)
    raw.setdefault("scene", {}).setdefault("name", "scene")
    return validate(raw, base / "scene.toml" if base else None)
