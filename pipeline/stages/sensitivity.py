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

Writes ``sensitivity.nc`` (indices with confidence intervals per output and parameter, the samples
and their outputs) and ``figures/sensitivity.png``.

References
----------
.. [HU17] J. Herman, W. Usher, "SALib: an open-source Python library for sensitivity analysis",
   J. Open Source Softw. 2(9) (2017) 97.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import xarray as xr

from ..analyses import plots
from ..fanout import local_cluster
from ..io import var
from ..runner import Inputs, Stage, build
from ..analyses.screening import headline_outputs, morris, sobol
from ..analyses.study import HEADLINES, Parameter
from ..evaluations import Evaluator, evaluate_batch, setup, upstream
from ..config.grid import protrusion_grid, range_grid

log = logging.getLogger(__name__)


def grid(scene: Any) -> np.ndarray:
    """Protrusions [nm] of each evaluation: ``[sensitivity] protrusion_nm``, else the ``[sweep]`` grid."""
    g = scene["sensitivity"]["protrusion_nm"]
    return protrusion_grid(scene) if g is None else range_grid(g)


_INDEX_META = {
    "mu_star": ("morris", "Morris mu*: mean absolute elementary effect, scaled to the parameter's whole range", None),
    "mu_star_conf": ("morris", "half-width of the bootstrap confidence interval of mu*", None),
    "sigma": ("morris", "Morris sigma: standard deviation of the elementary effects", None),
    "mu": ("morris", "Morris mu: mean elementary effect", None),
    "S1": ("sobol", "first-order Sobol index", "1"),
    "S1_conf": ("sobol", "half-width of the bootstrap confidence interval of S1", "1"),
    "ST": ("sobol", "total Sobol index", "1"),
    "ST_conf": ("sobol", "half-width of the bootstrap confidence interval of ST", "1"),
}


def dataset(params: Sequence[Parameter], results: dict[str, tuple], scene: Any) -> xr.Dataset:
    """``sensitivity.nc``: indices per output (variables ``<index>_<output>`` over ``parameter``) and samples."""
    names = [p.var_name for p in params]
    data: dict[str, Any] = {}
    coords: dict[str, Any] = {"parameter": var(np.array(names, dtype=object), "parameter", "1", "parameter",
                                               scene_keys=" ".join(p.name for p in params))}
    level = scene["sensitivity"]["confidence_level"]
    for method, (X, Y, idx) in results.items():
        run_dim = f"{method}_sample"
        coords[run_dim] = var(np.arange(len(X)), run_dim, "1", f"{method} sample index")
        for j, p in enumerate(params):
            data[f"{method}_{p.var_name}"] = var(X[:, j], run_dim, p.units, f"{method} sample of {p.name}")
        for out, (units, long_name) in HEADLINES.items():
            y = Y[out]
            data[f"{method}_{out}"] = var(y, run_dim, units, f"{long_name} ({method} samples)")
            ind = idx[out]
            for key, (m, text, u) in _INDEX_META.items():
                if m != method:
                    continue
                values = ind[key] if ind is not None else np.full(len(params), np.nan)
                extra = {"trajectories_used": ind["trajectories_used"]} if ind and "trajectories_used" in ind else {}
                data[f"{key}_{out}"] = var(values, "parameter", u or units, f"{text} of the {long_name}",
                                           confidence_level=level, undefined_samples=int(np.sum(~np.isfinite(y))),
                                           **extra)
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({"methods": " ".join(results), "outputs": " ".join(HEADLINES),
                     "sampling": "uniform within [low, high] of each parameter (SALib)",
                     "references": "Morris 1991; Campolongo, Cariboni & Saltelli 2007; Saltelli 2002, 2010; "
                                   "SALib (Herman & Usher 2017)"})
    return ds


