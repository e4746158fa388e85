"""Validating a scene (pipeline.config.validation): one test per class of error, each a SceneError whose
message names the file, the ``section.key`` and what was expected (docs/cli.md, "Scenes": "validated on
load with a clear error for every bad field"); a disabled effect's inputs are not required; ``replace``
validates again and equals the same ``--set`` override."""

from __future__ import annotations

import re

import pytest

from pipeline.config.scene import SceneError, load_scene


def _error(path, overrides=()):
    with pytest.raises(SceneError) as exc:
        load_scene(path, overrides)
    return str(exc.value)


def test_unknown_key(write_scene):
    path = write_scene("[tfc]\nfoo_bar = 1\n")
    msg = _error(path)
    assert str(path) in msg
    assert "unknown key tfc.foo_bar" in msg
    assert "expected one of" in msg and "protrusion_nm" in msg


def test_unknown_section(write_scene):
    path = write_scene("[warp]\nx = 1\n")
    msg = _error(path)
    assert str(path) in msg
    assert "unknown section [warp]" in msg
    assert "expected one of" in msg and "[tfc]" in msg


def test_wrong_unit(write_scene):
    path = write_scene("[air_bearing]\nflying_height_um = 0.011\n")
    msg = _error(path)
    assert str(path) in msg
    assert "air_bearing.flying_height_um" in msg
    assert "wrong unit 'um'" in msg and "expected 'nm'" in msg
    assert "air_bearing.flying_height_nm" in msg


def test_wrong_type(write_scene):
    path = write_scene('[tfc]\nprotrusion_nm = "nine"\n')
    msg = _error(path)
    assert str(path) in msg
    assert "tfc.protrusion_nm" in msg and "'nine'" in msg
    assert "expected a number" in msg


def test_wrong_type_bool_is_not_a_number(write_scene):
    path = write_scene("[roughness]\nsigma_nm = true\n")
    msg = _error(path)
    assert str(path) in msg and "roughness.sigma_nm" in msg and "expected a number" in msg


def test_negative_thickness(write_scene):
    path = write_scene("[lubricant]\nthickness_nm = -1\n")
    msg = _error(path)
    assert str(path) in msg
    assert "lubricant.thickness_nm" in msg and "-1" in msg
    assert "expected a number >= 0" in msg


def test_effect_that_does_not_exist(write_scene):
    path = write_scene('[scene]\neffects = ["air_bearing", "warp_drive"]\n')
    msg = _error(path)
    assert str(path) in msg
    assert "scene.effects" in msg
    assert "'warp_drive' is not an effect that exists" in msg
    assert "air_bearing" in msg and "friction" in msg  # what was expected: the known effects


def test_missing_afm_file(write_scene, tmp_path):
    path = write_scene('[roughness]\nafm = ["nope.di"]\n')
    msg = _error(path)
    assert str(path) in msg
    assert "roughness.afm" in msg and "'nope.di'" in msg and "does not exist" in msg
    assert str(tmp_path / "nope.di") in msg  # relative paths are taken from the scene's folder


def test_missing_dmw_record(write_scene, tmp_path):
    path = write_scene('[dmw]\nsource = "missing.csv"\n')
    msg = _error(path)
    assert str(path) in msg
    assert "dmw.source" in msg and "'missing.csv'" in msg and "does not exist" in msg
    assert 'expected "synthetic" or a record file' in msg
    assert str(tmp_path / "missing.csv") in msg


def test_set_paths_are_taken_from_the_working_directory(tmp_path, monkeypatch):
    # issue 35, 5: --set 'roughness.afm=["../afm/x.mi"]' was taken from the scene file's folder
    scenes, work = tmp_path / "scenes", tmp_path / "work"
    (work / "afm").mkdir(parents=True)
    scenes.mkdir()
    (scenes / "rec.csv").write_text("t,x\n0,0\n")  # the scene's own record, beside it
    (work / "rec.csv").write_text("t,x\n0,0\n")
    scene = scenes / "scene.toml"
    scene.write_text('[dmw]\nsource = "rec.csv"\n')
    monkeypatch.chdir(work)
    assert load_scene(scene)["dmw"]["source"] == str((scenes / "rec.csv").resolve())  # the file's own: its folder
    got = load_scene(scene, ['dmw.source="rec.csv"'])
    assert got["dmw"]["source"] == str((work / "rec.csv").resolve())  # typed here: from here
    with pytest.raises(SceneError) as err:
        load_scene(scene, ['roughness.afm=["afm/x.mi"]'])
    msg = str(err.value)
    assert "--set roughness.afm" in msg and "does not exist" in msg
    assert str(work / "afm" / "x.mi") in msg and str(scenes / "afm") not in msg, msg  # where it looked
    with pytest.raises(SceneError, match=re.escape(f"(looked for {work / 'nothere.toml'})")):
        load_scene("nothere.toml")


