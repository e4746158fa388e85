"""The slider's rigid body and air bearing (docs/model.md, sections "Slider dynamics" and "Parameters"): mass properties, modal
inversion of the pad stiffnesses from two natural frequencies, the choice of root, pad damping,
and the nonlinear rear law."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pipeline.model import assembly
from pipeline.physics import air_bearing as ab
from pipeline.config.scene import scene_from_dict

MM, NM = 1e-3, 1e-9
# The paper's femto slider (docs/model.md, section "Parameters", [recon]): 0.85 x 0.70 x 0.23 mm, 4250 kg/m^3, arms 0.30/0.40 mm.
L, W, T, RHO = 0.85 * MM, 0.70 * MM, 0.23 * MM, 4250.0
L_F, L_R = 0.30 * MM, 0.40 * MM
F1, F2 = 120e3, 300e3


@pytest.fixture(scope="module")
def mass():
    return ab.mass_properties(L, W, T, RHO)


def test_paper_slider_mass_and_inertia(mass):
    # docs/model.md, section "Parameters" states m = 0.58 mg and I = 3.75e-14 kg m^2 for the femto block
    # (m = rho L W T = 0.5816 mg, I = m (L^2 + T^2)/12 = 3.758e-14 kg m^2): within 1 %.
    m, I = mass
    assert m == pytest.approx(0.58e-6, rel=0.01)
    assert I == pytest.approx(3.75e-14, rel=0.01)
    # and exactly the uniform-block formulas
    assert m == pytest.approx(RHO * L * W * T, rel=1e-14)  # tol: the same product, a few roundings apart
    assert I == pytest.approx(m * (L**2 + T**2) / 12, rel=1e-14)  # tol: the same product, a few roundings apart


@pytest.mark.parametrize("f1, f2", [(F1, F2), (100e3, 400e3), (30 * F1, 30 * F2), (120e3, 1000e3)])
def test_both_stiffness_roots_reproduce_the_frequencies(mass, f1, f2):
    # Each (k_f, k_r) root of docs/model.md, section "Slider dynamics"'s two equations must give back exactly the two
    # natural frequencies as the generalised eigenvalues of (K, M): within 1e-9 relative.
    m, I = mass
    roots = ab.stiffness_roots(f1, f2, m, I, L_F, L_R)
    assert len(roots) == 2
    assert not np.allclose(roots[0], roots[1])
    for k_f, k_r in roots:
        assert k_f > 0 and k_r > 0
        w, phi = ab.modes(ab.pad_matrix(k_f, k_r, L_F, L_R), np.diag([m, I]))
        # tol: 2x2 eigenproblem (LAPACK, condition ~ f2/f1), under 1e-13 on any host
        np.testing.assert_allclose(w / (2 * np.pi), [f1, f2], rtol=1e-9)
        # the two invariants used by the inversion (product and sum of w^2)
        w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
        # tol: closed-form invariants of the inversion, tens of roundings
        assert k_f * k_r * (L_F + L_R) ** 2 / (m * I) == pytest.approx(w1**2 * w2**2, rel=1e-9)
        # tol: closed-form invariants of the inversion, tens of roundings
        assert (k_f * (1 / m + L_F**2 / I) + k_r * (1 / m + L_R**2 / I)
                == pytest.approx(w1**2 + w2**2, rel=1e-9))
        # mass-normalised modes: phi^T M phi = 1
        np.testing.assert_allclose(phi.T @ np.diag([m, I]) @ phi, np.eye(2), atol=1e-9)
    # documented order: the root with the larger rear stiffness first
    assert roots[0][1] > roots[1][1]


def test_default_root_is_the_stiff_rear_one_with_the_documented_numbers(mass):
    # docs/model.md, section "Air bearing": of the two roots the one with k_r > k_f: k_f 1.54e5, k_r 5.83e5 N/m at 120/300 kHz
    m, I = mass
    k_f, k_r, info = ab.choose_stiffness(F1, F2, m, I, L_F, L_R, L)
    assert info["chosen"] == "stiff-rear"
    assert k_f == pytest.approx(1.545e5, rel=1e-3) and k_r == pytest.approx(5.833e5, rel=1e-3)
    roots = ab.stiffness_roots(F1, F2, m, I, L_F, L_R)
    assert (k_f, k_r) == pytest.approx(roots[0], rel=1e-12)  # tol: the same root formula on the same numbers
    # its mode shapes: 120 kHz node 0.459 mm behind the CG (beyond the 0.425 mm half-length: bounce-like),
    # 300 kHz node 0.141 mm ahead of the CG
    assert info["roots"][0]["node_mode1"] == pytest.approx(-0.459e-3, abs=1e-6)
    assert info["roots"][0]["node_mode2"] == pytest.approx(0.141e-3, abs=1e-6)
    assert not info["roots"][0]["mode1_pitch_like"]
    # stiffness at the TFC point (8 um before the trailing edge): the static compliance of the
    # bearing there, 1 / (e^T K^-1 e) with e = (1, -l_c): 5.5e5 N/m (docs/model.md, section "Air bearing")
    l_c = L / 2 - 8e-6
    e = np.array([1.0, -l_c])
    k_tfc = 1.0 / (e @ np.linalg.solve(ab.pad_matrix(k_f, k_r, L_F, L_R), e))
    assert k_tfc == pytest.approx(5.5e5, rel=0.01)


def test_named_alternative_roots_and_their_mode_shapes(mass):
    m, I = mass
    roots = ab.stiffness_roots(F1, F2, m, I, L_F, L_R)
    k_f, k_r, info = ab.choose_stiffness(F1, F2, m, I, L_F, L_R, L, root="pitch-first")
    # pitch-first (the first reconstruction): the node of the first (120 kHz) mode lies on the slider
    w, phi = ab.modes(ab.pad_matrix(k_f, k_r, L_F, L_R), np.diag([m, I]))
    assert abs(ab.node_position(phi[:, 0])) < L / 2
    # for the paper slider that is the second root (small rear stiffness, k_f ~ 8 k_r)
    assert (k_f, k_r) == pytest.approx(roots[1], rel=1e-12)  # tol: the same root formula on the same numbers
    assert k_f == pytest.approx(8.473e5, rel=1e-3) and k_r == pytest.approx(1.063e5, rel=1e-3)
    assert [r["mode1_pitch_like"] for r in info["roots"]] == [False, True]
    assert info["roots"][1]["node_mode1"] == pytest.approx(0.340e-3, abs=1e-6)
    assert info["roots"][1]["node_mode2"] == pytest.approx(-0.190e-3, abs=1e-6)
    # bounce-first takes the other one (here the stiff-rear root)
    k_f2, k_r2, info2 = ab.choose_stiffness(F1, F2, m, I, L_F, L_R, L, root="bounce-first")
    assert (k_f2, k_r2) == pytest.approx(roots[0], rel=1e-12)  # tol: the same root formula on the same numbers
    w2, phi2 = ab.modes(ab.pad_matrix(k_f2, k_r2, L_F, L_R), np.diag([m, I]))
    assert abs(ab.node_position(phi2[:, 0])) >= L / 2
    with pytest.raises(ValueError, match="stiff-rear"):
        ab.choose_stiffness(F1, F2, m, I, L_F, L_R, L, root="stiffest")


def test_scene_slider_uses_the_chosen_root_and_frequencies():
    s, info = assembly.slider_from_scene(scene_from_dict({}))
    m, I = ab.mass_properties(L, W, T, RHO)
    k_f, k_r, _ = ab.choose_stiffness(F1, F2, m, I, L_F, L_R, L)
    assert (s.k_f, s.k_r) == pytest.approx((k_f, k_r), rel=1e-12)  # tol: the same root formula on the same numbers
    w, _ = ab.modes(s.stiffness_matrix, s.mass_matrix)
    # tol: 2x2 eigenproblem (LAPACK, condition ~ f2/f1), under 1e-13 on any host
    np.testing.assert_allclose(w / (2 * np.pi), [F1, F2], rtol=1e-9)
    # TFC point 8 um before the trailing edge, CG at mid-length; friction arm T/2
    # tol: a subtraction of two exact-ish lengths, a few roundings
    assert s.l_c == pytest.approx(L / 2 - 8e-6, rel=1e-12)
    assert s.friction_arm == pytest.approx(T / 2, rel=1e-12)  # tol: one division, a few roundings
    # rear preload F_r0 = k_r g0 / n, with g0 = FH0 = 11 nm and n = 2 (docs/model.md, section "Slider dynamics")
    assert s.rear_preload == pytest.approx(s.k_r * 11 * NM / 2, rel=1e-12)  # tol: one product, a few roundings


@pytest.mark.parametrize("zeta", [0.01, 0.05, 0.2])
def test_pad_dampers_give_the_modal_damping_ratio(zeta):
    # Pad dampers are not proportional damping, so the exact damping ratios of the linearised
    # slider (eigenvalues of the first-order system) deviate slightly from the target: measured
    # 0.05000111 for zeta = 0.05; required within 1e-3 of zeta (the brief's tolerance).
    s, _ = assembly.slider_from_scene(scene_from_dict({}))
    c_f, c_r = ab.pad_damping(s.k_f, s.k_r, s.m, s.I, s.l_f, s.l_r, zeta)
    assert c_f > 0 and c_r > 0
    s = dataclasses.replace(s, c_f=c_f, c_r=c_r)
    fn, ratios = ab.damping_ratios(s)
    np.testing.assert_allclose(ratios, [zeta, zeta], atol=1e-3)
    np.testing.assert_allclose(fn, [F1, F2], rtol=1e-3)
    # the modal projections phi_i^T C phi_i equal 2 zeta w_i exactly (the defining equations)
    w, phi = ab.modes(s.stiffness_matrix, s.mass_matrix)
    # tol: 2x2 matrix products of mass-normalised modes, tens of roundings of w
    np.testing.assert_allclose(np.diag(phi.T @ s.damping_matrix @ phi), 2 * zeta * w, rtol=1e-10)


def test_scene_damping_ratio_reaches_the_slider():
    s, info = assembly.slider_from_scene(scene_from_dict({"air_bearing": {"damping_ratio": 0.05}}))
    assert info["damping_ratio"] == 0.05
    np.testing.assert_allclose(ab.damping_ratios(s)[1], [0.05, 0.05], atol=1e-3)
    s0, _ = assembly.slider_from_scene(scene_from_dict({"air_bearing": {"damping_ratio": 0.0}}))
    assert s0.c_f == 0.0 and s0.c_r == 0.0


@pytest.mark.parametrize("n", [1.0, 2.0, 3.5])
def test_rear_force_is_zero_with_stiffness_k_r_at_g0(n):
    # docs/model.md, section "Slider dynamics": F_r = F_r0 [(g0/g)^n - 1], F_r0 = k_r g0 / n, so F_r(g0) = 0 and -dF_r/dg(g0) = k_r.
    k_r, g0 = 1.06e5, 11 * NM
    F0 = k_r * g0 / n
    assert ab.rear_force(g0, g0, n, F0) == 0.0
    h = 1e-4 * g0  # central difference: truncation error ~ (h/g0)^2 ~ 1e-8 relative
    k_fd = -(ab.rear_force(g0 + h, g0, n, F0) - ab.rear_force(g0 - h, g0, n, F0)) / (2 * h)
    assert k_fd == pytest.approx(k_r, rel=1e-6)
    # pushes the slider up when the gap closes, down when it opens
    assert ab.rear_force(0.5 * g0, g0, n, F0) > 0 > ab.rear_force(2 * g0, g0, n, F0)


@pytest.mark.parametrize("f1, f2", [(120e3, 130e3), (100e3, 101e3), (120e3, 150e3)])
def test_impossible_frequencies_raise(mass, f1, f2):
    # Too close together for this geometry: the quadratic for k_r has a negative discriminant.
    m, I = mass
    with pytest.raises(ValueError, match="no real air-bearing stiffness"):
        ab.stiffness_roots(f1, f2, m, I, L_F, L_R)
    with pytest.raises(ValueError):
        ab.choose_stiffness(f1, f2, m, I, L_F, L_R, L)


def test_no_pitch_first_root_raises(mass):
    # 120/200 kHz has two real roots, but in both the first mode's node is off the slider.
    m, I = mass
    assert len(ab.stiffness_roots(120e3, 200e3, m, I, L_F, L_R)) == 2
    with pytest.raises(ValueError, match="pitch-first"):
        ab.choose_stiffness(120e3, 200e3, m, I, L_F, L_R, L, root="pitch-first")


def test_scene_with_impossible_frequencies_fails_to_build():
    sc = scene_from_dict({"scene": {"effects": ["air_bearing", "pitch"]},
                          "air_bearing": {"frequencies_khz": [120.0, 130.0]}})
    with pytest.raises(ValueError):
        assembly.build_model(sc, None, None, None)
