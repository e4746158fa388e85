"""Tests of pipeline.physics.surface against surfaces whose statistics are known exactly.

The maps are SurfaceTopography topographies, taken to numbers by :mod:`pipeline.model.afm_scan`
(``profile_moments``, ``summarise``); reading AFM files is tested in tests/model/test_afm_scan.py.

Analytic cases: sinusoids (moments in closed form, also for the finite-difference stencils), a
paraboloid (one summit of known curvature), an egg-crate of two sinusoids (summit density and curvature
known; the summit route converges with grid refinement). Random case: SurfaceTopography's
``fourier_synthesis`` with a smooth PSD and unit amplitudes (random phases only), so the moments are
deterministic up to lattice and finite-difference errors, well inside 2 %.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from SurfaceTopography import Topography
from SurfaceTopography.Generation import fourier_synthesis

from pipeline.physics import asperity_statistics as st
from pipeline.model import afm_scan
from pipeline.physics import surface as sf

def _grid(n: int, length: float, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    x = (np.arange(n) + offset) * (length / n)
    return np.meshgrid(x, x, indexing="ij")  # axis 0 is x, as in SurfaceTopography


def _sine(n: int = 256, periods: int = 4, A: float = 3.0, along: str = "x") -> tuple[Topography, float, float]:
    L = float(n)  # pixel size 1 nm
    X, Y = _grid(n, L)
    k = 2 * np.pi * periods / L
    z = A * np.sin(k * (X if along == "x" else Y))
    return Topography(z, (L, L), periodic=True, unit="nm"), k, 1.0


def _smooth_psd_surface(n: int = 256, q0: float = 0.1, seed: int = 7) -> tuple[Topography, np.ndarray]:
    """Random-phase surface with PSD C(q) = C0 (q/q0)^2 exp(-(q/q0)^2), sigma = 1 nm; exact moments.

    Profile moments of an isotropic PSD: m0 = (1/2pi) int q C dq, m2 = (1/4pi) int q^3 C dq,
    m4 = (3/16pi) int q^5 C dq, i.e. C0 q0^2/(4 pi), C0 q0^4/(4 pi), 9 C0 q0^6/(16 pi) (alpha = 9/4).
    """
    C0 = 4 * np.pi / q0**2
    t = fourier_synthesis((n, n), (float(n), float(n)), psd=lambda q: C0 * (q / q0) ** 2 * np.exp(-(q / q0) ** 2),
                          amplitude_distribution=lambda m: np.ones(m), rng=seed, unit="nm").squeeze()
    exact = np.array([C0 * q0**2 / (4 * np.pi), C0 * q0**4 / (4 * np.pi), 9 * C0 * q0**6 / (16 * np.pi)])
    return t, exact


# ---------------------------------------------------------------------------------------------------
# Spectral route
# ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("along", ["x", "y"])
def test_sinusoid_moments_exact(along: str) -> None:
    """z = A sin(kx): m0 = A^2/2; along x m2 = A^2 k^2/2, m4 = A^2 k^4/2, along y zero; we average both."""
    A = 3.0
    t, k, dx = _sine(A=A, along=along)
    m0, m2, m4 = afm_scan.profile_moments(t)
    s = math.sin(k * dx / 2) / (k * dx / 2)  # transfer function of the difference stencils
    # tol: a mean of squares of a sampled sine (pairwise sum): ~log2(n) roundings
    assert m0 == pytest.approx(A**2 / 2, rel=1e-12)
    # tol: difference stencils of a sine, exact up to the sum's rounding and sin's ulp
    assert m2 == pytest.approx(A**2 * k**2 / 4 * s**2, rel=1e-10)
    # tol: difference stencils of a sine, exact up to the sum's rounding and sin's ulp
    assert m4 == pytest.approx(A**2 * k**4 / 4 * s**4, rel=1e-10)
    # and the continuum values within the stencils' (k dx)^2 error
    assert m2 == pytest.approx(A**2 * k**2 / 4, rel=5e-3)
    assert m4 == pytest.approx(A**2 * k**4 / 4, rel=5e-3)


def test_moments_match_surfacetopography_profile_values() -> None:
    """The x terms of our m2, m4 are SurfaceTopography's Rdq^2, Rddq^2; the y terms those of the transpose."""
    t, _ = _smooth_psd_surface(n=128, q0=0.15)
    _, m2, m4 = afm_scan.profile_moments(t)
    # tol: the same differences summed in another order: ~log2(n) roundings
    assert m2 == pytest.approx((t.Rdq() ** 2 + t.transpose().Rdq() ** 2) / 2, rel=1e-12)
    # tol: the same differences summed in another order: ~log2(n) roundings
    assert m4 == pytest.approx((t.Rddq() ** 2 + t.transpose().Rddq() ** 2) / 2, rel=1e-12)


