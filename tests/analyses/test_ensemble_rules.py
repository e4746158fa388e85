"""The ensemble statistics of the paper targets (pipeline/analyses/ensemble_rules.py) on synthetic data with
known answers: probabilities, medians and quantiles, mean and standard deviation, the 0.5 crossing."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import ensemble_rules as en


def _da(values, prot=None):
    values = np.asarray(values, float)
    if values.ndim == 1:
        return xr.DataArray(values, dims=("realisation",))
    return xr.DataArray(values, dims=("protrusion", "realisation"), coords={"protrusion": prot})


def test_touchdown_probability_counts_evaluated_realisations():
    # min clearance [nm]: negative = contact; NaN = not evaluated (counts in neither)
    c = _da([[0.3, 0.2, 0.1, 0.4], [0.1, -0.1, np.nan, 0.2], [-0.2, -0.1, -0.3, 0.05], [np.nan] * 4],
            [7.0, 7.2, 7.4, 7.6])
    p = en.touchdown_probability(c)
    np.testing.assert_array_equal(p.values[:3], [0.0, 1 / 3, 0.75])
    assert np.isnan(p.values[3])
    assert list(p.dims) == ["protrusion"]


def test_crossing_interpolates_linearly_and_is_nan_off_the_range():
    x = [9.0, 9.2, 9.4, 9.6]
    p = xr.DataArray([0.0, 0.25, 0.75, 1.0], dims="protrusion", coords={"protrusion": x})
    assert en.crossing(p, 0.5) == pytest.approx(9.3, abs=1e-12)
    assert en.crossing(p, 0.25) == pytest.approx(9.2, abs=1e-12)  # reached exactly at a point
    assert en.crossing(p, 0.1) == pytest.approx(9.0 + 0.2 * 0.1 / 0.25, abs=1e-12)
    assert np.isnan(en.crossing(p, 1.1))  # never reached
    assert np.isnan(en.crossing(p + 0.6, 0.5))  # already above at the first point: below the range
    # unsorted coordinates and NaN points: sorted and skipped
    q = xr.DataArray([0.75, np.nan, 0.0], dims="protrusion", coords={"protrusion": [9.4, 9.2, 9.0]})
    assert en.crossing(q, 0.5) == pytest.approx(9.0 + 0.4 * 0.5 / 0.75, abs=1e-12)


def test_touchdown_protrusion_of_eight_seeds_that_touch_one_step_apart():
    # realisation r first touches at 9.0 + 0.2 r // 2: two seeds per step, as a CDF 0.25, 0.5, 0.75, 1
    prot = np.round(np.arange(8.8, 9.81, 0.2), 9)
    first = 9.0 + 0.2 * (np.arange(8) // 2)
    c = _da(np.where(prot[:, None] >= first[None, :] - 1e-9, -0.1, 0.1), prot)
    p = en.touchdown_probability(c).values
    np.testing.assert_allclose(p, [0, 0.25, 0.5, 0.75, 1.0, 1.0])  # tol: fractions of counts of 4, exact in binary
    td, lo, hi = en.touchdown_protrusion(c)
    assert td == pytest.approx(9.2)
    assert lo == pytest.approx(8.8 + 0.2 * 0.1 / 0.25)
    assert hi == pytest.approx(9.4 + 0.2 * (0.9 - 0.75) / 0.25)


def test_median_and_quantiles_of_known_samples():
    v = _da([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0])
    med, lo, hi = en.median_spread(v)
    assert float(med) == 6.0 and float(lo) == 2.0 and float(hi) == 10.0  # order statistics of 11 values
    # NaN realisations are left out; one value is its own median and range
    med, lo, hi = en.median_spread(_da([np.nan, 4.0, np.nan]))
    assert float(med) == float(lo) == float(hi) == 4.0
    assert np.isnan(float(en.median_spread(_da([np.nan, np.nan]))[0]))


def test_mean_and_sample_standard_deviation():
    mean, std = en.mean_std(_da([1.0, 2.0, np.nan, 3.0]))
    assert float(mean) == 2.0 and float(std) == 1.0  # ddof = 1 over the three values
    mean, std = en.mean_std(_da([5.0]))
    assert float(mean) == 5.0 and np.isnan(float(std))


def test_exceedance_probability():
    bv = _da([[25.0, 10.0, 30.0, np.nan], [5.0, 19.9, 20.0, 21.0]], [10.0, 10.2])
    # tol: fractions of counts, one rounding
    np.testing.assert_allclose(en.exceedance_probability(bv, 20.0).values, [2 / 3, 0.25])  # strictly above


def test_flying_mean_leaves_out_contact_and_missing_points():
    prot = [4.0, 5.0, 6.0]
    fhm = _da([[10.0, 12.0], [14.0, np.nan], [16.0, 40.0]], prot)
    c = _da([[1.0, 1.0], [1.0, 1.0], [0.5, -0.1]], prot)  # realisation 1 touches at 6 nm
    # tol: a mean of three exact numbers, a few roundings
    np.testing.assert_allclose(en.flying_mean(fhm, c).values, [(10 + 14 + 16) / 3, 12.0])
