"""The main job: `hdi run` after set-up, everything recomputed (--force), on the paper scene
(``configs/paper-2009.toml``) and on the scene ``make run`` runs (:data:`MAIN`: the Reynolds bulge
bearing's table, static starts and the calibration past the touchdown).

Target: under 15 s (median of 3 fresh processes, after one untimed run that builds the inputs and the
numba cache), with the report's checks over 8 DMW realisations (the ``ensemble`` stage; 8 s without
them). Baseline of the same run: a fresh interpreter doing what every ``hdi`` command does
first (the CLI and the stage registry), the floor no recomputation can go below. The per-stage
seconds of the last run are kept.

Then the report's figures, in this process: drawn by the pool of forked workers
(:func:`pipeline.analyses.plots.draw_all`, the default) against one after the other (``workers=1``).
"""

from __future__ import annotations

import functools
import re
import shutil
import statistics
import subprocess
import tempfile
from pathlib import Path

from benchmarks.common import ROOT, hdi, makefile_scene, record, startup_seconds, timeit

PAPER = str(ROOT / "configs" / "paper-2009.toml")


#: The scene of ``make run``.
MAIN = makefile_scene("SCENE")


def hdi_run(results: list[dict], scene: str, label: str, floor: list[float]) -> Path:
    """Median of 3 ``hdi run SCENE --force`` after an untimed one; returns the output folder."""
    tmp = Path(tempfile.mkdtemp(prefix="bench_run_"))
    args = ("run", scene, "--out", str(tmp))
    hdi(*args)
    times, cpus, stages = [], [], {}
    for _ in range(3):
        wall, cpu, done = hdi(*args, "--force", stderr=subprocess.PIPE, text=True)
        times.append(wall)
        cpus.append(cpu)
        # the runner logs "<stage>: wrote <outputs> (<seconds> s)" on stderr
        stages = {m.group(1): float(m.group(2))
                  for m in re.finditer(r"^(\w+): wrote .*\((\d+\.\d+) s\)$", done.stderr, re.M)}
    record(results, f"hdi run {label} --force (main job with the report's ensemble of 8, everything recomputed)",
           times, target_s=15.0, stage_seconds_last_run=stages, cpu_median_s=statistics.median(cpus),
           ratio_to_startup=statistics.median(times) / statistics.median(floor))
    return tmp


def run(results: list[dict]) -> None:
    floor = startup_seconds(3)
    record(results, "interpreter start + hdi start-up (CLI and stage registry, fresh process)", floor)
    out = hdi_run(results, PAPER, "paper-2009", floor)
    try:
        report_figures(results, out)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    if MAIN != PAPER:
        shutil.rmtree(hdi_run(results, MAIN, f"{Path(MAIN).stem} (make run)", floor), ignore_errors=True)


def report_figures(results: list[dict], out: Path) -> None:
    """The report stage in process on the datasets of ``out``: figures by forked workers, then in order."""
    from pipeline.analyses import plots
    from pipeline.runner import Inputs
    from pipeline.config.scene import load_scene
    from pipeline.stages import report
    scene = load_scene(PAPER)
    draw_all = plots.draw_all

    def once(workers: int | None) -> None:
        plots.draw_all = functools.partial(draw_all, workers=workers)
        try:
            with tempfile.TemporaryDirectory() as staging:
                report.compute(scene, Inputs(out=out, staging=Path(staging)))
        finally:
            plots.draw_all = draw_all

    pool = timeit(lambda: once(None), repeat=3)
    alone = timeit(lambda: once(1), repeat=3)
    record(results, "report stage, paper scene, 8 figures: one process", alone)
    record(results, "report stage, paper scene, 8 figures: forked workers (default)", pool,
           speedup_vs_one_process=statistics.median(alone) / statistics.median(pool))
