"""The scene schema (pipeline.config.schema): unit suffixes split off key names (the longest suffix wins,
so ``_mhz`` is not read as ``_hz`` nor ``_mn`` as ``_n``), every default passes its own key's check and
choices (the defaults are the paper scene, docs/model.md, section "Parameters"), the ``[identify]`` keys
generated from the paper's targets, folder names, and ``hdi --help-keys``.
"""

from __future__ import annotations

import pytest

from pipeline.config.schema import (EFFECTS, SCHEMA, UNIT_SUFFIXES, SceneError, describe_keys, is_folder_name,
                                    strip_unit, target_keys, unit_suffix)
from pipeline.physics import paper
from pipeline.units import SUFFIX_FACTORS


@pytest.mark.parametrize("key, stem, suffix", [
    ("flying_height_nm", "flying_height", "nm"),
    ("sample_rate_mhz", "sample_rate", "mhz"),          # not "_hz"
    ("contact_force_mn", "contact_force", "mn"),        # not "_n"
    ("damping_n_s_m", "damping", "n_s_m"),              # not "_m"
    ("work_of_adhesion_j_m2", "work_of_adhesion", "j_m2"),
    ("summit_density_per_um2", "summit_density", "per_um2"),
    ("k", "k", None),
    ("seed", "seed", None),
])
def test_strip_unit_takes_the_longest_suffix(key, stem, suffix):
    assert strip_unit(key) == (stem, suffix)
    assert unit_suffix(key) == suffix


def test_unit_suffixes_are_the_units_table():
    assert set(UNIT_SUFFIXES) == set(SUFFIX_FACTORS)
    # every key named with a unit has a suffix the table converts (pipeline.config.si reads it)
    for section, keys in SCHEMA.items():
        for key in keys:
            suffix = unit_suffix(key)
            assert suffix is None or SUFFIX_FACTORS[suffix] > 0, (section, key)


def test_every_default_passes_its_own_check_and_choices():
    checked = 0
    for section, keys in SCHEMA.items():
        for key, spec in keys.items():
            d = spec.default
            if d is None:
                continue
            if spec.check and spec.kind in ("float", "int"):
                assert spec.check[0](d), (section, key, d)
                checked += 1
            if spec.choices and spec.kind == "str":
                assert d in spec.choices, (section, key, d)
            if spec.choices and spec.kind == "strs":
                assert set(d) <= set(spec.choices), (section, key, d)
            if spec.kind == "floats" and spec.length:
                assert len(d) == spec.length, (section, key, d)
    assert checked > 50
    assert SCHEMA["scene"]["effects"].default == list(EFFECTS)
    assert SCHEMA["air_bearing"]["flying_height_nm"].default == paper.FLYING_HEIGHT_NM


def test_checks_refuse_what_their_expectation_excludes():
    flying, check_text = SCHEMA["air_bearing"]["flying_height_nm"].check
    assert check_text.startswith("a number in (0, 10000] nm") and flying(1e-3) and flying(1e4)
    assert not flying(0.0) and not flying(-1.0) and not flying(1.0001e4)
    thickness, check_text = SCHEMA["lubricant"]["thickness_nm"].check
    assert check_text == "a number >= 0" and thickness(0.0) and not thickness(-1e-9)
    # a first racing stage of one DMW record is allowed (docs/model.md, "Identification"), none is not
    records, check_text = SCHEMA["identify"]["racing_records"].check
    assert check_text == "an integer >= 1" and records(1) and not records(0)


def test_identify_keys_are_generated_from_the_targets():
    keys = target_keys()
    declared = {s.key for t in paper.TARGETS.values() for s in t.keys()}
    assert set(keys) == declared
    assert set(keys) <= set(SCHEMA["identify"])
    # a pair (lo, hi) is a list of two numbers; its check is the ordering
    band = keys["bouncing_range_nm"]
    assert band.kind == "floats" and band.length == 2 and band.default == list(paper.BOUNCING_RANGE_NM)
    assert band.check[0]([9.8, 10.8]) and not band.check[0]([10.8, 10.8])
    flying = keys["fhm_flying_range_nm"]
    assert flying.check[0]([5.0, 5.0]) and not flying.check[0]([7.0, 4.0])
    tol = keys["touchdown_tolerance_nm"]
    assert tol.kind == "float" and tol.default == 0.1 and not tol.check[0](0.0)
    assert keys["sliding_at_nm"].default == paper.LIGHT_CONTACT_NM


@pytest.mark.parametrize("name, ok", [("paper-2009", True), ("a.b_c-1", True), (".", False), ("..", False),
                                      ("a/b", False), ("", False), ("sp ace", False), ("..x", True)])
def test_folder_names(name, ok):
    assert is_folder_name(name) is ok


def test_help_keys_lists_one_line_per_key():
    text = describe_keys("tfc")
    lines = text.strip().splitlines()
    assert lines[0] == "[tfc]" and len(lines) == 1 + len(SCHEMA["tfc"])
    assert "  protrusion_nm = 11.0  (float)  TFC protrusion delta [nm]" in lines
    assert describe_keys().count("\n[") == len(SCHEMA) - 1
    with pytest.raises(SceneError, match=r"^--help-keys warp: no section \[warp\]; expected one of scene, "):
        describe_keys("warp")


#: Absurd physical values that were taken without a word (tables, statistics and runs were made of them),
#: each with the bound it breaks (pipeline.config.schema): key -> (value, bound in the message).
ABSURD = {
    "air_bearing.flying_height_nm": (1e90, "(0, 10000] nm"),
    "air_bearing.frequencies_khz": ([1e-90, 1e90], "in [0.1, 10000] kHz"),
    "slider.length_mm": (1e90, "(0, 100] mm"),
    "slider.density_kg_m3": (1e-90, "[1, 100000] kg/m^3"),
    "tfc.half_length_um": (1e-90, "[0.001, 10000] um"),
    "roughness.sigma_nm": (1e50, "(0, 1000] nm"),
    "roughness.summit_radius_um": (1e-60, "[0.0001, 10000] um"),
    "roughness.summit_density_per_um2": (1e90, "(0, 1e+06] um^-2"),
    "materials.disk_modulus_gpa": (1e-90, "[0.001, 10000] GPa"),
    "lubricant.intermolecular_distance_nm": (1e-90, "[0.01, 10] nm"),
    "dmw.rms_nm": (1e90, "[0, 1000] nm"),
    "dmw.rpm": (1e90, "(0, 100000] rpm"),
    "dmw.radius_mm": (1e9, "(0, 1000] mm"),
}


@pytest.mark.parametrize("name", sorted(ABSURD))
def test_absurd_physical_values_are_refused_with_the_bound_they_break(paper_scene, name):
    section, key = name.split(".")
    value, bound = ABSURD[name]
    with pytest.raises(SceneError) as exc:
        paper_scene.replace(**{section: {key: value}})
    msg = str(exc.value)
    assert f"{name} = " in msg and bound in msg and "\n" not in msg
    default = SCHEMA[section][key].default  # (the paper scene's values lie within every bound)
    spec = SCHEMA[section][key]
    assert spec.check[0](default if spec.kind == "floats" else float(default))