def test_fourier_synthesis_moments_within_two_percent() -> None:
    t, exact = _smooth_psd_surface(n=256, q0=0.1)
    m = np.array(afm_scan.profile_moments(t))
    np.testing.assert_allclose(m, exact, rtol=0.02)
    s = sf.spectral_statistics(*m)
    assert s.sigma == pytest.approx(1.0, rel=0.02)
    assert s.alpha == pytest.approx(9 / 4, rel=0.02)
    ref = st.statistics_from_moments(*exact)
    assert s.eta == pytest.approx(ref["eta"], rel=0.02)
    assert s.R == pytest.approx(ref["R"], rel=0.02)
    # McCool's relations, as in statistics.py
    # tol: the same McCool formula on the same numbers
    assert s.sigma_s == pytest.approx(st.summit_sigma(s.sigma, s.eta, s.R), rel=1e-12)
    # (statistics.py uses alpha = 2412.74 (sigma eta R)^2, equal to m0 m4/m2^2 to 6 digits)
    assert s.y_s == pytest.approx(4 * s.sigma / math.sqrt(math.pi * s.alpha), rel=1e-5)


def test_alpha_below_mccool_limit_gives_nan_with_reason() -> None:
    with pytest.warns(sf.SurfaceWarning, match=r"alpha = m0 m4 / m2\^2 = 0\.8 <= 0\.8968.*negative"):
        s = sf.spectral_statistics(1.0, 1.0, 0.8)
    assert math.isnan(s.sigma_s)
    assert s.alpha == pytest.approx(0.8)
    assert np.isfinite([s.eta, s.R, s.y_s]).all()


# ---------------------------------------------------------------------------------------------------
# Summit route
# ---------------------------------------------------------------------------------------------------

