"""Switched against continuous friction on the shipped scenes (docs/model.md, section
"Switched and continuous friction", where the table this prints is kept).

For each scene and each ``contact.friction_switching`` ("criterion", the default, and "continuous"), one
:func:`pipeline.simulate` of the band's protrusions on the scene's own DMW record at a fixed k, and per
protrusion: the contact switches per ms of the steady window, the FHM/BV, the contact fraction and the
mean friction force. Printed: a markdown table, one row per scene, switching and protrusion.

Usage (from the project root; about a minute per scene after the kernel is compiled)::

    .venv/bin/python docs/experiments/friction_switching.py [--k 0.978] [--protrusions 9.8:11.0:0.2] \
        [--lab]

``--lab`` adds the lab's sliding-mode case: the two-population scene with the gimbal friction arm and
50 MPa of lubricant shear.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import pipeline as hdi  # noqa: E402
from pipeline.physics.friction import FRICTION_SWITCHING  # noqa: E402

SCENES = {
    "identified": ("configs/paper-2009-identified.toml", []),
    "two-population": ("configs/paper-2009-two-population-identified.toml", []),
}
LAB = {"two-population, gimbal arm, 50 MPa": ("configs/paper-2009-two-population-identified.toml",
                                              ['slider.friction_arm="gimbal"', "lubricant.shear_stress_mpa=50"])}


def rows(config: str, overrides: list[str], k: float, protrusions: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """Per switching: the steady-window outputs at the protrusions [nm] (dataset units)."""
    out = {}
    for how in FRICTION_SWITCHING:
        scene = hdi.load_scene(ROOT / config, [f"contact.k={k}", *overrides, f"contact.friction_switching={how}"])
        ds = hdi.simulate(hdi.build_model(scene), protrusions)
        out[how] = {name: ds[name].values for name in ("contact_switches_per_ms", "fhm_bv", "contact_fraction",
                                                      "friction_force")}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--k", type=float, default=0.978)
    ap.add_argument("--protrusions", default="9.8:11.0:0.2")
    ap.add_argument("--lab", action="store_true")
    a = ap.parse_args()
    lo, hi, step = (float(v) for v in a.protrusions.split(":"))
    prot = np.round(np.arange(lo, hi + step / 2, step), 6)
    scenes = {**SCENES, **(LAB if a.lab else {})}
    print("| scene | switching | protrusion [nm] | switches per ms | BV [%] | contact fraction | friction [mN] |")
    print("|---|---|---|---|---|---|---|")
    for name, (config, overrides) in scenes.items():
        for how, r in rows(config, overrides, a.k, prot).items():
            for i, x in enumerate(prot):
                print(f"| {name} | {how} | {x:.1f} | {r['contact_switches_per_ms'][i]:.0f} | {r['fhm_bv'][i]:.2f} | "
                      f"{r['contact_fraction'][i]:.2f} | {r['friction_force'][i]:.3f} |")


if __name__ == "__main__":
    main()
