"""Feasibility of a study's box (pipeline/analyses/feasibility.py): McCool's relations need the bandwidth
``alpha = 2412.74 (sigma eta R)^2 > 0.8968`` (docs/model.md, section "Asperity statistics"), so with the paper's
sigma and R a summit density below ``sqrt(0.8968 / 2412.74) / (sigma R)`` is refused before any evaluation,
in one line naming the file, the field, the key, the bound and the limit found by bisection (checked against
that closed form); the coupled keys are grouped by the sections that enter one rule together; the paper
scene's own boxes are feasible."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipeline.analyses import feasibility as fe
from pipeline.analyses.free_parameters import Parameter
from pipeline.config.scene import SceneError
from pipeline.physics.asperity_statistics import ALPHA_MIN


def _eta_limit(scene) -> float:
    """The summit density [um^-2] where alpha = ALPHA_MIN, with the scene's sigma and R."""
    r = scene["roughness"]
    sigma_r = r["sigma_nm"] * 1e-9 * r["summit_radius_um"] * 1e-6          # [m^2]
    return math.sqrt(ALPHA_MIN / 2412.74) / sigma_r * 1e-12                 # [m^-2] -> [um^-2]


def test_the_paper_scene_is_feasible_and_its_reference_is_its_own_values(paper_scene):
    params = [Parameter("roughness.summit_density_per_um2", 8.0, 20.0), Parameter("dmw.rms_nm", 0.3, 0.5)]
    ref = fe.reference(paper_scene, params)
    assert ref[0] == paper_scene["roughness"]["summit_density_per_um2"]      # within its bounds: the scene's
    assert ref[1] == 0.4                                                     # 0.266 nm is outside: the middle
    assert fe.problem(paper_scene, params, ref) is None
    fe.check_box(paper_scene, params, "identify.parameters")


def test_a_density_below_mccools_limit_is_refused_with_the_limit(paper_scene):
    limit = _eta_limit(paper_scene)
    assert 5.0 < limit < 8.0, limit
    params = [Parameter("roughness.summit_density_per_um2", 5.0, 20.0)]
    why = fe.problem(paper_scene, params, [5.0])
    r = paper_scene["roughness"]
    alpha = 2412.74 * (r["sigma_nm"] * 1e-9 * 5.0e12 * r["summit_radius_um"] * 1e-6) ** 2
    assert why.startswith(f"McCool's bandwidth alpha = {alpha:.3g} < {ALPHA_MIN}")
    with pytest.raises(SceneError) as info:
        fe.check_box(paper_scene, params, "sensitivity.parameters")
    line = str(info.value)
    assert line.startswith(f"{paper_scene.path}: sensitivity.parameters: roughness.summit_density_per_um2 low "
                           "bound 5 is infeasible: McCool's bandwidth") and "\n" not in line
    found = float(line.split("feasible from about ")[1].split(" ")[0])
    ref = paper_scene["roughness"]["summit_density_per_um2"]
    assert found == pytest.approx(limit, abs=2 * fe.LIMIT_TOLERANCE * (ref - 5.0))
    fe.check_box(paper_scene, [Parameter("roughness.summit_density_per_um2", limit * 1.001, 20.0)], "x")


def test_a_bad_value_of_the_scenes_rules_is_named_without_the_file(paper_scene):
    params = [Parameter("air_bearing.frequencies_khz[0]", 100.0, 500.0)]
    why = fe.problem(paper_scene, params, [500.0])               # the first mode above the second (300 kHz)
    assert why.endswith("air_bearing.frequencies_khz = [500.0, 300.0]: expected two increasing frequencies in "
                        "[0.1, 10000] kHz (air-bearing modes lie at 50-500 kHz) (air-bearing natural frequencies "
                        "[kHz] (recon))")
    assert not why.startswith(str(paper_scene.path))


def test_keys_are_grouped_by_the_sections_that_enter_one_rule_together():
    params = [Parameter(k, 0.0, 1.0) for k in ("roughness.sigma_nm", "dmw.rms_nm", "materials.hardness_gpa",
                                               "tfc.protrusion_nm", "slider.density_kg_m3", "air_bearing.damping_ratio",
                                               "lubricant.work_of_adhesion_j_m2")]
    assert fe.groups(params) == [[0, 2], [1], [3, 4, 5], [6]]
    assert [len(c) for c in fe._corners([0, 2])] == [2] * 4 and fe._corners([1]) == []
    nine = list(range(9))                                        # more than MAX_CORNER_KEYS: each pair's corners
    assert len(fe._corners(nine)) == 4 * math.comb(9, 2)


def test_the_paper_scenes_study_boxes_are_feasible(paper_scene):
    fe.check_study(paper_scene, "identify")                      # (raises at an infeasible bound or corner)
    fe.check_study(paper_scene, "sensitivity")
    # the rule such a box can break: the sensitivity box's lowest summit density is above McCool's limit
    density = next(p for p in paper_scene["sensitivity"]["parameters"] if p["key"].startswith("roughness.summit_d"))
    assert density["low"] > _eta_limit(paper_scene)
    # the scene's own values lie inside both boxes: each study's reference point is the scene itself
    for section in ("identify", "sensitivity"):
        params = [Parameter(p["key"], p["low"], p["high"]) for p in paper_scene[section]["parameters"]]
        assert np.array_equal(fe.reference(paper_scene, params), [fe.scene_value(paper_scene, p) for p in params])
