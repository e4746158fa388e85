"""The reference of the tests of the identification's scoring: the targets' ensemble statistics by the xarray
rules over named dimensions on a record's dataset (the form the identification scored with at d4badfb), which
:func:`pipeline.analyses.study.score` on the record's arrays must equal to the last bit."""

from __future__ import annotations

import numpy as np

from pipeline.analyses import ensemble_rules as en
from pipeline.analyses import study
from pipeline.physics import paper


def xarray_statistic(t: study.ObjectiveTerm, ds) -> tuple[float, float, float]:
    """A target's ensemble statistic on a dataset, by the xarray rules over named dimensions (the form the
    identification scored with before it scored on the record's arrays)."""
    at = study.at_protrusions
    if t.kind == "touchdown":
        return en.touchdown_protrusion(at(ds, "min_clearance", np.sort(ds["protrusion"].values)))
    if t.name == "fhm_flying":
        m, lo, hi = en.median_spread(en.flying_mean(at(ds, "fhm_bv", t.protrusions), at(ds, "min_clearance",
                                                                                            t.protrusions)))
        return float(m), float(lo), float(hi)
    if t.name == "bouncing":
        bv = study.bouncing_bv(at(ds, "fhm_bv", t.protrusions), at(ds, "min_clearance", t.protrusions))
        med, lo, hi = (v.values for v in en.median_spread(bv))
        if not np.all(np.isfinite(med)):
            return float("nan"), float("nan"), float("nan")
        return tuple(float(np.mean(np.minimum(v, t.target))) for v in (med, lo, hi))
    x = at(ds, paper.TARGETS[t.name].measure.output, t.protrusions).isel(protrusion=0)
    if t.spread == study.SPREAD_QUANTILES:
        m, lo, hi = en.median_spread(x)
        return float(m), float(lo), float(hi)
    mu, sd = (float(v) for v in en.mean_std(x))
    return mu, mu - sd, mu + sd


def xarray_score(record: dict, tlist, missing: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Values, residuals and spreads of an ensemble record by :func:`xarray_statistic` on its dataset
    (:func:`pipeline.analyses.study.record_dataset`): what :func:`pipeline.analyses.study.score` gives."""
    ds = study.record_dataset(record)
    stats = np.array([xarray_statistic(t, ds) for t in tlist], float)
    res = []
    for t, v in zip(tlist, stats[:, 0]):
        if t.kind == "touchdown":
            med = en.median_spread(study.at_protrusions(ds, "min_clearance", (t.protrusions[-1], t.protrusions[0])))[0]
            res.append(t._touchdown_residual(float(med.values[0]), float(med.values[1]), missing))
        else:
            res.append(t._residual_of(v, missing))
    return stats[:, 0], np.array(res), stats[:, 1:]
