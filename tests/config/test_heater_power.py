"""The scene's heater actuation (pipeline.config.heater_power): a touchdown given in mW becomes the touchdown
in nm that the stages read, by the scene's efficiency or table; a scene without an actuation is as before;
a bad actuation or a touchdown in mW that cannot be converted is refused at load, naming the keys."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.config import heater_power
from pipeline.config.scene import SceneError, load_scene

LINEAR = ["tfc.actuation_nm_per_mw=0.125"]
TABLE = ["tfc.actuation_power_mw=[0.0, 40.0, 80.0, 120.0]", "tfc.actuation_protrusion_nm=[0.0, 5.0, 9.0, 16.0]"]


def test_without_an_actuation_nothing_changes(paper_config):
    scene = load_scene(paper_config)
    assert heater_power.actuation(scene) is None
    assert heater_power.power_mw(scene, [9.8]) is None and heater_power.power_coordinates(scene, [9.8]) == {}
    assert scene["touchdown"]["onset_nm"] == 9.8 and scene["touchdown"]["onset_mw"] is None


def test_a_touchdown_in_mw_is_the_touchdown_in_nm_through_the_efficiency(paper_config):
    scene = load_scene(paper_config, LINEAR + ["touchdown.onset_mw=78.4", "touchdown.previous_mw=76.8"])
    assert (scene["touchdown"]["onset_nm"], scene["touchdown"]["previous_nm"]) == (9.8, 9.6)  # 0.125 nm/mW
    # tol: one division by the efficiency: one rounding of the decimal inputs
    np.testing.assert_allclose(heater_power.power_mw(scene, [9.6, 9.8]), [76.8, 78.4], rtol=1e-14)
    coord = heater_power.power_coordinates(scene, np.array([0.0, 8.0]))["heater_power"]
    assert coord.dims == ("protrusion",) and coord.attrs["units"] == "mW" and coord.values.tolist() == [0.0, 64.0]
    # varied again, the touchdown in nm follows the mW (or the new efficiency), not the one derived before
    assert scene.replace(touchdown={"onset_mw": 80.0})["touchdown"]["onset_nm"] == 10.0
    assert scene.replace(tfc={"actuation_nm_per_mw": 0.25})["touchdown"]["previous_nm"] == 19.2


def test_a_touchdown_in_mw_through_a_table_is_interpolated_between_its_rows(paper_config):
    scene = load_scene(paper_config, TABLE + ["touchdown.onset_mw=84.0", "touchdown.previous_mw=80.0"])
    assert scene["touchdown"]["onset_nm"] == pytest.approx(9.7, abs=1e-9) and scene["touchdown"]["previous_nm"] == 9.0
    # tol: linear interpolation between table rows of round numbers: a few roundings
    np.testing.assert_allclose(heater_power.power_mw(scene, [2.5, 9.0, 16.0]), [20.0, 80.0, 120.0], rtol=1e-14)
    # beyond the table (an ensemble's target protrusion outside the sweep): no power, the rest kept
    # tol: linear interpolation at a table row: exact, a rounding at most
    np.testing.assert_allclose(heater_power.power_mw(scene, [9.0, 17.0]), [80.0, np.nan], rtol=1e-14)


@pytest.mark.parametrize("override, message", [
    (["touchdown.onset_mw=98.0", "touchdown.previous_mw=96.0"], "touchdown.onset_mw = 98.0 needs the heater's actuation"),
    (LINEAR + ["touchdown.onset_mw=78.4"], "touchdown.onset_mw is given without touchdown.previous_mw"),
    (LINEAR + ["touchdown.onset_mw=78.4", "touchdown.previous_mw=76.8", "touchdown.onset_nm=9.7"],
     "touchdown.onset_mw = 78.4 mW is 9.8 nm, but touchdown.onset_nm = 9.7"),
    (TABLE + ["touchdown.onset_mw=130.0", "touchdown.previous_mw=80.0"],
     "touchdown.onset_mw = 130.0 mW lies outside tfc.actuation_power_mw 0-120 mW"),
    (["tfc.actuation_power_mw=[0.0, 50.0, 40.0]", "tfc.actuation_protrusion_nm=[0.0, 5.0, 16.0]"],
     "power is not strictly increasing at row 3 of 3"),
    (["tfc.actuation_power_mw=[0.0, 50.0, 100.0]", "tfc.actuation_protrusion_nm=[0.0, 5.0, 10.0]"],
     "sweep.protrusion_nm 0-15 nm lies outside tfc.actuation_protrusion_nm 0-10 nm"),
    (["tfc.actuation_power_mw=[0.0, 50.0]"], "tfc.actuation_power_mw is given without tfc.actuation_protrusion_nm"),
    (LINEAR + TABLE, "are both given: expected one form of the actuation"),
    (["tfc.actuation_nm_per_mw=0"], "tfc.actuation_nm_per_mw = 0: expected a positive number"),
])
def test_a_bad_actuation_or_touchdown_in_mw_is_refused_at_load_naming_the_keys(paper_config, override, message):
    with pytest.raises(SceneError, match=message.replace(".", r"\.").replace("(", r"\(").replace(")", r"\)")) as err:
        load_scene(paper_config, override)
    assert "\n" not in str(err.value)
