"""Validation of a parsed scene against the schema: every key's type, range and file, then the checks
across keys; the result is a :class:`Scene` with every default filled in.

Validation errors are :class:`~pipeline.config.schema.SceneError` and always name the file (or the
``--set`` option), the ``section.key`` and what was expected. A disabled effect's inputs are never required.
"""

from __future__ import annotations

import collections
import copy
import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

from ..paths import special_kind
from ..units import MHZ_IN_KHZ, MS, NS
from .heater_power import TOUCHDOWN_POWER_KEYS, resolve_touchdown
from .limits import MAX_INTEGER, MAX_MAGNITUDE, MAX_NESTING, MAX_STEPS, LimitError, check_physical
from ..physics.friction import FRICTION_LAWS
from .frozen import FrozenList, freeze, thaw
from .si import SI_VIEW
from .schema import FREE_LIMITS, SCHEMA, Key, SceneError, is_folder_name, strip_unit

#: Fewest output samples of a run's steady window (after ``solver.transient_ms``) a scene may ask for:
#: a regime and an FHM judged on fewer say nothing (the paper scene has 6000).
MIN_STEADY_SAMPLES = 10


def check_plain(value: Any, name: str, where: str) -> None:
    """Refuse what no scene value holds and what would end in a traceback later: an integer beyond 64 bits
    (:data:`~pipeline.config.limits.MAX_INTEGER`, TOML's range: ``float()`` of a 400-digit integer overflowed)
    or lists and tables nested deeper than :data:`~pipeline.config.limits.MAX_NESTING`, at any depth of
    ``value``.

    Parameters
    ----------
    value
        A value as parsed (TOML) or given (a dict of the API), before any conversion.
    name
        What the message names (``section.key``).
    where
        The culprit (the file, or ``--set TEXT``).

    Raises
    ------
    SceneError
        Naming ``where``, ``name`` and the bound broken.
    """
    todo = [(value, 0)]
    while todo:  # (a loop, not recursion: a value nested 10,000 deep reaches its bound, not Python's)
        item, depth = todo.pop()
        if isinstance(item, (dict, list, tuple)):
            if depth >= MAX_NESTING:
                raise SceneError(f"{where}: {name}: lists or tables nested more than {MAX_NESTING} deep; expected a "
                                 "number, a string, a list or a table of them (docs/cli.md, section 'Scenes')")
            todo += [(v, depth + 1) for v in (item.values() if isinstance(item, dict) else item)]
        elif isinstance(item, int) and not isinstance(item, bool) and abs(item) > MAX_INTEGER:
            digits = int(item.bit_length() * math.log10(2)) + 1  # (str() of 5,000 digits raises)
            raise SceneError(f"{where}: {name}: an integer of about {digits} digits; expected an integer of magnitude at "
                             "most 2**63 - 1 (TOML's 64-bit integers; write a number as a float, e.g. 1e3)")


