"""Loading scene files (pipeline.config.loading): ``--set`` overrides change the value and the scene's hash
(and a restated value changes neither), are validated and blamed on the option; a minimal file takes its
name from the file and every default; relative record paths are taken from the scene's folder; a file
that is missing or not TOML is one SceneError naming the file (docs/cli.md, "Scenes").
Scenes by name (:func:`pipeline.config.loading.find_scene`): the scenes of configs/ ship with the package and
load by name from any folder; a file that exists at the path given wins; a miss names the path tried and the
shipped scenes (docs/cli.md, "Scenes by name")."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from pipeline.cli import main
from pipeline.config.loading import find_scene, shipped_scenes
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


# Scenes by name


def test_the_shipped_scenes_are_the_files_of_configs(repo_root):
    shipped = shipped_scenes()
    configs = sorted(repo_root.glob("configs/*.toml"))
    assert list(shipped) == sorted(p.stem for p in configs) and "paper-2009" in shipped
    # one home: in the clone the package's scenes are the files of configs/ (pipeline/scenes/ holds a link to each,
    # relative, so that a clone anywhere keeps them; a scene added to configs/ without its link is not shipped)
    assert all(path == (repo_root / "configs" / f"{name}.toml").resolve() for name, path in shipped.items())
    links = sorted((repo_root / "pipeline" / "scenes").iterdir())
    assert [p.name for p in links] == [p.name for p in configs]
    assert all(p.is_symlink() and os.readlink(p) == f"../../configs/{p.name}" for p in links)


@pytest.mark.parametrize("name", ["paper-2009", "paper-2009-identified", "sweep-3x3"])
def test_a_name_loads_the_scene_its_file_does_from_any_folder(name, repo_root, tmp_path, monkeypatch):
    by_path = load_scene(repo_root / "configs" / f"{name}.toml", ["contact.k=0.5"])
    monkeypatch.chdir(tmp_path)
    for given in (name, f"{name}.toml"):
        by_name = load_scene(given, ["contact.k=0.5"])
        assert by_name.hash == by_path.hash and by_name.path == by_path.path.resolve()
        assert by_name.name == name  # (results/<name>/ as from the path)


def test_a_file_that_exists_wins_over_the_shipped_scene(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "paper-2009.toml").write_text('[scene]\nname = "mine"\n[tfc]\nprotrusion_nm = 3.5\n')
    mine = load_scene("paper-2009.toml")
    assert mine.name == "mine" and mine["tfc"]["protrusion_nm"] == 3.5
    assert load_scene("paper-2009").name == "paper-2009"  # (no file "paper-2009" here: the shipped one)
    assert find_scene("paper-2009") == shipped_scenes()["paper-2009"]
    assert find_scene("paper-2009.toml") == Path("paper-2009.toml")  # (the path as given)


def test_extends_reads_beside_the_scene_then_the_shipped_one(tmp_path, monkeypatch, repo_root):
    monkeypatch.chdir(tmp_path)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "derived.toml").write_text('[scene]\nname = "derived"\nextends = "paper-2009-identified"\n'
                                       '[tfc]\nprotrusion_nm = 3.5\n')
    scene = load_scene(mine / "derived.toml")
    identified = load_scene(repo_root / "configs" / "paper-2009-identified.toml")
    assert scene["tfc"]["protrusion_nm"] == 3.5 and identified["tfc"]["protrusion_nm"] != 3.5
    assert scene["lubricant"] == identified["lubricant"]  # the whole chain identified -> bulge -> paper
    assert scene["air_bearing"]["bulge"] == "ph-limit"  # (set by the base's base)
    # a base of that name beside the derived scene is the one read
    (mine / "paper-2009-identified").write_text('[scene]\nname = "b"\n[tfc]\nprotrusion_nm = 2.0\n'
                                                '[air_bearing]\nbulge = "none"\n')
    (mine / "derived.toml").write_text('[scene]\nname = "derived"\nextends = "paper-2009-identified"\n')
    assert load_scene(mine / "derived.toml")["tfc"]["protrusion_nm"] == 2.0


@pytest.mark.parametrize("given, tried", [("nope", "nope"), ("nope.toml", "nope.toml"),
                                          ("configs/paper-2009.toml", "configs/paper-2009.toml")])
def test_a_miss_names_the_path_tried_and_the_shipped_scenes(given, tried, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # (outside the clone: configs/paper-2009.toml is a path, not a name)
    with pytest.raises(SceneError) as info:
        load_scene(given)
    msg = str(info.value)
    assert msg.startswith(f"{given}: scene file does not exist (looked for {tmp_path / tried})")
    assert "\n" not in msg and all(name in msg for name in shipped_scenes())


def test_a_missing_base_names_the_derived_scene(tmp_path):
    (tmp_path / "d.toml").write_text('[scene]\nname = "d"\nextends = "nobase"\n')
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "d.toml")
    msg = str(info.value)
    assert msg.startswith(f"{tmp_path / 'd.toml'}: scene.extends: nobase: scene file does not exist "
                          f"(looked for {tmp_path / 'nobase'})") and "paper-2009-identified" in msg


def test_the_command_line_takes_a_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["dmw", "nope", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "looked for" in err and "paper-2009-identified" in err
    # `hdi roughness NAME`: a shipped scene's name is a scene, not an AFM file
    assert main(["roughness", "paper-2009", "--out", str(tmp_path / "out"), "-q"]) == 0
    assert (tmp_path / "out" / "roughness.nc").is_file() and list(tmp_path.iterdir()) == [tmp_path / "out"]


# ------------------------------------------------------------------ numbers, nesting and one value per --set
BIG = "1" + "0" * 400  # (a 400-digit integer: float() of it overflowed)


@pytest.mark.parametrize("text, name", [
    (f"[tfc]\nprotrusion_nm = {BIG}\n", "tfc.protrusion_nm"),
    (f"[air_bearing]\nfrequencies_khz = [{BIG}, 300.0]\n", "air_bearing.frequencies_khz"),
    (f"[sweep]\nprotrusion_nm = {{start = 0, stop = {BIG}, step = 1}}\n", "sweep.protrusion_nm"),
    (f'[sweep]\nroughness = [{{label = "a", sigma_nm = {BIG}}}]\n', "sweep.roughness"),
    ("[slider]\nlength_mm = 1000000000000000000000000000000\n", "slider.length_mm"),
])
def test_an_integer_beyond_64_bits_in_a_file_is_refused_naming_the_file(write_scene, text, name):
    """A 400-digit integer in a scene file (a key, a list, a range, a table) ended in OverflowError; a 31-digit
    one in a float key was taken as 1e30 mm. TOML's integers have 64 bits."""
    path = write_scene(text)
    msg = _error(path)
    assert msg.startswith(f"{path}: {name}: an integer of about ") and "\n" not in msg
    assert "expected an integer of magnitude at most 2**63 - 1 (TOML's 64-bit integers" in msg


