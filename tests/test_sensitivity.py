"""hdi sensitivity: Morris and Sobol indices through the evaluation path, checked on models with known indices.

The stand-in batch function replaces the slider (the statistics are what is tested; the slider's own
evaluation is tested in test_identify.py): the flying FHM is a linear model ``sum a_i x_i`` (exact
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
from pipeline.stages import sensitivity

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
    nc = sensitivity.run(scene, tmp_path / "out", scheduler="synchronous", task=stub_batch)
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
    np.testing.assert_allclose(td["mu_star"].values, 0.0)
    # every sample ran and every index uses every sample
    assert ds.attrs["failed_evaluations"] == 0 and int(ds["morris_failed"].sum()) == 0
    assert np.all(ds["morris_used"].values == 20) and np.all(ds["sobol_used"].values == 1024)
    for v in list(ds.data_vars) + list(ds.coords):
        assert "long_name" in ds[v].attrs, v
        assert "units" in ds[v].attrs or "unit_variable" in ds[v].attrs or ds[v].dtype.kind in "OUS", v
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
    ds = xr.open_dataset(sensitivity.run(scene, tmp_path / "out", scheduler="synchronous", task=stub_with_holes),
                         engine="netcdf4")
    force, fhm = ds.sel(output="contact_force"), ds.sel(output="fhm_flying")
    used, undefined = int(force["morris_used"]), int(force["morris_undefined_samples"])
    assert 2 <= used < 20 and undefined > 0
    assert np.all(np.isfinite(force["mu_star"].values))
    assert f"over {used} of 20 trajectories" in str(force["morris_note"].values)
    # the output without holes keeps every trajectory and its exact indices
    assert int(fhm["morris_used"]) == 20 and str(fhm["morris_note"].values) == ""
    np.testing.assert_allclose(fhm["mu_star"].values, np.abs(A) * 2 * math.pi, rtol=1e-9)


def test_screening_takes_any_outputs_callable():
    # the algorithms (analyses) on a plain function: y = 2 x0 over x0 in [0, 1], x1 not seen
    from pipeline.analyses import screening, study
    params = [study.Parameter("dmw.rms_nm", 0.0, 1.0), study.Parameter("air_bearing.damping_ratio", 0.0, 0.5)]

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
