"""Benchmark of the static start state (pipeline.model.start, ``solver.start = "static"``, the default).

Rows, on the paper scene's protrusion grid (76 protrusions, 0-15 nm, k = 0.445):

1. the starts of every protrusion with the flying branch and its fold found once per model (the
   ladder: what a sweep batch pays; the first start includes the search), against
2. the same starts each continuing the flying branch from zero protrusion and bracketing the fold
   anew (the static start before the fold was kept per model): ratio in the first row;
3. the fold's search alone (once per model);
4. row 1 with Newton's method from Python (:func:`pipeline.physics.equilibrium.newton`) instead of
   compiled (:mod:`pipeline.model.static_solver`), and row 2 likewise (the static start in Python):
   ratios to the compiled rows.

The main scene's starts (the bulge's tabulated lift) are in the calibration's rows (bench_calibrate).
The uncached start takes ~0.1-0.2 s per protrusion past the adhesion fold.
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from benchmarks.common import record, timeit
from pipeline.config.grid import protrusion_grid
from pipeline.config.scene import load_scene
from pipeline.model import assembly, kernel_inputs, running
from pipeline.model.start import start_state
from pipeline.stages.simulate import model_inputs
from pipeline.units import NM

ROOT = Path(__file__).resolve().parents[1]
K = 0.445


def run(results: list[dict]) -> None:
    """Append the start-state rows to ``results``."""
    scene = load_scene(ROOT / "configs" / "paper-2009.toml", [f"contact.k={K}", "solver.start=static"])
    with tempfile.TemporaryDirectory() as tmp:
        model = assembly.build_model(scene, *model_inputs(scene, Path(tmp)), K)
    grid = protrusion_grid(scene) * NM

    def cached(compiled: bool = True) -> None:
        m = replace(model)  # a fresh fold cache: the fold's search is in the time, once
        for p in grid:
            start_state(lambda mu: kernel_inputs.run_parameters(m, mu), p, "static", p + m.p["y_s"] - m.p["FH0"],
                        statics=m.statics, fold_max=2 * m.p["FH0"], compiled=compiled)

    def uncached(compiled: bool = True) -> None:
        for p in grid:
            start_state(lambda mu: kernel_inputs.run_parameters(model, mu), p, "static",
                        p + model.p["y_s"] - model.p["FH0"], compiled=compiled)

    def fold() -> None:
        running.start(replace(model), 0.0)

    t_cached, t_plain = timeit(cached, repeat=5), timeit(uncached, repeat=3)
    t_cached_py = timeit(lambda: cached(False), repeat=3)
    t_plain_py = timeit(lambda: uncached(False), repeat=3)
    record(results, f"static starts, paper grid ({grid.size} protrusions), ladder and fold once per model", t_cached,
           ratio_to_uncached=float(np.median(t_cached) / np.median(t_plain)),
           ratio_to_python_newton_from_zero=float(np.median(t_cached) / np.median(t_plain_py)))
    record(results, f"static starts, paper grid ({grid.size}), fold bracketed per protrusion", t_plain)
    record(results, "static start: the fold's search (once per model)", timeit(fold, repeat=5))
    record(results, f"static starts, paper grid ({grid.size}), ladder, Newton from Python", t_cached_py,
           compiled_speedup=float(np.median(t_cached_py) / np.median(t_cached)))
    record(results, f"static starts, paper grid ({grid.size}), fold per protrusion, Newton from Python "
           "(the start in Python)", t_plain_py,
           compiled_speedup=float(np.median(t_plain_py) / np.median(t_plain)))
