"""Datasets on disk: provenance attributes, atomic writes, explicit-engine reads.

Every dataset is written through :func:`write_dataset` (by :mod:`pipeline.runner` for the stages), which

* refuses a variable or coordinate without ``units`` and ``long_name`` (CF conventions) and writes it in its
  CF encoding, compressed and chunked (:mod:`pipeline.encoding`),
* adds the global attributes of docs/datasets.md (title, history, source, references, Conventions, the
  package's and the numerical libraries' versions, git revision, config hash, input-file hashes),
* records a checksum of each variable's values (:data:`CHECKSUM_ATTR`, :func:`data_checksums`),
* writes to a temporary file in the same folder and renames it into place, so an interrupted
  run never leaves a half-written file and never destroys the previous one.

Every dataset is read through :func:`read_dataset`, which checks those checksums: a damaged chunk (the HDF5
library's ``NetCDF: HDF error``) or values changed since hdi wrote them (a hand edit) is a one-line
:class:`DatasetDamaged` naming the file and the variable, never data used (:func:`stored_problem` gives the
runner the same verdict, to recompute such a dataset of a stage's own).

Every temporary file hdi writes is named by :func:`temporary_path` (or :func:`temporary_prefix`):
``.NAME.hdi-RUNID[.XXXXXXXX].tmp``, with this process's :data:`RUN_ID`. :func:`is_temporary` tells
those names apart from a user's (``.notes.tmp``), so the runner's cleaner removes only files hdi made.
"""

from __future__ import annotations

import datetime as _dt
import errno
import hashlib
import importlib.metadata
import json
import os
import re
import secrets
import subprocess
import tempfile
import threading
from functools import lru_cache
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
import xarray as xr

from . import DISTRIBUTION, __version__, duck_arrays, interrupts
from .paths import looked_for, refuse_links
from .variables import TIME
from .encoding import OLD_TIME_UNITS, cf_encoding
from .file_errors import current_umask, write_failure

# xarray's duck-array and dask-collection checks answered without importing dask and pint (~0.5 s a process)
duck_arrays.defer()

ENGINE = "netcdf4"
#: Serialises NetCDF I/O between threads of one process (pipeline.fanout runs tasks on threads):
#: the HDF5 library under netCDF4 is not thread-safe, and xarray does not lock file creation.
NETCDF_LOCK = threading.RLock()


#: This process's run id, part of the name of every temporary file it writes (:func:`temporary_path`).
RUN_ID = secrets.token_hex(6)
#: Names of hdi's temporary files: ``.NAME.hdi-<12 hex digits>.tmp``, or with mkstemp's random part
#: (``.NAME.hdi-<12 hex digits>.<random>.tmp``).
_TEMPORARY = re.compile(r"\..+\.hdi-[0-9a-f]{12}(\.[A-Za-z0-9_]+)?\.tmp")


def temporary_prefix(path: str | Path) -> str:
    """The name prefix of a temporary file for ``path`` (for :func:`tempfile.mkstemp`, with the suffix
    ``".tmp"``), marked as hdi's by :data:`RUN_ID`."""
    return f".{Path(path).name}.hdi-{RUN_ID}."


def temporary_path(path: str | Path) -> Path:
    """The temporary file beside ``path`` that is written, then renamed onto ``path``."""
    path = Path(path)
    return path.with_name(f".{path.name}.hdi-{RUN_ID}.tmp")


def is_temporary(name: str) -> bool:
    """Whether a file name is one of hdi's temporary files (:func:`temporary_path`), of any run."""
    return _TEMPORARY.fullmatch(name) is not None


#: Global attribute of every dataset the runner writes: the inputs key of the stage that made it
#: (:mod:`pipeline.runner`); equal keys, equal data.
KEY_ATTR = "inputs_key"


#: Global attribute of every dataset :func:`write_dataset` writes: JSON ``{variable: digest}``, a checksum of each
#: variable's and coordinate's values as they read back (:func:`data_checksums`), checked by :func:`read_dataset`.
CHECKSUM_ATTR = "data_checksums"


