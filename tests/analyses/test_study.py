"""The study's definitions (pipeline/analyses/study.py): the graded bouncing-band target (docs/model.md, section
"Identification": the mean over the band's steps of the bouncing BV, each step capped at the threshold, flying
runs at 0), and the parameters of a study (bad keys named in one line, a list element set alone, CF units for
every numeric scene key)."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analyses import study
from pipeline.config.scene import load_scene

import scoring_reference

PAPER = "configs/paper-2009.toml"
BAND = (10.0, 10.2, 10.4, 10.6, 10.8)


def _record(bv: np.ndarray, clearance: np.ndarray) -> dict:
    """A record over the band's five steps; ``bv``, ``clearance`` of shape (5, realisations)."""
    bv, clearance = np.atleast_2d(bv), np.atleast_2d(clearance)
    return {"protrusions": list(BAND), "realisations": bv.shape[1],
            "outputs": {"fhm_bv": bv.ravel().tolist(), "min_clearance": clearance.ravel().tolist()}}


@pytest.fixture(scope="module")
def band():
    return next(t for t in study.targets(load_scene(PAPER)) if t.name == "bouncing")


def test_band_steps_are_the_papers(band):
    assert band.protrusions == BAND and band.target == 20.0


def test_graded_value_on_one_record(band):
    bv = np.array([25.0, 30.0, 10.0, 40.0, 5.0])
    touch = np.array([-0.1, -0.1, -0.1, 0.2, -0.1])  # the fourth step flies: its 40 % is an FHM, no bounce
    t = study.Table(_record(bv[:, None], touch[:, None]))
    assert band.value(t) == pytest.approx((20 + 20 + 10 + 0 + 5) / 5)
    assert band.residual(t, 10.0) == pytest.approx((20 - 11.0) / 2.0)
    full = study.Table(_record(np.full((5, 1), 21.0), np.full((5, 1), -0.1)))
    assert band.value(full) == 20.0 and band.residual(full, 10.0) == 0.0


def test_graded_value_over_realisations_uses_each_steps_median(band):
    # three realisations: step medians 22, 18, 0 (two of three fly), 30, 12
    bv = np.array([[21, 22, 40], [10, 18, 19], [5, 30, 30], [29, 30, 35], [12, 12, 12]], float)
    cl = np.array([[-1, -1, -1], [-1, -1, -1], [-1, 1, 1], [-1, -1, -1], [-1, -1, -1]], float)
    ds = study.record_dataset(_record(bv, cl))
    value, lo, hi = band.ensemble(ds)
    assert value == pytest.approx((20 + 18 + 0 + 20 + 12) / 5)
    assert lo <= value <= hi
    assert band.ensemble_residual(ds, 10.0) == pytest.approx((20 - value) / 2.0)


def test_graded_value_grows_with_any_step(band):
    """The target an optimiser climbs: raising one step's BV below the threshold raises the value."""
    base = np.array([20.0, 15.0, 10.0, 5.0, 1.0])
    cl = np.full(5, -0.1)
    v0 = band.value(study.Table(_record(base[:, None], cl[:, None])))
    for j in range(5):
        up = base.copy()
        up[j] += 1.0
        v1 = band.value(study.Table(_record(up[:, None], cl[:, None])))
        assert (v1 > v0) == (base[j] < 20.0), j


def test_unevaluated_step_is_missing(band):
    bv = np.array([25.0, 30.0, np.nan, 40.0, 5.0])
    cl = np.array([-0.1, -0.1, np.nan, -0.1, -0.1])
    t = study.Table(_record(bv[:, None], cl[:, None]))
    assert np.isnan(band.value(t)) and band.residual(t, 10.0) == 10.0


