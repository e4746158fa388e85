"""Stage ``report`` on small synthetic datasets written with pipeline.io.write_dataset."""

from __future__ import annotations

import os

import numpy as np
import pytest
import xarray as xr

from pipeline.io import DatasetError, write_dataset
from pipeline.runner import Inputs
from pipeline.stages import report

from report_data import (PROT, check_png, read_csv, slice_values, write_calibration, write_dmw, write_histories,
                         write_roughness, write_sweep)


def render(scene, out):
    """The report of the hand-made datasets in ``out``, written straight into it (the stage's compute:
    through the runner, the datasets would first be made current for the scene, i.e. recomputed)."""
    report.compute(scene, Inputs.folder(out))
    return out / "figures"

@pytest.fixture()
def full_out(tmp_path):
    write_sweep(tmp_path)
    write_histories(tmp_path)
    write_calibration(tmp_path)
    write_dmw(tmp_path)
    write_roughness(tmp_path)
    return tmp_path


def test_every_figure_is_a_real_png(full_out, paper_scene):
    import matplotlib.pyplot as plt
    before = plt.get_fignums()
    figdir = render(paper_scene, full_out)
    assert figdir == full_out / "figures"
    for name in report.FIGURES:
        check_png(figdir / name)
    assert plt.get_fignums() == before, "the report stage must not leave pyplot figures open"
    assert not list(figdir.glob(".*.tmp"))


def test_summary_csv_rows_columns_and_values(full_out, paper_scene):
    render(paper_scene, full_out)
    header, rows = read_csv(full_out / "report" / "summary.csv")
    assert header[:4] == ["roughness", "damping [1]", "protrusion [nm]", "regime"]
    for col in ("clearance [nm]", "FHM/BV [%]", "interference [nm]", "mean pressure [MPa]",
                "shear stress [MPa]", "friction coefficient [1]"):
        assert col in header
    # from 2 nm before the first contact (3 nm) to the end: 1.0, 1.5, ..., 6.0
    prot = [float(r[2]) for r in rows]
    assert prot == pytest.approx(list(np.arange(1.0, 6.01, 0.5)))
    ref = slice_values()
    byname = {h: i for i, h in enumerate(header)}
    for r in rows:
        j = int(np.argmin(np.abs(PROT - float(r[2]))))
        assert r[0] == "scene" and float(r[1]) == pytest.approx(0.05)
        assert r[3] == {0: "flying", 1: "bouncing", 2: "surfing"}[int(ref["regime"][j])]
        assert float(r[byname["clearance [nm]"]]) == pytest.approx(ref["clearance"][j], rel=1e-5)
        assert float(r[byname["FHM/BV [%]"]]) == pytest.approx(ref["fhm_bv"][j], rel=1e-5)
        cell = r[byname["mean pressure [MPa]"]]
        if ref["regime"][j] == 0:
            assert cell == ""                           # undefined while flying: empty, not 0
        else:
            assert float(cell) == pytest.approx(ref["mean_pressure"][j], rel=1e-5)


def test_summary_and_comparison_text(full_out, paper_scene):
    render(paper_scene, full_out)
    md = (full_out / "report" / "summary.md").read_text()
    assert "First contact at 3 nm." in md
    # optimum (a): flying with FHM < 10 %: 0 nm (9 %), 0.5 nm (9.25 %), ..., 1.5 nm (9.75 %); least clearance
    # -> 1.5 nm; optimum (b): surfing with BV < 2 %: least interference at 4 nm
    assert "before touchdown: protrusion 1.5 nm" in md
    assert "steady sliding: protrusion 4 nm" in md
    for name in report.FIGURES:
        assert f"figures/{name}" in md
    cmp_ = (full_out / "report" / "comparison.md").read_text()
    assert "| touchdown protrusion | 9.8 nm (none at 9.6 nm) | first contact at 3 nm | -6.8 nm |" in cmp_
    assert "k = 0.4454" in cmp_
    # a gradual approach (0.2 nm minimum clearance at the last flying point, grid step 0.5 nm): no snap-in claim
    assert "comes into contact" in cmp_ and "snap-in" not in cmp_
    assert "| FHM at 4-7 nm (flying) | about 12.5 % | no flying point in 4-7 nm | – |" in cmp_
    assert "1.5 nm" in cmp_


