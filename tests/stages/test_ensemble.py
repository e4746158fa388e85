"""The paper's targets judged over DMW realisations, end to end on a short scene: the ensemble
stage and the report's comparison (report.realisations), and identify's evaluations
(identify.realisations), against single-record runs of the same seeds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline import evaluations
from pipeline.analyses import ensemble_rules as en
from pipeline.analyses import study
from pipeline.config.scene import SceneError, load_scene
from pipeline.io import read_dataset
from pipeline.model import dmw_record
from pipeline.runner import build, ensure

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"
# short runs, k fixed (no calibration), a grid across this model's adhesive snap-in (~7.5 nm) and the
# paper's checks; three realisations
SHORT = ["contact.k=0.978", "solver.duration_ms=0.6", "solver.transient_ms=0.2",
         "sweep.protrusion_nm={start=6.0, stop=11.0, step=0.2}", "sweep.batch_size=26",
         "identify.flying_step_nm=3.0", "identify.bouncing_range_nm=[9.8, 10.2]"]


@pytest.fixture(scope="module")
def run3(tmp_path_factory):
    out = tmp_path_factory.mktemp("ens3")
    scene = load_scene(PAPER, SHORT + ["report.realisations=3"])
    build(["report"], scene, out)
    return scene, out


def test_ensemble_stage_runs_each_seed_as_a_single_record_run(run3, tmp_path):
    scene, out = run3
    ens = read_dataset(out / "ensemble.nc")
    seeds = dmw_record.realisation_seeds(scene["dmw"]["seed"], 3)
    assert ens["dmw_seed"].values.tolist() == seeds
    x = ens["protrusion"].values
    # the targets' protrusions and the window around the sweep's first contact
    for p in study.target_protrusions(study.targets(scene)):
        assert np.any(np.abs(x - p) < 1e-9), p
    sweep = read_dataset(out / "sweep.nc").squeeze()
    fc = float(sweep["protrusion"].values[np.flatnonzero(sweep["regime"].values > 0)[0]])
    assert np.any(np.abs(x - (fc - 1.0)) < 1e-9) and np.any(np.abs(x - (fc + 1.0)) < 1e-9)
    # realisation 0 is the sweep's own run, bit for bit (at the points both have; 4 nm is off the sweep's grid)
    common = [p for p in x if np.any(np.abs(sweep["protrusion"].values - p) < 1e-9)]
    assert len(common) == len(x) - 1
    np.testing.assert_array_equal(ens["fhm_bv"].sel(protrusion=common).values[:, 0],
                                  sweep["fhm_bv"].sel(protrusion=common).values)
    # realisation 2 equals a single-record evaluation of the scene with that seed
    sub = scene.replace(dmw={"seed": seeds[2]})
    inputs = evaluations.prepare_inputs(sub, tmp_path / "seed2")
    rec = evaluations.evaluate(sub, [], [], list(x), inputs)
    np.testing.assert_array_equal(ens["fhm_bv"].values[:, 2], rec["outputs"]["fhm_bv"])
    np.testing.assert_array_equal(ens["min_clearance"].values[:, 2], rec["outputs"]["min_clearance"])
    from cf_check import cf_report  # ensemble.nc passes the CF-1.8 checks like the other datasets
    failures, crashed = cf_report(out / "ensemble.nc")
    assert crashed == [] and failures[3] == [] and failures[2] == [], failures
    # the sweep's ensemble summaries: the probability is the fraction of seeds in contact
    # tol: the same mean of the same booleans
    np.testing.assert_allclose(ens["touchdown_probability"].values,
                               np.mean(ens["min_clearance"].values < 0, axis=1))


def test_report_shows_each_target_over_the_realisations_with_its_spread(run3):
    scene, out = run3
    ens = read_dataset(out / "ensemble.nc")
    text = (out / "report" / "comparison.md").read_text()
    assert "| quantity | paper | ours | difference | over 3 DMW realisations (spread) |" in text
    assert "## Paper targets over 3 DMW realisations" in text
    # the bouncing band over the realisations: the steps above 0.5 counted, and its figure drawn
    probs = ens["bv_exceedance_probability"].sel(protrusion=[10.0, 10.2]).values
    assert f"; {int(np.sum(probs > 0.5))} of the 2 steps above 0.5 (figure `band.png`)." in text
    from report_data import check_png
    check_png(out / "figures" / "band.png")
    td, lo, hi = en.touchdown_protrusion(ens["min_clearance"])
    assert np.isfinite(td) and lo <= td <= hi
    # long_names short enough for a plot label; the target's sentence is the description, which the report's table shows
    for name, v in ens.variables.items():
        assert len(v.attrs["long_name"]) <= 40, (name, v.attrs["long_name"])
    band = ens["value_bouncing"]
    assert band.attrs["long_name"] == "bouncing"  # (the target's name: its sentence is too long for a label)
    assert band.attrs["description"].startswith("bouncing BV over (9.8, 10.2] nm")
    assert f"| {band.attrs['description'].replace(' over the DMW realisations', '')} |" in text
    assert f"the touchdown protrusion over the realisations: {td:.4g} nm (10-90 %: {lo:.4g}-{hi:.4g})" in text
    assert f"| touchdown protrusion | 9.8 nm (none at 9.6 nm) | {td:.4g} nm (10-90 %: {lo:.4g}-{hi:.4g}) |" in text
    # the median FHM at 9 nm with its 10-90 % range, and the 11-nm interference as mean +- std
    med, q10, q90 = (float(v) for v in en.median_spread(ens["fhm_bv"].sel(protrusion=9.0)))
    assert f"{med:.4g} % (10-90 %: {q10:.4g}-{q90:.4g})" in text
    m, sd = (float(v) for v in en.mean_std(ens["interference"].sel(protrusion=11.0)))
    assert f"{m:.4g} ± {sd:.2g} nm" in text


def test_one_realisation_makes_no_ensemble(tmp_path):
    scene = load_scene(PAPER, SHORT + ["report.realisations=1"])
    build(["report"], scene, tmp_path)
    assert not (tmp_path / "ensemble.nc").exists()
    assert "DMW realisations" not in (tmp_path / "report" / "comparison.md").read_text()


def test_identify_evaluation_judges_targets_over_its_realisations(tmp_path):
    scene = load_scene(PAPER, SHORT)
    tl = study.targets(scene)
    prots = study.target_protrusions(tl)
    inputs = evaluations.prepare_inputs(scene, tmp_path)
    one = evaluations.evaluate(scene, [], [], prots, inputs)
    three = evaluations.evaluate(scene, [], [], prots, inputs, realisations=3)
    assert three["realisations"] == 3 and three["error"] is None
    fhm = np.array(three["outputs"]["fhm_bv"])
    np.testing.assert_array_equal(fhm[:, 0], one["outputs"]["fhm_bv"])  # the scene's record first
    vals, res = study.residuals(three, tl, 10.0)
    names = [t.name for t in tl]
    i9 = prots.index(9.0)
    assert vals[names.index("fhm_touchdown")] == np.median(fhm[i9])  # the median of three values
    force = np.array(three["outputs"]["contact_force"])[prots.index(11.0)]
    # tol: the same mean of the same numbers
    assert vals[names.index("contact_force")] == pytest.approx(np.mean(force), rel=1e-12)
    spread = study.spreads(three, tl)[names.index("contact_force")]
    # tol: the same mean and std of the same numbers, a few roundings apart
    np.testing.assert_allclose(spread, np.mean(force) + np.array([-1, 1]) * np.std(force, ddof=1), rtol=1e-12)
    # touchdown residual on the median minimum clearance at 9.6 / 9.8 nm
    c = np.array(three["outputs"]["min_clearance"])
    on, prev = np.median(c[prots.index(9.8)]), np.median(c[prots.index(9.6)])
    assert res[names.index("touchdown")] == pytest.approx((max(0, on) + max(0, -prev)) / 0.1)
    # one realisation: the single-record judgement, unchanged
    v1, r1 = study.residuals(one, tl, 10.0)
    assert np.all(np.isnan(study.spreads(one, tl)))
    # the realisations are part of the evaluation's identity, one realisation keeps the old key
    base = evaluations.base_key(scene, inputs)
    assert evaluations.evaluation_key(base, [], [], prots) == evaluations.evaluation_key(base, [], [], prots, 1)
    assert evaluations.evaluation_key(base, [], [], prots, 3) != evaluations.evaluation_key(base, [], [], prots, 1)


def test_realisations_key_is_validated():
    with pytest.raises(SceneError, match=r"identify\.realisations.*\[1, 1000\]"):
        load_scene(PAPER, ["identify.realisations=0"])
    with pytest.raises(SceneError, match=r"report\.realisations"):
        load_scene(PAPER, ["report.realisations=2.5"])


def test_identify_stage_over_two_realisations_writes_each_targets_spread(write_scene, paper_config, tmp_path):
    import xarray as xr

    from pipeline.analyses.paper_comparison import identification_markdown

    path = write_scene(f"""
