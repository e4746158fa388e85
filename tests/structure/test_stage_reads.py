"""Every stage's ``compute`` reads only the scene keys its declaration puts in its inputs key.

A key a stage reads but does not declare is a silently stale result: change it, and the stage's
outputs still carry a current key. Here every stage of the main job (and ``simulate``) computes on
a scene that records each key it is asked for while ``compute`` runs, and each recorded key must
be in the part of the scene the runner hashes for that stage (:func:`pipeline.runner.scene_part` of
its ``reads``/``excludes``), or be one of its ``derived`` quantities' sources.
"""

from __future__ import annotations

import dataclasses

import pytest

from pipeline import runner
from pipeline.config.scene import load_scene

from scene_recording import declared, recording


#: Keys a stage reads that its key covers another way: its ``derived`` values, or how the work is
#: cut rather than what it computes (each sweep part is checked against its batch, so parts of another
#: batch size are recomputed, not mixed).
DERIVED = {
    # deepest_protrusion_nm; lubricant_shear (whether the term is on, not its stress); friction_stress_law
    # (the per-summit friction law the friction column integrates, if the scene's law is one)
    "interface": {"tfc.protrusion_nm", "sweep.protrusion_nm", "lubricant.shear_stress_mpa", "contact.friction_law"},
    "sweep": {"sweep.batch_size"},
}


@pytest.fixture(scope="module")
def recorded(paper_config, tmp_path_factory):
    """``{stage: keys read by its compute}`` for the main job and simulate of a light paper scene."""
    scene = load_scene(paper_config, ["sweep.protrusion_nm={start = 9.0, stop = 11.0, step = 0.2}",
                                      "solver.duration_ms=0.8", "solver.transient_ms=0.3"])
    rec = recording(scene)
    stages = runner.registry()
    logs: dict[str, set] = {}

    def wrap(name: str, compute):
        def recorded_compute(sc, inputs):
            logs[name] = set()
            sc.log = logs[name]
            try:
                return compute(sc, inputs)
            finally:
                sc.log = None
        return recorded_compute

    wrapped = {n: dataclasses.replace(st, compute=wrap(n, st.compute)) for n, st in stages.items()}
    wanted = [*runner.main_job(scene, stages), "simulate"]
    runner.Runner(rec, tmp_path_factory.mktemp("reads"), stages=wrapped).build(wanted)
    return scene, stages, logs


def test_each_stage_reads_only_what_it_declares(recorded):
    scene, stages, logs = recorded
    assert {"roughness", "dmw", "interface", "calibrate", "sweep", "report", "simulate"} <= set(logs)
    problems = {}
    for name, keys in logs.items():
        missing = keys - declared(stages[name], scene) - DERIVED.get(name, set())
        if missing:
            problems[name] = sorted(missing)
    assert not problems, f"keys read by compute but not in the stage's inputs key: {problems}"


def test_the_recorder_catches_an_undeclared_read(recorded):
    """The check can fail: the interface stage reading a [dmw] key it does not declare is reported."""
    scene, stages, logs = recorded
    assert "dmw.rms_nm" not in declared(stages["interface"], scene)
    assert "lubricant.work_of_adhesion_j_m2" in logs["interface"]  # (a read that is recorded)
