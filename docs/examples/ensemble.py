"""A small sweep over a few DMW realisations: touchdown probability and FHM/BV spread, from Python.

    python docs/examples/ensemble.py OUT        (or HDI_EXAMPLES_OUT=OUT python docs/examples/ensemble.py)

``sweep.realisations = 3`` runs every protrusion on the scene's DMW record and on two more records of
the same spectrum (other seeds); ``sweep.nc`` then holds the scalars on a ``realisation`` dimension and
their ensemble statistics (``fhm_bv_mean``, ``fhm_bv_std``, ``touchdown_probability``). Writes only into
the folder OUT (the results folder and ``OUT/ensemble.png``).
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
#: The paper scene, shortened (0.6-ms runs, three protrusions [nm], fixed k), over 3 DMW realisations.
TINY = ["solver.duration_ms=0.6", "solver.transient_ms=0.2", "contact.k=0.5",
        "sweep.protrusion_nm={start=8.0, stop=9.0, step=0.5}", "sweep.batch_size=3", "sweep.realisations=3"]


def main(out: Path) -> dict:
    scene = hdi.load_scene(PAPER, TINY)
    hdi.run_stage("sweep", scene, out, scheduler="synchronous")
    sweep = hdi.open_dataset(out, "sweep")
    from matplotlib.figure import Figure
    fig = Figure(figsize=(8, 6), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    plots.plot_touchdown_probability(sweep, ax=top)
    plots.plot_ensemble_fhm(sweep, ax=bottom)
    fig.savefig(out / "ensemble.png", dpi=100)
    first = sweep.isel(roughness=0, damping=0)
    return {"realisations": int(sweep.sizes["realisation"]), "protrusions": first["protrusion"].values.tolist(),
            "fhm_bv": first["fhm_bv"].values.tolist(), "fhm_bv_mean": first["fhm_bv_mean"].values.tolist(),
            "touchdown_probability": first["touchdown_probability"].values.tolist()}


if __name__ == "__main__":
    folder = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("HDI_EXAMPLES_OUT")
    if not folder:
        sys.exit("usage: python docs/examples/ensemble.py OUT (or set HDI_EXAMPLES_OUT): the folder to write into")
    print(json.dumps(main(Path(folder))))
