"""Reading measured DMW records (CSV or NetCDF) into validated arrays: the file side of the DMW.

:func:`load_record` reads one column or variable of displacement [length] or velocity [length/s],
finds or assumes its units and sampling rate, and checks every value; each problem is a
:class:`pipeline.physics.microwaviness.DMWError` naming the file, the field and what was expected. The physics
of the record (the paper's processing, synthesis, spectra) is :mod:`pipeline.physics.microwaviness`.
"""

from __future__ import annotations

import csv
import itertools
import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Iterator

import numpy as np

from .. import interrupts
from ..io import NETCDF_LOCK
from ..paths import looked_for, special_kind
from ..physics.microwaviness import TIME_JITTER_TOL, DMWError
from ..units import LENGTH_UNITS, TIME_UNITS, VELOCITY_UNITS
from ..units import MS

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Record:
    """A measured record, validated and converted to [nm] or [nm/s].

    Attributes
    ----------
    values : displacement [nm] or velocity [nm/s]
    sample_rate_hz : sampling rate [Hz]
    quantity : ``"displacement"`` or ``"velocity"``
    path : the file
    column : the column / variable read (a CSV column without header: its index)
    field : how the column is named in messages (``column 'velocity [mm/s]'``, ``variable 'w'``)
    units : the record's own units (as found, or assumed)
    notes : what was assumed (e.g. units not stated)
    """

    values: np.ndarray
    sample_rate_hz: float
    quantity: str
    path: str
    column: str
    field: str
    units: str
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def duration_s(self) -> float:
        """Record length ``n / fs`` [s]."""
        return self.values.size / self.sample_rate_hz


_BRACKET = re.compile(r"^\s*(.*?)\s*[\[\(]\s*([^\]\)]*?)\s*[\]\)]\s*$")
_SUFFIXES = ("nm_s", "um_s", "mm_s", "m_s", "nm", "um", "mm", "m", "ms", "us", "ns", "s")


#: What a column name or unit of a record's header must look like to be repeated in a message: a short
#: name of letters, digits and the signs of units. Anything else is file content (``dmw.source`` set to
#: ``/proc/self/environ`` or a key file printed it): a message names the column by its index instead,
#: and it never repeats a data value.
_NAME = re.compile(r"[A-Za-z_µμ][\w .\-\[\]()/%µμ^*+]{0,39}")


def _shown(text: str) -> str:
    """``text`` quoted for a message when it looks like a name (:data:`_NAME`), else ``(not shown)``."""
    return repr(text) if _NAME.fullmatch(text) else "(not shown)"


def _norm_unit(u: str) -> str:
    u = u.strip().lower().replace("µ", "u").replace("μ", "u")
    u = re.sub(r"\s*(s\^?-1|s⁻¹)$", "/s", u)          # "m s-1" -> "m/s"
    u = re.sub(r"\s*/\s*", "/", u)
    u = re.sub(r"_s$", "/s", u) if u.count("_") == 1 else u   # "m_s" -> "m/s"
    return {"micrometre": "um", "micrometer": "um", "nanometre": "nm", "nanometer": "nm",
            "meter": "m", "metre": "m", "sec": "s"}.get(u, u)


def _split_header(name: str) -> tuple[str, str | None]:
    """``"velocity [mm/s]"`` -> ``("velocity", "mm/s")``; ``"time_s"`` -> ``("time", "s")``."""
    m = _BRACKET.match(name)
    if m:
        return m.group(1).strip(), _norm_unit(m.group(2))
    low = name.strip()
    for suf in _SUFFIXES:
        if low.lower().endswith("_" + suf) and len(low) > len(suf) + 1:
            return low[: -len(suf) - 1], _norm_unit(suf)
    return low, None


#: quantity -> (kind of its unit, units -> factor to [nm] or [nm/s], the other quantity)
_QUANTITY_UNITS = {"displacement": ("length", LENGTH_UNITS, "velocity"),
                   "velocity": ("velocity", VELOCITY_UNITS, "displacement")}


