"""Benchmark of the static start state (pipeline.model.start, ``solver.start = "static"``, the default).

Rows, on the paper scene's protrusion grid (76 protrusions, 0-15 nm, k = 0.445):

1. the starts of every protrusion with the fold of the flying branch found once per model (what a
   sweep batch pays; the first start includes the fold's search), against
2. the same starts each continuing the flying branch from zero protrusion and bracketing the fold
   anew (the static start before the fold was kept per model): ratio in the first row;
3. the fold's search alone (once per model).

Issue 17 measured the uncached start at ~0.1-0.2 s per protrusion past the adhesion fold.
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from benchmarks.common import record, timeit
from pipeline.config.grid import protrusion_grid
from pipeline.config.scene import load_scene
from pipeline.model import slider as sl
from pipeline.model.start import start_state
from pipeline.stages.simulate import model_inputs
from pipeline.units import NM

ROOT = Path(__file__).resolve().parents[1]
K = 0.445


def run(results: list[dict]) -> None:
    """Append the start-state rows to ``results``."""
    scene = load_scene(ROOT / "configs" / "paper-2009.toml", [f"contact.k={K}", "solver.start=static"])
    with tempfile.TemporaryDirectory() as tmp:
        model = sl.build_model(scene, *model_inputs(scene, Path(tmp)), K)
    grid = protrusion_grid(scene) * NM

    def cached() -> None:
        m = replace(model)  # a fresh fold cache: the fold's search is in the time, once
        for p in grid:
            sl.start(m, p)

    def uncached() -> None:
        for p in grid:
            start_state(lambda mu: sl.run_parameters(model, mu), p, "static",
                        p + model.p["y_s"] - model.p["FH0"])

    def fold() -> None:
        sl.start(replace(model), 0.0)

    t_cached, t_plain = timeit(cached, repeat=5), timeit(uncached, repeat=3)
    record(results, f"static starts, paper grid ({grid.size} protrusions), fold once per model", t_cached,
           ratio_to_uncached=float(np.median(t_cached) / np.median(t_plain)))
    record(results, f"static starts, paper grid ({grid.size}), fold bracketed per protrusion", t_plain)
    record(results, "static start: the fold's search (once per model)", timeit(fold, repeat=5))
