"""The bulge lift versus apex gap from 5 nm down to contact, for each bulge law (docs/model.md, section
"Rough-gap bulge bearing", where the table this prints is kept, and docs/figures/bulge_near_contact.png).

The scene's bulge (footprint semi-axes, disk speed, roughness, lubricant thickness) at the given pad pressures
and protrusions; for each law the lift at apex gaps log-spaced over 0.15-5 nm, solved directly on the scene's
Reynolds grid (no table): the p h = const closed form, the Reynolds law with first-order slip (the shipped
``"reynolds"``), the smooth Reynolds solve with the Boltzmann flow rate, and the rough law ``"rough-reynolds"``
with the scene's settings and two variants (equal roughness on both surfaces: no shear flow; no wetting gap).
Printed: per case the lift at a few gaps, the gap of the largest lift and the lift there over the lift at the
lab's cap gap g_s = 1.65 nm.

Usage (from the project root; ~1 s per law, pad pressure and protrusion on 2 shared cores)::

    .venv/bin/python docs/experiments/bulge_near_contact.py [--config configs/paper-2009-two-population-identified.toml] \
        [--pads 2.1,2.2] [--protrusions 10.0,10.4,10.8] [--figure docs/figures/bulge_near_contact.png]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from pipeline.config.scene import load_scene  # noqa: E402
from pipeline.model import bulge_table as bt  # noqa: E402
from pipeline.model.dmw_record import disk_speed_m_s  # noqa: E402
from pipeline.physics import bulge_bearing as bb, reynolds  # noqa: E402

NM = 1e-9
GS = 1.65  # [nm] the lab's cap gap (docs/model.md, section "Lift cap (hypothesis H8)")
SHOWN = (5.0, 3.0, 2.0, GS, 1.2, 1.0, 0.7, 0.5, 0.3, 0.2)  # [nm] gaps printed


def laws(rough):
    """(label, solve keywords or None for the closed form)."""
    return [("p h = const", None),
            ("reynolds, first-order slip", dict(slip="first-order")),
            ("reynolds, Boltzmann", dict(slip="boltzmann")),
            ("rough-reynolds", dict(slip="boltzmann", roughness=rough)),
            ("rough, equal roughness (no shear flow)", dict(slip="boltzmann",
                                                          roughness=dataclasses.replace(rough, disk_share=0.5))),
            ("rough, no wetting gap", dict(slip="boltzmann", roughness=dataclasses.replace(rough, wet_gap=0.0)))]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--config", default="configs/paper-2009-two-population-identified.toml")
    ap.add_argument("--pads", default="2.1,2.2", help="pad pressures [MPa]")
    ap.add_argument("--protrusions", default="10.0,10.4,10.8", help="protrusions [nm]")
    ap.add_argument("--figure", default="docs/figures/bulge_near_contact.png")
    a = ap.parse_args()
    scene = load_scene(ROOT / a.config, ['air_bearing.bulge="rough-reynolds"'])
    si = scene.si
    rough = bt.scene_roughness(scene)
    sol = scene["solver"]
    grid = reynolds.ReynoldsGrid(cells_per_a=sol["bulge_cells_per_a"], cells_per_b=sol["bulge_cells_per_b"])
    base = dict(a=si.tfc.half_length, b=si.tfc.half_width, speed=disk_speed_m_s(scene["dmw"]), grid=grid,
                viscosity=bt.AIR_VISCOSITY, mean_free_path=bt.AIR_MEAN_FREE_PATH, ambient_pressure=bt.AMBIENT_PRESSURE)
    g = np.unique(np.concatenate([np.geomspace(0.15, 5.0, 40), SHOWN])) * NM
    pads = [float(x) for x in a.pads.split(",")]
    prots = [float(x) for x in a.protrusions.split(",")]
    results = {}
    print(f"sigma {rough.sigma / NM:g} nm, disk share {rough.disk_share:g}, wetting gap {rough.wet_gap / NM:g} nm, "
          f"U {base['speed']:.2f} m/s, a x b {base['a'] * 1e6:g} x {base['b'] * 1e6:g} um")
    print("| p_pad | delta | law | " + " | ".join(f"{x:g}" for x in SHOWN) + " | peak gap | peak / F(1.65) |")
    print("|---" * (len(SHOWN) + 5) + "|")
    for p in pads:
        for d in prots:
            for label, kw in laws(rough):
                if kw is None:
                    F = bb.ph_lift(g, d * NM, p * 1e6, base["a"], base["b"])[0]
                else:
                    F = reynolds.reynolds_solve(g, d * NM, p_pad=p * 1e6, **base, **kw)["lift"]
                results[(p, d, label)] = F
                i = int(np.argmax(F))
                at = [F[np.argmin(np.abs(g / NM - x))] * 1e3 for x in SHOWN]
                f_s = F[np.argmin(np.abs(g / NM - GS))]
                peak = f"{g[i] / NM:.2f}" if i > 0 else "< 0.15"
                print(f"| {p:g} | {d:g} | {label} | " + " | ".join(f"{v:.3f}" for v in at)
                      + f" | {peak} | {F[i] / f_s:.3f} |")
    if a.figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker
        fig, axes = plt.subplots(1, len(pads), figsize=(6.0 * len(pads), 4.6), sharey=True, squeeze=False)
        d = prots[len(prots) // 2]
        for ax, p in zip(axes[0], pads):
            for (label, _), style in zip(laws(rough), ("k--", "C0-", "C1:", "C3-", "C2-.", "C4--")):
                ax.plot(g / NM, results[(p, d, label)] * 1e3, style, label=label, lw=1.6)
            F_ph = results[(p, d, "p h = const")]
            f_cap = np.interp(GS, g / NM, F_ph)
            ax.plot(g / NM, np.where(g / NM < GS, f_cap, F_ph) * 1e3, color="0.6", lw=4, alpha=0.4,
                    label=f"lab cap H8 (p h = const held below {GS} nm)")
            ax.axvline(1.2, color="0.5", lw=0.8, ls=":")
            ax.text(1.22, 0.05, "contact criterion\n(d = k sigma)", transform=ax.get_xaxis_transform(), fontsize=7)
            ax.set_xscale("log")
            ticks = [0.2, 0.3, 0.5, 0.7, 1.0, GS, 3.0, 5.0]
            ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            ax.set_xlabel("apex gap g [nm] (to the mean of surface heights)")
            ax.set_title(f"p_pad {p:g} MPa, protrusion {d:g} nm", fontsize=10)
            ax.grid(alpha=0.3, which="both")
        axes[0][0].set_ylabel("bulge lift [mN]")
        axes[0][0].legend(fontsize=7, loc="upper right")
        fig.suptitle(f"Bulge lift versus apex gap: {scene.name} (sigma {rough.sigma / NM:g} nm)", fontsize=11)
        fig.tight_layout()
        fig.savefig(ROOT / a.figure, dpi=110)
        print(f"wrote {a.figure}")


if __name__ == "__main__":
    main()