def _value_factor(path: Path, field_name: str, unit: str | None, quantity: str,
                  scene_unit: str | None = None) -> tuple[float, str, tuple[str, ...]]:
    """Factor to [nm] / [nm/s] for a value column, and the unit used: the record's own (``unit``), else
    ``scene_unit`` (``dmw.unit``); a record stating none without ``dmw.unit`` is refused, one that states
    another than ``dmw.unit`` too."""
    kind, units, other = _QUANTITY_UNITS[quantity]
    notes: tuple[str, ...] = ()
    given = _norm_unit(scene_unit) if scene_unit else None
    if unit is None or unit == "":
        if given is None:
            example = "displacement [nm]" if quantity == "displacement" else "velocity [mm/s]"
            raise DMWError(f"{path}: {field_name}: no unit stated; expected one in the record (a CSV header such as "
                           f"'{example}' or '{quantity}_{'nm' if quantity == 'displacement' else 'mm_s'}', a NetCDF "
                           f"'units' attribute) or set dmw.unit (one of {', '.join(units)})")
        unit, notes = given, (f"{field_name}: no unit stated; {given} from dmw.unit",)
        if unit not in units:
            field_name = "dmw.unit"
    elif given is not None and given != unit:
        raise DMWError(f"{path}: {field_name}: the record states {_shown(unit)} but dmw.unit = {scene_unit!r}; "
                       f"expected them to agree (leave dmw.unit out for a record that states its unit)")
    if unit in units:
        return units[unit], unit, notes
    other_kind, other_units, _ = _QUANTITY_UNITS[other]
    if unit in other_units:  # a unit of the other quantity: the scene names the wrong one
        raise DMWError(f"{path}: {field_name}: has {other_kind} units {_shown(unit)} but the quantity is "
                       f"'{quantity}': set dmw.quantity = \"{other}\"")
    raise DMWError(f"{path}: {field_name}: unknown {kind} unit {_shown(unit)}; expected one of " + ", ".join(units))


def _time_factor(path: Path, field_name: str, unit: str | None) -> float:
    if unit is None or unit == "":
        return 1.0
    unit = unit.split(" since ")[0].strip()
    if unit not in TIME_UNITS:
        raise DMWError(f"{path}: {field_name}: unknown time unit {_shown(unit)}; expected one of "
                       + ", ".join(TIME_UNITS))
    return TIME_UNITS[unit]


def _is_time_name(base: str) -> bool:
    return base.strip().lower() in ("time", "t", "times")


def _rate_from_time(path: Path, field_name: str, t: np.ndarray) -> float:
    """Sampling rate [Hz] of a time axis [s]; rejects non-increasing or non-uniform axes."""
    if t.size < 2:
        raise DMWError(f"{path}: {field_name}: {t.size} sample(s); expected at least 2")
    if not np.all(np.isfinite(t)):
        bad = int(np.flatnonzero(~np.isfinite(t))[0])
        raise DMWError(f"{path}: {field_name}: non-finite time at sample {bad}; expected finite times")
    dt_all = np.diff(t)
    if np.any(dt_all <= 0):
        bad = int(np.flatnonzero(dt_all <= 0)[0])
        raise DMWError(f"{path}: {field_name}: time does not increase at sample {bad + 1} "
                       f"({t[bad]!r} -> {t[bad + 1]!r}); expected strictly increasing times")
    dt = (t[-1] - t[0]) / (t.size - 1)
    jitter = float(np.max(np.abs(t - (t[0] + dt * np.arange(t.size)))) / dt)
    if jitter > TIME_JITTER_TOL:
        raise DMWError(f"{path}: {field_name}: non-uniform time axis (largest deviation from a uniform "
                       f"grid {jitter:.3g} sampling intervals); expected uniform sampling within "
                       f"{TIME_JITTER_TOL:g} (write times with full precision, or drop the time column "
                       f"and give dmw.sample_rate_hz)")
    return 1.0 / dt


def _check_values(path: Path, field_name: str, x: np.ndarray) -> None:
    if x.size < 2:
        raise DMWError(f"{path}: {field_name}: {x.size} sample(s); expected at least 2")
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        raise DMWError(f"{path}: {field_name}: {bad.size} NaN/infinite value(s), first at sample "
                       f"{int(bad[0])}; expected finite numbers")


def _sniff_delimiter(line: str) -> str | None:
    for d in (",", ";", "\t"):
        if d in line:
            return d
    return None  # whitespace


