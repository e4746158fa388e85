"""Tests of the DMW physics (pipeline.physics.microwaviness) and stage (pipeline.stages.dmw).

Known answers: the synthetic record's rms and band are exact by construction, its periodogram is
the target power law bin by bin (fixed amplitudes), and the spectral derivative / integral pair is
an exact round trip for a periodic band-limited record.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from pipeline.io import read_dataset
from pipeline.model import measured_dmw
from pipeline.physics import microwaviness as dmw
from pipeline.config.scene import scene_from_dict
from pipeline.model import dmw_record
from pipeline.runner import ensure

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


# ---------------------------------------------------------------------------------------- records

def _write_csv(path: Path, header: str | None, rows: list[tuple]) -> Path:
    lines = ([header] if header else []) + [",".join(repr(float(c)) if not isinstance(c, str) else c
                                                     for c in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def good_record(tmp_path):
    """A 2 ms velocity record [mm/s] at 4 MS/s, with its displacement truth [nm]."""
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=9)
    v = dmw.displacement_to_velocity(x, FS) * 1e-6          # nm/s -> mm/s
    t = np.arange(x.size) / FS
    path = tmp_path / "ldv.csv"
    np.savetxt(path, np.column_stack([t, v]), delimiter=",", header="time [s],velocity [mm/s]", comments="")
    return path, x


def test_load_csv_with_units(good_record):
    path, x = good_record
    rec = measured_dmw.load_record(path, "velocity")
    assert rec.sample_rate_hz == pytest.approx(FS, rel=1e-9)
    assert rec.units == "mm/s" and rec.column == "velocity [mm/s]"
    back = dmw.velocity_to_displacement(rec.values, rec.sample_rate_hz, *BAND)
    assert rms(back - x) / rms(x) < 0.01


def test_load_headerless_and_sample_rate(tmp_path):
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=9)
    p1 = tmp_path / "one.csv"
    np.savetxt(p1, x)
    rec = measured_dmw.load_record(p1, sample_rate_hz=FS)
    assert rec.sample_rate_hz == FS and np.allclose(rec.values, x)
    assert rec.units == "nm" and "assumed nm" in rec.notes[0]
    p2 = tmp_path / "two.txt"
    np.savetxt(p2, np.column_stack([np.arange(x.size) / FS * 1e3, x]))    # whitespace-separated
    p2h = tmp_path / "two_ms.csv"
    np.savetxt(p2h, np.column_stack([np.arange(x.size) / FS * 1e3, x]), delimiter=";",
               header="time_ms;w_nm", comments="")
    assert measured_dmw.load_record(p2).sample_rate_hz == pytest.approx(FS * 1e-3, rel=1e-9)  # no unit: s
    assert measured_dmw.load_record(p2h).sample_rate_hz == pytest.approx(FS, rel=1e-9)


def test_load_netcdf(tmp_path):
    import xarray as xr
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=9)
    ds = xr.Dataset({"w": ("time", x * 1e-3, {"units": "um"})},
                    coords={"time": ("time", np.arange(x.size) / FS * 1e6, {"units": "us"})})
    p = tmp_path / "rec.nc"
    ds.to_netcdf(p, engine="netcdf4")
    rec = measured_dmw.load_record(p)
    assert rec.sample_rate_hz == pytest.approx(FS, rel=1e-9)
    assert np.allclose(rec.values, x)
    with pytest.raises(dmw.DMWError, match=r"rec\.nc.*'velocity'.*not found"):
        measured_dmw.load_record(p, column="velocity")
    with pytest.raises(dmw.DMWError, match=r"rec\.nc.*variable 'w'.*length units"):
        measured_dmw.load_record(p, quantity="velocity")


def _errors(tmp_path: Path) -> dict[str, tuple[Path, dict, str]]:
    t = np.arange(100) / FS
    v = np.sin(2 * np.pi * 1e5 * t)
    nan = v.copy()
    nan[17] = np.nan
    jitter = t.copy()
    jitter[50] += 0.01 / FS
    cases = {
        "nan": (_write_csv(tmp_path / "nan.csv", "time [s],displacement [nm]", list(zip(t, nan))), {},
                r"nan\.csv: column 'displacement \[nm\]'.*NaN"),
        "jitter": (_write_csv(tmp_path / "jit.csv", "time [s],displacement [nm]", list(zip(jitter, v))), {},
                   r"jit\.csv: column 'time \[s\]'.*non-uniform"),
        "short": (_write_csv(tmp_path / "short.csv", "time [s],displacement [nm]", list(zip(t, v))),
                  {"min_duration_s": T}, r"short\.csv: column 'displacement \[nm\]'.*0\.025 ms long.*2 ms"),
        "missing": (_write_csv(tmp_path / "miss.csv", "time [s],displacement [nm]", list(zip(t, v))),
                    {"column": "velocity"}, r"miss\.csv: column 'velocity' not found"),
        "one": (_write_csv(tmp_path / "one.csv", "time [s],displacement [nm]", [(0.0, 1.0)]), {},
                r"one\.csv: column 'displacement \[nm\]'.*1 sample"),
        "text": (_write_csv(tmp_path / "text.csv", "time [s],displacement [nm]",
                            [(0.0, 1.0), (2.5e-7, "abc"), (5e-7, 2.0)]), {},
                 r"text\.csv: column 'displacement \[nm\]': non-numeric value on line 3; expected a number$"),
        "backwards": (_write_csv(tmp_path / "back.csv", "time [s],displacement [nm]", list(zip(t[::-1], v))),
                      {}, r"back\.csv: column 'time \[s\]'.*does not increase"),
        "no_time": (_write_csv(tmp_path / "notime.csv", "displacement [nm]", [(c,) for c in v]), {},
                    r"notime\.csv: no time column"),
        "units": (_write_csv(tmp_path / "units.csv", "time [s],velocity [m/s]", list(zip(t, v))), {},
                  r"units\.csv: column 'velocity \[m/s\]'.*velocity units"),
        "absent": (tmp_path / "absent.csv", {}, r"absent\.csv: record file does not exist"),
    }
    return cases


@pytest.mark.parametrize("case", ["nan", "jitter", "short", "missing", "one", "text", "backwards",
                                  "no_time", "units", "absent"])
def test_bad_records_rejected_with_clear_errors(tmp_path, case):
    path, kw, pattern = _errors(tmp_path)[case]
    with pytest.raises(dmw.DMWError, match=pattern) as exc:
        measured_dmw.load_record(path, **kw)
    assert str(path) in str(exc.value)
    assert isinstance(exc.value, ValueError)


def test_nan_in_netcdf_rejected(tmp_path):
    import xarray as xr
    x = np.ones(10)
    x[3] = np.inf
    p = tmp_path / "bad.nc"
    xr.Dataset({"displacement": ("time", x, {"units": "nm"})},
               coords={"time": ("time", np.arange(10) / FS, {"units": "s"})}).to_netcdf(p, engine="netcdf4")
    with pytest.raises(dmw.DMWError, match=r"bad\.nc: variable 'displacement'.*NaN/infinite.*sample 3"):
        measured_dmw.load_record(p)


# ---------------------------------------------------------------------------------------- stage

def test_stage_writes_synthetic_dmw(tmp_path):
    scene = scene_from_dict({"dmw": {"rms_nm": 0.5}})
    path = ensure("dmw", scene, tmp_path)
    assert path == tmp_path / "dmw.nc"
    ds = read_dataset(path)
    units = {"elapsed_time": "s", "displacement": "nm", "frequency": "Hz", "psd": "nm2 Hz-1", "rms": "nm",
             "band_low": "Hz", "band_high": "Hz", "sample_rate": "Hz", "disk_speed": "m s-1"}
    for name, u in units.items():
        assert ds[name].attrs["units"] == u and ds[name].attrs["long_name"]
    assert ds.sizes["elapsed_time"] == 8400 and ds.sizes["frequency"] == 4201      # 2.1 ms, see below
    assert float(ds.rms) == pytest.approx(0.5, rel=1e-12)
    assert rms(ds.displacement.values) == pytest.approx(0.5, rel=1e-12)
    assert float(ds.band_low) == 1e4 and float(ds.band_high) == 5e5
    assert ds.band_low.attrs["realised"] == 1e4 and ds.band_high.attrs["realised"] == 5e5
    assert float(ds.sample_rate) == 4e6
    assert float(ds.disk_speed) == pytest.approx(19.5, abs=0.05)   # docs/model.md, section "DMW": V = 19.5 m/s
    assert ds.attrs["seed"] == 20090601 and ds.attrs["dmw_source"] == "synthetic"
    assert ds.attrs["exponent"] == -2.0 and ds.attrs["dmw_enabled"] == 1
    t, w, fs = dmw_record.load(tmp_path)
    assert fs == 4e6 and np.array_equal(t, np.arange(8400) / 4e6)
    assert np.array_equal(w, dmw.synthesize(0.5, BAND, -2.0, 2.1e-3, FS, seed=20090601))


def test_stage_duration_default_and_override(tmp_path):
    # default: simulated duration + disk travel over the slider (59 us), up to whole 0.1 ms periods
    scene = scene_from_dict({})
    V = dmw_record.settings(scene)["disk_speed_m_s"]
    need = 2e-3 + (0.30e-3 + 0.85e-3) / V                   # front arm + slider length [m] / V
    assert need < dmw_record.settings(scene)["duration_s"] == pytest.approx(2.1e-3, rel=1e-12)
    s1 = scene_from_dict({"solver": {"duration_ms": 1.0, "transient_ms": 0.2}})
    assert dmw_record.load(ensure("dmw", s1, tmp_path / "a"))[1].size == 4400
    s2 = scene_from_dict({"dmw": {"duration_ms": 3.0, "sample_rate_mhz": 2.0}})
    assert dmw_record.load(ensure("dmw", s2, tmp_path / "b"))[1].size == 6000


def test_stage_measured_velocity_record(tmp_path):
    # an 8 MS/s velocity record [um/s], 3 ms long; the scene wants 2 ms at 4 MS/s
    x8 = dmw.synthesize(0.7, BAND, -2.0, 3e-3, 8e6, seed=21)
    v8 = dmw.displacement_to_velocity(x8, 8e6) * 1e-3
    rec = tmp_path / "ldv.csv"
    np.savetxt(rec, np.column_stack([np.arange(x8.size) / 8e6, v8]), delimiter=",",
               header="time_s,velocity_um_s", comments="")
    scene = scene_from_dict({"dmw": {"source": str(rec), "quantity": "velocity", "rms_nm": 5.0}})
    ds = read_dataset(ensure("dmw", scene, tmp_path / "out"))
    w = ds.displacement.values
    assert w.size == 8400
    assert rms(w - x8[:16800:2]) / 0.7 < 0.01
    assert float(ds.rms) == pytest.approx(rms(w))            # not rescaled to rms_nm = 5
    assert ds.attrs["record_rms_nm"] == pytest.approx(rms(w))
    assert ds.attrs["dmw_source"] == str(rec) and ds.attrs["dmw_quantity"] == "velocity"
    assert str(rec) in ds.attrs["input_hashes"] and "seed" not in ds.attrs
    assert "resample_poly" in ds.attrs["processing"] and "integration" in ds.attrs["processing"]


def test_stage_measured_too_short_or_undersampled(tmp_path):
    x = dmw.synthesize(0.5, BAND, -2.0, 1e-3, FS, seed=1)
    rec = tmp_path / "short.csv"
    np.savetxt(rec, np.column_stack([np.arange(x.size) / FS, x]), delimiter=",",
               header="time [s],displacement [nm]", comments="")
    with pytest.raises(dmw.DMWError, match=r"short\.csv.*1 ms long.*2\.1 ms"):
        ensure("dmw", scene_from_dict({"dmw": {"source": str(rec)}}), tmp_path)
    slow = tmp_path / "slow.csv"
    x = dmw.synthesize(0.5, (1e4, 2e5), -2.0, 3e-3, 5e5, seed=1)
    np.savetxt(slow, x)
    scene = scene_from_dict({"dmw": {"source": str(slow), "sample_rate_hz": 5e5}})
    with pytest.raises(dmw.DMWError, match=r"slow\.csv: column 0: sampled at 500000 Hz.*Nyquist"):
        ensure("dmw", scene, tmp_path)


def test_failing_load_keeps_existing_dataset(tmp_path):
    good = ensure("dmw", scene_from_dict({}), tmp_path)
    before = good.read_bytes()
    bad = tmp_path / "bad.csv"
    t = np.arange(10000) / FS
    w = np.sin(2 * np.pi * 2e4 * t)
    w[123] = np.nan
    np.savetxt(bad, np.column_stack([t, w]), delimiter=",", header="time [s],displacement [nm]", comments="")
    with pytest.raises(dmw.DMWError, match=r"bad\.csv.*NaN"):
        ensure("dmw", scene_from_dict({"dmw": {"source": str(bad)}}), tmp_path)
    assert good.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "dmw.nc"]   # no temp files left


def test_effect_off_writes_zero_dmw_and_needs_no_record(tmp_path):
    scene = scene_from_dict({"scene": {"effects": ["air_bearing", "pitch", "contact"]},
                             "dmw": {"source": str(tmp_path / "does-not-exist.csv")}})
    ds = read_dataset(ensure("dmw", scene, tmp_path))
    assert ds.attrs["dmw_enabled"] == 0 and "not in scene" in ds.attrs["disabled"]
    assert float(ds.rms) == 0.0 and not np.any(ds.displacement.values)
    assert ds.sizes["elapsed_time"] == 8400


def test_disk_speed_formula():
    s = dmw_record.settings(scene_from_dict({"dmw": {"rpm": 7200.0, "radius_mm": 20.0}}))
    assert s["disk_speed_m_s"] == pytest.approx(2 * math.pi * 0.02 * 7200 / 60)


def test_default_record_is_long_enough_for_the_dynamics(tmp_path):
    from pipeline.model import assembly
    scene = scene_from_dict({"scene": {"effects": ["air_bearing", "pitch", "dmw"]}})
    _, w, fs = dmw_record.load(ensure("dmw", scene, tmp_path))
    model = assembly.build_model(scene, None, (w, fs), None)   # raises if the record is too short
    assert model.dmw is not None


def test_stage_skips_when_up_to_date(tmp_path):
    import os
    scene = scene_from_dict({})
    path = ensure("dmw", scene, tmp_path)
    os.utime(path, (1, 1))
    assert ensure("dmw", scene, tmp_path) == path and path.stat().st_mtime == 1          # not rewritten
    ensure("dmw", scene.replace(slider={"length_mm": 3.0}), tmp_path)                    # longer default record
    assert path.stat().st_mtime != 1 and dmw_record.load(path)[1].size == 8800
    os.utime(path, (1, 1))
    ensure("dmw", scene.replace(slider={"length_mm": 3.0}), tmp_path, force=True)
    assert path.stat().st_mtime != 1


def test_stage_reruns_when_record_changes(tmp_path):
    import os
    rec = tmp_path / "rec.csv"
    x = dmw.synthesize(0.5, BAND, -2.0, 3e-3, FS, seed=1)
    np.savetxt(rec, x)
    scene = scene_from_dict({"dmw": {"source": str(rec), "sample_rate_hz": FS}})
    path = ensure("dmw", scene, tmp_path / "out")
    rms1 = float(read_dataset(path).rms)
    os.utime(path, (1, 1))
    assert ensure("dmw", scene, tmp_path / "out") == path and path.stat().st_mtime == 1
    np.savetxt(rec, 2 * x)
    ensure("dmw", scene, tmp_path / "out")
    assert path.stat().st_mtime != 1
    assert float(read_dataset(path).rms) == pytest.approx(2 * rms1, rel=1e-9)    # processing is linear


@pytest.mark.parametrize("n", [4000, 4001, 2, 3])
def test_periodogram_equals_scipy(n):
    """The numpy periodogram of ``spectrum`` is scipy's boxcar periodogram (even and odd lengths:
    the Nyquist bin exists, and is counted once, only for even ``N``), Parseval included."""
    from scipy import signal
    x = np.random.default_rng(n).standard_normal(n)
    f, p = dmw.spectrum(x, FS)
    f_ref, p_ref = signal.periodogram(x, fs=FS, window="boxcar", detrend=False, scaling="density")
    np.testing.assert_allclose(f, f_ref, rtol=1e-15)
    np.testing.assert_allclose(p, p_ref, rtol=1e-12, atol=0)
    assert p.sum() * FS / n == pytest.approx(np.mean(x * x), rel=1e-12)  # Parseval, DC included
