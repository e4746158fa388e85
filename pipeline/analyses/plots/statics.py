"""The statics map's figures: every static state versus protrusion with its stability, and the barriers.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

from .common import LINE_COLOURS, axis_label, heater_power_axis, new_figure, note, panel, save, title, var_label

if TYPE_CHECKING:
    from matplotlib.axes import Axes


#: Categories of static states drawn by :func:`plot_statics_states`: (state_type, stable) -> label, colour.
_STATE_STYLE = {(0, 1): ("flying, stable", LINE_COLOURS[0]), (0, 0): ("flying, unstable", LINE_COLOURS[0]),
                (1, 1): ("contact, stable", LINE_COLOURS[1]), (1, 0): ("contact, unstable", LINE_COLOURS[1]),
                (2, 1): ("on the criterion, stable", LINE_COLOURS[2]),
                (2, 0): ("on the criterion, unstable", LINE_COLOURS[2])}


def _statics_window(st: xr.Dataset, above_nm: float = 2.5) -> tuple[float, float]:
    """Protrusions [nm] worth drawing: from 1 nm before the first state within ``above_nm`` of the criterion."""
    x = st["protrusion"].values
    near = np.nanmin(np.where(np.isfinite(st["clearance"].values), st["clearance"].values, np.inf), axis=1) < above_nm
    start = float(x[np.argmax(near)]) - 1.0 if near.any() else float(x[0])
    return max(float(x[0]), start) - 0.1, float(x[-1]) + 0.1


def _state_series(st: xr.Dataset) -> list[tuple[tuple[int, int], int, np.ndarray]]:
    """``(category, rank, clearance per protrusion)``: the ``rank``-th state (from the top) of each category
    (:data:`_STATE_STYLE`) at each protrusion, NaN where there is none."""
    c = st["clearance"].values
    kind, stable = st["state_type"].values, st["stable"].values
    out = []
    for cat in _STATE_STYLE:
        mask = (kind == cat[0]) & (stable == cat[1])
        ranks = int(mask.sum(axis=1).max()) if mask.size else 0
        for r in range(ranks):
            y = np.full(c.shape[0], np.nan)
            for i in range(c.shape[0]):
                vals = c[i][mask[i]]
                if vals.size > r:
                    y[i] = vals[r]
            out.append((cat, r, y))
    return out


def plot_statics_states(st: xr.Dataset, *, near_criterion: bool = False, ax: Axes | None = None) -> Axes:
    """The clearance [nm] of every static state versus TFC protrusion [nm] (``statics.nc``): stable states solid,
    unstable dashed, by where they lie (above the contact criterion, below it, on it); the criterion at 0.

    Parameters
    ----------
    st : the statics map (``statics.nc``: ``clearance`` [nm], ``state_type``, ``stable`` on protrusion [nm])
    near_criterion : draw only the protrusions from 1 nm before the first state within 2.5 nm of the criterion
        and clearances up to 3 nm (the fold and the unstable branch); ``False``: every protrusion and every
        clearance of the map
    ax : the axes to draw on (``None``: a new figure's)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = panel(ax, (8.5, 3.6))
    x = st["protrusion"].values
    for (kind, stable), rank, y in _state_series(st):
        label, colour = _STATE_STYLE[(kind, stable)]
        ax.plot(x, y, color=colour, ls="-" if stable else "--", lw=1.4 if stable else 1.0,
                marker="o", ms=3, mfc=colour if stable else "white",
                label=label if rank == 0 else None)
    ax.axhline(0.0, color="k", lw=0.7, ls=":", label="contact criterion (d = k sigma)")
    lo, hi = _statics_window(st) if near_criterion else (float(x[0]) - 0.1, float(x[-1]) + 0.1)
    ax.set_xlim(lo, hi)
    shown = st["clearance"].where((st["protrusion"] >= lo) & (st["protrusion"] <= hi)).values
    if np.isfinite(shown).any():
        top = float(np.nanmax(shown))
        ax.set_ylim(min(-0.3, float(np.nanmin(shown)) - 0.2), (min(top, 3.0) if near_criterion else top) + 0.2)
    ax.set_ylabel(var_label(st["clearance"], "static clearance"))
    heater_power_axis(ax, st)
    ax.legend(fontsize=7.5, loc="upper right", framealpha=0.9)
    return ax


def plot_statics_barriers(st: xr.Dataset, *, ax: Axes | None = None) -> Axes:
    """The energy barrier [J] out of each stable static state versus TFC protrusion [nm] (``statics.nc``, log
    scale; only where two or more stable states coexist), beside the DMW's energy scales (``dmw_energy``,
    ``dmw_kinetic_energy``) as horizontal lines."""
    ax = panel(ax, (8.5, 3.0))
    x = st["protrusion"].values
    b = st["barrier"].values
    kind = st["state_type"].values
    drawn = False
    for (cat, stable), rank, _ in _state_series(st):
        if not stable:
            continue
        y = np.full(x.size, np.nan)
        for i in range(x.size):
            sel = np.flatnonzero((kind[i] == cat) & (st["stable"].values[i] == 1))
            if sel.size > rank:
                y[i] = b[i, sel[rank]]
        y = np.where(y > 0, y, np.nan)
        if np.isfinite(y).any():
            label, colour = _STATE_STYLE[(cat, stable)]
            ax.plot(x, y, color=colour, marker="o", ms=3, lw=1.2, label=f"out of: {label}" if rank == 0 else None)
            drawn = True
    for name, ls, label in (("dmw_energy", "-", "DMW: 0.5 k_b σ_w² (bearing at the TFC point, one DMW rms)"),
                            ("dmw_kinetic_energy", ":", "DMW: 0.5 m_b σ_v² (TFC-point mass at the DMW's rms rate)")):
        if name in st and np.isfinite(float(st[name])) and float(st[name]) > 0:
            ax.axhline(float(st[name]), color="0.3", lw=1.0, ls=ls, label=label)
            drawn = True
    if not drawn:
        note(ax, "one stable state at every protrusion: no barrier", loc="lower left")
    else:
        ax.set_yscale("log")
        ax.legend(fontsize=7, loc="upper right", framealpha=0.9)
    ax.set_xlim(*_statics_window(st))
    ax.set_ylabel(var_label(st["barrier"], "energy barrier"))
    ax.set_xlabel(axis_label("TFC protrusion", st["protrusion"].attrs.get("units", "nm")))
    return ax


def fig_statics(st: xr.Dataset, scene: str, path: Path) -> Path:
    """The statics map (``statics.nc``): :func:`plot_statics_states` over every protrusion [nm] (top) and near
    the contact criterion (middle), :func:`plot_statics_barriers` (bottom, on the middle one's protrusions)."""
    fig, (ax, ax1, ax2) = new_figure(3, 1, size=(8.5, 9.6))
    plot_statics_states(st, ax=ax)
    ax.set_title("every static state", fontsize=10)
    plot_statics_states(st, near_criterion=True, ax=ax1)
    ax1.set_title("near the contact criterion", fontsize=10)
    plot_statics_barriers(st, ax=ax2)
    fig.suptitle(title("Static states of the slider: clearance, stability and barriers", scene), fontsize=11)
    return save(fig, path)
