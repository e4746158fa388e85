"""The sweep's grid (pipeline.config.grid): range tables ``{start, stop, step}`` with ``stop`` included when
it falls on the grid (to 1e-9 of a step: 15 / 0.2 is 74.99999999999999 in floating point), labels rounded to
1e-9 nm so a protrusion computed twice is the same label, roughness sets labelled from their values (each
number written exactly, so two different sets never share a label), and every bad set one SceneError
naming ``sweep.roughness[i]`` and what was expected."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.config import grid
from pipeline.config.scene import SceneError, scene_from_dict


@pytest.mark.parametrize("table, points", [
    ({"start": 0.0, "stop": 15.0, "step": 0.2}, 76),   # the paper's grid: 15 / 0.2 < 75 in floating point
    ({"start": 0.0, "stop": 0.3, "step": 0.1}, 4),     # 0.3 / 0.1 = 2.9999999999999996
    ({"start": 0.0, "stop": 1.0, "step": 0.3}, 4),     # stop off the grid: 0, 0.3, 0.6, 0.9
    ({"start": 2.0, "stop": 2.0, "step": 0.5}, 1),
])
def test_range_count_includes_stop_on_the_grid(table, points):
    assert grid.range_count(table) == points
    g = grid.range_grid(table)
    assert g.size == points and g[0] == table["start"]
    assert np.all(np.diff(g) > 0) and g[-1] <= table["stop"] + grid.TOL_NM


def test_labels_are_exact_decimals():
    g = grid.range_grid({"start": 0.0, "stop": 15.0, "step": 0.2})
    assert g[1] == 0.2 and g[3] == 0.6 and g[49] == 9.8 and g[-1] == 15.0  # (0.2 * 3 = 0.6000000000000001)
    assert grid.label(0.1 + 0.2) == 0.3
    assert grid.same_point(0.1 + 0.2, 0.3) and not grid.same_point(0.3 + 1e-8, 0.3)
    np.testing.assert_array_equal(grid.same_point(g, 9.8), g == 9.8)


def test_paper_scene_grid_and_default_damping():
    scene = scene_from_dict({})
    assert grid.protrusion_grid(scene).size == 76
    assert grid.damping_grid(scene) == [scene["air_bearing"]["damping_ratio"]]
    assert grid.scene_label(scene) == "sigma0.52nm_R5um_eta13.3"
    assert grid.damping_grid(scene_from_dict({"sweep": {"damping_ratio": [0.02, 0.1]}})) == [0.02, 0.1]


def test_roughness_sets_are_labelled_from_their_values():
    scene = scene_from_dict({"sweep": {"roughness": ["scene", {"sigma_nm": 0.4},
                                                     {"label": "smooth", "sigma_nm": 0.3}]}})
    sets = grid.roughness_sets(scene)
    assert {k: v["sigma_nm"] for k, v in sets.items()} == {
        "sigma0.52nm_R5um_eta13.3": 0.52, "sigma0.4nm_R5um_eta13.3": 0.4, "smooth": 0.3}
    # the missing keys come from the scene's [roughness]
    assert all(v["summit_radius_um"] == scene["roughness"]["summit_radius_um"] for v in sets.values())
    # the default is one set, the scene's own
    assert list(grid.roughness_sets(scene_from_dict({}))) == ["sigma0.52nm_R5um_eta13.3"]


def test_afm_labels_name_the_files_and_stay_short():
    assert grid.roughness_label({"afm": ["a/di-3.di", "b/mi-1.mi"], "route": "spectral"}) == "afm-di-3+mi-1"
    assert grid.roughness_label({"afm": ["a/di-3.di"], "route": "deterministic"}) == "afm-di-3-deterministic"
    many = ["x" * 30 + f"{i}.di" for i in range(3)]
    long = grid.roughness_label({"afm": many})
    assert len(long) <= 64 and long.startswith("afm-" + "x" * 30 + "0+2-")
    assert grid.roughness_label({"afm": many}) == long                      # deterministic
    assert grid.roughness_label({"afm": many[:2] + ["other/" + many[2]]}) != long  # the hash sees every path


@pytest.mark.parametrize("items, message", [
    (["nope"], r"sweep\.roughness\[0\] = 'nope': unknown roughness label; expected \"scene\" or a table"),
    ([{"label": "a b", "sigma_nm": 0.4}], r"sweep\.roughness\[0\]\.label = 'a b': expected a label of letters"),
    ([{"sigma_nm": 0.4}, {"sigma_nm": 0.4}], r"sweep\.roughness\[1\]: label 'sigma0\.4nm_R5um_eta13\.3' is used twice"),
    ([{"sigma_um": 0.4}], r"unknown key sweep\.roughness\[0\]\.sigma_um .*expected label or one of sigma_nm"),
    ([{"sigma_nm": -0.4}], r"sweep\.roughness\.sigma_nm \(set None\) = -0\.4: expected"),
])
def test_bad_roughness_sets_are_one_line_errors(items, message):
    with pytest.raises(SceneError, match=message) as exc:
        grid.roughness_sets(scene_from_dict({"sweep": {"roughness": items}}))
    assert "\n" not in str(exc.value)
