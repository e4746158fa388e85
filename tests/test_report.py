"""Stage ``report`` on small synthetic datasets written with pipeline.io.write_dataset."""

from __future__ import annotations

import csv
import os

import matplotlib.image as mpimg
import numpy as np
import pytest
import xarray as xr

from pipeline.io import DatasetError, write_dataset
from pipeline.variables import HISTORIES, SCALARS
from pipeline.runner import Inputs
from pipeline.stages import report


def render(scene, out):
    """The report of the hand-made datasets in ``out``, written straight into it (the stage's compute:
    through the runner, the datasets would first be made current for the scene, i.e. recomputed)."""
    report.compute(scene, Inputs.folder(out))
    return out / "figures"

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PROT = np.round(np.arange(0.0, 6.01, 0.5), 9)          # 13 protrusions [nm]
FIRST_CONTACT = 3.0
K = 0.4454


def _scalar_var(name, values, dims):
    return SCALARS[name].data(values, dims)


def slice_values(scale: float = 1.0) -> dict[str, np.ndarray]:
    """One roughness/damping slice: flying below 3 nm, bouncing at 3-3.5 nm, surfing from 4 nm."""
    n = PROT.size
    regime = np.where(PROT < FIRST_CONTACT, 0, np.where(PROT < 4.0, 1, 2))
    contact = regime > 0
    clearance = np.where(contact, -0.1 * (PROT - 2.5), 3.0 - PROT + 0.2)
    fhm = np.where(regime == 0, 9.0 + 0.5 * PROT, np.where(regime == 1, 20.0, 1.0 + 0.1 * (PROT - 4)))
    fhm = fhm * scale
    interference = np.where(contact, -clearance, np.nan)
    pressure = np.where(contact, 400.0 + 10 * PROT, np.nan)
    shear = np.where(contact, 300.0 + 2 * PROT, np.nan)
    return {
        "fhm_bv": fhm, "clearance": clearance, "min_clearance": clearance - 0.5,
        "interference": interference,
        "contact_force": np.where(contact, 1.0 + 0.1 * PROT, 0.0),
        "friction_force": np.where(contact, 0.7 + 0.05 * PROT, 0.0),
        "adhesion_force": 0.01 + 0.2 * PROT,
        "net_force": np.where(contact, 1.0, 0.0) - (0.01 + 0.2 * PROT),
        "friction_coefficient": shear / pressure,
        "mean_pressure": pressure, "shear_stress": shear,
        "real_area": np.where(contact, 4.0, np.nan),
        "nominal_area": np.linspace(120.0, 60.0, n),
        "protrusion_radius": np.linspace(2000.0, 700.0, n),
        "contact_fraction": np.where(regime == 2, 1.0, np.where(regime == 1, 0.5, 0.0)),
        "regime": regime,
    }


def write_sweep(out, dampings=(0.05,), scales=None):
    scales = scales or {d: 1.0 for d in dampings}
    dims = ("protrusion", "roughness", "damping")
    per = [slice_values(scales[d]) for d in dampings]
    data = {name: _scalar_var(name, np.stack([p[name] for p in per], axis=-1)[:, None, :], dims)
            for name in per[0]}
    coords = {"protrusion": ("protrusion", PROT, {"units": "nm", "long_name": "TFC protrusion"}),
              "roughness": ("roughness", np.array(["scene"], dtype=object), {"units": "1", "long_name": "set"}),
              "damping": ("damping", np.array(dampings, float), {"units": "1", "long_name": "damping ratio"})}
    write_dataset(xr.Dataset(data, coords=coords), out / "sweep.nc", stage="sweep",
                  extra_attrs={"k": K, "k_source": "scene (contact.k)", "steady_window": "0.5 ms to 2 ms",
                               "fhm_measure": "peak-to-peak"})


def write_histories(out):
    t = np.arange(400) * 2.5e-6                      # 1 ms
    prot = np.array([1.0, 5.0])
    rng = np.random.default_rng(1)
    shape = (2, 1, 1, t.size)
    wave = np.sin(2 * np.pi * 20e3 * t) + 0.3 * rng.standard_normal(t.size)
    contact = np.stack([np.zeros_like(t), (t > 1e-4).astype(float)])
    sep = np.stack([4.0 + 0.6 * wave, -0.2 + 0.05 * wave])
    values = {
        "separation": sep, "clearance": sep - 0.23, "in_contact": contact,
        "contact_force": contact * (1.5 + 0.1 * wave), "friction_force": contact * (1.0 + 0.07 * wave),
        "adhesion_force": np.stack([0.02 + 0 * t, 2.0 + 0.01 * wave]),
        "net_force": contact * (1.5 + 0.1 * wave) - 2.0,
        "friction_coefficient": np.where(contact > 0, 0.7 + 0.01 * wave, np.nan),
        "mean_pressure": np.where(contact > 0, 440 + 5 * wave, np.nan),
        "shear_stress": np.where(contact > 0, 312 + 1 * wave, np.nan),
    }
    dims = ("protrusion", "roughness", "damping", "time")
    data = {n: xr.Variable(dims, v.reshape(shape), attrs=HISTORIES[n].attrs())
            for n, v in values.items()}
    coords = {"protrusion": ("protrusion", prot, {"units": "nm", "long_name": "TFC protrusion"}),
              "roughness": ("roughness", np.array(["scene"], dtype=object), {"units": "1", "long_name": "set"}),
              "damping": ("damping", [0.05], {"units": "1", "long_name": "damping ratio"}),
              "time": ("time", t, {"units": "s", "long_name": "time"})}
    write_dataset(xr.Dataset(data, coords=coords), out / "sweep_histories.nc", stage="sweep")