[scene]
name = "ens-identify"
extends = "{paper_config}"

[solver]
duration_ms = 0.6
transient_ms = 0.2

[contact]
k = 0.978

[identify]
parameters = [{{key = "dmw.rms_nm", low = 0.1, high = 0.3}}]
targets = ["fhm_touchdown", "contact_force"]
population = 4
generations = 1
profile_points = 3
realisations = 2
""")
    scene = load_scene(path)
    nc = ensure("identify", scene, tmp_path / "out", scheduler="synchronous")
    ds = xr.open_dataset(nc, engine="netcdf4").load()
    assert ds.attrs["realisations"] == 2
    store = evaluations.EvaluationStore(tmp_path / "out" / "identify.evals.jsonl")
    recs = list(store.records.values())
    assert all(r["realisations"] == 2 and len(r["seeds"]) == 2 for r in recs)
    # the stored value and spread are the ensemble statistics of each record: median and 10-90 % of
    # the two FHM values at 9 nm, mean +- std of the two contact forces at 11 nm
    i = int(ds.attrs["best_evaluation"])
    x = float(ds["parameter_value"].sel(parameter="dmw.rms_nm")[i])  # (the best evaluation's record, by its value)
    rec = next(r for r in recs if abs(r["params"][0] - x) < 1e-12)
    prots = rec["protrusions"]
    fhm = np.array(rec["outputs"]["fhm_bv"])[prots.index(9.0)]
    # tol: the same median of the same numbers
    assert float(ds["value"].sel(target="fhm_touchdown")[i]) == pytest.approx(np.median(fhm), rel=1e-12)
    # tol: the same quantiles of the same numbers
    np.testing.assert_allclose(ds["spread"].sel(target="fhm_touchdown")[i].values, np.quantile(fhm, [0.1, 0.9]),
                               rtol=1e-12)
    f = np.array(rec["outputs"]["contact_force"])[prots.index(11.0)]
    # tol: the same mean and std of the same numbers, a few roundings apart
    np.testing.assert_allclose(ds["spread"].sel(target="contact_force")[i].values,
                               np.mean(f) + np.array([-1, 1]) * np.std(f, ddof=1), rtol=1e-12)
    from cf_check import cf_report
    failures, crashed = cf_report(nc)
    assert crashed == [] and failures[3] == [] and failures[2] == [], failures
    md = identification_markdown(ds)
    assert "Over 2 DMW realisations per evaluation" in md
    lo, hi = ds["spread"].sel(target="contact_force")[i].values
    assert f"[{lo:.4g}, {hi:.4g}]" in md


def test_identify_ensemble_of_a_scene_without_dmw_is_refused_in_one_line(tmp_path):

    scene = load_scene(PAPER, SHORT + ['scene.effects=["air_bearing", "pitch", "adhesion", "contact", "friction"]'])
    with pytest.raises(ValueError, match=r"identify\.realisations = 8 needs a synthetic DMW record.*set "
                                         r"identify\.realisations = 1"):
        ensure("identify", scene, tmp_path, scheduler="synchronous")
