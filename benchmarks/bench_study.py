"""Parameter-study benchmarks (one run each: they take minutes).

* ``hdi identify`` of the paper scene with every default free parameter (``[identify]``): wall time
  of the whole command (target 15 min on 2 cores), evaluations per second of the fan-out, and the
  share of the fan-out's worker time spent in the integrator (``kernel_seconds`` of identify.nc over
  workers x batch wall time).
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
        wall = _hdi("identify", str(scene_dir / "paper-2009.toml"), "--out", str(out), "--workers", str(WORKERS))
        record(results, "identify, paper scene, default free parameters (wall)", [wall], target_s=900.0,
               **study_stats(out / "identify.nc", WORKERS))
        out = Path(tmp) / "sensitivity"
        shutil.copytree(inputs, out)
        wall = _hdi("sensitivity", paper, "--out", str(out), "--workers", str(WORKERS),
                    "--set", 'sensitivity.methods=["morris"]', "--set", "sensitivity.morris_trajectories=10")
        record(results, "sensitivity, Morris 10 x 8 parameters = 90 sweeps of 76 (wall)", [wall], target_s=300.0,
               **study_stats(out / "sensitivity.nc", WORKERS))
