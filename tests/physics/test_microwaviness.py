"""Tests of the DMW physics (pipeline.physics.microwaviness): synthesis, processing and spectra. Reading
measured records is tested in tests/model/test_measured_dmw.py, the dmw stage in tests/stages/test_dmw.py.

Known answers: the synthetic record's rms and band are exact by construction, its periodogram is
the target power law bin by bin (fixed amplitudes), and the spectral derivative / integral pair is
an exact round trip for a periodic band-limited record.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from pipeline.physics import microwaviness as dmw

FS = 4e6            # [Hz] the paper's sampling rate
BAND = (1e4, 5e5)   # [Hz] the paper's band
T = 2e-3            # [s] the paper scene's simulated duration


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


# ---------------------------------------------------------------------------------------- synthesis

def test_rms_is_prescribed_and_mean_is_zero():
    w = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=1)
    assert w.shape == (8000,)
    assert abs(rms(w) - 0.5) / 0.5 < 1e-12          # well inside the 2 % required
    assert abs(w.mean()) < 1e-12


@pytest.mark.parametrize("band, duration", [(BAND, T), ((10.3e3, 333.3e3), 20e-3), ((2e4, 2e6), T)])
def test_band_edges_are_exact(band, duration):
    w = dmw.synthesize(0.5, band, -2.0, duration, FS, seed=7)
    f, p = dmw.spectrum(w, FS)
    df = f[1]
    assert abs(p.sum() * df - 0.25) < 1e-12          # Parseval: periodogram integrates to rms^2
    outside = (f < band[0]) | (f > band[1])
    assert p[outside].sum() / p.sum() < 1e-6
    nz = f[p > 1e-12 * p.max()]
    assert band[0] <= nz.min() < band[0] + df and abs(nz.min() / band[0] - 1) < 0.02
    assert band[1] - df < nz.max() <= band[1] and abs(nz.max() / band[1] - 1) < 0.02


def test_band_narrower_than_resolution_is_rejected():
    with pytest.raises(ValueError, match="make the record longer"):
        dmw.synthesize(0.5, (10.1e3, 10.4e3), -2.0, T, FS, seed=1)   # resolution 500 Hz


def test_band_above_nyquist_is_rejected():
    with pytest.raises(ValueError, match="Nyquist"):
        dmw.synthesize(0.5, (1e4, 3e6), -2.0, T, FS, seed=1)


@pytest.mark.parametrize("exponent", [-3.0, -2.0, -1.0, 0.0])
def test_power_law_exponent_recovered(exponent):
    # fixed amplitudes: the periodogram is the power law bin by bin
    w = dmw.synthesize(0.5, BAND, exponent, T, FS, seed=3, amplitudes="fixed")
    f, p = dmw.spectrum(w, FS)
    assert abs(dmw.power_law_fit(f, p, BAND)[0] - exponent) < 1e-9
    # gaussian amplitudes: periodogram scatter; 10k bins in band give the slope to ~0.02
    w = dmw.synthesize(0.5, BAND, exponent, 20e-3, FS, seed=3)
    f, p = dmw.spectrum(w, FS)
    assert abs(dmw.power_law_fit(f, p, BAND)[0] - exponent) < 0.1


def test_synthetic_record_is_gaussian():
    w = dmw.synthesize(1.0, BAND, -2.0, 50e-3, FS, seed=11)
    z = w / rms(w)
    assert abs(np.mean(z**3)) < 0.1                     # skewness
    assert abs(np.mean(z**4) - 3.0) < 0.2               # kurtosis


def test_same_seed_same_record_bit_for_bit():
    a = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=20090601)
    b = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=20090601)
    c = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=20090602)
    assert a.tobytes() == b.tobytes()
    assert not np.array_equal(a, c)
    assert abs(np.corrcoef(a, c)[0, 1]) < 0.2


def test_same_seed_keeps_phases_when_exponent_changes():
    a = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=5, amplitudes="fixed")
    b = dmw.synthesize(0.5, BAND, -1.0, T, FS, seed=5, amplitudes="fixed")
    A, B = np.fft.rfft(a), np.fft.rfft(b)
    k = slice(20, 1001)
    assert np.allclose(np.angle(A[k] / B[k]), 0.0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(rms_nm=st.floats(0.01, 5.0), exponent=st.floats(-4.0, 1.0),
       lo=st.floats(1e3, 5e4), ratio=st.floats(2.0, 100.0), seed=st.integers(0, 2**32 - 1),
       amplitudes=st.sampled_from(["gaussian", "fixed"]))
def test_property_rms_and_band(rms_nm, exponent, lo, ratio, seed, amplitudes):
    fs, duration = 2e6, 1e-3                              # 2000 samples, 1 kHz resolution
    hi = min(lo * ratio, fs / 2)
    w = dmw.synthesize(rms_nm, (lo, hi), exponent, duration, fs, seed, amplitudes=amplitudes)
    assert abs(rms(w) / rms_nm - 1) < 1e-9
    f, p = dmw.spectrum(w, fs)
    tol = dmw.EDGE_TOL          # a bin within 1e-9 (relative) of an edge counts as on the edge
    outside = (f < lo * (1 - tol)) | (f > hi * (1 + tol))
    assert p[outside].sum() <= 1e-6 * p.sum()


# ---------------------------------------------------------------------------------------- processing

@pytest.mark.parametrize("exponent", [-3.0, -2.0, 0.0])
def test_velocity_to_displacement_round_trip(exponent):
    x = dmw.synthesize(0.5, BAND, exponent, T, FS, seed=2)
    v = dmw.displacement_to_velocity(x, FS)                 # [nm/s]
    back = dmw.velocity_to_displacement(v + 3e5, FS, BAND[0], BAND[1])   # plus an LDV offset
    assert rms(back - x) / rms(x) < 0.01
    back = dmw.velocity_to_displacement(v, FS, BAND[0])     # no low-pass: still exact in band
    assert rms(back - x) / rms(x) < 0.01


def test_process_displacement_removes_offset_and_drift():
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=2)
    t = np.arange(x.size) / FS
    y = dmw.process_displacement(x + 40.0 + 2e4 * t, FS, BAND[0], BAND[1])   # 40 nm offset, 40 nm drift
    assert rms(y - x) / rms(x) < 0.01


def test_velocity_integration_non_periodic_segment_is_reasonable():
    # a 2 ms window of a longer record: not periodic; the brick-wall edge costs a few per cent
    xl = dmw.synthesize(0.5, BAND, -2.0, 20e-3, FS, seed=4)
    vl = dmw.displacement_to_velocity(xl, FS)
    x, v = xl[4000:12000], vl[4000:12000]
    back = dmw.velocity_to_displacement(v, FS, BAND[0], BAND[1])
    assert rms(back - (x - x.mean())) / rms(x) < 0.15


def test_spectrum_welch_option():
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=2)
    f, p = dmw.spectrum(x, FS, nperseg=2048)
    assert f.size == 1025
    assert abs(np.trapezoid(p, f) / 0.25 - 1) < 0.1


def test_resample_rational_ratio():
    w8 = dmw.synthesize(0.5, BAND, -2.0, T, 8e6, seed=3)
    y, how = dmw.resample(w8, 8e6, 4e6)
    assert "resample_poly" in how and y.size == 8000
    assert rms(y - w8[::2]) / 0.5 < 1e-3


# ---------------------------------------------------------------------------------------- spectra


@pytest.mark.parametrize("n", [4000, 4001, 2, 3])
def test_periodogram_equals_scipy(n):
    """The numpy periodogram of ``spectrum`` is scipy's boxcar periodogram (even and odd lengths:
    the Nyquist bin exists, and is counted once, only for even ``N``), Parseval included."""
    from scipy import signal
    x = np.random.default_rng(n).standard_normal(n)
    f, p = dmw.spectrum(x, FS)
    f_ref, p_ref = signal.periodogram(x, fs=FS, window="boxcar", detrend=False, scaling="density")
    # tol: k fs / n two ways, IEEE arithmetic alone: an ulp or two, the same on any host
    np.testing.assert_allclose(f, f_ref, rtol=1e-15)
    # tol: two FFTs of a seeded record (numpy's, scipy's): the smallest bins' rounding, measured 3e-14
    np.testing.assert_allclose(p, p_ref, rtol=1e-12, atol=0)
    # tol: Parseval's identity: FFT rounding, ~log2(n) eps of the mean square
    assert p.sum() * FS / n == pytest.approx(np.mean(x * x), rel=1e-12)  # Parseval, DC included
