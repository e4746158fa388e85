"""Stage ``dmw``: the disk's dynamic microwaviness ``w(t)`` [nm], synthesised or measured.

Reads ``[dmw]`` of the scene (docs/model.md, section "DMW") and writes ``dmw.nc``:

=================  ===============  =========  ====================================================
name               dims             units      meaning
=================  ===============  =========  ====================================================
``time``           time             s          sample times ``i / fs`` (coordinate)
``displacement``   time             nm         DMW ``w(t)``, zero mean
``frequency``      frequency        Hz         periodogram frequencies, ``k / duration`` (coordinate)
``psd``            frequency        nm2 Hz-1   one-sided periodogram of ``displacement``
``rms``            --               nm         rms of ``displacement`` (measured: as found)
``band_low``       --               Hz         band lower edge (``dmw.band_khz[0]``)
``band_high``      --               Hz         band upper edge (``dmw.band_khz[1]``)
``sample_rate``    --               Hz         ``fs`` (``dmw.sample_rate_mhz``)
``disk_speed``     --               m s-1      ``V = 2 pi r rpm / 60`` (19.49 m/s in the paper scene)
=================  ===============  =========  ====================================================

``band_low``/``band_high`` carry the realised edges (the first/last frequency bin inside the band)
as the attribute ``realised``. Global attributes record the provenance: ``dmw_source``
(``"synthetic"`` or the record's path), ``dmw_quantity``, ``processing`` (the steps applied, in
order), ``exponent`` and ``amplitudes`` (synthetic), the record's own sample rate, column, units,
rms and fitted spectral exponent (measured), ``periodic`` and ``dmw_enabled``; plus the usual
provenance of :func:`pipeline.io.write_dataset` (seed for a synthetic record, the record's hash for
a measured one).

Record length: ``dmw.duration_ms`` when given; otherwise ``solver.duration_ms`` plus the disk's
travel time over the slider (the dynamics reads the record ahead of ``t`` for the front pad), rounded
up to whole periods of the band's lower edge: 2.1 ms (8400 samples) in the paper scene
(:func:`~pipeline.model.dmw_record.default_duration`); a measured record shorter than that is used whole.
Whatever its length, a record must hold what the simulation reads (:func:`~pipeline.model.dmw_record.needed_samples`:
the simulated duration, the front pad's lead and 3 samples, 8151 samples for the paper scene's 2 ms),
checked here before anything is written, in the one message of :func:`~pipeline.model.dmw_record.check_length`.
The formats of a measured record: docs/my-drive.md, section "The DMW record".

Synthetic: :func:`pipeline.physics.microwaviness.synthesize` with ``rms_nm``, ``band_khz``, ``exponent``,
``seed``, ``sample_rate_mhz`` and that duration.

Measured (``source`` a path): :func:`~pipeline.model.measured_dmw.load_record`, then the paper's processing
at the record's own rate (velocity integrated, :func:`~pipeline.physics.microwaviness.velocity_to_displacement`;
displacement detrended, :func:`~pipeline.physics.microwaviness.process_displacement`; both band-passed to
``band_khz``), resampled to ``sample_rate_mhz`` (:func:`~pipeline.physics.microwaviness.resample`) and cut to
the first ``duration_ms``. A measured record is never rescaled: ``rms_nm`` is ignored and the
record's own rms is written (and a warning logged when it differs from ``rms_nm`` by more than 2x).
The record is validated before anything is written, so a bad record never replaces an existing
``dmw.nc``.

Effect switched off (``"dmw"`` not in ``scene.effects``): the stage writes ``dmw.nc`` with zero
displacement (``rms = 0``, ``dmw_enabled = 0``, attribute ``disabled``), reading no record and
drawing no random numbers. A downstream stage that reads it therefore gets exactly "no DMW" even if
it forgets to check the effect, and a scene with the effect off never needs a record file.

Up to date (:mod:`pipeline.runner`): the stage reads ``[dmw]``, ``solver.duration_ms``, the effects,
the slider's length, front arm and TFC position (the default record length, the length a record must
have) and the bytes of a measured record;
``dmw.nc`` is recomputed only when one of them changed (``force=True`` recomputes).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import xarray as xr

from ..model import dmw_record
from ..model.dmw_record import FILENAME, check_length, front_pad_lead_s, settings, synthetic_record
from ..model.measured_dmw import load_record
from ..physics import microwaviness as phys
from ..runner import Inputs, Stage
from ..units import MS
from ..variables import DMW, TIME, coordinate

log = logging.getLogger(__name__)


def _measured(s: dict[str, Any], need: tuple[float, float]) -> tuple[np.ndarray, dict[str, Any]]:
    """Load, process, resample and cut a measured record; raise before anything is written.

    ``need``: ``(simulated duration, front-pad lead)`` [s], the record's length rule
    (:func:`pipeline.model.dmw_record.check_length`), checked at the record's own rate and after resampling.
    """
    fs, (lo, hi), dur = s["sample_rate_hz"], s["band_hz"], s["duration_s"]
    rec = load_record(s["source"], s["quantity"], s["column"], s["record_rate_hz"], unit=s["unit"],
                      min_duration_s=dur if s["duration_set"] else None)
    where = f"{rec.path}: {rec.field}"
    check_length(rec.values.size, rec.sample_rate_hz, *need, where)
    if hi > rec.sample_rate_hz / 2:
        raise phys.DMWError(f"{where}: sampled at {rec.sample_rate_hz:g} Hz, whose Nyquist frequency is "
                            f"below the band's upper edge {hi:g} Hz (dmw.band_khz); expected a record "
                            f"sampled at > {2 * hi:g} Hz")
    steps = []
    if rec.quantity == "velocity":
        x = phys.velocity_to_displacement(rec.values, rec.sample_rate_hz, lo, hi)
        steps.append(f"FFT band-pass [{lo:g}, {hi:g}] Hz (zero-phase brick-wall) with spectral "
                     f"integration of velocity to displacement (mean velocity and drift removed)")
    else:
        x = phys.process_displacement(rec.values, rec.sample_rate_hz, lo, hi)
        steps.append("linear detrend")
        steps.append(f"FFT band-pass [{lo:g}, {hi:g}] Hz (zero-phase brick-wall)")
    x, how = phys.resample(x, rec.sample_rate_hz, fs)
    if how != "none":
        steps.append(f"resampled {rec.sample_rate_hz:g} -> {fs:g} Hz by {how}")
    check_length(x.size, fs, *need, f"{where} (resampled to {fs:g} Hz)")
    n = phys.n_samples(dur, fs)
    if not s["duration_set"]:  # (the default length, or the whole record when it is shorter and long enough)
        n = min(n, x.size)
    elif x.size < n:  # resampling may lose the last sample or two of a record just long enough
        raise phys.DMWError(f"{where}: after resampling to {fs:g} Hz the record has {x.size} samples; "
                            f"expected at least {n} for dmw.duration_ms = {dur / MS:g}")
    if x.size > n:
        steps.append(f"first {n} samples kept (of {x.size})")
    x = x[:n]
    f, p = phys.spectrum(x, fs)
    try:
        expo = phys.power_law_fit(f, p, (lo, hi))[0]
    except ValueError:
        expo = float("nan")
    attrs = {
        "dmw_quantity": rec.quantity,
        "processing": "; ".join(steps),
        "record_column": rec.column,
        "record_units": rec.units,
        "record_sample_rate_hz": rec.sample_rate_hz,
        "record_samples": int(rec.values.size),
        "record_rms_nm": float(np.sqrt(np.mean(x * x))),
        "record_fitted_exponent": expo,
        "record_notes": "; ".join(rec.notes) if rec.notes else "none",
        "rescaled": "no (a measured record is never rescaled; dmw.rms_nm is not used)",
        "periodic": "no (a measured record is not assumed periodic)",
    }
    rms = attrs["record_rms_nm"]
    if s["rms_nm"] > 0 and not (0.5 <= rms / s["rms_nm"] <= 2.0):
        log.warning("dmw: %s: measured DMW rms %.3g nm differs from dmw.rms_nm = %.3g nm; the record is used "
                    "as measured (check its units)", rec.path, rms, s["rms_nm"])
    return x, attrs


def _files(scene: Any) -> dict[str, str]:
    """The measured record, when the stage reads one (effect on, ``source`` a path)."""
    if "dmw" not in scene.effects or scene["dmw"]["source"] == "synthetic":
        return {}
    return {"dmw.source": settings(scene)["source"]}


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``dmw.nc`` dataset of the scene (see the module docstring).

    Raises
    ------
    pipeline.physics.microwaviness.DMWError
        For an unusable measured record (nothing is written then).
    """
    s = settings(scene)
    fs, (lo, hi), dur = s["sample_rate_hz"], s["band_hz"], s["duration_s"]
    n = phys.n_samples(dur, fs)
    seed = None
    enabled = "dmw" in scene.effects
    need = (float(scene.si.solver.duration), front_pad_lead_s(scene))
    if enabled and s["duration_set"]:  # (a record of the length asked for: long enough for the simulation?)
        check_length(n, fs, *need, f"dmw.duration_ms = {scene['dmw']['duration_ms']:g}",
                     "set dmw.duration_ms to at least that, or leave it out (the default length is enough)")
    if not enabled:
        w = np.zeros(n)
        attrs = {"dmw_quantity": "displacement", "processing": "none (effect off)",
                 "disabled": "dmw effect not in scene: zero displacement, no record read",
                 "periodic": "yes"}
        source = "none"
    elif s["source"] == "synthetic":
        seed = s["seed"]
        w = synthetic_record(s)
        attrs = {"dmw_quantity": "displacement",
                 "processing": "spectral synthesis (pipeline.physics.microwaviness.synthesize): complex-normal "
                               "rfft coefficients, power-law amplitudes in the band, zero outside, "
                               "rescaled to rms_nm",
                 "exponent": s["exponent"], "amplitudes": "gaussian", "synthesis_rms_nm": s["rms_nm"],
                 "periodic": f"yes (period {dur:g} s = the record length)"}
        source = "synthetic"
    else:
        w, attrs = _measured(s, need)
        source = s["source"]
        n, dur = w.size, w.size / fs
    time = np.arange(n) / fs
    f, p = phys.spectrum(w, fs)
    try:
        k_lo, k_hi = phys.band_bins(n, fs, (lo, hi))
        realised = [k_lo * fs / n, k_hi * fs / n]
    except ValueError:
        realised = [float("nan"), float("nan")]
    rms = float(np.sqrt(np.mean(w * w)))
    ds = xr.Dataset(
        {
            "displacement": DMW["displacement"].data(w, (TIME,)),
            "psd": DMW["psd"].data(p, ("frequency",),
                                   method="periodogram, rectangular window, no detrend (scipy.signal.periodogram)"),
            "rms": DMW["rms"].data(rms, ()),
            "band_low": DMW["band_low"].data(lo, (), realised=realised[0]),
            "band_high": DMW["band_high"].data(hi, (), realised=realised[1]),
            "sample_rate": DMW["sample_rate"].data(fs, ()),
            "disk_speed": DMW["disk_speed"].data(s["disk_speed_m_s"], (), formula="2 pi radius rpm / 60"),
        },
        coords={TIME: coordinate(TIME, time), "frequency": DMW["frequency"].data(f, ("frequency",))},
    )
    ds.attrs.update({"dmw_source": source, "dmw_enabled": int(enabled), "duration_s": dur, **attrs})
    if seed is not None:
        ds.attrs["seed"] = int(seed)
    return ds


STAGE = Stage(
    "dmw", compute, outputs=(FILENAME,),
    reads=dmw_record.FIELDS,
    files=_files, order=20, main_job=True,
    doc="the disk's dynamic microwaviness, synthesised or measured, dmw.nc")
