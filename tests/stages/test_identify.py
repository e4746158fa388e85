"""hdi identify: the twin experiment (targets made by the model itself), resuming, the written scene.
(The study's parameters: analyses/test_study.py; the search on plain functions: analyses/identification/;
the evaluation store and keys: core/test_evaluations.py.)"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline import evaluations
from pipeline.analyses import free_parameters, identification, study
from pipeline.model import scene_inputs
from pipeline.model.inputs import cached
from pipeline.config.scene import load_scene
from pipeline.physics import paper
from pipeline.runner import ensure
import twin

TRUE = {"dmw.rms_nm": 0.14, "lubricant.work_of_adhesion_j_m2": 0.07}

SCENE = twin.scene_text("""
targets = ["fhm_flying", "contact_force"]
fhm_flying_tolerance_percent = 0.3
contact_force_tolerance_mn = 0.05
population = 6
generations = 8
profile_points = 9
batch_size = 4
realisations = 1
""")


def _twin_scene(write_scene, paper_config, tmp_path, text=SCENE):
    """The scene of ``text`` with every target's value set to what the model gives at :data:`TRUE`."""
    path = write_scene(text.format(paper=paper_config))
    scene = load_scene(path)
    params = free_parameters.parse_parameters(scene["identify"]["parameters"], str(path), "identify.parameters")
    tl = study.targets(scene)
    inputs = evaluations.prepare_inputs(scene, tmp_path / "out")
    rec = evaluations.evaluate(scene, params, [TRUE[p.name] for p in params], study.target_protrusions(tl), inputs)
    values, _ = study.residuals(rec, tl, 10.0)
    assert np.all(np.isfinite(values))
    return load_scene(path, [f"identify.{paper.TARGETS[t.name].value.key}={float(v)!r}" for t, v in zip(tl, values)]), path


def test_twin_experiment_recovers_the_true_parameters_within_the_reported_interval(write_scene, paper_config,
                                                                                    tmp_path):
    scene, path = _twin_scene(write_scene, paper_config, tmp_path)
    out = tmp_path / "out"
    nc = ensure("identify", scene, out, scheduler="synchronous")
    ds = xr.open_dataset(nc, engine="netcdf4")
    assert ds.attrs["within_tolerance"] == 1
    from cf_check import cf_report  # identify.nc fits the ecosystem like the other datasets
    failures, crashed = cf_report(nc)
    assert crashed == [] and failures[3] == [] and failures[2] == [], failures
    assert ds.attrs["interval_method"] == identification.METHODS["optimised"]  # (the default)
    for p in free_parameters.parse_parameters(scene["identify"]["parameters"], "", ""):
        at = ds.sel(parameter=p.name)
        lo, hi = float(at["interval"].sel(bound="low")), float(at["interval"].sel(bound="high"))
        assert lo <= TRUE[p.name] <= hi, (p.name, lo, hi, float(at["best"]))
        # the interval is informative: well inside the bounds
        assert hi - lo < 0.5 * (p.high - p.low)
        # and never narrower than the slice it started from
        slo, shi = at["slice_interval"].values
        assert lo <= slo and shi <= hi
        assert str(at["parameter_units"].values) == p.units
    # every evaluation is in the dataset, with units (its own, or the variable holding each parameter's or target's)
    for v in list(ds.data_vars) + list(ds.coords):
        a = ds[v].attrs
        assert "long_name" in a and ("units" in a or a.get("unit_variable") in ds or ds[v].dtype.kind in "OSU"), v
        assert len(a["long_name"]) <= 40, (v, a["long_name"])  # a plot's label; the sentence: description
    assert ds["best"].attrs["description"].startswith("identified value of each parameter")
    assert ds.sizes["evaluation"] == len(evaluations.EvaluationStore(out / "identify.evals.jsonl").records)
    # the reconstructed point (evaluation 0) is worse than the identified one
    assert float(ds["objective"][0]) > float(ds["objective"][ds.attrs["best_evaluation"]])
    # the written scene extends the twin scene and loads with the identified values
    written = out / "identified.toml"  # in the results folder, not beside the scene
    assert not (path.parent / "identified.toml").exists() and not (path.parent / "twin-identified.toml").exists()
    text = written.read_text()
    assert text.count("# [identified] interval [") == 2  # one per identified value, with its interval
    # the header names the budget the values came from
    cfg = scene["identify"]
    assert (f"# Budget: differential evolution population {cfg['population']} x 2 parameters, at most "
            f"{cfg['generations']} generations ({ds.attrs['generations']} run), {cfg['profile_points']} profile "
            f"points") in text
    assert f"; {ds.sizes['evaluation']} evaluations." in text
    rev = ds.attrs["git_revision"]  # the revision identify.nc was made at, a dirty tree said so
    assert f"(git {rev[:12]}{'-dirty' if rev.endswith('-dirty') else ''});" in text.splitlines()[0]
    ident = load_scene(written)
    assert ident["dmw"]["rms_nm"] == pytest.approx(float(ds.best.sel(parameter="dmw.rms_nm")), rel=1e-5)
    assert ident["solver"]["duration_ms"] == 0.8  # inherited
    # the report's three columns: paper, reconstructed, identified; nothing unreached in a twin experiment
    from pipeline.analyses.paper_comparison import identification_markdown
    md = identification_markdown(ds.load())
    assert "| target | paper | reconstructed | identified |" in md
    assert "Every target is reached within tolerance" in md
    # a target no evaluation brings within tolerance is listed with the closest value reached (measured)
    far = ds.copy(deep=True)
    far["residual"][:, 1] = np.abs(far["residual"][:, 1]) + 5.0
    far["best_abs_residual"][1] = float(np.min(np.abs(far["residual"][:, 1])))
    k = int(np.argmin(np.abs(far["residual"][:, 1].values)))
    md = identification_markdown(far)
    assert "Targets no parameter set within the bounds reaches" in md
    assert f"reached {float(far['value'].sel(target='contact_force')[k]):.4g} mN" in md
    # unchanged inputs: the runner keeps identify.nc (nothing run); resuming after identify.nc is lost:
    # every evaluation is read back from the store, none computed, the same result
    from pipeline.runner import last_run
    runs = last_run(out, "identify")
    assert ensure("identify", scene, out, scheduler="synchronous") == nc and last_run(out, "identify") == runs
    nc.unlink()
    nc2 = ensure("identify", scene, out, scheduler="synchronous")
    assert last_run(out, "identify")["evaluations_computed"] == 0
    ds2 = xr.open_dataset(nc2, engine="netcdf4")
    np.testing.assert_array_equal(ds2["objective"].values, ds["objective"].values)


