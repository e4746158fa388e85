"""Dynamic microwaviness (DMW): synthesis and LDV-style processing (reading measured records:
:mod:`pipeline.model.measured_dmw`).

The DMW is the disk's vertical displacement under the slider versus time, ``w(t)`` [nm]. The paper
measured it with a laser Doppler vibrometer (LDV) at mid-diameter, 5425 rpm, high-passed at 10 kHz,
content up to 500 kHz, 4 MS/s, averaged over 100 revolutions, velocity integrated to displacement
[VLP09] (docs/model.md, section "DMW").

Conventions
-----------
* Displacements in [nm], velocities in [nm/s], times in [s], frequencies in [Hz].
* Every filter here is a zero-phase *brick-wall* filter in the discrete Fourier domain: bins with
  ``lo <= f <= hi`` are kept unchanged, all others set to zero. This is the same band definition as
  the synthesis, so a synthetic record passes the processing unchanged, and nothing inside the band
  is attenuated (a Butterworth high-pass at ``lo``, even run forward-backward, halves the amplitude
  at ``lo``, where a red DMW spectrum has most of its energy). The DFT treats the record as one
  period of a periodic signal: exact for the synthetic record (periodic by construction) and for a
  synchronous average over whole revolutions (the paper's record); for any other record the wrap
  discontinuity leaks, which the linear detrend of displacement records keeps small, and which
  integration suppresses for velocity records (leakage ~ 1/f^2 after division by ``i 2 pi f``).
* A synthetic record is periodic with period equal to its duration, so circular delays
  (``np.roll``, or interpolation modulo the duration) are seamless.

References
----------
.. [VLP09] A. I. Vakis, S.-C. Lee, A. A. Polycarpou, "Dynamic head-disk interface instabilities with
   friction for light contact (surfing) recording", IEEE Trans. Magn. 45(11) (2009) 4966-4971,
   DOI 10.1109/TMAG.2009.2029410.
.. [SD91] M. Shinozuka, G. Deodatis, "Simulation of stochastic processes by spectral representation",
   Appl. Mech. Rev. 44(4) (1991) 191-204 (random-phase / random-amplitude spectral synthesis).
.. [PW93] D. B. Percival, A. T. Walden, *Spectral Analysis for Physical Applications*, Cambridge
   University Press (1993), ch. 6 (periodogram) and 6.17 (Welch's overlapped segment averaging).
.. [Bra11] A. Brandt, *Noise and Vibration Analysis*, Wiley (2011), sec. 3.4 and 9.5 (integration of
   vibration signals in the frequency domain).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

# scipy.signal (detrend, Welch, resample_poly) is imported inside the functions that use it: its import
# pulls in scipy.stats and costs ~0.5 s of every `hdi` process, while a synthetic record needs none of it.
#: Largest relative deviation of a record's time axis from a uniform grid (in sampling intervals).
TIME_JITTER_TOL = 1e-6
#: Relative tolerance used to decide whether a DFT bin lies on a band edge (floating-point round-off).
EDGE_TOL = 1e-9



class DMWError(ValueError):
    """A DMW record is unusable. The message names the file, the field and what was expected."""


# --------------------------------------------------------------------------------------------------
# Synthesis
# --------------------------------------------------------------------------------------------------

def n_samples(duration_s: float, sample_rate_hz: float) -> int:
    """Number of samples of a record of ``duration_s`` [s] at ``sample_rate_hz`` [Hz] (rounded).

    Parameters
    ----------
    duration_s : record length [s]
    sample_rate_hz : sampling rate [Hz]

    Returns
    -------
    int
        The number of samples [-].

    References
    ----------
    docs/model.md, section "DMW" (the record's grid).
    """
    return int(round(duration_s * sample_rate_hz))


def band_bins(n: int, sample_rate_hz: float, band_hz: tuple[float, float]) -> tuple[int, int]:
    """Indices ``(k_lo, k_hi)`` of the first and last ``rfft`` bins inside ``[lo, hi]``.

    Bin ``k`` has frequency ``k fs / n`` [Hz] (resolution ``1/duration``). A bin is inside when
    ``lo <= f_k <= hi`` up to a relative :data:`EDGE_TOL`, so a band edge that is a multiple of the
    resolution (10 kHz and 500 kHz on a 2 ms record) is included exactly; otherwise the realised
    band ``[f_klo, f_khi]`` lies inside ``[lo, hi]`` by less than one resolution step. The DC bin is
    never included (the DMW has zero mean).

    Parameters
    ----------
    n : number of samples
    sample_rate_hz : sampling rate fs [Hz]
    band_hz : ``(lo, hi)`` [Hz]

    Raises
    ------
    ValueError
        When no bin lies in the band (record shorter than about ``1/(hi - lo)``).

    Returns
    -------
    (int, int)
        The bin indices [-].

    References
    ----------
    [SD91] (the band of the spectral representation); docs/model.md, section "DMW".
    """
    lo, hi = band_hz
    df = sample_rate_hz / n
    k_lo = max(1, math.ceil(lo / df * (1 - EDGE_TOL)))
    k_hi = min(n // 2, math.floor(hi / df * (1 + EDGE_TOL)))
    if k_hi < k_lo:
        raise ValueError(f"band [{lo:g}, {hi:g}] Hz holds no frequency of a {n}-sample record at "
                         f"{sample_rate_hz:g} Hz (resolution {df:g} Hz): make the record longer")
    return k_lo, k_hi


def synthesize(rms_nm: float, band_hz: tuple[float, float], exponent: float, duration_s: float,
               sample_rate_hz: float, seed: int, *, amplitudes: str = "gaussian") -> np.ndarray:
    """A Gaussian, band-limited, power-law DMW record [nm] with exactly the prescribed rms.

    Spectral representation [SD91]: the ``rfft`` coefficient of bin ``k`` is
    ``c_k = A_k (g1 + i g2) / sqrt(2)`` with ``g1, g2`` standard normal and ``A_k = f_k^(exponent/2)``
    inside the band (:func:`band_bins`), zero outside; the record is ``irfft(c)``, rescaled to
    ``rms_nm``. Complex-normal coefficients (Rayleigh amplitude, uniform phase) make the record an
    exactly Gaussian, stationary, periodic process; ``amplitudes="fixed"`` keeps ``|c_k| = A_k``
    (random phase only), whose periodogram equals the target spectrum bin by bin.

    The normals are drawn for *every* ``rfft`` bin, in bin order, from
    ``numpy.random.default_rng(numpy.random.SeedSequence(seed))``, so for one seed and record length
    a change of band, exponent or rms keeps the phase of each bin (comparable parameter studies).

    Parameters
    ----------
    rms_nm : rms displacement [nm] (0 gives zeros)
    band_hz : ``(lo, hi)`` band [Hz]; ``0 <= lo < hi <= fs/2``
    exponent : exponent of the one-sided displacement PSD, ``S(f) ~ f^exponent`` [1] (e.g. -2)
    duration_s : record length [s]; the number of samples is ``round(duration_s * fs)``
    sample_rate_hz : sampling rate fs [Hz]
    seed : seed of the ``SeedSequence``
    amplitudes : ``"gaussian"`` (default) or ``"fixed"``

    Returns
    -------
    numpy.ndarray
        ``w`` [nm], ``round(duration_s * fs)`` samples at times ``i / fs``; zero mean, rms ``rms_nm``.

    References
    ----------
    [SD91] M. Shinozuka, G. Deodatis, Appl. Mech. Rev. 44 (1991) 191-204 (module docstring); docs/model.md,
    section "DMW".
    """
    if not (rms_nm >= 0 and math.isfinite(rms_nm)):
        raise ValueError(f"rms_nm = {rms_nm!r}: expected a finite number >= 0")
    lo, hi = float(band_hz[0]), float(band_hz[1])
    if not (0 <= lo < hi):
        raise ValueError(f"band_hz = {band_hz!r}: expected 0 <= lo < hi")
    if sample_rate_hz <= 0 or hi > sample_rate_hz / 2 * (1 + EDGE_TOL):
        raise ValueError(f"band_hz upper edge {hi:g} Hz is above the Nyquist frequency "
                         f"{sample_rate_hz / 2:g} Hz of sample_rate_hz = {sample_rate_hz:g}")
    if amplitudes not in ("gaussian", "fixed"):
        raise ValueError(f"amplitudes = {amplitudes!r}: expected 'gaussian' or 'fixed'")
    n = n_samples(duration_s, sample_rate_hz)
    if n < 2:
        raise ValueError(f"duration_s = {duration_s!r} at {sample_rate_hz:g} Hz gives {n} samples: expected >= 2")
    k_lo, k_hi = band_bins(n, sample_rate_hz, (lo, hi))
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    g = rng.standard_normal((n // 2 + 1, 2))
    if rms_nm == 0:
        return np.zeros(n)
    k = np.arange(k_lo, k_hi + 1)
    amp = (k * (sample_rate_hz / n)) ** (0.5 * exponent)
    z = g[k, 0] + 1j * g[k, 1]
    if amplitudes == "fixed":
        z = z / np.abs(z)  # unit modulus, the same uniform phase as the gaussian draw
    else:
        z = z / np.sqrt(2.0)
    c = np.zeros(n // 2 + 1, dtype=complex)
    c[k] = amp * z
    if n % 2 == 0 and k_hi == n // 2:
        # The Nyquist coefficient of a real signal is real; sqrt(2) keeps its expected power that
        # of an interior bin (which counts twice, for +f and -f).
        c[-1] = np.sqrt(2.0) * c[-1].real
    w = np.fft.irfft(c, n)
    return w * (rms_nm / np.sqrt(np.mean(w * w)))


def displacement_to_velocity(x: np.ndarray, sample_rate_hz: float) -> np.ndarray:
    """Exact spectral derivative of a periodic, band-limited record: ``v = irfft(i 2 pi f X)``.

    Parameters
    ----------
    x : displacement [nm], uniformly sampled, treated as one period
    sample_rate_hz : sampling rate [Hz]

    Returns
    -------
    numpy.ndarray
        velocity [nm/s]. The Nyquist bin (no defined sign of derivative) is set to zero.

    References
    ----------
    [VLP09] (the paper's LDV processing: high-pass at 10 kHz, velocity integrated); docs/model.md, section "DMW".
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    X = np.fft.rfft(x) * (2j * np.pi * f)
    if n % 2 == 0:
        X[-1] = 0.0
    return np.fft.irfft(X, n)


# --------------------------------------------------------------------------------------------------
# Processing (the paper's LDV chain)
# --------------------------------------------------------------------------------------------------

def _band_mask(n: int, sample_rate_hz: float, highpass_hz: float,
               lowpass_hz: float | None) -> tuple[np.ndarray, np.ndarray]:
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    keep = (f > 0) & (f >= highpass_hz * (1 - EDGE_TOL))
    if lowpass_hz is not None:
        keep &= f <= lowpass_hz * (1 + EDGE_TOL)
    return f, keep


def _check_filter_args(x: np.ndarray, sample_rate_hz: float, highpass_hz: float,
                       lowpass_hz: float | None) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise ValueError(f"expected a 1-D record of >= 2 samples, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("record holds NaN or infinite values")
    if not sample_rate_hz > 0:
        raise ValueError(f"sample_rate_hz = {sample_rate_hz!r}: expected > 0")
    if not highpass_hz >= 0:
        raise ValueError(f"highpass_hz = {highpass_hz!r}: expected >= 0")
    if lowpass_hz is not None and not lowpass_hz > highpass_hz:
        raise ValueError(f"lowpass_hz = {lowpass_hz!r}: expected > highpass_hz = {highpass_hz!r}")
    return x


def velocity_to_displacement(v: np.ndarray, sample_rate_hz: float, highpass_hz: float,
                             lowpass_hz: float | None = None) -> np.ndarray:
    """Displacement [nm] from an LDV velocity record [nm/s]: high-pass, integrate, remove drift.

    One zero-phase step in the discrete Fourier domain [Bra11]: ``X(f) = V(f) / (i 2 pi f)`` for
    ``highpass_hz <= f (<= lowpass_hz)``, ``X = 0`` elsewhere, ``x = irfft(X)``. This is the paper's
    chain (high-pass at 10 kHz, integrate velocity to displacement [VLP09]) with a brick-wall filter:
    the mean velocity (LDV offset), whose integral is a linear drift, and all content below the
    high-pass (the integral's low-frequency wander, runout) are removed in the same step, so no
    separate drift removal is needed and in-band content is integrated exactly (no trapezoid error,
    which is ~5 % at 500 kHz for 4 MS/s). See the module notes on periodicity.

    Parameters
    ----------
    v : velocity [nm/s], uniformly sampled
    sample_rate_hz : sampling rate [Hz]
    highpass_hz : high-pass edge [Hz] (the band's lower edge; > 0 is needed to remove drift)
    lowpass_hz : optional low-pass edge [Hz] (the band's upper edge)

    Returns
    -------
    numpy.ndarray
        displacement [nm], same length, zero mean.

    References
    ----------
    [VLP09] (the paper's chain), [Bra11] (module docstring: the Fourier-domain integration); docs/model.md,
    section "DMW".
    """
    v = _check_filter_args(v, sample_rate_hz, highpass_hz, lowpass_hz)
    n = v.size
    f, keep = _band_mask(n, sample_rate_hz, highpass_hz, lowpass_hz)
    V = np.fft.rfft(v)
    X = np.zeros_like(V)
    X[keep] = V[keep] / (2j * np.pi * f[keep])
    if n % 2 == 0:
        X[-1] = 0.0  # the Nyquist bin has no defined phase for an integral
    return np.fft.irfft(X, n)


def process_displacement(x: np.ndarray, sample_rate_hz: float, highpass_hz: float,
                         lowpass_hz: float | None = None) -> np.ndarray:
    """A displacement record [nm] processed like the paper's: drift removal and high-pass.

    Linear detrend (least squares; removes offset and drift, and the wrap discontinuity a drift
    would cause in the periodic DFT), then the zero-phase brick-wall filter of
    :func:`velocity_to_displacement` without the integration.

    Parameters
    ----------
    x : displacement [nm], uniformly sampled
    sample_rate_hz : sampling rate [Hz]
    highpass_hz : high-pass edge [Hz]
    lowpass_hz : optional low-pass edge [Hz]

    Returns
    -------
    numpy.ndarray
        displacement [nm], same length, zero mean.

    References
    ----------
    [VLP09] (the paper's LDV processing: high-pass at 10 kHz, velocity integrated); docs/model.md, section "DMW".
    """
    from scipy import signal
    x = _check_filter_args(x, sample_rate_hz, highpass_hz, lowpass_hz)
    x = signal.detrend(x, type="linear")
    _, keep = _band_mask(x.size, sample_rate_hz, highpass_hz, lowpass_hz)
    X = np.fft.rfft(x)
    X[~keep] = 0.0
    return np.fft.irfft(X, x.size)


def spectrum(x: np.ndarray, sample_rate_hz: float, nperseg: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One-sided power spectral density of a record.

    Default: the periodogram with a rectangular window and no detrending [PW93],
    ``psd_k = c_k |X_k|^2 / (fs N)`` with ``X = rfft(x)`` and ``c_k = 2`` except at 0 Hz and (even
    ``N``) at Nyquist, where ``c_k = 1``: resolution ``1/duration``, no leakage for a periodic record
    such as the synthetic one, and Parseval exact, ``sum(psd) * df == mean(x**2)`` (for zero-mean
    ``x``). It equals scipy's ``periodogram(..., window="boxcar", detrend=False, scaling="density")``
    (tested to 1e-12); it is written out with numpy because importing scipy.signal costs more than
    the whole synthesis. With ``nperseg``: Welch's average of Hann-windowed, half-overlapping segments
    [PW93] (``scipy.signal.welch``; smoother, for measured records; leaks by the Hann sidelobes).

    Parameters
    ----------
    x : record [nm]
    sample_rate_hz : sampling rate [Hz]
    nperseg : Welch segment length [samples], or ``None`` for the periodogram

    Returns
    -------
    frequency : numpy.ndarray
        Bin frequencies [Hz].
    psd : numpy.ndarray
        One-sided PSD [nm^2/Hz].

    References
    ----------
    [PW93] D. B. Percival, A. T. Walden, Spectral Analysis for Physical Applications (1993); docs/model.md,
    section "DMW".
    """
    x = np.asarray(x, dtype=float)
    if nperseg is None:
        n = x.size
        psd = np.abs(np.fft.rfft(x)) ** 2 / (sample_rate_hz * n)
        stop = psd.size - 1 if n % 2 == 0 else psd.size  # (even N: the last bin is Nyquist, once)
        psd[1:stop] *= 2.0  # one-sided: both signs of every other frequency
        return np.fft.rfftfreq(n, 1.0 / sample_rate_hz), psd
    from scipy import signal
    return signal.welch(x, fs=sample_rate_hz, window="hann", nperseg=min(nperseg, x.size),
                        detrend="constant", scaling="density")


def power_law_fit(frequency: np.ndarray, psd: np.ndarray, band_hz: tuple[float, float]) -> tuple[float, float]:
    """Least-squares fit of ``log psd = log C + exponent log f`` over the bins in ``band_hz``.

    For Gaussian coefficients each periodogram bin is ``S(f)`` times an exponential variable, whose
    logarithm has a constant mean: the slope is unbiased, ``C`` is low by ``exp(-0.577)``.

    Parameters
    ----------
    frequency : bin frequencies [Hz] (:func:`spectrum`)
    psd : one-sided PSD [nm^2/Hz] at those bins
    band_hz : ``(lo, hi)`` of the fit [Hz]

    Returns
    -------
    exponent : float
        The spectral exponent [1].
    prefactor : float
        C [nm^2/Hz / Hz^exponent].

    Raises
    ------
    ValueError
        For fewer than 2 positive bins in the band.

    References
    ----------
    [PW93] (the periodogram's exponential statistics); docs/model.md, section "DMW".
    """
    lo, hi = band_hz
    sel = (frequency >= lo * (1 - EDGE_TOL)) & (frequency <= hi * (1 + EDGE_TOL)) & (psd > 0)
    if np.count_nonzero(sel) < 2:
        raise ValueError(f"fewer than 2 positive PSD bins in [{lo:g}, {hi:g}] Hz: cannot fit a power law")
    slope, icpt = np.polyfit(np.log(frequency[sel]), np.log(psd[sel]), 1)
    return float(slope), float(np.exp(icpt))


def resample(x: np.ndarray, sample_rate_hz: float, new_rate_hz: float) -> tuple[np.ndarray, str]:
    """Resample a band-limited record to ``new_rate_hz`` [Hz].

    When the rate ratio is a fraction ``up/down`` with ``down <= 1000`` (exact to 1e-9), polyphase
    filtering (``scipy.signal.resample_poly``, Kaiser-windowed FIR, ``padtype="line"`` to limit edge
    transients); otherwise cubic-spline interpolation (accurate when the content is well below both
    Nyquist frequencies, as after the band filter). The output has ``floor(n * new / old)`` samples.

    Parameters
    ----------
    x : the record [nm] (or any unit), uniformly sampled
    sample_rate_hz : its sampling rate [Hz]
    new_rate_hz : the rate wanted [Hz]

    Returns
    -------
    y : numpy.ndarray
        The resampled record [nm] (the unit of ``x``).
    method : str
        A description for provenance [-].

    References
    ----------
    [PW93] (band-limited resampling); ``scipy.signal.resample_poly``; docs/model.md, section "DMW".
    """
    x = np.asarray(x, dtype=float)
    ratio = new_rate_hz / sample_rate_hz
    if abs(ratio - 1) < 1e-12:
        return x.copy(), "none"
    frac = Fraction(ratio).limit_denominator(1000)
    m = int(math.floor(x.size * ratio + 1e-9))
    if abs(float(frac) - ratio) <= 1e-9 * ratio:
        from scipy import signal
        y = signal.resample_poly(x, frac.numerator, frac.denominator, padtype="line")
        return y[:m], f"scipy.signal.resample_poly(up={frac.numerator}, down={frac.denominator}, padtype='line')"
    from scipy.interpolate import CubicSpline
    t = np.arange(x.size) / sample_rate_hz
    tn = np.arange(m) / new_rate_hz
    tn = tn[tn <= t[-1]]
    return CubicSpline(t, x)(tn), "scipy.interpolate.CubicSpline"