# ------------------------------------------------ the scoring on the record's arrays against the xarray form
def ensemble_record(tlist, n: int, seed: int) -> dict:
    """An evaluation record of ``n`` DMW realisations at the targets' protrusions: FHM/BV, minimum clearance
    (contact from about 9.8 nm, the band's steps mixed) and the light-contact outputs, with a failed run."""
    rng = np.random.default_rng(seed)
    prots = study.target_protrusions(tlist)
    k = len(prots)
    p = np.array(prots)[:, None]
    outputs = {"fhm_bv": 5.0 + 20.0 * rng.random((k, n)) + (p > 9.7) * 10.0,
               "min_clearance": (9.75 - p) + 0.15 * rng.standard_normal((k, n)),
               "interference": 0.3 + 0.05 * rng.standard_normal((k, n)),
               "contact_force": 1.0 + 0.2 * rng.standard_normal((k, n)),
               "real_area": 0.5 + 0.1 * rng.random((k, n)), "mean_pressure": 300 + 40 * rng.random((k, n)),
               "friction_coefficient": 0.3 + 0.1 * rng.random((k, n)),
               "net_force": -0.1 + 0.1 * rng.standard_normal((k, n))}
    for v in outputs.values():
        v[3, n - 1] = np.nan  # (a failed run of the last realisation)
    return {"protrusions": prots, "realisations": n, "outputs": {name: v.tolist() for name, v in outputs.items()}}


def test_scoring_on_the_records_arrays_is_the_xarray_scoring_to_the_last_bit(paper_scene):
    # every paper target, ensembles of 2, 4 and 8 records (racing's stages), a failed run among them
    tlist = study.targets(paper_scene)
    assert {t.kind for t in tlist} == {"touchdown", "equal", "above", "below"}
    for n, seed in ((2, 1), (4, 2), (8, 3), (8, 4)):
        record = ensemble_record(tlist, n, seed)
        vals, res, spread = study.score(record, tlist, 10.0)
        x_vals, x_res, x_spread = scoring_reference.xarray_score(record, tlist, 10.0)
        np.testing.assert_array_equal(vals, x_vals)
        np.testing.assert_array_equal(res, x_res)
        np.testing.assert_array_equal(spread, x_spread)
        np.testing.assert_array_equal(study.spreads(record, tlist), x_spread)
        assert np.isfinite(vals).sum() >= len(tlist) - 1, vals  # (the statistics are numbers, not NaN throughout)
        # the same statistics on the record's dataset (ensemble.nc's form)
        ds = study.record_dataset(record)
        for t in tlist:
            np.testing.assert_array_equal(t.ensemble(ds), t.ensemble(study.Ensemble.of_record(record)))


def test_a_one_record_part_of_an_ensemble_is_scored_by_the_ensemble_rules(paper_scene):
    """A first racing stage of one DMW record (``identify.racing_records = 1``) is a partial ensemble: scored by the
    ensemble's statistics of one value (the xarray rules' to the last bit), not by the rules of a scene's record
    alone, which it differs from where the two rules differ: the touchdown value (the crossing of a touchdown
    probability of 0 or 1 at 0.5, halfway between the last flying and the first touching protrusion, against the
    first touching protrusion) and the spreads (its one value, against none)."""
    tlist = study.targets(paper_scene)
    whole = {**ensemble_record(tlist, 8, 5), "seeds": list(range(8))}
    part = study.head(whole, 1)
    assert study.is_ensemble(part) and study.realisations_of(part) == 1
    vals, res, spread = study.score(part, tlist, 10.0)
    for got, want in zip((vals, res, spread), scoring_reference.xarray_score(part, tlist, 10.0)):
        np.testing.assert_array_equal(got, want)
    # the same realisation as a scene's record alone (no realisations named): the single-record rules
    single = {"protrusions": part["protrusions"],
              "outputs": {k: [row[0] for row in v] for k, v in part["outputs"].items()}}
    assert not study.is_ensemble(single)
    s_vals, s_res, s_spread = study.score(single, tlist, 10.0)
    assert np.all(np.isnan(s_spread)) and np.isfinite(spread).any()
    i = [t.kind for t in tlist].index("touchdown")
    prots = np.sort(part["protrusions"])
    first = int(np.searchsorted(prots, s_vals[i]))
    assert 0 < first and prots[first] == s_vals[i]
    assert vals[i] == pytest.approx(0.5 * (prots[first - 1] + prots[first]), abs=1e-12)
    # every residual is the same number by either rule (a statistic of one value is that value)
    # tol: a statistic of one value is that value: a few roundings at most
    np.testing.assert_allclose(res, s_res, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(np.delete(vals, i), np.delete(s_vals, i))