@dataclass(frozen=True)
class Scene:
    """A validated scene: read-only all the way down (its sections and the tables in their lists are
    :class:`~pipeline.config.frozen.FrozenSection` s, its lists :class:`~pipeline.config.frozen.FrozenList` s, its attributes cannot be reassigned); vary it
    with :meth:`replace`.

    Attributes
    ----------
    path
        The TOML file it came from (``None`` for scenes built in code).
    config
        ``section -> key -> value`` with every default filled in (read-only).
    overrides
        The ``--set`` strings applied, in order (kept for provenance).
    """

    path: Path | None
    config: dict[str, dict[str, Any]]
    overrides: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        object.__setattr__(self, "config", freeze(self.config))
        object.__setattr__(self, "overrides", FrozenList(self.overrides, "overrides"))

    @property
    def name(self) -> str:
        return self.config["scene"]["name"]

    @property
    def effects(self) -> frozenset[str]:
        return frozenset(self.config["scene"]["effects"])

    def __getitem__(self, section: str) -> dict[str, Any]:
        return self.config[section]

    def has(self, effect: str) -> bool:
        """Whether the scene asks for ``effect`` (one of :data:`EFFECTS`)."""
        return effect in self.effects

    #: the scene in SI units (:func:`pipeline.config.si.to_si`): ``scene.si.air_bearing.flying_height`` [m]
    si = SI_VIEW

    @property
    def hash(self) -> str:
        """SHA-256 of the canonical (sorted-key JSON) configuration: the scene's identity."""
        blob = json.dumps(self.config, sort_keys=True, default=str).encode()
        return hashlib.sha256(blob).hexdigest()

    def replace(self, **sections: dict[str, Any]) -> "Scene":
        """A copy with some keys changed, validated again as ``--set`` is: the way to vary a scene.

        ``scene.replace(tfc={"protrusion_nm": 9.0}, contact={"k": 0.5})``: each keyword is a section, its
        value a dict of that section's keys (values in the key's units, as the scene file takes them).

        Raises
        ------
        SceneError
            An unknown section or key, or a value the key does not allow, naming ``replace``, the
            ``section.key``, the value and what was expected.
        """
        cfg = thaw(self.config)
        blame: dict[tuple[str, str], str] = {}
        for sec, keys in sections.items():
            if not isinstance(keys, dict):
                raise SceneError(f"scene.replace({sec}={keys!r}): expected a dict of the section's keys "
                                 f"(e.g. scene.replace(contact={{'k': 0.5}}))")
            for key, value in keys.items():
                check_plain(value, f"{sec}.{key}", f"scene.replace({sec}={{{key!r}: ...}})")  # (before _thaw recurses)
                blame[(sec, key)] = f"scene.replace({sec}={{{key!r}: {shown(value)}}})"
                # (a base is merged when a file is read, not here; the scene's own value passed back unchanged, as
                # `{**scene["scene"], ...}` does, changes nothing)
                if (sec, key) == ("scene", "extends") and thaw(value) != cfg.get("scene", {}).get("extends"):
                    raise SceneError(f"{blame[(sec, key)]}: scene.extends cannot be replaced: a base scene is merged "
                                     "when a scene file is read; load the base scene itself (load_scene) and replace "
                                     "the keys that differ, or write `extends` in a scene file")
            cfg.setdefault(sec, {}).update(thaw(keys))
        for mw, nm in TOUCHDOWN_POWER_KEYS.items():  # (a touchdown in nm set from mW is set again from mW)
            if cfg["touchdown"].get(mw) is not None and nm not in sections.get("touchdown", {}):
                cfg["touchdown"].pop(nm, None)
        raw = {s: {k: v for k, v in d.items() if v is not None} for s, d in cfg.items()}
        return validate(raw, self.path, overrides=self.overrides, resolve_paths=False, blame=blame)

    def to_toml_text(self) -> str:
        """The configuration as JSON text (stored in dataset provenance)."""
        return json.dumps(self.config, sort_keys=True, default=str)


def shown(value: Any, width: int = 200) -> str:
    """``repr(value)``, cut to ``width`` characters with the number of items of a longer list (an error
    quoting a list of 200,000 protrusions stays a line one can read)."""
    text = repr(value)
    if len(text) <= width:
        return text
    items = f" ({len(value)} items)" if isinstance(value, (list, tuple, dict)) else ""
    return text[:width] + "..." + items


def _where(path: Path | None) -> str:
    return str(path) if path is not None else "<scene>"


#: The expectation of a number too large (:data:`pipeline.config.limits.MAX_MAGNITUDE`).
_MAGNITUDE = f"a number of magnitude at most {MAX_MAGNITUDE:g} (larger ones overflow when converted to SI units)"


def _representable(value: float) -> bool:
    """Whether a finite number's magnitude is at most :data:`~pipeline.config.limits.MAX_MAGNITUDE`."""
    return abs(value) <= MAX_MAGNITUDE


def check_value(section: str, key: str, spec: Key, value: Any, where: str, base: Path | None) -> Any:
    """One value checked against its key's schema and normalised (numbers to float, file paths resolved).

    Parameters
    ----------
    section, key
        Where the value stands (``section.key`` in the message).
    spec
        The key's schema.
    value
        The value as parsed.
    where
        What the message names as the culprit (the file, or ``--set TEXT``).
    base
        The folder relative file paths are taken from (``None``: as given).

    Raises
    ------
    SceneError
        For a value of the wrong kind, out of range (an integer beyond 64 bits or a value nested too deep:
        :func:`check_plain`), or naming a file that does not exist or is special.
    """
    name = f"{section}.{key}"
    doc = f" ({spec.doc})" if spec.doc else ""

    def fail(expected: str, got: Any = value) -> SceneError:
        return SceneError(f"{where}: {name} = {shown(got)}: expected {expected}{doc}")

    check_plain(value, name, where)  # (before any conversion: float() of a 400-digit integer overflows)
    kind = spec.kind
    if kind in _KIND_CHECKS:
        value = _KIND_CHECKS[kind](value, spec, key, fail)
    if spec.check is not None and kind not in ("tables",):
        pred, expected = spec.check
        if not pred(value):
            raise fail(expected)
    if spec.path and value is not None:
        value = _resolved_paths(value, name, where, doc, base)
    return value


