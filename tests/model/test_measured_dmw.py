"""Reading measured DMW records (pipeline.model.measured_dmw.load_record): CSV with and without a header,
NetCDF, units and sampling rates found or assumed, and every bad record refused with one error naming the
file, the column and what was expected.

Known answers: a synthetic record (pipeline.physics.microwaviness.synthesize) written as velocity [mm/s]
or displacement [nm, um] reads back to the same displacement and sampling rate.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.model import measured_dmw
from pipeline.physics import microwaviness as dmw


FS = 4e6            # [Hz] the paper's sampling rate
BAND = (1e4, 5e5)   # [Hz] the paper's band
T = 2e-3            # [s] the paper scene's simulated duration


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


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
    # tol: a rate from a time column's step (t/step < 1e4 over the step), a few roundings
    assert rec.sample_rate_hz == pytest.approx(FS, rel=1e-9)
    assert rec.units == "mm/s" and rec.column == "velocity [mm/s]"
    back = dmw.velocity_to_displacement(rec.values, rec.sample_rate_hz, *BAND)
    assert rms(back - x) / rms(x) < 0.01


def test_load_headerless_and_sample_rate(tmp_path):
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=9)
    p1 = tmp_path / "one.csv"
    np.savetxt(p1, x)
    # a record that states no unit is refused unless dmw.unit gives it (no silent "assumed nm")
    with pytest.raises(dmw.DMWError, match=r"one\.csv: column 0: no unit stated; .*or set dmw\.unit"):
        measured_dmw.load_record(p1, sample_rate_hz=FS)
    rec = measured_dmw.load_record(p1, sample_rate_hz=FS, unit="nm")
    assert rec.sample_rate_hz == FS and np.allclose(rec.values, x)
    assert rec.units == "nm" and "nm from dmw.unit" in rec.notes[0]
    um = measured_dmw.load_record(p1, sample_rate_hz=FS, unit="um")  # [um] -> [nm]
    assert np.allclose(um.values, 1e3 * x) and um.units == "um"
    p2 = tmp_path / "two.txt"
    np.savetxt(p2, np.column_stack([np.arange(x.size) / FS * 1e3, x]))    # whitespace-separated
    p2h = tmp_path / "two_ms.csv"
    np.savetxt(p2h, np.column_stack([np.arange(x.size) / FS * 1e3, x]), delimiter=";",
               header="time_ms;w_nm", comments="")
    # tol: a rate from a time column's step (t/step < 1e4 over the step), a few roundings
    assert measured_dmw.load_record(p2, unit="nm").sample_rate_hz == pytest.approx(FS * 1e-3, rel=1e-9)  # time: s
    # a unit stated in the record and another in dmw.unit: refused
    with pytest.raises(dmw.DMWError, match=r"two_ms\.csv: column 'w_nm': the record states 'nm' but dmw\.unit = 'um'"):
        measured_dmw.load_record(p2h, unit="um")
    # tol: a rate from a time column's step (t/step < 1e4 over the step), a few roundings
    assert measured_dmw.load_record(p2h).sample_rate_hz == pytest.approx(FS, rel=1e-9)


def test_load_netcdf(tmp_path):
    import xarray as xr
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=9)
    ds = xr.Dataset({"w": ("time", x * 1e-3, {"units": "um"})},
                    coords={"time": ("time", np.arange(x.size) / FS * 1e6, {"units": "us"})})
    p = tmp_path / "rec.nc"
    ds.to_netcdf(p, engine="netcdf4")
    rec = measured_dmw.load_record(p)
    # tol: a rate from a time column's step (t/step < 1e4 over the step), a few roundings
    assert rec.sample_rate_hz == pytest.approx(FS, rel=1e-9)
    assert np.allclose(rec.values, x)
    with pytest.raises(dmw.DMWError, match=r"rec\.nc.*'velocity'.*not found"):
        measured_dmw.load_record(p, column="velocity")
    with pytest.raises(dmw.DMWError, match=r"rec\.nc.*variable 'w'.*length units"):
        measured_dmw.load_record(p, quantity="velocity")


def test_load_netcdf_on_a_sample_dimension_with_a_sample_rate(tmp_path):
    """A NetCDF record without a time coordinate, on a dimension 'sample': read at dmw.sample_rate_hz (was
    refused, "dimensions ('sample',); expected ('time',)"); without the rate, or with a unit stated nowhere,
    refused in one line."""
    import xarray as xr
    x = dmw.synthesize(0.5, BAND, -2.0, T, FS, seed=9)
    p = tmp_path / "samples.nc"
    xr.Dataset({"displacement": ("sample", x, {"units": "nm"})}).to_netcdf(p, engine="netcdf4")
    rec = measured_dmw.load_record(p, sample_rate_hz=FS)
    assert rec.sample_rate_hz == FS and rec.units == "nm" and np.array_equal(rec.values, x)
    with pytest.raises(dmw.DMWError, match=r"samples\.nc: no 'time' coordinate and no sample rate; .*dmw\.sample_rate_hz"):
        measured_dmw.load_record(p)
    bare = tmp_path / "bare.nc"
    xr.Dataset({"w": ("sample", x)}).to_netcdf(bare, engine="netcdf4")
    with pytest.raises(dmw.DMWError, match=r"bare\.nc: variable 'w': no unit stated; .*set dmw\.unit"):
        measured_dmw.load_record(bare, sample_rate_hz=FS)
    assert np.array_equal(measured_dmw.load_record(bare, sample_rate_hz=FS, unit="um").values, 1e3 * x)
    two = tmp_path / "two.nc"
    xr.Dataset({"w": (("run", "sample"), np.vstack([x, x]), {"units": "nm"})}).to_netcdf(two, engine="netcdf4")
    with pytest.raises(dmw.DMWError, match=r"two\.nc: variable 'w': dimensions \('run', 'sample'\); expected one "
                                           r"dimension"):
        measured_dmw.load_record(two, sample_rate_hz=FS, column="w")


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


def test_the_record_formats_of_docs_my_drive_run_and_read_back(tmp_path, monkeypatch, capsys):
    """docs/my-drive.md, section "The DMW record": its script writes the four forms (CSV with a header and unit
    suffix, CSV without a header, NetCDF on time, NetCDF on a sample dimension) and its `hdi dmw` commands read
    each to the same record; its scene file loads."""
    import re
    import shlex
    from pipeline import cli
    from pipeline.io import read_dataset
    page = (Path(__file__).resolve().parents[2] / "docs" / "my-drive.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```(\w+)\n(.*?)```", page, re.S)
    scene = next(text for lang, text in blocks if lang == "toml")
    section = page[page.index("## The DMW record"):page.index("## Your roughness scans")]
    script, commands = (text for lang, text in re.findall(r"```(\w+)\n(.*?)```", section, re.S))
    monkeypatch.chdir(tmp_path)
    exec(compile(script, "docs/my-drive.md", "exec"), {})
    (tmp_path / "my-drive.toml").write_text(scene)
    records = []
    for i, line in enumerate(c for c in commands.splitlines() if c.startswith("hdi dmw")):
        assert cli.main(shlex.split(line)[1:] + ["--out", f"out{i}", "-q"]) == 0, capsys.readouterr().err
        records.append(read_dataset(tmp_path / f"out{i}" / "dmw.nc").displacement.values)
    assert len(records) == 4
    for r in records[1:]:  # (the same record in four forms: equal to rounding of the written text)
        assert r.size == records[0].size == 8400 and np.allclose(r, records[0], rtol=0, atol=1e-9)
    assert 0.3 < rms(records[0]) < 0.5  # (the 0.4-nm record, band-passed again: as written)


def test_a_record_cut_short_is_refused_naming_its_last_line(tmp_path):
    x = dmw.synthesize(0.16, BAND, -2.0, 1e-4, FS, seed=3)
    whole = tmp_path / "whole.csv"
    np.savetxt(whole, x)
    assert measured_dmw.load_record(whole, sample_rate_hz=FS, unit="nm").values.size == x.size
    text = whole.read_bytes()
    for cut in (2, 9, 20):                    # inside the last number: its exponent ("e-0"), its digits, its mantissa
        part = tmp_path / f"cut{cut}.csv"
        part.write_bytes(text[:-cut])
        with pytest.raises(dmw.DMWError, match=rf"cut{cut}\.csv: line {x.size}: the file ends inside this line "
                                               r"\(no line break after it\), as a record cut short ends"):
            measured_dmw.load_record(part, sample_rate_hz=FS, unit="nm")
    with_comment = tmp_path / "comment.csv"                 # a last line that is no data: not a cut record
    with_comment.write_bytes(text + b"# end")
    assert measured_dmw.load_record(with_comment, sample_rate_hz=FS, unit="nm").values.size == x.size
    crlf = tmp_path / "crlf.csv"
    crlf.write_bytes(text.replace(b"\n", b"\r\n"))
    assert measured_dmw.load_record(crlf, sample_rate_hz=FS, unit="nm").values.size == x.size
