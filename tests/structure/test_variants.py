"""Every model variant is one registry entry (pipeline/physics/variants.py): every registry in the physics
layer is the live list of choices of its scene key, every entry is a choice that validates and reaches
the model as that entry's behaviour, the lookup of an unknown name is one line naming the key, and the
"Model variants" table of docs/model.md is the one the entries generate.

The entries are parametrized from the registries themselves, so a new entry is tested without editing
this file; a new registry needs its probe in :data:`PROBES` (the test of the probes fails without one).
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from pipeline import physics
from pipeline.config.scene import SCHEMA, SceneError
from pipeline.config.schema import describe_keys
from pipeline.config.variants_table import scene_key, variant_keys, variants_table, with_variants_table
from pipeline.config.si import to_si
from pipeline.model import assembly, bulge_table, forces, kernel_inputs, outcomes, running, scene_inputs
from pipeline.model.dmw_record import disk_speed_m_s
from pipeline.model.interface_tables import build_tables, roughness_statistics
from pipeline.physics import air_bearing as ab
from pipeline.physics import bulge_bearing as bb, reynolds
from pipeline.physics.variants import Entry, Registry, Variant
from slider_scenes import FLYING, K, make_scene

ROOT = Path(__file__).resolve().parents[2]
NM = 1e-9
#: The effects of a scene whose model has interface tables (no DMW: no record needed to build it).
CONTACT = ["air_bearing", "pitch", "adhesion", "contact", "friction"]
ENTRIES = [(key, name) for key, registry in variant_keys().items() for name in registry]


def _registries() -> dict[str, Registry]:
    """Every :class:`Registry` at module level in the physics layer, ``"module.NAME"`` -> registry."""
    out = {}
    for info in pkgutil.iter_modules(physics.__path__):
        module = importlib.import_module(f"pipeline.physics.{info.name}")
        for attr, value in vars(module).items():
            if isinstance(value, Registry) and all(value is not r for r in out.values()):
                out[f"{module.__name__}.{attr}"] = value
    return out


def test_every_physics_registry_is_the_live_choice_list_of_its_scene_key():
    registries = _registries()
    assert len(registries) >= 12  # (the shipped variants' registries: none may drop out of the scan unnoticed)
    keys = variant_keys()
    for where, registry in registries.items():
        assert registry.key in keys, f"{where} ({registry.key}) is no scene key's choices"
        assert keys[registry.key] is registry, where  # the registry itself: read live, not a copy
    assert len(keys) == len(registries)


@pytest.mark.parametrize("key,name", ENTRIES, ids=[f"{k}={n}" for k, n in ENTRIES])
def test_every_entry_has_the_one_shape(key, name):
    entry = variant_keys()[key][name]
    assert isinstance(entry, Entry)
    assert entry.summary and "\n" not in entry.summary, "one line for --help-keys and docs/model.md"
    assert entry.source, "where the law is stated"
    assert hasattr(entry, "behaviour")
    for keyword, where in entry.parameters:  # the scene values it reads exist, by their SI name
        section, _, stem = where.partition(".")
        assert keyword.isidentifier() and section in SCHEMA, where
        to_si(make_scene(FLYING))[section][stem]  # (a value the SI view does not have: KeyError)
        assert scene_key(where).partition(".")[2] in SCHEMA[section]  # (the key a scene file writes)


def _unknown(registry: Registry):
    with pytest.raises(ValueError) as exc:
        registry.lookup("no-such-variant")
    return str(exc.value)


@pytest.mark.parametrize("key", list(variant_keys()))
def test_an_unknown_name_is_one_line_naming_the_key_and_the_choices(key):
    registry = variant_keys()[key]
    assert _unknown(registry) == f"{key} = 'no-such-variant': expected one of {list(registry)}"
    section, _, name = key.partition(".")
    with pytest.raises(SceneError, match=f"{name}.*one of " + ", ".join(map(repr, registry))):
        make_scene(FLYING, **{section: {name: "no-such-variant"}})


def test_a_registered_entry_is_at_once_a_choice_and_in_help_keys(monkeypatch):
    registry = variant_keys()["solver.fhm_measure"]
    monkeypatch.setitem(registry, "half-range", Variant(behaviour=lambda d: float(np.ptp(d)) / 2,
                                                        summary="half the peak-to-peak (a test)", source="a test"))
    scene = make_scene(FLYING, solver={"fhm_measure": "half-range"})
    assert scene["solver"]["fhm_measure"] == "half-range"
    assert "      half-range: half the peak-to-peak (a test)" in describe_keys("solver").splitlines()
    assert "| `solver.fhm_measure` | `half-range` | half the peak-to-peak (a test) |" in variants_table()


def test_docs_model_variants_table_is_the_generated_one():
    page = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    assert with_variants_table(page) == page, \
        "docs/model.md's variants table differs from the registries: run `make variants`"
    # every variant key and option is in it, the default marked once per key
    for key, registry in variant_keys().items():
        default = SCHEMA[key.partition(".")[0]][key.partition(".")[2]].default
        assert default in registry, key
        for name in registry:
            assert f"| `{key}` | `{name}`{' (default)' if name == default else ''} |" in page


# ------------------------------------------------------------------------------------ reaching the model
def _bulge_table(scene) -> object:
    """A small bulge table of the scene's footprint by the closed form (the dynamics reads any law's table
    the same way, :func:`pipeline.model.bulge_table.from_dataset`)."""
    si = to_si(scene)
    return bulge_table.bulge_table(model="ph-limit", p_pad=si.air_bearing.pad_pressure, a=si.tfc.half_length,
                                   b=si.tfc.half_width, speed=disk_speed_m_s(scene["dmw"]),
                                   gaps=np.geomspace(0.05, 20.0, 9) * NM, protrusions=np.linspace(0, 15, 4) * NM)


def _scene(key, name, effects=FLYING, **sections):
    """A scene choosing ``name`` for ``key``; a scene value the entry reads that has no default gets 1 (in the
    key's unit: ``contact.friction_coefficient``)."""
    section, _, stem = key.partition(".")
    values = {section: {stem: name}}
    for _, where in variant_keys()[key][name].parameters:
        s, _, k = scene_key(where).partition(".")
        if SCHEMA[s][k].default is None:
            values.setdefault(s, {})[k] = 1.0
    for s, v in sections.items():
        values[s] = {**values.get(s, {}), **v}
    return make_scene(effects, **values)


def _model(scene):
    """The model of ``scene`` (interface tables in memory with contact or adhesion; a bulge table when a
    law reads one)."""
    bulge = _bulge_table(scene) if scene_inputs.table_stages(scene) else None
    if scene.effects & {"contact", "adhesion"}:
        interface = build_tables(scene, roughness_statistics(scene))
        return assembly.build_model(scene, interface, None, K, bulge=bulge), interface
    return assembly.build_model(scene, None, None, None, bulge=bulge), None


class Spy:
    """A behaviour that records its calls and returns the entry's own."""

    def __init__(self, behaviour):
        self.behaviour, self.calls = behaviour, 0

    def __call__(self, *args, **kwargs):
        self.calls += 1
        return self.behaviour(*args, **kwargs)


def _spied(monkeypatch, key, name) -> Spy:
    """The entry ``name`` of ``key``'s registry with its behaviour replaced by a :class:`Spy` of it."""
    registry = variant_keys()[key]
    spy = Spy(registry[name].behaviour)
    monkeypatch.setitem(registry, name, replace(registry[name], behaviour=spy))
    return spy


def _tfc_law(key, name, entry, monkeypatch):
    scene = _scene(key, name)
    model, _ = _model(scene)
    law_forces = [law.force.func if isinstance(law.force, partial) else law.force for law in model.tfc_tabulated]
    if entry.force is None:  # ("none": the model without it)
        assert model.tfc_tabulated == () and model.tfc_stiffening is None
    elif entry.closed_form == "gap-power":  # the kernel's compiled form, with the entry's parameters
        assert model.tfc_stiffening is not None and model.tfc_tabulated == ()
        assert model.tfc_stiffening["k_t"] == to_si(scene).air_bearing.tfc_stiffness
    else:  # tabulated: the entry's force, bound to the scene values it names
        assert law_forces == [entry.force]
        assert scene_inputs.table_stages(scene) == ((entry.table,) if entry.table else ())
        bound = model.tfc_tabulated[0].force.keywords
        assert {k: bound[k] for k, _ in entry.parameters} == assembly.law_parameters(scene, entry)


def _friction_arm(key, name, entry, monkeypatch):
    scene = _scene(key, name)
    model, _ = _model(scene)
    assert model.slider.friction_arm == to_si(scene).slider.thickness * entry.behaviour
    assert model.p["friction_arm"] == model.slider.friction_arm


def _stiffness_root(key, name, entry, monkeypatch):
    spy = _spied(monkeypatch, key, name)
    model, _ = _model(_scene(key, name))
    chosen = [r for r in model.info["roots"] if (r["k_f"], r["k_r"]) == (model.slider.k_f, model.slider.k_r)]
    assert spy.calls >= 1 and len(chosen) == 1 and entry.behaviour(chosen[0]) and model.info["chosen"] == name


def _rear_law(key, name, entry, monkeypatch):
    model, _ = _model(_scene(key, name))
    assert model.rear_law.name == name and ab.REAR_LAWS[model.rear_law.name] is entry
    assert model.rear_law.key == forces.rear_law_ref(name).key


def _bulge_profile(key, name, entry, monkeypatch):
    model, _ = _model(_scene(key, name, air_bearing={"bulge": "ph-limit"}))
    (law,) = model.tfc_tabulated
    kw = law.force.keywords
    assert kw["profile"] == name
    g = np.array([1.0, 2.0]) * NM
    # the compiled closed form with the entry's profile code
    expected = [bb.ph_force_stiffness(gi, 5 * NM, kw["p_pad"], kw["a"], kw["b"], entry.behaviour, 0.0)[0] for gi in g]
    # tol: the same compiled law called through its wrapper or directly: the same operations
    np.testing.assert_allclose(law.force(g, 5 * NM), expected, rtol=1e-14)


def _bulge_slip(key, name, entry, monkeypatch):
    # consumed by the bulge stage's Reynolds solve (pipeline.model.bulge_table.scene_table), on a small grid
    # here: the table says which slip it solved with, and the solve runs the entry's coefficients
    scene = _scene(key, name, air_bearing={"bulge": "reynolds"},
                   solver={"bulge_cells_per_a": 4, "bulge_cells_per_b": 2})
    si = to_si(scene)
    registry = variant_keys()[key]
    seen = []

    class Coefficients(tuple):  # (the entry's coefficients, noting that the solve read them)
        def __iter__(self):
            seen.append(True)
            return super().__iter__()

    if entry.behaviour is not None:
        monkeypatch.setitem(registry, name, replace(entry, behaviour=Coefficients(entry.behaviour)))
    ds = bulge_table.bulge_table(model="reynolds", p_pad=si.air_bearing.pad_pressure, a=si.tfc.half_length,
                                 b=si.tfc.half_width, speed=disk_speed_m_s(scene["dmw"]),
                                 gaps=np.array([1.0, 2.0, 4.0, 8.0]) * NM, protrusions=np.array([0.0, 9.0]) * NM,
                                 profile="ellipsoid", slip=scene["air_bearing"]["bulge_slip"],
                                 grid=reynolds.ReynoldsGrid(cells_per_a=4, cells_per_b=2))
    assert ds.attrs["slip_model"] == name and np.all(np.isfinite(ds["bulge_lift"].values))
    assert bool(seen) == (entry.behaviour is not None)


def _friction(key, name, entry, monkeypatch):
    spy = _spied(monkeypatch, key, name)
    # the lubricant shear on, so that the switching has two parts to place
    model, interface = _model(_scene(key, name, effects=CONTACT, lubricant={"shear_stress_mpa": 5.0}))
    assert spy.calls == 1 and model.friction is not None
    if key == "contact.friction_switching":  # a second table (the continuous part) or none
        assert model.friction.shape[1] == (8 if spy.behaviour(np.zeros(2), np.ones(2))[1] is not None else 4)


def _area_model(key, name, entry, monkeypatch):
    model, _ = _model(_scene(key, name, effects=CONTACT))
    assert model.area_model == name
    if entry.behaviour is None:
        assert kernel_inputs.interface_tables(model, 5 * NM, 1e-11).contact is model.contact
    else:
        spy = _spied(monkeypatch, key, name)
        tabs = kernel_inputs.interface_tables(model, 5 * NM, 1e-11)
        assert spy.calls == 1 and tabs.contact is not model.contact and tabs.contact.shape == model.contact.shape


def _start(key, name, entry, monkeypatch):
    if entry.behaviour is not None:
        spy = _spied(monkeypatch, key, name)
    model, _ = _model(_scene(key, name))
    assert model.start == name
    y, note = running.start(model, 5 * NM)
    if entry.behaviour is None:
        assert not y.any() and note == "nominal attitude"
    else:
        assert spy.calls == 1 and note.startswith("static")


def _fhm_measure(key, name, entry, monkeypatch):
    spy = _spied(monkeypatch, key, name)
    model, _ = _model(_scene(key, name, solver={"duration_ms": 0.2, "transient_ms": 0.1}))
    assert model.fhm_measure == name
    outcomes.summarize(running.run_model(model, 5 * NM))
    assert spy.calls == 1


#: How each variant key reaches the model: a check that the model built from a scene choosing the entry
#: (or the stage consuming the key) runs the entry's behaviour.
PROBES = {
    "slider.friction_arm": _friction_arm,
    "air_bearing.stiffness_root": _stiffness_root,
    "air_bearing.rear_law": _rear_law,
    "air_bearing.tfc_stiffening": _tfc_law,
    "air_bearing.bulge": _tfc_law,
    "air_bearing.bulge_profile": _bulge_profile,
    "air_bearing.bulge_slip": _bulge_slip,
    "contact.friction_law": _friction,
    "contact.friction_switching": _friction,
    "contact.area_model": _area_model,
    "solver.start": _start,
    "solver.fhm_measure": _fhm_measure,
}


def test_every_variant_key_has_a_probe():
    assert set(PROBES) == set(variant_keys())


@pytest.mark.parametrize("key,name", ENTRIES, ids=[f"{k}={n}" for k, n in ENTRIES])
def test_every_entry_is_a_scene_choice_that_reaches_the_model(key, name, monkeypatch):
    section, _, stem = key.partition(".")
    registry = variant_keys()[key]
    assert SCHEMA[section][stem].choices is registry and name in SCHEMA[section][stem].choices
    PROBES[key](key, name, registry[name], monkeypatch)