def write_calibration(out):
    ks = np.linspace(-1.0, 1.0, 5)
    data = {"touchdown": ("k", [3.5, 3.0, 3.0, 2.5, np.nan], {"units": "nm", "long_name": "first contact"})}
    for name, v in (("k_calibrated", 0.25), ("k_low", 0.0), ("k_high", 0.5), ("k_onset", 0.0), ("k_previous", 0.5),
                    ("contact_probability_one_sided", 0.4), ("contact_probability_two_sided", 0.8)):
        data[name] = ((), v, {"units": "1", "long_name": name})
    ds = xr.Dataset(data, coords={"k": ("k", ks, {"units": "1", "long_name": "k"})})
    write_dataset(ds, out / "calibration.nc", stage="calibrate",
                  extra_attrs={"outcome": "admissible k in (0, 0.5]", "touchdown_onset_nm": 3.0,
                               "touchdown_previous_nm": 2.5})


def write_dmw(out):
    fs, n = 4e6, 4000
    rng = np.random.default_rng(2)
    w = np.convolve(rng.standard_normal(n), np.ones(20) / 20, mode="same")
    f = np.fft.rfftfreq(n, 1 / fs)
    psd = np.abs(np.fft.rfft(w)) ** 2 / (fs * n)
    ds = xr.Dataset({
        "displacement": ("time", w, {"units": "nm", "long_name": "DMW"}),
        "psd": ("frequency", psd, {"units": "nm2 Hz-1", "long_name": "PSD"}),
        "rms": ((), float(np.std(w)), {"units": "nm", "long_name": "rms"}),
        "band_low": ((), 10e3, {"units": "Hz", "long_name": "band low"}),
        "band_high": ((), 500e3, {"units": "Hz", "long_name": "band high"}),
    }, coords={"time": ("time", np.arange(n) / fs, {"units": "s", "long_name": "time"}),
               "frequency": ("frequency", f, {"units": "Hz", "long_name": "frequency"})})
    write_dataset(ds, out / "dmw.nc", stage="dmw", extra_attrs={"dmw_source": "synthetic", "seed": 2})


def write_roughness(out):
    surfaces = np.array(["disk", "tfc", "combined"], dtype=object)
    sm = ("surface", "route")
    vals = {"sigma": [[0.4, 0.41], [0.3, 0.31], [0.5, np.nan]], "sigma_s": [[0.3, 0.3], [0.2, 0.2], [0.35, np.nan]],
            "summit_radius": [[4.0, 3.0], [6.0, 5.0], [5.0, np.nan]],
            "summit_density": [[12.0, 9.0], [8.0, 7.0], [10.0, np.nan]]}
    units = {"sigma": "nm", "sigma_s": "nm", "summit_radius": "um", "summit_density": "um-2"}
    data = {k: (sm, np.array(v), {"units": units[k], "long_name": k}) for k, v in vals.items()}
    data["pixel_size"] = ("surface", [5.0, 5.0, np.nan], {"units": "nm", "long_name": "pixel size"})
    ds = xr.Dataset(data, coords={"surface": ("surface", surfaces, {"units": "1", "long_name": "surface"}),
                                  "route": ("route", np.array(["spectral", "summits"], dtype=object),
                                             {"units": "1", "long_name": "route"})})
    write_dataset(ds, out / "roughness.nc", stage="roughness")


def check_png(path):
    assert path.is_file(), path
    raw = path.read_bytes()
    assert raw[:8] == PNG_SIGNATURE, f"{path.name} is not a PNG"
    assert len(raw) > 5_000, f"{path.name} is only {len(raw)} bytes"
    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[0] > 300 and img.shape[1] > 500
    rgb = img[..., :3].reshape(-1, 3)
    assert rgb.var(axis=0).sum() > 1e-3, f"{path.name} is (nearly) a single colour"
    q = (rgb * 255).astype(np.int64)
    colours = np.unique(q[:, 0] * 65536 + q[:, 1] * 256 + q[:, 2])
    assert colours.size > 20, f"{path.name} has too few colours"


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


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
