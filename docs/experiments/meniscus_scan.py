"""Does a meniscus formation time give the paper's bouncing band with a heavy 11-nm contact?

The bulge scene (configs/paper-2009-bulge.toml: p_pad 3 MPa, static start states) with
``lubricant.meniscus_time_us`` = tau_m, scanned over tau_m, the protrusion and DMW seeds
(docs/model.md, section "Meniscus formation", where the table this prints is kept).

Per run, over the steady window ``[transient, duration]``: BV = peak-to-peak of the separation at the
output samples over FH0 [%]; "sustained" when the BV of each quarter of the window exceeds 20 %; the
contact fraction; at the deepest protrusion the mean interference and contact force. Per tau_m and
protrusion over the seeds: the median BV, how many seeds are sustained, how many touched.

Protocols: ``independent`` starts each protrusion from the scene's start state (``solver.start =
"static"``: the static flying equilibrium, past the adhesion fold the contact branch, with the
meniscus state at its equilibrium, i.e. a fully formed meniscus); ``stepping`` runs the protrusions
upward in order, each from the end state of the previous one (meniscus state included), as the heater
is stepped in the experiment (the DMW record restarts at every step).

Usage (from the project root; small by default, it shares the machine)::

    .venv/bin/python docs/experiments/meniscus_scan.py [--taus 0,1,3,10,30,100,300] \
        [--protrusions 9.6:11.2:0.2] [--seeds 20090601,777,1,2] [--duration-ms 2] [--k 0.978] \
        [--protocol independent|stepping]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from pipeline.config.scene import load_scene
from pipeline.model import assembly, outcomes, running
from pipeline.stages.simulate import model_inputs
from pipeline.units import NM

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "paper-2009-bulge.toml"


def quarters_bv(run: running.Run) -> tuple[float, list[float], float, float, float]:
    """BV over the steady window [%], BV of its four quarters [%], contact fraction, mean interference
    [nm] and mean contact force [mN] of a run."""
    m = run.model
    h = outcomes.histories(run)
    win = run.time >= m.transient - 1e-15
    d = h["separation"][win]
    fh0 = m.p.FH0
    parts = np.array_split(d, 4)
    inc = h["in_contact"][win]
    interference = float(np.mean(m.k_sigma - d[inc])) / NM if inc.any() else 0.0
    force = float(np.mean(h["contact_force"][win])) * 1e3
    return (float(np.ptp(d) / fh0 * 100), [float(np.ptp(q) / fh0 * 100) for q in parts], float(np.mean(inc)),
            interference, force)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--taus", default="0,1,3,10,30,100,300")
    ap.add_argument("--protrusions", default="9.6:11.2:0.2")
    ap.add_argument("--seeds", default="20090601,777,1,2")
    ap.add_argument("--duration-ms", type=float, default=2.0)
    ap.add_argument("--k", type=float, default=0.978)
    ap.add_argument("--protocol", default="independent", choices=("independent", "stepping"))
    a = ap.parse_args()
    taus = [float(x) for x in a.taus.split(",")]
    lo, hi, st = (float(x) for x in a.protrusions.split(":"))
    prots = np.round(np.arange(lo, hi + st / 2, st), 3)
    seeds = [int(x) for x in a.seeds.split(",")]
    rows: dict[tuple[float, float], list[tuple]] = {}
    t0 = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            base = [f"contact.k={a.k}", f"dmw.seed={seed}", f"solver.duration_ms={a.duration_ms}",
                    f"dmw.duration_ms={a.duration_ms + 0.2}"]
            folder = Path(tmp) / str(seed)
            interface, rec = model_inputs(load_scene(CONFIG, base), folder)
            for tau in taus:
                scene = load_scene(CONFIG, base + [f"lubricant.meniscus_time_us={tau}"])
                model = assembly.build_model(scene, interface, rec, a.k)
                y0 = None
                for prot in prots:
                    run = running.run_model(model, prot * NM, y0=y0)
                    if a.protocol == "stepping":
                        y0 = run.state[-1]
                    res = quarters_bv(run)
                    rows.setdefault((tau, prot), []).append(res)
                    print(f"seed {seed} tau {tau:g} us {prot:.1f} nm: BV {res[0]:.1f} % quarters "
                          f"{' '.join(f'{q:.1f}' for q in res[1])} contact {res[2]:.2f} "
                          f"interference {res[3]:.2f} nm force {res[4]:.3f} mN", flush=True)
    print(f"\n{a.protocol}, {len(seeds)} seeds ({', '.join(map(str, seeds))}), {a.duration_ms:g} ms, k = {a.k}, "
          f"{time.time() - t0:.0f} s\n")
    print("| tau_m [us] | " + " | ".join(f"{p:.1f}" for p in prots) + " |")
    print("|---|" + "---|" * len(prots))
    for tau in taus:
        cells = []
        for prot in prots:
            r = rows[(tau, prot)]
            bv = np.median([x[0] for x in r])
            sus = sum(min(x[1]) > 20 for x in r)
            touched = sum(x[2] > 0 for x in r)
            cells.append(f"{bv:.1f} ({sus}/{touched})")
        print(f"| {tau:g} | " + " | ".join(cells) + " |")
    last = prots[-1]
    print(f"\nat {last:.1f} nm (median over seeds): " + "; ".join(
        f"tau {tau:g}: BV {np.median([x[0] for x in rows[(tau, last)]]):.2f} %, interference "
        f"{np.median([x[3] for x in rows[(tau, last)]]):.2f} nm, force {np.median([x[4] for x in rows[(tau, last)]]):.3f} mN"
        for tau in taus))


if __name__ == "__main__":
    main()