#: Data rows of a CSV record between two progress lines (a 10-million-row file takes about a minute).
PROGRESS_ROWS = 2_000_000


def _data_lines(fh: Iterable[str], first: int = 1) -> Iterator[tuple[int, str]]:
    """``(line number, line)`` of the data lines of a CSV file: not blank, not a ``#`` comment."""
    for i, ln in enumerate(fh, start=first):
        ln = ln.rstrip("\r\n")
        if ln.strip() and not ln.lstrip().startswith("#"):
            yield i, ln


def count_lines(path: str | Path) -> int:
    """Lines of a text file (an upper bound on a CSV record's samples), counted without decoding it."""
    n, last = 0, b"\n"
    with open(path, "rb") as fh:
        while block := fh.read(1 << 22):
            n += block.count(b"\n")
            last = block[-1:]
    return n + (last != b"\n")


def _ends_a_line(path: str | Path) -> bool:
    """Whether a (non-empty) text file's last byte ends a line: what every CSV writer leaves, and a file
    cut short does not."""
    with open(path, "rb") as fh:
        fh.seek(0, 2)
        if fh.tell() == 0:
            return True
        fh.seek(-1, 2)
        return fh.read(1) in (b"\n", b"\r")


#: Suffixes of NetCDF records (any other is read as CSV).
NETCDF_SUFFIXES = (".nc", ".nc4", ".cdf", ".netcdf")


def record_samples(path: str | Path) -> int:
    """At most how many samples a record file holds, from its size alone (no value is read): a CSV's
    lines, a NetCDF file's longest dimension; 0 for a file that cannot be read (the reader says why)."""
    path = Path(path)
    if special_kind(path) is not None:  # (a FIFO, /dev/zero: never opened; the reader refuses it)
        return 0
    try:
        if path.suffix.lower() not in NETCDF_SUFFIXES:
            return count_lines(path)
        import netCDF4
        with NETCDF_LOCK, netCDF4.Dataset(path) as nc:
            return max((len(d) for d in nc.dimensions.values()), default=0)
    except OSError:
        return 0


def _read_csv(path: Path, quantity: str, column: str | None, sample_rate_hz: float | None,
              unit: str | None = None) -> tuple[np.ndarray, float, str, str, str, tuple[str, ...]]:
    """Read a CSV record row by row into the two arrays it needs (a list of rows of strings took ~600
    bytes a sample: 6 GB for 10 million); a UTF-8 byte-order mark before the header is not part of it."""
    try:
        return _parse_csv(path, quantity, column, sample_rate_hz, unit)
    except UnicodeDecodeError:
        raise DMWError(f"{path}: not a text (CSV) file; expected CSV or NetCDF (.nc)") from None


