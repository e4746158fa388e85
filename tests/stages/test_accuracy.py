"""The accuracy stage on a tiny configuration: dataset layout, zero error of a re-run of the reference,
errors shrinking as the tolerance tightens, the chosen defaults and the work-precision figure."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import knob_study as knob_study
from pipeline.io import check_cf
from pipeline.config.scene import load_scene
from pipeline.stages import accuracy
from pipeline.runner import ensure

#: A light reference and two settings per knob (three for rtol, to see a trend).
REFERENCE = {"table_step_nm": 0.005, "quadrature_nodes": 16, "quadrature_panels": 2, "sample_rate_mhz": 8.0}
KNOBS = {"rtol": [1e-9, 1e-7, 1e-5], "max_step_ns": [25.0, 250.0], "stiffness_step": [0.25, 1.0],
         "table_step_nm": [0.005, 0.02],
         "interpolation_order": [3, 1], "quadrature_nodes": [16, 8], "quadrature_panels": [2, 1],
         "sample_rate_mhz": [8.0, 4.0], "min_dwell_ns": [1.0, 20.0]}


@pytest.fixture(scope="module")
def result(tmp_path_factory, paper_config):
    out = tmp_path_factory.mktemp("accuracy")
    scene = load_scene(paper_config, ["solver.duration_ms=0.6", "solver.transient_ms=0.2", "contact.k=0.445"])
    runs = []  # (configuration, Result) of every evaluation, to see which runs the rows come from
    evaluate = accuracy._evaluate

    def spy(scene, values, *args):
        res = evaluate(scene, values, *args)
        runs.append((dict(values), res))
        return res

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(accuracy, "_evaluate", spy)
        path = ensure("accuracy", scene, out, reference=REFERENCE, knobs=KNOBS, repeat=1)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        ds = ds.load()
    return out, path, ds, runs


def test_dataset_layout(result):
    out, path, ds, _ = result
    assert path == out / "accuracy.nc"
    assert dict(ds.sizes) == {"point": 3, "knob": len(KNOBS), "level": 3, "output": len(knob_study.HEADLINE),
                              "configuration": 2}
    # every knob but the deterministic interface's grid (only for interface.model = "deterministic")
    assert list(ds["knob"].values) == [kb.name for kb in knob_study.KNOBS if kb.name != "contact_grid_points"]
    assert list(ds["point"].values) == ["flying", "touchdown", "sliding"]
    # tol: the scene's protrusions written as they are
    np.testing.assert_allclose(ds["protrusion"].values, [5.0, 7.6, 11.0])
    assert ds["error"].dims == ("point", "knob", "level", "output")
    assert ds["wall_time"].dims == ("point", "knob", "level")
    assert ds["error"].attrs["units"] == "1" and ds["wall_time"].attrs["units"] == "s"
    assert ds["fhm_bv"].attrs["units"] == "%" and ds["reference_clearance"].attrs["units"] == "nm"
    check_cf(ds)  # units and long_name on every variable and coordinate
    assert all(len(ds[v].attrs["long_name"]) <= 40 for v in ds.variables), \
        [(v, ds[v].attrs["long_name"]) for v in ds.variables if len(ds[v].attrs["long_name"]) > 40]
    assert ds["passes"].attrs["description"].startswith("every headline error below")
    assert ds.attrs["stage"] == "accuracy"
    # settings per knob, NaN-padded
    # tol: the knob's settings written as they are
    np.testing.assert_allclose(ds["setting"].sel(knob="rtol").values, KNOBS["rtol"])
    assert np.isnan(ds["setting"].sel(knob="interpolation_order").values[2])
    assert (ds["wall_time"].values[np.isfinite(ds["setting"].values)[None].repeat(3, 0)] > 0).all()


def test_reference_setting_has_zero_error(result):
    _, _, ds, runs = result
    ref = ds["is_reference"].values.astype(bool)
    # every knob but the step-size controllers (whose rows move the other controllers) contains it
    names = list(ds["knob"].values)
    for name in set(names) - {"rtol", "max_step_ns", "stiffness_step"}:
        assert ref[names.index(name), 0], name
    # the rows equal to the reference are a fresh run of it (not a copy): zero error is determinism.
    # The reference configuration runs three times: untimed (compilation), timed, and for those rows.
    full = {**knob_study.REFERENCE, **REFERENCE}
    at_ref = [res for cfg, res in runs if cfg == full]
    assert len(at_ref) == 3 and len({id(r) for r in at_ref}) == 3
    for j, name in enumerate(knob_study.HEADLINE):
        np.testing.assert_array_equal(ds[f"reference_{name}"].values, at_ref[1].values[:, j])
        np.testing.assert_array_equal(ds[name].values[:, ref], np.repeat(at_ref[2].values[:, j, None], ref.sum(), 1))
    err = ds["error"].values[:, ref, :]
    assert np.all((err == 0) | np.isnan(err))
    assert (ds["steps"].values[:, ref] > 0).all() and (ds["simulation_time"].values[:, ref] > 0).all()
    # and the measure sees a change: every other setting errs at some point
    other = ~ref & np.isfinite(ds["setting"].values)
    worst = np.nanmax(ds["max_error"].values[:, other], axis=0)
    assert np.all(worst > 0), dict(zip(np.array(names)[np.nonzero(other)[0]], worst))
    # outputs that do not apply while flying are NaN, not errors
    flying = ds["error"].sel(point="flying", knob="table_step_nm", level=1)
    assert np.isnan(flying.sel(output="interference")) and np.isnan(flying.sel(output="friction_coefficient"))
    assert np.isfinite(flying.sel(output="fhm_bv"))


def test_error_decreases_as_rtol_tightens(result):
    _, _, ds, _ = result
    e = ds["max_error"].sel(knob="rtol").values[:, :3]  # (point, level): rtol 1e-9, 1e-7, 1e-5
    assert np.all(np.isfinite(e))
    # monotone within noise (a factor 2, or 1e-5 absolute where the error is at round-off level:
    # in contact the integrator's stiffness step cap, not the tolerance, may set the step)
    for p in range(e.shape[0]):
        assert e[p, 1] >= 0.5 * e[p, 0] - 1e-5 and e[p, 2] >= 0.5 * e[p, 1] - 1e-5, e[p]
    assert e[:, 0].max() < 1e-4
    # flying, the tolerance alone sets the step: a clear trend over four decades in the global error,
    # seen in the time-mean clearance (every step's error adds to it). Not in the maximum over the
    # outputs, which is FHM's: a peak-to-peak is the error at two instants, a random-signed local error
    # that does not fall monotonically with rtol (flying at 5 nm from the static start, vs rtol 1e-10:
    # 1.7e-4 at rtol 1e-7, 1.4e-3 at 1e-6, 7.5e-4 at 1e-5; the mean clearance 8.8e-7, 7.0e-6, 6.6e-5 nm)
    c = ds["error"].sel(knob="rtol", point="flying", output="clearance").values[:3]
    assert c[2] > c[1] > c[0] and c[2] > 30 * c[0], c


def test_chosen_defaults_and_figure(result):
    out, _, ds, _ = result
    chosen = json.loads(ds.attrs["chosen_defaults"])
    assert set(chosen) == set(KNOBS)
    for name, value in chosen.items():
        lvl = int(ds["chosen_level"].sel(knob=name))
        if value is None:
            assert lvl == -1
            continue
        assert value == pytest.approx(float(ds["setting"].sel(knob=name).values[lvl]))
        assert ds["passes"].sel(knob=name).values[lvl] == 1
    # the chosen settings are checked together, against a tenth of the tolerance
    assert ds["combined_max_error"].dims == ("configuration", "point")
    assert float(ds.attrs["combined_tolerance"]) == pytest.approx(0.1 * float(ds.attrs["tolerance"]))
    assert (ds["combined_max_error"].sel(configuration="chosen").values < float(ds.attrs["combined_tolerance"])).all()
    fig = out / "figures" / "work_precision.png"
    assert fig.is_file() and fig.stat().st_size > 10_000
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_accuracy_dataset_is_declared_and_cf_clean(result):
    """Every variable of accuracy.nc is declared in the variable schema with its units, and the CF-1.8
    compliance checker finds nothing (the knob settings, whose units differ per knob, name the variable
    holding their units instead of a wrong common one)."""
    from cf_check import cf_report
    from pipeline.io import read_dataset
    from pipeline.variables import declared

    _, path, _, _ = result
    ds = read_dataset(path)
    for name in list(ds.coords) + list(ds.data_vars):
        assert ds[name].attrs.get("units", "") == declared("accuracy", name).units, name
    assert ds["setting"].attrs["unit_variable"] == "setting_units"
    failures, crashed = cf_report(path)
    assert crashed == [] and failures[3] == [] and failures[2] + failures[1] == []
