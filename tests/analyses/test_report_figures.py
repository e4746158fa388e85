"""Which of the report's figures are drawn from which data (pipeline/analyses/report_figures.py), on hand-made
datasets: with only a sweep, the FHM figure is drawn and every other figure is named with the reason it is
not; the history figures show the protrusions asked for that the sweep kept (else every kept one) and at most
four panels; a history slice is the combination's at the nearest protrusion."""

from __future__ import annotations

import numpy as np
import xarray as xr

from pipeline.analyses import plots, report_figures as rf
from pipeline.analyses.report_settings import ReportSettings
from pipeline.analyses.sweep_slices import combinations

X = np.array([9.0, 9.2, 9.4])


def _sweep() -> xr.Dataset:
    return xr.Dataset({"fhm_bv": ("protrusion", [1.0, 2.0, 8.0], {"units": "%"}),
                       "regime": ("protrusion", [0, 0, 2])}, coords={"protrusion": X}, attrs={"k": 0.978})


def _histories(prots) -> xr.Dataset:
    t = np.arange(5) * 250e-9
    clearance = np.add.outer(np.asarray(prots, float), t * 0.0)          # each protrusion's own value
    return xr.Dataset({"clearance": (("protrusion", "elapsed_time"), clearance, {"units": "nm"})},
                      coords={"protrusion": list(prots), "elapsed_time": t})


def _data(**given) -> dict:
    names = ("sweep", "ensemble", "sweep_histories", "calibration", "roughness", "dmw", "interface", "bulge")
    return {**{n: None for n in names}, "sweep": _sweep(), **given}


def test_with_only_a_sweep_the_fhm_figure_is_drawn_and_the_others_say_why_not(tmp_path):
    jobs, skipped = rf.figure_jobs(_data(), combinations(_sweep()), ReportSettings(), "scene", tmp_path)
    assert [(f, args[2]) for f, args, _ in jobs] == [(plots.fig_fhm, tmp_path / "fig6_fhm.png")]
    assert jobs[0][2]["first_contact"] == 9.4 and jobs[0][2]["touchdown_nm"] == 9.8
    assert set(skipped) == {"fig3_clearance.png", "fig4_forces.png", "fig5_stresses.png", "fig7_shear.png",
                            "calibration.png", "roughness.png", "dmw.png"}
    assert skipped["dmw.png"] == "dmw.nc is absent (`hdi dmw` not run)"
    assert skipped["fig7_shear.png"] == "sweep.nc has no shear_stress (friction/contact effects off)"


def test_the_histories_figures_show_the_kept_protrusions_asked_for_in_at_most_four_panels(tmp_path):
    hist = _histories([5.0, 9.0, 9.2, 9.4, 11.0])
    assert rf.history_protrusions(hist, [11.0, 5.0, 7.0]) == [5.0, 11.0]       # 7 nm was not kept
    assert rf.history_protrusions(hist, [7.0]) == [5.0, 9.0, 9.2, 9.4, 11.0]    # none kept: every one
    jobs, skipped = rf.figure_jobs(_data(sweep_histories=hist), combinations(_sweep()),
                                   ReportSettings(histories_nm=[]), "scene", tmp_path)
    clearance = next(args for f, args, _ in jobs if f is plots.fig_clearance)
    panels = clearance[0]
    assert [p for p, _, _ in panels] == [5.0, 9.0, 9.2, 11.0]                  # lowest, two between, highest
    assert [regime for _, _, regime in panels] == [None, 0, 0, None]            # on the sweep's grid or not
    assert float(panels[-1][1]["clearance"][0]) == 11.0
    # no forces or stresses in these histories: said so
    assert "no forces" in skipped["fig4_forces.png"] and "no stresses" in skipped["fig5_stresses.png"]


def test_a_history_slice_is_the_combinations_at_the_nearest_protrusion():
    hist = xr.concat([_histories(X), _histories(X) + 100.0],
                     dim=xr.DataArray([0.02, 0.05], dims="damping", name="damping"))
    h = rf.history_slice(hist, {"roughness": None, "damping": 0.049}, 9.25)
    assert h["clearance"].dims == ("elapsed_time",)
    np.testing.assert_array_equal(h["clearance"].values, 109.2)                # damping 0.05, 9.2 nm
