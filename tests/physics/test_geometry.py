"""TFC bulge geometry (docs/model.md, section "Nominal area"): nominal area, effective radius, pitched lowest point."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from pipeline.physics import geometry as g

NM, UM = 1e-9, 1e-6
A, B = 3 * UM, 25 * UM          # [paper] semi-axes a (sliding), b (across)


def test_paper_nominal_area():
    # docs/model.md, section "Nominal area" [paper]: A_n = 62 um^2 at delta = 11 nm; s_n = 1.56 nm (3 sigma, sigma = 0.52 nm).
    # Hand computation: u = 1.56/11 = 0.1418182, 2u - u^2 = 0.2635240, pi * 3 * 25 * 0.2635240 = 62.0914 um^2
    An = g.nominal_area(11 * NM, A, B, 1.56 * NM) / UM**2
    assert An == pytest.approx(62.0914, rel=1e-5)
    assert An == pytest.approx(62.0, rel=0.005)


def test_paper_scene_section_depth(paper_scene):
    # s_n = section_depth_sigma * sigma = 3 * 0.52 nm = 1.56 nm (docs/model.md, section "Parameters")
    s_n = paper_scene["contact"]["section_depth_sigma"] * paper_scene["roughness"]["sigma_nm"] * NM
    t = paper_scene["tfc"]
    An = g.nominal_area(t["protrusion_nm"] * NM, t["half_length_um"] * UM, t["half_width_um"] * UM, s_n)
    assert An / UM**2 == pytest.approx(62.0, rel=0.005)


def test_nominal_area_is_the_ellipsoid_section():
    # Direct: the ellipsoid (x/a)^2 + (y/b)^2 + ((h - delta)/delta)^2 = 1 cut at height s_n is an
    # ellipse with semi-axes a r, b r, r^2 = 1 - (1 - s_n/delta)^2
    delta, s_n = 7 * NM, 2 * NM
    r2 = 1 - (1 - s_n / delta) ** 2
    assert g.nominal_area(delta, A, B, s_n) == pytest.approx(np.pi * A * B * r2, rel=1e-14)


def test_nominal_area_paraboloid_limit_first_order():
    # u = s_n/delta -> 0 (shallow section of the 11 nm bulge): A_n -> 2 pi a b s_n / delta
    # (paraboloid); the relative error is exactly -u/2, i.e. O(u)
    delta = 11 * NM
    errs = []
    for u in (1e-1, 1e-2, 1e-3, 1e-4):
        s_n = u * delta
        rel = g.nominal_area(delta, A, B, s_n) / (2 * np.pi * A * B * s_n / delta) - 1
        assert rel == pytest.approx(-u / 2, rel=1e-6)
        errs.append(abs(rel))
    assert errs[1] / errs[2] == pytest.approx(10.0, rel=1e-5)   # first order: tenfold per decade


def test_effective_radius_paraboloid_limit_first_order():
    # u -> 0: R_eff -> a^2 / delta (apex curvature of the ellipse). From R = (c^2 + h^2)/(2h),
    # c^2 = a^2 (2u - u^2), h = s_n = u delta: R / (a^2/delta) - 1 = u (delta^2/a^2 - 1) / 2 -> O(u)
    # (delta^2/a^2 ~ 1e-5 for the paper's bulge, so the error is -u/2 to 5 digits)
    delta = 11 * NM
    errs = []
    for u in (1e-1, 1e-2, 1e-3, 1e-4):
        s_n = u * delta
        rel = g.effective_radius(delta, A, s_n) / (A * A / delta) - 1
        assert rel == pytest.approx(u * (delta**2 / A**2 - 1) / 2, rel=1e-6)
        errs.append(abs(rel))
    assert errs[1] / errs[2] == pytest.approx(10.0, rel=1e-5)


def test_effective_radius_is_the_arc_through_apex_and_chord_ends():
    delta, s_n = 11 * NM, 1.56 * NM
    R = float(g.effective_radius(delta, A, s_n))
    c = A * np.sqrt(1 - (1 - s_n / delta) ** 2)      # half-chord of the section along sliding
    # circle centred (0, R) through the apex (0, 0) must pass through (c, s_n)
    assert np.hypot(c, s_n - R) == pytest.approx(R, rel=1e-12)
    # hand value: c^2 = 9 um^2 * 0.2635240 = 2.371716e-12 m^2 -> R = c^2/(2 s_n) + s_n/2 = 760.166 um
    assert R / UM == pytest.approx(760.166, rel=1e-6)


def test_u_is_capped_at_one():
    s_n = 1.56 * NM
    assert g.section_fraction(1.0 * NM, s_n) == 1.0
    assert g.section_fraction(0.0, s_n) == 1.0
    assert g.section_fraction(3.12 * NM, s_n) == pytest.approx(0.5)
    # a bulge lower than the section depth: the whole footprint pi a b
    for delta in (0.0, 0.5 * NM, s_n):
        assert g.nominal_area(delta, A, B, s_n) == pytest.approx(np.pi * A * B, rel=1e-15)
    # arc through apex and the footprint ends (+-a, delta); flat slider: infinite radius
    assert g.effective_radius(0.5 * NM, A, s_n) == pytest.approx((A * A + (0.5 * NM) ** 2) / NM, rel=1e-14)
    assert np.isinf(g.effective_radius(0.0, A, s_n))


def test_vectorised_and_monotone_in_protrusion():
    s_n = 1.56 * NM
    delta = np.linspace(0, 15, 76) * NM
    An = g.nominal_area(delta, A, B, s_n)
    R = g.effective_radius(delta, A, s_n)
    assert An.shape == R.shape == delta.shape
    assert np.all(np.diff(An) <= 0)             # the section shrinks as the bulge grows
    assert np.all(np.diff(R[1:]) < 0)           # ... and sharpens
    assert np.all(np.isfinite(An))


def _exact_lowest_point(delta, a, theta):
    """min over x of h(x) - theta x, h(x) = delta (1 - sqrt(1 - (x/a)^2)) (the bulge, apex at 0)."""
    f = lambda x: delta * (1 - np.sqrt(1 - (x / a) ** 2)) - theta * x  # noqa: E731
    r = minimize_scalar(f, bounds=(-a * 0.999999, a * 0.999999), method="bounded",
                        options={"xatol": 1e-6 * a * abs(theta) * a / delta + 1e-18})
    return r.x, f(r.x)


@pytest.mark.parametrize("theta", [1e-5, 1e-4, 1e-3, -2e-4])
def test_lowest_point_offset_exact(theta):
    delta = 11 * NM
    x, dz = g.lowest_point_offset(delta, A, theta)
    xe, dze = _exact_lowest_point(delta, A, theta)
    assert x == pytest.approx(xe, rel=1e-4)
    assert dz == pytest.approx(dze, rel=1e-8)
    assert dz <= 0


def test_lowest_point_offset_small_angle_limit():
    # docs/model.md, section "Nominal area": negligible at sub-milliradian pitch; small-angle limit dz = -a^2 theta^2 / (2 delta),
    # x = a^2 theta / delta, with relative corrections O(phi^2), phi = a theta / delta
    delta = 11 * NM
    for theta in (1e-6, 1e-5, 1e-4):
        x, dz = g.lowest_point_offset(delta, A, theta)
        phi = A * theta / delta
        assert dz == pytest.approx(-A * A * theta**2 / (2 * delta), rel=2 * phi**2 + 1e-12)
        assert x == pytest.approx(A * A * theta / delta, rel=2 * phi**2 + 1e-12)
    # paper bulge at 0.1 mrad: hand value 9e-12 * 1e-8 / 22e-9 = 4.09 pm
    assert g.lowest_point_offset(delta, A, 1e-4)[1] == pytest.approx(-4.0909e-12, rel=1e-3)


def test_lowest_point_offset_degenerate():
    assert g.lowest_point_offset(11 * NM, A, 0.0) == (0.0, 0.0)
    assert g.lowest_point_offset(0.0, A, 1e-4) == (0.0, 0.0)
