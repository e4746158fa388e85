"""Declared reads (pipeline/config/fields.py): declarations name schema keys, and a declared scene refuses
any other key, also through its SI view."""

from __future__ import annotations

import pickle

import pytest

from pipeline.config.fields import DeclaredScene, UndeclaredRead, expand, fields, parameter_fields, section_fields, whole
from pipeline.config.schema import SCHEMA
from pipeline.config.si import si_value, to_si
from pipeline.physics.bulge_bearing import BULGE_LAWS


def test_fields_are_schema_keys_and_expand_sections():
    assert fields("tfc.protrusion_nm", "tfc.protrusion_nm") == ("tfc.protrusion_nm",)
    assert fields("interface.*") == ("interface.*",)
    assert expand(fields("interface.*", "tfc.protrusion_nm")) == ("interface.model", "interface.adhesion",
                                                                  "tfc.protrusion_nm")
    assert len(expand(("solver.*",))) == len(SCHEMA["solver"]) == 19
    assert section_fields("sweep", "batch_size") == tuple(f"sweep.{k}" for k in SCHEMA["sweep"] if k != "batch_size")
    with pytest.raises(ValueError, match=r"'tfc.protrusion_um': no key of the scene schema"):
        fields("tfc.protrusion_um")
    with pytest.raises(ValueError, match="no key of the scene schema"):
        fields("*")
    with pytest.raises(ValueError, match=r"\['size'\] are no keys of \[sweep\]"):
        section_fields("sweep", "size")


def test_registry_parameters_are_named_by_their_scene_keys():
    assert set(parameter_fields(BULGE_LAWS.values())) == {
        "air_bearing.pad_pressure_mpa", "air_bearing.bulge_profile", "tfc.half_length_um", "tfc.half_width_um"}


def test_a_declared_scene_reads_its_keys_and_refuses_the_others(paper_scene):
    view = DeclaredScene(paper_scene, "the test stage", ("tfc.protrusion_nm", "scene.effects"))
    assert view["tfc"]["protrusion_nm"] == paper_scene["tfc"]["protrusion_nm"] == 11.0
    assert view.has("contact") and view.effects == paper_scene.effects
    assert view.name == paper_scene.name and view.hash == paper_scene.hash and whole(view) is paper_scene
    with pytest.raises(UndeclaredRead, match=r"^the test stage read the scene key tfc.half_length_um, which it "
                                             r"does not declare"):
        view["tfc"]["half_length_um"]
    with pytest.raises(UndeclaredRead, match="tfc.half_length_um"):
        dict(view["tfc"])  # (a whole section read: each of its keys)
    assert view.config == {"tfc": {"protrusion_nm": 11.0}, "scene": {"effects": paper_scene["scene"]["effects"]}}
    # (not a KeyError: a reader's "absent key, take the default" does not swallow it)
    assert not issubclass(UndeclaredRead, (KeyError, ValueError, RuntimeError))


def test_the_si_view_of_a_declared_scene_reads_through_the_declaration(paper_scene):
    view = DeclaredScene(paper_scene, "the test stage", ("air_bearing.flying_height_nm",))
    si = to_si(view)
    assert si.air_bearing.flying_height == paper_scene["air_bearing"]["flying_height_nm"] * 1e-9  # (one product)
    assert si_value(si, "air_bearing.flying_height") == si.air_bearing.flying_height
    with pytest.raises(UndeclaredRead, match="air_bearing.damping_ratio"):
        si.air_bearing.damping_ratio


def test_a_declared_section_allows_the_keys_it_has_when_read(paper_scene, monkeypatch):
    """A section declared whole (``"identify.*"``) reads a key a registry added to it after the declaration."""
    view = DeclaredScene(paper_scene, "the test stage", fields("identify.*"))
    assert view["identify"]["population"] == paper_scene["identify"]["population"]
    monkeypatch.setitem(SCHEMA["identify"], "dummy_nm", SCHEMA["identify"]["interference_nm"])
    assert "identify.dummy_nm" in expand(fields("identify.*"))
    with pytest.raises(UndeclaredRead):
        view["tfc"]["protrusion_nm"]


def test_a_varied_declared_scene_keeps_the_declaration_and_pickles(paper_scene):
    view = DeclaredScene(paper_scene, "the test stage", ("tfc.protrusion_nm",))
    varied = view.replace(tfc={"protrusion_nm": 10.0})
    assert varied["tfc"]["protrusion_nm"] == 10.0 and varied.reader == "the test stage"
    with pytest.raises(UndeclaredRead):
        varied["tfc"]["half_length_um"]
    back = pickle.loads(pickle.dumps(varied))  # (a stage's tasks carry it to dask workers)
    assert back["tfc"]["protrusion_nm"] == 10.0 and back.allowed == varied.allowed and back == varied