def test_two_sided_fallback_k(paper_scene):
    # docs/model.md, "Contact criterion": the paper's 32.8 % is two-sided: k = 0.978 (a study takes k without
    # a calibration)
    k, source = scene_inputs.contact_k(paper_scene)
    assert k == pytest.approx(0.978, abs=1e-3) and "two-sided" in source


def test_candidate_inputs_are_cached_by_stage_key_alone():
    made = []
    first = cached("test", "key-1", lambda: made.append(1) or "tables")
    again = cached("test", "key-1", lambda: made.append(2) or "other")  # same key: not made again
    assert first == again == "tables" and made == [1]


def test_a_profile_point_better_than_the_optimum_becomes_the_optimum(write_scene, paper_config, tmp_path):
    # one generation of a small population stops short of the twin's truth; the profiles find better
    # points, and the written optimum moves to them (the profiles made again around it) until none is
    # better by more than PROFILE_GAIN or the rounds run out (without the polish of the search's optimum, which
    # takes it there before the profiles: tests/analyses/identification/test_search.py)
    scene, path = _twin_scene(write_scene, paper_config, tmp_path)
    scene = load_scene(path, ["identify.generations=1", "identify.population=4", "identify.profile_points=5",
                              "identify.seed=1", "identify.polish=false",
                              *[f"identify.{k}={scene['identify'][k]!r}" for k in ("fhm_flying_percent",
                                                                                      "contact_force_mn")]])
    ds = xr.open_dataset(ensure("identify", scene, tmp_path / "out", scheduler="synchronous"), engine="netcdf4")
    rounds = int(ds.attrs["profile_rounds"])
    assert 2 <= rounds <= identification.PROFILE_ROUNDS  # (here the global search stops short: it moved)
    best = ds["best"].values
    points = ds["parameter_value"].values
    i_best = int(ds.attrs["best_evaluation"])
    np.testing.assert_array_equal(points[i_best], best)  # the written optimum is the best evaluated point
    role, cost = ds["role"].values, ds["objective"].values
    assert cost[i_best] == np.nanmin(cost) == ds.attrs["best_objective"]
    # the profiles' centre: no profile point (slice or re-optimised) beats it by more than the gain
    i_centre = int(ds.attrs["profile_centre_evaluation"])
    centre, c_centre = points[i_centre], float(cost[i_centre])
    assert c_centre <= float(np.nanmin(cost[role <= 1]))  # at least as good as the global search's best
    if rounds < identification.PROFILE_ROUNDS:
        assert c_centre - float(np.nanmin(cost[(role == 2) | (role == 4)])) <= identification.PROFILE_GAIN
    # the profiles of the last round pass through their centre
    for j, c in enumerate(centre):
        assert c in ds["profile"][j].values


