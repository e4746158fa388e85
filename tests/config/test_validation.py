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
    # a path given with --set ('roughness.afm=["../afm/x.mi"]') is the user's, from the working directory, not
    # from the scene file's folder; a path in the file is from the file's folder
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


# ------------------------------------------------------------------ read-only all the way down
def test_a_scene_is_read_only_at_every_depth(paper_config):
    """A list inside a loaded scene could be changed in place: a frequency set to -120 kHz after validation ran
    as a positive one while the provenance recorded it negative; an effect 'bogus' appended was written.
    Copies (pickled to dask workers, deep-copied) are read-only too, with the same hash and text."""
    import copy
    import pickle
    scene = load_scene(paper_config)
    before = (scene.hash, scene.to_toml_text())
    changes = [lambda s: s["air_bearing"]["frequencies_khz"].__setitem__(0, -120.0),
               lambda s: s["scene"]["effects"].append("bogus"),
               lambda s: s["scene"]["effects"].extend(["bogus"]),
               lambda s: s["dmw"]["band_khz"].__iadd__([1.0]),
               lambda s: s["dmw"]["band_khz"].sort(reverse=True),
               lambda s: s["identify"]["parameters"].pop(),
               lambda s: s["identify"]["parameters"][0].__setitem__("low", -5.0),
               lambda s: s.overrides.append("tfc.protrusion_nm=1")]
    for copied in (scene, pickle.loads(pickle.dumps(scene)), copy.deepcopy(scene)):
        for change in changes:
            with pytest.raises(TypeError, match=r"read-only: scene\['\w+'\] cannot be changed in place"):
                change(copied)
        assert (copied.hash, copied.to_toml_text()) == before
        for name in ("path", "config", "overrides"):
            with pytest.raises(AttributeError):
                setattr(copied, name, None)
    assert scene["dmw"]["band_khz"] == [10.0, 500.0] and isinstance(scene["dmw"]["band_khz"], list)  # (read as a list)
    mutable = list(scene["scene"]["effects"]) + ["x"]  # (copies are plain lists)
    mutable.append("y")
    assert len(mutable) == len(scene["scene"]["effects"]) + 2


#: SHA-256 of each shipped scene's configuration text (``Scene.to_toml_text``, the repository's folder written
#: ``<root>``: the bases' paths are absolute). The scene's hash is the SHA-256 of that text and keys the runner's
#: cache: a change here re-runs every stage. The text lists every schema key with its default, so a new key (the
#: heater's actuation, dmw.unit, lubricant.solid_work_of_adhesion_j_m2, the frictional heating's two tfc keys)
#: changes every value, deliberately; the read-only lists left the text of the scenes as it was (checked against
#: the values before them).
#: Update a value only with a deliberate change of that scene file or of the schema.
SHIPPED_TEXT_SHA256 = {
    "paper-2009": "564a6ee0c997254a428564fe8bae5cba0eb41b9804f1607a3dac8e083c268931",
    "paper-2009-bulge": "e1033104295cbdaad0290cd507f510ea0b3fcf4c49a084e4de81c9f6f05bcc3b",
    "paper-2009-identified": "74e2f13bd5b3ccc2df9af511840988aa226bdd936f992623cdf1b93b61e013d8",
    "paper-2009-identified-section-datum": "57428e40a2fe40886a9fb3d4eaf8003c5e0160d5679205dbcc6ab6a855ad1923",
    "paper-2009-reynolds": "4eb010d1083a374663c2a56cf3b2c12b2a083914f53dfedc9fce62292df3bffd",
    "paper-2009-two-population": "f195e96237ff61dcc7996a219007d0f6394bf37b25dd38828565b43a5b616f45",
    "paper-2009-two-population-identified": "967a78677596077e7fa51fcb5935307c415cdeda9f8096ceb0f866c0803eee35",
    "paper-2009-two-population-rough": "fadbb983cebf2d4a9f27bb3cc9309ef7138076d40554971d8c0f6705015d694d",
    "sweep-3x3": "f586eeb2d11f343164794ab87e26180e9074f619d2715f626d113f5d4ab7c46c",
}


@pytest.mark.parametrize("name", sorted(SHIPPED_TEXT_SHA256))
def test_the_shipped_scenes_text_and_hash_are_unchanged(name, repo_root):
    import hashlib
    scene = load_scene(repo_root / "configs" / f"{name}.toml")
    text = scene.to_toml_text()
    assert scene.hash == hashlib.sha256(text.encode()).hexdigest()
    root = str(repo_root.resolve())
    assert hashlib.sha256(text.replace(root, "<root>").encode()).hexdigest() == SHIPPED_TEXT_SHA256[name]


