"""The figures' shared conventions: colours, axis labels with units, titles, new figures and panels, the
heater-power axis, shading of regimes, envelopes, and writing a figure as PNG (:func:`save`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from ...io import temporary_path
from ...paths import refuse_links
from ...variables import GROUPS, Regime, regime_name

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


#: Regime code -> (name, shading colour); names from the variable schema.
REGIME_COLOURS = {int(r): (regime_name(r), c) for r, c in zip(Regime, ("#cfe8ff", "#ffe1b3", "#d5f5d0"))}
DPI = 150
LINE_COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")

_UNIT_TEXT = {"1": "1", "um2": "µm²", "um": "µm", "um-2": "µm⁻²", "nm2 Hz-1": "nm²/Hz", "nm2": "nm²",
              "m s-1": "m/s", "J m-2": "J/m²", "nm-2": "nm⁻²", "%": "%"}


def unit_text(units: str | None) -> str:
    """Printable form of a CF ``units`` string (``"um2"`` -> ``"µm²"``)."""
    if units is None:
        return ""
    return _UNIT_TEXT.get(units, units)


def axis_label(quantity: str, units: str | None) -> str:
    """``"quantity [units]"`` (``[-]`` for dimensionless quantities)."""
    u = unit_text(units)
    return f"{quantity} [{'-' if u in ('', '1') else u}]"


def var_label(da: xr.DataArray, quantity: str | None = None) -> str:
    """Axis label of a data array from its ``units`` attribute (and ``long_name`` if no quantity); a
    variable without them takes both from its declaration in :mod:`pipeline.variables`."""
    decl = next((g[str(da.name)] for g in GROUPS.values() if str(da.name) in g), None)
    units = da.attrs.get("units", decl.units if decl else None)
    name = quantity or da.attrs.get("long_name") or (decl.long_name if decl else str(da.name or ""))
    return axis_label(name, units)


#: The modules a figure is drawn with, imported lazily (~0.7 s: only drawing stages pay them; a drawing stage
#: declares them as its ``lazy_imports``, :class:`pipeline.runner.Stage`).
DRAWING_MODULES = ("matplotlib.figure", "matplotlib.backends.backend_agg")


def title(what: str, scene: str) -> str:
    """A figure title naming what is shown and the scene."""
    return f"{what}\nscene: {scene}"


def new_figure(nrows: int = 1, ncols: int = 1, *, size: tuple[float, float] = (7.5, 4.8),
               sharex: bool = False, sharey: bool = False, squeeze: bool = True) -> tuple[Figure, Any]:
    """A pyplot-free figure with a grid of axes (constrained layout)."""
    from matplotlib.figure import Figure  # (here: ~0.7 s of import that only drawing stages pay)
    fig = Figure(figsize=size, layout="constrained")
    axes = fig.subplots(nrows, ncols, sharex=sharex, sharey=sharey, squeeze=squeeze)
    return fig, axes


def panel(ax: Axes | None, size: tuple[float, float] = (7.5, 4.8)) -> Axes:
    """``ax``, or the axes of a new figure of ``size`` [inch] (:func:`new_figure`) when it is ``None``."""
    return ax if ax is not None else new_figure(size=size)[1]


def heater_power_axis(ax: Axes, ds: xr.Dataset) -> Any | None:
    """A top axis of heater power [mW] over an axis of protrusion [nm], where ``ds`` has the coordinate
    ``heater_power`` on ``protrusion`` (a scene with an actuation, pipeline/config/heater_power.py): its
    ticks read the dataset's own pairs (linear between them, as the actuation is), so the figure states
    both axes of the user's drive. ``None`` (nothing drawn) without that coordinate."""
    if "heater_power" not in ds.coords or ds["heater_power"].dims != ("protrusion",) or ds.sizes["protrusion"] < 2:
        return None
    x, p = ds["protrusion"].values.astype(float), ds["heater_power"].values.astype(float)
    known = np.isfinite(p)  # (NaN: a protrusion beyond an actuation table)
    if known.sum() < 2:
        return None
    order = np.argsort(x[known])
    x, p = x[known][order], p[known][order]

    def along(u: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:  # linear, extended by the end rows
        u = np.asarray(u, float)
        lo = b[0] + (u - a[0]) * (b[1] - b[0]) / (a[1] - a[0])
        hi = b[-1] + (u - a[-1]) * (b[-1] - b[-2]) / (a[-1] - a[-2])
        return np.where(u < a[0], lo, np.where(u > a[-1], hi, np.interp(u, a, b)))

    top = ax.secondary_xaxis("top", functions=(lambda u: along(u, x, p), lambda u: along(u, p, x)))
    top.set_xlabel(var_label(ds["heater_power"], "heater power"), fontsize=9)
    return top


def envelope(x: np.ndarray, y: np.ndarray, bins: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """A long trace thinned for drawing: the minimum and the maximum of each of ``bins`` equal index
    ranges, in order (NaN ignored), so every peak stays visible at any resolution a PNG has.

    A 10 ns history of 2 ms has 2e5 samples, 100 per pixel column at 150 dpi: drawing all of them
    costs most of the report's time and shows nothing more.
    """
    x, y = np.asarray(x), np.asarray(y, dtype=float)
    if y.size <= 2 * bins:
        return x, y
    start = np.linspace(0, y.size, bins + 1).astype(int)[:-1]
    with np.errstate(invalid="ignore"):
        lo, hi = np.fmin.reduceat(y, start), np.fmax.reduceat(y, start)
    end = np.append(start[1:], y.size)
    # each bin drawn as its minimum at its first sample, then its maximum at its centre
    xs = np.column_stack([x[start], x[(start + end) // 2]]).ravel()
    return xs, np.column_stack([lo, hi]).ravel()


def save(fig: Figure, path: str | Path, dpi: int = DPI) -> Path:
    """Write ``fig`` as PNG to ``path`` (folder created) and release its artists."""
    path = refuse_links(Path(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_path(path)
    fig.savefig(tmp, dpi=dpi, format="png")
    tmp.replace(path)
    fig.clear()
    return path


def note(ax: Any, text: str, loc: str = "upper right", **kw: Any) -> None:
    """A boxed note inside the axes."""
    x, ha = (0.98, "right") if "right" in loc else (0.02, "left")
    y, va = (0.96, "top") if "upper" in loc else (0.04, "bottom")
    ax.text(x, y, text, transform=ax.transAxes, ha=ha, va=va, fontsize=kw.pop("fontsize", 8),
            bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="0.6", alpha=0.9), **kw)


def shade_regimes(ax: Any, x: np.ndarray, regime: np.ndarray, legend: bool = True) -> None:
    """Shade contiguous runs of equal regime code along x (half a grid step either side)."""
    x = np.asarray(x, float)
    regime = np.asarray(regime)
    if x.size == 0:
        return
    edges = np.empty(x.size + 1)
    if x.size > 1:
        mid = 0.5 * (x[1:] + x[:-1])
        edges[1:-1] = mid
        edges[0] = x[0] - (mid[0] - x[0])
        edges[-1] = x[-1] + (x[-1] - mid[-1])
    else:
        edges[:] = [x[0] - 0.5, x[0] + 0.5]
    seen: set[int] = set()
    start = 0
    for i in range(1, x.size + 1):
        if i == x.size or regime[i] != regime[start]:
            code = int(regime[start]) if np.isfinite(regime[start]) else -1  # NaN: missing (not shaded)
            if code in REGIME_COLOURS:
                name, colour = REGIME_COLOURS[code]
                ax.axvspan(edges[start], edges[i], color=colour, alpha=0.8, lw=0, zorder=0,
                           label=(name if legend and code not in seen else None))
                seen.add(code)
            start = i


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``(first, last)`` index pairs of the runs of True in ``mask``."""
    mask = np.asarray(mask, bool)
    out, start = [], None
    for i, m in enumerate(mask):
        if m and start is None:
            start = i
        if not m and start is not None:
            out.append((start, i - 1))
            start = None
    if start is not None:
        out.append((start, mask.size - 1))
    return out