#: The twin with a correlated pair: the FHM at 9 nm grows with the DMW amplitude and falls with the work of
#: adhesion (about equally over 10 % of their bounds); with a tight tolerance it and the flying FHM correlate
#: the two parameters (Gauss-Newton correlation ~0.9). The scene starts at the truth: one generation suffices.
CORRELATED = SCENE.replace('targets = ["fhm_flying", "contact_force"]', 'targets = ["fhm_flying", "fhm_touchdown"]\n'
                           'fhm_touchdown_tolerance_percent = 0.01').replace(
    "population = 6\ngenerations = 8\nprofile_points = 9", "population = 4\ngenerations = 1\nprofile_points = 7").replace(
    "[contact]", "[dmw]\nrms_nm = 0.14\n\n[lubricant]\nwork_of_adhesion_j_m2 = 0.07\n\n[contact]")


@pytest.mark.slow  # (16-25 s on the shared 2 cores: 48 evaluations of the real slider)
def test_twin_correlated_pair_profile_interval_is_wider_than_the_slice(write_scene, paper_config, tmp_path):
    # a slice (the other parameter held at the optimum) is too narrow where parameters
    # correlate; the profile re-optimises it and finds the wider interval, which holds the truth
    scene, path = _twin_scene(write_scene, paper_config, tmp_path, CORRELATED)
    out = tmp_path / "out"
    ds = xr.open_dataset(ensure("identify", scene, out, scheduler="synchronous"), engine="netcdf4").load()
    assert ds.attrs["within_tolerance"] == 1 and ds.attrs["interval_method"] == identification.METHODS["optimised"]
    assert float(ds["correlation"][0, 1]) > 0.8
    params = free_parameters.parse_parameters(scene["identify"]["parameters"], "", "")
    for p in params:
        lo, hi = ds["interval"].sel(parameter=p.name).values
        slo, shi = ds["slice_interval"].sel(parameter=p.name).values
        assert lo <= slo and shi <= hi and lo <= TRUE[p.name] <= hi, (p.name, lo, hi, slo, shi)
        # 1 / sqrt(1 - rho^2) wider in theory (2.4 at rho 0.9); the grid's linear crossings make it ~2.2
        assert hi - lo > 1.5 * (shi - slo), (p.name, lo, hi, slo, shi)
        assert str(ds["parameter_b_units"].sel(parameter_b=p.name).values) == p.units
    assert ds["profile_parameters"].attrs["unit_variable"] == "parameter_b_units"
    # the other parameter moves along the valley on each profile (correlation > 0: both up or both down)
    rms, w = (ds["profile_parameters"].sel(parameter_b=p.name).values for p in params)
    opt = ds["profile_optimised"].values.astype(bool)
    assert opt[0].sum() >= 2 and opt[1].sum() >= 2
    moved = opt[0] & (rms[0] != TRUE["dmw.rms_nm"])
    assert moved.any() and np.all(np.sign(rms[0, moved] - TRUE["dmw.rms_nm"]) == np.sign(w[0, moved] - TRUE[params[1].name]))
    # its budget, in the records with role 4
    role = ds["role"].values
    assert int(np.sum(role == 4)) == int(ds.attrs["profile_optimiser_evaluations"]) <= \
        2 * scene["identify"]["profile_evaluations"]
    # the report and the written scene say which interval they give
    from pipeline.analyses.paper_comparison import identification_markdown
    md = identification_markdown(ds)
    assert "| profile interval | slice interval |" in md and "Interval (profile, other parameters re-optimised)" in md
    assert "profile, other parameters re-optimised" in (out / "identified.toml").read_text().splitlines()[3]


# ---------------------------------------------------------------- outputs go only where the user said
def _stub_batch(base, params, rows, protrusions, inputs):
    """A stand-in for the slider: FHM and contact force linear in the parameters (the written scene is
    what is tested here, not the fit)."""
    return twin.stub_records(rows, protrusions, lambda x: {
        "fhm_bv": 10.0 * float(x[0]), "contact_fraction": 1.0, "min_clearance": -0.1, "contact_force": float(x[1]),
        "interference": 0.5, "mean_pressure": 400.0})


