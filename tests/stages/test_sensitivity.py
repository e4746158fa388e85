"""hdi sensitivity: Morris and Sobol indices through the evaluation path, checked on models with known indices.

The stand-in batch function replaces the slider (the statistics are what is tested; the slider's own
evaluation is tested in stages/test_identify.py): the flying FHM is a linear model ``sum a_i x_i`` (exact
indices: ``S1_i = ST_i = a_i^2 / sum a_j^2`` for equal ranges, Morris ``mu*_i = |a_i| (high - low)``,
``sigma_i = 0``) and the contact force at 11 nm is the Ishigami function (Ishigami & Homma 1990;
``S1 = (0.3139, 0.4424, 0)``, ``ST = (0.5576, 0.4424, 0.2437)``); the fourth parameter enters neither.
The stand-in maps each parameter's bounds onto [-pi, pi] (the indices of the test functions are those of
that range; Sobol indices do not change under the map, and Morris mu* is scaled to the whole range).

The box of a study is checked before anything is built (pipeline/analyses/feasibility.py): the shipped
bounds pass, a summit density below McCool's limit is refused in one line with the limit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from pipeline.config.scene import load_scene
from pipeline.runner import ensure

A = np.array([2.0, -1.0, 0.5, 0.0])
S1_ISHIGAMI = np.array([0.3139, 0.4424, 0.0, 0.0])
ST_ISHIGAMI = np.array([0.5576, 0.4424, 0.2437, 0.0])


def ishigami(x: np.ndarray) -> float:
    return math.sin(x[0]) + 7.0 * math.sin(x[1]) ** 2 + 0.1 * x[2] ** 4 * math.sin(x[0])


def unit_box(params, x) -> np.ndarray:
    """The parameter values ``x`` mapped from their bounds onto [-pi, pi]."""
    lo, hi = np.array([p.low for p in params]), np.array([p.high for p in params])
    return -math.pi + 2 * math.pi * (np.asarray(x, float) - lo) / (hi - lo)


def stub_batch(base, params, rows, protrusions, inputs):
    p = np.asarray(protrusions)
    n = len(p)
    out = []
    for key, x in rows:
        x = unit_box(params, x)
        touch = p >= 9.8 - 1e-9  # contact from 9.8 nm: the exact minimum clearance below zero there
        outputs = {"fhm_bv": [float(A @ x)] * n, "contact_fraction": list(touch.astype(float)),
                   "min_clearance": list(np.where(touch, -0.1, 0.1)),
                   "contact_force": [ishigami(x)] * n, "interference": [0.5] * n, "mean_pressure": [400.0] * n}
        out.append((key, {"params": list(x), "protrusions": list(p), "outputs": outputs, "seconds": 0.0,
                          "kernel_seconds": 0.0, "error": None}))
    return out


SCENE = """
[scene]
name = "sens"
extends = "{paper}"

[identify]
fhm_flying_range_nm = [9.0, 9.6]

[sensitivity]
parameters = [{{key = "dmw.rms_nm", low = 0.08, high = 0.30}},
              {{key = "contact.damping_n_s_m", low = 0.0, high = 0.05}},
              {{key = "air_bearing.rear_exponent", low = 1.0, high = 3.0}},
              {{key = "lubricant.intermolecular_distance_nm", low = 0.2, high = 0.5}}]