Fail = Callable[..., SceneError]


def _check_float(value: Any, spec: Key, key: str, fail: Fail) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail("a number")
    value = float(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise fail("a finite number")
    if not _representable(value):
        raise fail(_MAGNITUDE)
    return value


def _check_int(value: Any, spec: Key, key: str, fail: Fail) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise fail("an integer")
    return value


def _check_str(value: Any, spec: Key, key: str, fail: Fail) -> str:
    if not isinstance(value, str):
        raise fail("a string")
    if spec.choices and value not in spec.choices:
        raise fail("one of " + ", ".join(map(repr, spec.choices)))
    return value


def _check_bool(value: Any, spec: Key, key: str, fail: Fail) -> bool:
    if not isinstance(value, bool):
        raise fail("true or false")
    return value


def _check_floats(value: Any, spec: Key, key: str, fail: Fail) -> list[float]:
    if not isinstance(value, list) or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
        raise fail("a list of numbers")
    value = [float(v) for v in value]
    if not all(math.isfinite(v) for v in value):
        raise fail("a list of finite numbers (no nan or inf)")
    if not all(map(_representable, value)):
        raise fail("a list of " + _MAGNITUDE.replace("a number", "numbers"))
    if spec.length is not None and len(value) != spec.length:
        raise fail(f"a list of {spec.length} numbers")
    return value


def _check_strs(value: Any, spec: Key, key: str, fail: Fail) -> list[str]:
    if not isinstance(value, list) or any(not isinstance(v, str) for v in value):
        raise fail("a list of strings")
    if spec.choices:
        bad = [v for v in value if v not in spec.choices]
        if bad:
            raise fail(f"names from {list(spec.choices)}; {bad[0]!r} is not an effect that exists"
                       if key == "effects" else f"values from {list(spec.choices)}")
        if len(set(value)) != len(value):
            raise fail("no repeated names")
    return value


def _check_range(value: Any, spec: Key, key: str, fail: Fail) -> dict[str, float]:
    if not isinstance(value, dict) or set(value) != {"start", "stop", "step"}:
        raise fail("a table {start = ..., stop = ..., step = ...}")
    if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value.values()):
        raise fail("numbers for start, stop and step")
    value = {k: float(v) for k, v in value.items()}
    if not all(math.isfinite(v) for v in value.values()):
        raise fail("finite numbers for start, stop and step (no nan or inf)")
    if not all(map(_representable, value.values())):
        raise fail(_MAGNITUDE.replace("a number", "numbers") + " for start, stop and step")
    if value["step"] <= 0:
        raise fail("step > 0")
    if value["stop"] < value["start"]:
        raise fail("stop >= start (the grid is not reversed)")
    if value["start"] < 0:
        raise fail("protrusions >= 0 (start is negative)")
    return value


def _check_tables(value: Any, spec: Key, key: str, fail: Fail) -> list:
    if not isinstance(value, list) or not value or any(not isinstance(v, (dict, str)) for v in value):
        raise fail("a non-empty list of tables (or labels of sets defined elsewhere)")
    return value


#: The check of a value of each kind of key (:func:`check_value`): ``check(value, spec, key, fail)`` returns
#: the value normalised (numbers to float) or raises ``fail(expected)``.
_KIND_CHECKS: dict[str, Callable[[Any, Key, str, Fail], Any]] = {
    "float": _check_float, "int": _check_int, "str": _check_str, "bool": _check_bool, "floats": _check_floats,
    "strs": _check_strs, "range": _check_range, "tables": _check_tables,
}


