"""Calibration benchmarks: the exact method's kernel time on the paper scene, against bisection.

Rows: (1) the exact k*(protrusion) over the paper grid (76 protrusions plus the two touchdown
protrusions: two flying runs each, bisection only where the transient dips lower), in process, after
compilation: target < 1 s; (2) the bisection method for the two touchdown protrusions alone (what the
exact method replaces), same run, as the baseline of the speed-up; (3) `hdi calibrate` as a fresh
process, whole command; (4) the calibration of the main scene (the Makefile's ``SCENE``: the bulge's
tabulated lift, 76 protrusions and the two touchdown protrusions) in process on the local default (2
threads), against the ~4 s it took with the static starts in Python (:data:`MAIN_BEFORE_S`; target: 2x).
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from benchmarks.common import makefile_scene, record, timeit
from pipeline.model import assembly
from pipeline.config.scene import load_scene
from pipeline.analyses import calibration as cal
from pipeline.stages.simulate import model_inputs
from pipeline.config.grid import protrusion_grid

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "configs" / "paper-2009.toml"


def run(results: list[dict]) -> None:
    scene = load_scene(PAPER)
    td = scene["touchdown"]
    k_range, tol = tuple(td["k_range"]), td["k_tolerance"]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        interface, rec = model_inputs(scene, out)
        model = assembly.build_model(scene, interface, rec, k=0.0)
        todo = np.union1d(protrusion_grid(scene), [td["onset_nm"], td["previous_nm"]])

        def exact() -> None:
            # as a batch of the stage does (calibration.threshold_batch): one contact-off model, whose
            # static-start fold (searched once per repetition) the flying runs share and bounds the
            # bisection's models'
            off = replace(model, k=cal.CONTACT_OFF_K)
            for p in todo:
                lo, lo_all, _ = cal.flying_minimum(off, float(p))
                cal.k_star(off, float(p), lo, lo_all, k_range, tol)

        def bisection() -> None:
            for p in (td["onset_nm"], td["previous_nm"]):
                cal.k_threshold(model, p, k_range, tol)

        t_exact = timeit(exact, repeat=5)
        t_bis = timeit(bisection, repeat=3)
        record(results, f"calibration, exact k* at {todo.size} protrusions (kernel, in process)", t_exact,
               target_s=1.0)
        record(results, "calibration, bisection k* at the 2 touchdown protrusions only (kernel, in process)", t_bis,
               exact_whole_curve_over_bisection_two_points=statistics.median(t_exact) / statistics.median(t_bis))
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "pipeline.cli", "calibrate", str(PAPER), "--out", str(out),
                            "--force"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
            times.append(time.perf_counter() - t0)
        record(results, "hdi calibrate --force, paper scene, whole command (fresh process)", times)
    main_scene(results)


#: The main scene's calibration with the static starts in Python, not compiled (~4 s on the 2 cores) [s].
MAIN_BEFORE_S = 4.0


def main_scene(results: list[dict]) -> None:
    """Row (4): the main scene's calibration, in process, local default, from its inputs made once."""
    from pipeline.analyses.calibration import calibrate
    from pipeline.model.inputs import from_folder
    from pipeline.model.scene_inputs import input_stages
    from pipeline.runner import build
    scene = load_scene(makefile_scene("SCENE"))
    with tempfile.TemporaryDirectory() as tmp:
        for stage in input_stages(scene, calibration=False):
            build(stage, scene, Path(tmp))

        def once() -> None:
            calibrate(scene, from_folder(scene, tmp, calibration=False))

        times = timeit(once, repeat=5)
    med = statistics.median(times)
    record(results, "calibration of the main scene (in process, local default: 2 threads)", times,
           target_s=MAIN_BEFORE_S / 2, before_issue_26_s=MAIN_BEFORE_S, speedup_vs_before=MAIN_BEFORE_S / med)
