"""Parameter-study benchmarks (one run each: they take minutes).

* ``hdi identify`` as ``make identify`` runs it (the Makefile's ``IDENTIFY_SCENE``,
  ``configs/paper-2009-bulge.toml``: 6 free parameters, 8-realisation DMW ensembles, 13 protrusions x 8
  records = 104 runs per evaluation, the budget of the scene's ``[identify]``: population 4 x 6,
  12 generations, 5 profile points): wall and CPU time of the whole command (target 15 min on 2 cores),
  evaluations per second of the fan-out, the share of the workers' time in the integrator
  (``kernel_seconds`` over workers x batch wall time), and the projection of the schema's default
  budget (population 10 x parameters, 20 generations, 11 profile points, optimised profiles of at most 40
  evaluations per parameter) from the measured seconds per evaluation.
* ``hdi sensitivity`` Morris screening, 10 trajectories over the 8 default parameters = 90 sweeps of
  the 76-protrusion paper grid (target 5 min on 2 cores).

Both as fresh ``hdi`` processes on a local cluster of 2 workers, from the same inputs (dmw,
interface) made once and not timed. ``BENCH_STUDY=0`` leaves this module out (benchmarks/run.py; the
studies dominate ``make bench``).
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from .common import ROOT, hdi, makefile_scene, record

WORKERS = 2
#: The schema's default budget of ``[identify]`` (pipeline/config/scene.py), for the projection.
DEFAULT_BUDGET = {"population": 10, "generations": 20, "profile_points": 11, "profile_method": "optimised",
                  "profile_evaluations": 40}
#: The default budget's identify on 8-record ensembles on the 2 cores (~20 min projected with the static
#: starts in Python) [s]
DEFAULT_BUDGET_TARGET_S = 600.0


def evaluation_budget(scene_path: str, **budget: int) -> int:
    """Largest number of evaluations of identify (differential evolution may stop earlier) with the
    scene's ``[identify]`` budget, or ``budget`` (population, generations, profile_points, profile_method,
    profile_evaluations) instead: the reconstructed point, population x parameters x (generations + 1),
    the slices and Gauss-Newton, and an optimised profile's re-optimisation (profile_evaluations per
    parameter at most); one profile round (a profile point better than the optimum repeats them)."""
    from pipeline.config.scene import load_scene
    i = {**load_scene(scene_path)["identify"], **budget}
    n = len(i["parameters"])
    reopt = i["profile_evaluations"] * n if i["profile_method"] == "optimised" and n > 1 else 0
    return 1 + i["population"] * n * (i["generations"] + 1) + (i["profile_points"] + 1) * n + 2 * n + reopt


def _hdi(*args: str) -> float:
    """Wall time [s] of one fresh ``hdi`` process."""
    return hdi(*args)[0]


def study_stats(path: Path, workers: int) -> dict:
    """Evaluations per second and kernel share of an identify.nc / sensitivity.nc."""
    from pipeline.runner import last_run
    entry = last_run(path.parent, path.stem)  # the run log of the stage (timings are not in the datasets)
    batch = float(entry["batch_seconds"])
    n = int(entry["evaluations_computed"])
    kernel = float(entry["kernel_seconds"])
    return {"evaluations": n, "batch_seconds": batch, "evaluations_per_second": n / batch if batch else None,
            "kernel_share": kernel / (workers * batch) if batch else None}


def run(results: list[dict]) -> None:
    paper = str(ROOT / "configs" / "paper-2009.toml")
    ident = makefile_scene("IDENTIFY_SCENE")
    with tempfile.TemporaryDirectory() as tmp:
        # the scenes run from a copy (with what they extend): nothing of the study lands in configs/
        scene_dir = Path(tmp) / "configs"
        scene_dir.mkdir()
        for name in {Path(paper).name, Path(ident).name}:
            shutil.copy(ROOT / "configs" / name, scene_dir / name)
        scene = str(scene_dir / Path(ident).name)
        out = Path(tmp) / "identify"
        _hdi("interface", scene, "--out", str(out))
        _hdi("dmw", scene, "--out", str(out))
        wall, cpu, _ = hdi("identify", scene, "--out", str(out), "--workers", str(WORKERS))
        stats = study_stats(out / "identify.nc", WORKERS)
        per_eval = stats["batch_seconds"] / stats["evaluations"] if stats["evaluations"] else None
        default_n = evaluation_budget(scene, **DEFAULT_BUDGET)
        record(results, f"identify as make identify ({Path(ident).name}: its [identify] budget, "
               "8-realisation ensembles) (wall)", [wall], target_s=900.0, cpu_s=cpu, **stats,
               seconds_per_evaluation=per_eval, scene_budget_evaluations=evaluation_budget(scene),
               default_budget_evaluations=default_n,
               projected_default_budget_s=per_eval * default_n if per_eval else None,
               default_budget_target_s=DEFAULT_BUDGET_TARGET_S,
               projected_default_budget_meets_target=bool(per_eval and per_eval * default_n < DEFAULT_BUDGET_TARGET_S))
        inputs = Path(tmp) / "inputs"
        _hdi("interface", paper, "--out", str(inputs))
        _hdi("dmw", paper, "--out", str(inputs))
        out = Path(tmp) / "sensitivity"
        shutil.copytree(inputs, out)
        wall = _hdi("sensitivity", paper, "--out", str(out), "--workers", str(WORKERS),
                    "--set", 'sensitivity.methods=["morris"]', "--set", "sensitivity.morris_trajectories=10")
        record(results, "sensitivity, Morris 10 x 8 parameters = 90 sweeps of 76 (wall)", [wall], target_s=300.0,
               **study_stats(out / "sensitivity.nc", WORKERS))
