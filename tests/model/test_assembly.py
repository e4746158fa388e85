"""Building the model from a scene (pipeline.model.assembly; docs/model.md, sections "Slider dynamics", "Air
bearing", "Separation datum"): the rigid slider's mass and pitch inertia of a block, the pad stiffnesses
whose two modes are the scene's natural frequencies (both roots of the modal inversion), the friction arm
``T/2`` or ``T``, the summit datum ``y_s`` from the interface or McCool's relation, the contact criterion's
rule, the state's tolerances and the lift cap (hypothesis H8)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from pipeline.config.scene import scene_from_dict
from pipeline.model import assembly

NM = 1e-9


def _modal_frequencies(s) -> np.ndarray:
    """Natural frequencies [Hz] of the undamped 2-DOF slider (z, theta) on its two pads."""
    K = np.array([[s.k_f + s.k_r, s.k_r * s.l_r - s.k_f * s.l_f],
                  [s.k_r * s.l_r - s.k_f * s.l_f, s.k_f * s.l_f**2 + s.k_r * s.l_r**2]])
    w2 = np.linalg.eigvals(np.linalg.solve(np.diag([s.m, s.I]), K))
    return np.sort(np.sqrt(w2.real)) / (2 * np.pi)


@pytest.mark.parametrize("root", ["stiff-rear", "pitch-first", "bounce-first"])
def test_slider_modes_are_the_scenes_frequencies(root):
    scene = scene_from_dict({"air_bearing": {"stiffness_root": root}})
    s, info = assembly.slider_from_scene(scene)
    L, W, T = 0.85e-3, 0.70e-3, 0.23e-3
    assert s.m == pytest.approx(4250.0 * L * W * T, rel=1e-12)  # tol: the same product, a few roundings
    # tol: the same product, a few roundings
    assert s.I == pytest.approx(s.m * (L**2 + T**2) / 12, rel=1e-12)  # a block pitching about its CG
    # tol: 2x2 eigenproblem (LAPACK, condition ~ f2/f1), under 1e-13 on any host
    np.testing.assert_allclose(_modal_frequencies(s), [120e3, 300e3], rtol=1e-9)
    assert info["chosen"] == root and any(r["k_f"] == s.k_f and r["k_r"] == s.k_r for r in info["roots"])
    if root == "stiff-rear":
        assert s.k_r > s.k_f
    # tol: a subtraction and a unit product, a few roundings
    assert s.l_c == pytest.approx(L / 2 - 8e-6, rel=1e-12) and s.g0 == pytest.approx(11 * NM, rel=1e-12)


def test_friction_arm_is_half_the_thickness_or_the_thickness():
    cg, _ = assembly.slider_from_scene(scene_from_dict({}))
    gimbal, info = assembly.slider_from_scene(scene_from_dict({"slider": {"friction_arm": "gimbal"}}))
    assert cg.friction_arm == pytest.approx(0.115e-3, rel=1e-12)  # tol: a unit product and a halving, a few roundings
    # tol: a unit product, a few roundings
    assert gimbal.friction_arm == pytest.approx(0.23e-3, rel=1e-12) and info["friction_arm"] == "gimbal"


def test_undamped_slider_has_no_pad_dampers():
    s, info = assembly.slider_from_scene(scene_from_dict({}), damping_ratio=0.0)
    assert (s.c_f, s.c_r) == (0.0, 0.0) and info["damping_ratio"] == 0.0


def test_summit_datum_from_the_interface_or_mccool():
    scene = scene_from_dict({})
    # tol: a unit product, one rounding
    assert assembly.summit_datum(scene, xr.Dataset({"y_s": 0.7})) == pytest.approx(0.7 * NM, rel=1e-12)
    # McCool: y_s = 4 sigma / sqrt(pi alpha), alpha = 2412.74 (sigma eta R)^2 of the paper's statistics
    sigma, eta, R = 0.52e-9, 13.3e12, 5e-6
    alpha = 2412.74 * (sigma * eta * R) ** 2
    assert assembly.summit_datum(scene, None) == pytest.approx(4 * sigma / math.sqrt(math.pi * alpha), rel=1e-5)


def test_afm_scenes_need_the_interface_for_the_datum(repo_root):
    scene = scene_from_dict({"roughness": {"afm": [str(repo_root / "tests" / "data" / "afm" / "di-3.di")]}})
    with pytest.raises(ValueError, match="a scene with roughness.afm needs its interface.nc"):
        assembly.summit_datum(scene, None)


def test_contact_criterion_rule():
    contact = frozenset({"air_bearing", "contact"})
    assert assembly.criterion(contact, 0.978) == 0.978
    assert np.isnan(assembly.criterion(frozenset({"air_bearing"}), None))
    for k in (None, np.nan, np.inf):
        with pytest.raises(ValueError, match=r"^the contact effect needs the criterion k: set contact\.k"):
            assembly.criterion(contact, k)


def test_tolerances_scale_with_the_arm_and_the_second_frequency():
    scene = scene_from_dict({"solver": {"atol_nm": 2e-4}})
    s, _ = assembly.slider_from_scene(scene)
    atol, w2 = 2e-4 * NM, 2 * np.pi * 300e3
    # tol: products and quotients of the same numbers, a few roundings
    np.testing.assert_allclose(assembly.tolerances(scene, s), [atol, atol / s.l_c, atol * w2, atol / s.l_c * w2],
                               rtol=1e-12)


def test_capped_lift_is_held_below_the_cap_gap():
    def lift(g, delta):
        return 1e-3 * delta / (g + 1e-9)

    g = np.array([0.1, 0.5, 1.0, 2.0]) * NM
    capped = assembly.capped_lift(g, 10 * NM, force=lift, gap=1.0 * NM)
    np.testing.assert_array_equal(capped[:3], lift(1.0 * NM, 10 * NM))
    assert capped[3] == lift(2.0 * NM, 10 * NM)


def test_a_model_on_another_record_is_the_model_built_with_it():
    """``with_record`` (a study candidate's realisations) gives, field by field, the model ``build_model``
    gives with that record, and leaves the model it copies as it was."""
    import dataclasses
    from slider_scenes import ALL, build, make_scene, synthetic_record
    scene = make_scene(ALL, contact={"damping_n_s_m": 0.02})
    other = synthetic_record(scene.replace(dmw={"seed": 7, "rms_nm": 0.3}))
    first = build(scene)
    before = first.dmw.copy()
    moved, built = assembly.with_record(first, other), build(scene, other)
    assert not np.array_equal(moved.dmw, before)
    for f in dataclasses.fields(assembly.Model):
        a, b = getattr(moved, f.name), getattr(built, f.name)
        if isinstance(a, np.void):
            assert a.tobytes() == b.tobytes(), f.name
        elif isinstance(a, np.ndarray) or isinstance(a, float):
            assert np.array_equal(a, b, equal_nan=True), f.name
        else:
            assert a == b, f.name
    np.testing.assert_array_equal(first.dmw, before)
    assert moved.p is not first.p and moved.statics is not first.statics


def test_a_per_summit_friction_law_reads_its_own_friction_column():
    """``contact.friction_law = "kogut-etsion"``: the model's friction table is the interface tables' friction
    column as that law integrated it; tables integrated for another law are refused in one line."""
    from pipeline.model.interface_tables import build_tables, roughness_statistics
    from pipeline.model.piecewise import piecewise_coefficients
    from slider_scenes import ALL, K, make_scene
    scene = make_scene(ALL, contact={"friction_law": "kogut-etsion"})
    plain = make_scene(ALL)
    tables = build_tables(scene, roughness_statistics(scene))
    model = assembly.build_model(scene, tables, None if "dmw" not in scene.effects else _record(scene), K)
    values = tables["friction_stress"].values * 1e6  # [MPa] -> [Pa]
    order = scene["solver"]["interpolation_order"]
    np.testing.assert_array_equal(model.friction, piecewise_coefficients(values, model.p.tab_h, order))
    with pytest.raises(ValueError, match="integrates the 'shear-strength' law, but contact.friction_law = "
                                         "'kogut-etsion' reads its own per-summit table; re-run `hdi interface`"):
        assembly.build_model(scene, build_tables(plain, roughness_statistics(plain)), _record(scene), K)
    with pytest.raises(ValueError, match="integrates the 'kogut-etsion' law, but contact.friction_law = "
                                         "'shear-strength' reads the shear-strength table"):
        assembly.build_model(plain, tables, _record(plain), K)


def _record(scene):
    from slider_scenes import synthetic_record
    return synthetic_record(scene)
