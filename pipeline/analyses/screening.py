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

A sample whose output does not exist (no touchdown on the grid, no contact at 11 nm) or whose
evaluation failed leaves that output undefined for the sample, and the indices use the samples the
method allows without it:

* **Morris**: the elementary effects of the trajectories whose every point is defined (a trajectory
  with an undefined point has no complete set of effects); ``used`` of the
  ``morris_trajectories``; undefined (NaN) with fewer than :data:`MIN_WHOLE` whole trajectories.
* **Sobol**: the Saltelli design comes in blocks of ``parameters + 2`` rows per base sample (A, the
  ``AB_i`` rows and B: SALib's order), and the estimators are means over the base samples, so the
  blocks with an undefined row are left out and the indices computed over the whole blocks
  (``used`` of ``sobol_samples``). Where the undefined samples cluster in a part of the box the
  kept samples are not uniform over it, and the indices are those of the defined part, approximate;
  the note says so. Undefined (NaN) with fewer than :data:`MIN_WHOLE` whole blocks, or when the output
  does not vary over them (zero variance).

Each output gets a note (:class:`Indices`) that says which samples the indices use and, where they are
undefined, why; the stage logs the notes and writes them to ``sensitivity.nc``, the figure shows them.

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

import textwrap
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import xarray as xr

from . import plots
from .free_parameters import Parameter
from .study import HEADLINES, headline
from ..io import var

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


#: Fewest whole Morris trajectories or Sobol blocks an index is computed from.
MIN_WHOLE = 2


@dataclass
class Indices:
    """The indices of one output by one method.

    Attributes
    ----------
    values : index name -> one value per parameter (NaN where undefined)
    used, total : whole trajectories (Morris) or blocks (Sobol) used, of those sampled
    undefined : samples where the output is undefined
    note : which samples the indices use, and why they are undefined where they are ("" when every
        sample is used)
    """

    values: dict[str, np.ndarray]
    used: int
    total: int
    undefined: int
    note: str = ""

    @property
    def defined(self) -> bool:
        return bool(np.any(np.isfinite(next(iter(self.values.values())))))


def _undefined_text(y: np.ndarray) -> str:
    n = int(np.sum(~np.isfinite(y)))
    return f"{n} of {y.size} samples undefined (no value or a failed evaluation)"


def morris(outputs: Outputs, params: Sequence[Parameter], c: Mapping[str, Any]) -> tuple[np.ndarray, dict, dict[str, Indices]]:
    """Morris samples, outputs and :class:`Indices` per output (``mu``, ``mu_star``, ``sigma``,
    ``mu_star_conf``) over the whole trajectories.

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
    names = ("mu", "mu_star", "sigma", "mu_star_conf")
    for name, y in Y.items():
        # a trajectory with an undefined point has no complete elementary effects: leave it out
        whole = np.all(np.isfinite(y.reshape(-1, step)), axis=1)
        used, total, undefined = int(whole.sum()), whole.size, int(np.sum(~np.isfinite(y)))
        if used < MIN_WHOLE:
            nan = {k: np.full(len(params), np.nan) for k in names}
            out[name] = Indices(nan, used, total, undefined,
                                f"undefined: {used} of {total} trajectories whole, {MIN_WHOLE} needed; "
                                + _undefined_text(y))
            continue
        rows = np.repeat(whole, step)
        si = analyze.analyze(prob, X[rows], y[rows], num_resamples=c["bootstrap"], conf_level=c["confidence_level"],
                             num_levels=c["morris_levels"], seed=c["seed"])
        note = "" if used == total else f"over {used} of {total} trajectories (the whole ones); " + _undefined_text(y)
        out[name] = Indices({k: np.asarray(si[k], float) for k in names}, used, total, undefined, note)
    return X, Y, out


def sobol(outputs: Outputs, params: Sequence[Parameter], c: Mapping[str, Any]) -> tuple[np.ndarray, dict, dict[str, Indices]]:
    """Sobol samples, outputs and :class:`Indices` per output (``S1``, ``S1_conf``, ``ST``, ``ST_conf``) over
    the whole Saltelli blocks (module docstring).

    ``outputs`` as for :func:`morris`; ``c``: ``sobol_samples``, ``seed``, ``bootstrap``, ``confidence_level``.
    """
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample
    prob = problem(params)
    X = sample.sample(prob, c["sobol_samples"], calc_second_order=False, seed=c["seed"])
    Y = outputs(X)
    out = {}
    step = len(params) + 2  # (A, AB_1 .. AB_D, B: one base sample's rows, without second-order indices)
    names = ("S1", "S1_conf", "ST", "ST_conf")
    nan = {k: np.full(len(params), np.nan) for k in names}
    for name, y in Y.items():
        whole = np.all(np.isfinite(y.reshape(-1, step)), axis=1)
        used, total, undefined = int(whole.sum()), whole.size, int(np.sum(~np.isfinite(y)))
        kept = y[np.repeat(whole, step)]
        if used < MIN_WHOLE:
            out[name] = Indices(nan, used, total, undefined,
                                f"undefined: {used} of {total} Saltelli blocks whole, {MIN_WHOLE} needed; "
                                + _undefined_text(y))
            continue
        if np.ptp(kept) == 0:
            out[name] = Indices(nan, used, total, undefined,
                                f"undefined: the output does not vary (every used sample {kept[0]:g}: zero variance)")
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            si = analyze.analyze(prob, kept, calc_second_order=False, num_resamples=c["bootstrap"],
                                 conf_level=c["confidence_level"], seed=c["seed"])
        note = "" if used == total else (
            f"over {used} of {total} Saltelli blocks (those without an undefined row; approximate where the "
            "undefined samples cluster in part of the box); " + _undefined_text(y))
        out[name] = Indices({k: np.asarray(si[k], float) for k in names}, used, total, undefined, note)
    return X, Y, out


# ------------------------------------------------------------------------------------------ dataset
#: The indices of each method: name -> (method, long name (a plot label), description, units: None for the
#: output's own).
INDEX_META = {
    "mu_star": ("morris", "Morris mu*", "Morris mu*: mean absolute elementary effect, scaled to the parameter's "
                "whole range", None),
    "mu_star_conf": ("morris", "mu* confidence half-width", "half-width of the bootstrap confidence interval of mu*",
                     None),
    "sigma": ("morris", "Morris sigma", "Morris sigma: standard deviation of the elementary effects", None),
    "mu": ("morris", "Morris mu", "Morris mu: mean elementary effect", None),
    "S1": ("sobol", "first-order Sobol index", "first-order Sobol index", "1"),
    "S1_conf": ("sobol", "S1 confidence half-width", "half-width of the bootstrap confidence interval of S1", "1"),
    "ST": ("sobol", "total Sobol index", "total Sobol index", "1"),
    "ST_conf": ("sobol", "ST confidence half-width", "half-width of the bootstrap confidence interval of ST", "1"),
}
#: What a method's ``used``/``total`` count.
UNITS_OF_USE = {"morris": "trajectories", "sobol": "Saltelli blocks (base samples)"}


def failures_text(errors: Sequence[str | None]) -> str:
    """``"N of M evaluations failed; first: ..."`` ("" when none failed)."""
    failed = [e for e in errors if e]
    return f"{len(failed)} of {len(errors)} evaluations failed; first: {failed[0]}" if failed else ""


def dataset(params: Sequence[Parameter], results: Mapping[str, tuple], errors: Mapping[str, Sequence[str | None]],
            level: float) -> xr.Dataset:
    """``sensitivity.nc``: the indices over ``(output, parameter)``, the samples and their outputs.

    ``results``: method -> ``(X, Y, {output: Indices})`` of :func:`morris`/:func:`sobol`; ``errors``:
    method -> the error of each sample's evaluation (``None``: it ran); ``level``: the confidence level.
    Outputs differ in unit: the Morris indices and the outputs name the variable holding each output's
    unit (``unit_variable = "output_units"``), the samples each parameter's (``parameter_units``).
    """
    outs = list(HEADLINES)
    P, O = ("parameter",), ("output",)
    coords: dict[str, Any] = {
        "parameter": var(np.array([p.name for p in params], dtype=object), P, "", "free parameter (scene key)"),
        "output": var(np.array(outs, dtype=object), O, "", "headline output"),
    }
    data: dict[str, Any] = {
        "parameter_units": var(np.array([p.units for p in params], dtype=object), P, "", "unit of the parameter"),
        "parameter_low": var(np.array([p.low for p in params]), P, "", "lower bound of the parameter",
                             unit_variable="parameter_units"),
        "parameter_high": var(np.array([p.high for p in params]), P, "", "upper bound of the parameter",
                              unit_variable="parameter_units"),
        "output_units": var(np.array([HEADLINES[o][0] for o in outs], dtype=object), O, "", "unit of the output"),
        "output_long_name": var(np.array([HEADLINES[o][1] for o in outs], dtype=object), O, "",
                                "what the output is"),
    }
    for method, (X, Y, idx) in results.items():
        run_dim = f"{method}_sample"
        S = (run_dim,)
        coords[run_dim] = var(np.arange(len(X)), S, "1", f"{method} sample index")
        data[f"{method}_values"] = var(np.asarray(X, float), S + P, "", f"{method} parameter values",
                                       description=f"{method} samples: parameter values",
                                       unit_variable="parameter_units")
        data[f"{method}_outputs"] = var(np.stack([np.asarray(Y[o], float) for o in outs], axis=1), S + O, "",
                                        f"{method} outputs",
                                        description=f"{method} samples: headline outputs (NaN: undefined)",
                                        unit_variable="output_units")
        errs = list(errors.get(method, [None] * len(X)))
        failed = [e for e in errs if e]
        data[f"{method}_failed"] = var(np.array([1 if e else 0 for e in errs], np.int8), S, "1",
                                       f"{method} sample failed",
                                       description=f"the evaluation of the {method} sample failed (1) or ran (0)",
                                       flag_values=np.array([0, 1], np.int8), flag_meanings="ran failed",
                                       failed_evaluations=len(failed), first_failure=failed[0] if failed else "")
        data[f"{method}_used"] = var(np.array([idx[o].used for o in outs], np.int32), O, "1",
                                     f"used by the {method} indices",
                                     description=f"whole {UNITS_OF_USE[method]} the {method} indices use",
                                     out_of=int(idx[outs[0]].total))
        data[f"{method}_undefined_samples"] = var(np.array([idx[o].undefined for o in outs], np.int32), O, "1",
                                                  f"{method} undefined samples",
                                                  description=f"{method} samples where the output is undefined")
        data[f"{method}_note"] = var(np.array([idx[o].note for o in outs], dtype=object), O, "",
                                     f"{method} note",
                                     description=f"which samples the {method} indices use; why undefined where they "
                                                 "are")
        for key, (m, label, text, u) in INDEX_META.items():
            if m != method:
                continue
            values = np.stack([idx[o].values[key] for o in outs])
            extra = {"unit_variable": "output_units"} if u is None else {}
            data[key] = var(values, O + P, u or "", label, description=f"{text} of the output",
                            confidence_level=level, **extra)
    ds = xr.Dataset(data, coords=coords)
    total = sum(len(errors.get(m, [])) for m in results)
    n_failed = sum(1 for m in results for e in errors.get(m, []) if e)
    ds.attrs.update({"methods": " ".join(results), "outputs": " ".join(outs), "failed_evaluations": n_failed,
                     "evaluations": total,
                     "sampling": "uniform within [low, high] of each parameter (SALib)",
                     "method_references": "Morris 1991; Campolongo, Cariboni & Saltelli 2007; Saltelli 2002, 2010; "
                                   "SALib (Herman & Usher 2017)"})
    return ds


def figure(ds: xr.Dataset, scene: str, path: Path) -> Path:
    """Morris mu* (error bars: its confidence interval) and Sobol S1/ST per output and parameter; a panel
    whose indices are undefined, or use only part of the samples, says so (``<method>_note``)."""
    outs = [str(o) for o in ds["output"].values]
    methods = ds.attrs["methods"].split()
    names = [str(p) for p in ds["parameter"].values]
    fig, axes = plots.new_figure(len(methods), len(outs), size=(3.0 * len(outs), 3.0 * len(methods)), squeeze=False)
    y = np.arange(len(names))
    labels = [n.split(".", 1)[1] for n in names]
    for i, method in enumerate(methods):
        for j, out in enumerate(outs):
            ax = axes[i, j]
            at = ds.sel(output=out)
            if method == "morris":
                ax.barh(y, at["mu_star"].values, xerr=at["mu_star_conf"].values, color=plots.LINE_COLOURS[0])
                ax.set_xlabel(plots.axis_label("mu*", str(at["output_units"].values)), fontsize=8)
                main = at["mu_star"].values
            else:
                ax.barh(y - 0.2, at["S1"].values, 0.4, xerr=at["S1_conf"].values, color=plots.LINE_COLOURS[2], label="S1")
                ax.barh(y + 0.2, at["ST"].values, 0.4, xerr=at["ST_conf"].values, color=plots.LINE_COLOURS[1], label="ST")
                ax.set_xlabel(plots.axis_label("Sobol index", "1"), fontsize=8)
                if j == 0:
                    ax.legend(fontsize=7, loc="lower right")
                main = at["ST"].values
            note = str(at[f"{method}_note"].values)
            if note:
                # (the reason, shortened to the panel: the whole note is in sensitivity.nc and the log)
                text = note.split(" (")[0].split("; ")[0] if np.any(np.isfinite(main)) else note
                plots.note(ax, textwrap.fill(text, 34), loc="upper right", fontsize=6)
            ax.set_yticks(y, labels if j == 0 else [], fontsize=7)
            ax.set_title(f"{str(at['output_long_name'].values)[:40]}\n[{method}]", fontsize=7)
    fig.suptitle(plots.title("Sensitivity of the headline outputs", scene), fontsize=9)
    return plots.save(fig, path)
