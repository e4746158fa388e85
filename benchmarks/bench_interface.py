"""Interface-table benchmark: all ISBL populations of one roughness at the default grid."""

from __future__ import annotations

from pathlib import Path

from pipeline.config.scene import load_scene
from pipeline.model.interface_tables import build_tables, roughness_statistics

from .common import record, timeit

ROOT = Path(__file__).resolve().parents[1]


def run(results: list[dict]) -> None:
    scene = load_scene(ROOT / "configs" / "paper-2009.toml")
    stats = roughness_statistics(scene)
    ds = build_tables(scene, stats)
    n = ds.sizes["separation"]
    record(results, f"interface tables, paper roughness, all populations ({n} separations)",
           timeit(lambda: build_tables(scene, stats), repeat=9), target_s=0.5, separations=n)
    fine = scene.replace(solver={"table_step_nm": 0.001})
    record(results, "interface tables at 10x finer grid (0.001 nm)",
           timeit(lambda: build_tables(fine, stats), repeat=3))
