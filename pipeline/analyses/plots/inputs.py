"""The figures of the model's inputs: roughness statistics, the DMW record, the interface models and the
bulge lift table.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np
import xarray as xr

from ...units import KHZ, S_IN_MS
from ...variables import TIME
from .common import LINE_COLOURS, axis_label, envelope, new_figure, note, save, title, unit_text, var_label

if TYPE_CHECKING:
    pass


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
