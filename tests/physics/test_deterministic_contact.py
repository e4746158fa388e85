"""The deterministic interface: FFT boundary-element contact against analytic limits, and its tables.

Analytic cases (pipeline.physics.deterministic_contact):

* Hertz: a sphere indenting an elastic flat, load ``(4/3) E' sqrt(R) delta^1.5`` and contact radius
  ``sqrt(R delta)`` (Johnson 1985, eqs. 4.22-4.23), non-periodic half-space.
* Light contact of a random surface: ``A/A0 = kappa p / (E' h'_rms)`` with ``h'_rms`` the rms gradient
  (``sqrt(<|grad h|^2>)``), kappa between Persson's ``sqrt(8/pi)`` = 1.60 (Persson, J. Chem. Phys. 115
  (2001) 3840) and the Bush-Gibson-Thomas asymptote ``sqrt(2 pi)`` = 2.51 (Wear 35 (1975) 87);
  simulations give ~2 (Hyun et al., Phys. Rev. E 70 (2004) 026117).
* The statistical model's own limit: a periodic lattice of identical paraboloidal summits (density
  eta, radius R) carries ``p = eta (4/3) E' sqrt(R) w^1.5`` on ``A/A0 = eta pi R w`` (GW 1966 with
  every summit at one height). The deterministic interference ``w_det`` is measured from the mean
  plane of the deformed flat, which the periodic array of loads P shifts by the lattice sum
  ``zeta_Z2(1/2) P / (pi E' lambda)``, ``zeta_Z2(1/2) = 4 zeta(1/2) beta(1/2) = -3.9003`` (the Epstein
  zeta function of the square lattice, Glasser & Zucker, Theor. Chem. Adv. Perspect. 5 (1980) 67), so
  ``w_det = w - 1.2415 P/(E' lambda)``: the deterministic solution tends to GW as the summits grow
  sparse (lambda -> infinity), and agrees with it at every spacing once that interaction is added.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from pipeline.physics import deterministic_contact as dc
from pipeline.config.scene import SceneError, load_scene
from pipeline.variables import declared

from cf_check import cf_report

AFM = Path(__file__).resolve().parents[1] / "data" / "afm"
#: zeta(1/2) and Dirichlet beta(1/2) (Glasser & Zucker 1980): the square-lattice sum of 1/r.
ZETA_HALF, BETA_HALF = -1.4603545088095868, 0.6676914571896092
LATTICE = -4.0 * ZETA_HALF * BETA_HALF / np.pi  # = 1.2415: w - w_det = LATTICE P / (E' lambda)


# ------------------------------------------------------------------------------------------ Hertz
@pytest.mark.parametrize("delta", [0.5, 2.0])
def test_hertz_sphere_load_and_contact_radius(delta):
    R = 1000.0  # nm; E' = 1 (loads in units of E' nm^2)
    r = dc.hertz_check(R, delta, size=600.0 if delta > 1 else 400.0, points=128)
    assert r["load"] == pytest.approx(4.0 / 3.0 * np.sqrt(R) * delta**1.5, rel=0.01)
    # the contact radius from the pixel count: within one pixel (3.1-4.7 nm) of sqrt(R delta)
    assert abs(r["contact_radius"] - np.sqrt(R * delta)) < 1.0 * (600.0 if delta > 1 else 400.0) / 128


# --------------------------------------------------------------------------- random, light load
def _random_surface(seed: int, n: int = 256, size: float = 1000.0) -> np.ndarray:
    from SurfaceTopography.Generation import fourier_synthesis
    np.random.seed(seed)  # fourier_synthesis draws from numpy's global generator
    t = fourier_synthesis((n, n), (size, size), 0.8, rms_slope=0.1, short_cutoff=8 * size / n)
    h = np.asarray(t.heights(), float)
    return h - h.mean()


def test_light_contact_area_is_proportional_to_load_between_persson_and_bgt():
    kappas = {0.01: [], 0.03: []}
    for seed in (1, 2, 3, 4):
        h = _random_surface(seed)
        slope = dc.rms_slope(h, (1000.0, 1000.0))
        for target in kappas:
            r = dc.contact_at_load(h, (1000.0, 1000.0), target * slope / 2.0)
            kappas[target].append(r["area_fraction"] * slope / r["pressure"])
    k1, k3 = np.mean(kappas[0.01]), np.mean(kappas[0.03])
    for k in (k1, k3):
        assert np.sqrt(8.0 / np.pi) < k < np.sqrt(2.0 * np.pi)
    # proportional: the same kappa at 1 % and 3 % of real area (pixel counting biases the smaller one up)
    assert k1 / k3 == pytest.approx(1.0, abs=0.12)


# ---------------------------------------------------------------- the statistical model's own limit
def _summit_lattice(n: int, cells: int, spacing: float, R: float, depth: float):
    L = cells * spacing
    x = (np.arange(n) + 0.5) * L / n
    X, Y = np.meshgrid(x, x, indexing="ij")
    dx, dy = X % spacing - spacing / 2, Y % spacing - spacing / 2
    h = np.maximum(-(dx**2 + dy**2) / (2 * R), -depth)  # identical paraboloidal caps on a flat base
    return h - h.mean(), (L, L)


@pytest.mark.parametrize("spacing,depth", [(256.0, 6.0), (512.0, 20.0)])
def test_sparse_identical_summits_reach_the_gw_limit(spacing, depth):
    R, w = 1000.0, 3.0
    h, sizes = _summit_lattice(128, 2, spacing, R, depth)
    y_s = h.max()                     # every summit at the same height: their mean is the top
    eta = 4 / (sizes[0] * sizes[1])
    P = 4.0 / 3.0 * np.sqrt(R) * w**1.5  # Hertz load of one summit at interference w
    r = dc.contact_at_load(h, sizes, eta * P)  # GW: p = eta x Hertz
    assert r["pressure"] == pytest.approx(eta * P, rel=1e-6)
    w_det = y_s - r["mean_gap"]       # d = u - y_s, interference = -d
    # real area = eta pi R w (pixel counting: within 4 %)
    assert r["area_fraction"] == pytest.approx(eta * np.pi * R * w, rel=0.04)
    # with the elastic interaction of the lattice the interference is GW's within 2 %
    assert w_det == pytest.approx(w - LATTICE * P / spacing, rel=0.02)
    # and the gap to GW is that interaction alone: it halves when the spacing doubles
    assert (w - w_det) * spacing / P == pytest.approx(LATTICE, rel=0.06)


# ------------------------------------------------------------------------------- tabulation, maps
def test_tabulate_is_zero_beyond_first_contact_monotone_and_through_the_solved_points():
    h = _random_surface(5, n=64)
    s = dc.contact_series(h, (1000.0, 1000.0), points=8)
    assert np.all(np.diff(s.pressure) > 0) and np.all(np.diff(s.mean_gap) < 0)
    g = np.linspace(-2.0, s.onset_gap + 5.0, 400)
    p, a = dc.tabulate(s, g)
    assert np.all(p[g >= s.onset_gap] == 0) and np.all(a[g >= s.onset_gap] == 0)
    assert np.all(np.diff(p) <= 1e-15) and np.all(np.diff(a) <= 1e-15)  # decreasing with separation
    assert a.max() <= 1.0
    ps, as_ = dc.tabulate(s, s.mean_gap)
    # tol: the solver's own tabulation read back at its nodes, a few roundings
    np.testing.assert_allclose(ps, s.pressure, rtol=1e-12)
    # tol: the solver's own tabulation read back at its nodes, a few roundings
    np.testing.assert_allclose(as_, s.area_fraction, rtol=1e-12)


def test_combine_maps_and_resample():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(32, 32))
    # a second map on the same domain at half the resolution: its values are read at the centres
    h, sizes = dc.combine_maps([(a, (10.0, 10.0)), (np.zeros((16, 16)), (10.0, 10.0))])
    np.testing.assert_allclose(h, a - a.mean())  # tol: the map less its mean, a few roundings of a mean
    assert sizes == (10.0, 10.0)
    # a smooth periodic map on a coarser grid is read at the finer grid's pixel centres (bilinear)
    xc = (np.arange(16) + 0.5) * 10.0 / 16
    xf = (np.arange(32) + 0.5) * 10.0 / 32
    b = np.cos(2 * np.pi * xc / 10.0)[:, None] * np.ones(16)[None, :]
    h2, _ = dc.combine_maps([(np.zeros((32, 32)), (10.0, 10.0)), (b, (10.0, 10.0))])
    np.testing.assert_allclose(h2[:, 0], np.cos(2 * np.pi * xf / 10.0), atol=0.02)
    r = dc.resample(a, 16)
    assert r.shape == (16, 16) and dc.resample(a, 64).shape == (32, 32)
    assert r.mean() == pytest.approx(a.mean(), abs=1e-12)


# ------------------------------------------------------------------------ scene option and stage
def test_scene_option_is_validated(paper_config):
    with pytest.raises(SceneError, match="interface.model = 'deterministic' needs a measured surface"):
        load_scene(paper_config, ["interface.model='deterministic'"])
    with pytest.raises(SceneError, match=r"interface.model = 'gw'.*expected one of 'statistical', 'deterministic'"):
        load_scene(paper_config, ["interface.model='gw'"])
    with pytest.raises(SceneError, match="contact_grid_points"):
        load_scene(paper_config, ["solver.contact_grid_points=4"])
    assert load_scene(paper_config)["interface"]["model"] == "statistical"


def _afm_scene(paper_config, model: str, points: int = 32):
    return load_scene(paper_config, [f"roughness.afm=['{AFM / 'mi-1.mi'}']", f"interface.model='{model}'",
                                     f"solver.contact_grid_points={points}",
                                     "scene.effects=['air_bearing', 'pitch', 'adhesion', 'contact', 'friction']"])


@pytest.fixture(scope="module")
def both_models(paper_config):
    from pipeline.model.interface_tables import build_tables, roughness_statistics
    stat = _afm_scene(paper_config, "statistical")
    det = _afm_scene(paper_config, "deterministic")
    stats = roughness_statistics(stat)
    return stat, det, build_tables(stat, stats), build_tables(det, stats)


def test_both_models_side_by_side_on_a_model_coordinate(both_models):
    _, _, ds_stat, ds = both_models
    assert list(ds["model"].values) == ["statistical", "deterministic"]
    assert "model" not in ds_stat.dims  # the default writes what it always wrote
    for name in ("contact_pressure", "real_area_fraction", "friction_stress"):
        assert ds[name].dims == ("model", "separation")
        # the statistical row is the statistical-only table, bit for bit
        assert np.array_equal(ds[name].sel(model="statistical").values, ds_stat[name].values)
    for name in ("adhesion_pressure", "contact_fraction", "sigma"):
        assert ds[name].identical(ds_stat[name])
    det = ds.sel(model="deterministic")
    # the same shear-strength law on the computed real area
    # tol: the same shear-strength product, one rounding
    np.testing.assert_allclose(det["friction_stress"].values,
                               float(ds["shear_strength"]) * det["real_area_fraction"].values, rtol=1e-12)
    # datum: d = u - y_s; no contact above the highest point, the solved points on the table
    d = ds["separation"].values
    assert np.all(det["contact_pressure"].values[d > float(ds["solved_separation"].max()) + 40] == 0)
    on = np.interp(ds["solved_separation"].values, d, det["real_area_fraction"].values)
    np.testing.assert_allclose(on, ds["solved_real_area_fraction"].values, rtol=0.05, atol=1e-4)
    assert ds["contact_grid_points"] == 32 * 32


def test_dynamics_read_the_scene_s_model(both_models):
    from pipeline.model import assembly
    stat, det, ds_stat, ds = both_models
    m_stat = assembly.build_model(stat, ds_stat, None, 1.0)
    m_same = assembly.build_model(stat, ds, None, 1.0)       # both tables, statistical scene
    m_det = assembly.build_model(det, ds, None, 1.0)
    for key in ("contact", "friction", "area", "adhesion"):
        assert np.array_equal(getattr(m_stat, key), getattr(m_same, key))
    assert np.array_equal(m_det.adhesion, m_stat.adhesion)  # adhesion stays statistical
    assert m_det.contact.shape == m_stat.contact.shape and not np.array_equal(m_det.contact, m_stat.contact)


@pytest.mark.slow  # the stage through the CLI, the roughness stage and the CF checker (~15 s)
def test_deterministic_interface_nc_round_trip(tmp_path, paper_config):
    from pipeline import cli
    argv = ["interface", str(paper_config), "--out", str(tmp_path), "--set", f"roughness.afm=['{AFM / 'mi-1.mi'}']",
            "--set", "interface.model='deterministic'", "--set", "solver.contact_grid_points=32"]
    assert cli.main(argv) == 0
    with xr.open_dataset(tmp_path / "interface.nc", engine="netcdf4") as ds:
        cp = ds["contact_pressure"].sel(model="deterministic")
        assert cp.dims == ("separation",) and cp.attrs["units"] == "MPa"
        assert float(ds["solved_contact_pressure"].max()) > 0
        for name in list(ds.data_vars) + list(ds.coords):  # declared once, written in its units
            decl = declared("interface", name)
            assert ds[name].attrs.get("units", "") == decl.units, name
    failures, crashed = cf_report(tmp_path / "interface.nc")
    assert crashed == [] and failures[3] == [] and failures[2] + failures[1] == []


def test_interface_figure_of_both_models(both_models, tmp_path):
    from pipeline.analyses import plots
    _, _, _, ds = both_models
    path = plots.fig_interface_models(ds, "afm", tmp_path / "interface_models.png")
    assert path.is_file() and path.stat().st_size > 10_000


def test_a_load_that_does_not_converge_is_left_out(monkeypatch):
    h = _random_surface(6, n=32)
    solve = dc._solve
    calls = []

    def flaky(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise dc.ConvergenceError("stalled")
        return solve(*args, **kwargs)

    monkeypatch.setattr(dc, "_solve", flaky)
    s = dc.contact_series(h, (1000.0, 1000.0), points=6)
    assert len(s.skipped) == 1 and s.mean_gap.size == 5
    assert np.all(np.diff(s.pressure) > 0) and np.all(np.diff(s.mean_gap) < 0)
