"""Screening and variance-based sensitivity of outputs to parameters (the algorithms of ``hdi sensitivity``).

Each method takes an evaluation callable (samples to outputs by name) and returns the samples, the
outputs and the indices; the stage (:mod:`pipeline.stages.sensitivity`) reads the scene, evaluates the
samples on the fan-out through the evaluation store and writes ``sensitivity.nc``.

Methods (SALib [HU17]_):

* **Morris** elementary effects [Mor91]_ with the improved measure ``mu*`` [CCS07]_:
  ``morris_trajectories`` trajectories of ``parameters + 1`` points on a ``morris_levels`` grid.
  ``mu*`` [output units] is the mean of ``|Delta y| / Delta`` over the trajectories, with the step
  ``Delta = levels / (2 (levels - 1))`` a fraction of the parameter's range (SALib's scaling): the
  output change extrapolated to the whole range (``y = a x`` gives ``|a|`` times the range);
  ``sigma`` is the spread of the effects (interaction or nonlinearity); ``mu*`` has a bootstrap
  confidence interval.
* **Sobol** first-order ``S1`` and total ``ST`` indices [Sal02]_ [Sal10]_ from the Saltelli
  extension of a Sobol' sequence, ``N (parameters + 2)`` evaluations (``sobol_samples = N``), with
  bootstrap confidence intervals.

A sample whose output does not exist (no touchdown on the grid, no contact at 11 nm, a failed run:
e.g. two frequencies no real air bearing has) leaves that output undefined for the sample. Morris
leaves out the trajectories with an undefined point (``trajectories_used`` on each index); the Sobol
indices of an output with any undefined sample are NaN (the estimator needs every sample);
``undefined_samples`` says how many (a parameter range that removes the contact is itself a
finding). An output that does not vary at all has NaN Sobol indices (zero variance).

References
----------
.. [HU17] J. Herman, W. Usher, "SALib: an open-source Python library for sensitivity analysis",
   J. Open Source Softw. 2(9) (2017) 97.
.. [Mor91] M. D. Morris, "Factorial sampling plans for preliminary computational experiments",
   Technometrics 33(2) (1991) 161-174.
.. [CCS07] F. Campolongo, J. Cariboni, A. Saltelli, "An effective screening design for sensitivity
   analysis of large models", Environ. Model. Softw. 22 (2007) 1509-1518.
.. [Sal02] A. Saltelli, "Making best use of model evaluations to compute sensitivity indices",
   Comput. Phys. Commun. 145 (2002) 280-297.
.. [Sal10] A. Saltelli et al., "Variance based sensitivity analysis of model output. Design and
   estimator for the total sensitivity index", Comput. Phys. Commun. 181 (2010) 259-270.
"""

from __future__ import annotations

import warnings
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from .study import HEADLINES, Parameter, headline

#: An evaluation callable: the outputs of samples (shape ``(samples, parameters)``), one array per name.
Outputs = Callable[[np.ndarray], dict[str, np.ndarray]]


def problem(params: Sequence[Parameter]) -> dict[str, Any]:
    """The SALib problem of the parameters."""
    return {"num_vars": len(params), "names": [p.name for p in params], "bounds": [[p.low, p.high] for p in params]}


def headline_outputs(records: Sequence[dict[str, Any]], scene: Any) -> dict[str, np.ndarray]:
    """The headline outputs (:data:`pipeline.analyses.study.HEADLINES`) of evaluation records, one value per
    record (:func:`pipeline.analyses.study.headline`, the definitions of ``[identify]`` of ``scene``)."""
    heads = [headline(r, scene) for r in records]
    return {name: np.array([h[name] for h in heads], float) for name in HEADLINES}


def morris(outputs: Outputs, params: Sequence[Parameter], c: Mapping[str, Any]) -> tuple[np.ndarray, dict, dict]:
    """Morris samples, outputs and indices per output (``mu``, ``mu_star``, ``sigma``, ``mu_star_conf``;
    ``None`` for an output with fewer than two whole trajectories).

    ``outputs(X)``: the outputs of the samples ``X`` (shape ``(samples, parameters)``) by name; ``c``: the
    ``[sensitivity]`` settings (``morris_trajectories``, ``morris_levels``, ``seed``, ``bootstrap``,
    ``confidence_level``).
    """
    from SALib.analyze import morris as analyze
    from SALib.sample import morris as sample
    prob = problem(params)
    X = sample.sample(prob, N=c["morris_trajectories"], num_levels=c["morris_levels"], seed=c["seed"])
    Y = outputs(X)
    out = {}
    step = len(params) + 1
    for name, y in Y.items():
        # a trajectory with an undefined point has no complete elementary effects: leave it out
        whole = np.all(np.isfinite(y.reshape(-1, step)), axis=1)
        if whole.sum() < 2:
            out[name] = None
            continue
        rows = np.repeat(whole, step)
        si = analyze.analyze(prob, X[rows], y[rows], num_resamples=c["bootstrap"], conf_level=c["confidence_level"],
                             num_levels=c["morris_levels"], seed=c["seed"])
        out[name] = {k: np.asarray(si[k], float) for k in ("mu", "mu_star", "sigma", "mu_star_conf")}
        out[name]["trajectories_used"] = int(whole.sum())
    return X, Y, out


def sobol(outputs: Outputs, params: Sequence[Parameter], c: Mapping[str, Any]) -> tuple[np.ndarray, dict, dict]:
    """Sobol samples, outputs and indices per output (``S1``, ``S1_conf``, ``ST``, ``ST_conf``; ``None`` for
    an output with an undefined sample or no variance).

    ``outputs`` as for :func:`morris`; ``c``: ``sobol_samples``, ``seed``, ``bootstrap``, ``confidence_level``.
    """
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample
    prob = problem(params)
    X = sample.sample(prob, c["sobol_samples"], calc_second_order=False, seed=c["seed"])
    Y = outputs(X)
    out = {}
    for name, y in Y.items():
        if not np.all(np.isfinite(y)) or np.ptp(y) == 0:
            out[name] = None
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            si = analyze.analyze(prob, y, calc_second_order=False, num_resamples=c["bootstrap"],
                                 conf_level=c["confidence_level"], seed=c["seed"])
        out[name] = {k: np.asarray(si[k], float) for k in ("S1", "S1_conf", "ST", "ST_conf")}
    return X, Y, out
