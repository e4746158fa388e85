"""Stage ``sensitivity``: which [recon] parameters the headline outputs depend on.

``hdi sensitivity CONFIG`` samples the parameters of ``[sensitivity] parameters`` (scene keys with
bounds, uniform within them) and evaluates every sample as a sweep over the protrusion grid
(``[sensitivity] protrusion_nm``, default the ``[sweep]`` grid) on the dask fan-out, through the
evaluation core of ``hdi identify`` (:mod:`pipeline.analyses.study`: same candidates, same store, resumable).
The headline outputs (:data:`pipeline.analyses.study.HEADLINES`) are the touchdown protrusion, the flying FHM
at 4-7 nm, the BV after touchdown, and the interference, contact force and mean pressure at 11 nm.

Methods (:mod:`pipeline.analyses.screening`, which holds the sampling and the indices; this stage
reads the scene, evaluates the samples and writes the outputs): Morris elementary effects with ``mu*``
and its bootstrap confidence interval, and the Sobol first-order and total indices (SALib [HU17]_).

Before anything is built, the box of the parameters is checked against the model's own rules at its
bounds and corners (:func:`pipeline.analyses.feasibility.check_study`, the stage's ``check``): a box the
model cannot evaluate everywhere is refused in one line naming the key, the bound and the limit. An
evaluation that still fails is logged (``N of M evaluations failed; first: ...``) and flagged in the
dataset; the indices use the samples their method allows (:mod:`pipeline.analyses.screening`), and the
log, the dataset and the figure say which, and why an index is undefined.

Writes ``sensitivity.nc`` (dimensions ``output`` and ``parameter``: ``mu_star(output, parameter)``,
``mu_star_conf``, ``sigma``, ``mu``, ``S1``, ``S1_conf``, ``ST``, ``ST_conf``; per method the samples
``<method>_values(<method>_sample, parameter)``, their outputs ``<method>_outputs(<method>_sample,
output)``, the failed evaluations ``<method>_failed`` and per output the samples used and a note;
docs/datasets.md) and ``figures/sensitivity.png``.

References
----------
.. [HU17] J. Herman, W. Usher, "SALib: an open-source Python library for sensitivity analysis",
   J. Open Source Softw. 2(9) (2017) 97.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import xarray as xr

from ..analyses.feasibility import box_check
from ..fanout import local_cluster
from ..runner import Inputs, Stage
from ..analyses.study import TARGET_FIELDS
from ..analyses.screening import dataset, failures_text, figure, headline_outputs, morris, sobol
from ..evaluations import Evaluator, evaluate_batch, setup, upstream
from ..model.scene_inputs import STUDY_FIELDS
from ..config.grid import protrusion_grid, range_grid

log = logging.getLogger(__name__)


def grid(scene: Any) -> np.ndarray:
    """Protrusions [nm] of each evaluation: ``[sensitivity] protrusion_nm``, else the ``[sweep]`` grid."""
    g = scene["sensitivity"]["protrusion_nm"]
    return protrusion_grid(scene) if g is None else range_grid(g)


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """``sensitivity.nc`` (module docstring); draws ``figures/sensitivity.png`` under ``inputs.staging``.

    Options (``inputs.options``): ``scheduler``, ``workers``, ``force`` (forget the evaluation store),
    ``task`` (the batch function, for tests).
    """
    opts = inputs.options
    c = scene["sensitivity"]
    prots = [float(x) for x in grid(scene)]
    params, base_inputs, store = setup(scene, inputs, "sensitivity", bool(opts.get("force")))
    results, errors = {}, {}
    workers = opts.get("workers")
    with local_cluster(opts.get("scheduler"), workers) as address:
        ev = Evaluator(scene, params, prots, base_inputs, store, c["batch_size"], address, workers,
                       task=opts.get("task") or evaluate_batch)
        for method in c["methods"]:
            def outputs(X: np.ndarray, method: str = method) -> dict[str, np.ndarray]:
                records = ev(X)
                errors[method] = [r.get("error") for r in records]
                return headline_outputs(records, scene)

            results[method] = (morris if method == "morris" else sobol)(outputs, params, c)
            failed = failures_text(errors[method])
            if failed:
                log.warning("sensitivity: %s: %s (sensitivity.evals.jsonl holds each error)", method, failed)
            for out, ind in results[method][2].items():
                if ind.note:
                    (log.info if ind.defined else log.warning)("sensitivity: %s indices of %s: %s", method, out, ind.note)
    ds = dataset(params, results, errors, c["confidence_level"])
    ds.attrs["protrusions_per_evaluation"] = len(prots)
    inputs.record(evaluations_computed=ev.evaluated, batch_seconds=round(ev.batch_seconds, 3),
                  kernel_seconds=round(ev.kernel_seconds, 3))
    figure(ds, scene.name, inputs.staging / "figures" / "sensitivity.png")
    log.info("sensitivity: %s, %d sweeps of %d protrusions computed in %.1f s of fan-out",
             " + ".join(c["methods"]), ev.evaluated, len(prots), ev.batch_seconds)
    return ds


STAGE = Stage(
    "sensitivity", compute, simulates=True, outputs=("sensitivity.nc", "figures/sensitivity.png"),
    # (the [sweep] grid is the default protrusion grid of the evaluations)
    # (and the targets' definitions in [identify], which define the headline outputs)
    reads=(*STUDY_FIELDS, "sweep.*", "sensitivity.*", *TARGET_FIELDS), unkeyed=("sensitivity.batch_size",),
    upstream=upstream, check=box_check("sensitivity"), order=85, keeps=lambda scene: ("sensitivity.evals.jsonl",),
    doc="Morris and Sobol indices of the headline outputs over the [sensitivity] parameters, sensitivity.nc")
