"""What two deviations from the paper do to the main scene (docs/model.md, section
"Deviations", items 18-19, where the tables this prints are kept).

1. The paper checks of ``configs/paper-2009-identified.toml`` (the scene ``make run`` runs) over its
   8-realisation ensemble, for the default and for each option, each from its own ``hdi run``
   (calibration included)::

       hdi run configs/paper-2009-identified.toml --out OUT/default
       hdi run configs/paper-2009-identified.toml --set contact.area_model='"integrated"' --out OUT/integrated
       hdi run configs/paper-2009-identified.toml --set slider.friction_arm='"gimbal"' --out OUT/gimbal

   (run by this script unless ``--no-run``; up to date folders are not recomputed). Each target is judged
   as ``hdi identify`` judges it (:meth:`pipeline.analyses.study.ObjectiveTerm.ensemble_residual`, ``|r| <= 1``:
   within tolerance).
2. At the identified 11-nm state of the default run (the scene's record, steady window): the contact
   force, real area and adhesion of the flat section against those of the same stresses integrated over
   the bulge at the same separations; and what the integration leaves out beyond the table's top.
3. The static TFC gap opening by the friction moment at 11 nm (the static contact equilibrium with
   friction minus the one without), arm ``T/2`` against ``T``.

Usage (from the project root; ~5 min on 2 shared cores with the runs)::

    .venv/bin/python docs/experiments/deviations.py [--out /tmp/deviations] [--no-run]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.analyses import study
from pipeline.config.scene import load_scene
from pipeline.model.forces import separation_at
from pipeline.model.piecewise import ppval
from pipeline.model.state import THETA, Z
from pipeline.model import assembly, kernel_inputs, outcomes, running
from pipeline.physics.geometry import table_truncation
from pipeline.stages.simulate import model_inputs
from pipeline.units import NM

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "paper-2009-identified.toml"
OPTIONS = {"default": [], "integrated": ['contact.area_model="integrated"'],
           "gimbal": ['slider.friction_arm="gimbal"']}
EFFECTS_NO_FRICTION = "scene.effects=['air_bearing','pitch','dmw','adhesion','contact']"


def run_all(out: Path) -> None:
    for name, sets in OPTIONS.items():
        cmd = [str(ROOT / ".venv" / "bin" / "hdi"), "run", str(CONFIG), "--out", str(out / name)]
        for s in sets:
            cmd += ["--set", s]
        subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)


def checks(out: Path) -> None:
    """The table of checks: value over the realisations and residual per option."""
    scene = load_scene(CONFIG)
    tlist = study.targets(scene)
    ens = {name: xr.open_dataset(out / name / "ensemble.nc") for name in OPTIONS}
    print("| check | paper | " + " | ".join(OPTIONS) + " |")
    print("|---|---|" + "---|" * len(OPTIONS))
    met = dict.fromkeys(OPTIONS, 0)
    for t in tlist:
        cells = []
        for name, ds in ens.items():
            r = t.ensemble_residual(ds, float("nan"))
            ok = bool(abs(r) <= 1)
            met[name] += ok
            value = t.ensemble(ds)[0] if t.ensemble else float("nan")
            cells.append(f"{value:.4g} {'(met)' if ok else '(missed)'}")
        print(f"| {t.long_name} [{t.units}] | {t.paper} | " + " | ".join(cells) + " |")
    print("| checks met | | " + " | ".join(f"{met[n]} of {len(tlist)}" for n in OPTIONS) + " |")
    print("| k (source) | | " + " | ".join(f"{ds.attrs['k']:.4g} ({ds.attrs['k_source'].split(':')[0]})"
                                            for ds in ens.values()) + " |")


def model_of(out: Path, sets: list[str], k: float) -> assembly.Model:
    scene = load_scene(CONFIG, [f"contact.k={k}"] + sets)
    interface, record = model_inputs(scene, out)
    bulge = xr.open_dataset(out / "bulge.nc") if (out / "bulge.nc").exists() else None
    return assembly.build_model(scene, interface, record, k, bulge=bulge)


def same_state(out: Path) -> None:
    """Flat section against integrated at the default run's 11-nm separations."""
    k = float(xr.open_dataset(out / "default" / "calibration.nc")["k_calibrated"])
    folder = out / "default"
    flat = model_of(folder, [], k)
    integrated = model_of(folder, OPTIONS["integrated"], k)
    delta = 11 * NM
    run = running.run_model(flat, delta)
    hist = outcomes.histories(run)
    win = (run.time >= flat.transient - 1e-15) & hist["in_contact"]
    d = hist["separation"][win]
    p = run.p
    print(f"11 nm, default run, scene's record: {win.sum()} samples in contact, separation "
          f"{d.mean() / NM:.4f} nm (range {d.min() / NM:.4f} to {d.max() / NM:.4f})")
    tabs = {"flat-section": kernel_inputs.interface_tables(flat, delta, p["A_n"]),
            "integrated": kernel_inputs.interface_tables(integrated, delta, p["A_n"])}
    for name, unit, scale in (("contact", "mN", 1e3), ("area", "um^2", 1e12), ("adhesion", "mN", 1e3),
                              ("friction", "mN", 1e3)):
        v = {m: scale * p["A_n"] * float(np.mean(ppval(getattr(t, name), p.tab_x0, p.tab_h, d)))
             for m, t in tabs.items()}
        print(f"  {name:9s} flat {v['flat-section']:.4g} {unit}, integrated {v['integrated']:.4g} {unit} "
              f"(ratio {v['integrated'] / v['flat-section']:.3f})")
    x = p.tab_x0 + p.tab_h * np.arange(flat.adhesion.shape[0] + 1)
    top = float(ppval(flat.adhesion, p.tab_x0, p.tab_h, x[-1:])[0])
    cut = table_truncation(top, x, delta) * 2 * np.pi * flat.half_length * flat.half_width
    reach = x[-1] - delta
    print(f"  table top {x[-1] / NM:g} nm, adhesion there {top / 1e6:.3g} MPa: rows d <= {reach / NM:g} nm are exact; "
          f"the largest left out (held value beyond the top) {cut.max() * 1e3:.3g} mN at the top row")


def gap_opening(out: Path) -> None:
    """The static TFC gap opening by the friction moment at 11 nm, per arm."""
    folder = out / "default"
    k = float(xr.open_dataset(folder / "calibration.nc")["k_calibrated"])
    delta = 11 * NM
    d = {}
    for name, sets in (("none", [EFFECTS_NO_FRICTION]), ("cg", []), ("gimbal", OPTIONS["gimbal"])):
        m = model_of(folder, sets, k)
        y, note = running.start(m, delta)
        p, _, _ = kernel_inputs.run_parameters(m, delta)
        d[name] = separation_at(p, y[Z], y[THETA], 0.0)
        print(f"  friction {name:6s}: arm {m.p['friction_arm'] * 1e3:.4g} mm, {note}, d = {d[name] / NM:.4f} nm")
    for arm in ("cg", "gimbal"):
        print(f"  opening with arm {arm}: {(d[arm] - d['none']) / NM:.4f} nm")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="/tmp/deviations")
    ap.add_argument("--no-run", action="store_true", help="read the three folders as they are")
    a = ap.parse_args()
    out = Path(a.out)
    if not a.no_run:
        run_all(out)
    checks(out)
    print()
    same_state(out)
    print()
    gap_opening(out)


if __name__ == "__main__":
    sys.exit(main())