def test_paraboloid_single_summit_exact() -> None:
    """z = -(x^2 + y^2)/(2 R0): one summit, curvature 1/R0 exactly (the Laplacian stencil is exact)."""
    n, dx, R0 = 41, 2.0, 500.0
    x = (np.arange(n) - n // 2) * dx
    X, Y = np.meshgrid(x, x, indexing="ij")
    z = -(X**2 + Y**2) / (2 * R0)
    s = sf.summit_statistics(z, (dx, dx))
    assert s.count == 1
    # tol: a paraboloid's curvature from second differences, exact up to a few roundings
    assert s.R == pytest.approx(R0, rel=1e-12)
    assert s.eta == pytest.approx(1 / ((n - 2) * dx) ** 2, rel=1e-12)  # tol: a count and a product, a few roundings
    assert s.sigma_s == 0.0
    assert s.y_s == pytest.approx(-z.mean(), rel=1e-12)  # tol: a mean of the same heights, ~log2(n) roundings
    # spectral: curvature is constant, so m4 = 1/R0^2 exactly, R = 0.375 sqrt(pi) R0
    _, _, m4 = afm_scan.profile_moments(Topography(z, (n * dx, n * dx), unit="nm"))
    # tol: a paraboloid's constant second differences, ~log2(n) roundings of the mean
    assert m4 == pytest.approx(1 / R0**2, rel=1e-12)


def _egg_crate(periods_px: int, A: float = 2.0, L: float = 400.0, cells: int = 8) -> tuple[np.ndarray, float]:
    """A (cos kx + cos ky), summits off the grid by 0.3 pixel: eta = 1/L^2, R = 1/(A k^2), y_s = 2A."""
    n = cells * periods_px
    dx = L / periods_px
    X, Y = _grid(n, cells * L, offset=0.3)
    k = 2 * np.pi / L
    return A * (np.cos(k * (X - L / 2)) + np.cos(k * (Y - L / 2))), dx


def test_summit_route_converges_with_grid_refinement() -> None:
    A, L = 2.0, 400.0
    eta, R = 1 / L**2, 1 / (A * (2 * np.pi / L) ** 2)
    errors = []
    for ppp in (8, 16, 32, 64):
        z, dx = _egg_crate(ppp, A=A, L=L)
        s = sf.summit_statistics(z, (dx, dx))
        assert s.count == 64
        errors.append((abs(s.eta / eta - 1), abs(s.R / R - 1), abs(s.y_s / (2 * A) - 1)))
    errors = np.array(errors)
    assert np.all(np.diff(errors, axis=0) < 0), errors  # each refinement reduces every error
    assert np.all(errors[-1] < 0.02), errors
    assert errors[-1, 1] < errors[0, 1] / 30  # curvature error is O(dx^2)


def test_summits_are_strict_maxima_and_skip_border() -> None:
    z = np.zeros((5, 6))
    z[2, 2] = 1.0        # summit
    z[0, 3] = 5.0        # border: never a summit
    z[3, 4] = z[2, 4] = 0.5  # plateau of two equal pixels: not strict
    mask = sf.summit_mask(z)
    assert mask.shape == (3, 4)
    assert np.argwhere(mask).tolist() == [[1, 1]]


def test_routes_agree_on_a_gaussian_surface() -> None:
    """Finely sampled random-phase Gaussian surface: summit count and McCool agree (Nayak's theory)."""
    t, _ = _smooth_psd_surface(n=512, q0=0.15, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", sf.SurfaceWarning)  # no disagreement warning here
        s = afm_scan.summarise(t, label="gauss")
    assert s.summits.eta == pytest.approx(s.spectral.eta, rel=0.15)
    assert s.summits.R == pytest.approx(s.spectral.R, rel=0.10)
    assert s.summits.sigma_s == pytest.approx(s.spectral.sigma_s, rel=0.15)
    assert s.summits.y_s == pytest.approx(s.spectral.y_s, rel=0.10)
    assert s.pixel_size == 1.0


def test_disagreeing_routes_warn_with_the_reason() -> None:
    """Ridges A sin(kx) gently modulated along y (B cos(qy), q << k) are far from an isotropic Gaussian:
    the spectral route sees the ridge curvature in every direction and predicts eta = m4/(6 pi sqrt 3 m2)
    ~ k^2/(6 pi sqrt 3), ~19 times the true one summit per ridge period and y period."""
    n = 256
    X, Y = _grid(n, float(n))
    k, q = 2 * np.pi / 16, 2 * np.pi / 256
    z = 3.0 * np.sin(k * X) + 0.5 * np.cos(q * (Y - 128.3))
    t = Topography(z, (float(n), float(n)), periodic=True, unit="nm")
    with pytest.warns(sf.SurfaceWarning, match="sampling interval.*noise.*cut-off"):
        s = afm_scan.summarise(t, label="ridges")
    assert any("ridges: summit density eta differs" in w for w in s.warnings)
    assert s.summits.count == 16  # one per ridge (the y maximum at y = 128.3 lies inside)
    assert s.spectral.eta / s.summits.eta > 10


# ---------------------------------------------------------------------------------------------------
# Combination
# ---------------------------------------------------------------------------------------------------

def test_moments_of_a_sum_of_orthogonal_surfaces_add() -> None:
    """A sin(k1 x) + B sin(k2 y): all cross terms vanish on the grid, so moments (and sigma^2) add exactly."""
    t1, _, _ = _sine(A=3.0, periods=4, along="x")
    t2, _, _ = _sine(A=1.5, periods=9, along="y")
    both = Topography(t1.heights() + t2.heights(), t1.physical_sizes, periodic=True, unit="nm")
    with pytest.warns(sf.SurfaceWarning, match="no summit"):  # straight ridges have no strict maxima
        s1, s2, s12 = (afm_scan.summarise(t, label=lab) for t, lab in ((t1, "a"), (t2, "b"), (both, "ab")))
    c = sf.combine([s1, s2])
    # tol: moments of summed maps: sums of n^2 terms in another order, ~log2(n) roundings
    np.testing.assert_allclose([c.m0, c.m2, c.m4], [s12.m0, s12.m2, s12.m4], rtol=1e-10)
    # tol: a sum of two squares of square roots, a few roundings
    assert c.spectral.sigma**2 == pytest.approx(s1.spectral.sigma**2 + s2.spectral.sigma**2, rel=1e-12)
    # tol: the same moments, a few roundings apart
    assert c.spectral.sigma == pytest.approx(s12.spectral.sigma, rel=1e-12)
    assert c.label == "combined" and math.isnan(c.summits.eta) and math.isnan(c.pixel_size)
    assert c.summits.sigma == pytest.approx(math.hypot(s1.summits.sigma, s2.summits.sigma))


def test_combined_random_surfaces_sigma_squared_adds() -> None:
    t1, _ = _smooth_psd_surface(n=128, q0=0.15, seed=1)
    t2, _ = _smooth_psd_surface(n=128, q0=0.3, seed=2)
    s1, s2 = afm_scan.summarise(t1), afm_scan.summarise(t2)
    c = sf.combine([s1, s2])
    ref = st.statistics_from_moments(*sf.combine_moments([(s1.m0, s1.m2, s1.m4), (s2.m0, s2.m2, s2.m4)]))
    # tol: a square root of a sum, a few roundings
    assert c.spectral.sigma == pytest.approx(math.sqrt(s1.m0 + s2.m0), rel=1e-12)
    assert c.spectral.eta == pytest.approx(ref["eta"], rel=1e-12)  # tol: the same formula on the same moments
    assert c.spectral.R == pytest.approx(ref["R"], rel=1e-12)  # tol: the same formula on the same moments
    # the summed height map has (nearly) the summed moments: independent phases, small cross terms
    both = Topography(t1.heights() + t2.heights(), t1.physical_sizes, periodic=True, unit="nm")
    np.testing.assert_allclose(afm_scan.profile_moments(both), [c.m0, c.m2, c.m4], rtol=0.05)


def test_combine_single_surface_is_a_copy() -> None:
    t, _ = _smooth_psd_surface(n=64, q0=0.3)
    s = afm_scan.summarise(t, label="one")
    c = sf.combine([s])
    assert c.label == "combined" and c.spectral == s.spectral and c.summits == s.summits


# --------------------------------------------------------------------------------------------------
# Bounds of a sampled map
# --------------------------------------------------------------------------------------------------

def test_the_bounds_of_a_map_hold_at_their_values_and_refuse_beyond() -> None:
    lo, hi = sf.PIXEL_SIZE_BOUNDS_NM
    assert sf.sampling_error((64 * lo, 64 * hi), (64, 64)) is None
    assert sf.sampling_error((256.0, 256.0), (64, 64)) is None
    assert sf.sampling_error((0.9 * 64 * lo, 256.0), (64, 64)).startswith("pixel size 0.0009 nm")
    assert sf.sampling_error((1e-27, 1e-27), (64, 64)).endswith(f"expected {lo:g} to {hi:g} nm")
    assert sf.sampling_error((2 * sf.MAX_SIZE_NM, 256.0), (1 << 20, 64)).startswith("lateral size 2e+08 x 256 nm: "
                                                                                       "expected at most 1e+08 nm")
    for sizes in ((-256.0, 256.0), (0.0, 256.0), (math.nan, 256.0), (math.inf, 256.0)):
        assert "expected positive finite sizes" in sf.sampling_error(sizes, (64, 64))
    h = np.zeros((4, 4))
    h[0, 0] = sf.MAX_HEIGHT_NM
    assert sf.heights_error(h) is None and sf.heights_error(-h) is None
    h[0, 0] = 3e38
    assert sf.heights_error(h) == "heights reach 3e+38 nm: expected heights within +-100000 nm (100 um, any AFM's z range)"
    h[1, 1] = math.nan  # (undefined pixels do not count; only defined ones are bounded)
    assert sf.heights_error(h).startswith("heights reach 3e+38 nm")
    assert sf.heights_error(np.full((4, 4), math.nan)) == "every height is undefined: expected a measured height map"
    assert sf.roughness_error(sf.MIN_RMS_NM) is None and sf.roughness_error(0.5) is None
    assert sf.roughness_error(0.0).startswith("rms height 0 nm after detrending: expected at least 0.001 nm")
    assert sf.roughness_error(math.nan).startswith("rms height nan nm after detrending: expected at least 0.001 nm")