protrusion_nm = {{start = 9.0, stop = 11.0, step = 0.2}}
morris_trajectories = 20
sobol_samples = 1024
bootstrap = 50
batch_size = 512
"""


def test_indices_of_known_models_through_the_evaluation_path(write_scene, paper_config, tmp_path):
    scene = load_scene(write_scene(SCENE.format(paper=paper_config)))
    nc = ensure("sensitivity", scene, tmp_path / "out", scheduler="synchronous", task=stub_batch)
    ds = xr.open_dataset(nc, engine="netcdf4")
    span = 2 * math.pi
    # the layout: indices over (output, parameter), selected by the scene key and the output's name
    assert ds["mu_star"].dims == ("output", "parameter") and ds["ST_conf"].dims == ("output", "parameter")
    assert list(ds["parameter"].values) == ["dmw.rms_nm", "contact.damping_n_s_m", "air_bearing.rear_exponent",
                                            "lubricant.intermolecular_distance_nm"]
    fhm, force = ds.sel(output="fhm_flying"), ds.sel(output="contact_force")
    assert str(fhm["output_units"].values) == "%" and ds["mu_star"].attrs["unit_variable"] == "output_units"
    assert ds["morris_values"].dims == ("morris_sample", "parameter")
    assert ds["sobol_outputs"].dims == ("sobol_sample", "output")
    # linear model: Morris exact, Sobol within sampling error
    # tol: a linear model's elementary effects: exact up to tens of roundings of the span
    np.testing.assert_allclose(fhm["mu_star"].values, np.abs(A) * span, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fhm["sigma"].values, 0.0, atol=1e-9)
    exact = A**2 / np.sum(A**2)
    np.testing.assert_allclose(fhm["S1"].values, exact, atol=0.03)
    np.testing.assert_allclose(fhm["ST"].values, exact, atol=0.03)
    # Ishigami: published indices; the unused parameter gets ~0
    np.testing.assert_allclose(force["S1"].values, S1_ISHIGAMI, atol=0.05)
    np.testing.assert_allclose(force["ST"].values, ST_ISHIGAMI, atol=0.05)
    assert abs(float(force["ST"].sel(parameter="lubricant.intermolecular_distance_nm"))) < 1e-9
    assert float(force["mu_star"].sel(parameter="lubricant.intermolecular_distance_nm")) == 0.0
    # the confidence intervals are reported and cover the exact first-order indices of the linear model
    assert np.all(np.abs(fhm["S1"].values - exact) <= fhm["S1_conf"].values + 0.01)
    assert np.all(force["S1_conf"].values[:3] > 0)
    # an output that does not vary (touchdown is 9.8 nm in every sample) has undefined Sobol indices, and says why
    td = ds.sel(output="touchdown")
    assert np.all(np.isnan(td["ST"].values)) and "does not vary" in str(td["sobol_note"].values)
    # tol: the effects of a constant output are 0 up to a few roundings
    np.testing.assert_allclose(td["mu_star"].values, 0.0)
    # every sample ran and every index uses every sample
    assert ds.attrs["failed_evaluations"] == 0 and int(ds["morris_failed"].sum()) == 0
    assert np.all(ds["morris_used"].values == 20) and np.all(ds["sobol_used"].values == 1024)
    for v in list(ds.data_vars) + list(ds.coords):
        assert "long_name" in ds[v].attrs, v
        assert len(ds[v].attrs["long_name"]) <= 40, (v, ds[v].attrs["long_name"])  # a label; sentence: description
        assert "units" in ds[v].attrs or "unit_variable" in ds[v].attrs or ds[v].dtype.kind in "OUS", v
    assert ds["mu_star"].attrs["long_name"] == "Morris mu*"
    assert ds["mu_star"].attrs["description"].startswith("Morris mu*: mean absolute elementary effect")
    from cf_check import cf_report  # sensitivity.nc fits the ecosystem like the other datasets
    failures, crashed = cf_report(nc)
    assert crashed == [] and failures[3] == [] and failures[2] == [], failures


def stub_with_holes(base, params, rows, protrusions, inputs):
    """The linear stand-in, with no contact at 11 nm (undefined contact force) when x4 > 2."""
    out = stub_batch(base, params, rows, protrusions, inputs)
    for (_, x), (_, rec) in zip(rows, out):
        if unit_box(params, x)[3] > 2.0:
            rec["outputs"]["contact_force"] = [float("nan")] * len(rec["protrusions"])
    return out


def test_morris_leaves_out_trajectories_with_undefined_points(write_scene, paper_config, tmp_path):
    text = SCENE.format(paper=paper_config).replace("[sensitivity]", '[sensitivity]\nmethods = ["morris"]')
    scene = load_scene(write_scene(text))
    ds = xr.open_dataset(ensure("sensitivity", scene, tmp_path / "out", scheduler="synchronous", task=stub_with_holes),
                         engine="netcdf4")
    force, fhm = ds.sel(output="contact_force"), ds.sel(output="fhm_flying")
    used, undefined = int(force["morris_used"]), int(force["morris_undefined_samples"])
    assert 2 <= used < 20 and undefined > 0
    assert np.all(np.isfinite(force["mu_star"].values))
    assert f"over {used} of 20 trajectories" in str(force["morris_note"].values)
    # the output without holes keeps every trajectory and its exact indices
    assert int(fhm["morris_used"]) == 20 and str(fhm["morris_note"].values) == ""
    # tol: a linear model's elementary effects: exact up to tens of roundings of the span
    np.testing.assert_allclose(fhm["mu_star"].values, np.abs(A) * 2 * math.pi, rtol=1e-9)


def test_screening_takes_any_outputs_callable():
    # the algorithms (analyses) on a plain function: y = 2 x0 over x0 in [0, 1], x1 not seen
    from pipeline.analyses import free_parameters, screening
    params = [free_parameters.Parameter("dmw.rms_nm", 0.0, 1.0), free_parameters.Parameter("air_bearing.damping_ratio", 0.0, 0.5)]

    def outputs(X):
        return {"y": 2.0 * X[:, 0]}

    c = {"morris_trajectories": 4, "morris_levels": 4, "seed": 1, "bootstrap": 10, "confidence_level": 0.95,
         "sobol_samples": 8}
    X, Y, idx = screening.morris(outputs, params, c)
    assert X.shape == (4 * 3, 2) and np.array_equal(Y["y"], 2.0 * X[:, 0])
    assert idx["y"].values["mu_star"] == pytest.approx([2.0, 0.0]) and idx["y"].used == 4
    X, Y, idx = screening.sobol(outputs, params, c)
    assert X.shape == (8 * 4, 2)
    # (8 base samples: the estimate of x0 is rough; the parameter no output sees has exactly none)
    st, s1 = idx["y"].values["ST"], idx["y"].values["S1"]
    assert st[0] > 0.5 and st[1] == 0.0 and s1[1] == 0.0


def stub_failing(base, params, rows, protrusions, inputs):
    """The linear stand-in whose evaluation fails (no outputs, an error) where the first parameter is above
    pi/2 on [-pi, pi]: a quarter of the box, as an infeasible corner of a real box would."""
    out = stub_batch(base, params, rows, protrusions, inputs)
    for (_, x), (_, rec) in zip(rows, out):
        u = unit_box(params, x)
        if u[0] > math.pi / 2:
            rec["outputs"], rec["error"] = {}, f"stand-in failure at x0 = {u[0]:.3f}"
    return out


def test_failed_evaluations_are_counted_and_the_indices_use_the_samples_left(write_scene, paper_config, tmp_path,
                                                                             caplog):
    text = SCENE.format(paper=paper_config).replace("sobol_samples = 1024", "sobol_samples = 256")
    scene = load_scene(write_scene(text))
    with caplog.at_level("INFO", logger="pipeline.stages.sensitivity"):
        nc = ensure("sensitivity", scene, tmp_path / "out", scheduler="synchronous", task=stub_failing)
    ds = xr.open_dataset(nc, engine="netcdf4")
    for method, rows in (("morris", 20 * 5), ("sobol", 256 * 6)):
        X = ds[f"{method}_values"].values
        failed = unit_box_array(X) > math.pi / 2
        assert 0 < failed.sum() < rows and ds[f"{method}_values"].shape[0] == rows
        # counted in the dataset: the flags are exactly the failing samples, and the count with the first error
        np.testing.assert_array_equal(ds[f"{method}_failed"].values, failed.astype(np.int8))
        assert ds[f"{method}_failed"].attrs["failed_evaluations"] == failed.sum()
        assert ds[f"{method}_failed"].attrs["first_failure"].startswith("stand-in failure at x0 = ")
        # and in the log, in one line
        line = f"sensitivity: {method}: {failed.sum()} of {rows} evaluations failed; first: stand-in failure"
        assert any(line in r.getMessage() for r in caplog.records), line
    assert ds.attrs["failed_evaluations"] == int(ds["morris_failed"].sum() + ds["sobol_failed"].sum())
    # Morris: the whole trajectories, whose elementary effects of the linear model are exact
    fhm = ds.sel(output="fhm_flying")
    assert 2 <= int(fhm["morris_used"]) < 20
    # tol: a linear model's elementary effects: exact up to tens of roundings of the span
    np.testing.assert_allclose(fhm["mu_star"].values, np.abs(A) * 2 * math.pi, rtol=1e-9)
    # Sobol: the whole blocks; the failures depend on the first parameter alone, so the blocks kept still
    # sample the others uniformly: the fourth (unused) has no index
    force = ds.sel(output="contact_force")
    used = int(force["sobol_used"])
    assert 0.4 * 256 < used < 0.8 * 256  # (a block is whole when both its A and B rows have x0 <= pi/2)
    assert np.all(np.isfinite(force["ST"].values)) and np.all(np.isfinite(force["S1"].values))
    assert f"over {used} of 256 Saltelli blocks" in str(force["sobol_note"].values)
    assert abs(float(force["ST"][3])) < 1e-9
    # (the first parameter is now on [-pi, pi/2], so Ishigami's published values do not apply; the second's
    # term 7 sin^2 is additive, so its first-order and total indices are equal within sampling error)
    assert abs(float(force["S1"][1]) - float(force["ST"][1])) < 0.08
    from cf_check import cf_report
    failures, crashed = cf_report(nc)
    assert crashed == [] and failures[3] == [] and failures[2] == [], failures


def unit_box_array(X: np.ndarray) -> np.ndarray:
    """The first parameter (dmw.rms_nm, 0.08-0.30) of the samples ``X`` on [-pi, pi]."""
    return -math.pi + 2 * math.pi * (X[:, 0] - 0.08) / (0.30 - 0.08)


def test_indices_undefined_without_whole_trajectories_say_why(write_scene, paper_config, tmp_path):
    # every evaluation fails: no index exists, the dataset, the log and the figure say why
    def all_fail(base, params, rows, protrusions, inputs):
        out = stub_batch(base, params, rows, protrusions, inputs)
        for _, rec in out:
            rec["outputs"], rec["error"] = {}, "no model"
        return out
    text = SCENE.format(paper=paper_config).replace("sobol_samples = 1024", "sobol_samples = 8")
    nc = ensure("sensitivity", load_scene(write_scene(text)), tmp_path / "out", scheduler="synchronous", task=all_fail)
    ds = xr.open_dataset(nc, engine="netcdf4")
    assert np.all(np.isnan(ds["mu_star"].values)) and np.all(np.isnan(ds["ST"].values))
    assert ds.attrs["failed_evaluations"] == 20 * 5 + 8 * 6
    assert str(ds["morris_note"].sel(output="touchdown").values).startswith("undefined: 0 of 20 trajectories whole")
    assert str(ds["sobol_note"].sel(output="touchdown").values).startswith("undefined: 0 of 8 Saltelli blocks whole")
    assert (tmp_path / "out" / "figures" / "sensitivity.png").stat().st_size > 0


# ------------------------------------------------------------------------------------- the box check
def test_the_shipped_default_bounds_pass_the_box_check(paper_scene):
    from pipeline.analyses import feasibility
    for section in ("sensitivity", "identify"):
        feasibility.check_study(paper_scene, section)  # (raises on an infeasible bound or corner)
    # the default summit density starts above McCool's limit for the paper's sigma and R
    from pipeline.physics.asperity_statistics import ALPHA_MIN
    density = next(p for p in paper_scene["sensitivity"]["parameters"] if p["key"] == "roughness.summit_density_per_um2")
    limit = math.sqrt(ALPHA_MIN / 2412.74) / (0.52e-9 * 5e-6) * 1e-12  # [um^-2]
    assert limit == pytest.approx(7.415, abs=1e-3) and density["low"] > limit


def density_box(paper_config, low: float) -> str:
    return f"""
