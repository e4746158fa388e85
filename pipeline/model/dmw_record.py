"""The disk's dynamic microwaviness (DMW) record of a scene, in memory: settings, synthesis, reading.

:func:`settings` is the ``[dmw]`` section in SI units with its defaults resolved; :func:`synthetic_record`
the seeded synthetic record it describes (docs/model.md, section "DMW"); :func:`load` reads a ``dmw.nc``
back for the dynamics. The dmw stage writes the record; the sweep's ensembles, the parameter studies
and the accuracy stage make candidates' records with the same functions.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ..config.fields import fields
from ..physics import microwaviness as phys
from ..units import MM, MS
from ..variables import TIME

FILENAME = "dmw.nc"

#: The scene keys of the record (:func:`settings`; the default record length depends on the slider's size,
#: :func:`default_duration`, the length a record must have on where the TFC point lies, :func:`front_pad_lead_s`).
FIELDS = fields("dmw.*", "solver.duration_ms", "scene.effects", "slider.length_mm", "slider.front_arm_mm",
                "slider.tfc_from_trailing_edge_um")


def synthetic_record(s: dict[str, Any]) -> np.ndarray:
    """The synthetic displacement record [nm] of :func:`settings` ``s`` (``source = "synthetic"``):
    :func:`pipeline.physics.microwaviness.synthesize` of its rms, band, exponent, duration, rate and seed."""
    return phys.synthesize(s["rms_nm"], tuple(s["band_hz"]), s["exponent"], s["duration_s"], s["sample_rate_hz"],
                           s["seed"])


def disk_speed_m_s(dmw: dict[str, Any]) -> float:
    """Disk speed [m/s] under the slider, ``V = 2 pi r rpm / 60``, from ``[dmw] radius_mm`` and ``rpm``
    (docs/model.md, section "DMW": 19.49 m/s in the paper scene). The one home of this rule."""
    return 2.0 * math.pi * float(dmw["radius_mm"]) * MM * float(dmw["rpm"]) / 60.0


def settings(scene: Any) -> dict[str, Any]:
    """The stage's settings in SI units, with defaults resolved.

    Returns
    -------
    dict with ``source`` (``"synthetic"`` or an absolute path), ``quantity``, ``column``,
    ``rms_nm`` [nm], ``band_hz`` (lo, hi) [Hz], ``exponent`` [1], ``seed``, ``sample_rate_hz`` [Hz],
    ``duration_s`` [s] (``duration_set``: whether ``dmw.duration_ms`` gives it), ``record_rate_hz`` [Hz] or
    ``None``, ``unit`` (``dmw.unit``: of a measured record that states none) or ``None``, ``disk_speed_m_s`` [m/s].
    """
    d = scene["dmw"]
    si = scene.si
    band_hz = tuple(float(f) for f in si.dmw.band)
    speed = disk_speed_m_s(d)
    if d["duration_ms"] is not None:
        duration_s = float(si.dmw.duration)
    else:
        duration_s = default_duration(si.solver.duration, scene["slider"], speed, band_hz[0],
                                      float(si.dmw.sample_rate))
    source = d["source"]
    if source != "synthetic":
        p = Path(source).expanduser()
        if not p.is_absolute() and getattr(scene, "path", None) is not None:
            p = Path(scene.path).parent / p
        source = str(p)
    return {
        "source": source,
        "quantity": d["quantity"],
        "column": d["column"],
        "rms_nm": float(d["rms_nm"]),
        "band_hz": band_hz,
        "exponent": float(d["exponent"]),
        "seed": int(d["seed"]),
        "sample_rate_hz": float(si.dmw.sample_rate),
        "duration_s": duration_s,
        "record_rate_hz": d["sample_rate_hz"],
        "unit": d["unit"],
        "duration_set": d["duration_ms"] is not None,
        "disk_speed_m_s": speed,
    }


def default_duration(sim_duration_s: float, slider: dict[str, Any], disk_speed_m_s: float,
                     band_low_hz: float, sample_rate_hz: float) -> float:
    """Record length [s] when ``dmw.duration_ms`` is not given.

    The dynamics reads the record at ``t`` plus the disk's travel time from the front pad to the
    TFC point (``pipeline.model.assembly.build_model`` requires ``duration + (l_f + l_c)/V + 2/fs``). This
    takes the simulated duration plus ``(front_arm + length)/V`` (an upper bound of that delay,
    since the TFC point is less than a slider length behind the centre of gravity) plus 4 samples,
    rounded up to a whole number of periods ``1/band_low`` so that the band's lower edge, where a
    red spectrum has most of its energy, is a frequency bin of the record (2 ms -> 2.1 ms in the
    paper scene: 8400 samples, resolution 476.2 Hz, edges 10 kHz = bin 21 and 500 kHz = bin 1050).
    """
    margin = (slider["front_arm_mm"] + slider["length_mm"]) * MM / disk_speed_m_s + 4.0 / sample_rate_hz
    need = sim_duration_s + margin
    if band_low_hz <= 0:
        return math.ceil(need * sample_rate_hz) / sample_rate_hz
    return math.ceil(need * band_low_hz * (1 - 1e-12)) / band_low_hz


def front_pad_lead_s(scene: Any) -> float:
    """How long before the TFC point the front pad sees a point of the disk [s]: ``(l_f + l_c) / V``, the
    front arm plus the TFC point's arm behind the CG (``slider.length_mm / 2 -
    slider.tfc_from_trailing_edge_um``) over the disk speed (:func:`disk_speed_m_s`; 0.0368 ms in the paper
    scene). The dynamics reads the record that far ahead of ``t`` (:func:`pipeline.model.assembly.disk_record`)."""
    ss = scene.si.slider
    return (ss.front_arm + (ss.length / 2 - ss.tfc_from_trailing_edge)) / disk_speed_m_s(scene["dmw"])


#: Samples a record needs beyond ``t = duration + lead``: the last sample at least two sampling intervals
#: past it (the spline of the record's samples is evaluated up to there, :func:`needed_samples`).
END_SAMPLES = 3


def needed_samples(duration_s: float, lead_s: float, sample_rate_hz: float) -> int:
    """The fewest samples [1] a DMW record at ``sample_rate_hz`` [Hz] must hold for a simulation of
    ``duration_s`` [s] whose front pad reads ``lead_s`` [s] ahead (:func:`front_pad_lead_s`): its last sample,
    at ``(n - 1) / fs``, at least ``duration + lead + 2 / fs``. The one rule of a record's length: the dmw stage
    checks a record with it before writing ``dmw.nc``, the model before it runs one (:func:`check_length`)."""
    return math.ceil((duration_s + max(lead_s, 0.0)) * sample_rate_hz * (1 - 1e-12)) + END_SAMPLES


def check_length(samples: int, sample_rate_hz: float, duration_s: float, lead_s: float, where: str,
                 remedy: str = "give a longer record") -> None:
    """Refuse a DMW record of ``samples`` at ``sample_rate_hz`` [Hz] shorter than :func:`needed_samples`, in
    one line: ``where`` (the file and what holds the record), its length, the length needed and how it is
    made up, and what to change (``remedy``, or a shorter ``solver.duration_ms``).

    Raises
    ------
    pipeline.physics.microwaviness.DMWError
        The record is too short.
    """
    need = needed_samples(duration_s, lead_s, sample_rate_hz)
    if samples >= need:
        return
    longest = (samples - END_SAMPLES) / sample_rate_hz - max(lead_s, 0.0)
    raise phys.DMWError(
        f"{where}: {samples} samples at {sample_rate_hz:.6g} Hz ({samples / sample_rate_hz / MS:.6g} ms); the "
        f"simulation needs at least {need} ({need / sample_rate_hz / MS:.6g} ms): solver.duration_ms = "
        f"{duration_s / MS:g} plus {max(lead_s, 0.0) / MS:.4g} ms, the disk's travel from the front pad to the TFC "
        f"point, plus {END_SAMPLES} samples; {remedy}"
        + (f", or solver.duration_ms <= {math.floor(longest / MS * 1e4) / 1e4:g}" if longest > 0 else ""))


def load(path: str | Path) -> tuple[np.ndarray, np.ndarray, float]:
    """Read a ``dmw.nc`` back for the dynamics.

    Parameters
    ----------
    path : ``dmw.nc`` or the folder holding it

    Returns
    -------
    time_s : [s]
    displacement_nm : [nm]
    sample_rate_hz : [Hz]
    """
    path = Path(path)
    if path.is_dir():
        path = path / FILENAME
    from ..io import read_dataset  # (here: xarray, pipeline.model.ahead.NOT_IMPORTED_EARLY)
    return from_dataset(read_dataset(path, stage="dmw", variables=VARIABLES))


#: The variables of ``dmw.nc`` the dynamics reads.
VARIABLES = ("displacement", TIME, "sample_rate")


def from_dataset(ds: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """``(time [s], displacement [nm], sample rate [Hz])`` of a ``dmw.nc`` dataset in memory."""
    return (np.asarray(ds[TIME].values, dtype=float), np.asarray(ds["displacement"].values, dtype=float),
            float(ds["sample_rate"].values))


def realisation_seeds(seed: int, n: int) -> list[int]:
    """Seeds [1] of ``n`` DMW realisations (``[sweep] realisations``): the scene's own first.

    Realisation 0 is the scene's record (``dmw.seed``), so one realisation is today's sweep; realisation
    ``r >= 1`` is seeded from ``numpy.random.SeedSequence(seed).spawn(n - 1)[r - 1]`` (its first 32-bit
    word), independent streams by construction. A child depends only on its index, so the first ``m``
    realisations of ``n`` are those of ``m`` (ensembles nest).
    """
    if n < 1:
        raise ValueError(f"realisations = {n}: expected an integer >= 1")
    children = np.random.SeedSequence(seed).spawn(n - 1)
    return [int(seed)] + [int(c.generate_state(1, np.uint32)[0]) for c in children]
