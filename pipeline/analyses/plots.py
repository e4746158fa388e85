"""Figures of the report stage (matplotlib object API: no pyplot, no global state).

Every ``fig_*`` function takes datasets as written by the stages (dataset units, see docs/datasets.md), draws
one figure, writes it as PNG with :func:`save` and returns the path. The panels a notebook draws on its
own axes are ``plot_*`` functions: each takes ``ax=`` (a matplotlib ``Axes``; ``None``: a new figure's)
and returns the axes it drew on; the ``fig_*`` figures are made of them. Figures are
:class:`matplotlib.figure.Figure` objects that are never registered with pyplot, so nothing leaks
between calls and nothing needs a display (``MPLBACKEND=Agg`` or not).

Conventions: every axis is labelled ``quantity [units]`` (:func:`axis_label`, units taken from the
variable's ``units`` attribute and written in plain text: ``um2`` -> ``µm²``); every title says what
is shown and for which scene (:func:`title`); regimes use :data:`REGIME_COLOURS`.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import sys
import threading
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np
import xarray as xr

from .. import interrupts
from ..fanout import available_cores
from ..io import temporary_path
from ..paths import refuse_links
from ..units import KHZ, S_IN_MS
from ..variables import GROUPS, TIME, Regime, regime_name

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


#: The figures of the :func:`draw_all` call in progress (its forked workers inherit them).
_JOBS: list[tuple[Callable[..., Path], tuple, dict]] = []


def _draw(i: int) -> Path:
    fn, args, kwargs = _JOBS[i]
    return fn(*args, **kwargs)


def _worker_init(parent: int) -> None:
    # Ctrl-C: the parent answers it and stops the pool; a killed parent takes its workers with it
    interrupts.default_in_child(parent)


def draw_all(jobs: Sequence[tuple[Callable[..., Path], tuple, dict]], workers: int | None = None) -> list[Path]:
    """Draw independent figures ``(function, args, kwargs)``; returns their paths, in order.

    Agg rendering holds the GIL, so threads do not draw two figures at once; processes do. On Linux,
    with no other thread alive in this process, the figures are drawn by a pool of ``workers``
    (default: the cores this process may use) *forked* processes, which inherit matplotlib already
    imported and the datasets: only an index goes to a worker and a path comes back. Anywhere else
    (another OS, or threads that might hold a lock at the fork) they are drawn here, in order. A
    figure's error is raised here either way (a worker that dies: ``BrokenProcessPool``). A worker dies
    with this process however it ends (:func:`pipeline.interrupts.die_with_parent`). The paper scene's 8
    figures: ``make bench``, row
    "report".
    """
    jobs = list(jobs)
    n = min(len(jobs), workers or available_cores())
    if n < 2 or not sys.platform.startswith("linux") or threading.active_count() > 1:
        return [fn(*args, **kwargs) for fn, args, kwargs in jobs]
    for module in DRAWING_MODULES:
        importlib.import_module(module)  # once, before the fork (~0.7 s every worker would pay again)
    global _JOBS
    _JOBS = jobs
    # (an executor, not multiprocessing.Pool: a worker that dies, e.g. killed for memory, raises
    # BrokenProcessPool here where Pool.map would wait for its lost figure forever)
    pool = ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork"), initializer=_worker_init,
                               initargs=(os.getpid(),))
    try:
        paths = list(pool.map(_draw, range(len(jobs))))
        interrupts.check()
        return paths
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        _JOBS = []


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


def _shade_transient(ax: Any, transient_ms: float | None) -> None:
    if transient_ms and transient_ms > 0:
        ax.axvspan(0.0, transient_ms, color="0.88", lw=0, zorder=0, label="start-up transient (discarded)")


def _regime_name(code: int | None) -> str:
    return "unknown" if code is None else {"missing": "unknown"}.get(regime_name(code), regime_name(code))


# --------------------------------------------------------------------------------------------- Fig. 3
def fig_clearance(hist: Sequence[tuple[float, xr.Dataset, int | None]], scene: str, path: Path,
                  transient_ms: float | None = None) -> Path:
    """Clearance (separation when absent) time histories, one panel per protrusion (paper Fig. 3).

    ``hist``: ``(protrusion [nm], one-slice history dataset (dim time), regime code or None)``.
    """
    fig, axes = new_figure(len(hist), 1, size=(7.5, 2.6 * len(hist) + 0.8), sharex=True, squeeze=False)
    for ax, (delta, h, code) in zip(axes[:, 0], hist):
        plot_clearance(h, delta, code, transient_ms=transient_ms, ax=ax)
    axes[-1, 0].set_xlabel(axis_label("time", "ms"))
    shown = list(dict.fromkeys(_regime_name(code) for _, _, code in hist))
    what = ", ".join(shown[:-1]) + f" and {shown[-1]}" if len(shown) > 1 else shown[0]
    fig.suptitle(title(f"Fig. 3: clearance histories, {what}", scene), fontsize=11)
    return save(fig, path)


def plot_clearance(h: xr.Dataset, delta: float, code: int | None = None, *, transient_ms: float | None = None,
                   ax: Axes | None = None) -> Axes:
    """One protrusion's clearance (separation when absent) [nm] versus time [ms], contact shaded (a panel
    of Fig. 3).

    Parameters
    ----------
    h : one protrusion's histories (dim ``time`` [s]): ``clearance`` or ``separation`` [nm], and
        ``in_contact`` when kept
    delta : its TFC protrusion [nm] (the panel's title)
    code : its regime code (:class:`pipeline.variables.Regime`; ``None``: unknown)
    transient_ms : the start-up transient [ms] shaded as discarded (``None``: none)
    ax : the axes to draw on (``None``: a new figure's)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on (the time axis is not labelled: a figure labels its lowest panel).
    """
    ax = panel(ax, (7.5, 3.4))
    t = h[TIME].values * S_IN_MS
    name = "clearance" if "clearance" in h else "separation"
    y = h[name]
    _shade_transient(ax, transient_ms)
    ax.plot(*envelope(t, y.values), lw=0.6, color=LINE_COLOURS[0], label=name)
    if name == "clearance":
        ax.axhline(0.0, color="k", lw=0.8, ls="--", label="contact threshold d = k σ")
    if "in_contact" in h:
        c = np.nan_to_num(h["in_contact"].values) > 0.5
        frac = c.mean() if c.size else 0.0
        for n, (i0, i1) in enumerate(runs(c)[:400]):
            ax.axvspan(t[i0], t[i1], color="#d62728", alpha=0.12, lw=0, zorder=0,
                       label="in contact" if n == 0 else None)
        state = f"{_regime_name(code)}; in contact {100 * frac:.0f} % of the time"
    else:
        state = _regime_name(code)
    ax.set_ylabel(var_label(y, name))
    ax.set_title(f"protrusion δ = {delta:g} nm ({state})", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best", framealpha=0.9)
    return ax


# --------------------------------------------------------------------------------------------- Fig. 4
FORCES = (("contact_force", "contact", LINE_COLOURS[0]), ("friction_force", "friction", LINE_COLOURS[1]),
          ("adhesion_force", "adhesion (attractive)", LINE_COLOURS[2]), ("net_force", "net vertical", "k"))


def fig_forces(h: xr.Dataset, delta: float, scene: str, path: Path, transient_ms: float | None = None) -> Path:
    """Contact, friction, adhesion and net force histories at one protrusion (paper Fig. 4)."""
    fig, ax = new_figure(size=(9.0, 4.6))   # (the legend beside the axes)
    plot_forces(h, transient_ms=transient_ms, ax=ax)
    fig.suptitle(title(f"Fig. 4: interface forces in light contact, protrusion {delta:g} nm", scene), fontsize=11)
    return save(fig, path)


def plot_forces(h: xr.Dataset, *, transient_ms: float | None = None, ax: Axes | None = None) -> Axes:
    """Contact, friction, adhesion and net vertical force [mN] versus time [ms] at one protrusion (Fig. 4).

    Parameters
    ----------
    h : one protrusion's histories (dim ``time`` [s]); the forces of :data:`FORCES` it holds are drawn
    transient_ms : the start-up transient [ms] shaded as discarded (``None``: none)
    ax : the axes to draw on (``None``: a new figure's)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = panel(ax, (7.5, 4.6))
    t = h[TIME].values * S_IN_MS
    _shade_transient(ax, transient_ms)
    units = None
    for name, label, colour in FORCES:
        if name in h:
            ax.plot(*envelope(t, h[name].values), lw=0.8, color=colour, label=label)
            units = h[name].attrs.get("units", units)
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(axis_label("time", "ms"))
    ax.set_ylabel(axis_label("force", units or "mN"))
    ax.grid(alpha=0.3)
    # beside the axes: inside, wherever it goes it covers a force (adhesion, the largest, runs along the top)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, framealpha=0.9)
    return ax


# --------------------------------------------------------------------------------------------- Fig. 5
STRESSES = (("friction_coefficient", "friction coefficient μ"), ("mean_pressure", "mean contact pressure"),
            ("shear_stress", "shear stress"))


def fig_stresses(h: xr.Dataset, delta: float, scene: str, path: Path, transient_ms: float | None = None) -> Path:
    """Friction coefficient, mean contact pressure and shear stress histories (paper Fig. 5)."""
    names = [(n, q) for n, q in STRESSES if n in h]
    fig, axes = new_figure(max(len(names), 1), 1, size=(7.5, 2.2 * max(len(names), 1) + 0.8), sharex=True,
                           squeeze=False)
    t = h[TIME].values * S_IN_MS
    for i, (ax, (name, q)) in enumerate(zip(axes[:, 0], names)):
        _shade_transient(ax, transient_ms)
        y = h[name].values
        ax.plot(*envelope(t, y), lw=0.8, color=LINE_COLOURS[i])
        ax.set_ylabel(var_label(h[name], q), fontsize=9)
        ax.grid(alpha=0.3)
        fin = y[np.isfinite(y)]
        if fin.size:
            lo, hi = float(fin.min()), float(fin.max())
            scale = max(abs(lo), abs(hi), 1e-12)
            if hi - lo < 0.02 * scale:  # (nearly) constant: show it as a flat line, not amplified noise
                mid = 0.5 * (lo + hi)
                lo, hi = mid - 0.05 * scale, mid + 0.05 * scale
            pad = 0.05 * (hi - lo)
            ax.set_ylim(lo - pad, hi + pad)
            ax.ticklabel_format(axis="y", useOffset=False)
            win = fin if transient_ms is None else y[(t >= transient_ms) & np.isfinite(y)]
            if win.size:
                note(ax, f"steady-window mean {np.mean(win):.4g}", loc="lower right")
        else:
            note(ax, "no contact: undefined", loc="lower right")
    if not names:
        note(axes[0, 0], "no stress histories in the dataset", loc="upper left")
    axes[-1, 0].set_xlabel(axis_label("time", "ms"))
    fig.suptitle(title(f"Fig. 5: friction coefficient and contact stresses, protrusion {delta:g} nm", scene),
                 fontsize=11)
    return save(fig, path)


# --------------------------------------------------------------------------------------------- Fig. 6
def _combo_label(labels: dict[str, Any]) -> str:
    parts = []
    if labels.get("roughness") is not None:
        parts.append(f"roughness {labels['roughness']}")
    if labels.get("damping") is not None:
        parts.append(f"ζ = {labels['damping']:g}")
    return ", ".join(parts) or "sweep"


def fig_fhm(combos: Sequence[tuple[dict[str, Any], xr.Dataset]], scene: str, path: Path, *,
            touchdown_nm: float | None = None, previous_nm: float | None = None, limit: float = 10.0,
            first_contact: float | None = None) -> Path:
    """FHM/BV [%] versus protrusion with regimes shaded (from the first combination), paper Fig. 6.

    A log scale is used when FHM (flying) and BV (in contact) differ by more than a factor 20, so
    both stay readable.
    """
    fig, ax = new_figure(size=(10.0, 5.0))
    plot_fhm(combos, touchdown_nm=touchdown_nm, previous_nm=previous_nm, limit=limit, first_contact=first_contact,
             ax=ax)
    fig.suptitle(title("Fig. 6: flying-height modulation / bouncing vibration versus protrusion", scene), fontsize=11)
    return save(fig, path)


def plot_fhm(combos: xr.Dataset | Sequence[tuple[dict[str, Any], xr.Dataset]], *, touchdown_nm: float | None = None,
             previous_nm: float | None = None, limit: float = 10.0, first_contact: float | None = None,
             ax: Axes | None = None) -> Axes:
    """FHM/BV [%] versus TFC protrusion [nm], regimes shaded (from the first combination): Fig. 6's axes.

    Parameters
    ----------
    combos : a dataset with ``fhm_bv`` [%] (and ``regime``) on dim ``protrusion`` [nm] (a ``simulate``
        result, one slice of ``sweep.nc``), or ``(labels, dataset)`` pairs, one line each (labels: the
        slice's ``roughness`` and ``damping``)
    touchdown_nm, previous_nm : the measured touchdown and the step before it [nm] (``None``: not drawn)
    limit : the stable-flying limit of FHM [%]
    first_contact : the first protrusion in contact here [nm] (``None``: not drawn)
    ax : the axes to draw on (``None``: a new figure's)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on (a log scale when FHM and BV differ by more than a factor 20).
    """
    ax = panel(ax, (10.0, 5.0))
    if isinstance(combos, xr.Dataset):
        combos = [({}, combos)]
    first = combos[0][1]
    x0 = first["protrusion"].values
    if "regime" in first:
        shade_regimes(ax, x0, np.asarray(first["regime"].values).reshape(-1))
    allv = []
    for i, (labels, ds) in enumerate(combos):
        y = np.asarray(ds["fhm_bv"].values, float).reshape(-1)
        allv.append(y)
        ax.plot(ds["protrusion"].values, y, marker="o", ms=2.5, lw=1.2, color=LINE_COLOURS[i % len(LINE_COLOURS)],
                label=_combo_label(labels) if len(combos) > 1 else "FHM (flying) / BV (contact)")
    v = np.concatenate(allv)
    v = v[np.isfinite(v) & (v > 0)]
    if v.size and v.max() / v.min() > 20:
        ax.set_yscale("log")
    ax.axhline(limit, color="k", ls="--", lw=1.0, label=f"stable flying: FHM < {limit:g} %")
    if touchdown_nm is not None:
        ax.axvline(touchdown_nm, color="#d62728", lw=1.4, label=f"measured touchdown {touchdown_nm:g} nm")
    if previous_nm is not None:
        ax.axvline(previous_nm, color="#d62728", lw=0.8, ls=":", label=f"no contact at {previous_nm:g} nm (measured)")
    if first_contact is not None:
        ax.axvline(first_contact, color="#9467bd", lw=1.2, ls="-.", label=f"first contact here: {first_contact:g} nm")
    ax.set_xlabel(axis_label("TFC protrusion δ", "nm"))
    ax.set_ylabel(axis_label("FHM / BV (peak-to-peak / FH0)", "%"))
    heater_power_axis(ax, first)
    ax.grid(alpha=0.3, which="both")
    shade_note = "regimes shaded for " + _combo_label(combos[0][0]) if len(combos) > 1 else None
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), framealpha=0.9, title=shade_note,
              title_fontsize=7.5)
    return ax


# ------------------------------------------------------------------------------------ DMW ensemble
def touchdown_lines(axes: Sequence[Any], touchdown_nm: float | None, previous_nm: float | None,
                    lw: float = 1.2, labelled: bool = True) -> None:
    """The measured touchdown [nm] (labelled on the first axes unless not ``labelled``) and the previous
    step [nm] as vertical lines on every axes, each gridded."""
    for a in axes:
        if touchdown_nm is not None:
            a.axvline(touchdown_nm, color="#d62728", lw=lw, label=f"measured touchdown {touchdown_nm:g} nm"
                      if labelled and a is axes[0] else None)
        if previous_nm is not None:
            a.axvline(previous_nm, color="#d62728", lw=0.8, ls=":")
        a.grid(alpha=0.3)


def fig_ensemble(sweep: xr.Dataset, scene: str, path: Path, *, touchdown_nm: float | None = None,
                 previous_nm: float | None = None) -> Path:
    """Touchdown probability (top) and FHM/BV ensemble mean with a +-1 std band (bottom) versus protrusion.

    From the ``realisation`` statistics of ``sweep.nc`` (``[sweep] realisations > 1``), the first
    roughness set and damping ratio; each realisation's FHM/BV is drawn faintly behind the band.
    """
    fig, (ax, ax2) = new_figure(2, 1, size=(8.5, 6.4), sharex=True)
    plot_touchdown_probability(sweep, touchdown_nm=touchdown_nm, previous_nm=previous_nm, ax=ax)
    plot_ensemble_fhm(sweep, touchdown_nm=touchdown_nm, previous_nm=previous_nm, ax=ax2, labelled=False)
    fig.suptitle(title("Touchdown and FHM/BV over DMW realisations", scene), fontsize=11)
    return save(fig, path)


def _first_combination(sweep: xr.Dataset) -> tuple[xr.Dataset, dict[str, int]]:
    """The first roughness set and damping ratio of a sweep, and the selection that took them."""
    sel = {d: 0 for d in ("roughness", "damping") if d in sweep.dims}
    return sweep.isel(sel), sel


def plot_touchdown_probability(sweep: xr.Dataset, *, touchdown_nm: float | None = None,
                               previous_nm: float | None = None, ax: Axes | None = None) -> Axes:
    """The touchdown probability [1] over DMW realisations versus TFC protrusion [nm] (top of
    :func:`fig_ensemble`), of the sweep's first roughness set and damping ratio.

    Parameters
    ----------
    sweep : ``sweep.nc`` of ``[sweep] realisations > 1`` (``touchdown_probability`` on ``protrusion``)
    touchdown_nm, previous_nm : the measured touchdown and the step before it [nm] (``None``: not drawn)
    ax : the axes to draw on (``None``: a new figure's)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = panel(ax, (8.5, 3.4))
    ds, sel = _first_combination(sweep)
    x = ds["protrusion"].values
    n = ds.sizes.get("realisation", 1)
    p = ds["touchdown_probability"]
    ax.step(x, p.values, where="mid", color=LINE_COLOURS[3], lw=1.4, label=f"{n} DMW realisations")
    ax.set_ylim(-0.03, 1.03)
    ax.set_ylabel(var_label(p, "touchdown probability"))
    touchdown_lines((ax,), touchdown_nm, previous_nm, lw=1.2)
    heater_power_axis(ax, ds)
    ax.legend(fontsize=7.5, loc="upper left", framealpha=0.9)
    what = ", ".join(f"{d} {ds[d].values.item()}" for d in sel)
    ax.set_title(f"first grid combination ({what})" if what else "", fontsize=9)
    return ax


def plot_ensemble_fhm(sweep: xr.Dataset, *, touchdown_nm: float | None = None, previous_nm: float | None = None,
                      ax: Axes | None = None, labelled: bool = True) -> Axes:
    """FHM/BV [%] of every DMW realisation, their mean and a +-1 std band versus TFC protrusion [nm]
    (bottom of :func:`fig_ensemble`), of the sweep's first roughness set and damping ratio.

    Parameters
    ----------
    sweep : ``sweep.nc`` of ``[sweep] realisations > 1`` (``fhm_bv``, ``fhm_bv_mean``, ``fhm_bv_std``)
    touchdown_nm, previous_nm : the measured touchdown and the step before it [nm] (``None``: not drawn)
    ax : the axes to draw on (``None``: a new figure's)
    labelled : name the touchdown line in the legend (a figure names it once, on its top panel)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = panel(ax, (8.5, 3.4))
    ds, _ = _first_combination(sweep)
    x = ds["protrusion"].values
    ax.plot(x, np.asarray(ds["fhm_bv"].values).reshape(x.size, -1), color="0.6", lw=0.4, alpha=0.5)
    m, s = ds["fhm_bv_mean"].values, ds["fhm_bv_std"].values
    ax.fill_between(x, m - s, m + s, color=LINE_COLOURS[0], alpha=0.25, lw=0, label="mean ± 1 std")
    ax.plot(x, m, color=LINE_COLOURS[0], lw=1.4, marker="o", ms=2.5, label="ensemble mean")
    ax.set_ylabel(axis_label("FHM / BV (peak-to-peak / FH0)", ds["fhm_bv"].attrs.get("units", "%")))
    ax.set_xlabel(axis_label("TFC protrusion δ", "nm"))
    touchdown_lines((ax,), touchdown_nm, previous_nm, lw=1.2, labelled=labelled)
    ax.legend(fontsize=7.5, loc="upper left", framealpha=0.9)
    return ax


def fig_band(ens: xr.Dataset, scene: str, path: Path, *, band_nm: Sequence[float] = (), threshold: float = 20.0,
             touchdown_nm: float | None = None, previous_nm: float | None = None) -> Path:
    """The bouncing band over DMW realisations (``ensemble.nc``, whose stage computed every statistic drawn):
    :func:`plot_band` (top) and :func:`plot_band_probabilities` (bottom) versus protrusion [nm]."""
    fig, (ax, ax2) = new_figure(2, 1, size=(8.5, 6.6), sharex=True)
    plot_band(ens, band_nm=band_nm, threshold=threshold, touchdown_nm=touchdown_nm, previous_nm=previous_nm, ax=ax)
    plot_band_probabilities(ens, band_nm=band_nm, threshold=threshold, touchdown_nm=touchdown_nm,
                            previous_nm=previous_nm, ax=ax2, labelled=False)
    fig.suptitle(title("The bouncing band over DMW realisations", scene), fontsize=11)
    return save(fig, path)


def fig_bulge(bulge: xr.Dataset, scene: str, path: Path, *, protrusions_nm: Sequence[float] = (9.8, 10.4, 11.0),
              cap_nm: float | None = None) -> Path:
    """The bulge's air-bearing lift [mN] versus apex gap [nm] (``bulge.nc``: the scene's law, solid, and the
    p h = const closed form on the same grid, dashed) at the table's protrusions nearest ``protrusions_nm``,
    from 5 nm down to the table's smallest gap; with ``cap_nm`` (``air_bearing.lift_cap_gap_nm``) the capped
    lift the model runs with, grey (docs/model.md, sections "Rough-gap bulge bearing", "Lift cap (hypothesis H8)")."""
    fig, ax = new_figure(size=(7.5, 4.8))
    g = bulge["apex_gap"].values
    keep = g <= 5.0 + 1e-9
    prot = bulge["protrusion"].values
    for i, want in enumerate(dict.fromkeys(float(prot[np.argmin(np.abs(prot - w))]) for w in protrusions_nm)):
        row = bulge.sel(protrusion=want)
        lift, ph = row["bulge_lift"].values, row["bulge_lift_ph_limit"].values
        ax.plot(g[keep], lift[keep], color=f"C{i}", lw=1.8,
                label=f"{bulge.attrs.get('bulge_model', 'law')}, {want:g} nm")
        ax.plot(g[keep], ph[keep], color=f"C{i}", lw=1.0, ls="--", label=f"p h = const, {want:g} nm")
        if cap_nm:
            held = np.interp(np.log(cap_nm), np.log(g), lift)
            ax.plot(g[keep], np.where(g[keep] < cap_nm, held, lift[keep]), color="0.5", lw=4, alpha=0.35,
                    label="lift cap (H8)" if i == 0 else None)
    ax.set_xscale("log")
    ax.set_xlabel(axis_label("apex gap", bulge["apex_gap"].attrs.get("units", "nm")))
    ax.set_ylabel(axis_label("bulge lift", bulge["bulge_lift"].attrs.get("units", "mN")))
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(title(f"Bulge air-bearing lift at p_pad {float(bulge['pad_pressure']):g} MPa", scene), fontsize=11)
    return save(fig, path)


def _paper_band(ax: Axes, band_nm: Sequence[float], label: str | None) -> None:
    if len(band_nm):
        ax.axvspan(min(band_nm) - 0.1, max(band_nm) + 0.1, color="#ffbf00", alpha=0.15, lw=0, label=label)


def plot_band(ens: xr.Dataset, *, band_nm: Sequence[float] = (), threshold: float = 20.0,
              touchdown_nm: float | None = None, previous_nm: float | None = None, ax: Axes | None = None) -> Axes:
    """The bouncing BV [%] (BV where the run touched, 0 where it flew) of every DMW realisation, with its
    median and 10-90 % range and the paper's threshold, versus TFC protrusion [nm] (top of :func:`fig_band`).

    Parameters
    ----------
    ens : ``ensemble.nc`` (``bouncing_bv``, ``bouncing_bv_spread``, ``bouncing_bv_median``)
    band_nm : the paper's band of protrusions [nm], shaded (empty: none); the axes then start 2 nm below it
    threshold : the bouncing threshold of BV [%]
    touchdown_nm, previous_nm : the measured touchdown and the step before it [nm] (``None``: not drawn)
    ax : the axes to draw on (``None``: a new figure's)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = panel(ax, (8.5, 3.4))
    x = ens["protrusion"].values
    n = ens.sizes["realisation"]
    _paper_band(ax, band_nm, "the paper's band")
    bv = ens["bouncing_bv"]
    lo, hi = ens["bouncing_bv_spread"].values.T
    ax.plot(x, bv.values, ".", color="0.55", ms=3, alpha=0.6)
    ax.fill_between(x, lo, hi, color=LINE_COLOURS[0], alpha=0.2, lw=0, label="10-90 % of the realisations")
    ax.plot(x, ens["bouncing_bv_median"].values, color=LINE_COLOURS[0], lw=1.4, marker="o", ms=3,
            label=f"median over {n} DMW realisations")
    ax.axhline(threshold, color="k", lw=0.8, ls="--", label=f"paper: BV > {threshold:g} %")
    ax.set_ylabel(axis_label("bouncing BV (0 where flying)", bv.attrs.get("units", "%")))
    touchdown_lines((ax,), touchdown_nm, previous_nm, lw=1.0)
    heater_power_axis(ax, ens)
    ax.legend(fontsize=7.5, loc="upper left", framealpha=0.9)
    if len(band_nm):  # around the band: from 2 nm below it (the flying FHM targets far below add nothing here)
        ax.set_xlim(max(float(np.min(x)), min(band_nm) - 2.0) - 0.1, float(np.max(x)) + 0.1)
    return ax


def plot_band_probabilities(ens: xr.Dataset, *, band_nm: Sequence[float] = (), threshold: float = 20.0,
                            touchdown_nm: float | None = None, previous_nm: float | None = None,
                            ax: Axes | None = None, labelled: bool = True) -> Axes:
    """The fraction of the DMW realisations bouncing above the threshold, the touchdown probability and the
    median contact fraction with its 10-90 % range [1] versus TFC protrusion [nm] (bottom of :func:`fig_band`).

    Parameters
    ----------
    ens : ``ensemble.nc`` (``bv_exceedance_probability``; ``touchdown_probability`` and
        ``contact_fraction_median``/``_spread`` when present)
    band_nm : the paper's band of protrusions [nm], shaded (empty: none)
    threshold : the bouncing threshold of BV [%] (the legend)
    touchdown_nm, previous_nm : the measured touchdown and the step before it [nm] (``None``: not drawn)
    ax : the axes to draw on (``None``: a new figure's)
    labelled : name the paper's band and the touchdown line in the legend (a figure names them once, on
        its top panel)

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = panel(ax, (8.5, 3.4))
    x = ens["protrusion"].values
    _paper_band(ax, band_nm, "the paper's band" if labelled else None)
    ax.plot(x, ens["bv_exceedance_probability"].values, color=LINE_COLOURS[3], lw=1.4, marker="s", ms=3,
            label=f"P(bouncing BV > {threshold:g} %)")
    if "touchdown_probability" in ens:
        ax.plot(x, ens["touchdown_probability"].values, color="#d62728", lw=1.0, ls="--",
                label="touchdown probability")
    if "contact_fraction_median" in ens:
        clo, chi = ens["contact_fraction_spread"].values.T
        ax.fill_between(x, clo, chi, color=LINE_COLOURS[2], alpha=0.2, lw=0)
        ax.plot(x, ens["contact_fraction_median"].values, color=LINE_COLOURS[2], lw=1.2,
                label="contact fraction of the window (median, 10-90 %)")
    ax.axhline(0.5, color="k", lw=0.6, ls=":")
    ax.set_ylim(-0.03, 1.03)
    ax.set_ylabel(axis_label("probability / fraction", "1"))
    ax.set_xlabel(axis_label("TFC protrusion δ", "nm"))
    touchdown_lines((ax,), touchdown_nm, previous_nm, lw=1.0, labelled=labelled)
    ax.legend(fontsize=7.5, loc="upper left", framealpha=0.9)
    return ax


# --------------------------------------------------------------------------------------------- Fig. 7
def fig_shear(combos: Sequence[tuple[dict[str, Any], xr.Dataset]], scene: str, path: Path, *,
              touchdown_nm: float | None = None, shear_strength: float | None = None) -> Path:
    """Shear stress (top) and mean contact pressure (bottom) versus protrusion past touchdown (Fig. 7)."""
    fig, (ax, ax2) = new_figure(2, 1, size=(7.5, 6.0), sharex=True)
    any_points = False
    xmin = None
    for i, (labels, ds) in enumerate(combos):
        x = ds["protrusion"].values
        tau = np.asarray(ds["shear_stress"].values, float).reshape(-1)
        ok = np.isfinite(tau)
        if not ok.any():
            continue
        any_points = True
        xmin = x[ok].min() if xmin is None else min(xmin, x[ok].min())
        colour = LINE_COLOURS[i % len(LINE_COLOURS)]
        lab = _combo_label(labels) if len(combos) > 1 else None
        ax.plot(x[ok], tau[ok], marker="o", ms=2.5, lw=1.2, color=colour, label=lab or "shear stress")
        if "mean_pressure" in ds:
            p = np.asarray(ds["mean_pressure"].values, float).reshape(-1)
            ax2.plot(x[ok], p[ok], marker="s", ms=2.5, lw=1.2, color=colour, label=lab or "mean contact pressure")
    if shear_strength is not None and np.isfinite(shear_strength):
        ax.axhline(shear_strength, color="0.4", ls="--", lw=1.0,
                   label=f"shear strength τ_y = H/(2.8√3) = {shear_strength:.4g} MPa")
    for a in (ax, ax2):
        if touchdown_nm is not None:
            a.axvline(touchdown_nm, color="#d62728", lw=1.2, label=f"measured touchdown {touchdown_nm:g} nm")
        a.grid(alpha=0.3)
    if not any_points:
        note(ax, "no contact anywhere in the sweep: shear stress undefined", loc="upper left", fontsize=10)
    else:
        ax.set_xlim(left=xmin - 0.3)
        if touchdown_nm is not None:
            ax.set_xlim(left=min(xmin, touchdown_nm) - 0.3)
        y = ax.get_ylim()
        if y[1] - y[0] < 1e-6 * max(abs(y[1]), 1.0) * 10:
            ax.set_ylim(y[0] * 0.9, y[1] * 1.1)
    ax.set_ylabel(axis_label("shear stress", "MPa"))
    ax2.set_ylabel(axis_label("mean contact pressure", "MPa"))
    ax2.set_xlabel(axis_label("TFC protrusion δ", "nm"))
    ax.legend(fontsize=7.5, loc="best", framealpha=0.9)
    ax2.legend(fontsize=7.5, loc="best", framealpha=0.9)
    fig.suptitle(title("Fig. 7: contact shear stress and mean pressure past touchdown", scene), fontsize=11)
    return save(fig, path)


# ------------------------------------------------------------------------------------------ calibration
def fig_calibration(cal: xr.Dataset, scene: str, path: Path, *, onset_nm: float, previous_nm: float,
                    k_used: float | None = None, k_source: str = "") -> Path:
    """Touchdown protrusion versus k, the measured band and the admissible k interval."""
    fig, ax = new_figure(size=(7.5, 5.0))
    k = cal["k"].values
    td = np.asarray(cal["touchdown"].values, float)
    ax.axhspan(previous_nm, onset_nm, color="#ffd6d6", lw=0, zorder=0,
               label=f"measured: contact at {onset_nm:g} nm, none at {previous_nm:g} nm")
    ax.axhline(onset_nm, color="#d62728", lw=0.8)
    ax.axhline(previous_nm, color="#d62728", lw=0.8, ls=":")
    ax.plot(k, td, marker="o", ms=4, lw=1.2, color=LINE_COLOURS[0], label="touchdown protrusion (simulated)")
    none = ~np.isfinite(td)
    if none.any():
        top = np.nanmax(td) if np.isfinite(td).any() else onset_nm
        ax.plot(k[none], np.full(none.sum(), top + 0.5), "x", color="0.3", label="no contact on the grid")
    lo, hi = float(cal["k_low"]) if "k_low" in cal else np.nan, float(cal["k_high"]) if "k_high" in cal else np.nan
    kc = float(cal["k_calibrated"]) if "k_calibrated" in cal else np.nan
    if np.isfinite(lo) and np.isfinite(hi):
        ax.axvspan(lo, hi, color="#c9f0c2", alpha=0.9, lw=0, zorder=0, label=f"admissible k: ({lo:.3f}, {hi:.3f}]")
        ax.axvline(kc, color="#2ca02c", lw=1.2, label=f"calibrated k = {kc:.3f}")
    else:
        outcome = str(cal.attrs.get("outcome", "no admissible k"))
        short = outcome.split(":")[0]
        finite = td[np.isfinite(td)]
        extra = (f"\ntouchdown at {finite[0]:g} nm for every k scanned" if finite.size == td.size and finite.size
                 and np.ptp(finite) == 0 else "")
        note(ax, f"{short}{extra}", loc="lower left", fontsize=9, color="#a00000")
    if k_used is not None and np.isfinite(k_used) and not (np.isfinite(kc) and abs(kc - k_used) < 1e-9):
        src = "fallback" if "fallback" in k_source else "used"
        ax.axvline(k_used, color="#9467bd", lw=1.2, ls="-.", label=f"k {src} in the sweep: {k_used:.3f}")
    ax.set_xlabel(axis_label("contact criterion constant k (contact when d < k σ)", "1"))
    ax.set_ylabel(axis_label("touchdown protrusion", "nm"))
    ylo = np.nanmin(np.concatenate([td[np.isfinite(td)], [previous_nm]])) - 1.0
    yhi = np.nanmax(np.concatenate([td[np.isfinite(td)], [onset_nm]])) + 1.0
    ax.set_ylim(ylo, yhi)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7.5, loc="best", framealpha=0.9)
    fig.suptitle(title("Calibration of the contact criterion k against the measured touchdown", scene), fontsize=11)
    return save(fig, path)


# -------------------------------------------------------------------------------------------- roughness
ROUGH_BARS = (("sigma", "σ (rms)"), ("summit_density", "η (summit density)"), ("summit_radius", "R (summit radius)"))
ROUGH_TABLE = (("sigma", "rms roughness σ"), ("sigma_s", "summit-height std σ_s"), ("y_s", "summit-mean offset y_s"),
               ("summit_radius", "summit radius R"), ("summit_density", "summit density η"),
               ("bandwidth_alpha", "bandwidth α"), ("plasticity_index", "plasticity index ψ (GW)"),
               ("plasticity_index_ke", "plasticity index ψ (CEB/KE)"))


def has_afm_surfaces(rough: xr.Dataset) -> bool:
    """Whether ``roughness.nc`` holds measured surfaces (anything but ``explicit``/``combined``)."""
    return any(str(s) not in ("explicit", "combined") for s in rough["surface"].values)


def fig_roughness(rough: xr.Dataset, scene: str, path: Path, interface: xr.Dataset | None = None) -> Path:
    """Per-surface bars of sigma, eta, R by route (AFM input), or a table of the explicit statistics."""
    if has_afm_surfaces(rough):
        return _roughness_bars(rough, scene, path)
    return _roughness_table(rough, scene, path, interface)


def _roughness_bars(rough: xr.Dataset, scene: str, path: Path) -> Path:
    surfaces = [str(s) for s in rough["surface"].values]
    methods = [str(m) for m in rough["route"].values]
    fig, axes = new_figure(1, len(ROUGH_BARS), size=(4.0 * len(ROUGH_BARS), 4.4), squeeze=False)
    x = np.arange(len(surfaces))
    w = 0.8 / max(len(methods), 1)
    for ax, (name, q) in zip(axes[0], ROUGH_BARS):
        for j, m in enumerate(methods):
            vals = np.asarray(rough[name].sel(route=m).values, float)
            bars = ax.bar(x + (j - (len(methods) - 1) / 2) * w, np.nan_to_num(vals), w,
                          color=LINE_COLOURS[j], label=f"{m} route")
            for b, v in zip(bars, vals):
                if not np.isfinite(v):
                    ax.text(b.get_x() + b.get_width() / 2, 0, "n/a", ha="center", va="bottom", fontsize=7,
                            rotation=90)
        ax.set_xticks(x, surfaces, rotation=30, ha="right", fontsize=8)
        ax.set_ylabel(var_label(rough[name], q))
        ax.grid(alpha=0.3, axis="y")
    axes[0, 0].legend(fontsize=8)
    if "pixel_size" in rough:
        px = ", ".join(f"{s}: {p:.3g} nm" for s, p in zip(surfaces, rough["pixel_size"].values) if np.isfinite(p))
        if px:
            fig.text(0.01, 0.005, f"pixel size {px}", fontsize=7)
    fig.suptitle(title("Asperity statistics per AFM surface and route", scene), fontsize=11)
    return save(fig, path)


def _fmt(v: float) -> str:
    return "n/a" if not np.isfinite(v) else f"{v:.4g}"


def _roughness_table(rough: xr.Dataset, scene: str, path: Path, interface: xr.Dataset | None) -> Path:
    surface = "explicit" if "explicit" in [str(s) for s in rough["surface"].values] else str(rough["surface"].values[0])
    methods = [str(m) for m in rough["route"].values]
    rows, cells, dropped = [], [], []
    for name, q in ROUGH_TABLE:
        if name not in rough:
            continue
        da = rough[name].sel(surface=surface)
        vals = [float(da.sel(route=m)) for m in methods] if "route" in da.dims else [float(da)] * len(methods)
        if not np.isfinite(vals).any():
            dropped.append(q)
            continue
        rows.append(f"{q} [{unit_text(rough[name].attrs.get('units')) if rough[name].attrs.get('units') != '1' else '-'}]")
        cells.append([_fmt(v) for v in vals])
    if interface is not None:
        for name, q in (("plasticity_index_gw", "ψ (GW) used by the interface"),
                        ("plasticity_index_ke", "ψ (CEB/KE) used by the interface"),
                        ("hardness", "hardness H"), ("composite_modulus", "composite modulus E'")):
            if name in interface:
                u = interface[name].attrs.get("units", "1")
                rows.append(f"{q} [{'-' if u == '1' else unit_text(u)}]")
                cells.append([_fmt(float(interface[name]))] + [""] * (len(methods) - 1))
    fig, ax = new_figure(size=(8.0, 0.32 * (len(rows) + 1) + 1.3))
    ax.axis("off")
    tab = ax.table(cellText=cells, rowLabels=rows, colLabels=[f"{m} route" for m in methods],
                   cellLoc="center", bbox=[0.45, 0.0, 0.55, 1.0])
    tab.auto_set_font_size(False)
    tab.set_fontsize(9)
    for (r, c), cell in tab.get_celld().items():
        if r == 0:
            cell.set_facecolor("#dde7f3")
        elif r % 2 == 0:
            cell.set_facecolor("#f5f5f5")
        if c == -1:
            cell.set_text_props(ha="left")
    sub = f"surface '{surface}' (explicit statistics, no AFM scan): the summit route needs a scan (n/a)"
    if dropped:
        sub += "\nnot in roughness.nc (no hardness given there): " + "; ".join(dropped)
    ax.set_title(sub, fontsize=8.5)
    fig.suptitle(title("Roughness statistics of the combined surface", scene), fontsize=11)
    return save(fig, path)


# ------------------------------------------------------------------------------------------------- DMW
def fig_dmw(dmw: xr.Dataset, scene: str, path: Path) -> Path:
    """The DMW record (top) and its one-sided PSD, log-log, with the band edges (bottom)."""
    fig, (ax, ax2) = new_figure(2, 1, size=(7.5, 6.4))
    t = dmw[TIME].values * S_IN_MS
    w = dmw["displacement"]
    ax.plot(*envelope(t, w.values), lw=0.5, color=LINE_COLOURS[0])
    rms = float(dmw["rms"]) if "rms" in dmw else float(np.sqrt(np.mean(w.values ** 2)))
    src = dmw.attrs.get("dmw_source", "unknown")
    note(ax, f"rms {rms:.4g} nm; source: {src}", loc="upper right")
    ax.set_xlabel(axis_label("time", "ms"))
    ax.set_ylabel(var_label(w, "disk displacement w"))
    ax.grid(alpha=0.3)
    ax.set_title("record", fontsize=10)
    if "psd" in dmw and "frequency" in dmw.coords:
        f = dmw["frequency"].values
        p = dmw["psd"].values
        ok = (f > 0) & np.isfinite(p) & (p > 0)
        ax2.loglog(f[ok] / KHZ, p[ok], lw=0.6, color=LINE_COLOURS[0], label="periodogram")
        for name, ls in (("band_low", "--"), ("band_high", "--")):
            if name in dmw:
                edge = float(dmw[name]) / KHZ
                ax2.axvline(edge, color="#d62728", ls=ls, lw=1.0,
                            label=f"band {'lower' if name == 'band_low' else 'upper'} edge {edge:g} kHz")
        if ok.any():
            lo_e = float(dmw["band_low"]) if "band_low" in dmw else 0.0
            hi_e = float(dmw["band_high"]) if "band_high" in dmw else np.inf
            inband = p[ok & (f > lo_e * 1.0001) & (f < hi_e * 0.9999)]
            pos = inband if inband.size else p[ok]
            ax2.set_ylim(np.percentile(pos, 0.5) / 10, pos.max() * 10)
            fmax = f[ok].max() if not np.isfinite(hi_e) else min(hi_e * 4, f.max())
            ax2.set_xlim((lo_e / 4 if lo_e > 0 else f[ok].min()) / KHZ, fmax / KHZ)
        ax2.set_xlabel(axis_label("frequency", "kHz"))
        ax2.set_ylabel(var_label(dmw["psd"], "PSD of w"))
        ax2.legend(fontsize=7.5, loc="lower left", framealpha=0.9)
    else:
        ax2.axis("off")
        note(ax2, "no spectrum in dmw.nc", loc="upper left")
    ax2.grid(alpha=0.3, which="both")
    ax2.set_title("spectrum", fontsize=10)
    fig.suptitle(title("Dynamic microwaviness (DMW) of the disk", scene), fontsize=11)
    return save(fig, path)


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

#: Real-area fractions of the light-contact band where the interface figure compares the two models [1].
LIGHT_CONTACT_AREA = (0.005, 0.1)


def fig_interface_models(interface: xr.Dataset, scene: str, path: Path) -> Path:
    """The statistical and the deterministic interface tables versus separation, and their relative
    difference where contact is light (statistical real area in :data:`LIGHT_CONTACT_AREA`).

    ``interface`` holds both on its ``model`` coordinate (``interface.model = "deterministic"``);
    the deterministic solves themselves are marked on the curves.
    """
    fig, axes = new_figure(3, 1, size=(7.5, 8.6))
    d = interface["separation"].values
    colours = dict(zip(("statistical", "deterministic"), LINE_COLOURS))
    # from well inside full contact to where the deterministic tables end (first contact) or 1e-4 of
    # real area, below which a statistical Gaussian tail only fills the axis
    a_det = interface["real_area_fraction"].sel(model="deterministic").values
    reach = d[(a_det > 0) | (interface["real_area_fraction"].sel(model="statistical").values > 1e-4)]
    solved = interface["solved_separation"].values if "solved_separation" in interface else reach
    x_lim = (max(d[0], float(np.min(solved)) - 2.0), float(reach.max()) + 1.0) if reach.size else (d[0], d[-1])
    for ax, name, quantity, solved_name, floor in (
            (axes[0], "contact_pressure", "contact pressure", "solved_contact_pressure", 1e-4),
            (axes[1], "real_area_fraction", "real-area fraction", "solved_real_area_fraction", 1e-5)):
        top = 0.0
        for model in interface["model"].values:
            y = interface[name].sel(model=model).values
            ok = (y > 0) & (d >= x_lim[0]) & (d <= x_lim[1])
            ax.semilogy(d[ok], y[ok], lw=1.3, color=colours.get(str(model)), label=str(model))
            top = max(top, float(y[ok].max()) if ok.any() else 0.0)
        if solved_name in interface:
            ax.semilogy(interface["solved_separation"].values, interface[solved_name].values, "o", ms=3.5,
                        mfc="none", color=colours["deterministic"], label="deterministic solves")
        if top > 0:
            ax.set_ylim(top * floor, top * 3)
        ax.set_xlim(*x_lim)
        ax.set_ylabel(var_label(interface[name], quantity))
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="upper right")
    lo, hi = LIGHT_CONTACT_AREA
    a_stat = interface["real_area_fraction"].sel(model="statistical").values
    band = (a_stat >= lo) & (a_stat <= hi)
    ax = axes[2]
    for name, quantity, ls in (("contact_pressure", "contact pressure", "-"), ("real_area_fraction", "real area", "--")):
        s = interface[name].sel(model="statistical").values
        t = interface[name].sel(model="deterministic").values
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(band & (s > 0), (t - s) / s, np.nan)
        ax.plot(d, 100 * rel, ls=ls, color=LINE_COLOURS[2], label=quantity)
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_ylabel(axis_label("relative difference", "%"))
    ax.set_title("(deterministic - statistical) / statistical", fontsize=10)
    ax.set_xlabel(var_label(interface["separation"], "separation d from the mean of summit heights"))
    ax.grid(alpha=0.3)
    if band.any():
        ax.set_xlim(d[band].min() - 1.0, d[band].max() + 1.0)
        ax.legend(fontsize=8, loc="best")
    note(ax, f"where the statistical real area is {lo * 100:g}-{hi * 100:g} %", loc="lower left")
    fig.suptitle(title("Interface tables: statistical (GW/Kogut-Etsion) and deterministic (FFT BEM)", scene),
                 fontsize=11)
    return save(fig, path)


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