[scene]
name = "box"
extends = "{paper_config}"

[sensitivity]
parameters = [{{key = "dmw.rms_nm", low = 0.08, high = 0.30}},
              {{key = "roughness.summit_density_per_um2", low = {low}, high = 20.0}}]
"""


def test_a_density_below_mccools_limit_is_refused_with_the_limit(write_scene, paper_config):
    from pipeline.analyses import feasibility
    from pipeline.config.scene import SceneError
    path = write_scene(density_box(paper_config, 5.0))
    with pytest.raises(SceneError) as err:
        feasibility.check_study(load_scene(path), "sensitivity")
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"{path}: sensitivity.parameters: roughness.summit_density_per_um2 "
                                              "low bound 5 is infeasible: McCool's bandwidth alpha = 0.408 < 0.8968")
    # the limit, found by bisection between the bound and the scene's 13.3: McCool's sqrt(0.8968/2412.74)/(sigma R)
    limit = float(msg.rsplit("feasible from about ", 1)[1].split()[0])
    assert limit == pytest.approx(math.sqrt(0.8968 / 2412.74) / (0.52e-9 * 5e-6) * 1e-12, abs=2e-3)
    feasibility.check_study(load_scene(write_scene(density_box(paper_config, 7.5))), "sensitivity")


def test_an_infeasible_corner_names_the_bounds_that_fail_together(write_scene, paper_config):
    from pipeline.analyses import feasibility
    from pipeline.config.scene import SceneError
    text = f"""
