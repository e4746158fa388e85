"""The solver's work-precision figure of ``accuracy.nc``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

from .common import LINE_COLOURS, new_figure, save

if TYPE_CHECKING:
    pass


def fig_work_precision(ds: xr.Dataset, path: Path) -> Path:
    """Max error versus wall time of ``accuracy.nc``, log-log, one line per knob, one panel per operating point.

    Each knob's chosen default is starred; failed runs and changed regimes (infinite error) are drawn
    as crosses at the top; errors below 1e-10 at 1e-10; the dashed line is the dataset's ``tolerance``.
    """
    lo, hi = 1e-10, 1e3
    points = list(ds["point"].values)
    fig, axes = new_figure(1, len(points), size=(5.2 * len(points), 4.6), sharey=True, squeeze=False)
    tol = float(ds.attrs["tolerance"])
    for ip, (ax, p) in enumerate(zip(axes[0], points)):
        for ik, kb in enumerate(ds["knob"].values):
            sel = ds.isel(point=ip, knob=ik)
            ok = np.isfinite(sel["setting"].values)
            x = sel["wall_time"].values[ok]
            y = np.clip(np.nan_to_num(sel["max_error"].values[ok], nan=lo, posinf=hi), lo, hi)
            c = LINE_COLOURS[ik % len(LINE_COLOURS)]
            bad = sel["failed"].values[ok].astype(bool) | np.isinf(sel["max_error"].values[ok])
            ax.plot(x[~bad], y[~bad], "-o", color=c, ms=4, lw=1.2, label=str(kb))
            if bad.any():
                ax.plot(x[bad], np.full(bad.sum(), hi), "x", color=c, ms=9, mew=2)
            lvl = int(ds["chosen_level"].values[ik])
            if lvl >= 0:
                ax.plot([sel["wall_time"].values[lvl]], [np.clip(sel["max_error"].values[lvl], lo, hi)], "*",
                        color=c, ms=13, mec="k", mew=0.6)
        ax.axhline(tol, color="k", ls="--", lw=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(lo / 2, hi * 2)
        ax.set_xlabel("wall time [s] (setup + simulation)")
        ax.set_title(f"{p} ({float(ds['protrusion'].values[ip]):g} nm)")
        ax.grid(True, which="major", alpha=0.3)
    axes[0][0].set_ylabel("max relative error of headline outputs [1]")
    axes[0][-1].legend(fontsize=8, loc="upper right")
    fig.suptitle("Work-precision per accuracy knob, others at reference (step-size rows: the other step "
                 "controllers lifted or relaxed, see attribute row_base)\n"
                 f"dashed: {tol:g} tolerance; star: chosen default; x: failed or regime changed; "
                 f"errors < {lo:g} drawn at {lo:g}", fontsize=9)
    return save(fig, path, dpi=120)
