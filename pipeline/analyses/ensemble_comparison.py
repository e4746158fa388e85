"""The comparison with the paper over DMW realisations: the report's ensemble table (pure functions).

Reads ``ensemble.nc`` (:mod:`pipeline.stages.ensemble`: the scene on ``report.realisations`` DMW
records at the protrusions the paper's checks read) and judges every paper target as ``hdi identify``
does (:attr:`pipeline.analyses.study.Target.ensemble`, the statistics of
:mod:`pipeline.analyses.ensemble`): each value with its spread (10-90 % of the realisations for the
touchdown protrusion and the FHM/BV medians, mean +- 1 standard deviation for the light-contact
state), beside the value of the scene's own record alone (realisation 0, the sweep's).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import xarray as xr

from . import ensemble as en
from .markdown import number, table
from .study import SPREAD_STD, Table, Target

#: Unit text of a target's units in the tables.
_UNIT = {"1": ""}


def _u(units: str) -> str:
    u = _UNIT.get(units, units)
    return f" {u}" if u else ""


def single_record_table(ens: xr.Dataset) -> Table:
    """Realisation 0 (the scene's own record) of ``ensemble.nc`` as a single-record :class:`Table`."""
    outputs = {name: np.asarray(ens[name].values, float)[:, 0] for name in ens.data_vars
               if ens[name].dims == ("protrusion", en.DIM)}
    return Table({"protrusions": ens["protrusion"].values, "outputs": outputs})


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


def target_cells(ens: xr.Dataset, tlist: Sequence[Target]) -> dict[str, dict[str, Any]]:
    """Per target name: ``value, low, high`` over the realisations, its ``cell`` text, and ``single``,
    the value of the scene's record alone."""
    single = single_record_table(ens)
    out = {}
    for t in tlist:
        v, lo, hi = t.ensemble(ens) if t.ensemble else (np.nan, np.nan, np.nan)
        s = t.value(single)
        out[t.name] = {"target": t, "value": v, "low": lo, "high": hi,
                       "cell": value_cell(v, lo, hi, t.units, t.spread),
                       "single": f"{number(s)}{_u(t.units)}" if np.isfinite(s) else "none"}
    return out


def _mean_std_cell(ens: xr.Dataset, name: str, at: float, units: str) -> str:
    x = ens["protrusion"].values
    j = np.flatnonzero(np.abs(x - at) < 1e-6)
    if name not in ens or not j.size:
        return "–"
    m, sd = (float(v) for v in en.mean_std(ens[name].isel(protrusion=int(j[0]))))
    return value_cell(m, m - sd, m + sd, units, SPREAD_STD)


def main_table_column(labels: Sequence[str], ens: xr.Dataset, cells: dict[str, dict[str, Any]],
                      nominal_area_at: float) -> list[str]:
    """The cells of the comparison table's column over the realisations, one per row label: the
    touchdown, the flying FHM and A_n at ``nominal_area_at`` [nm]; ``–`` for the other rows."""
    out = []
    for lab in labels:
        if lab.startswith("touchdown") and "touchdown" in cells:
            out.append(cells["touchdown"]["cell"])
        elif lab.startswith("FHM at") and "fhm_flying" in cells:
            out.append(f"{cells['fhm_flying']['cell']} at {cells['fhm_flying']['target'].long_name.split('over ')[-1]}")
        elif lab.startswith("A_n at"):
            out.append(_mean_std_cell(ens, "nominal_area", nominal_area_at, "um^2"))
        else:
            out.append("–")
    return out


def _probability_text(p: xr.DataArray) -> str:
    """``x nm: p`` where the probability is between 0 and 1, with the last 0 and the first 1 around."""
    x, v = p["protrusion"].values, p.values
    ok = np.isfinite(v)
    x, v = x[ok], v[ok]
    if not x.size:
        return "no value"
    keep = (v > 0) & (v < 1)
    zero, one = np.flatnonzero(v == 0), np.flatnonzero(v == 1)
    first = np.flatnonzero(v > 0)
    if first.size and first[0] > 0:
        keep[first[0] - 1] = True
    if one.size:
        keep[one[0]] = True
    if not keep.any():
        keep[:] = True
    parts = [f"{xi:g} nm: {number(vi, 3)}" for xi, vi in zip(x[keep], v[keep])]
    head = f"0 below {x[keep][0]:g} nm; " if zero.size and zero[0] < np.flatnonzero(keep)[0] else ""
    tail = f"; 1 above {x[one[0]]:g} nm" if one.size and np.all(v[one[0]:] == 1) and one[0] < x.size - 1 else ""
    return head + ", ".join(parts) + tail


def ensemble_markdown(ens: xr.Dataset, tlist: Sequence[Target], cells: dict[str, dict[str, Any]],
                      band: Sequence[float], bv_min_percent: float, sliding_at: float) -> str:
    """The section "Paper targets over N DMW realisations" of ``comparison.md``."""
    n = ens.sizes[en.DIM]
    seeds = ", ".join(str(int(s)) for s in ens["dmw_seed"].values)
    rows = []
    for t in tlist:
        c = cells[t.name]
        rows.append([t.long_name, t.paper, c["cell"], c["single"]])
    p = en.touchdown_probability(ens["min_clearance"])
    td, lo, hi = en.touchdown_protrusion(ens["min_clearance"])
    bv = ens["fhm_bv"]
    x = ens["protrusion"].values
    in_band = [float(b) for b in band if np.any(np.abs(x - b) < 1e-6)]
    pb = en.exceedance_probability(bv.sel(protrusion=in_band), bv_min_percent) if in_band else None
    j = np.flatnonzero(np.abs(x - sliding_at) < 1e-6)
    text = [
        "", f"## Paper targets over {n} DMW realisations", "",
        f"From `ensemble.nc`: the scene on {n} DMW records (seeds {seeds}; the first is the scene's own record, "
        "the sweep's), at the protrusions the targets read and near the sweep's first contact, with the sweep's k. "
        "Each target is judged as `hdi identify` judges it (pipeline/analyses/ensemble.py): the touchdown where the "
        "touchdown probability crosses 0.5, with the 10-90 % range of the realisations' touchdown protrusions; FHM/BV "
        "as the median over the realisations with its 10-90 % range; the light-contact state as mean ± 1 standard "
        "deviation over the realisations in contact. The last column is the scene's record alone.", "",
        table(["target", "paper", f"over {n} realisations (spread)", "scene's record alone"], rows), "",
        f"- Touchdown probability versus protrusion: {_probability_text(p)}; crosses 0.5 at "
        + (f"{number(td)} nm" if np.isfinite(td) else "no evaluated protrusion")
        + (f" (10-90 %: {number(lo)}-{number(hi)} nm)." if np.isfinite(lo) and np.isfinite(hi) else "."),
    ]
    if pb is not None:
        text.append(f"- P(BV > {bv_min_percent:g} %) over the bouncing band: "
                    + ", ".join(f"{b:g} nm: {number(float(v), 3)}" for b, v in zip(in_band, pb.values)) + ".")
    if j.size:
        frac = float(en.touchdown_probability(ens["min_clearance"].isel(protrusion=int(j[0]))))
        text.append(f"- At {sliding_at:g} nm {int(round(frac * n))} of the {n} realisations are in contact in the "
                    "steady window; the light-contact means are over those.")
    return "\n".join(text) + "\n"