[scene]
name = "box"
extends = "{paper_config}"

[identify]
parameters = [{{key = "air_bearing.damping_ratio", low = 0.01, high = 0.2}},
              {{key = "air_bearing.frequencies_khz[0]", low = 60.0, high = 200.0}},
              {{key = "air_bearing.frequencies_khz[1]", low = 210.0, high = 500.0}}]
"""
    with pytest.raises(SceneError) as err:
        feasibility.check_study(load_scene(write_scene(text)), "identify")
    # each bound alone is feasible (200/300 and 120/210 kHz); 200/210 kHz has no real stiffness pair
    msg = str(err.value)
    assert ("the corner air_bearing.frequencies_khz[0] high bound 200, air_bearing.frequencies_khz[1] low bound 210 "
            "is infeasible: no real air-bearing stiffness") in msg and "damping_ratio" not in msg


def test_the_cli_refuses_an_infeasible_box_in_one_line_and_writes_nothing(write_scene, paper_config, tmp_path, capsys):
    from pipeline import cli
    out = tmp_path / "out"
    code = cli.main(["sensitivity", str(write_scene(density_box(paper_config, 5.0))), "--out", str(out)])
    err = capsys.readouterr().err
    assert code != 0 and "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "roughness.summit_density_per_um2 low bound 5 is infeasible" in lines[0]
    assert not out.exists()


def test_a_plasticity_index_past_the_hardness_limit_is_refused(write_scene, paper_config):
    # H derived from psi: H/E' = sqrt(sigma_s/R)/psi, below the physical 1e-3 for psi > sqrt(sigma_s/R)/1e-3
    from pipeline.analyses import feasibility
    from pipeline.config.scene import SceneError
    from pipeline.physics.asperity_statistics import explicit_statistics
    from pipeline.physics.material_bounds import HARDNESS_RATIO_BOUNDS
    st = explicit_statistics(0.52e-9, 5.0e-6, 13.3 / 1e-12)
    limit = math.sqrt(st["sigma_s"] / st["R"]) / HARDNESS_RATIO_BOUNDS[0]
    text = f"""
[scene]
name = "box"
extends = "{paper_config}"

[identify]
parameters = [{{key = "materials.plasticity_index", low = 0.1, high = 20.0}}]
"""
    with pytest.raises(SceneError) as err:
        feasibility.check_study(load_scene(write_scene(text)), "identify")
    msg = str(err.value)
    assert "materials.plasticity_index high bound 20 is infeasible: plasticity limits: hardness" in msg
    assert float(msg.rsplit("feasible up to about ", 1)[1]) == pytest.approx(limit, rel=1e-3)
