"""The free parameters of a study (pipeline.analyses.free_parameters): a bad key names the field, a list element
sets only that element, and every numeric scene key has CF units."""

from __future__ import annotations
import pytest
from pipeline.config.scene import SceneError
from pipeline.analyses import free_parameters


def test_bad_parameter_key_names_the_field(paper_scene):
    with pytest.raises(SceneError, match=r"identify.parameters\[0\].key = 'dmw.rms_um'"):
        free_parameters.parse_parameters([{"key": "dmw.rms_um", "low": 0, "high": 1}], "f.toml", "identify.parameters")
    with pytest.raises(SceneError, match="low < high"):
        free_parameters.parse_parameters([{"key": "dmw.rms_nm", "low": 1, "high": 0}], "f.toml", "identify.parameters")
    with pytest.raises(SceneError, match="index into a list"):
        free_parameters.parse_parameters([{"key": "air_bearing.frequencies_khz[2]", "low": 1, "high": 2}], "f", "p")


def test_list_element_parameter_sets_only_that_element(paper_scene):
    p = free_parameters.parse_parameters([{"key": "air_bearing.frequencies_khz[1]", "low": 200, "high": 400}], "f", "p")
    sc = free_parameters.with_values(paper_scene, p, [350.0])
    assert sc["air_bearing"]["frequencies_khz"] == [120.0, 350.0]
    assert free_parameters.scene_value(sc, p[0]) == 350.0


def test_parameter_units_are_cf_for_every_numeric_scene_key():
    import cf_units  # (a declared test dependency: pyproject.toml's `test` extra)
    from pipeline.config.scene import SCHEMA
    for section, keys in SCHEMA.items():
        for key, spec in keys.items():
            if spec.kind in ("float", "floats"):
                units = free_parameters.Parameter(f"{section}.{key}", 0.0, 1.0).units
                cf_units.Unit(units)  # UDUNITS parses it
    units = {name: free_parameters.Parameter(name, 0.0, 1.0).units for name in
             ("lubricant.work_of_adhesion_j_m2", "contact.damping_n_s_m", "roughness.summit_density_per_um2",
              "slider.density_kg_m3", "dmw.sample_rate_mhz", "contact.section_depth_sigma")}
    assert units == {"lubricant.work_of_adhesion_j_m2": "J m-2", "contact.damping_n_s_m": "N s m-1",
                     "roughness.summit_density_per_um2": "um-2", "slider.density_kg_m3": "kg m-3",
                     "dmw.sample_rate_mhz": "MHz", "contact.section_depth_sigma": "1"}
    assert free_parameters.Parameter("air_bearing.frequencies_khz[0]", 1.0, 2.0).var_name == "air_bearing__frequencies_khz_0"
