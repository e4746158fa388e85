"""Statics maps of the three mechanisms that could deepen the 11-nm contact, and of the roughness datum, before
any dynamics (docs/results.md, sections "Statics of the three mechanisms" and "The mechanisms on the band scene",
where the tables this prints are kept; docs/model.md, section "Mechanism statics"; docs/figures/mechanism_statics.png,
docs/figures/mechanism_statics_band.png).

For a scene (``--scene``, default the main scene ``configs/paper-2009-identified.toml``, with its ``--set``
overrides; its k, calibrated or chosen) and each mechanism at a few values within its bounds
(:func:`pipeline.analyses.mechanism_statics.mechanism_map`):

* penetration adhesion: ``lubricant.solid_work_of_adhesion_j_m2`` = 0.05, 0.075, 0.10 J/m^2 (bounds), 0.149
  (outside: the estimate that asked for it);
* frictional heating: ``eta_f`` = 0.01, 0.02, 0.05, 0.1 nm/mW (bounds 0-0.1: a heater's ~0.1 nm/mW times the
  slider's share of the heat);
* pitch compliance: ``air_bearing.stiffness_root = "pitch-first"``, ``slider.friction_arm = "gimbal"``, and
  both (the value: the free TFC point's lift per mN of friction);
* the roughness datum: the contact criterion at the nominal-area section, ``contact.k = 3`` (k sigma = 1.56 nm;
  on the main scene this is ``configs/paper-2009-identified-section-datum.toml``).

Every variant keeps the scene's k (``--set contact.k=...``: the contact state's separation does not depend on
k, and no variant but the pitch root changes the flight), except the roughness datum, whose k is its reading.
Printed: per case the protrusions with a stable flying state, the contact state's interference, contact force,
mu and friction power at 9.8 and 11 nm, its heat's protrusion and flash temperature at 11 nm; written: the map
(``--results``/mechanism_statics.nc) and the figure.

Usage (from the project root; ~2 min on 2 shared cores for the main scene, most of it the variants' interface
tables and their first compile; the band scene's rough-gap bearing adds a bulge table per variant)::

    .venv/bin/python docs/experiments/mechanism_statics.py [--results results/mechanisms] \
        [--figure docs/figures/mechanism_statics.png]
    .venv/bin/python docs/experiments/mechanism_statics.py --scene configs/paper-2009-two-population-rough.toml \
        --set air_bearing.pad_pressure_mpa=2.2 --set dmw.exponent=-4 --set dmw.rms_nm=1.8 --name "band scene" \
        --results results/mechanisms-band --figure docs/figures/mechanism_statics_band.png
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


#: The main scene, the map's default.
MAIN = ROOT / "configs" / "paper-2009-identified.toml"
#: The roughness datum: the contact criterion at the nominal-area section (k = contact.section_depth_sigma).
SECTION_DATUM = "contact.k=3.0"


def cases(results: Path, scene: Path = MAIN, sets: tuple[str, ...] = (), name: str = "main scene"
          ) -> tuple[list, object]:
    """The map's cases and the scene's interface dataset (``scene`` with its ``--set`` overrides ``sets``)."""
    base = hdi.build_model(hdi.load_scene(scene, sets), results / "main", progress=False)
    k = f"contact.k={base.k!r}"
    out = [ms.Case("none", 0.0, base, label=name)]
    for w in (0.05, 0.075, 0.10, 0.149):
        m = hdi.build_model(hdi.load_scene(scene, [*sets, k, f"lubricant.solid_work_of_adhesion_j_m2={w}"]),
                            results / f"ws-{w:g}", progress=False)
        out.append(ms.Case("penetration-adhesion", w, m, label=f"W_s {w:g}" + (" (outside)" if w > 0.10 else "")))
    for eta in (0.01, 0.02, 0.05, 0.1):
        out.append(ms.Case("frictional-heating", eta, base, heating=eta, label=f"eta_f {eta:g}"))
    for extra, label in (([ 'air_bearing.stiffness_root="pitch-first"'], "pitch-first"),
                         (['slider.friction_arm="gimbal"'], "gimbal arm"),
                         (['air_bearing.stiffness_root="pitch-first"', 'slider.friction_arm="gimbal"'],
                          "pitch-first, gimbal arm")):
        m = hdi.build_model(hdi.load_scene(scene, [*sets, k, *extra]),
                            results / label.replace(", ", "-").replace(" ", "-"), progress=False)
        out.append(ms.Case("pitch-compliance", ms.friction_lift(m) / 1e-6, m, label=label))  # [nm/mN]
    datum = hdi.build_model(hdi.load_scene(scene, [*sets, SECTION_DATUM]), results / "datum", progress=False)
    out.append(ms.Case("roughness-datum", datum.k_sigma / 1e-9, datum,
                       label=f"section datum (k sigma {datum.k_sigma / 1e-9:.2f} nm)"))
    iface = hdi.open_dataset(results / "main", "interface")
    return out, iface


def _steps(d, name: str) -> str:
    """The protrusions [nm] where the flag ``name`` is set, as ``lo-hi``, or ``none``."""
    at = d["protrusion"].values[d[name].values == 1]
    return f"{at.min():.1f}-{at.max():.1f}" if at.size else "none"


def table(ds) -> str:
    """The map's markdown table: per case the flying, contact and coexistence steps, the contact at 9.8 and 11 nm."""
    rows = ["| case | k | lift [nm/mN] | fold [nm] | flying at [nm] | contact at [nm] | both at [nm] | "
            "9.8 nm: interference / force / mu | 11 nm: interference [nm] | force [mN] | real area [um^2] | mu | "
            "friction power [mW] | heat protrusion [nm] | flash T [K] |", "|" + "---|" * 15]
    for c in ds["case"].values:
        d = ds.sel(case=c)
        a, b = d.sel(protrusion=SHOWN[0]), d.sel(protrusion=SHOWN[1])
        rows.append(f"| {c} | {float(d['k']):.4g} | {float(d['friction_lift']):.3f} | {float(d['fold']):.3f} | "
                    f"{_steps(d, 'flying')} | {_steps(d, 'contact')} | {_steps(d, 'coexist')} | "
                    f"{float(a['interference']):.3f} / {float(a['contact_force']):.3f} / "
                    f"{float(a['friction_coefficient']):.3f} | {float(b['interference']):.3f} | "
                    f"{float(b['contact_force']):.3f} | {float(b['real_area']):.2f} | "
                    f"{float(b['friction_coefficient']):.3f} | {float(b['friction_power']):.1f} | "
                    f"{float(b['thermal_protrusion']):.3f} | {float(b['flash_temperature']):.1f} |")
    return "\n".join(rows)


def figure(ds, path: Path, title: str = "paper-2009-identified") -> None:
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
    fig.suptitle(f"Static contact state per mechanism ({title})")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def options(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line: ``--results``, ``--figure``, ``--scene``, ``--set`` (repeatable) and ``--name``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default="results/mechanisms", type=Path)
    ap.add_argument("--figure", default=None, type=Path)
    ap.add_argument("--scene", default=MAIN, type=Path, help="the scene (default: the main scene)")
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="SECTION.KEY=VALUE",
                    help="override a key of the scene (TOML value syntax), as hdi's --set; repeatable")
    ap.add_argument("--name", default="main scene", help="the scene's row in the table")
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = options(argv)
    found, iface = cases(args.results, args.scene, tuple(args.sets), args.name)
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
        scene = found[0].model.scene.name
        figure(ds, args.figure, scene if args.name == "main scene" else f"{args.name}: {scene}, {len(args.sets)} --set")


if __name__ == "__main__":
    main()