def _resolved_paths(value: Any, name: str, where: str, doc: str, base: Path | None) -> Any:
    """A path key's file (or list of files) resolved against ``base``; a file that does not exist or is special
    (a FIFO, a device: reading it never ends) is a :class:`SceneError` naming it."""
    items = value if isinstance(value, list) else [value]
    resolved = []
    for item in items:
        p = Path(item).expanduser()
        if not p.is_absolute() and base is not None:
            p = (base / p).resolve()
        if not p.exists():
            raise SceneError(f"{where}: {name}: file {item!r} does not exist (looked for {p}){doc}")
        if special_kind(p) not in (None, "a folder"):  # (reading a FIFO or a device never ends)
            raise SceneError(f"{where}: {name}: {p} is {special_kind(p)}; expected a regular file{doc}")
        resolved.append(str(p))
    return resolved if isinstance(value, list) else resolved[0]


def validate(raw: dict[str, Any], path: Path | None = None, *, overrides: Iterable[str] = (),
             resolve_paths: bool = True, blame: dict[tuple[str, str], str] | None = None) -> Scene:
    """Validate a parsed scene and fill in defaults.

    Parameters
    ----------
    raw
        The parsed TOML (``section -> key -> value``).
    path
        The file it came from, for error messages and relative file paths.
    blame
        ``(section, key) -> "--set TEXT"`` for keys set on the command line: their errors name the
        ``--set`` option, not the file.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        For an unknown section or key, a key in the wrong unit, a value of the wrong type or out of
        range, an effect that does not exist, or a file that does not exist.
    """
    where = _where(path)
    base = path.parent if (path is not None and resolve_paths) else None
    config: dict[str, dict[str, Any]] = {}
    for section, table in raw.items():
        if section not in SCHEMA:
            culprit = next((b for (sec, _), b in (blame or {}).items() if sec == section), where)
            raise SceneError(f"{culprit}: unknown section [{section}]: expected one of "
                             + ", ".join(f"[{s}]" for s in SCHEMA))
        if not isinstance(table, dict):
            raise SceneError(f"{where}: {section} must be a table [{section}]")
    blame = blame or {}
    for section, keys in SCHEMA.items():
        table = raw.get(section, {})
        out: dict[str, Any] = {}
        for key, value in table.items():
            where = blame.get((section, key), _where(path))
            if key not in keys:
                stem, unit = strip_unit(key)
                twins = [k for k in keys if strip_unit(k)[0] == stem]
                if twins and unit is not None:
                    want = strip_unit(twins[0])[1]
                    raise SceneError(f"{where}: {section}.{key}: wrong unit {unit!r}; expected {want!r} "
                                     f"(write it as {section}.{twins[0]}; units are part of key names)")
                raise SceneError(f"{where}: unknown key {section}.{key}: expected one of "
                                 + ", ".join(keys))
            out[key] = check_value(section, key, keys[key], value, where, base)
        where = _where(path)
        for key, spec in keys.items():
            if key not in out:
                out[key] = copy.deepcopy(spec.default)
        config[section] = out
    if config["scene"]["name"] is None:
        if path is None:
            raise SceneError(f"{where}: scene.name is missing: expected a name")
        # (the name makes results/<name>/ and the sweep's part files: a file `paper-2009 (copy).toml` failed
        # only at the sweep, after the upstream stages ran; a file `...toml` would put results/../)
        if not is_folder_name(path.stem):
            raise SceneError(f"{where}: scene.name is missing and the file name gives {path.stem!r}: expected "
                             "scene.name = a name of letters, digits, '.', '_' or '-', not '.' or '..' "
                             "(set scene.name in the file, or rename the file)")
        config["scene"]["name"] = path.stem
    try:  # (the touchdown in mW becomes the touchdown in nm that every stage reads)
        resolve_touchdown(config, raw.get("touchdown", {}), where)
    except ValueError as exc:
        raise SceneError(str(exc)) from None
    _cross_checks(config, where)
    try:  # (a protrusion far beyond the flying height: no --yes makes it physical)
        check_physical(Scene(path, config), where)
    except LimitError as exc:
        raise SceneError(str(exc)) from None
    return Scene(path=path, config=config, overrides=list(overrides))


def _cross_checks(config: dict[str, dict[str, Any]], where: str) -> None:
    """The checks across keys, in order (the first that fails raises its :class:`SceneError`)."""
    _window_checks(config, where)
    _list_checks(config, where)
    eff = set(config["scene"]["effects"])
    _model_checks(config, eff, where)
    _dmw_checks(config, eff, where)


