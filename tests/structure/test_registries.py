"""'Where to add things' made true: a paper target is one declaration, a stage is one module."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import study
from pipeline.analyses.ensemble_comparison import ensemble_markdown
from pipeline.analyses.paper_comparison import identification_markdown
from pipeline.config import scene as scene_schema
from pipeline.config.scene import SCHEMA, SceneError, load_scene
from pipeline.physics import paper
from pipeline.runner import ensure
from pipeline.stages import ensemble
import twin

#: A target of a kind the paper does not state: the mean clearance at 5 nm protrusion equal to 0.3 nm.
DUMMY = paper.Target(
    "dummy", "dummy clearance at {at:g} nm", "nm", "equal",
    paper.Setting("dummy_clearance_nm", 0.3, "a dummy clearance [nm] (test)"),
    paper.Setting("dummy_clearance_tolerance_nm", 0.05, "its tolerance [nm] (test)"),
    paper.Measure("at", "clearance", "dummy_at_nm"), "{value:g} nm", "nowhere (a test)",
    (paper.Setting("dummy_at_nm", 5.0, "protrusion of the dummy clearance [nm] (test)", "nonnegative"),))

SCENE = twin.scene_text("""
targets = ["fhm_touchdown", "dummy"]
dummy_clearance_nm = 0.35
population = 4
generations = 1
profile_points = 3
realisations = 1
""", name="dummy")


def _clearance_batch(base, params, rows, protrusions, inputs):
    """A stand-in for the slider: the clearance is twice the first parameter [nm], the FHM ten times it."""
    return twin.stub_records(rows, protrusions, lambda x: {"clearance": 2.0 * float(x[0]), "fhm_bv": 10.0 * float(x[0]),
                                                           "min_clearance": 0.1})


@pytest.fixture()
def dummy_target(monkeypatch):
    """The dummy declared (one registry entry); the schema's generated ``[identify]`` keys made again."""
    monkeypatch.setitem(paper.TARGETS, "dummy", DUMMY)
    for key, spec in scene_schema.target_keys().items():
        monkeypatch.setitem(SCHEMA["identify"], key, spec)


def test_a_declared_target_is_in_the_schema_with_its_keys(dummy_target, paper_config):
    spec = SCHEMA["identify"]
    assert "dummy" in spec["targets"].choices
    assert spec["dummy_clearance_nm"].default == 0.3 and spec["dummy_at_nm"].default == 5.0
    assert spec["dummy_clearance_tolerance_nm"].default == 0.05
    # the generated keys are validated like every key: one line naming the field
    with pytest.raises(SceneError, match="identify.dummy_at_nm"):
        load_scene(paper_config, ["identify.dummy_at_nm=-1.0"])
    # the paper's own keys are generated from their declarations with today's names and defaults
    assert spec["fhm_flying_range_nm"].default == [4.0, 7.0] and spec["fhm_flying_range_nm"].length == 2
    assert spec["sliding_at_nm"].default == paper.LIGHT_CONTACT_NM
    assert spec["touchdown_tolerance_nm"].default == 0.1


def test_every_declaration_names_a_known_measurement_and_scene_keys():
    assert set(study.MEASUREMENTS) == set(paper.MEASURES)
    for t in paper.TARGETS.values():
        assert t.measure.how in paper.MEASURES, t.name
        where = t.measure.where if isinstance(t.measure.where, tuple) else (t.measure.where,)
        for key in (*where, t.measure.step, t.value if isinstance(t.value, str) else ""):
            if key:
                section, _, name = key.rpartition(".")
                assert name in SCHEMA[section or "identify"], (t.name, key)


def test_without_the_declaration_the_target_is_refused(paper_config):
    with pytest.raises(SceneError, match="identify.targets"):
        load_scene(paper_config, ["identify.targets=['dummy']"])


