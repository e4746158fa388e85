"""The main job (issue 12): `hdi run` on the paper scene after set-up, everything recomputed (--force).

Target: under 8 s (median of 3 fresh processes, after one untimed run that builds the inputs and the
numba cache). Baseline of the same run: a fresh interpreter importing the CLI and every stage of the
main job, the floor no recomputation can go below. The per-stage seconds of the last run are kept.
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.common import record, run_process

ROOT = Path(__file__).resolve().parents[1]
PAPER = str(ROOT / "configs" / "paper-2009.toml")
IMPORTS = ("import pipeline.cli, pipeline.stages.roughness, pipeline.stages.dmw, pipeline.stages.interface, "
           "pipeline.stages.calibrate, pipeline.stages.sweep, pipeline.stages.report")


def run(results: list[dict]) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "pipeline.cli", "run", PAPER, "--out", tmp]
        subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True)
        times, cpus, stages = [], [], {}
        for _ in range(3):
            wall, cpu, done = run_process(cmd + ["--force"], ROOT, capture_output=True, text=True)
            times.append(wall)
            cpus.append(cpu)
            stages = {m.group(1): float(m.group(2))
                      for m in re.finditer(r"^\s*(\w+): .*\((\d+\.\d+) s\)$", done.stdout, re.M)}
        floor = []
        for _ in range(3):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", IMPORTS], cwd=ROOT, check=True)
            floor.append(time.perf_counter() - t0)
        record(results, "interpreter start + imports of the main job's stages", floor)
        record(results, "hdi run paper-2009 --force (main job, everything recomputed)", times, target_s=8.0,
               stage_seconds_last_run=stages, cpu_median_s=statistics.median(cpus), ratio_to_imports=statistics.median(times) / statistics.median(floor))
