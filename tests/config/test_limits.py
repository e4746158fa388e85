"""Upper bounds on what a scene asks to compute (pipeline.config.limits): a protrusion beyond the flying
height by more than MAX_INTERFERENCE_NM (100 nm) is refused with one line naming the key, the value and the
bound, directly and when a scene is loaded; the bound moves with the flying height; the other limits are
the ones the scene's checks quote (magnitude, work of adhesion, integers), and the paper scene's sizes
(docs: 701 table rows, 8000 samples, 76 scenes) lie 100 to 1000 times below them."""

from __future__ import annotations

import pytest

from pipeline.config import limits
from pipeline.config.scene import SceneError, scene_from_dict


def _raw(fh0=11.0, tfc=11.0, sweep_stop=15.0, sensitivity_stop=None):
    """A scene as :func:`pipeline.config.limits.check_physical` reads it (sections of plain dicts)."""
    return {"air_bearing": {"flying_height_nm": fh0}, "tfc": {"protrusion_nm": tfc},
            "sweep": {"protrusion_nm": {"start": 0.0, "stop": sweep_stop, "step": 0.2}},
            "sensitivity": {"protrusion_nm": None if sensitivity_stop is None else
                            {"start": 0.0, "stop": sensitivity_stop, "step": 1.0}}}


def test_the_interference_bound_is_inclusive_and_moves_with_the_flying_height():
    limits.check_physical(_raw(tfc=111.0))                       # exactly FH0 + 100 nm
    limits.check_physical(_raw(fh0=50.0, tfc=150.0))
    with pytest.raises(limits.LimitError) as exc:
        limits.check_physical(_raw(tfc=111.5), "scene.toml")
    assert str(exc.value) == ("scene.toml: tfc.protrusion_nm = 111.5 nm: expected at most the flying height "
                              "air_bearing.flying_height_nm = 11 nm + 100 nm; an interference of 100.5 nm is "
                              "outside the rough-surface contact model")
    assert isinstance(exc.value, ValueError)


@pytest.mark.parametrize("raw, key", [(_raw(sweep_stop=112.0), "sweep.protrusion_nm stop = 112 nm"),
                                      (_raw(sensitivity_stop=200.0), "sensitivity.protrusion_nm stop = 200 nm")])
def test_every_protrusion_key_is_bounded(raw, key):
    with pytest.raises(limits.LimitError, match=f"^<scene>: {key}: expected at most"):
        limits.check_physical(raw, "<scene>")


def test_loading_refuses_an_unphysical_protrusion_as_a_scene_error():
    assert scene_from_dict({"tfc": {"protrusion_nm": 111.0}})["tfc"]["protrusion_nm"] == 111.0
    with pytest.raises(SceneError, match=r"tfc\.protrusion_nm = 111\.5 nm: .*an interference of 100\.5 nm"):
        scene_from_dict({"tfc": {"protrusion_nm": 111.5}})


def test_the_scene_checks_quote_these_limits():
    with pytest.raises(SceneError, match=r"solver\.duration_ms = 1e\+101: expected a number of magnitude at most 1e\+100"):
        scene_from_dict({"solver": {"duration_ms": 1e101}})
    with pytest.raises(SceneError, match=r"work_of_adhesion_j_m2 = 1\.5: expected a number in \[0, 1\] J/m\^2"):
        scene_from_dict({"lubricant": {"work_of_adhesion_j_m2": limits.MAX_WORK_OF_ADHESION + 0.5}})
    assert limits.MAX_INTEGER == 9223372036854775807  # int64's largest


def test_limits_are_far_above_the_paper_scene():
    # the paper scene's sizes (module docstring): 701 rows, 8000 history and record samples, 76 scenes
    for limit, paper_size in ((limits.MAX_TABLE_ROWS, 701), (limits.MAX_HISTORY_SAMPLES, 8000),
                              (limits.MAX_RECORD_SAMPLES, 8000), (limits.MAX_SCENES, 76)):
        assert 100 <= limit / paper_size, (limit, paper_size)
    assert limits.MAX_KEPT_HISTORY_SAMPLES >= limits.MAX_HISTORY_SAMPLES
    # about ten times the paper scene's work of adhesion (0.106 J/m^2: 9.4 times)
    paper_work = scene_from_dict({})["lubricant"]["work_of_adhesion_j_m2"]
    assert paper_work == 0.106 and limits.MAX_WORK_OF_ADHESION / paper_work == pytest.approx(10, rel=0.1)
