"""Each stage declares the scene keys it reads, and exactly the stages that declare a key recompute when it
changes.

A stage's ``reads`` (schema keys: its model builders' ``FIELDS`` and its own) are its inputs key's scene
part, and its ``compute`` reads the scene through :class:`pipeline.config.fields.DeclaredScene`, which refuses
any other key: a key read but not keyed (a stale result that looks current) is an error at its first read.
Here: the declarations are the builders' and name schema keys; every declared key, edited in a light paper
scene, changes the inputs keys of exactly the stages that declare it and of those downstream of them (the
keys only: no stage runs); for a few keys the main job, built once, is stale in exactly those stages and a
rebuild rewrites only them.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pipeline import runner
from pipeline.config.fields import UndeclaredRead, expand
from pipeline.config.scene import SceneError, load_scene
from pipeline.config.schema import SCHEMA, Key
from pipeline.model import assembly, bulge_table, dmw_record, interface_tables, scene_inputs
from pipeline.physics.variants import Registry

#: A light paper scene: a short grid, short runs.
LIGHT = ["sweep.protrusion_nm={start = 9.0, stop = 11.0, step = 0.2}", "solver.duration_ms=0.8",
         "solver.transient_ms=0.3"]


@pytest.fixture(scope="module")
def light(paper_config):
    return load_scene(paper_config, LIGHT)


def test_no_stage_reads_the_whole_scene():
    for name, st in runner.registry().items():
        assert st.reads and "*" not in st.reads, name
        keys = expand((*st.reads, *st.unkeyed))
        assert all(k.partition(".")[2] in SCHEMA[k.partition(".")[0]] for k in keys), name
        # no stage is keyed by every section: the main job's stages are keyed by a part of the scene
        assert len({k.partition(".")[0] for k in st.keyed()}) < len(SCHEMA), name
    stages = runner.registry()
    assert len(stages["simulate"].keyed()) < 60 and len(stages["report"].keyed()) < 20


def test_stages_read_their_builders_fields():
    stages = runner.registry()
    assert stages["dmw"].reads == dmw_record.FIELDS
    assert stages["interface"].reads == interface_tables.FIELDS
    assert stages["bulge"].reads == bulge_table.FIELDS
    for name in ("calibrate", "simulate", "statics", "sweep", "ensemble"):
        assert set(expand(scene_inputs.SIMULATION_FIELDS)) <= set(stages[name].keyed()), name
    assert set(expand(assembly.MODEL_FIELDS)) <= set(expand(scene_inputs.SIMULATION_FIELDS))
    # a registry's parameters are the model's fields (here the Reynolds bulge's pad pressure)
    assert "air_bearing.pad_pressure_mpa" in assembly.MODEL_FIELDS
    # what a simulation does not read is no input of the stages that only simulate
    for key in ("materials.hardness_gpa", "lubricant.thickness_nm", "report.histories_nm", "sweep.protrusion_nm"):
        assert key not in stages["simulate"].keyed(), key
    assert "sweep.batch_size" in stages["sweep"].unkeyed and "sweep.batch_size" not in stages["sweep"].keyed()


def _candidates(spec: Key, value):
    """Values other than ``value`` a key of schema ``spec`` may take, the likeliest valid first."""
    if spec.choices is not None and spec.kind == "str":
        return [c for c in (spec.choices if isinstance(spec.choices, Registry) else spec.choices) if c != value]
    if spec.kind == "bool":
        return [not value]
    if spec.kind == "int":
        return [value + 1, value - 1, value * 2, 1] if value is not None else [1, 2, 10]
    if spec.kind in ("float", "float_or_str"):
        if isinstance(value, (int, float)) and value:
            return [value * 1.05, value * 0.95, value * 2, value * 0.5, -value]
        return [0.5, 0.1, 1.0, 10.0, 2.0, 0.01]
    if spec.kind == "floats":
        if value:
            return [[v * 1.05 for v in value], [v * 0.95 for v in value], value[:-1]]
        return [[9.0], [10.0, 11.0]]
    if spec.kind == "range" and value is not None:
        return [{**value, "stop": value["stop"] + value["step"]}, {**value, "start": value["start"] - value["step"]}]
    if spec.kind in ("strs", "tables") and value and len(value) > 1:
        return [list(value[:-1]), list(value[1:])]
    return []


#: Edits of keys whose valid values no generic candidate reaches (a file, a key that needs another).
EDITS = {
    "dmw.source": ['dmw.source="{csv}"'],
    "dmw.column": ['dmw.column="w"'],
    "dmw.unit": ['dmw.unit="um"'],
    "roughness.afm": ['roughness.afm=["{afm}"]'],
    "roughness.channel": ['roughness.afm=["{afm}"]', 'roughness.channel="Height"'],
    "interface.model": ['roughness.afm=["{afm}"]', 'interface.model="deterministic"'],
    "interface.adhesion": ['interface.adhesion="two-population"', "lubricant.bridge_work_of_adhesion_j_m2=0.005"],
    "lubricant.bridge_work_of_adhesion_j_m2": ['interface.adhesion="two-population"',
                                               "lubricant.bridge_work_of_adhesion_j_m2=0.005"],
    "air_bearing.lift_cap_gap_nm": ['air_bearing.bulge="reynolds"', "air_bearing.lift_cap_gap_nm=1.65"],
    "sweep.roughness": ['sweep.roughness=["scene", {{label="rough", sigma_nm=0.8}}]'],
    "sweep.damping_ratio": ["sweep.damping_ratio=[0.02, 0.05]"],
    "sensitivity.protrusion_nm": ["sensitivity.protrusion_nm={{start = 9.0, stop = 11.0, step = 0.5}}"],
    "tfc.actuation_power_mw": ["tfc.actuation_power_mw=[0.0, 50.0]", "tfc.actuation_protrusion_nm=[0.0, 20.0]"],
    "tfc.actuation_protrusion_nm": ["tfc.actuation_power_mw=[0.0, 50.0]", "tfc.actuation_protrusion_nm=[0.0, 20.0]"],
    "touchdown.onset_mw": ["tfc.actuation_nm_per_mw=0.2", "touchdown.onset_mw=49.0", "touchdown.previous_mw=48.0"],
    "touchdown.previous_mw": ["tfc.actuation_nm_per_mw=0.2", "touchdown.onset_mw=49.0", "touchdown.previous_mw=48.0"],
}


@pytest.fixture(scope="module")
def files(repo_root, tmp_path_factory):
    """The files of :data:`EDITS`: a measured DMW record (a CSV of displacement [nm]) and an AFM scan."""
    csv = tmp_path_factory.mktemp("record") / "record.csv"
    t = np.arange(20000) / 4e6
    np.savetxt(csv, np.column_stack([t, 0.3 * np.sin(2 * np.pi * 1e5 * t)]), delimiter=",",
               header="time_s,displacement_nm", comments="")
    return {"csv": csv, "afm": repo_root / "tests" / "data" / "afm" / "mi-1.mi"}


def _edited(scene, key: str, files):
    """The scene with ``key`` changed to a valid value (and nothing else, but for :data:`EDITS`); ``None``
    when no candidate is valid."""
    section, _, name = key.partition(".")
    if key in EDITS:
        try:
            return load_scene(scene.path, [*LIGHT, *(s.format(**files) for s in EDITS[key])])
        except SceneError:
            return None
    for value in _candidates(SCHEMA[section][name], scene[section][name]):
        try:
            new = scene.replace(**{section: {name: value}})
        except SceneError:
            continue
        if new[section][name] != scene[section][name]:
            return new
    return None


def _changed(a, b) -> set[str]:
    return {f"{s}.{k}" for s in a.config for k in a.config[s] if a.config[s][k] != b.config[s].get(k)}


def _keys(scene, out) -> dict[str, str]:
    r = runner.Runner(scene, out)
    return {name: r.key(name) for name in r.stages}


def _expected(stages, scene, new, changed: set[str]) -> set[str]:
    """The stages whose inputs key must change: those declaring a changed key, those whose derived values or
    upstream set changed, and everything downstream of them (in a folder where no optional stage is current)."""
    direct = {n for n, st in stages.items()
              if set(st.keyed()) & changed or st.derived(scene) != st.derived(new)
              or st.upstream_names(scene) != st.upstream_names(new)}
    out = set(direct)
    grew = True
    while grew:
        grew = False
        for n, st in stages.items():
            if n not in out and set(st.upstream_names(new)) & out:  # (optional stages: not current here)
                out.add(n)
                grew = True
    return out


DECLARED = sorted({k for st in runner.registry().values() for k in st.keyed()})


@pytest.mark.parametrize("key", DECLARED)
def test_a_declared_key_recomputes_exactly_its_readers(key, light, files, tmp_path):
    stages = runner.registry()
    new = _edited(light, key, files)
    if new is None:
        pytest.fail(f"no valid edit of {key}: add one to EDITS")
    changed = _changed(light, new)
    assert key in changed
    before, after = _keys(light, tmp_path), _keys(new, tmp_path)
    recomputed = {n for n in stages if before[n] != after[n]}
    unused = set(runner.unused_keys(light)) | set(runner.unused_keys(new))
    if changed <= unused:  # (a synthesis key of a measured record: no input at all)
        assert recomputed == set()
    else:
        assert recomputed == _expected(stages, light, new, changed - unused), key


@pytest.fixture(scope="module")
def built(light, tmp_path_factory):
    """The main job and ``simulate`` of the light scene, built (every compute under its declaration)."""
    out = tmp_path_factory.mktemp("reads")
    wanted = [*runner.main_job(light), "simulate"]
    runner.Runner(light, out).build(wanted)
    return out, wanted


def _stamps(out):
    return {p.relative_to(out).as_posix(): p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()
            and ".hdi" not in p.parts}


@pytest.mark.slow
@pytest.mark.parametrize("edit, recomputed", [
    # a key of the dynamics only: the stages that simulate, and the report after them
    ("lubricant.meniscus_time_us=5.0", {"calibrate", "simulate", "statics", "sweep", "ensemble", "report"}),
    # a key of the surfaces (hardness): the statistics, the tables and everything that reads them
    ("materials.hardness_gpa=9.0", {"roughness", "interface", "calibrate", "simulate", "statics", "sweep",
                                    "ensemble", "report"}),
    # a key of the sweep's histories and the report's figures
    ("report.histories_nm=[9.0, 10.0]", {"sweep", "ensemble", "report"}),
])
def test_an_edit_recomputes_the_declaring_stages_end_to_end(built, light, edit, recomputed):
    out, wanted = built
    new = load_scene(light.path, [*LIGHT, edit])
    plan = runner.Runner(new, out).plan(wanted)
    stale = {n for n in plan if runner.Runner(new, out).stale_reason(n) is not None}
    assert stale == recomputed & set(plan)
    assert stale == _expected(runner.registry(), light, new, _changed(light, new)) & set(plan)


@pytest.mark.slow
def test_a_rebuild_rewrites_only_the_declaring_stages(built, light):
    out, wanted = built
    new = load_scene(light.path, [*LIGHT, "report.histories_nm=[9.0, 10.0]"])
    before = _stamps(out)
    runner.Runner(new, out).build(wanted)
    after = _stamps(out)
    rewritten = {f for f in before if after.get(f) != before[f]}
    assert "interface.nc" not in rewritten and "calibration.nc" not in rewritten and "statics.nc" not in rewritten
    assert {"sweep.nc", "report/summary.md"} <= rewritten
    runner.Runner(light, out).build(wanted)  # (back to the fixture's scene for the other tests)


def test_an_undeclared_read_is_refused_naming_the_stage_and_the_key(light, tmp_path):
    def compute(scene, inputs):
        scene["dmw"]["rms_nm"]  # declared
        scene["tfc"]["protrusion_nm"]  # not declared

    st = runner.Stage("toy", compute, outputs=("toy.nc",), reads=("dmw.rms_nm",))
    with pytest.raises(UndeclaredRead, match=r"^the toy stage read the scene key tfc.protrusion_nm, which it does "
                                             r"not declare"):
        runner.Runner(light, tmp_path, stages={"toy": st}).build(["toy"])
    assert not (tmp_path / "toy.nc").exists()


def test_a_stage_declares_schema_keys_only():
    with pytest.raises(ValueError, match=r"'tfc.protrusion': no key of the scene schema"):
        runner.Stage("toy", lambda scene, inputs: None, outputs=("toy.nc",), reads=("tfc.protrusion",))
    with pytest.raises(ValueError, match=r"'\*': no key of the scene schema"):
        dataclasses.replace(runner.registry()["simulate"], reads=("*",))


@pytest.mark.parametrize("study", ["identify", "sensitivity", "accuracy"])
def test_a_study_keys_its_candidates_inputs_within_its_declaration(study, light, tmp_path):
    """A study makes its candidates' inputs itself (``pipeline.evaluations.candidate_inputs``: their stage keys
    by a runner on the candidate scene, as the study reads it): every key those read is one it declares."""
    view = runner.registry()[study].view(light)
    r = runner.Runner(view, tmp_path)
    for stage in ("roughness", "dmw", "interface", "bulge"):
        assert r.key(stage) == runner.Runner(light, tmp_path).key(stage)
    with pytest.raises(UndeclaredRead, match=rf"the {study} stage read the scene key report.realisations"):
        runner.Runner(view, tmp_path).key("ensemble")