def test_a_declared_target_is_fitted_and_reported(dummy_target, write_scene, paper_config, tmp_path):
    scene = load_scene(write_scene(SCENE.format(paper=paper_config)))
    t = {t.name: t for t in study.targets(scene)}["dummy"]
    assert (t.long_name, t.paper, t.target, t.tolerance, t.protrusions) == \
        ("dummy clearance at 5 nm", "0.35 nm", 0.35, 0.05, (5.0,))
    # identify: the residual vector has the dummy's entry, (2 x rms - 0.35) / 0.05 at every evaluation
    nc = ensure("identify", scene, tmp_path / "out", scheduler="synchronous", task=_clearance_batch)
    ds = xr.open_dataset(nc, engine="netcdf4").load()
    assert [str(n) for n in ds["target"].values] == ["fhm_touchdown", "dummy"]
    rms = ds["parameter_value"].sel(parameter="dmw.rms_nm").values
    np.testing.assert_allclose(ds["value"].sel(target="dummy").values, 2.0 * rms)  # tol: a product by 2, exact
    # tol: a residual of exact decimals, a few roundings
    np.testing.assert_allclose(ds["residual"].sel(target="dummy").values, (2.0 * rms - 0.35) / 0.05)
    dummy = ds.sel(target="dummy")
    assert str(dummy["target_paper"].values) == "0.35 nm" and str(dummy["target_units"].values) == "nm"
    # the report's comparison lists it, paper and reconstructed value (rms 0.14 of the paper scene)
    md = identification_markdown(ds)
    assert f"| dummy clearance at 5 nm | 0.35 nm | {2.0 * rms[0]:.4g} nm (r = " in md
    # and over DMW realisations: ensemble.nc judges it (the median, its 10-90 % range), the report's
    # ensemble table lists it
    record = {"protrusions": study.target_protrusions(study.targets(scene)), "realisations": 3,
              "outputs": {"clearance": [0.3, 0.4, 0.5] * 2, "fhm_bv": [9.0] * 6, "min_clearance": [0.1] * 6}}
    ens = study.record_dataset(record)
    ens = ens.assign(ensemble.judged(ens, scene)).assign(dmw_seed=("realisation", [1, 2, 3]))
    assert float(ens["value_dummy"]) == pytest.approx(0.4) and float(ens["single_dummy"]) == pytest.approx(0.3)
    assert "| dummy clearance at 5 nm | 0.35 nm | 0.4 nm (10-90 %: 0.32-0.48) | 0.3 nm |" in ensemble_markdown(ens)


# ------------------------------------------------------------------------------------------- stages
DUMMY_STAGE = '''
"""A dummy stage (a test): one dataset with the scene's flying height."""
import xarray as xr
from pipeline.runner import Stage


def compute(scene, inputs):
    return xr.Dataset({"flying_height": ((), scene["slider"]["length_mm"], {"units": "mm", "long_name": "x"})})


STAGE = Stage("dummy_stage", compute, outputs=("dummy_stage.nc",), reads=("slider.*",), doc="a dummy stage (test)")
'''


def _make_n(folder, *goals: str) -> str:
    """What ``make -n GOALS`` in ``folder`` would run."""
    import subprocess
    done = subprocess.run(["make", "-n", "--no-print-directory", "-C", str(folder), *goals], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_every_registered_stage_is_a_make_target_named_as_its_module(repo_root):
    from pipeline import runner
    stages = runner.registry()
    modules = sorted(p.stem for p in (repo_root / "pipeline" / "stages").glob("*.py") if p.stem != "__init__")
    # the Makefile lists the stage modules' files; each module is named after its stage
    assert sorted(stages) == modules
    assert {getattr(__import__(f"pipeline.stages.{m}", fromlist=["STAGE"]), "STAGE").name for m in modules} == \
        set(modules)
    lines = _make_n(repo_root, *stages).splitlines()
    for name in stages:  # (sweep and identify run their own scenes)
        assert any(line.split()[:2] == [".venv/bin/hdi", name] for line in lines), (name, lines)
    assert "bulge" in stages


def test_a_new_stage_module_is_a_stage_of_the_runner_the_cli_and_make(tmp_path, monkeypatch, paper_config,
                                                                      repo_root):
    import shutil
    import sys

    from pipeline import cli, runner, stages
    folder = tmp_path / "more_stages"
    folder.mkdir()
    (folder / "dummy_stage.py").write_text(DUMMY_STAGE)
    # the module beside the others, without a file in the repository: the package searches one more folder
    monkeypatch.setattr(stages, "__path__", [*stages.__path__, str(folder)])
    monkeypatch.delitem(sys.modules, "pipeline.stages.dummy_stage", raising=False)
    try:
        assert "dummy_stage" in runner.registry()
        assert cli._parser(runner.registry()).parse_args(["dummy_stage", "x.toml"]).stage == "dummy_stage"
        out = tmp_path / "out"
        assert cli.main(["dummy_stage", str(paper_config), "--out", str(out)]) == 0
        assert float(xr.open_dataset(out / "dummy_stage.nc", engine="netcdf4")["flying_height"]) == 0.85
    finally:
        sys.modules.pop("pipeline.stages.dummy_stage", None)
    # make: the Makefile in a copy of the tree with the module added has the target
    copy = tmp_path / "copy"
    (copy / "pipeline" / "stages").mkdir(parents=True)
    shutil.copy(repo_root / "Makefile", copy / "Makefile")
    for p in (repo_root / "pipeline" / "stages").glob("*.py"):
        (copy / "pipeline" / "stages" / p.name).touch()
    for name in ("pyproject.toml", "uv.lock", ".venv/.installed-run"):  # (the stamp is newer: nothing to install)
        (copy / name).parent.mkdir(exist_ok=True)
        (copy / name).touch()
    with pytest.raises(AssertionError, match="No rule to make target 'dummy_stage'"):
        _make_n(copy, "dummy_stage")
    (copy / "pipeline" / "stages" / "dummy_stage.py").write_text(DUMMY_STAGE)
    assert _make_n(copy, "dummy_stage").split() == [".venv/bin/hdi", "dummy_stage", "configs/paper-2009-identified.toml"]
