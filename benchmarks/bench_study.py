"""Parameter-study benchmarks (one run each: they take minutes).

* ``hdi identify`` of the paper scene with every default free parameter (``[identify]``) and
  8-realisation DMW ensembles (``identify.realisations = 8``, the default: 13 protrusions x 8 records =
  104 runs per evaluation): wall and CPU time of the whole command (target 15 min on 2 cores),
  evaluations per second of the fan-out, and the share of the fan-out's worker time spent in the
  integrator (``kernel_seconds`` of identify.nc over workers x batch wall time). The default budget
  (20 generations, at most 1345 evaluations) does not fit: 104 runs of ~13.5 ms of CPU each per
  evaluation (measured: 78 evaluations, 8112 runs, 110 s of CPU) is ~16 min on two quiet cores before
  any overhead. The row runs
  :data:`GENERATIONS` generations instead (at most 865 evaluations; every other setting the default)
  and records the projection of the default budget from the measured seconds per evaluation.
* ``hdi sensitivity`` Morris screening, 10 trajectories over the 8 default parameters = 90 sweeps of
  the 76-protrusion paper grid (target 5 min on 2 cores).

Both as fresh ``hdi`` processes on a local cluster of 2 workers, from the same inputs (dmw,
interface) made once and not timed. ``BENCH_STUDY=0`` skips them (they dominate ``make bench``).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from .common import ROOT, hdi, record

WORKERS = 2
#: DMW realisations per evaluation (the default of ``identify.realisations``).
REALISATIONS = 8
#: Differential-evolution generations of the bench row (default 20: does not fit 15 min with
#: 8-realisation ensembles, see the module docstring).
GENERATIONS = 12


def evaluation_budget(scene_path: str, generations: int) -> int:
    """Largest number of evaluations of identify (differential evolution may stop earlier): the
    reconstructed point, population x parameters x (generations + 1), the profiles and Gauss-Newton."""
    from pipeline.config.scene import load_scene
    i = load_scene(scene_path)["identify"]
    n = len(i["parameters"])
    return 1 + i["population"] * n * (generations + 1) + (i["profile_points"] + 1) * n + 2 * n


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
    if os.environ.get("BENCH_STUDY", "1") == "0":
        print("bench_study skipped (BENCH_STUDY=0)")
        return
    paper = str(ROOT / "configs" / "paper-2009.toml")
    with tempfile.TemporaryDirectory() as tmp:
        inputs = Path(tmp) / "inputs"
        _hdi("interface", paper, "--out", str(inputs))
        _hdi("dmw", paper, "--out", str(inputs))
        scene_dir = Path(tmp) / "configs"
        scene_dir.mkdir()
        # identify writes <scene>-identified.toml beside the scene: run it on a copy
        shutil.copy(paper, scene_dir / "paper-2009.toml")
        out = Path(tmp) / "identify"
        shutil.copytree(inputs, out)
        scene = str(scene_dir / "paper-2009.toml")
        wall, cpu, _ = hdi("identify", scene, "--out", str(out), "--workers", str(WORKERS),
                           "--set", f"identify.realisations={REALISATIONS}",
                           "--set", f"identify.generations={GENERATIONS}")
        stats = study_stats(out / "identify.nc", WORKERS)
        per_eval = stats["batch_seconds"] / stats["evaluations"] if stats["evaluations"] else None
        default_n = evaluation_budget(scene, 20)
        record(results, f"identify, paper scene, 6 free parameters, {REALISATIONS}-realisation ensembles, "
               f"{GENERATIONS} generations (wall)", [wall], target_s=900.0, cpu_s=cpu, **stats,
               seconds_per_evaluation=per_eval, default_budget_evaluations=default_n,
               projected_default_budget_s=per_eval * default_n if per_eval else None)
        out = Path(tmp) / "sensitivity"
        shutil.copytree(inputs, out)
        wall = _hdi("sensitivity", paper, "--out", str(out), "--workers", str(WORKERS),
                    "--set", 'sensitivity.methods=["morris"]', "--set", "sensitivity.morris_trajectories=10")
        record(results, "sensitivity, Morris 10 x 8 parameters = 90 sweeps of 76 (wall)", [wall], target_s=300.0,
               **study_stats(out / "sensitivity.nc", WORKERS))
