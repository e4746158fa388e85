"""A scene, one protrusion's history, a small sweep and a figure, from Python.

    python docs/examples/quickstart.py OUT        (or HDI_EXAMPLES_OUT=OUT python docs/examples/quickstart.py)

Writes only into the folder OUT: the results folder of the sweep (``OUT/sweep.nc`` and the datasets it
reads) and ``OUT/quickstart.png``. A tiny scene keeps it to seconds: 0.6-ms runs, three protrusions.
"""

import json
import os
import sys
from pathlib import Path

import pipeline as hdi
from pipeline.analyses import plots

#: The paper scene, by the name it is shipped under (works outside the clone: `load_scene` finds it in
#: the installed package)
PAPER = "paper-2009"
#: The paper scene, shortened: 0.6-ms runs (0.2 ms of start-up discarded), three protrusions [nm], a
#: fixed contact criterion k (no calibration).
TINY = ["solver.duration_ms=0.6", "solver.transient_ms=0.2", "contact.k=0.5",
        "sweep.protrusion_nm={start=9.5, stop=10.5, step=0.5}", "sweep.batch_size=3"]


def main(out: Path) -> dict:
    scene = hdi.load_scene(PAPER, TINY)
    # one protrusion in time: the model the simulate and sweep stages run, its inputs made in `out`
    model = hdi.build_model(scene, out)
    one = hdi.simulate(model, [10.0], histories=[10.0])
    history = hdi.histories_of(one).sel(protrusion=10.0)      # clearance [nm], forces [mN] ... on time [s]
    # a small sweep, as `hdi sweep CONFIG --set ... --out OUT` makes it (kept in `out`, not recomputed)
    hdi.run_stage("sweep", scene, out, scheduler="synchronous")
    sweep = hdi.open_dataset(out, "sweep").isel(roughness=0, damping=0)
    # the figure: two panels on axes of our own
    from matplotlib.figure import Figure
    fig = Figure(figsize=(8, 7), layout="constrained")
    top, bottom = fig.subplots(2, 1)
    plots.plot_clearance(history, 10.0, int(one["regime"][0]), transient_ms=0.2, ax=top)
    top.set_xlabel("time [ms]")
    plots.plot_fhm(sweep, ax=bottom)
    fig.savefig(out / "quickstart.png", dpi=100)
    return {"fhm_bv_10nm": float(one["fhm_bv"][0]), "history_samples": int(history.sizes["elapsed_time"]),
            "protrusions": sweep["protrusion"].values.tolist(), "sweep_fhm_bv": sweep["fhm_bv"].values.tolist()}


if __name__ == "__main__":
    folder = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("HDI_EXAMPLES_OUT")
    if not folder:
        sys.exit("usage: python docs/examples/quickstart.py OUT (or set HDI_EXAMPLES_OUT): the folder to write into")
    print(json.dumps(main(Path(folder))))