USER_TEXT = "# my own edits of the identified scene, which no identify run may touch\n"


def _user_scene(tmp_path, paper_config):
    """A scene in a folder of its own beside a user's ``twin-identified.toml``; the scene, loaded with a tiny budget."""
    configs = tmp_path / "configs"
    configs.mkdir()
    path = configs / "twin.toml"
    path.write_text(SCENE.format(paper=paper_config))
    (configs / "twin-identified.toml").write_text(USER_TEXT)
    return load_scene(path, ["identify.population=4", "identify.generations=1", "identify.profile_points=3"]), path


def test_identify_writes_its_scene_into_the_results_folder_not_over_the_users_file(tmp_path, paper_config):
    # `hdi identify configs/paper-2009.toml --out elsewhere` writes into elsewhere/, never configs/paper-2009-identified.toml
    scene, path = _user_scene(tmp_path, paper_config)
    out = tmp_path / "elsewhere"
    nc = ensure("identify", scene, out, scheduler="synchronous", task=_stub_batch)
    beside = path.parent / "twin-identified.toml"
    assert beside.read_text() == USER_TEXT
    assert sorted(p.name for p in path.parent.iterdir()) == ["twin-identified.toml", "twin.toml"]
    written = out / "identified.toml"
    ident = load_scene(written)  # extends the scene from the results folder
    ds = xr.open_dataset(nc, engine="netcdf4")
    assert ds.attrs["identified_scene"] == "identified.toml"
    assert ident["dmw"]["rms_nm"] == pytest.approx(float(ds.best.sel(parameter="dmw.rms_nm")), rel=1e-5)
    assert ident["solver"]["duration_ms"] == 0.8
    # a no-op rerun touches neither
    before = written.stat().st_mtime_ns
    ensure("identify", scene, out, scheduler="synchronous", task=_stub_batch)
    assert beside.read_text() == USER_TEXT and written.stat().st_mtime_ns == before
    # the copy goes only where named; an existing file of other content is left as it is unless forced
    with pytest.raises(ValueError, match="twin-identified.toml: exists and differs"):
        ensure("identify", scene, out, scheduler="synchronous", task=_stub_batch, write_scene=beside)
    assert beside.read_text() == USER_TEXT
    copy = tmp_path / "mine" / "twin-identified.toml"
    copy.parent.mkdir()
    ensure("identify", scene, out, scheduler="synchronous", task=_stub_batch, write_scene=copy)
    assert load_scene(copy)["dmw"]["rms_nm"] == ident["dmw"]["rms_nm"]  # its extends resolved from its own folder
    ensure("identify", scene, out, scheduler="synchronous", task=_stub_batch, write_scene=copy)  # same text: no error
    ensure("identify", scene, out, scheduler="synchronous", task=_stub_batch, write_scene=beside, force=True)
    assert load_scene(beside)["dmw"]["rms_nm"] == ident["dmw"]["rms_nm"]
    assert not list(path.parent.glob(".*.tmp")) and not list(copy.parent.glob(".*.tmp"))


def _fails(capsys, *argv: str) -> str:
    from pipeline import cli
    code = cli.main(list(argv))
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    return err


def test_write_scene_is_refused_before_the_study_starts(tmp_path, paper_config, capsys):
    # a --write-scene that exists, lies in a folder no process may write in, in none, or is a folder: refused before
    # the study starts (not after it), the existing file kept
    scene, path = _user_scene(tmp_path, paper_config)
    out = tmp_path / "out"
    beside = path.parent / "twin-identified.toml"
    err = _fails(capsys, "identify", str(path), "--out", str(out), "--write-scene", str(beside))
    assert f"--write-scene {beside}: exists" in err and "--force" in err
    # a folder no process may write in (root included)
    err = _fails(capsys, "identify", str(path), "--out", str(out), "--write-scene", "/proc/twin-identified.toml")
    assert "folder /proc is not writable" in err
    err = _fails(capsys, "identify", str(path), "--out", str(out), "--write-scene", str(tmp_path / "no" / "x.toml"))
    assert "does not exist" in err
    err = _fails(capsys, "identify", str(path), "--out", str(out), "--write-scene", str(tmp_path))
    assert "is a folder" in err
    err = _fails(capsys, "sweep", str(path), "--out", str(out), "--write-scene", str(tmp_path / "x.toml"))
    assert "--write-scene: not used by `hdi sweep`" in err
    assert not out.exists() and beside.read_text() == USER_TEXT  # nothing ran, nothing written


