"""Benchmark of the bulge's air-bearing table (pipeline.model.bulge_table) for the paper scene.

Target (issue 17): the Reynolds table of the paper scene under 30 s. The table is 31 protrusions
(0-15 nm at 0.5 nm) x 25 apex gaps (0.05-20 nm, log-spaced), the default Reynolds grid (32 x 12 cells
per semi-axis, the pad ring 1 a ahead and behind), first-order slip, p_pad = 1 MPa. Baselines in the
same run: one protrusion row of the same table (the unit the table repeats 30 times) and the closed-form
(p h = const) table on the same grid.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from benchmarks.common import record, timeit
from pipeline.model import bulge_table as bt
from pipeline.physics import bulge_bearing as bb
from pipeline.config.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]


def run(results: list[dict]) -> None:
    """Append the bulge-table rows to ``results``."""
    scene = load_scene(ROOT / "configs" / "paper-2009.toml")
    tfc, dmw = scene["tfc"], scene["dmw"]
    speed = 2 * np.pi * dmw["radius_mm"] * 1e-3 * dmw["rpm"] / 60.0
    kw = dict(p_pad=1e6, a=tfc["half_length_um"] * 1e-6, b=tfc["half_width_um"] * 1e-6, speed=speed)
    gaps, dls = bt.table_gaps(), bt.table_protrusions()
    cases = int((dls > 0).sum()) * gaps.size
    row = timeit(lambda: bb.reynolds_table(gaps, dls[10:11], viscosity=bt.AIR_VISCOSITY,
                                           mean_free_path=bt.AIR_MEAN_FREE_PATH,
                                           ambient_pressure=bt.AMBIENT_PRESSURE, **kw), repeat=5)
    record(results, f"bulge Reynolds table, one protrusion row ({gaps.size} gaps)", row)
    full = timeit(lambda: bt.bulge_table(model="reynolds", gaps=gaps, protrusions=dls, **kw), repeat=3, warmup=0)
    med_row = float(np.median(row))
    record(results, f"bulge Reynolds table, paper scene ({dls.size} x {gaps.size})", full, target_s=30.0,
           cases=cases, ms_per_case=float(np.median(full)) / cases * 1e3,
           ratio_to_one_row=float(np.median(full)) / med_row)
    record(results, "bulge p h = const table, same grid",
           timeit(lambda: bt.bulge_table(model="ph-limit", gaps=gaps, protrusions=dls, **kw), repeat=9))
