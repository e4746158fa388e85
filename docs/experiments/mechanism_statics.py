"""Statics maps of the three mechanisms that could deepen the 11-nm contact, and of the roughness datum, before
any dynamics (docs/results.md, section "Statics of the three mechanisms", where the tables this prints are
kept; docs/model.md, section "Mechanism statics"; docs/figures/mechanism_statics.png).

For the main scene (``configs/paper-2009-identified.toml``, its calibrated k) and each mechanism at a few
values within its bounds (:func:`pipeline.analyses.mechanism_statics.mechanism_map`):

* penetration adhesion: ``lubricant.solid_work_of_adhesion_j_m2`` = 0.05, 0.075, 0.10 J/m^2 (bounds), 0.149
  (outside: the estimate that asked for it);
* frictional heating: ``eta_f`` = 0.01, 0.02, 0.05, 0.1 nm/mW (bounds 0-0.1: a heater's ~0.1 nm/mW times the
  slider's share of the heat);
* pitch compliance: ``air_bearing.stiffness_root = "pitch-first"``, ``slider.friction_arm = "gimbal"``, and
  both (the value: the free TFC point's lift per mN of friction);
* the roughness datum: ``configs/paper-2009-identified-section-datum.toml`` (k sigma = 1.56 nm).

Every variant keeps the main scene's calibrated k (``--set contact.k=...``: the contact state's separation
does not depend on k, and no variant but the pitch root changes the flight), except the roughness datum,
whose k is its reading. Printed: per case the protrusions with a stable flying state, the contact state's
interference, contact force, mu and friction power at 9.8 and 11 nm, its heat's protrusion and flash
temperature at 11 nm; written: the map (``--out``, NetCDF) and the figure.

Usage (from the project root; ~2 min on 2 shared cores, most of it the variants' interface tables and their
first compile)::

    .venv/bin/python docs/experiments/mechanism_statics.py [--results results/mechanisms] \
        [--figure docs/figures/mechanism_statics.png]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import pipeline as hdi  # noqa: E402
from pipeline.analyses import mechanism_statics as ms  # noqa: E402

PROTRUSIONS = np.round(np.arange(9.0, 11.41, 0.2), 1)  # [nm]
SHOWN = (9.8, 11.0)  # [nm]


def cases(results: Path) -> tuple[list, object]:
    """The map's cases and the main scene's interface dataset."""
    main = ROOT / "configs" / "paper-2009-identified.toml"
    base = hdi.build_model(main, results / "main", progress=False)
    k = f"contact.k={base.k!r}"
    out = [ms.Case("none", 0.0, base, label="main scene")]
    for w in (0.05, 0.075, 0.10, 0.149):
        m = hdi.build_model(hdi.load_scene(main, [k, f"lubricant.solid_work_of_adhesion_j_m2={w}"]),
                            results / f"ws-{w:g}", progress=False)
        out.append(ms.Case("penetration-adhesion", w, m, label=f"W_s {w:g}" + (" (outside)" if w > 0.10 else "")))
    for eta in (0.01, 0.02, 0.05, 0.1):
        out.append(ms.Case("frictional-heating", eta, base, heating=eta, label=f"eta_f {eta:g}"))
    for sets, name in (([ 'air_bearing.stiffness_root="pitch-first"'], "pitch-first"),
                       (['slider.friction_arm="gimbal"'], "gimbal arm"),
                       (['air_bearing.stiffness_root="pitch-first"', 'slider.friction_arm="gimbal"'],
                        "pitch-first, gimbal arm")):
        m = hdi.build_model(hdi.load_scene(main, [k, *sets]), results / name.replace(", ", "-").replace(" ", "-"),
                            progress=False)
        out.append(ms.Case("pitch-compliance", ms.friction_lift(m) / 1e-6, m, label=name))  # [nm/mN]
    datum = hdi.build_model(ROOT / "configs" / "paper-2009-identified-section-datum.toml", results / "datum",
                            progress=False)
    out.append(ms.Case("roughness-datum", datum.k_sigma / 1e-9, datum, label="section datum (k sigma 1.56 nm)"))
    iface = hdi.open_dataset(results / "main", "interface")
    return out, iface


def table(ds) -> str:
    rows = ["| case | k | lift [nm/mN] | fold [nm] | flying at [nm] | 9.8 nm: interference / force / mu | 11 nm: interference [nm] | "
            "force [mN] | mu | friction power [mW] | heat protrusion [nm] | flash T [K] |", "|" + "---|" * 12]
    for c in ds["case"].values:
        d = ds.sel(case=c)
        fly = d["protrusion"].values[d["flying"].values == 1]
        a, b = d.sel(protrusion=SHOWN[0]), d.sel(protrusion=SHOWN[1])
        head = f"| {c} | {float(d['k']):.4g} | {float(d['friction_lift']):.3f} | {float(d['fold']):.3f} | "
        rows.append(head + (f"{fly.min():.1f}-{fly.max():.1f} | " if fly.size else "none | "))
        rows[-1] += (f"{float(a['interference']):.3f} / {float(a['contact_force']):.3f} / "
                     f"{float(a['friction_coefficient']):.3f} | {float(b['interference']):.3f} | "
                     f"{float(b['contact_force']):.3f} | {float(b['friction_coefficient']):.3f} | "
                     f"{float(b['friction_power']):.1f} | {float(b['thermal_protrusion']):.3f} | "
                     f"{float(b['flash_temperature']):.1f} |")
    return "\n".join(rows)


def figure(ds, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharex=True)
    styles = {"none": "k-", "penetration-adhesion": "-", "frictional-heating": "--", "pitch-compliance": "-.",
              "roughness-datum": ":"}
    for c in ds["case"].values:
        d = ds.sel(case=c)
        style = styles[str(d["mechanism"].values)]
        for ax, name in zip(axes.flat[:3], ("interference", "contact_force", "friction_coefficient")):
            ax.plot(d["protrusion"], d[name], style, label=str(c), lw=1.8 if style == "k-" else 1.2)
        axes.flat[3].plot(d["protrusion"], d["flying_clearance"], style, lw=1.2)
    for ax, name in zip(axes.flat, ("interference", "contact_force", "friction_coefficient", "flying_clearance")):
        v = ms.MAP[name]
        ax.set_ylabel(f"{v.long_name} [{v.units}]" if v.units not in ("", "1") else v.long_name)
        ax.grid(alpha=0.3)
    axes.flat[2].axhspan(1.05, 1.35, color="0.9", zorder=0, label="paper's mu 1.05-1.35")
    axes.flat[3].set_title("stable flying state (none: the line ends)", fontsize=9)
    for ax in axes[1]:
        ax.set_xlabel("protrusion [nm]")
    axes.flat[0].legend(fontsize=7, ncol=2)
    fig.suptitle("Static contact state per mechanism (paper-2009-identified)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default="results/mechanisms", type=Path)
    ap.add_argument("--figure", default=None, type=Path)
    args = ap.parse_args(argv)
    found, iface = cases(args.results)
    ds = ms.mechanism_map(found, PROTRUSIONS, interface=iface)
    args.results.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(args.results / "mechanism_statics.nc")
    print(table(ds))
    # the thermal bounds: a glass substrate (the map's) and a metal underlayer under the contact
    metal = ms.Thermal(k_disk=50.0, diffusivity_disk=1.5e-5)
    for name, th in (("glass disk", ms.Thermal()), ("metal underlayer", metal)):
        d = ms.mechanism_map(found[:1], [11.0], interface=iface, thermal=th).isel(case=0, protrusion=0)
        print(f"11 nm, {name} (k_disk {th.k_disk:g} W/(m K), kappa {th.diffusivity_disk:g} m2/s): flash "
              f"{float(d['flash_temperature']):.1f} K (slider share {float(d['heat_partition']):.2f}, Pe "
              f"{float(d['contact_peclet']):.3g}, {float(d['contact_count']):.0f} summits); nominal "
              f"{float(d['nominal_temperature']):.1f} K (slider share {float(d['nominal_heat_partition']):.2f})")
    if args.figure:
        figure(ds, args.figure)


if __name__ == "__main__":
    main()
