"""TFC bulge geometry (docs/model.md, section "Nominal area"): nominal area, effective radius, pitched lowest point;
and the interface stresses summed over the bulge's gap field (section "Deviations", item 18)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import dblquad
from scipy.optimize import minimize_scalar

from pipeline.model import piecewise as pw
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
    # tol: closed form two ways, a few IEEE roundings (no libm)
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
    # tol: closed form through hypot, a few roundings (libm hypot: under an ulp)
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
        # tol: the same product pi a b, at most an ulp or two apart
        assert g.nominal_area(delta, A, B, s_n) == pytest.approx(np.pi * A * B, rel=1e-15)
    # arc through apex and the footprint ends (+-a, delta); flat slider: infinite radius
    # tol: closed form, a few roundings
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
    # tol: a minimum's value is second order in the bounded search's 1e-6 relative x-tolerance
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


# ------------------------------------------------------------------------------------------------
# the interface stresses summed over the bulge's gap field (docs/model.md, section "Deviations", item 18):
# ellipsoid_force and ellipsoid_table_integral against the footprint integral and closed forms

MPA = 1e6
H = 0.05 * NM            # table step [m]
L_C = 0.4 * NM           # decay length of the synthetic contact law [m]


def closed_exponential(d: np.ndarray, delta: float, length: float) -> np.ndarray:
    """``int_0^1 exp(-(d + delta u)/length) (1 - u) du`` in closed form: with ``k = delta/length``,
    ``exp(-d/length) (k - 1 + exp(-k)) / k^2`` (written with expm1 so small k keeps its digits)."""
    k = delta / length
    return np.exp(-np.asarray(d) / length) * (k - (-np.expm1(-k))) / k**2


def table(values: np.ndarray, order: int = 3) -> np.ndarray:
    return pw.piecewise_coefficients(values, H, order)


GRID = np.arange(-3.0, 25.0 + 1e-9, 0.05) * NM


def test_one_dimensional_form_is_the_footprint_integral():
    # the change of variables of ellipsoid_force's docstring against the plain double integral over the
    # elliptical footprint of p(d + h(x, y)), h = delta (1 - sqrt(1 - (x/a)^2 - (y/b)^2))
    delta, d = 7.0 * NM, 0.3 * NM

    def law(gap):
        return 50 * MPA * np.exp(-gap / L_C) + 3 * MPA / (1 + (gap / NM) ** 2)

    def integrand(Y, X):  # on the unit disk, X = x/a, Y = y/b
        return law(d + delta * (1 - np.sqrt(max(0.0, 1 - X * X - Y * Y))))

    plain, err = dblquad(integrand, -1, 1, lambda X: -np.sqrt(1 - X * X), lambda X: np.sqrt(1 - X * X),
                         epsabs=0, epsrel=1e-11)
    plain *= A * B
    # tol: dblquad at epsrel 1e-11 against the force's own quadrature, 1e-9 holds both
    assert g.ellipsoid_force(law, d, delta, A, B) == pytest.approx(plain, rel=1e-9)


def test_table_integral_is_exact_for_a_cubic():
    # a cubic law is its own not-a-knot spline: the integral of the table is the closed form
    # sum_k c_k(d) / ((k + 1)(k + 2)), c_k(d) the coefficients of p(d + delta u) in u
    coef = np.array([3.0, 2.0, -0.5, 0.1])  # p(x) = sum coef[j] (x/nm)^j [Pa]
    delta = 7.3 * NM
    I = g.ellipsoid_table_integral(table(np.polynomial.polynomial.polyval(GRID / NM, coef)), H, delta)
    inside = GRID + delta <= GRID[-1]
    for i in np.nonzero(inside)[0][::37]:
        shifted = np.polynomial.Polynomial([GRID[i] / NM, delta / NM])  # x/nm as a polynomial in u
        in_u = np.polynomial.Polynomial(coef)(shifted).coef
        exact = sum(c / ((k + 1) * (k + 2)) for k, c in enumerate(in_u))
        # tol: an exact polynomial integral against the table's, tens of roundings
        assert I[i] == pytest.approx(exact, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("delta_nm", [0.03, 1.0, 11.0, 11.0000001])
def test_exponential_law_converges_to_its_closed_form(delta_nm):
    # p = P exp(-x/L): the integral of its spline table converges to the closed form as the spline does
    # (halving the step divides the error by 5-25 over the separations the dynamics visits); partial
    # pieces (delta not a multiple of the step) included
    delta = delta_nm * NM
    errors = []
    for h in (0.1 * NM, 0.05 * NM, 0.025 * NM):
        x = np.arange(-3.0 * NM, 20.0 * NM + h / 2, h)
        I = g.ellipsoid_table_integral(pw.piecewise_coefficients(np.exp(-x / L_C), h, 3), h, delta)
        inside = x + delta <= x[-1]
        rel = np.abs(I[inside] / closed_exponential(x[inside], delta, L_C) - 1)
        assert np.max(rel) < 5e-5  # (the largest at the ends of the table: the not-a-knot spline)
        errors.append(np.max(rel[(x[inside] >= -2 * NM) & (x[inside] <= 5 * NM)]))  # away from the ends
    assert errors[1] < 5e-7
    assert errors[0] / errors[1] > 4 and errors[1] / errors[2] > 4


def test_flat_bulge_limit():
    # delta -> 0: the whole footprint at the apex gap, F = pi a b p(d) (I = p/2), approached linearly
    p = 50 * MPA * np.exp(-GRID / L_C)
    c = table(p)
    # tol: the delta -> 0 limit is p/2 exactly up to a few roundings
    assert g.ellipsoid_table_integral(c, H, 0.0) == pytest.approx(p / 2, rel=1e-12)
    for delta in (1e-3 * H, 1e-5 * H):
        I = g.ellipsoid_table_integral(c, H, delta)
        # first order: I = p/2 + delta p'/6 + ... with p' = -p/L
        assert np.allclose(I[:-1] / (p[:-1] / 2) - 1, -delta / (3 * L_C), rtol=1e-3, atol=1e-12)
    # tol: the same np.exp of the same argument on both sides, times pi a b
    assert g.ellipsoid_force(lambda x: 50 * MPA * np.exp(-x / L_C), 0.2 * NM, 0.0, A, B) == pytest.approx(
        np.pi * A * B * 50 * MPA * np.exp(-0.2 * NM / L_C), rel=1e-14)


def test_step_law_gives_the_flat_section():
    # p = P0 below d0, 0 above: F = P0 x (section of the ellipsoid at depth d0 - d) = P0 A_n(s_n = d0 - d).
    # Tabulated with linear interpolation the step is a ramp over one piece [d0, d0 + h]: F lies between
    # the sections at depths d0 - d and d0 + h - d
    P0, d0, delta = 100 * MPA, 2.0 * NM, 11.0 * NM
    c = table(np.where(GRID <= d0 + 1e-15, P0, 0.0), order=1)
    F = 2 * np.pi * A * B * g.ellipsoid_table_integral(c, H, delta)
    below = (GRID < d0 - 1e-15) & (GRID > d0 - 15 * NM)
    lo = P0 * g.nominal_area(delta, A, B, d0 - GRID[below])
    hi = P0 * g.nominal_area(delta, A, B, d0 + H - GRID[below])
    assert np.all(lo <= F[below] * (1 + 1e-12)) and np.all(F[below] <= hi * (1 + 1e-12))
    # ... and the ramp's integral is the mean of the two to second order in h
    assert F[below] == pytest.approx((lo + hi) / 2, rel=2e-3)
    # the step itself, integrated by the one-dimensional form in closed form: int_0^u* (1 - u) du
    for d in (1.0 * NM, -5.0 * NM, -10 * NM):
        u = min((d0 - d) / delta, 1.0)
        # tol: closed form two ways, a few roundings
        assert 2 * np.pi * A * B * P0 * (u - u * u / 2) == pytest.approx(
            P0 * g.nominal_area(delta, A, B, d0 - d), rel=1e-14)


def test_nothing_is_taken_beyond_the_table():
    # a constant table: held beyond its top it would give p/2 at every node; the integral stops at the
    # top, and what it leaves out is table_truncation's p (1 - u_top)^2 / 2
    P, delta = 7 * MPA, 4.0 * NM
    I = g.ellipsoid_table_integral(table(np.full(GRID.size, P)), H, delta)
    cut = g.table_truncation(P, GRID, delta)
    # tol: a constant table's integral and its truncation sum to P/2 up to tens of roundings
    assert np.allclose(I + cut, P / 2, rtol=1e-12)
    assert np.all(cut[GRID + delta <= GRID[-1]] == 0) and cut[-1] == P / 2
