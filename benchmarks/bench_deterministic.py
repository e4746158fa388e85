"""Deterministic interface tables (FFT boundary elements, ``interface.model = "deterministic"``) for each
bundled AFM scan at its own resolution: wall time and peak memory.

Each scan runs in a fresh process (its peak RSS, ``ru_maxrss``, is then the scan's own, not the largest
so far), which first computes the deterministic tables alone (``solver.contact_grid_points`` = the
scan's grid, so nothing is resampled; peak RSS measured right after, before anything else allocates)
and then the statistical interface dataset of the same scene (the baseline, timed in the same
process). Rows: the deterministic wall time (one run: a 512 x 512 scan takes minutes), its ratio to
the statistical build, the peak RSS of the process and its growth during the solve (what the solver
adds over the imports and the scan), the grid and the conjugate-gradient iterations.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from .common import record, record_failure

ROOT = Path(__file__).resolve().parents[1]
SCANS = sorted((ROOT / "tests" / "data" / "afm").glob("*.*"))

CHILD = r"""
import json, resource, sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np
from pipeline.config.scene import load_scene
from pipeline.model.interface_tables import build_tables, interface_parameters, needed_quantities, roughness_statistics
from pipeline.model.deterministic_tables import deterministic_tables
from pipeline.model.afm_scan import read_topography
from pipeline.physics import isbl
scan = sys.argv[1]
n = max(read_topography(scan).nb_grid_pts)
base = ["roughness.afm=['%s']" % scan, "solver.contact_grid_points=%d" % n]
stat = load_scene(sys.argv[2], base)
det = load_scene(sys.argv[2], base + ["interface.model='deterministic'"])
stats = roughness_statistics(stat)
p = interface_parameters(det, stats)
d = isbl.separation_grid(-8 * p.sigma_s, max(30e-9, 12.5 * p.sigma_s), 0.05e-9)
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.perf_counter()
_, solved = deterministic_tables(det, stats["y_s"], p.E, p.H, d, needed_quantities(det.effects))
t_det = time.perf_counter() - t0
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.perf_counter(); build_tables(stat, stats); t_stat = time.perf_counter() - t0
print(json.dumps({"grid": n, "t_stat": t_stat, "t_det": t_det, "rss_mib": rss1 / 1024,
                  "rss_growth_mib": (rss1 - rss0) / 1024, "solves": len(solved["iterations"]),
                  "iterations": int(np.sum(solved["iterations"])), "pixel_nm": solved["pixel_size"] * 1e9,
                  "skipped": len(solved["skipped"])}))
"""


def run(results: list[dict]) -> None:
    for scan in SCANS:
        out = subprocess.run([sys.executable, "-c", CHILD, str(scan), str(ROOT / "configs" / "paper-2009.toml")],
                             cwd=ROOT, capture_output=True, text=True)
        if out.returncode != 0:  # say which scan failed and why, and go on with the others
            last = (out.stderr.strip().splitlines() or ["(no message)"])[-1]
            record_failure(results, f"deterministic interface tables, {scan.name}", last)
            continue
        r = json.loads(out.stdout.strip().splitlines()[-1])
        record(results, f"deterministic interface tables, {scan.name} ({r['grid']}^2)", [r["t_det"]],
               grid=r["grid"], pixel_nm=r["pixel_nm"], solves=r["solves"], cg_iterations=r["iterations"],
               statistical_s=r["t_stat"], ratio_to_statistical=r["t_det"] / r["t_stat"],
               peak_rss_mib=r["rss_mib"], rss_growth_mib=r["rss_growth_mib"], skipped_loads=r["skipped"])
        print(f"    peak RSS {r['rss_mib']:.0f} MiB (+{r['rss_growth_mib']:.0f} MiB during the solves), "
              f"{r['solves']} solves ({r['skipped']} loads left out), {r['iterations']} CG iterations, x{r['t_det'] / r['t_stat']:.0f} the "
              f"statistical tables", flush=True)
