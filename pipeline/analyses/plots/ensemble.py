"""The figures over DMW realisations: touchdown probability and FHM spread of an ensemble sweep, and the
bouncing band.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np
import xarray as xr

from .common import LINE_COLOURS, axis_label, heater_power_axis, new_figure, panel, save, title, var_label

if TYPE_CHECKING:
    from matplotlib.axes import Axes


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
