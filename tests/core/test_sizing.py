"""The size of the work a scene asks for (pipeline/sizing.py), counted by hand on the paper scene: interface
table rows from -5 nm (11 nm flying height less the 15 nm deepest protrusion and 1 nm) to 30 nm in 0.05 nm
steps, history samples of a 2 ms run at 250 ns, the 2.1 ms DMW record at 4 MHz, the sweep's 76 scenes and the
studies' evaluations by their formulas; a size beyond its limit is one line that ``--yes`` lifts, a
protrusion beyond the flying height by more than 100 nm is refused even then."""

from __future__ import annotations

import pytest

from pipeline import sizing
from pipeline.config.limits import POLISH_EVALUATIONS
from pipeline.config.limits import MAX_HISTORY_SAMPLES, MAX_SCENES, LimitError
from pipeline.model.interface_tables import separation_labels


def _sizes(scene, stage: str) -> dict[str, tuple[int, int]]:
    """``{first words of what: (size, limit)}``."""
    return {what.split(" (")[0]: (size, limit) for what, size, limit in sizing.sizes(scene, stage)}


def test_the_paper_sweep_is_counted_by_hand(paper_scene):
    got = _sizes(paper_scene, "sweep")
    assert got["interface table rows"][0] == 701 == separation_labels(-5.0, 30.0, 0.05).size
    assert got["history samples per run"][0] == round(2e-3 / 250e-9) + 1 == 8001
    assert got["DMW record samples"][0] == 8400                  # 2.1 ms x 4 MHz
    assert got["sweep scenes"] == (76, MAX_SCENES)               # 0 to 15 nm in 0.2 nm steps
    assert got["kept history samples"][0] == 2 * 8001            # report.histories_nm = [5, 11]
    assert sizing.deepest_studied_protrusion_nm(paper_scene) == 15.0 and sizing.table_rows(paper_scene) == 701


def test_each_stage_counts_only_what_it_makes(paper_scene):
    assert _sizes(paper_scene, "roughness") == {}
    assert set(_sizes(paper_scene, "interface")) == {"interface table rows", "DMW record samples"}
    assert set(_sizes(paper_scene, "dmw")) == {"interface table rows", "DMW record samples"}
    no_dmw = paper_scene.replace(scene={"effects": ["air_bearing", "pitch"]})
    assert set(_sizes(no_dmw, "simulate")) == {"history samples per run"}
    assert _sizes(paper_scene, "statics")["statics protrusions"] == (76, MAX_SCENES)


def test_the_studies_evaluations_follow_their_formulas(paper_scene):
    i = paper_scene["identify"]
    n_par = len(i["parameters"])
    assert (i["population"], i["generations"], n_par, i["profile_points"], i["profile_evaluations"],
            i["realisations"]) == (10, 20, 6, 11, 40, 8)
    # (population x parameters x (generations + 1) + (profile points + re-optimisations + the polish's 40) x
    # parameters) x realisations
    assert POLISH_EVALUATIONS == 40
    assert _sizes(paper_scene, "identify")["identify evaluations"][0] == (10 * 6 * 21 + (11 + 40 + 40) * 6) * 8 == 14448
    sliced = paper_scene.replace(identify={"profile_method": "slice", "polish": False})
    assert _sizes(sliced, "identify")["identify evaluations"][0] == (10 * 6 * 21 + 11 * 6) * 8
    # Morris r (k + 1) plus Saltelli N (k + 2), at each of the sweep's 76 protrusions
    s = paper_scene["sensitivity"]
    assert (s["morris_trajectories"], s["sobol_samples"], len(s["parameters"])) == (10, 32, 8)
    assert _sizes(paper_scene, "sensitivity")["sensitivity scenes"] == ((10 * 9 + 32 * 10) * 76, 10 * MAX_SCENES)


def test_a_size_beyond_its_limit_is_one_line_and_yes_lifts_it(paper_scene):
    fine = paper_scene.replace(solver={"output_step_ns": 0.5})     # 2 ms / 0.5 ns + 1 samples a run
    with pytest.raises(LimitError) as info:
        sizing.check_sizes(fine, "simulate", where="scene.toml")
    line = str(info.value)
    assert line == (f"scene.toml: 4,000,001 history samples per run (solver.duration_ms = 2 / output_step_ns = 0.5) "
                    f"exceed {MAX_HISTORY_SAMPLES:,}; pass --yes to run them anyway")
    sizing.check_sizes(fine, "simulate", yes=True)
    sizing.check_sizes(paper_scene, "run")                         # the paper scene is within every limit


def test_a_protrusion_far_beyond_the_flying_height_is_refused_even_with_yes(paper_scene):
    """(Loading refuses such a scene already; the check here guards a scene made in Python as plain tables.)"""
    tables = {name: dict(paper_scene[name]) for name in paper_scene.config}
    deep = {**tables, "tfc": {**tables["tfc"], "protrusion_nm": 111.5}}        # 11 nm + 100 nm + 0.5 nm
    with pytest.raises(LimitError, match=r"tfc.protrusion_nm = 111.5 nm: .*air_bearing.flying_height_nm = 11 nm \+ 100 nm"):
        sizing.check_sizes(deep, "simulate", yes=True)
    sizing.check_sizes({**tables, "tfc": {**tables["tfc"], "protrusion_nm": 111.0}}, "simulate", yes=True)  # the limit itself
    sizing.check_sizes(paper_scene.replace(tfc={"protrusion_nm": 111.0}), "simulate")