def figure(ds: xr.Dataset, params: Sequence[Parameter], scene: str, path: Path) -> Path:
    """Morris mu* (error bars: its confidence interval) and Sobol ST per output and parameter."""
    outs = list(HEADLINES)
    methods = ds.attrs["methods"].split()
    fig, axes = plots.new_figure(len(methods), len(outs), size=(3.0 * len(outs), 3.0 * len(methods)), squeeze=False)
    y = np.arange(len(params))
    labels = [p.name.split(".", 1)[1] for p in params]
    for i, method in enumerate(methods):
        for j, out in enumerate(outs):
            ax = axes[i, j]
            if method == "morris":
                v, e = ds[f"mu_star_{out}"].values, ds[f"mu_star_conf_{out}"].values
                ax.barh(y, v, xerr=e, color=plots.LINE_COLOURS[0])
                ax.set_xlabel(plots.axis_label("mu*", ds[f"mu_star_{out}"].attrs["units"]), fontsize=8)
            else:
                ax.barh(y - 0.2, ds[f"S1_{out}"].values, 0.4, xerr=ds[f"S1_conf_{out}"].values,
                        color=plots.LINE_COLOURS[2], label="S1")
                ax.barh(y + 0.2, ds[f"ST_{out}"].values, 0.4, xerr=ds[f"ST_conf_{out}"].values,
                        color=plots.LINE_COLOURS[1], label="ST")
                ax.set_xlabel(plots.axis_label("Sobol index", "1"), fontsize=8)
                if j == 0:
                    ax.legend(fontsize=7)
            if np.all(~np.isfinite(ds[f"{'mu_star' if method == 'morris' else 'ST'}_{out}"].values)):
                plots.note(ax, "undefined\n(see sensitivity.nc)", loc="upper right")
            ax.set_yticks(y, labels if j == 0 else [], fontsize=7)
            ax.set_title(f"{HEADLINES[out][1][:40]}\n[{method}]", fontsize=7)
    fig.suptitle(plots.title("Sensitivity of the headline outputs", scene), fontsize=9)
    return plots.save(fig, path)


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """``sensitivity.nc`` (module docstring); draws ``figures/sensitivity.png`` under ``inputs.staging``.

    Options (``inputs.options``): ``scheduler``, ``workers``, ``force`` (forget the evaluation store),
    ``task`` (the batch function, for tests).
    """
    opts = inputs.options
    c = scene["sensitivity"]
    prots = [float(x) for x in grid(scene)]
    params, base_inputs, store = setup(scene, inputs, "sensitivity", bool(opts.get("force")))
    results = {}
    workers = opts.get("workers")
    with local_cluster(opts.get("scheduler"), workers) as address:
        ev = Evaluator(scene, params, prots, base_inputs, store, c["batch_size"], address, workers,
                       task=opts.get("task") or evaluate_batch)

        def outputs(X: np.ndarray) -> dict[str, np.ndarray]:
            return headline_outputs(ev(X), scene)

        for method in c["methods"]:
            results[method] = (morris if method == "morris" else sobol)(outputs, params, c)
    ds = dataset(params, results, scene)
    ds.attrs["protrusions_per_evaluation"] = len(prots)
    inputs.record(evaluations_computed=ev.evaluated, batch_seconds=round(ev.batch_seconds, 3),
                  kernel_seconds=round(ev.kernel_seconds, 3))
    figure(ds, params, scene.name, inputs.staging / "figures" / "sensitivity.png")
    log.info("sensitivity: %s, %d sweeps of %d protrusions computed in %.1f s of fan-out",
             " + ".join(c["methods"]), ev.evaluated, len(prots), ev.batch_seconds)
    return ds


STAGE = Stage(
    "sensitivity", compute, outputs=("sensitivity.nc", "figures/sensitivity.png"),
    # (the [sweep] grid is the default protrusion grid of the evaluations: not excluded)
    reads=("*",), excludes=("report", "identify", "scene.name", "scene.description", "sensitivity.batch_size"),
    upstream=upstream, order=85, keeps=lambda scene: ("sensitivity.evals.jsonl",),
    doc="Morris and Sobol indices of the headline outputs over the [sensitivity] parameters, sensitivity.nc")


def run(scene: Any, out: Path, scheduler: str | None = None, workers: int | None = None, force: bool = False,
        **options: Any) -> Path:
    """Stage entry point (``hdi sensitivity``): makes ``sensitivity.nc`` current (:func:`pipeline.runner.build`)."""
    return build("sensitivity", scene, out, force=force, scheduler=scheduler, workers=workers,
                 **options)["sensitivity"][0]
