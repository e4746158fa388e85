"""Benchmark of the bulge's air-bearing table (the ``bulge`` stage, pipeline.model.bulge_table.scene_table).

Target: the Reynolds table of the paper bulge scene (configs/paper-2009-bulge.toml with
``air_bearing.bulge = "reynolds"``) under 30 s on 2 cores: what ``hdi bulge`` computes, 31 protrusions
(0-15 nm at 0.5 nm) x 25 apex gaps (0.05-20 nm, log-spaced), the scene's Reynolds grid (32 x 12 cells per
semi-axis, the pad ring 1 a ahead and behind), first-order slip, p_pad = 3 MPa. Baselines in the same run:
one protrusion row of the same table (the unit the table repeats 30 times) and the closed-form
(p h = const) table of the same scene and grid.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from benchmarks.common import record, timeit
from pipeline.config.scene import load_scene
from pipeline.model import bulge_table as bt
from pipeline.physics import reynolds
from pipeline.units import MPA, NM, UM

ROOT = Path(__file__).resolve().parents[1]


def run(results: list[dict]) -> None:
    """Append the bulge-table rows to ``results``."""
    scene = load_scene(ROOT / "configs" / "paper-2009-bulge.toml", ['air_bearing.bulge="reynolds"'])
    ph = scene.replace(air_bearing={"bulge": "ph-limit"})
    ds = bt.scene_table(ph)  # the grid of the stage's table
    gaps, dls = ds["apex_gap"].values * NM, ds["protrusion"].values * NM
    a, t, sol = scene["air_bearing"], scene["tfc"], scene["solver"]
    kw = dict(p_pad=a["pad_pressure_mpa"] * MPA, a=t["half_length_um"] * UM, b=t["half_width_um"] * UM,
              speed=ds.attrs["disk_speed_m_s"], viscosity=bt.AIR_VISCOSITY, mean_free_path=bt.AIR_MEAN_FREE_PATH,
              ambient_pressure=bt.AMBIENT_PRESSURE,
              grid=reynolds.ReynoldsGrid(cells_per_a=sol["bulge_cells_per_a"], cells_per_b=sol["bulge_cells_per_b"]))
    cases = int((dls > 0).sum()) * gaps.size
    row = timeit(lambda: reynolds.reynolds_table(gaps, dls[20:21], **kw), repeat=5)
    record(results, f"bulge Reynolds table, one protrusion row ({gaps.size} gaps)", row)
    full = timeit(lambda: bt.scene_table(scene), repeat=3, warmup=0)
    med_row = float(np.median(row))
    record(results, f"bulge Reynolds table, paper bulge scene ({dls.size} x {gaps.size})", full, target_s=30.0,
           cases=cases, ms_per_case=float(np.median(full)) / cases * 1e3,
           ratio_to_one_row=float(np.median(full)) / med_row)
    record(results, "bulge p h = const table, same scene and grid", timeit(lambda: bt.scene_table(ph), repeat=9))
