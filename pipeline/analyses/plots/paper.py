"""The paper's figures of one scene: the clearance (Fig. 3), forces (Fig. 4), stresses (Fig. 5), FHM (Fig. 6) and
shear (Fig. 7) versus time or protrusion, and the calibration's touchdown onset.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np
import xarray as xr

from ...units import S_IN_MS
from ...variables import TIME, regime_name
from .common import (LINE_COLOURS, axis_label, envelope, heater_power_axis, new_figure, note, panel, runs, save,
                     shade_regimes, title, var_label)

if TYPE_CHECKING:
    from matplotlib.axes import Axes


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
