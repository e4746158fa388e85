"""The bouncing band versus a parameter of the two-population scene (docs/model.md, section
"Two adhesion populations", where the table this prints is kept, and docs/figures/band_scan.png).

For each value of one scene key, ``hdi sweep`` of the scene with that value over the DMW realisations
(``sweep.realisations``) at a fixed k, then per protrusion over the realisations: the median bouncing BV
(the BV of a run that touched in the steady window, 0 for one that flew: pipeline.analyses.study.bouncing_bv),
the fraction bouncing above 20 % and the median contact fraction of the window. Figure: those curves,
one per value; printed: the table.

Usage (from the project root; each value is one sweep, ~1 min on 2 cores)::

    .venv/bin/python docs/experiments/band_scan.py [--config configs/paper-2009-two-population-identified.toml] \
        [--key lubricant.bridge_work_of_adhesion_j_m2] [--values 0.002,0.0055,0.011,0.022] \
        [--protrusions 8.6:11.2:0.2] [--realisations 8] [--k 0.978] [--out /tmp/band_scan] \
        [--figure docs/figures/band_scan.png]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from pipeline.analyses import ensemble_rules as en  # noqa: E402
from pipeline.analyses.study import bouncing_bv  # noqa: E402
from pipeline.io import read_dataset  # noqa: E402

THRESHOLD = 20.0  # [%] the paper's band


def sweep(config: str, key: str, value: str, grid: str, n: int, k: float, out: Path) -> xr.Dataset:
    """``hdi sweep`` of ``config`` with ``key = value``; its ``sweep.nc`` (first roughness and damping)."""
    lo, hi, step = grid.split(":")
    folder = out / f"{key}={value}"
    cmd = [str(ROOT / ".venv" / "bin" / "hdi"), "sweep", config, "--out", str(folder), "--yes",
           "--set", f"{key}={value}", "--set", f"contact.k={k}", "--set", f"sweep.realisations={n}",
           "--set", f"sweep.protrusion_nm={{start={lo}, stop={hi}, step={step}}}"]
    subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    ds = read_dataset(folder / "sweep.nc")
    return ds.isel({d: 0 for d in ("roughness", "damping") if d in ds.dims})


def band_curves(ds: xr.Dataset) -> dict[str, np.ndarray]:
    """Median bouncing BV [%], P(bouncing BV > 20 %) and median contact fraction [1] versus protrusion."""
    bv = bouncing_bv(ds["fhm_bv"], ds["min_clearance"])
    return {"protrusion": ds["protrusion"].values, "bv": en.median_spread(bv)[0].values,
            "p20": en.exceedance_probability(bv, THRESHOLD).values,
            "contact": en.median_spread(ds["contact_fraction"].fillna(0.0))[0].values}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default="configs/paper-2009-two-population-identified.toml")
    ap.add_argument("--key", default="lubricant.bridge_work_of_adhesion_j_m2")
    ap.add_argument("--values", default="0.002,0.0055,0.011,0.022")
    ap.add_argument("--protrusions", default="8.6:11.2:0.2")
    ap.add_argument("--realisations", type=int, default=8)
    ap.add_argument("--k", type=float, default=0.978)
    ap.add_argument("--out", default="/tmp/band_scan")
    ap.add_argument("--figure", default="docs/figures/band_scan.png")
    a = ap.parse_args()
    curves = {v: band_curves(sweep(a.config, a.key, v, a.protrusions, a.realisations, a.k, Path(a.out)))
              for v in a.values.split(",")}

    print(f"{a.key} | steps of (9.8, 10.8] with P(BV > 20 %) > 0.5 | median bouncing BV 9.6-11.0 nm [%] | "
          "median contact fraction 9.6-11.0 nm")
    for v, c in curves.items():
        x = c["protrusion"]
        sel = (x > 9.59) & (x < 11.01)
        band = (x > 9.79) & (x < 10.81)
        print(f"{v} | {int(np.sum(c['p20'][band] > 0.5))} | " + " ".join(f"{b:.0f}" for b in c["bv"][sel])
              + " | " + " ".join(f"{f:.2f}" for f in c["contact"][sel]))

    import matplotlib
    matplotlib.use("Agg")
    from pipeline.analyses.plots import axis_label, new_figure, save
    fig, (ax, ax2) = new_figure(2, 1, size=(8.0, 6.4), sharex=True)
    for a_ in (ax, ax2):
        a_.axvspan(9.9, 10.9, color="#ffbf00", alpha=0.15, lw=0)
        a_.grid(alpha=0.3)
    for v, c in curves.items():
        line, = ax.plot(c["protrusion"], c["bv"], marker="o", ms=3, lw=1.3, label=f"{a.key.split('.')[-1]} = {v}")
        ax2.plot(c["protrusion"], c["contact"], color=line.get_color(), lw=1.3)
        ax2.plot(c["protrusion"], c["p20"], color=line.get_color(), lw=0.9, ls="--")
    ax.axhline(THRESHOLD, color="k", lw=0.8, ls="--")
    ax.set_ylabel(axis_label("median bouncing BV (0 where flying)", "%"))
    ax2.set_ylabel(axis_label("contact fraction (solid), P(BV > 20 %) (dashed)", "1"))
    ax2.set_xlabel(axis_label("TFC protrusion δ", "nm"))
    ax.legend(fontsize=7.5, loc="upper right")
    fig.suptitle(f"The band versus {a.key}\n({Path(a.config).stem}, {a.realisations} DMW realisations, "
                 f"k = {a.k:g}; shaded: the paper's band steps 10.0-10.8 nm)", fontsize=9.5)
    print("figure:", save(fig, ROOT / a.figure))


if __name__ == "__main__":
    main()
