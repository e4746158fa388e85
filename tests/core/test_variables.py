"""The variable schema and CF compliance: every variable every stage writes is declared (with the
units it is written in), and the CF-1.8 compliance checker finds no error in any dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cf_check import cf_report
from pipeline import variables as vs
from pipeline.encoding import OLD_TIME_UNITS
from pipeline.io import read_dataset, write_dataset
from pipeline.variables import TIME
from pipeline.config.scene import load_scene
from pipeline.stages import roughness, sweep
from pipeline.runner import ensure

ROOT = Path(__file__).resolve().parents[2]
AFM = ROOT / "tests" / "data" / "afm"

#: A small scene: 3 protrusions (one kept as history), short runs, fixed k (no calibration needed by
#: the sweep), and 2 roughness sets x 2 damping ratios so that the labels and grid dims are > 1.
SMALL = [
    "solver.duration_ms=0.6", "solver.transient_ms=0.2", "touchdown.curve_points=3", "contact.k=0.5",
    "sweep.protrusion_nm={start=9.5, stop=10.5, step=0.5}", "sweep.batch_size=3", "sweep.histories_nm=[10.0]",
    "report.histories_nm=[10.0]",
    'sweep.roughness=[{label="smooth", sigma_nm=0.4}, {label="rough", sigma_nm=0.6}]',
    "sweep.damping_ratio=[0.03, 0.05]",
]


@pytest.fixture(scope="module")
def datasets(tmp_path_factory) -> dict[str, Path]:
    """Every dataset of a small run: stage -> file (accuracy.nc is checked in stages/test_accuracy.py)."""
    out = tmp_path_factory.mktemp("small")
    scene = load_scene(ROOT / "configs" / "paper-2009.toml", SMALL)
    paths = {
        "dmw": ensure("dmw", scene, out),
        "interface": ensure("interface", scene, out),
        "calibration": ensure("calibrate", scene, out),
        "histories": ensure("simulate", scene, out),
        "summary": out / "summary.nc",
        "sweep": sweep.run_sweep(scene, out, scheduler="synchronous"),
        "sweep_histories": out / "sweep_histories.nc",
        "sweep-part": out / sweep.PARTS / "batch-00000.nc",
    }
    # several AFM surfaces: string labels of length > 1 on two dims (this crashed the checker once)
    paths["roughness"] = roughness.run_files([AFM / "di-3.di", AFM / "mi-1.mi"], out / "afm")
    return paths


def test_every_written_variable_is_declared_with_its_units(datasets):
    for dataset, path in datasets.items():
        ds = read_dataset(path)
        for name in list(ds.coords) + list(ds.data_vars):
            decl = vs.declared(dataset, name)
            assert ds[name].attrs.get("units", "") == decl.units, (dataset, name)
            assert ds[name].attrs["long_name"].startswith(decl.long_name.split(" (")[0]), (dataset, name)
            assert ds[name].dims[len(ds[name].dims) - len(decl.dims):] == decl.dims, (dataset, name)


def test_effects_off_leave_their_variables_out(datasets, tmp_path):
    """Variables declared for an effect the scene lacks are absent (and the rest is declared)."""
    scene = load_scene(ROOT / "configs" / "paper-2009.toml",
                       SMALL + ['scene.effects=["air_bearing","pitch","dmw","contact"]'])
    ensure("simulate", scene, tmp_path)
    ds = read_dataset(tmp_path / "summary.nc")
    absent = {n for n, v in vs.SCALARS.items() if v.effect in ("friction", "adhesion")}
    assert absent == {"friction_force", "adhesion_force", "friction_coefficient", "shear_stress", "thermal_protrusion",
                      "friction_power", "flash_temperature"}
    assert not absent & set(ds.data_vars)
    assert {"contact_force", "regime", "interference"} <= set(ds.data_vars)


#: The datasets of :func:`datasets` (one checker run each, about 3 s on a loaded 2-core machine).
DATASETS = ("roughness", "dmw", "interface", "calibration", "histories", "summary", "sweep", "sweep_histories",
            "sweep-part")


@pytest.mark.parametrize("dataset", DATASETS)
def test_cf_checker_finds_no_error(datasets, dataset):
    """No high-priority failure and no crashed check; what remains at medium/low priority today is
    nothing either (asserted, so a regression shows up here)."""
    failures, crashed = cf_report(datasets[dataset])
    assert crashed == []
    assert failures[3] == []
    assert failures[2] + failures[1] == []


def test_time_is_plain_seconds_under_xarrays_default_decoding(datasets):
    """``time`` was stored as ``s since 1970-01-01``: the default ``xr.open_dataset`` decoded it to
    datetimes at 1 us, merging the 250 ns samples (8001 -> 2001) so that ``.sel`` hit several rows."""
    path = datasets["sweep_histories"]
    n = read_dataset(path).sizes[TIME]
    with xr.open_dataset(path, engine="netcdf4") as raw:  # xarray's defaults, as a user opens it
        t = raw[TIME]
        assert t.dtype == np.float64 and t.attrs["units"] == "s"
        assert "since" not in t.attrs["units"] and "standard_name" not in t.attrs
        assert np.unique(t.values).size == n == t.size
        # the output step of the scene (solver.output_step_ns = 250) in seconds
        # tol: steps of a time grid: rounding of t_i (t/step < 1e4) over the step
        np.testing.assert_allclose(np.diff(t.values), 250e-9, rtol=1e-9)
        row = raw["separation"].sel({TIME: float(t[7])})
        assert TIME not in row.dims  # one sample, not several
    ds = read_dataset(path)
    assert ds[TIME].attrs["units"] == "s"
    np.testing.assert_allclose(ds[TIME].values, t.values, rtol=0, atol=0)  # tol: NetCDF stores float64 as it is: exact


def test_dmw_time_is_plain_seconds_and_a_dmw_dataset_reads_back_as_a_record(datasets):
    from pipeline.model.measured_dmw import load_record
    with xr.open_dataset(datasets["dmw"], engine="netcdf4") as raw:
        t = raw[TIME].values
        assert t.dtype == np.float64 and np.unique(t).size == t.size
        rate = 1 / float(np.median(np.diff(t)))
    # tol: a median step of the grid: rounding of t_i (t/step < 1e4) over the step
    assert rate == pytest.approx(4e6, rel=1e-9)  # dmw.sample_rate_mhz = 4
    rec = load_record(datasets["dmw"], column="displacement")
    assert rec.sample_rate_hz == pytest.approx(4e6, rel=1e-9)  # tol: the record's rate from its step, a few roundings


def test_coordinates_have_no_fill_value(datasets):
    import netCDF4
    for dataset, path in datasets.items():
        with netCDF4.Dataset(path) as nc:
            for dim in nc.dimensions:
                if dim in nc.variables:
                    assert "_FillValue" not in nc.variables[dim].ncattrs(), (dataset, dim)


def test_regime_is_an_intenum_with_a_declared_missing_value(tmp_path):
    assert [(r.name, int(r)) for r in vs.Regime] == [("FLYING", 0), ("BOUNCING", 1), ("SURFING", 2)]
    decl = vs.SCALARS["regime"]
    assert decl.flag_values == (0, 1, 2) and decl.flag_meanings == "flying bouncing surfing"
    assert decl.fill_value not in decl.flag_values
    # a grid point not computed (NaN) is written as the declared _FillValue and read back as NaN
    ds = xr.Dataset({"regime": vs.scalar("regime", np.array([0, np.nan, 2]), ("protrusion",))},
                    coords={"protrusion": vs.coordinate("protrusion", [1.0, 2.0, 3.0])})
    path = write_dataset(ds, tmp_path / "summary.nc", stage="simulate")
    with xr.open_dataset(path, engine="netcdf4", mask_and_scale=False) as raw:
        assert raw["regime"].dtype == np.int8
        assert raw["regime"].values.tolist() == [0, vs.REGIME_FILL, 2]
        assert raw["regime"].attrs["_FillValue"] == vs.REGIME_FILL
    back = read_dataset(path)["regime"].values
    assert back[0] == 0 and np.isnan(back[1]) and back[2] == 2
    assert [vs.regime_name(c) for c in back] == ["flying", "missing", "surfing"]
    failures, crashed = cf_report(path)
    assert failures[3] == [] and crashed == []


def test_roughness_route_dimension_works_with_sel(datasets):
    """The former ``method`` dimension collided with ``sel(method=...)``; ``route`` does not."""
    ds = read_dataset(datasets["roughness"])
    assert ds["sigma"].dims == ("surface", "route")
    assert list(ds["route"].values) == ["spectral", "summits"]
    assert list(ds["surface"].values) == ["di-3", "mi-1", "combined"]
    row = ds.sel(surface="combined", route="spectral")
    # combined sigma: quadrature sum of the two scans' (docs/model.md, section "Asperity statistics")
    s = ds["sigma"].sel(route="spectral").values
    # tol: hypot against the combined moments' square root, a few roundings
    assert float(row["sigma"]) == pytest.approx(float(np.hypot(s[0], s[1])), rel=1e-9)
    assert "method" not in ds.dims  # sel's own method= keyword is free again


def test_scaling_from_si_matches_the_declared_units():
    """``from_si`` multiplies by si_factor: 1 mN = 1e-3 N, 1 um2 = 1e-12 m2, 1 MPa = 1e6 Pa."""
    assert float(vs.scalar("contact_force", 2.5e-3, ()).values) == pytest.approx(2.5)
    assert float(vs.scalar("real_area", 3e-12, ()).values) == pytest.approx(3.0)
    assert float(vs.scalar("mean_pressure", 4.2e8, ()).values) == pytest.approx(420.0)
    assert float(vs.history("separation", 1.5e-9, ()).values) == pytest.approx(1.5)


#: Variables the model computes in percent already (FHM/BV, docs/model.md "FHM and BV"): their
#: ``si_unit`` is 1 against the unit ``%`` on purpose.
PERCENT_FROM_MODEL = {"fhm_bv", "reference_fhm_bv", "fhm_bv_mean", "fhm_bv_std"}


def test_every_declared_unit_is_read_by_pint_with_its_si_factor():
    """Every unit string of the schema parses in cf_xarray's pint registry (the one the README names),
    and converts to SI base units by exactly the factor ``si_unit`` the writer divides by."""
    from cf_xarray.units import units as ureg
    checked = 0
    for group in vs.GROUPS.values():
        for name, v in group.items():
            if v.dtype == "str" or v.flag_values is not None or v.flag_masks is not None:
                continue
            factor = float(ureg.Quantity(1.0, v.units or "1").to_base_units().magnitude)
            expected = 0.01 if name in PERCENT_FROM_MODEL else v.si_unit
            # tol: pint's factor against the unit table's decimal, a few roundings
            assert factor == pytest.approx(expected, rel=1e-12), (name, v.units)
            checked += 1
    assert checked > 100


def test_pint_quantify_works_on_every_dataset(datasets):
    """``import cf_xarray.units, pint_xarray`` then ``ds.pint.quantify()`` on each stage's dataset:
    every variable becomes a quantity in its declared unit (a clearance converts to metres by 1e-9)."""
    import cf_xarray.units  # noqa: F401 (registers the UDUNITS-style registry with pint-xarray)
    import pint_xarray  # noqa: F401 (the .pint accessor)
    from cf_xarray.units import units as ureg
    for dataset, path in datasets.items():
        with xr.open_dataset(path) as ds:
            q = ds.pint.quantify()
            for name, var in ds.data_vars.items():
                if "units" in var.attrs and "flag_values" not in var.attrs and "flag_masks" not in var.attrs:
                    assert q[name].pint.units == ureg.Unit(var.attrs["units"] or "1"), (dataset, name)
    with xr.open_dataset(datasets["summary"]) as ds:
        q = ds.pint.quantify()
        metres = q["min_clearance"].pint.to("m").pint.magnitude
        # tol: pint's factor 1e-9 against the literal, IEEE arithmetic alone: an ulp or two
        np.testing.assert_allclose(metres, ds["min_clearance"].values * 1e-9, rtol=1e-15)


def test_one_name_for_the_elapsed_time_in_memory_and_in_the_files(datasets, tmp_path):
    """``xr.open_dataset``, ``hdi.open_dataset`` and ``simulate`` all give the time as ``elapsed_time``."""
    assert TIME == "elapsed_time"
    for dataset in ("dmw", "histories", "sweep_histories", "sweep-part"):
        with xr.open_dataset(datasets[dataset], engine="netcdf4") as raw:
            assert TIME in raw.dims and "time" not in raw.variables, dataset
        assert TIME in read_dataset(datasets[dataset]).dims, dataset
    # a file written before (coordinate ``time``, and before that in ``s since 1970-01-01``) reads under the one name
    old = read_dataset(datasets["histories"]).rename({TIME: "time"})
    del old.attrs["data_checksums"]                       # (a file of that time: written before the checksums)
    for units in ("s", OLD_TIME_UNITS):
        old["time"].attrs["units"] = units
        old.to_netcdf(tmp_path / "old.nc", engine="netcdf4")
        back = read_dataset(tmp_path / "old.nc")
        assert TIME in back.dims and back[TIME].attrs["units"] == "s"
        np.testing.assert_array_equal(back[TIME].values, old["time"].values)


#: The longest ``long_name`` (a plot's axis label with its units; the sentence is the ``description``).
LONG_NAME_MAX = 40


def test_long_names_are_short_and_the_sentence_is_the_description(datasets):
    """long_names fit a plot label (a whole sentence, up to 140 characters, would clip it): the sentence is the
    description."""
    for group, variables in vs.GROUPS.items():
        for name, v in variables.items():
            assert 0 < len(v.long_name) <= LONG_NAME_MAX, (group, name, v.long_name)
            assert v.description != v.long_name, (group, name)
    assert vs.SCALARS["fhm_bv"].long_name == "FHM/BV"
    assert vs.SCALARS["fhm_bv"].description.startswith("flying-height modulation (flying) / bouncing vibration")
    for dataset, path in datasets.items():
        ds = read_dataset(path)
        for name in list(ds.coords) + list(ds.data_vars):
            decl = vs.declared(dataset, name)
            assert ds[name].attrs.get("description", "").startswith(decl.description), (dataset, name)


def test_cf_xarray_finds_the_separation_axis(datasets):
    import cf_xarray  # noqa: F401 (registers the .cf accessor)
    with xr.open_dataset(datasets["interface"], engine="netcdf4") as raw:
        assert raw.cf.axes == {"Z": ["separation"]}
        assert raw.cf["Z"].attrs["positive"] == "up"
        np.testing.assert_array_equal(raw.cf["Z"].values, raw["separation"].values)


#: The variables whose name says they come from a published formula (a pressure, stress, force, area, the
#: asperity statistics and plasticity indices, FHM/BV, the contact criterion k and what it decides, the air
#: bearing's and the bulge's laws, the statics' barriers): each must cite its sources (CF ``references``).
FROM_A_FORMULA = (r"pressure|stress|force|real_area|fhm|plasticity|interference|shear_strength|^k$|^k_|sigma_s|^y_s$"
                  r"|summit_(radius|density|offset)|bandwidth|lift|bearing_number|barrier|stiffness|damper$"
                  r"|heater_power|clearance|contact_probability|touchdown|^regime$|in_contact|contact_fraction")
#: Names that match :data:`FROM_A_FORMULA` but whose values no published formula of docs/model.md gives, and why.
NO_FORMULA = {
    "pad_pressure": "the scene's air pressure under the trailing pad, an input",
    "tfc_stiffness": "the scene's stiffening k_t, an input",
    "contact_damping_force": "the contact damping c_c dd/dt, the model's own [recon] term",
    "k_source": "where k comes from: a label",
    "solved_contact_pressure": "the deterministic solve, whose sources docs/deterministic_interface.md gives",
    "solved_real_area_fraction": "the deterministic solve, whose sources docs/deterministic_interface.md gives",
}


def test_every_variable_from_a_published_formula_cites_its_sources_as_docs_model_md_does():
    import re
    from pipeline.cf_variable import CITATIONS
    model = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    listed = dict(re.findall(r"^- \[([^\]]+)\] (.*(?:\n  .*)*)", model[model.index("\n## References\n"):], re.M))
    headings = set(re.findall(r"^#{2,3} (.+)$", model, re.M))
    for key, text in CITATIONS.items():                     # each source word for word as docs/model.md lists it
        assert " ".join(listed[key].split()) == text, key
    cited = 0
    for group, variables in vs.GROUPS.items():
        for name, v in variables.items():
            if re.search(FROM_A_FORMULA, name) and NO_FORMULA.get(name) is None:
                assert v.references is not None, (group, name)
            if v.references is not None:
                cited += 1
                assert v.references.section in headings, (group, name, v.references.section)
                text = v.attrs()["references"]
                assert all(f"[{k}] {CITATIONS[k].removesuffix('.')}" in text for k in v.references.keys)
                assert text.endswith(f'(docs/model.md, section "{v.references.section}")')
    assert cited > 100
    assert vs.SCALARS["fhm_bv"].attrs()["references"].startswith("[VLP09] A. I. Vakis, S.-C. Lee, A. A. Polycarpou")
    assert vs.INTERFACE["plasticity_index_gw"].attrs()["references"] == (
        '[GW66] J. A. Greenwood, J. B. P. Williamson, "Contact of nominally flat surfaces", Proc. R. Soc. Lond. A 295 '
        '(1966) 300-319 (docs/model.md, section "Plasticity index")')


def test_the_sources_reach_the_written_datasets(datasets):
    """Every written variable carries its declaration's ``references`` (and none that its declaration lacks): the
    attribute changes no number (the CF checker's run on these files: test_cf_checker_finds_no_error)."""
    carried = 0
    for dataset, path in datasets.items():
        ds = read_dataset(path)
        for name in list(ds.coords) + list(ds.data_vars):
            decl = vs.declared(dataset, name)
            assert ds[name].attrs.get("references") == decl.attrs().get("references"), (dataset, name)
            carried += "references" in ds[name].attrs
    assert carried > 50
