"""Which of the report's figures to draw, from which data (no drawing here: :mod:`pipeline.analyses.plots` draws).

:func:`figure_jobs` turns the loaded datasets into drawing jobs ``(figure function, arguments,
keywords)`` for :func:`pipeline.analyses.plots.draw_all`, and names each figure it cannot draw with the reason
(a missing optional dataset, an effect that is off); :func:`draw` draws the jobs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np
import xarray as xr

from . import plots
from ..physics import paper
from ..variables import TIME
from .report_settings import ReportSettings
from .sweep_slices import TOL, attr_float, first_contact, regime_at, scalar

FIGURES = ("fig3_clearance.png", "fig4_forces.png", "fig5_stresses.png", "fig6_fhm.png", "fig7_shear.png",
           "calibration.png", "roughness.png", "dmw.png")
#: Drawn only for a sweep with several DMW realisations (``[sweep] realisations > 1``).
ENSEMBLE_FIGURE = "ensemble.png"
#: Drawn only with the paper's checks over DMW realisations (``ensemble.nc``, ``report.realisations > 1``).
BAND_FIGURE = "band.png"
#: Drawn only when the scene's bulge law is tabulated (``bulge.nc``: ``air_bearing.bulge = "reynolds"`` or
#: ``"rough-reynolds"``).
BULGE_FIGURE = "bulge.png"
#: Drawn only when interface.nc holds both interface models (``interface.model = "deterministic"``).
INTERFACE_FIGURE = "interface_models.png"

#: Drawn with the statics map (``statics.nc``, the ``statics`` stage).
STATICS_FIGURE = "statics.png"

#: One drawing job: figure function, positional arguments, keyword arguments.
Job = tuple[Callable[..., Any], tuple, dict]


def history_slice(hist: xr.Dataset, labels: dict[str, Any], delta: float) -> xr.Dataset:
    """The time histories of one combination (``labels``) at the protrusion nearest ``delta`` [nm]."""
    sel: dict[str, Any] = {}
    if "roughness" in hist.dims and labels["roughness"] is not None:
        sel["roughness"] = labels["roughness"]
    if "damping" in hist.dims and labels["damping"] is not None:
        sel["damping"] = hist["damping"].values[np.argmin(np.abs(hist["damping"].values - labels["damping"]))]
    h = hist.sel(sel) if sel else hist
    j = int(np.argmin(np.abs(h["protrusion"].values - delta)))
    h = h.isel(protrusion=j)
    for d in [d for d in h.dims if d != TIME]:
        h = h.isel({d: 0})
    return h


def history_protrusions(hist: xr.Dataset, wanted: list[float]) -> list[float]:
    """Protrusions [nm] of the histories to show: those of ``wanted`` present, else all."""
    have = np.sort(np.asarray(hist["protrusion"].values, float))
    chosen = [float(h) for h in have if any(abs(h - w) < TOL for w in wanted)]
    return chosen or [float(h) for h in have]


def figure_jobs(data: dict[str, xr.Dataset | None], combos: list, settings: ReportSettings, name: str,
                figdir: Path) -> tuple[list[Job], dict[str, str]]:
    """The drawing jobs of every figure whose inputs exist (paths under ``figdir``), and the skipped
    figures' reasons.

    ``data`` holds the datasets by name (``sweep``, ``ensemble``, ``sweep_histories``, ``calibration``,
    ``roughness``, ``dmw``, ``interface``, ``bulge``; ``None`` when absent); ``combos`` the sweep's slices, the
    default first.
    """
    jobs: list[Job] = []
    skipped: dict[str, str] = {}
    ds0 = combos[0][1]
    onset, previous = settings.onset_nm, settings.previous_nm

    _history_jobs(data["sweep_histories"], combos, settings, name, figdir, jobs, skipped)

    fc = first_contact(ds0)
    jobs.append((plots.fig_fhm, (combos, name, figdir / "fig6_fhm.png"),
                 dict(touchdown_nm=onset, previous_nm=previous, limit=paper.STABLE_FHM_PERCENT, first_contact=fc)))
    if "shear_stress" in ds0:
        tau_y = scalar(data["interface"], "shear_strength")
        jobs.append((plots.fig_shear, (combos, name, figdir / "fig7_shear.png"),
                     dict(touchdown_nm=onset, shear_strength=tau_y if np.isfinite(tau_y) else None)))
    else:
        skipped["fig7_shear.png"] = "sweep.nc has no shear_stress (friction/contact effects off)"

    cal = data["calibration"]
    if cal is None:
        skipped["calibration.png"] = "calibration.nc is absent (k fixed by the scene, or `hdi calibrate` not run)"
    else:
        k_used = attr_float(data["sweep"], "k")
        jobs.append((plots.fig_calibration, (cal, name, figdir / "calibration.png"),
                     dict(onset_nm=float(cal.attrs.get("touchdown_onset_nm", onset)),
                          previous_nm=float(cal.attrs.get("touchdown_previous_nm", previous)),
                          k_used=k_used if np.isfinite(k_used) else None,
                          k_source=str(data["sweep"].attrs.get("k_source", "")))))
    if data["roughness"] is None:
        skipped["roughness.png"] = "roughness.nc is absent (`hdi roughness` not run)"
    else:
        jobs.append((plots.fig_roughness, (data["roughness"], name, figdir / "roughness.png", data["interface"]), {}))
    if data["dmw"] is None:
        skipped["dmw.png"] = "dmw.nc is absent (`hdi dmw` not run)"
    else:
        jobs.append((plots.fig_dmw, (data["dmw"], name, figdir / "dmw.png"), {}))
    if data.get("ensemble") is not None:
        jobs.append((plots.fig_ensemble, (data["ensemble"], name, figdir / ENSEMBLE_FIGURE),
                     dict(touchdown_nm=onset, previous_nm=previous)))
    checks = data.get("checks")
    if checks is not None and "value_bouncing" in checks and "bouncing_bv_median" in checks:
        jobs.append((plots.fig_band, (checks, name, figdir / BAND_FIGURE),
                     dict(band_nm=tuple(np.atleast_1d(checks["value_bouncing"].attrs["protrusions_nm"])),
                          threshold=float(checks["bv_exceedance_probability"].attrs["threshold_percent"]),
                          touchdown_nm=onset, previous_nm=previous)))
    if data.get("bulge") is not None:
        jobs.append((plots.fig_bulge, (data["bulge"], name, figdir / BULGE_FIGURE),
                     dict(cap_nm=settings.lift_cap_nm)))
    if data.get("statics") is not None:
        jobs.append((plots.fig_statics, (data["statics"], name, figdir / STATICS_FIGURE), {}))
    if data["interface"] is not None and "model" in data["interface"].dims:  # interface.model = "deterministic"
        jobs.append((plots.fig_interface_models, (data["interface"], name, figdir / INTERFACE_FIGURE), {}))
    return jobs, skipped


def _history_jobs(hist: xr.Dataset | None, combos: list, settings: ReportSettings, name: str, figdir: Path,
                  jobs: list[Job], skipped: dict[str, str]) -> None:
    """The jobs of the figures of the kept time histories (the paper's Figs. 3-5: clearance, forces, stresses),
    appended to ``jobs``, or the reasons they are skipped in ``skipped``."""
    labels0, ds0 = combos[0]
    transient = settings.transient_ms
    if hist is None:
        for f in FIGURES[:3]:
            skipped[f] = "sweep_histories.nc is absent (no time histories were kept by the sweep)"
    else:
        prots = history_protrusions(hist, settings.histories_nm)
        high = prots[-1]
        # every kept protrusion (the paper's Fig. 3: flying and light contact, and a step of the band when
        # report.histories_nm names one), at most four panels: the lowest, the highest and two between
        shown = prots if len(prots) <= 4 else [prots[0], *prots[1:-1][:2], prots[-1]]
        panels = [(p, history_slice(hist, labels0, p), regime_at(ds0, p)) for p in dict.fromkeys(shown)]
        jobs.append((plots.fig_clearance, (panels, name, figdir / "fig3_clearance.png", transient), {}))
        h_high = panels[-1][1]
        if any(v in h_high for v, _, _ in plots.FORCES):
            jobs.append((plots.fig_forces, (h_high, high, name, figdir / "fig4_forces.png", transient), {}))
        else:
            skipped["fig4_forces.png"] = "the histories hold no forces (contact/adhesion effects off)"
        if any(v in h_high for v, _ in plots.STRESSES):
            jobs.append((plots.fig_stresses, (h_high, high, name, figdir / "fig5_stresses.png", transient), {}))
        else:
            skipped["fig5_stresses.png"] = "the histories hold no stresses (contact effect off)"


def draw(jobs: list[Job]) -> list[Path]:
    """Draw the jobs (:func:`pipeline.analyses.plots.draw_all`, in parallel processes); the written paths, in job order."""
    # the slowest figure (the log-log spectrum: ~1 s) first, so the pool's workers finish together
    order = sorted(range(len(jobs)), key=lambda i: jobs[i][0] is not plots.fig_dmw)
    paths = plots.draw_all([jobs[i] for i in order])
    return [p for _, p in sorted(zip(order, paths))]
