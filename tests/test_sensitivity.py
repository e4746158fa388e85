"""hdi sensitivity: Morris and Sobol indices through the evaluation path, checked on models with known indices.

The stand-in batch function replaces the slider (the statistics are what is tested; the slider's own
evaluation is tested in test_identify.py): the flying FHM is a linear model ``sum a_i x_i`` (exact
indices: ``S1_i = ST_i = a_i^2 / sum a_j^2`` for equal ranges, Morris ``mu*_i = |a_i| (high - low)``,
``sigma_i = 0``) and the contact force at 11 nm is the Ishigami function (Ishigami & Homma 1990;
``S1 = (0.3139, 0.4424, 0)``, ``ST = (0.5576, 0.4424, 0.2437)``); the fourth parameter enters neither.
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


def stub_batch(base, params, rows, protrusions, inputs):
    p = np.asarray(protrusions)
    n = len(p)
    out = []
    for key, x in rows:
        x = np.asarray(x, float)
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
parameters = [{{key = "dmw.exponent", low = -3.141592653589793, high = 3.141592653589793}},
              {{key = "contact.k", low = -3.141592653589793, high = 3.141592653589793}},
              {{key = "air_bearing.rear_exponent", low = -3.141592653589793, high = 3.141592653589793}},
              {{key = "lubricant.intermolecular_distance_nm", low = -3.141592653589793, high = 3.141592653589793}}]
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
    # linear model: Morris exact, Sobol within sampling error
    np.testing.assert_allclose(ds["mu_star_fhm_flying"].values, np.abs(A) * span, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ds["sigma_fhm_flying"].values, 0.0, atol=1e-9)
    exact = A**2 / np.sum(A**2)
    np.testing.assert_allclose(ds["S1_fhm_flying"].values, exact, atol=0.03)
    np.testing.assert_allclose(ds["ST_fhm_flying"].values, exact, atol=0.03)
    # Ishigami: published indices; the unused parameter gets ~0
    np.testing.assert_allclose(ds["S1_contact_force"].values, S1_ISHIGAMI, atol=0.05)
    np.testing.assert_allclose(ds["ST_contact_force"].values, ST_ISHIGAMI, atol=0.05)
    assert abs(float(ds["ST_contact_force"][3])) < 1e-9
    assert float(ds["mu_star_contact_force"][3]) == 0.0
    # the confidence intervals are reported and cover the exact first-order indices of the linear model
    assert np.all(np.abs(ds["S1_fhm_flying"].values - exact) <= ds["S1_conf_fhm_flying"].values + 0.01)
    assert np.all(ds["S1_conf_contact_force"].values[:3] > 0)
    # an output that does not vary (touchdown is 9.8 nm in every sample) has undefined Sobol indices
    assert np.all(np.isnan(ds["ST_touchdown"].values))
    np.testing.assert_allclose(ds["mu_star_touchdown"].values, 0.0)
    for v in ds.data_vars:
        assert "units" in ds[v].attrs and "long_name" in ds[v].attrs
    from cf_check import cf_report  # sensitivity.nc fits the ecosystem like the other datasets
    failures, crashed = cf_report(nc)
    assert crashed == [] and failures[3] == [] and failures[2] == [], failures


def stub_with_holes(base, params, rows, protrusions, inputs):
    """The linear stand-in, with no contact at 11 nm (undefined contact force) when x4 > 2."""
    out = stub_batch(base, params, rows, protrusions, inputs)
    for (_, x), (_, rec) in zip(rows, out):
        if x[3] > 2.0:
            rec["outputs"]["contact_force"] = [float("nan")] * len(rec["protrusions"])
    return out


def test_morris_leaves_out_trajectories_with_undefined_points(write_scene, paper_config, tmp_path):
    text = SCENE.format(paper=paper_config).replace("[sensitivity]", '[sensitivity]\nmethods = ["morris"]')
    scene = load_scene(write_scene(text))
    ds = xr.open_dataset(sensitivity.run(scene, tmp_path / "out", scheduler="synchronous", task=stub_with_holes),
                         engine="netcdf4")
    used = ds["mu_star_contact_force"].attrs["trajectories_used"]
    undefined = ds["mu_star_contact_force"].attrs["undefined_samples"]
    assert 2 <= used < 20 and undefined > 0
    assert np.all(np.isfinite(ds["mu_star_contact_force"].values))
    # the output without holes keeps every trajectory and its exact indices
    assert ds["mu_star_fhm_flying"].attrs["trajectories_used"] == 20
    np.testing.assert_allclose(ds["mu_star_fhm_flying"].values, np.abs(A) * 2 * math.pi, rtol=1e-9)


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
    assert idx["y"]["mu_star"] == pytest.approx([2.0, 0.0]) and idx["y"]["trajectories_used"] == 4
    X, Y, idx = screening.sobol(outputs, params, c)
    assert X.shape == (8 * 4, 2)
    # (8 base samples: the estimate of x0 is rough; the parameter no output sees has exactly none)
    assert idx["y"]["ST"][0] > 0.5 and idx["y"]["ST"][1] == 0.0 and idx["y"]["S1"][1] == 0.0