def test_an_integer_beyond_64_bits_in_a_base_scene_names_the_base(write_scene, tmp_path):
    base = write_scene(f"[tfc]\nprotrusion_nm = {BIG}\n", "base.toml")
    path = write_scene('[scene]\nextends = "base.toml"\nname = "derived"\n')
    assert _error(path).startswith(f"{base}: tfc.protrusion_nm: an integer of about 401 digits")


def test_an_integer_beyond_64_bits_in_a_set_or_the_api_is_refused(paper_config):
    import pipeline as hdi
    msg = _error(paper_config, [f"tfc.protrusion_nm={BIG}"])
    assert msg.startswith(f"--set tfc.protrusion_nm={BIG}: tfc.protrusion_nm: an integer of about 401 digits")
    msg = _error(paper_config, [f"air_bearing.frequencies_khz=[{BIG}, 300]"])
    assert "air_bearing.frequencies_khz: an integer of about 401 digits" in msg
    with pytest.raises(SceneError, match=r"^--set tfc\.protrusion_nm=10{400}: tfc\.protrusion_nm: an integer of about"):
        hdi.load_scene(paper_config, {"tfc.protrusion_nm": 10**400})
    with pytest.raises(SceneError, match=r"^--set tfc\.protrusion_nm=\.\.\.: an integer of more than 4,300 digits"):
        load_scene(paper_config, ["tfc.protrusion_nm=" + "1" * 5000])  # (Python's own limit, a ValueError)


@pytest.mark.parametrize("value", ["[" * 3000 + "]" * 3000, "{a = " * 2000 + "1" + "}" * 2000])
def test_a_value_nested_deeper_than_the_parser_goes_is_one_error(write_scene, paper_config, value):
    """Arrays or inline tables nested thousands deep ended in RecursionError (in the file and in --set)."""
    path = write_scene(f"[tfc]\nprotrusion_nm = {value}\n")
    msg = _error(path)
    assert msg == (f"{path}: not valid TOML: lists or tables nested too deep for the TOML parser; expected at most 8 "
                   "levels (docs/cli.md, section 'Scenes')")
    assert _error(paper_config, [f"tfc.protrusion_nm={value}"]).startswith(
        "--set tfc.protrusion_nm=...: lists or tables nested too deep for the TOML parser")
    path = write_scene("[tfc]\nprotrusion_nm = " + "[" * 20 + "]" * 20 + "\n")  # (parsed, beyond the bound)
    assert _error(path) == (f"{path}: tfc.protrusion_nm: lists or tables nested more than 8 deep; expected a number, "
                            "a string, a list or a table of them (docs/cli.md, section 'Scenes')")


@pytest.mark.parametrize("text, extra", [("tfc.protrusion_nm=5\n[contact]\nk = 0.5", "contact"),
                                         ("tfc.protrusion_nm=5\nhalf_length_um = 4", "half_length_um")])
def test_a_set_value_is_one_value(paper_config, text, extra):
    """A newline in a --set value smuggled a second key or table into the parse, which was then dropped: the
    scene ran with contact.k unset and no word. One --set is one value."""
    with pytest.raises(SceneError) as exc:
        parse_override(text)
    assert str(exc.value) == (f"--set {text!r}: tfc.protrusion_nm: the value holds more than one TOML value (a "
                              f"newline and {extra!r}); expected one value: one --set per key")
    with pytest.raises(SceneError, match="the value runs over several lines and is no TOML value"):
        parse_override("scene.description=abc\n[contact]\nk = = 1")  # (no TOML: not a bare word either)
    # a value of several lines that is one TOML value is one value
    assert parse_override("air_bearing.frequencies_khz=[120.0,\n 300.0]") == ("air_bearing", "frequencies_khz",
                                                                               [120.0, 300.0])
    assert parse_override("scene.description=two words") == ("scene", "description", "two words")
    assert load_scene(paper_config, ['scene.description="a\\n[contact]\\nk = 0.5"'])["scene"]["description"] == \
        "a\n[contact]\nk = 0.5"  # (a TOML string holding newlines is a string)
