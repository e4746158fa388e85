"""The analyses layer imports nothing above it: no stage, no runner, no command line, directly or
through what it imports; and the paper's published values have one home."""

from __future__ import annotations

import pkgutil

import pipeline.analyses
from pipeline import code_version as cv
from pipeline.analyses import optimum
from pipeline.physics import paper
from pipeline.config.scene import SCHEMA

ABOVE = ("pipeline.stages", "pipeline.runner", "pipeline.cli", "pipeline.api")

#: The one import edge not followed: the package's lazy re-export of the public API (imported on first
#: use of one of its names, never when a module below imports the package; tests/structure/test_layers.py
#: LAZY_ALLOWED, where a subprocess checks that ``import pipeline`` loads no submodule).
LAZY_EDGES = {("pipeline", "pipeline.api")}


def test_analyses_import_only_downward():
    names = [f"pipeline.analyses.{m.name}" for m in pkgutil.iter_modules(pipeline.analyses.__path__)]
    assert "pipeline.analyses.paper_comparison" in names and "pipeline.analyses.knob_study" in names
    for name in names:
        seen, todo = set(), [name]
        while todo:  # every module it imports, transitively
            mod = todo.pop()
            if mod in seen:
                continue
            seen.add(mod)
            todo.extend(m for m in cv.imports(mod) if (mod, m) not in LAZY_EDGES)
        above = sorted(m for m in seen if m.startswith(ABOVE))
        assert not above, f"{name} imports {above}"


def test_paper_values_are_the_defaults_and_limits():
    """The scene's [paper] defaults and the optimum limits are the published values of physics/paper.py."""
    assert SCHEMA["touchdown"]["onset_nm"].default == paper.TOUCHDOWN_NM == 9.8
    assert SCHEMA["touchdown"]["previous_nm"].default == paper.PREVIOUS_STEP_NM == 9.6
    assert SCHEMA["identify"]["fhm_flying_percent"].default == paper.FHM_FLYING_PERCENT == 12.5
    assert SCHEMA["identify"]["fhm_flying_range_nm"].default == [4.0, 7.0]
    assert SCHEMA["identify"]["bouncing_range_nm"].default == [9.8, 10.8]
    assert SCHEMA["identify"]["interference_nm"].default == paper.INTERFERENCE_NM == 0.58
    assert SCHEMA["air_bearing"]["flying_height_nm"].default == paper.FLYING_HEIGHT_NM == 11.0
    assert SCHEMA["materials"]["plasticity_index"].default == paper.PLASTICITY_INDEX == 0.52
    assert SCHEMA["sweep"]["protrusion_nm"].default == {"start": 0.0, "stop": 15.0, "step": 0.2}
    assert optimum.FHM_LIMIT == paper.STABLE_FHM_PERCENT == 10.0
    assert optimum.BV_LIMIT == paper.SLIDING_BV_MAX_PERCENT == 2.0
    # a list default is a copy: a scene that edits its value in place cannot change the published one
    SCHEMA["dmw"]["band_khz"].default.append(0.0)
    try:
        assert paper.DMW_BAND_KHZ == (10.0, 500.0)
    finally:
        SCHEMA["dmw"]["band_khz"].default.pop()