def _canonical(values: Any, fill: Any = None) -> bytes | np.ndarray | None:
    """The bytes :func:`data_checksums` hashes for one variable's values, the same for the values written
    and those :func:`read_dataset` reads back: numbers (integers, flags, floats) as little-endian float64
    with one NaN (an integer variable's declared ``_FillValue`` ``fill`` read back as NaN, as xarray decodes
    it), labels as UTF-8 strings each preceded by its length; ``None`` for values of another kind (dates,
    which hdi does not write)."""
    a = np.asarray(values)
    if a.dtype.kind in "OUS":
        items = (x.decode("utf-8", "surrogateescape") if isinstance(x, bytes) else str(x) for x in a.ravel())
        return b"".join(len(e).to_bytes(8, "little") + e for e in (t.encode("utf-8", "surrogatepass")
                                                                   for t in items))
    if a.dtype.kind not in "biuf":
        return None
    f = np.ascontiguousarray(a, dtype="<f8")
    if fill is not None and a.dtype.kind in "iu":
        f = np.where(a == np.asarray(fill).item(), np.nan, f)
    nan = np.isnan(f)
    if nan.any():  # (one NaN: the payload of a NaN is not a value)
        f = np.where(nan, np.nan, f)
    return f  # (hashed through its buffer: no copy of a float64 array)


def data_checksums(ds: xr.Dataset, encoding: Mapping[str, Mapping[str, Any]] | None = None) -> dict[str, str]:
    """``{name: SHA-256 hex digest}`` of every variable and coordinate of ``ds``: of its dimensions, shape
    and values in the canonical form of :func:`_canonical`; ``encoding``: the NetCDF encoding it is written
    with (an integer variable's ``_FillValue``)."""
    sums = {}
    for name, v in ds.variables.items():
        fill = (encoding or {}).get(str(name), {}).get("_FillValue")
        data = _canonical(v.values, fill)
        if data is None:
            continue
        h = hashlib.sha256(json.dumps([list(map(str, v.dims)), list(v.shape)]).encode())
        h.update(memoryview(data).cast("B"))
        sums[str(name)] = h.hexdigest()
    return sums


class DatasetError(ValueError):
    """A dataset on disk is missing, unreadable, or lacks what a stage needs."""


class DatasetDamaged(DatasetError):
    """A dataset whose stored values cannot be read back (a damaged chunk) or differ from the checksums
    written with them (:data:`CHECKSUM_ATTR`): damaged, or edited since hdi wrote it."""


class DatasetBusy(DatasetError):
    """Another process holds a dataset open for writing: hdi neither reads nor replaces it (the edit of
    that process would be lost)."""

    def __init__(self, path: str | Path):
        super().__init__(f"{path}: busy: another process has it open for writing (its HDF5 file lock); close it "
                         "there, or wait for that process, and run again")


def is_busy(path: str | Path) -> bool:
    """Whether another process holds the NetCDF/HDF5 file ``path`` open for writing: the HDF5 library
    (1.10 and later) holds an exclusive ``flock`` on a file it has open for writing, so a shared one
    cannot be had. ``False`` for a missing file, where ``flock`` does not exist, or when the writer's
    library does not lock (``HDF5_USE_FILE_LOCKING=FALSE``)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover (not POSIX)
        return False
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    except OSError:  # (a file system without flock: cannot tell)
        return False
    finally:
        os.close(fd)  # (releases the shared lock)
    return False


@lru_cache(maxsize=1)
def git_revision() -> str:
    """The git revision of the package source (``"unknown"`` outside a checkout)."""
    here = Path(__file__).resolve().parent
    try:
        rev = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True,
                             text=True, timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--", "."],
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return rev + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def file_hash(path: str | Path, chunk: int = 1 << 20) -> str:
    """SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            h.update(block)
    return h.hexdigest()


def check_cf(ds: xr.Dataset, where: str = "dataset") -> None:
    """Raise unless every variable and coordinate has a ``long_name`` and, unless it is a label
    (strings carry no units in CF) or names the variable holding its units (``unit_variable``),
    a ``units`` attribute."""
    missing = [name for name in list(ds.data_vars) + list(ds.coords)
               if "long_name" not in ds[name].attrs
               or ("units" not in ds[name].attrs and ds[name].dtype.kind not in "OUS"
                   and "unit_variable" not in ds[name].attrs)]
    if missing:
        raise DatasetError(f"{where}: variables without units/long_name: {missing}")


#: The paper the model implements, as CF's ``references`` attribute of every dataset (its DOI).
PAPER_REFERENCE = ("A. P. Vakis, S.-C. Lee, A. A. Polycarpou, \"Dynamic head-disk interface instabilities with "
                   "friction for light contact (surfing) recording\", IEEE Trans. Magn. 45(11) 4966-4971 (2009), "
                   "https://doi.org/10.1109/TMAG.2009.2029410")

