"""The lift cap, hypothesis H8 (``air_bearing.lift_cap_gap_nm``, docs/model.md, section "Lift cap (hypothesis H8)"):
off leaves the TFC-point table identical, on holds the bulge force constant below the cap gap and leaves it
unchanged above, bad values are refused, and the simulations' inputs key changes with it."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline import runner
from pipeline.config.scene import SceneError, load_scene
from pipeline.model import dynamics as dyn
from pipeline.model import forces as fo
from pipeline.model import assembly, kernel_inputs
from pipeline.model import piecewise as pw
from pipeline.physics import bulge_bearing as bb

NM = 1e-9
#: the bulge scene (p h = const law) at the lab's pad pressure, flying only (no interface table needed)
SETS = ["air_bearing.pad_pressure_mpa=2.2", 'scene.effects=["air_bearing","pitch"]']


@pytest.fixture(scope="module")
def scenes(repo_root):
    path = repo_root / "configs" / "paper-2009-bulge.toml"
    return {cap: load_scene(path, SETS + ([] if cap is None else [f"air_bearing.lift_cap_gap_nm={cap}"]))
            for cap in (None, 0.0, 1.65)}


def _kernel_force(model, delta, g):
    c, x0, h = kernel_inputs.tfc_table(model, delta)
    p = dyn.with_values(model.p, delta=delta, tfc_x0=x0, tfc_h=h)
    return np.array([fo.tfc_air_force(p, None, c, gi) for gi in g])


def test_off_leaves_the_table_identical(scenes):
    """No cap (the default) and a cap at 0 give the same TFC-point table, bit for bit, as the bare p h = const
    law sampled on the kernel's grid."""
    plain = assembly.build_model(scenes[None], None, None, None)
    zero = assembly.build_model(scenes[0.0], None, None, None)
    for delta in (4 * NM, 10.4 * NM):
        a, x0, h = kernel_inputs.tfc_table(plain, delta)
        b, _, _ = kernel_inputs.tfc_table(zero, delta)
        assert np.array_equal(a, b)
        law = bb.BULGE_LAWS["ph-limit"]
        g = np.linspace(law.gap_range[0] * plain.p.FH0, law.gap_range[1] * plain.p.FH0, law.points)
        F = bb.ph_limit_force(g, delta, **assembly.law_parameters(scenes[None], law))
        np.testing.assert_array_equal(a, pw.piecewise_coefficients(F, h, 3))


def test_on_holds_the_force_below_the_cap_gap_and_not_above(scenes):
    plain = assembly.build_model(scenes[None], None, None, None)
    capped = assembly.build_model(scenes[1.65], None, None, None)
    delta = 10.4 * NM
    F_s = bb.ph_limit_force(np.array([1.65 * NM]), delta, 2.2e6, 3e-6, 25e-6, "ellipsoid")[0]
    below = np.array([0.3, 0.7, 1.0, 1.5]) * NM
    above = np.array([1.8, 3.0, 6.0, 20.0]) * NM
    kb = _kernel_force(capped, delta, below)
    np.testing.assert_allclose(kb[:, 0], F_s, rtol=1e-6)  # the cubic rings only next to the kink
    assert np.all(np.abs(kb[:, 1]) < 1e-3 * _kernel_force(plain, delta, [1.65 * NM])[0, 1])
    np.testing.assert_allclose(_kernel_force(capped, delta, above), _kernel_force(plain, delta, above), rtol=1e-6)
    grows = _kernel_force(plain, delta, below)[:, 0] / F_s  # the law itself keeps growing
    assert np.all(np.diff(grows) < 0) and grows[-1] > 1.05 and grows[0] > 2.0


def test_bad_values_are_refused(repo_root):
    path = repo_root / "configs" / "paper-2009-two-population-identified.toml"
    with pytest.raises(SceneError, match=r"lift_cap_gap_nm.*-1.*>= 0"):
        load_scene(path, ["air_bearing.lift_cap_gap_nm=-1.0"])
    with pytest.raises(SceneError, match="lift_cap_gap_nm = 1.65 caps the bulge lift.*'none'"):
        load_scene(path, ["air_bearing.lift_cap_gap_nm=1.65", 'air_bearing.bulge="none"'])


def test_the_cap_is_an_input_of_the_simulations(scenes):
    """The model reads the cap (:data:`pipeline.model.assembly.MODEL_FIELDS`): it changes the simulations'
    inputs key; the bulge table does not read it (the cap acts on the model's TFC-point law, not on the table)."""
    stage = runner.registry()["sweep"]
    parts = [runner.scene_part(scenes[c], stage.reads) for c in (None, 1.65)]
    assert parts[0] != parts[1]
    bulge = runner.registry()["bulge"]
    assert "air_bearing.lift_cap_gap_nm" not in bulge.reads