def _window_checks(config: dict[str, dict[str, Any]], where: str) -> None:
    """The touchdown's two protrusions in order, and a steady window of enough samples after the transient."""
    td = config["touchdown"]
    if td["previous_nm"] >= td["onset_nm"]:
        raise SceneError(f"{where}: touchdown.previous_nm = {td['previous_nm']} must be below "
                         f"touchdown.onset_nm = {td['onset_nm']}")
    sol = config["solver"]
    if sol["transient_ms"] >= sol["duration_ms"]:
        raise SceneError(f"{where}: solver.transient_ms = {sol['transient_ms']} must be shorter than "
                         f"solver.duration_ms = {sol['duration_ms']}")
    steady = (sol["duration_ms"] - sol["transient_ms"]) * (MS / NS) / sol["output_step_ns"]
    if steady < MIN_STEADY_SAMPLES:  # (1e-6 ms: one sample judged "surfing")
        raise SceneError(f"{where}: solver.duration_ms = {sol['duration_ms']:g} - transient_ms = "
                         f"{sol['transient_ms']:g} leaves a steady window of {steady:.3g} samples of "
                         f"output_step_ns = {sol['output_step_ns']:g}; expected at least {MIN_STEADY_SAMPLES} "
                         "samples to judge a regime and an FHM on")


def _list_checks(config: dict[str, dict[str, Any]], where: str) -> None:
    """The free parameters' bounds within their limits, distinct kept protrusions and damping ratios, and a run
    that the integrator's step budget can finish."""
    sol = config["solver"]
    for item in config["identify"]["parameters"] or []:  # (the tables' form: checked by the study reading them)
        key = item.get("key") if isinstance(item, dict) else None
        if key not in FREE_LIMITS:
            continue
        lo, hi, why = FREE_LIMITS[key]
        low, high = item.get("low"), item.get("high")
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (low, high)) and (low < lo or high > hi):
            raise SceneError(f"{where}: identify.parameters: {key} low = {low}, high = {high}: expected bounds "
                             f"within [{lo:g}, {hi:g}] ({why}; docs/model.md, section 'DMW as free parameters')")
    for section in ("sweep", "report"):  # (the sweep keeps those of report.histories_nm without its own)
        kept = config[section]["histories_nm"] or []
        # (the histories' coordinate is the protrusion: a value twice gave two equal labels, one row all NaN)
        # (neighbours in sorted order: a pair within 1e-9 has such a neighbour; all pairs took hours for 200,000)
        order = sorted(kept)
        twice = sorted({round(b, 9) for a, b in zip(order, order[1:]) if abs(b - a) < 1e-9})
        if twice:
            raise SceneError(f"{where}: {section}.histories_nm = {shown(kept)}: {twice[0]:.10g} appears more than once; "
                             "expected distinct protrusions [nm] (each is a coordinate value of the kept histories)")
    if sol["duration_ms"] * (MS / NS) / sol["max_step_ns"] > MAX_STEPS:
        raise SceneError(f"{where}: solver.max_step_ns = {sol['max_step_ns']:g}: a run of solver.duration_ms = "
                         f"{sol['duration_ms']:g} needs at least {sol['duration_ms'] * (MS / NS) / sol['max_step_ns']:.3g} "
                         f"steps of it, beyond the integrator's {MAX_STEPS:,}; expected at least "
                         f"{sol['duration_ms'] * (MS / NS) / MAX_STEPS:.3g} ns (default 500)")
    damping = config["sweep"]["damping_ratio"] or []
    twice = sorted(d for d, n in collections.Counter(damping).items() if n > 1)  # (count() per item: quadratic)
    if twice:
        raise SceneError(f"{where}: sweep.damping_ratio = {shown(damping)}: {twice[0]:g} appears more than once; "
                         "expected distinct ratios (each is a coordinate value of sweep.nc)")