@pytest.mark.parametrize("name, text", [("...toml", ""), ("dots.toml", 'name = ".."\n'),
                                        ("dot.toml", 'name = "."\n')])
def test_a_scene_whose_name_leaves_the_results_folder_is_refused(tmp_path, paper_config, capsys, monkeypatch,
                                                                   name, text):
    # a scene named `..` (or a file `...toml`) is refused: its results folder results/../ would be the current folder
    (tmp_path / name).write_text(f'[scene]\n{text}extends = "{paper_config}"\n')
    monkeypatch.chdir(tmp_path)
    err = _fails(capsys, "dmw", name)
    assert "scene.name" in err and "not '.' or '..'" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


# ------------------------------------------------------ one best point, wherever the profiles found it
def _separable_batch(base, params, rows, protrusions, inputs):
    """A stand-in for the slider whose objective has its minimum at grid points of the profiles (5 points of
    the twin's bounds: dmw.rms_nm 0.165, work of adhesion 0.07): it flies everywhere, its FHM is 100 x the
    DMW amplitude [%] and its contact force 10 x the work of adhesion [mN]."""
    return twin.stub_records(rows, protrusions, lambda x: {
        "fhm_bv": 100.0 * float(x[0]), "contact_fraction": 0.0, "min_clearance": 0.1,
        "contact_force": 10.0 * float(x[1]), "interference": 0.0, "mean_pressure": 0.0})


#: The stand-in's targets, one generation of a small population: the search stops short of the minimum (and no
#: polish takes it there before the profiles: the case is a profile point better than their centre)
BEST_POINT = twin.scene_text("""
targets = ["fhm_flying", "contact_force"]
fhm_flying_percent = 16.5
contact_force_mn = 0.7
population = 4
generations = 1
profile_points = 5
seed = 3
realisations = 1
polish = false
""")


@pytest.mark.parametrize("tolerances, rounds", [
    # the last round's profiles find a point far better than their centre (rounds = 1: no round more moves it)
    (["identify.fhm_flying_tolerance_percent=0.1", "identify.contact_force_tolerance_mn=0.01"], 1),
    # a point better than the centre by less than PROFILE_GAIN (wide tolerances: the whole objective is below 1)
    (["identify.fhm_flying_tolerance_percent=30", "identify.contact_force_tolerance_mn=2"], None)])
def test_a_profile_point_better_than_the_centre_is_the_one_best_point_everywhere(tmp_path, paper_config, monkeypatch,
                                                                                   caplog, tolerances, rounds):
    # identify.nc's best_evaluation (the lowest objective, a profile point may hold it), its *_best values and
    # the written scene name one point
    if rounds is not None:
        monkeypatch.setattr(identification.profiles, "PROFILE_ROUNDS", rounds)
    path = tmp_path / "twin.toml"
    path.write_text(BEST_POINT.format(paper=paper_config))
    scene = load_scene(path, tolerances)
    out = tmp_path / "out"
    with caplog.at_level("INFO", logger="pipeline"):
        ds = xr.open_dataset(ensure("identify", scene, out, scheduler="synchronous", task=_separable_batch),
                             engine="netcdf4").load()
    objective, role = ds["objective"].values, ds["role"].values
    i_best, i_centre = int(ds.attrs["best_evaluation"]), int(ds.attrs["profile_centre_evaluation"])
    # the case this test is for: a profile point (slice or re-optimised) is the best, not the profiles' centre
    assert role[i_best] in (2, 4) and i_best != i_centre
    gain = objective[i_centre] - objective[i_best]
    assert gain > identification.PROFILE_GAIN if rounds else 0 < gain <= identification.PROFILE_GAIN
    # ... one best point: the lowest objective, its values, the written scene, the log's last line
    assert objective[i_best] == np.min(objective) == ds.attrs["best_objective"]
    np.testing.assert_array_equal(ds["best"].values, ds["parameter_value"][i_best].values)
    written = load_scene(out / "identified.toml")
    for p in free_parameters.parse_parameters(scene["identify"]["parameters"], "", ""):
        section, key, _ = p.parts
        assert written[section][key] == pytest.approx(float(ds["best"].sel(parameter=p.name)), rel=1e-5)
    last = [r.getMessage() for r in caplog.records if "evaluations (" in r.getMessage()]
    assert len(last) == 1 and f"best objective {objective[i_best]:.4g} (evaluation {i_best})" in last[0]
    assert any(f"the best point (evaluation {i_best}) is not the profiles' centre (evaluation {i_centre})"
               in r.getMessage() for r in caplog.records)
    # the intervals are read around the best point: each holds its value
    lo, hi = ds["interval"].sel(bound="low").values, ds["interval"].sel(bound="high").values
    assert np.all((lo <= ds["best"].values) & (ds["best"].values <= hi)), (lo, hi, ds["best"].values)
    # the residual bars of the figure and the report's identified column are the best evaluation's
    from pipeline.analyses.paper_comparison import identification_markdown
    md = identification_markdown(ds)
    r = ds["residual"][i_best].values
    assert f"(r = {r[1]:+.2g}) |" in md.split("| contact force", 1)[1].splitlines()[0]
    # the header of the written scene names the scene it comes from and the best evaluation
    head = (out / "identified.toml").read_text().splitlines()[1]
    assert 'identified scene of twin.toml (scene "twin"' in head and f"best evaluation {i_best} of identify.nc" in head


