"""Sweep benchmarks: the paper sweep and the 684-scene grid, wall time including start-up,
and the speed-up of 2 workers over 1 (all measured in the same run, as fresh `hdi` processes).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .common import record

ROOT = Path(__file__).resolve().parents[1]


def _hdi(*args: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pipeline.cli", *args], cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def _sweep_wall(config: str, workers: int, inputs: Path, repeat: int = 3,
                compute: list | None = None) -> list[float]:
    """Wall time of `hdi sweep` (process start-up, cluster start-up, compute, assembly).

    ``compute`` collects the wall time of the batch phase alone (``compute_seconds`` of the sweep's entry
    in the run log, ``.hdi/runs.jsonl``: timings are kept out of the datasets).
    """
    from pipeline.runner import last_run
    times = []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp)
            for f in inputs.glob("*.nc"):
                shutil.copy(f, out / f.name)
            times.append(_hdi("sweep", config, "--out", str(out), "--workers", str(workers)))
            if compute is not None:
                compute.append(float(last_run(out, "sweep")["compute_seconds"]))
    return times


def run(results: list[dict]) -> None:
    paper = str(ROOT / "configs" / "paper-2009.toml")
    grid = str(ROOT / "configs" / "sweep-3x3.toml")
    with tempfile.TemporaryDirectory() as tmp:
        inputs = Path(tmp)
        # inputs of the sweep (dmw, interface, calibration), made once and not timed
        _hdi("calibrate", paper, "--out", str(inputs))
        one = _sweep_wall(paper, 1, inputs)
        two = _sweep_wall(paper, 2, inputs)
        record(results, "paper sweep, 76 protrusions, 1 worker (wall, incl. start-up)", one)
        record(results, "paper sweep, 76 protrusions, 2 workers (wall, incl. start-up)", two, target_s=30.0,
               speedup_vs_1_worker=min(one) / min(two) if two else None)
        c1, c2 = [], []
        g1 = _sweep_wall(grid, 1, inputs, repeat=2, compute=c1)
        g2 = _sweep_wall(grid, 2, inputs, repeat=2, compute=c2)
        speedup = min(g1) / min(g2)
        speedup_c = min(c1) / min(c2)
        record(results, "sweep-3x3 grid, 684 scenes, 2 workers (wall, incl. start-up)", g2, target_s=120.0,
               speedup_vs_1_worker=speedup, speedup_target=1.8)
        record(results, "sweep-3x3 grid, 684 scenes, 1 worker (wall, incl. start-up)", g1)
        record(results, "sweep-3x3 grid, batch phase only, 2 workers", c2, speedup_vs_1_worker=speedup_c,
               speedup_target=1.8)
        record(results, "sweep-3x3 grid, batch phase only, 1 worker", c1)
        print(f"  speed-up of 2 workers over 1 on the 684-scene grid: {speedup:.2f} whole command, "
              f"{speedup_c:.2f} batch phase (target >= 1.8)")