def _parse_csv(path: Path, quantity: str, column: str | None, sample_rate_hz: float | None,
               unit: str | None = None) -> tuple[np.ndarray, float, str, str, str, tuple[str, ...]]:
    n_lines = count_lines(path)
    with open(path, "rb") as fh:
        if b"\x00" in fh.read(1 << 16):  # (a binary file, or /proc/self/environ: NUL is no CSV character)
            raise DMWError(f"{path}: not a text (CSV) file (it holds NUL bytes); expected CSV or NetCDF (.nc)")
    with open(path, encoding="utf-8-sig") as fh:
        lines = _data_lines(fh)
        first = next(lines, None)
        if first is None:
            raise DMWError(f"{path}: no data rows; expected a CSV record")
        delim = _sniff_delimiter(first[1])

        def split(ln: str) -> list[str]:
            if delim is None:
                return ln.split()
            cells = ln.split(delim) if '"' not in ln else next(csv.reader([ln], delimiter=delim))  # (quotes: csv)
            return [c.strip() for c in cells]

        head = split(first[1])
        header = None if all(_numeric(c) for c in head if c != "") else head
        ncol = len(head)
        names = header if header is not None else [str(i) for i in range(ncol)]
        # how a column is named in messages: its header name when it looks like one, else its index
        shown = [h if header is not None and _NAME.fullmatch(h) else f"column {i}" for i, h in enumerate(names)]
        labels = [f"column {h!r}" if h == n else h for h, n in zip(shown, names)]
        split_names = [_split_header(h) for h in names] if header is not None else [(n, None) for n in names]
        time_idx, val_idx = _columns(path, split_names, names, shown, header is not None, column, quantity,
                                     sample_rate_hz)
        wanted = [val_idx] + ([time_idx] if time_idx is not None else [])
        out = np.empty((len(wanted), n_lines))
        n = 0
        line_no = first[0]
        for line_no, ln in itertools.chain([] if header is not None else [first], lines):
            row = split(ln)
            if len(row) > ncol and any(c != "" for c in row[ncol:]):
                raise DMWError(f"{path}: line {line_no}: {len(row)} columns; expected {ncol} "
                               f"({', '.join(shown)}) as in the first row")
            for k, i in enumerate(wanted):
                if i >= len(row) or row[i] == "":
                    raise DMWError(f"{path}: {labels[i]}: missing value on line {line_no}; expected a number")
                try:
                    out[k, n] = float(row[i])
                except ValueError:
                    raise DMWError(f"{path}: {labels[i]}: non-numeric value on line {line_no}; "
                                   f"expected a number") from None  # (the value not shown: file content)
            n += 1
            if n % PROGRESS_ROWS == 0:
                log.info("dmw: %s: read %d of at most %d rows", path, n, n_lines)
    if line_no == n_lines and not _ends_a_line(path):
        raise DMWError(f"{path}: line {line_no}: the file ends inside this line (no line break after it), as a record "
                       "cut short ends (an interrupted copy or download), maybe in the middle of a number; restore the "
                       f"whole file, or end it with a line break if line {line_no} is complete")
    field_name = labels[val_idx]
    x = out[0, :n]
    _check_values(path, field_name, x)
    factor, unit, notes = _value_factor(path, field_name, split_names[val_idx][1], quantity, unit)
    if time_idx is not None:
        t = out[1, :n] * _time_factor(path, labels[time_idx], split_names[time_idx][1])
        rate = _rate_from_time(path, labels[time_idx], t)
        if sample_rate_hz is not None and abs(rate / sample_rate_hz - 1) > 1e-6:
            raise DMWError(f"{path}: {labels[time_idx]}: time axis gives {rate:.9g} Hz but "
                           f"dmw.sample_rate_hz = {sample_rate_hz:g}; expected them to agree")
    else:
        rate = float(sample_rate_hz)  # type: ignore[arg-type]
    return x * factor, rate, names[val_idx], field_name, unit, notes