#: Libraries whose versions can change a dataset's numbers, recorded in every dataset's provenance.
NUMERIC_LIBRARIES = ("numpy", "scipy", "numba", "xarray", "netCDF4")


@lru_cache(maxsize=1)
def software_versions() -> str:
    """``"hdi-dynamics 0.1.0; numpy 2.4.6; ..."``: this package and :data:`NUMERIC_LIBRARIES`, from their
    installed metadata (``"not installed"`` for one that is missing)."""
    found = [f"{DISTRIBUTION} {__version__}"]
    for name in NUMERIC_LIBRARIES:
        try:
            found.append(f"{name} {importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:  # pragma: no cover
            found.append(f"{name} not installed")
    return "; ".join(found)


def provenance(scene: Any = None, *, stage: str,
               inputs: Iterable[str | Path] | Mapping[str | Path, str] = ()) -> dict[str, str]:
    """Global attributes recording how a dataset was made.

    Parameters
    ----------
    scene
        The :class:`pipeline.config.scene.Scene` (or ``None``).
    stage
        The stage name (``"interface"``, ...).
    inputs
        Files read by the stage; their SHA-256 is recorded (a mapping ``{file: SHA-256}`` gives hashes
        already computed, as the runner's inputs key has them).
    """
    now = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()
    attrs = {
        "title": f"HDI pipeline: {stage}",
        "Conventions": "CF-1.8",
        "source": f"{DISTRIBUTION} {__version__}, the model of Vakis, Lee & Polycarpou, IEEE Trans. Magn. "
                  "45(11) 4966-4971, 2009",
        "references": PAPER_REFERENCE,
        "history": f"{now}: hdi {stage}" + (f" {scene.path}" if scene is not None and scene.path else ""),
        "stage": stage,
        "pipeline_version": __version__,
        "software_versions": software_versions(),
        "git_revision": git_revision(),
    }
    if scene is not None:
        attrs["scene_name"] = scene.name
        attrs["config_hash"] = scene.hash
        attrs["config"] = scene.to_toml_text()
        attrs["effects"] = " ".join(sorted(scene.effects))
        if scene.overrides:
            attrs["overrides"] = " ".join(scene.overrides)
    known = inputs if isinstance(inputs, Mapping) else {p: None for p in inputs}
    hashes = {str(p): h or file_hash(p) for p, h in known.items()}
    attrs["input_hashes"] = json.dumps(hashes, sort_keys=True)
    return attrs


def write_dataset(ds: xr.Dataset, path: str | Path, scene: Any = None, *, stage: str,
                  inputs: Iterable[str | Path] | Mapping[str | Path, str] = (),
                  extra_attrs: dict[str, Any] | None = None, compress: bool = True) -> Path:
    """Write ``ds`` to ``path`` atomically with provenance.

    Parameters
    ----------
    ds
        The dataset; every variable and coordinate must carry ``units`` and ``long_name``.
    path
        Destination ``.nc`` file; its folder is created.
    scene, stage, inputs
        See :func:`provenance`.
    extra_attrs
        More global attributes (stage-specific).
    compress
        Compress the numeric variables (:func:`cf_encoding`); false for a working file that is read back
        once and written where time counts more than space (a sweep's parts).

    Returns
    -------
    Path
        The written file.
    """
    path = refuse_links(Path(path))  # (a planted link in a results folder: not written through)
    check_cf(ds, str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    out, encoding = cf_encoding(ds, compress)
    attrs = dict(ds.attrs)
    attrs.update(provenance(scene, stage=stage, inputs=inputs))
    if extra_attrs:
        attrs.update(extra_attrs)
    attrs[CHECKSUM_ATTR] = json.dumps(data_checksums(out, encoding), sort_keys=True)
    out.attrs = {k: (json.dumps(v) if isinstance(v, (dict, list, tuple)) else v) for k, v in attrs.items()}
    fd, tmp = tempfile.mkstemp(prefix=temporary_prefix(path), suffix=".tmp", dir=path.parent)
    os.close(fd)
    os.chmod(tmp, 0o666 & ~current_umask())  # (mkstemp makes 0600; a dataset is shared like any file)
    try:
        if path.is_dir():  # (before a byte is written: os.replace would fail after the whole write)
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        with NETCDF_LOCK:
            _to_netcdf(out, tmp, encoding)
        interrupts.check()  # (a signal HDF5's callbacks swallowed: the temporary file is removed, nothing replaced)
        if is_busy(path):  # (another process's open file: replacing it would lose that process's edit)
            raise DatasetBusy(path)
        os.replace(tmp, path)
    except (OSError, RuntimeError) as exc:  # (netCDF4 says RuntimeError "NetCDF: HDF error" for a full disk)
        Path(tmp).unlink(missing_ok=True)
        raise write_failure(path, exc, int(out.nbytes)) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def move_dataset(written: str | Path, path: str | Path) -> Path:
    """Put a dataset :func:`write_dataset` wrote to ``written`` (a staging copy, on the same file system) in
    place at ``path`` by a rename, with the checks of :func:`write_dataset`: no link on the way, ``path`` not a
    folder, not held open by another process. Returns ``path``."""
    path = refuse_links(Path(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.is_dir():
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
    if is_busy(path):
        raise DatasetBusy(path)
    os.replace(written, path)
    return path


def _to_netcdf(ds: xr.Dataset, path: str, encoding: dict[str, dict[str, Any]]) -> None:
    """``ds.to_netcdf(path, engine="netcdf4", encoding=encoding)``, through the store of that engine.

    Why not ``to_netcdf`` itself: for a file path it asks dask which scheduler is active, and that
    imports ``dask.distributed`` (0.26 s of every process that writes a dataset, measured on the
    2-core machine; most ``hdi`` commands use no cluster). Opening the store with an explicit lock
    (:data:`NETCDF_LOCK`, held by the caller) skips that probe; the data are numpy arrays, written
    when stored, so the file is the same.
    """
    store = xr.backends.NetCDF4DataStore.open(path, mode="w", format="NETCDF4", lock=NETCDF_LOCK)
    try:
        ds.dump_to_store(store, encoding=encoding)
    finally:
        store.close()


def read_attrs(path: str | Path, variables: Iterable[str] = ()) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Global attributes of a NetCDF file, and the stored values of ``variables`` (those present).

    Reads the header with netCDF4 alone, without decoding the dataset into xarray: the runner checks
    the inputs key of every output and upstream dataset at every command, and the sweep every part
    (5 ms a file instead of 22 ms).

    Raises
    ------
    OSError
        When the file is missing or not NetCDF (as :class:`netCDF4.Dataset` raises it).
    """
    import netCDF4
    if is_busy(path):
        raise DatasetBusy(path)
    with NETCDF_LOCK, netCDF4.Dataset(path) as nc:
        attrs = {k: nc.getncattr(k) for k in nc.ncattrs()}
        values = {v: np.asarray(nc.variables[v][:]) for v in variables if v in nc.variables}
    interrupts.check()  # (netCDF4's error checks can swallow a signal raised during the read)
    return attrs, values


def read_dataset(path: str | Path, *, stage: str | None = None, variables: Iterable[str] = (),
                 check: bool = True) -> xr.Dataset:
    """Open a stage dataset fully into memory (the file is closed afterwards), its values checked against
    the checksums written with them (:data:`CHECKSUM_ATTR`; a dataset without them is read unchecked).

    ``check`` false reads a file that is no stage's output unchecked: a user's own dataset derived from one
    (``ds.sel(...).to_netcdf(...)`` carries the checksums of the whole dataset it came from).

    Raises
    ------
    DatasetDamaged
        When a variable cannot be read back (a damaged chunk) or its values differ from its checksum
        (damaged or edited since hdi wrote it), naming the file and the variable.
    DatasetError
        When the file is missing, not NetCDF, or lacks one of ``variables``.
    """
    path = Path(path)
    if not path.is_file():
        hint = f" (run `hdi {stage}` first)" if stage else ""
        raise DatasetError(f"{path}: dataset does not exist{looked_for(path)}{hint}")
    if is_busy(path):
        raise DatasetBusy(path)
    seen = _identity(path)
    try:
        with NETCDF_LOCK, xr.open_dataset(path, engine=ENGINE, decode_times=False, decode_timedelta=False) as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise DatasetError(f"{path}: not a readable NetCDF dataset: {exc}") from None
    except RuntimeError as exc:  # (netCDF4's "NetCDF: HDF error": a chunk that does not decompress)
        raise _damaged(path, _unreadable_variable(path), f"its data cannot be read back ({exc})", stage) from None
    interrupts.check()  # (netCDF4's error checks can swallow a signal raised during the read)
    problem = _checksum_problem(ds, seen) if check else None
    if problem is not None:
        raise _damaged(path, *problem, stage)
    if "time" in ds.variables and TIME not in ds.variables:  # (a file of the time before one name)
        ds = ds.rename({"time": TIME})
        if ds[TIME].attrs.get("units") == OLD_TIME_UNITS:
            ds[TIME].attrs["units"] = "s"
    missing = [v for v in variables if v not in ds.variables]
    if missing:
        raise DatasetError(f"{path}: missing variables {missing}")
    return ds


#: Files whose values this process found equal to their checksums, by :func:`_identity`: the runner's check of
#: a stored dataset (:func:`stored_problem`) and the stage's read of it hash it once.
_VERIFIED: set[tuple] = set()


def _identity(path: Path) -> tuple | None:
    """What identifies a file's bytes in this process: its device, inode, size, modification and change times
    (an edit or a replacement changes one of them)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return os.path.abspath(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns


def _checksum_problem(ds: xr.Dataset, seen: tuple | None) -> tuple[str, str] | None:
    """``(variable, what is wrong)`` when the values of ``ds`` (as read back) differ from the checksums
    written with them; ``None`` when they agree, or the file carries none."""
    text = ds.attrs.get(CHECKSUM_ATTR)
    if text is None or (seen is not None and seen in _VERIFIED):
        return None
    try:
        written = json.loads(text)
        if not isinstance(written, dict):
            raise ValueError
    except ValueError:
        return CHECKSUM_ATTR, "its checksums are not hdi's (not a JSON mapping of variables)"
    found = data_checksums(ds)
    for name, digest in written.items():
        if name not in found:
            return name, "missing (the dataset was written with it)"
        if found[name] != digest:
            return name, "values differ from the checksum written with them (damaged, or edited since hdi wrote it)"
    extra = sorted(set(found) - set(written))
    if extra:
        return extra[0], "not written by hdi (added since)"
    if seen is not None:
        _VERIFIED.add(seen)
    return None


def _unreadable_variable(path: Path) -> str:
    """The first variable of ``path`` whose values the HDF5 library cannot read back (``"?"``: none found)."""
    import netCDF4
    try:
        with NETCDF_LOCK, netCDF4.Dataset(path) as nc:
            for name, v in nc.variables.items():
                try:
                    v.set_auto_maskandscale(False)
                    v[...]
                except (RuntimeError, OSError, ValueError):
                    return str(name)
    except (RuntimeError, OSError, ValueError):
        pass
    return "?"


def _damaged(path: Path, variable: str, what: str, stage: str | None) -> DatasetDamaged:
    """The one line of a damaged dataset: the file, the variable, what is wrong, what to do."""
    todo = (f"run `hdi {stage}` again: it recomputes a damaged dataset of its own" if stage else
            "recompute it (run its stage again), or restore it from a copy")
    return DatasetDamaged(f"{path}: variable {variable!r}: {what}; {todo}")


def stored_problem(path: str | Path, written: str | None = None) -> str | None:
    """Why a stored dataset of a stage cannot be reused as it is (``None``: it can): unreadable, damaged or
    edited (its values differ from their checksums, :func:`read_dataset`), or written without checksums.

    ``written``: the SHA-256 of the file's bytes as hdi wrote them (the runner's record of the stage): bytes
    equal to those are the values written, so only a file whose bytes changed since (damaged, edited,
    rewritten) is read back and checked value by value, which costs a full read (~10x the hash of the file
    on ``sweep_histories.nc``: docs/datasets.md).
    """
    path = Path(path)
    seen = _identity(path)
    if seen is not None and seen in _VERIFIED:
        return None
    if written is not None and seen is not None and file_hash(path) == written:
        _VERIFIED.add(seen)
        return None
    try:
        ds = read_dataset(path)
    except DatasetBusy:
        raise
    except DatasetDamaged as exc:
        return str(exc).removeprefix(f"{path}: ").split("; ")[0]
    except DatasetError as exc:
        return str(exc).removeprefix(f"{path}: ")
    if CHECKSUM_ATTR not in ds.attrs:
        return "has no data checksums"
    return None


def results_dir(scene: Any, out: str | Path | None = None) -> Path:
    """Where a scene's stage outputs go: ``out`` or ``results/<scene name>/``."""
    return Path(out) if out is not None else Path("results") / scene.name


def var(data: Any, dims: Any, units: str, long_name: str, **attrs: Any) -> xr.Variable:
    """An ``xarray.Variable`` with its CF ``units`` (none when ``units`` is empty) and ``long_name``."""
    return xr.Variable(dims, data, attrs={**({"units": units} if units else {}), "long_name": long_name, **attrs})
