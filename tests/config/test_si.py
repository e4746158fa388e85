"""``to_si``: every scene key in SI units, by the one units table, read-only."""

from __future__ import annotations


import pytest

from pipeline.config.scene import SCHEMA, unit_suffix
from pipeline.config.si import SI_NAMES, to_si
from pipeline.units import NM, SUFFIX_DIVISORS, UM, UM2, si_factor


def test_paper_scene_values_in_si(paper_scene):
    si = to_si(paper_scene)
    assert si.air_bearing.flying_height == 11.0 * NM  # the same product the model used to form by hand
    assert si.air_bearing.frequencies == (120e3, 300e3)
    assert si.tfc.half_length == pytest.approx(3e-6) and si.tfc.protrusion == paper_scene["tfc"]["protrusion_nm"] * NM
    assert si.roughness.summit_density == pytest.approx(13.3e12)
    assert si.materials.disk_modulus == pytest.approx(150e9)
    assert si.lubricant.work_of_adhesion == 0.106  # J/m^2 is SI
    assert si.dmw.rpm == 5425.0  # a key named by its unit alone has no suffix to drop: kept as it is
    assert si.dmw.sample_rate == pytest.approx(4e6) and si.dmw.record_sample_rate is None
    assert si.contact.section_depth == 3.0  # in sigmas: dimensionless
    assert si.air_bearing.damping_ratio == 0.05 and si.scene.name == "paper-2009"  # no unit: unchanged


def test_every_key_is_converted_by_its_suffix(paper_scene):
    si = to_si(paper_scene)
    for section, keys in SCHEMA.items():
        for key in keys:
            suffix = unit_suffix(key)
            name = SI_NAMES.get((section, key), key if suffix is None else key[: -len(suffix) - 1])
            value, converted = paper_scene[section][key], si[section][name]
            if suffix is None or value is None or isinstance(value, (str, dict)):
                assert converted == value or converted is value
            elif isinstance(value, list):
                if all(isinstance(v, (int, float)) for v in value):
                    assert converted == tuple(v * si_factor(suffix) for v in value)
            elif suffix in SUFFIX_DIVISORS:  # (an inverse unit: divided by its unit)
                assert converted == value / SUFFIX_DIVISORS[suffix], f"{section}.{key}"
            else:
                assert converted == value * si_factor(suffix), f"{section}.{key}"


def test_an_inverse_unit_is_divided_as_the_physics_divides_it(paper_scene):
    """``summit_density_per_um2 / UM2``, the division the summit statistics always made: the product by 1e12
    rounds otherwise for about one value in eight (the paper's 13.3 um^-2 among them)."""
    scene = paper_scene
    assert scene["roughness"]["summit_density_per_um2"] == 13.3
    assert scene.si.roughness.summit_density == 13.3 / UM2 != 13.3 * si_factor("per_um2")
    assert scene.si.roughness.summit_radius == scene["roughness"]["summit_radius_um"] * UM


def test_groups_are_read_only_and_name_what_exists(paper_scene):
    si = to_si(paper_scene)
    with pytest.raises(AttributeError, match="read-only"):
        si.tfc.protrusion = 1.0
    with pytest.raises(AttributeError, match=r"\[tfc\] has no key 'protrusion_nm' in SI form"):
        si.tfc.protrusion_nm
    with pytest.raises(AttributeError, match=r"no section \[nonsense\]"):
        si.nonsense