def _numeric(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def _columns(path: Path, split: list[tuple[str, str | None]], names: list[str], shown: list[str],
             has_header: bool, column: str | None, quantity: str,
             sample_rate_hz: float | None) -> tuple[int | None, int]:
    """Indices of the time column (``None``: none) and of the value column of a CSV record."""
    ncol = len(names)
    time_idx = next((i for i, (b, _) in enumerate(split) if has_header and _is_time_name(b)), None)
    if time_idx is None and not has_header and ncol == 2 and sample_rate_hz is None:
        time_idx = 0  # headerless two-column file: time, value
    if column is not None:
        key = column.strip().lower()
        matches = [i for i, (b, _) in enumerate(split) if key in (names[i].strip().lower(), b.lower())]
        if not matches and key.isdigit() and int(key) < ncol:
            matches = [int(key)]
        if not matches:
            raise DMWError(f"{path}: column {column!r} not found; expected one of {shown} "
                           f"(or a column index 0..{ncol - 1}) (dmw.column)")
        val_idx = matches[0]
    else:
        candidates = [i for i in range(ncol) if i != time_idx]
        named = [i for i in candidates if split[i][0].lower() == quantity]
        if len(named) == 1:
            val_idx = named[0]
        elif len(candidates) == 1:
            val_idx = candidates[0]
        else:
            raise DMWError(f"{path}: {len(candidates)} value columns {[shown[i] for i in candidates]}; "
                           f"expected one: set dmw.column")
    if time_idx is None and sample_rate_hz is None:
        raise DMWError(f"{path}: no time column (a header 'time', 'time [s]', 'time_s', ...) and no "
                       f"sample rate; expected a time column or dmw.sample_rate_hz")
    return time_idx, val_idx


def _read_netcdf(path: Path, quantity: str, column: str | None, sample_rate_hz: float | None,
                 unit: str | None = None) -> tuple[np.ndarray, float, str, str, str, tuple[str, ...]]:
    """A NetCDF record: a variable on a ``time`` coordinate [s] (or ms, us), or, with ``sample_rate_hz``, a
    variable on one dimension of any name (``sample``) without a time coordinate."""
    import xarray as xr
    try:
        with xr.open_dataset(path, engine="netcdf4", decode_times=False, decode_timedelta=False) as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise DMWError(f"{path}: not a readable NetCDF file ({exc}); expected NetCDF with a variable "
                       f"on a 'time' coordinate") from None
    except RuntimeError as exc:  # (netCDF4's "NetCDF: HDF error": a chunk that does not decompress)
        raise DMWError(f"{path}: its data cannot be read back ({exc}: a damaged file); restore the record "
                       "from a copy (dmw.source)") from None
    interrupts.check()  # (netCDF4's error checks can swallow a signal raised during the read)
    if "elapsed_time" in ds.variables and "time" not in ds.variables:  # a dmw.nc of this pipeline (variables.TIME)
        ds = ds.rename({"elapsed_time": "time"})
    timed = "time" in ds.variables or "time" in ds.dims
    if not timed and sample_rate_hz is None:
        raise DMWError(f"{path}: no 'time' coordinate and no sample rate; expected a 'time' "
                       f"coordinate [s] or dmw.sample_rate_hz")

    def fits(v: Any) -> bool:  # (a record's variable: on 'time', or on one dimension when there is no time)
        return ds[v].dims == ("time",) if timed else ds[v].ndim == 1
    on = "'time'" if timed else "one dimension"
    if column is not None:
        if column not in ds.data_vars:
            raise DMWError(f"{path}: variable {column!r} not found; expected one of "
                           f"{', '.join(_shown(str(v)) for v in sorted(map(str, ds.data_vars)))} (dmw.column)")
        name = column
    else:
        cands = [str(v) for v in ds.data_vars if fits(v)]
        named = [v for v in cands if v == quantity]
        if named:
            name = named[0]
        elif len(cands) == 1:
            name = cands[0]
        else:
            raise DMWError(f"{path}: {len(cands)} variables on {on} ({', '.join(map(_shown, cands))}); expected "
                           "one: set dmw.column")
    da = ds[name]
    field_name = f"variable {_shown(name)}"
    if not fits(name):
        raise DMWError(f"{path}: {field_name}: dimensions {da.dims}; expected ('time',)" if timed else
                       f"{path}: {field_name}: dimensions {da.dims}; expected one dimension (samples at "
                       f"dmw.sample_rate_hz)")
    try:
        x = np.asarray(da.values, dtype=float)
    except (TypeError, ValueError):
        raise DMWError(f"{path}: {field_name}: non-numeric data ({da.dtype}); expected numbers") from None
    _check_values(path, field_name, x)
    own = da.attrs.get("units")
    factor, own, notes = _value_factor(path, field_name, _norm_unit(own) if own else None, quantity, unit)
    if "time" in ds.variables:
        tv = ds["time"]
        try:
            t = np.asarray(tv.values, dtype=float)
        except (TypeError, ValueError):
            raise DMWError(f"{path}: coordinate 'time': non-numeric ({tv.dtype}); expected seconds") from None
        tu = tv.attrs.get("units")
        t = t * _time_factor(path, "coordinate 'time'", _norm_unit(tu) if tu else None)
        rate = _rate_from_time(path, "coordinate 'time'", t)
        if sample_rate_hz is not None and abs(rate / sample_rate_hz - 1) > 1e-6:
            raise DMWError(f"{path}: coordinate 'time' gives {rate:.9g} Hz but dmw.sample_rate_hz = "
                           f"{sample_rate_hz:g}; expected them to agree")
    elif sample_rate_hz is not None:
        rate = float(sample_rate_hz)
    else:
        raise DMWError(f"{path}: dimension 'time' has no coordinate and there is no sample rate; expected a "
                       f"'time' coordinate [s] or dmw.sample_rate_hz")
    return x * factor, rate, name, field_name, own, notes


def load_record(path: str | Path, quantity: str = "displacement", column: str | None = None,
                sample_rate_hz: float | None = None, *, unit: str | None = None,
                min_duration_s: float | None = None) -> Record:
    """Read and validate a measured DMW record (CSV or NetCDF).

    CSV (any other suffix than ``.nc``/``.nc4``/``.cdf``): comma, semicolon, tab or whitespace
    separated; ``#`` comment lines skipped; an optional header row; the last data row ends with a line break,
    as every CSV writer ends it (a file that ends inside its last row was cut short, maybe in the middle of a
    number that still parses, ``1.5e-0`` of ``1.5e-04``: refused naming that line). The time column is the one named
    ``time``/``t`` (unit in brackets or as a suffix: ``time [s]``, ``time (ms)``, ``time_us``; default
    s); without a header, a two-column file is ``time, value`` unless ``sample_rate_hz`` is given. The
    value column is ``column`` (header name, with or without its unit, or index), else the one named
    like ``quantity``, else the only non-time column. Units of values: ``nm``, ``um``, ``mm``, ``m``
    (displacement) or ``nm/s``, ``um/s``, ``mm/s``, ``m/s`` (velocity); unstated units are
    refused unless ``unit`` (``dmw.unit``) gives them (noted in :attr:`Record.notes`).

    NetCDF: the variable ``column``, else the one named like ``quantity``, else the only variable on
    ``time``; units from the ``units`` attributes; the ``time`` coordinate in s (or ``ms``, ``us``).
    Without a ``time`` coordinate and with ``sample_rate_hz``: the same on any one dimension (``sample``).

    The formats, with a runnable example of each: docs/my-drive.md, section "The DMW record".

    Parameters
    ----------
    path : the record file
    quantity : ``"displacement"`` [nm] or ``"velocity"`` [nm/s]
    column : column or variable name (``None``: see above)
    sample_rate_hz : sampling rate [Hz] of a record without a time axis (checked against one if present)
    unit : unit of the values when the record states none (``"nm"``, ``"mm/s"``, ...; ``None``: the record
        must state it)
    min_duration_s : required length [s] (``None``: no check)

    Returns
    -------
    Record
        values in [nm] or [nm/s].

    Raises
    ------
    DMWError
        Missing or unreadable file (a CSV file cut short, a damaged NetCDF file), missing column, non-numeric or
        NaN/infinite values, fewer than 2
        samples, a time axis that is not strictly increasing or not uniform (relative deviation
        > :data:`TIME_JITTER_TOL`), units that contradict ``quantity``, or a record shorter than
        ``min_duration_s``. The message names the file and the field.
    """
    path = Path(path)
    if quantity not in ("displacement", "velocity"):
        raise DMWError(f"{path}: quantity = {quantity!r}: expected 'displacement' or 'velocity' (dmw.quantity)")
    if sample_rate_hz is not None and not (sample_rate_hz > 0 and math.isfinite(sample_rate_hz)):
        raise DMWError(f"{path}: sample_rate_hz = {sample_rate_hz!r}: expected a positive number "
                       f"(dmw.sample_rate_hz)")
    if special_kind(path) is not None:  # (checked before opening: reading a FIFO or /dev/zero never ends)
        raise DMWError(f"{path}: is {special_kind(path)}; expected a regular file, a CSV or NetCDF record "
                       "(dmw.source)")
    if not path.is_file():
        raise DMWError(f"{path}: record file does not exist{looked_for(path)} (dmw.source)")
    reader = _read_netcdf if path.suffix.lower() in NETCDF_SUFFIXES else _read_csv
    x, rate, name, field_name, units, notes = reader(path, quantity, column, sample_rate_hz, unit)
    rec = Record(values=x, sample_rate_hz=float(rate), quantity=quantity, path=str(path), column=name,
                 field=field_name, units=units, notes=notes)
    if min_duration_s is not None and rec.duration_s < min_duration_s * (1 - 1e-9):
        raise DMWError(f"{path}: {field_name}: record is "
                       f"{rec.duration_s / MS:.6g} ms long ({x.size} samples at {rate:.6g} Hz); expected "
                       f"at least the requested duration {min_duration_s / MS:.6g} ms (dmw.duration_ms)")
    return rec
