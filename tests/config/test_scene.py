"""Scene files (pipeline.config.scene, the names users import): the paper scene loads with the values of
docs/model.md, section "Parameters", and a deterministic hash; the module's names are those of the schema,
validation and loading modules. Loading and --set overrides are tested in tests/config/test_loading.py, the
validation errors in tests/config/test_validation.py."""

from __future__ import annotations

import re

from pipeline.config.scene import EFFECTS, load_scene


# --------------------------------------------------------------------------------------------
# The paper scene
# --------------------------------------------------------------------------------------------

def test_paper_scene_loads(paper_scene, paper_config):
    s = paper_scene
    assert s.path == paper_config
    assert s.name == "paper-2009"
    assert s.effects == frozenset(EFFECTS)
    # Values of docs/model.md, section "Parameters" / configs/paper-2009.toml
    assert s["air_bearing"]["flying_height_nm"] == 11.0
    assert s["tfc"]["half_length_um"] == 3.0 and s["tfc"]["half_width_um"] == 25.0
    assert s["roughness"]["sigma_nm"] == 0.52
    assert s["lubricant"]["thickness_nm"] == 0.75
    assert s["materials"]["plasticity_index"] == 0.52
    assert s["materials"]["hardness_gpa"] is None          # derived from psi (docs/model.md, section "Parameters")
    assert s["contact"]["k"] is None                       # calibrated, not given
    assert s["sweep"]["protrusion_nm"] == {"start": 0.0, "stop": 15.0, "step": 0.2}
    # every schema key is filled in (defaults)
    assert s["solver"]["quadrature_nodes"] == 24
    assert re.fullmatch(r"[0-9a-f]{64}", s.hash)


def test_hash_is_deterministic(paper_config):
    assert load_scene(paper_config).hash == load_scene(paper_config).hash