def test_replace_refuses_a_base_scene(paper_scene, repo_root):
    """``replace(scene={"extends": ...})`` recorded a base in the scene's provenance and applied none of its keys."""
    bulge = repo_root / "configs" / "paper-2009-bulge.toml"
    with pytest.raises(SceneError, match=r"^scene\.replace\(scene=\{'extends': .*\}\): scene\.extends cannot be "
                                         r"replaced: a base scene is merged when a scene file is read") as exc:
        paper_scene.replace(scene={"extends": str(bulge)})
    assert "\n" not in str(exc.value)
    # a scene's own section passed back with a key changed (its extends as it is) is no new base
    scene = load_scene(bulge)
    assert scene["scene"]["extends"]
    varied = scene.replace(scene={**scene["scene"], "effects": [e for e in scene.effects if e != "dmw"]})
    assert varied.effects == scene.effects - {"dmw"} and varied["scene"]["extends"] == scene["scene"]["extends"]


# ------------------------------------------------------------------ numbers and nesting from the API
@pytest.mark.parametrize("sections", [{"tfc": {"protrusion_nm": 10**400}},
                                      {"air_bearing": {"frequencies_khz": [10**400, 300.0]}},
                                      {"sweep": {"protrusion_nm": {"start": 0, "stop": 10**400, "step": 1}}},
                                      {"identify": {"parameters": [{"key": "dmw.rms_nm", "low": 0, "high": 10**400}]}},
                                      {"tfc": {"protrusion_nm": 2**63}}])
def test_replace_refuses_an_integer_beyond_64_bits(paper_scene, sections):
    """A 400-digit integer given to ``replace`` (or ``scene_from_dict``) ended in OverflowError."""
    from pipeline.config.scene import scene_from_dict
    (section, keys), = sections.items()
    key = next(iter(keys))
    for make in (lambda: paper_scene.replace(**sections), lambda: scene_from_dict(sections)):
        with pytest.raises(SceneError, match=rf"{section}\.{key}: an integer of about \d+ digits; expected an integer "
                                             r"of magnitude at most 2\*\*63 - 1") as exc:
            make()
        assert "\n" not in str(exc.value)
    # (an integer within 64 bits is a number like any other)
    assert paper_scene.replace(tfc={"protrusion_nm": 9}).hash == paper_scene.replace(tfc={"protrusion_nm": 9.0}).hash


def test_replace_refuses_a_value_nested_deeper_than_any_scene(paper_scene):
    """A list nested 5,000 deep given to ``replace`` ended in RecursionError."""
    from pipeline.config.limits import MAX_NESTING
    deep: list = []
    for _ in range(5000):
        deep = [deep]
    with pytest.raises(SceneError, match=rf"tfc\.protrusion_nm: lists or tables nested more than {MAX_NESTING} deep"):
        paper_scene.replace(tfc={"protrusion_nm": deep})
    shallow: list = []
    for _ in range(MAX_NESTING - 1):
        shallow = [shallow]
    with pytest.raises(SceneError, match=r"tfc\.protrusion_nm = .*: expected a number"):  # (within the bound: the key's check)
        paper_scene.replace(tfc={"protrusion_nm": shallow})


def test_a_long_list_of_histories_is_checked_in_linear_time(write_scene):
    """200,000 protrusions in report.histories_nm: the check for repeated values compared every pair (hours)."""
    import time
    values = [i * 1e-3 for i in range(200_000)]
    path = write_scene("[report]\nhistories_nm = [" + ", ".join(map(repr, values + [values[-1] + 1e-12])) + "]\n")
    t0 = time.perf_counter()
    msg = _error(path)
    assert time.perf_counter() - t0 < 30
    assert "report.histories_nm" in msg and f"{values[-1]:.10g} appears more than once" in msg


def test_a_long_list_of_damping_ratios_is_checked_in_linear_time(write_scene):
    """200,000 damping ratios: the check for repeated values counted each one in the whole list (hours)."""
    import time
    values = [i * 1e-6 for i in range(200_000)]
    path = write_scene("[sweep]\ndamping_ratio = [" + ", ".join(map(repr, values + [values[7]])) + "]\n")
    t0 = time.perf_counter()
    msg = _error(path)
    assert time.perf_counter() - t0 < 30
    assert "sweep.damping_ratio = [0.0, 1e-06, " in msg and "(200001 items)" in msg
    assert f"{values[7]:g} appears more than once" in msg and len(msg) < 600


def test_solid_work_of_adhesion_needs_the_adhesion_effect(write_scene):
    path = write_scene('[scene]\neffects = ["air_bearing", "contact"]\n[lubricant]\nsolid_work_of_adhesion_j_m2 = 0.12\n')
    msg = _error(path)
    assert str(path) in msg and "lubricant.solid_work_of_adhesion_j_m2" in msg and "'adhesion' effect" in msg


def test_solid_work_of_adhesion_out_of_range(write_scene):
    path = write_scene("[lubricant]\nsolid_work_of_adhesion_j_m2 = -0.1\n")
    msg = _error(path)
    assert str(path) in msg and "lubricant.solid_work_of_adhesion_j_m2" in msg and "J/m^2" in msg