def test_default_combination_first(tmp_path, paper_scene):
    # damping 0.02 comes first on the grid; the scene's air_bearing.damping_ratio = 0.05 must lead
    write_sweep(tmp_path, dampings=(0.02, 0.05), scales={0.02: 2.0, 0.05: 1.0})
    render(paper_scene, tmp_path)
    header, rows = read_csv(tmp_path / "report" / "summary.csv")
    damping = [float(r[1]) for r in rows]
    assert damping == [0.05] * 11 + [0.02] * 11
    fhm = header.index("FHM/BV [%]")
    assert float(rows[0][fhm]) == pytest.approx(9.5)      # 1 nm of the 0.05 block
    assert float(rows[11][fhm]) == pytest.approx(19.0)    # same point, the 0.02 block (scale 2)
    md = (tmp_path / "report" / "summary.md").read_text()
    assert md.index("damping ratio 0.05") < md.index("damping ratio 0.02")
    check_png(tmp_path / "figures" / "fig6_fhm.png")


def test_missing_optional_inputs_skip_their_figures(tmp_path, paper_scene, caplog):
    caplog.set_level("INFO", logger="pipeline")
    write_sweep(tmp_path)
    stale = tmp_path / "figures" / "dmw.png"
    stale.parent.mkdir()
    stale.write_bytes(b"old figure of an earlier run")
    figdir = render(paper_scene, tmp_path)
    for name in ("fig6_fhm.png", "fig7_shear.png"):
        check_png(figdir / name)
    for name in ("fig3_clearance.png", "fig4_forces.png", "fig5_stresses.png", "calibration.png",
                 "roughness.png", "dmw.png"):
        assert not (figdir / name).exists(), name
    md = (tmp_path / "report" / "summary.md").read_text()
    assert "`figures/dmw.png`: skipped, dmw.nc is absent" in md
    assert "`figures/fig3_clearance.png`: skipped, sweep_histories.nc is absent" in md
    assert "skipped calibration.png" in caplog.text
    assert (tmp_path / "report" / "summary.csv").is_file()
    assert "interface.nc absent" in (tmp_path / "report" / "comparison.md").read_text()


def test_no_contact_anywhere_keeps_the_whole_grid(tmp_path, paper_scene):
    write_sweep(tmp_path)
    ds = xr.open_dataset(tmp_path / "sweep.nc", engine="netcdf4").load()
    ds["regime"][:] = 0
    for name in ("interference", "mean_pressure", "shear_stress", "friction_coefficient"):
        ds[name][:] = np.nan
    write_dataset(ds, tmp_path / "sweep.nc", stage="sweep")
    render(paper_scene, tmp_path)
    _, rows = read_csv(tmp_path / "report" / "summary.csv")
    assert len(rows) == PROT.size
    assert "No contact anywhere on the grid." in (tmp_path / "report" / "summary.md").read_text()
    check_png(tmp_path / "figures" / "fig7_shear.png")


def test_snap_in_is_named_when_the_evidence_shows_it(tmp_path, paper_scene):
    """A large margin at the last flying point and a k-independent touchdown -> adhesive snap-in."""
    write_sweep(tmp_path)
    ds = xr.open_dataset(tmp_path / "sweep.nc", engine="netcdf4").load()
    ds["min_clearance"][:] = 2.0
    write_dataset(ds, tmp_path / "sweep.nc", stage="sweep", extra_attrs={"k": float("nan")})
    cal = xr.Dataset({"touchdown": ("k", [3.0, 3.0, 3.0], {"units": "nm", "long_name": "first contact"}),
                      "k_calibrated": ((), np.nan, {"units": "1", "long_name": "k"})},
                     coords={"k": ("k", [-1.0, 0.0, 1.0], {"units": "1", "long_name": "k"})})
    write_dataset(cal, tmp_path / "calibration.nc", stage="calibrate",
                  extra_attrs={"outcome": "no admissible k", "k_range": "[-1, 1]"})
    render(paper_scene, tmp_path)
    cmp_ = (tmp_path / "report" / "comparison.md").read_text()
    assert "jumps into contact" in cmp_
    assert "Likely cause: adhesive snap-in" in cmp_
    assert "the touchdown protrusion is 3 nm for every k in [-1, 1]" in cmp_
    check_png(tmp_path / "figures" / "calibration.png")


def test_sweep_is_required(tmp_path, paper_scene):
    with pytest.raises(DatasetError, match="sweep.nc"):
        render(paper_scene, tmp_path)