def _model_checks(config: dict[str, dict[str, Any]], eff: set[str], where: str) -> None:
    """The effects the model needs (the air bearing), those each option needs and the options it needs."""
    if "air_bearing" not in eff:
        raise SceneError(f"{where}: scene.effects = {sorted(eff)}: expected 'air_bearing' among them "
                         "(nothing else holds the slider up)")
    ab = config["air_bearing"]
    if ab["lift_cap_gap_nm"] is not None and ab["bulge"] == "none":
        raise SceneError(f"{where}: air_bearing.lift_cap_gap_nm = {ab['lift_cap_gap_nm']:g} caps the bulge lift: it "
                         "needs air_bearing.bulge = 'ph-limit', 'reynolds' or 'rough-reynolds' (it is 'none')")
    c = config["contact"]
    if c["friction_law"] == "coefficient" and c["friction_coefficient"] is None:
        raise SceneError(f"{where}: contact.friction_law = 'coefficient' needs contact.friction_coefficient "
                         "(a number >= 0, the paper's mu is ~1.2)")
    if FRICTION_LAWS.lookup(c["friction_law"]).summit is not None and config["interface"]["model"] != "statistical":
        raise SceneError(f"{where}: contact.friction_law = {c['friction_law']!r} is a per-summit law of the statistical "
                         f"tables: it needs interface.model = 'statistical' (it is {config['interface']['model']!r})")
    lub, two = config["lubricant"], config["interface"]["adhesion"] == "two-population"
    if two and lub["bridge_work_of_adhesion_j_m2"] is None:
        raise SceneError(f"{where}: interface.adhesion = 'two-population' needs lubricant.bridge_work_of_adhesion_j_m2 "
                         "(a number >= 0 [J/m^2]; about 0.005 for van der Waals across the bonded film)")
    if not two and lub["bridge_work_of_adhesion_j_m2"] is not None:
        raise SceneError(f"{where}: lubricant.bridge_work_of_adhesion_j_m2 acts only with interface.adhesion = "
                         "'two-population' (it is 'isbl': one work of adhesion for every summit)")
    if c["friction_switching"] != "criterion" and "friction" not in eff:
        raise SceneError(f"{where}: contact.friction_switching = {c['friction_switching']!r} says how the friction "
                         "acts: it needs the 'friction' effect (or 'criterion', the default)")
    if lub["solid_work_of_adhesion_j_m2"] is not None and "adhesion" not in eff:
        raise SceneError(f"{where}: lubricant.solid_work_of_adhesion_j_m2 changes the adhesion of the summits that "
                         "penetrate the bonded layer: it needs the 'adhesion' effect")
    if lub["shear_stress_mpa"] > 0 and "friction" not in eff:
        raise SceneError(f"{where}: lubricant.shear_stress_mpa > 0 is a friction term: it needs the 'friction' effect")
    if config["interface"]["model"] == "deterministic":
        if not config["roughness"]["afm"]:
            raise SceneError(f"{where}: interface.model = 'deterministic' needs a measured surface: set "
                             "roughness.afm (AFM scans); the explicit statistics have no height map to solve")
        if "contact" not in eff:
            raise SceneError(f"{where}: interface.model = 'deterministic' needs the 'contact' effect "
                             "(it replaces the contact tables)")
    if "friction" in eff and "contact" not in eff:
        raise SceneError(f"{where}: scene.effects: 'friction' needs 'contact' (friction acts only in contact)")
    if "pitch" in eff and "air_bearing" not in eff:
        raise SceneError(f"{where}: scene.effects: 'pitch' needs 'air_bearing'")


def _dmw_checks(config: dict[str, dict[str, Any]], eff: set[str], where: str) -> None:
    """A DMW record file that exists and is regular (resolved in place), and a DMW band below the Nyquist
    frequency of its sample rate."""
    if "dmw" in eff:
        src = config["dmw"]["source"]
        if src != "synthetic":
            p = Path(src)
            if not p.is_absolute() and where != "<scene>":
                p = Path(where).parent / p
            if not p.exists():
                raise SceneError(f"{where}: dmw.source: file {src!r} does not exist (looked for {p}); "
                                 f"expected \"synthetic\" or a record file")
            if special_kind(p) is not None:  # (reading a FIFO or /dev/zero never ends)
                raise SceneError(f"{where}: dmw.source: {p} is {special_kind(p)}; expected a regular file (a "
                                 "CSV or NetCDF record)")
            config["dmw"]["source"] = str(p.resolve())
    lo, hi = config["dmw"]["band_khz"]
    nyq = config["dmw"]["sample_rate_mhz"] * MHZ_IN_KHZ / 2
    if hi > nyq:
        raise SceneError(f"{where}: dmw.band_khz upper edge {hi} kHz is above the Nyquist frequency "
                         f"{nyq} kHz of dmw.sample_rate_mhz = {config['dmw']['sample_rate_mhz']}")