def test_dmw_record_not_required_without_dmw_effect(write_scene):
    # the README: a disabled effect's inputs are not required
    path = write_scene('[scene]\neffects = ["air_bearing"]\n[dmw]\nsource = "missing.csv"\n')
    assert load_scene(path).effects == {"air_bearing"}


@pytest.mark.parametrize("grid, expected", [
    ("{ start = 5.0, stop = 1.0, step = 0.2 }", "stop >= start"),          # reversed
    ("{ start = -1.0, stop = 1.0, step = 0.2 }", "protrusions >= 0"),      # negative
    ("{ start = 0.0, stop = 1.0, step = 0.0 }", "step > 0"),               # zero step
    ("{ start = 0.0, stop = 1.0, step = -0.2 }", "step > 0"),              # negative step
    ("{}", "a table {start = ..., stop = ..., step = ...}"),               # empty
    ("{ start = 0.0, stop = 1.0 }", "a table {start = ..., stop = ..., step = ...}"),  # incomplete
])
def test_bad_sweep_grid(write_scene, grid, expected):
    path = write_scene(f"[sweep]\nprotrusion_nm = {grid}\n")
    msg = _error(path)
    assert str(path) in msg
    assert "sweep.protrusion_nm" in msg
    assert f"expected {expected}" in msg


def test_empty_damping_list(write_scene):
    path = write_scene("[sweep]\ndamping_ratio = []\n")
    msg = _error(path)
    assert str(path) in msg and "sweep.damping_ratio" in msg and "expected a non-empty list" in msg


def test_friction_needs_contact(write_scene):
    path = write_scene('[scene]\neffects = ["air_bearing", "friction"]\n')
    msg = _error(path)
    assert str(path) in msg and "scene.effects" in msg and "'friction' needs 'contact'" in msg


def test_replace_revalidates_and_matches_override(paper_scene, paper_config):
    r = paper_scene.replace(tfc={"protrusion_nm": 9.0})
    assert r["tfc"]["protrusion_nm"] == 9.0 and paper_scene["tfc"]["protrusion_nm"] == 11.0
    assert r.hash == load_scene(paper_config, ["tfc.protrusion_nm=9.0"]).hash
    with pytest.raises(SceneError, match=r"tfc\.protrusion_nm = -1\.0: expected a number >= 0"):
        paper_scene.replace(tfc={"protrusion_nm": -1.0})


def test_no_racing_records(write_scene):
    path = write_scene("[identify]\nracing_records = 0\n")
    msg = _error(path)
    assert str(path) in msg and "identify.racing_records" in msg and "0" in msg
    assert "expected an integer >= 1" in msg


def test_per_summit_friction_laws_need_the_statistical_tables(write_scene):
    path = write_scene('[contact]\nfriction_law = "kogut-etsion"\n[interface]\nmodel = "deterministic"\n')
    msg = _error(path)
    assert str(path) in msg and "contact.friction_law = 'kogut-etsion'" in msg and "interface.model = 'statistical'" in msg


def test_solid_work_of_adhesion_needs_the_adhesion_effect(write_scene):
    path = write_scene('[scene]\neffects = ["air_bearing", "contact"]\n[lubricant]\nsolid_work_of_adhesion_j_m2 = 0.12\n')
    msg = _error(path)
    assert str(path) in msg and "lubricant.solid_work_of_adhesion_j_m2" in msg and "'adhesion' effect" in msg


def test_solid_work_of_adhesion_out_of_range(write_scene):
    path = write_scene("[lubricant]\nsolid_work_of_adhesion_j_m2 = -0.1\n")
    msg = _error(path)
    assert str(path) in msg and "lubricant.solid_work_of_adhesion_j_m2" in msg and "J/m^2" in msg
