"""The comparison with the paper over DMW realisations: the report's ensemble table (pure formatting).

Reads ``ensemble.nc`` (:mod:`pipeline.stages.ensemble`), in which every paper target is already judged
over the realisations as ``hdi identify`` judges it (``value_<target>``, ``spread_<target>``,
``single_<target>``: :func:`pipeline.analyses.study.ensemble_summary`, the statistics of
:mod:`pipeline.analyses.ensemble_rules`), and writes each value with its spread beside it (10-90 % of the
realisations for the touchdown protrusion and the FHM/BV medians, mean ± 1 standard deviation for the
light-contact state) next to the value of the scene's own record alone. Nothing is computed here.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .markdown import number, table

#: The ``spread`` attribute of a target judged by mean ± 1 standard deviation (the light-contact state;
#: :attr:`pipeline.analyses.study.ObjectiveTerm.spread`); the others give the 10-90 % range.
SPREAD_STD = "mean +- 1 standard deviation"


def _u(units: str) -> str:
    return "" if units in ("1", "") else f" {units}"


def value_cell(value: float, low: float, high: float, units: str, spread: str) -> str:
    """``value unit`` with its spread beside it: ``(10-90 %: low-high)`` or ``± std``."""
    if not np.isfinite(value):
        return "none"
    u = _u(units)
    if spread == SPREAD_STD:
        sd = 0.5 * (high - low)
        return f"{number(value)} ± {number(sd, 2)}{u}" if np.isfinite(sd) else f"{number(value)}{u} (one value)"
    if not (np.isfinite(low) and np.isfinite(high)):
        return f"{number(value)}{u} (spread: –)"
    return f"{number(value)}{u} (10-90 %: {number(low)}-{number(high)})"


def target_names(ens: xr.Dataset) -> list[str]:
    """The targets judged in ``ensemble.nc``, in the order of the targets."""
    return [str(v)[len("value_"):] for v in ens.data_vars if str(v).startswith("value_")]


def target_cell(ens: xr.Dataset, name: str) -> str:
    """The value of target ``name`` over the realisations with its spread (:func:`value_cell`)."""
    v = ens[f"value_{name}"]
    lo, hi = (float(x) for x in ens[f"spread_{name}"].values)
    return value_cell(float(v), lo, hi, str(v.attrs.get("units", "")), str(v.attrs.get("spread", "")))


def _at(ens: xr.Dataset, name: str, at: float) -> float:
    x = ens["protrusion"].values
    j = np.flatnonzero(np.abs(x - at) < 1e-6)
    return float(ens[name].values[j[0]]) if name in ens and j.size else float("nan")


def main_table_column(labels: list[str], ens: xr.Dataset, nominal_area_at: float) -> list[str]:
    """The cells of the comparison table's column over the realisations, one per row label: the
    touchdown, the flying FHM and A_n at ``nominal_area_at`` [nm]; ``–`` for the other rows."""
    names = target_names(ens)
    out = []
    for lab in labels:
        if lab.startswith("touchdown") and "touchdown" in names:
            out.append(target_cell(ens, "touchdown"))
        elif lab.startswith("FHM at") and "fhm_flying" in names:
            rng = ens["value_fhm_flying"].attrs["protrusions_nm"]
            out.append(f"{target_cell(ens, 'fhm_flying')} at {', '.join(f'{p:g}' for p in np.atleast_1d(rng))} nm")
        elif lab.startswith("A_n at") and "nominal_area_mean" in ens:
            m, sd = _at(ens, "nominal_area_mean", nominal_area_at), _at(ens, "nominal_area_std", nominal_area_at)
            out.append(value_cell(m, m - sd, m + sd, "um^2", SPREAD_STD))
        else:
            out.append("–")
    return out


def _probability_text(x: np.ndarray, v: np.ndarray) -> str:
    """``x nm: p`` where the probability is between 0 and 1, with the last 0 and the first 1 around."""
    ok = np.isfinite(v)
    x, v = x[ok], v[ok]
    if not x.size:
        return "no value"
    keep = (v > 0) & (v < 1)
    first = np.flatnonzero(v > 0)
    if first.size and first[0] > 0:
        keep[first[0] - 1] = True
    one = np.flatnonzero(v == 1)
    if one.size:
        keep[one[0]] = True
    if not keep.any():
        keep[:] = True
    idx = np.flatnonzero(keep)
    head = f"0 below {x[idx[0]]:g} nm; " if idx[0] > 0 and np.all(v[:idx[0]] == 0) else ""
    tail = f"; 1 above {x[idx[-1]]:g} nm" if idx[-1] < x.size - 1 and np.all(v[idx[-1]:] == 1) else ""
    return head + ", ".join(f"{x[i]:g} nm: {number(v[i], 3)}" for i in idx) + tail


def ensemble_markdown(ens: xr.Dataset) -> str:
    """The section "Paper targets over N DMW realisations" of ``comparison.md``."""
    n = ens.sizes["realisation"]
    seeds = ", ".join(str(int(s)) for s in ens["dmw_seed"].values)
    names = target_names(ens)
    rows = []
    for name in names:
        v = ens[f"value_{name}"]
        s = float(ens[f"single_{name}"])
        rows.append([v.attrs.get("description", v.attrs["long_name"]).replace(" over the DMW realisations", ""), v.attrs["paper"],
                     target_cell(ens, name), f"{number(s)}{_u(str(v.attrs.get('units', '')))}" if np.isfinite(s)
                     else "none"])
    x = ens["protrusion"].values
    text = [
        "", f"## Paper targets over {n} DMW realisations", "",
        f"From `ensemble.nc`: the scene on {n} DMW records (seeds {seeds}; the first is the scene's own record, "
        "the sweep's), at the protrusions the targets read and near the sweep's first contact, with the sweep's k. "
        "Each target is judged as `hdi identify` judges it (pipeline/analyses/ensemble_rules.py): the touchdown where the "
        "touchdown probability crosses 0.5, with the 10-90 % range of the realisations' touchdown protrusions; FHM/BV "
        "as the median over the realisations with its 10-90 % range; the light-contact state as mean ± 1 standard "
        "deviation over the realisations in contact. The last column is the scene's record alone.", "",
        table(["target", "paper", f"over {n} realisations (spread)", "scene's record alone"], rows), "",
    ]
    if "touchdown_probability" in ens:
        line = f"- Touchdown probability versus protrusion: {_probability_text(x, ens['touchdown_probability'].values)}"
        if "touchdown" in names:
            line += f"; the touchdown protrusion over the realisations: {target_cell(ens, 'touchdown')}"
        text.append(line + ".")
    if "bouncing" in names and "bv_exceedance_probability" in ens:
        band = np.atleast_1d(ens["value_bouncing"].attrs["protrusions_nm"])
        thr = ens["bv_exceedance_probability"].attrs["threshold_percent"]
        probs = [_at(ens, "bv_exceedance_probability", b) for b in band]
        steps = sum(1 for v in probs if np.isfinite(v) and v > 0.5)
        text.append(f"- P(bouncing BV > {thr:g} %) over the bouncing band (in contact in the steady window): "
                    + ", ".join(f"{b:g} nm: {number(v, 3)}" for b, v in zip(band, probs))
                    + f"; {steps} of the {len(band)} steps above 0.5 (figure `band.png`).")
    if "sliding_bv" in names and "touchdown_probability" in ens:
        at = float(np.atleast_1d(ens["value_sliding_bv"].attrs["protrusions_nm"])[0])
        frac = _at(ens, "touchdown_probability", at)
        if np.isfinite(frac):
            text.append(f"- At {at:g} nm {int(round(frac * n))} of the {n} realisations are in contact in the "
                        "steady window; the light-contact means are over those.")
    return "\n".join(text) + "\n"