def test_identify_nc_has_parameter_target_and_bound_dimensions(tmp_path, paper_config):
    # the study's results are variables on parameter, target and bound dimensions, not a variable per name
    # (air_bearing__frequencies_khz_1_slice_interval, ...)
    path = tmp_path / "twin.toml"
    path.write_text(BEST_POINT.format(paper=paper_config))
    scene = load_scene(path, ["identify.fhm_flying_tolerance_percent=0.1", "identify.contact_force_tolerance_mn=0.01"])
    nc = ensure("identify", scene, tmp_path / "out", scheduler="synchronous", task=_separable_batch)
    ds = xr.open_dataset(nc, engine="netcdf4").load()
    assert list(ds["parameter"].values) == ["dmw.rms_nm", "lubricant.work_of_adhesion_j_m2"]
    assert list(ds["target"].values) == ["fhm_flying", "contact_force"]
    assert ds["interval"].dims == ("parameter", "bound") and ds["slice_interval"].dims == ("parameter", "bound")
    assert ds["profile"].dims == ds["profile_objective"].dims == ("parameter", "point")
    assert ds["best"].dims == ("parameter",) and ds["residual"].dims == ("evaluation", "target")
    assert ds["value"].dims == ("evaluation", "target") and ds["parameter_value"].dims == ("evaluation", "parameter")
    assert not [v for v in ds.data_vars if "__" in str(v)]  # no variable per parameter
    # the values in each parameter's units, which a coordinate along the dimension holds
    rms = ds.sel(parameter="dmw.rms_nm", bound="low")
    assert str(rms["parameter_units"].values) == "nm" and ds["interval"].attrs["unit_variable"] == "parameter_units"
    assert float(ds["search_bounds"].sel(parameter="dmw.rms_nm", bound="low")) == 0.08
    assert float(rms["interval"]) <= float(rms["best"]) <= float(ds["interval"].sel(parameter="dmw.rms_nm",
                                                                                    bound="high"))
    ct = ds.sel(target="contact_force")
    assert str(ct["target_units"].values) == "mN" and float(ct["goal"]) == 0.7 and float(ct["tolerance"]) == 0.01
    # tol: a product by 10 of the same parameter, one rounding
    np.testing.assert_allclose(ct["value"].values, 10.0 * ds["parameter_value"].sel(
        parameter="lubricant.work_of_adhesion_j_m2").values)
    # tol: the same sum of squares, a few roundings apart
    np.testing.assert_allclose(ds["objective"].values, (ds["residual"]**2).sum("target").values)
    # the profile of each parameter passes through the best point's value here (centre = best or not, it is a grid)
    assert ds["correlation"].dims == ("parameter", "parameter_b")
    from cf_check import cf_report  # CF-checked like every dataset
    failures, crashed = cf_report(nc)
    assert crashed == [] and failures[3] == [] and failures[2] == [], failures


def test_the_report_refuses_an_identify_nc_of_the_older_layout_in_one_line():
    from pipeline.analyses.paper_comparison import identification_markdown
    old = xr.Dataset({"dmw__rms_nm_best": xr.DataArray(0.14, attrs={"units": "nm"}),
                      "value_contact_force": xr.DataArray([1.0], dims="evaluation")},
                     attrs={"best_evaluation": 0, "reconstructed_evaluation": 0})
    with pytest.raises(ValueError, match=r"identify.nc: written by an older hdi identify .*dmw__rms_nm_best.*run "
                                         r"`hdi identify` again"):
        identification_markdown(old)
