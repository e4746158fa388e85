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
from pipeline.stages import ensemble, identify

#: A target of a kind the paper does not state: the mean clearance at 5 nm protrusion equal to 0.3 nm.
DUMMY = paper.Target(
    "dummy", "dummy clearance at {at:g} nm", "nm", "equal",
    paper.Setting("dummy_clearance_nm", 0.3, "a dummy clearance [nm] (test)"),
    paper.Setting("dummy_clearance_tolerance_nm", 0.05, "its tolerance [nm] (test)"),
    paper.Measure("at", "clearance", "dummy_at_nm"), "{value:g} nm", "nowhere (a test)",
    (paper.Setting("dummy_at_nm", 5.0, "protrusion of the dummy clearance [nm] (test)", "nonnegative"),))

SCENE = """
[scene]
name = "dummy"
extends = "{paper}"

[solver]
duration_ms = 0.8
transient_ms = 0.3

[contact]
k = 0.978

[identify]
parameters = [{{key = "dmw.rms_nm", low = 0.08, high = 0.25}},
              {{key = "lubricant.work_of_adhesion_j_m2", low = 0.03, high = 0.11}}]
targets = ["fhm_touchdown", "dummy"]
dummy_clearance_nm = 0.35
population = 4
generations = 1
profile_points = 3
realisations = 1
"""


def _clearance_batch(base, params, rows, protrusions, inputs):
    """A stand-in for the slider: the clearance is twice the first parameter [nm], the FHM ten times it."""
    n = len(protrusions)
    out = []
    for key, x in rows:
        outputs = {"clearance": [2.0 * float(x[0])] * n, "fhm_bv": [10.0 * float(x[0])] * n,
                   "min_clearance": [0.1] * n}
        out.append((key, {"params": list(map(float, x)), "protrusions": list(map(float, protrusions)),
                          "outputs": outputs, "seconds": 0.0, "kernel_seconds": 0.0, "error": None}))
    return out


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


def test_without_the_declaration_the_target_is_refused(paper_config):
    with pytest.raises(SceneError, match="identify.targets"):
        load_scene(paper_config, ["identify.targets=['dummy']"])


def test_a_declared_target_is_fitted_and_reported(dummy_target, write_scene, paper_config, tmp_path):
    scene = load_scene(write_scene(SCENE.format(paper=paper_config)))
    t = {t.name: t for t in study.targets(scene)}["dummy"]
    assert (t.long_name, t.paper, t.target, t.tolerance, t.protrusions) == \
        ("dummy clearance at 5 nm", "0.35 nm", 0.35, 0.05, (5.0,))
    # identify: the residual vector has the dummy's entry, (2 x rms - 0.35) / 0.05 at every evaluation
    nc = identify.run(scene, tmp_path / "out", scheduler="synchronous", task=_clearance_batch)
    ds = xr.open_dataset(nc, engine="netcdf4").load()
    assert [str(n) for n in ds["target"].values] == ["fhm_touchdown", "dummy"]
    rms = ds["dmw__rms_nm"].values
    np.testing.assert_allclose(ds["value_dummy"].values, 2.0 * rms)
    np.testing.assert_allclose(ds["residual"].sel(target="dummy").values, (2.0 * rms - 0.35) / 0.05)
    assert ds["value_dummy"].attrs["paper"] == "0.35 nm" and ds["value_dummy"].attrs["units"] == "nm"
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