def test_envelope_keeps_every_peak_of_a_long_trace():
    """The thinned trace drawn for a history keeps its extremes (a one-sample spike, the global minimum),
    ignores NaN, stays in time order and leaves short traces untouched."""
    from pipeline.analyses.plots import envelope
    t = np.linspace(0.0, 2.0, 200_001)
    y = np.sin(2 * np.pi * 37 * t)
    y[123_457], y[5] = 7.5, np.nan                 # a spike one sample wide; a gap
    ts, ys = envelope(t, y, bins=1000)
    assert ts.size == ys.size == 2000 and np.all(np.diff(ts) >= 0)
    assert np.nanmax(ys) == 7.5 and np.nanmin(ys) == np.nanmin(y)
    short_t, short_y = envelope(t[:1000], y[:1000], bins=1000)
    assert np.array_equal(short_t, t[:1000]) and np.array_equal(short_y, y[:1000], equal_nan=True)


def test_every_file_the_report_draws_is_a_declared_output(full_out, paper_scene, tmp_path_factory):
    """The runner moves only declared outputs out of the staging folder: an ensemble sweep's
    ``figures/ensemble.png`` must be one of them, or it is drawn and thrown away."""
    from pipeline.analyses.ensemble_rules import statistics as ensemble_statistics
    from pipeline.variables import ENSEMBLE
    sweep = xr.open_dataset(full_out / "sweep.nc", engine="netcdf4").load()
    ens = xr.concat([sweep, sweep], dim="realisation")
    data = {n: ens[n].variable.transpose(*sweep[n].dims, "realisation") for n in sweep.data_vars}
    ens = xr.Dataset({**data, **ensemble_statistics(data)}, coords=sweep.coords)
    ens["realisation"] = ENSEMBLE["realisation"].data(np.arange(2), ("realisation",))
    write_dataset(ens, full_out / "sweep.nc", stage="sweep", extra_attrs=dict(sweep.attrs))
    staging = tmp_path_factory.mktemp("staging")
    report.compute(paper_scene, Inputs(out=full_out, staging=staging))
    drawn = {p.relative_to(staging).as_posix() for p in staging.rglob("*") if p.is_file()}
    assert "figures/" + report.ENSEMBLE_FIGURE in drawn
    assert drawn <= set(report.STAGE.output_names(paper_scene))


def _line_figure(path, slope):
    from pipeline.analyses import plots
    fig, ax = plots.new_figure()
    ax.plot([0.0, 1.0], [0.0, slope])
    plots.save(fig, path)
    return path, os.getpid()


def _broken_figure(path):
    raise ValueError(f"{path}: this figure cannot be drawn")


def _dying_figure(path):
    os._exit(3)  # (a worker killed mid-figure, e.g. by the out-of-memory killer)


def test_figures_drawn_by_worker_processes_are_the_figures_drawn_in_process(tmp_path):
    """``plots.draw_all`` gives the same PNG bytes, in the same order, whether the figures are drawn
    in this process or by its forked workers, and a figure's error reaches the caller."""
    import sys
    import threading
    from pipeline.analyses import plots
    here = plots.draw_all([(_line_figure, (tmp_path / f"a{i}.png", i + 1.0), {}) for i in range(3)], workers=1)
    there = plots.draw_all([(_line_figure, (tmp_path / f"b{i}.png", i + 1.0), {}) for i in range(3)], workers=2)
    assert [p.name for p, _ in there] == ["b0.png", "b1.png", "b2.png"]
    assert [p.read_bytes() for p, _ in there] == [p.read_bytes() for p, _ in here]
    assert {pid for _, pid in here} == {os.getpid()}
    # forked workers exactly where it is safe: Linux, no other thread alive (else drawn here)
    forked = sys.platform.startswith("linux") and threading.active_count() == 1
    assert (os.getpid() not in {pid for _, pid in there}) == forked
    with pytest.raises(ValueError, match="cannot be drawn"):
        plots.draw_all([(_line_figure, (tmp_path / "c.png", 1.0), {}), (_broken_figure, (tmp_path / "d.png",), {})],
                       workers=2)
    if forked:  # a dead worker is an error, not a wait for its figure forever
        from concurrent.futures.process import BrokenProcessPool
        with pytest.raises(BrokenProcessPool):
            plots.draw_all([(_line_figure, (tmp_path / "e.png", 1.0), {}), (_dying_figure, (tmp_path / "f.png",), {})],
                           workers=2)
