"""Asperity statistics (McCool / Nayak, docs/model.md, section "Asperity statistics") and the plasticity index."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics import asperity_statistics as st
from pipeline.physics.asperity import critical_interference
from pipeline.model.interface_tables import interface_parameters, roughness_statistics

NM = 1e-9


def test_alpha_constant_follows_from_the_moment_relations():
    # alpha = m0 m4 / m2^2 with eta = m4/(6 pi sqrt3 m2), R = 0.375 sqrt(pi/m4)
    # => alpha = (sigma eta R)^2 * 108 pi / 0.375^2 = 2412.743 (sigma eta R)^2 (docs/model.md, section "Asperity statistics")
    assert 108 * np.pi / 0.375**2 == pytest.approx(2412.74, rel=2e-6)
    assert st.bandwidth_alpha(1.0, 1.0, 1.0) == 2412.74


def test_moments_round_trip():
    sigma, eta, R = 0.52e-9, 1e13, 5e-6
    m0, m2, m4 = st.moments_from_statistics(sigma, eta, R)
    out = st.statistics_from_moments(m0, m2, m4)
    # tol: a round trip through the moments, a few roundings and a sqrt
    assert out["sigma"] == pytest.approx(sigma, rel=1e-14)
    # tol: a round trip through the moments, a few roundings and a sqrt
    assert out["eta"] == pytest.approx(eta, rel=1e-14)
    assert out["R"] == pytest.approx(R, rel=1e-14)  # tol: a round trip through the moments, a few roundings and a sqrt
    # alpha from the moments equals the closed form 2412.74 (sigma eta R)^2 (to its 6 digits)
    assert out["alpha"] == pytest.approx(st.bandwidth_alpha(sigma, eta, R), rel=2e-6)


def test_cml_summit_statistics():
    # docs/model.md, section "ISBL interface" surface: sigma = 0.5 nm, eta = 5e15 m^-2, R = 20 nm. Hand computation:
    # sigma eta R = 0.05, alpha = 2412.74 * 0.0025 = 6.03185;
    # sigma_s^2 = 0.25 nm^2 - 3.717e-4 / (1e8 m^-1)^2 = 0.25 - 0.03717 = 0.21283 nm^2 -> 0.461335 nm;
    # y_s = 4 * 0.5 / sqrt(pi * 6.03185) = 0.459441 nm.
    sigma, eta, R = 0.5e-9, 5e15, 20e-9
    # tol: 2412.74 (sigma eta R)^2 of exact decimals, a few roundings
    assert st.bandwidth_alpha(sigma, eta, R) == pytest.approx(6.03185, rel=1e-12)
    assert st.summit_sigma(sigma, eta, R) / NM == pytest.approx(0.461335, rel=1e-6)
    assert st.summit_offset(sigma, eta, R) / NM == pytest.approx(0.459441, rel=1e-6)


def test_paper_summit_statistics():
    # docs/model.md, section "Parameters": sigma = 0.52 nm, R = 5 um, eta = 10 um^-2. Hand computation:
    # sigma eta R = 0.026, alpha = 2412.74 * 0.026^2 = 1.631012;
    # sigma_s^2 = 0.2704 - 3.717e-4/(5e7)^2 [m^2] = 0.2704 - 0.14868 nm^2 = 0.12172 nm^2 -> 0.348884 nm;
    # y_s = 4 * 0.52 / sqrt(pi * 1.631012) = 0.918882 nm.
    sigma, eta, R = 0.52e-9, 1e13, 5e-6
    assert st.bandwidth_alpha(sigma, eta, R) == pytest.approx(1.631012, rel=1e-6)
    assert st.summit_sigma(sigma, eta, R) / NM == pytest.approx(0.348884, rel=1e-6)
    assert st.summit_offset(sigma, eta, R) / NM == pytest.approx(0.918882, rel=1e-6)


@pytest.mark.parametrize("alpha", [1.0, 1.631, 6.0, 50.0])
def test_summit_sigma_equals_mccool_alpha_form(alpha):
    # McCool 1986: sigma_s^2 = (1 - 0.8968/alpha) sigma^2; the 3.717e-4 of docs/model.md, section "Asperity statistics" is 0.8968/2412.74
    # rounded to 4 digits (3.71693e-4), so the two forms agree to ~1e-4 of the subtracted term.
    sigma, R = 0.5e-9, 1e-6
    eta = np.sqrt(alpha / 2412.74) / (sigma * R)
    expected = sigma * np.sqrt(1 - 0.8968 / alpha)
    assert st.summit_sigma(sigma, eta, R) == pytest.approx(expected, rel=1e-4 * 0.8968 / (alpha - 0.8968))


def test_summit_sigma_rejects_small_bandwidth():
    sigma, R = 0.5e-9, 1e-6
    eta = np.sqrt(0.85 / 2412.74) / (sigma * R)   # alpha = 0.85 < 0.8968
    with pytest.raises(ValueError, match="alpha"):
        st.summit_sigma(sigma, eta, R)


def test_composite_modulus():
    # 1/E' = 0.91/150 + 0.91/200 GPa^-1 -> E' = 94.1915 GPa (docs/model.md, section "Parameters": "E' = 94 GPa")
    assert st.composite_modulus(150e9, 200e9, 0.3) / 1e9 == pytest.approx(94.1915, rel=1e-6)
    # equal bodies: E' = E / (2 (1 - nu^2))
    # tol: IEEE arithmetic alone (no libm), a few roundings: identical on any host
    assert st.composite_modulus(100.0, 100.0, 0.25) == pytest.approx(100 / (2 * (1 - 0.0625)), rel=1e-15)
    # a rigid second body: E' = E / (1 - nu^2)
    # tol: IEEE arithmetic alone (no libm), a few roundings: identical on any host
    assert st.composite_modulus(100.0, np.inf, 0.3, 0.0) == pytest.approx(100 / 0.91, rel=1e-15)


def test_ke_hardness_factor():
    # K = 0.454 + 0.41 nu (docs/model.md, section "Asperity statistics")
    # tol: 0.454 + 0.41 nu of exact decimals, two roundings
    assert st.ke_hardness_factor(0.3) == pytest.approx(0.577, rel=1e-15)


def test_plasticity_index_forms_hand_values():
    # E' = 100 GPa, H = 2 GPa, sigma_s = 1 nm, R = 1 um: sqrt(sigma_s/R) = 0.0316228
    # GW: 50 * 0.0316228 = 1.581139; KE: 2*100/(pi*0.577*2) * 0.0316228 = 55.1661 * 0.0316228 = 1.744513
    E, H, s, R = 100e9, 2e9, 1e-9, 1e-6
    assert st.plasticity_index_gw(E, H, s, R) == pytest.approx(1.581139, rel=1e-6)
    assert st.plasticity_index_ke(E, H, s, R, 0.3) == pytest.approx(1.744513, rel=1e-6)
    assert st.hardness_from_plasticity_gw(1.581139, E, s, R) == pytest.approx(H, rel=1e-6)


def test_plasticity_index_paper_scene(paper_scene):
    stats = roughness_statistics(paper_scene)
    p = interface_parameters(paper_scene, stats)
    # docs/model.md, section "Asperity statistics": the paper reports psi = 0.52 [paper]; H is set from it (docs/model.md, section "Parameters")
    # tol: H is set from psi = 0.52: a round trip of a few roundings and a sqrt
    assert st.plasticity_index_gw(p.E, p.H, p.sigma_s, p.R) == pytest.approx(0.52, rel=1e-12)
    # docs/model.md, section "Separation datum" (eta 13.3 um^-2): hand computation 94.1915/0.52 * sqrt(0.431680 nm / 5 um) = 1.68308 GPa
    # (the first reconstruction's eta 10 um^-2 gave docs/model.md, section "Parameters"'s "about 1.5 GPa", 1.51309)
    assert p.H / 1e9 == pytest.approx(1.68308, rel=1e-5)
    # The CEB/KE form for the same surface: 0.52 * 2/(pi K), K = 0.577 -> 0.573730
    psi_ke = st.plasticity_index_ke(p.E, p.H, p.sigma_s, p.R, p.nu)
    assert psi_ke == pytest.approx(0.573730, rel=1e-5)
    # ... and it is sqrt(sigma_s / w_c) (statistics.plasticity_index_ke docstring)
    wc = critical_interference(p.R, p.E, p.H, p.nu)
    # tol: the same formula rearranged, a few roundings and a sqrt
    assert psi_ke == pytest.approx(np.sqrt(p.sigma_s / wc), rel=1e-12)


def test_explicit_hardness_overrides_plasticity_index(paper_config):
    from pipeline.config.scene import load_scene
    scene = load_scene(paper_config, ["materials.hardness_gpa=3.0", "materials.composite_modulus_gpa=120"])
    p = interface_parameters(scene, roughness_statistics(scene))
    assert p.H == 3.0e9 and p.E == 120e9


def test_contact_probabilities_are_two_sided_first():
    # docs/model.md, section "Contact criterion": the paper's "3 sigma = 0.3 %" is 2 Q(3) = 0.27 %; its 32.8 % is k = 0.978
    two, one = st.contact_probabilities(3.0)
    assert two == pytest.approx(0.0026998, rel=1e-4) and one == pytest.approx(0.0013499, rel=1e-4)
    assert st.k_from_probability(0.328) == pytest.approx(0.978, abs=5e-4)
    assert st.contact_probabilities(0.978)[0] == pytest.approx(0.328, abs=2e-4)
    # the inverse round-trips and is symmetric in k
    for k in (0.1, 0.978, 2.5):
        # tol: ndtri(ndtr(k)): condition P/(k phi) < 12 here, times a few ulps of each
        assert st.k_from_probability(st.contact_probabilities(k)[0]) == pytest.approx(k, rel=1e-12)
        assert st.contact_probabilities(-k)[0] == st.contact_probabilities(k)[0]
    with pytest.raises(ValueError, match=r"\(0, 1\)"):
        st.k_from_probability(1.0)


def test_the_physical_bound_of_k_is_a_one_sided_contact_probability_of_one_half():
    """k >= 0: Q(k) <= 0.5 (the one-sided probability at the bound is exactly 1/2); below it, why in words."""
    assert st.K_PHYSICAL_MIN == 0.0 and st.contact_probabilities(st.K_PHYSICAL_MIN)[1] == 0.5
    assert st.unphysical_k(0.0) is None and st.unphysical_k(1.0736) is None and st.unphysical_k(np.nan) is None
    why = st.unphysical_k(-0.9117)  # (a user's record calibrated to the paper's touchdown)
    assert why.startswith("k = -0.9117 is below 0: its one-sided contact probability P(z > k sigma) = 0.819")
    assert st.contact_probabilities(-1e-9)[1] > 0.5
