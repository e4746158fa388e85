"""Loading scene files (pipeline.config.loading): ``--set`` overrides change the value and the scene's hash
(and a restated value changes neither), are validated and blamed on the option; a minimal file takes its
name from the file and every default; relative record paths are taken from the scene's folder; a file
that is missing or not TOML is one SceneError naming the file (docs/cli.md, "Scenes")."""

from __future__ import annotations

import pytest

from pipeline.config.scene import SceneError, load_scene, parse_override


def _error(path, overrides=()):
    with pytest.raises(SceneError) as exc:
        load_scene(path, overrides)
    return str(exc.value)


def test_set_override_changes_value_and_hash(paper_scene, paper_config):
    s = load_scene(paper_config, ["tfc.protrusion_nm=9.0"])
    assert s["tfc"]["protrusion_nm"] == 9.0
    assert paper_scene["tfc"]["protrusion_nm"] == 11.0
    assert s.hash != paper_scene.hash
    assert s.overrides == ["tfc.protrusion_nm=9.0"]
    # same override, same identity
    assert load_scene(paper_config, ["tfc.protrusion_nm=9.0"]).hash == s.hash
    # an override that restates the file's value changes nothing in the configuration
    assert load_scene(paper_config, ["tfc.protrusion_nm=11.0"]).hash == paper_scene.hash


def test_set_override_list_and_integer(paper_config):
    s = load_scene(paper_config, ['scene.effects=["air_bearing", "contact"]', "solver.quadrature_nodes=48"])
    assert s.effects == {"air_bearing", "contact"}
    assert s["solver"]["quadrature_nodes"] == 48


def test_set_override_is_validated(paper_config):
    with pytest.raises(SceneError) as exc:
        load_scene(paper_config, ["tfc.protrusion_nm=-3"])
    msg = str(exc.value)
    # blamed on the --set option that set it, not on the (valid) file
    assert msg.startswith("--set tfc.protrusion_nm=-3: tfc.protrusion_nm") and ">= 0" in msg
    assert str(paper_config) not in msg


def test_parse_override_malformed():
    with pytest.raises(SceneError, match="section.key=value"):
        parse_override("protrusion_nm=9")


def test_minimal_scene_takes_name_from_file(write_scene):
    s = load_scene(write_scene("[tfc]\nprotrusion_nm = 5\n", name="tiny.toml"))
    assert s.name == "tiny"
    assert s["tfc"]["protrusion_nm"] == 5.0 and isinstance(s["tfc"]["protrusion_nm"], float)
    assert s["air_bearing"]["flying_height_nm"] == 11.0


def test_existing_dmw_record_is_resolved(write_scene, tmp_path):
    (tmp_path / "rec.csv").write_text("t,x\n0,0\n")
    s = load_scene(write_scene('[dmw]\nsource = "rec.csv"\n'))
    assert s["dmw"]["source"] == str((tmp_path / "rec.csv").resolve())


def test_invalid_toml(write_scene):
    path = write_scene("[tfc\nprotrusion_nm = 1\n")
    msg = _error(path)
    assert str(path) in msg
    assert "not valid TOML" in msg and "line 1" in msg


def test_missing_scene_file(tmp_path):
    path = tmp_path / "nothere.toml"
    msg = _error(path)
    assert str(path) in msg and "scene file does not exist" in msg
