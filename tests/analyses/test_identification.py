"""The identification (pipeline/analyses/identification.py) on plain functions: the profile intervals (a slice
holds the other parameters at the optimum, a profile re-optimises them), the interval's
interpolated crossings, and the whole search on any evaluation callable (no stage, store or fan-out).
Racing over the DMW records (docs/model.md, "Racing over the DMW records"): the bound, the evaluator's parts,
and racing against the full method on a noisy stand-in and on the twin."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import pytest
import xarray as xr

from pipeline import evaluations
from pipeline.analyses import ensemble_rules as en
from pipeline.analyses import identification, study
from pipeline.model.inputs import SimulationInputs, Source

RHO = 0.9
#: r = R x with R^T R = Sigma^-1 (unit variances, correlation RHO): the objective x^T Sigma^-1 x
R = np.linalg.cholesky(np.linalg.inv(np.array([[1.0, RHO], [RHO, 1.0]]))).T
#: a third residual no parameter moves: the optimum misses it (objective 4), so the interval is where the
#: objective stays within 1 of its profile minimum, the 68 % interval of a Gaussian with covariance Sigma
OFFSET = 2.0


def _targets(n: int) -> list[study.ObjectiveTerm]:
    """``n`` equality targets r0.. of value 0 and tolerance 1, each read from the output of its name."""
    return [study.ObjectiveTerm(f"r{k}", f"residual {k}", "1", "equal", 0.0, 1.0, (9.0,),
                         lambda t, k=k: t.value(f"r{k}", 9.0), "") for k in range(n)]


def _identification(residuals) -> identification.Identification:
    """An identification whose evaluations are ``residuals(x)`` (a vector per point), no stage nor store."""
    def evaluate(points):
        out = []
        for x in points:
            r = residuals(np.asarray(x, float))
            out.append({"key": repr(tuple(map(float, x))), "params": list(map(float, x)), "protrusions": [9.0],
                        "outputs": {f"r{k}": [float(v)] for k, v in enumerate(r)}})
        return out
    return identification.Identification(evaluate, _targets(len(residuals(np.zeros(2)))), 10.0)


PARAMS = [study.Parameter("dmw.rms_nm", -3.0, 3.0), study.Parameter("contact.damping_n_s_m", -3.0, 3.0)]


def _cfg(method: str = "optimised", budget: int = 80, points: int = 25, polish: bool = True) -> dict:
    return {"generations": 3, "population": 5, "seed": 1, "profile_points": points, "profile_method": method,
            "profile_evaluations": budget, "polish": polish}


def _quadratic(x: np.ndarray) -> np.ndarray:
    return np.append(R @ x, OFFSET)


def test_a_slice_is_the_conditional_width_a_profile_the_marginal_one():
    # the optimum is the reconstructed point (0, 0): profile_points 25 put grid points at every 0.25
    ident = _identification(_quadratic)
    out = identification.identify(ident, PARAMS, np.zeros(2), _cfg())
    assert np.array_equal(out["best"], np.zeros(2)) and not out["within"]
    assert out["method"] == identification.METHODS["optimised"]
    # the slice: x1^2 / (1 - rho^2) <= 1, so +-sqrt(1 - rho^2) = +-0.436 (linear crossings between grid points:
    # 0.420 here, so within 0.02)
    half = np.sqrt(1.0 - RHO**2)
    np.testing.assert_allclose(out["slice_intervals"], [[-half, half]] * 2, atol=0.02)
    # the profile: min over x2 of the objective is x1^2 (unit marginal variance): +-1 within 0.01
    np.testing.assert_allclose(out["intervals"], [[-1.0, 1.0]] * 2, atol=0.01)
    # never narrower than the slice, pointwise never above it
    assert np.all(out["intervals"][:, 0] <= out["slice_intervals"][:, 0])
    assert np.all(out["intervals"][:, 1] >= out["slice_intervals"][:, 1])
    ok = np.isfinite(out["profile_cost"])
    assert np.all(out["profile_cost"][ok] <= out["slice_cost"][ok])
    # the other parameter follows the valley, x2 = rho x1, where the profile was re-optimised
    xs = out["profile_points_x"][0]
    opt = out["profile_optimised"][0]
    assert opt.sum() >= 8  # (every point inside the interval and the first outside, both sides)
    np.testing.assert_allclose(xs[opt, 1], RHO * xs[opt, 0], atol=0.05 * 6.0)
    # the slice method holds it at the optimum and gives the slice's interval
    sliced = identification.identify(_identification(_quadratic), PARAMS, np.zeros(2), _cfg("slice"))
    np.testing.assert_array_equal(sliced["intervals"], out["slice_intervals"])
    assert sliced["method"] == identification.METHODS["slice"] and not sliced["profile_optimised"].any()
    from pipeline.analyses.paper_comparison import SLICE_METHOD  # (the report's name of an older dataset's intervals)
    assert SLICE_METHOD == identification.METHODS["slice"]


def test_a_curved_valley_is_followed_by_the_compass_search():
    # r = ((x2 - x1^2) / 0.2, x1, 2): at the optimum (0, 0) the Gauss-Newton slope is zero, so the
    # prediction holds x2 and the compass search (and the secant after it) must find x2 = x1^2: the
    # profile of x1 is x1^2 (interval +-1), its slice x1^2 + 25 x1^4 (+-0.43; +-0.38 by linear crossings
    # between the grid points 0.25 and 0.5)
    ident = _identification(lambda x: np.array([(x[1] - x[0]**2) / 0.2, x[0], OFFSET]))
    out = identification.identify(ident, PARAMS, np.zeros(2), _cfg(budget=120))
    g = out["profile_value"][0]
    assert out["slice_intervals"][0] == pytest.approx(identification.interval(g, g**2 + 25 * g**4, 1.0, 0.0))
    assert out["slice_intervals"][0] == pytest.approx([-0.38, 0.38], abs=0.01)
    # re-optimised to the compass step (5 % of x2's range, 0.3): the objective at x1 = 1 is within
    # (0.15 / 0.2)^2 = 0.56 of the profile's, so the crossing is within a quarter of a grid step
    assert out["intervals"][0] == pytest.approx([-1.0, 1.0], abs=0.07)


def test_the_re_optimisation_spends_at_most_its_budget():
    # each parameter's two walks share profile_evaluations; every one is in the records with role 4
    for budget in (3, 10, 40):
        ident = _identification(_quadratic)
        # (no polish: its polls at the grid's spacing are slice points, which would keep its role)
        out = identification.identify(ident, PARAMS, np.zeros(2), _cfg(budget=budget, points=13, polish=False))
        roles = np.array(list(ident.roles.values()))
        n4 = int(np.sum(roles == 4))
        assert n4 == out["profile_optimiser_evaluations"] <= 2 * budget
        assert identification.ROLES[4] == "profile-optimiser"
        # the rest is what a slice costs: its points (the grid holds the optimum, the reconstructed point) and
        # Gauss-Newton
        assert np.sum(roles == 2) == 2 * (13 - 1) and np.sum(roles == 3) == 2 * 2
    # 3 evaluations buy one point per parameter: its prediction and the poll around it (1 + 2 x (2 - 1))
    ident = _identification(_quadratic)
    out = identification.identify(ident, PARAMS, np.zeros(2), _cfg(budget=3, points=13, polish=False))
    assert out["profile_optimiser_evaluations"] == 6 and out["profile_optimised"].sum() == 2


def test_interval_interpolates_crossings():
    g = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    m = np.array([3.0, 1.0, 0.0, 0.5, 2.0])
    lo, hi = identification.interval(g, m, 1.0, 2.0)
    assert lo == pytest.approx(1.0)
    assert hi == pytest.approx(3.0 + 0.5 / 1.5)


def test_the_identification_takes_any_evaluation_callable(paper_scene):
    # the algorithm (analyses) on a plain function, no stage, store or fan-out: the FHM at 9 nm is ten times
    # the first parameter, which the second does not touch; the target is 9 % within 1 %
    scene = paper_scene.replace(identify={"targets": ["fhm_touchdown"]})
    tlist = study.targets(scene)
    params = [study.Parameter("dmw.rms_nm", 0.5, 1.5), study.Parameter("air_bearing.damping_ratio", 0.01, 0.2)]

    def evaluate(points):
        return [{"key": repr(tuple(x)), "params": list(map(float, x)), "protrusions": [9.0],
                 "outputs": {"fhm_bv": [10.0 * float(x[0])]}} for x in points]

    ident = identification.Identification(evaluate, tlist, 10.0)
    out = identification.identify(ident, params, np.array([1.2, 0.05]),
                                  {"generations": 5, "population": 5, "seed": 1, "profile_points": 5,
                                   "profile_method": "optimised", "profile_evaluations": 40, "polish": True})
    assert out["within"] and abs(10.0 * out["best"][0] - 9.0) <= 1.0
    # the interval of the first parameter is where |10 x - 9| <= 1; the second is seen by no target
    assert out["intervals"][0] == pytest.approx([0.8, 1.0], abs=1e-9)
    assert np.isinf(out["gn_std"][1]) and np.all(np.isnan(out["correlation"][1]))
    assert ident.roles[ident.keys[0]] == 0 and len(ident.records) == len(set(ident.keys))


# ------------------------------------------------------------------------------------ the bound
def test_margin_is_the_error_of_a_partial_mean_against_the_whole_ensemble():
    race = identification.Racing.doubling(2, 8, 3.0)
    assert race.stages == (2, 4, 8) and race.total == 8
    assert identification.Racing.doubling(2, 6, 3.0).stages == (2, 4, 6)
    # z sqrt(pi/2) s sqrt((N - n) / (N n)): n = 2 of 8, s = 1 -> 3 x 1.2533 x sqrt(6/16) = 2.3025
    m = race.margin(np.array([1.0, 0.0, np.nan]), 2)
    # tol: closed form, a few roundings (libm sqrt is exact)
    assert m[0] == pytest.approx(3.0 * math.sqrt(math.pi / 2) * math.sqrt(6.0 / 16.0), rel=1e-12)
    assert m[0] == pytest.approx(2.3025, abs=1e-4)
    assert m[1] == 0.0 and np.isinf(m[2])  # (an unknown spread: no bound)
    assert np.all(race.margin(np.array([1.0, 5.0]), 8) == 0.0)  # every record: exact
    # the variance it stands for, by simulation: the mean of 8 minus the mean of its first 2 (unit spread)
    rng = np.random.default_rng(1)
    x = rng.standard_normal((200_000, 8))
    d = x.mean(axis=1) - x[:, :2].mean(axis=1)
    assert np.std(d) == pytest.approx(math.sqrt(6.0 / 16.0), rel=0.01)


def test_lower_bound_lowers_each_residual_by_its_margin():
    res = np.array([3.0, -2.0, 0.5, 10.0])
    margin = np.array([1.0, 1.0, 1.0, np.inf])
    assert identification.lower_bound(res, margin, "cost") == pytest.approx(2.0**2 + 1.0**2)
    assert identification.lower_bound(res, margin, "max") == pytest.approx(2.0)
    assert identification.lower_bound(res, np.zeros(4), "cost") == pytest.approx(study.cost(res))


# ------------------------------------------------------------------------- the evaluator's parts
def _ensemble_task(base, params, rows, protrusions, inputs, realisations, records=None):
    """A stand-in for the slider on an ensemble: record ``r``'s output is ``x0 + r`` at every protrusion."""
    a, b = records or (0, realisations)
    out = []
    for key, x in rows:
        rec = {"params": list(map(float, x)), "protrusions": list(map(float, protrusions)),
               "outputs": {"fhm_bv": [[float(x[0]) + r for r in range(a, b)] for _ in protrusions]},
               "seconds": 1.0 * (b - a), "kernel_seconds": 0.5 * (b - a), "error": None,
               "realisations": b - a, "seeds": list(range(a, b))}
        if (a, b) != (0, realisations):
            rec["first_record"] = a
        out.append((key, rec))
    return out


def _racing_evaluator(paper_scene, tmp_path):
    """An evaluator of 8 records in racing stages of 2, 4, 8 over one parameter (``dmw.rms_nm``) at 9 nm, on
    :func:`_ensemble_task` (no simulation), and its store."""
    inputs = SimulationInputs(Source("interface", key="i"), Source("dmw", key="d"))
    params = [study.Parameter("dmw.rms_nm", 0.0, 1.0)]
    store = evaluations.EvaluationStore(tmp_path / "s.jsonl")
    return evaluations.Evaluator(paper_scene, params, [9.0], inputs, store, 2, "synchronous", task=_ensemble_task,
                                 realisations=8, stages=(2, 4, 8)), store


def test_the_evaluator_runs_an_ensemble_in_parts_and_joins_them(paper_scene, tmp_path):
    ev, store = _racing_evaluator(paper_scene, tmp_path)
    first = ev([[0.1], [0.2]], 2)
    assert [r["realisations"] for r in first] == [2, 2] and ev.record_evaluations == 4
    assert first[0]["outputs"]["fhm_bv"] == [[0.1, 1.1]] and first[0]["key"] == ev.key([0.1])
    whole = ev([[0.1]], 8)[0]  # the first part is read back: 6 records more
    assert ev.record_evaluations == 4 + 6 and whole["realisations"] == 8 and whole["key"] == ev.key([0.1])
    assert whole["outputs"]["fhm_bv"] == [[0.1 + r for r in range(8)]] and whole["seeds"] == list(range(8))
    assert whole["seconds"] == 8.0 and whole["error"] is None
    with pytest.raises(ValueError, match="records 3: expected one of the racing stages"):
        ev([[0.1]], 3)
    # a whole evaluation of the full method in the store is read back, its first records as the part
    store.put([(ev.key([0.3]), _ensemble_task(None, None, [("k", [0.3])], [9.0], None, 8)[0][1])])
    part = ev([[0.3]], 4)[0]
    assert part["outputs"]["fhm_bv"] == [[0.3, 1.3, 2.3, 3.3]] and part["seconds"] == 4.0
    assert ev.record_evaluations == 10  # nothing computed
    # the stages' parts of the real evaluation are the whole, bit for bit: tests/analyses below (twin)


def test_a_point_evaluated_already_is_not_run_again(paper_scene, tmp_path):
    # a racing identification on the evaluator: the (candidate, record) pairs computed are counted once, whatever
    # asks for the point again (a walk's poll met by another walk, a slice point, a resumed run)
    ev, store = _racing_evaluator(paper_scene, tmp_path)
    targets = [study.ObjectiveTerm("fhm", "fhm", "%", "equal", 0.0, 1.0, (9.0,), lambda t: t.value("fhm_bv", 9.0),
                                   "", lambda e: study._median(study.Ensemble.of(e).at("fhm_bv", (9.0,))[0]))]
    ident = identification.Identification(ev, targets, 10.0, identification.Racing.doubling(2, 8, 3.0))
    pts = np.array([[0.1], [20.0], [30.0]])
    ident.evaluate(pts[:1], 0)  # the best point, on every record: objective (0.1 + 3.5)^2
    _, _, r = ident.evaluate(pts, 1, bound=ident.best_cost, refs=pts[0])
    # 20 and 30 stop after their first 2 records (residuals 20.5 and 30.5, less a margin of 5.6 from the best
    # point's spread of the records, 2.45, are above its 3.6); 0.1 is the best point, held
    assert [ident.depth[k] for k in ident.keys] == [8, 2, 2]
    assert ev.record_evaluations == 8 + 2 + 2 and ident.record_evaluations == 12
    assert r[:, 0] == pytest.approx([3.6, 20.5, 30.5])
    # asked again, on every record: only their records 2-7 run; a third time, nothing
    ident.evaluate(pts, 4)
    assert ev.record_evaluations == 8 + 8 + 8 and [ident.depth[k] for k in ident.keys] == [8, 8, 8]
    ident.evaluate(pts[::-1], 2, bound=0.0, refs=pts[0])
    assert ev.record_evaluations == 24 and ident.record_evaluations == 24


# ------------------------------------------------------------------- racing on a noisy stand-in
RACE_RHO = 0.8
#: r = RACE_R x with RACE_R^T RACE_R = Sigma^-1 (unit variances, correlation RACE_RHO), plus a record's noise
RACE_R = np.linalg.cholesky(np.linalg.inv(np.array([[1.0, RACE_RHO], [RACE_RHO, 1.0]]))).T
N_RECORDS = 8
#: each DMW record's error of each residual, the same for every candidate (common random numbers); its
#: spread NOISE in residual units
NOISE = 0.1
ERRORS = NOISE * np.random.default_rng(7).standard_normal((N_RECORDS, 3))


def _record_values(x: np.ndarray) -> np.ndarray:
    """The residuals of each record at ``x``, shape (records, 3): two correlated ones and one the optimum
    misses by 2 (so the interval is where the objective stays within 1 of its profile minimum)."""
    base = np.append(RACE_R @ x, 2.0)
    # (an error that grows away from the optimum too: a record's noise is not the same everywhere)
    return base[None, :] + ERRORS * (1.0 + 0.3 * np.abs(x).sum())


def _mean_targets() -> list[study.ObjectiveTerm]:
    def ensemble(k):
        def f(ds: xr.Dataset) -> tuple[float, float, float]:
            mu, sd = (float(v) for v in en.mean_std(study.at_protrusions(ds, f"r{k}", (9.0,)).isel(protrusion=0)))
            return mu, mu - sd, mu + sd
        return f
    return [study.ObjectiveTerm(f"r{k}", f"residual {k}", "1", "equal", 0.0, 1.0, (9.0,),
                                lambda t, k=k: t.value(f"r{k}", 9.0), "", ensemble(k)) for k in range(3)]


def _stand_in(calls: list):
    """The evaluation callable of an ensemble identification (``evaluate(points, upto)``), counting the
    (candidate, record) pairs it is asked for in ``calls``."""
    def evaluate(points, upto=N_RECORDS):
        out = []
        for x in points:
            v = _record_values(np.asarray(x, float))[:upto]
            calls.append(upto)
            out.append({"key": repr(tuple(map(float, x))), "params": list(map(float, x)), "protrusions": [9.0],
                        "outputs": {f"r{k}": [list(map(float, v[:, k]))] for k in range(3)},
                        "realisations": upto, "seeds": list(range(upto))})
        return out
    return evaluate


def _full_cost(x: np.ndarray) -> float:
    return study.cost(_record_values(np.asarray(x, float)).mean(axis=0))


CFG = {"generations": 4, "population": 5, "seed": 2, "profile_points": 7, "profile_method": "optimised",
       "profile_evaluations": 20, "polish": True}


def _run(racing):
    calls: list[int] = []
    ident = identification.Identification(_stand_in(calls), _mean_targets(), 10.0, racing)
    out = identification.identify(ident, PARAMS, np.array([2.0, -1.0]), CFG)
    return ident, out


def test_racing_keeps_the_optimum_exact_and_stops_only_worse_candidates():
    full_ident, full = _run(None)
    race = identification.Racing.doubling(2, N_RECORDS, 3.0)
    ident, out = _run(race)
    # the best point ran on every record and its objective is the whole ensemble's
    key = ident.best_key
    # tol: the same mean of the same records, summed in the same order
    assert ident.depth[key] == N_RECORDS and ident.best_cost == pytest.approx(_full_cost(out["best"]), rel=1e-12)
    # a candidate stopped early is worse than the best point on the whole ensemble (the guarantee, here for
    # every one of them), and but for the polish's its partial objective says so too: the polish's points lie
    # close to their reference, the current point, whose whole ensemble and paired records bound them tighter
    # than their own two records (its vertex (0.0019, -0.0944) stops on 2 records at a partial 3.76 below the
    # best 3.83; on all 8 it is 3.85)
    stopped = [k for k, d in ident.depth.items() if d < N_RECORDS]
    assert len(stopped) >= 0.3 * len(ident.depth)
    for k in stopped:
        x = np.array(ident.records[k]["params"])
        assert _full_cost(x) > ident.best_cost, (x, _full_cost(x), ident.best_cost)
        if ident.roles[k] != 5:
            assert study.cost(ident.scores[k][1]) > ident.best_cost
    # the cost: (candidate, record) pairs; the full method runs every evaluation on all 8
    assert full_ident.record_evaluations == N_RECORDS * len(full_ident.records)
    assert ident.record_evaluations < 0.75 * full_ident.record_evaluations
    # the same optimum and intervals as the full method, within their tolerance: each optimum inside the other's
    # interval, the interval ends within one profile step (0.5) of each other; both hold the marginal
    # 68 % interval of the whole ensemble's objective (+-1 around its minimum here, unit marginal variance)
    step = (PARAMS[0].high - PARAMS[0].low) / (CFG["profile_points"] - 1)
    for i in range(2):
        assert full["intervals"][i, 0] <= out["best"][i] <= full["intervals"][i, 1]
        assert out["intervals"][i, 0] <= full["best"][i] <= out["intervals"][i, 1]
    np.testing.assert_allclose(out["intervals"], full["intervals"], atol=step)
    assert np.abs(out["best"] - full["best"]).max() < 0.5 * step


def test_a_first_stage_of_one_record_is_bounded_by_the_pooled_spreads_alone():
    """``racing_records = 1``: stages 1, 2, 4, 8. The margin at one record, by simulation: the error of one normal
    record against the median of 8 is within the margin's unit (sd 0.96 against sqrt(pi/2) sqrt(7/8) = 1.17), so
    z = 3 holds it at least as often as at two records. One record has no spread of its own: before any whole
    evaluation the margin is infinite (no candidate stops on its first record), after it the pooled spreads bound it;
    on the noisy stand-in it keeps the optimum and the intervals of stages 2, 4, 8 and runs fewer pairs."""
    race = identification.Racing.doubling(1, N_RECORDS, 3.0)
    assert race.stages == (1, 2, 4, 8)
    unit = race.margin(np.array([1.0]), 1)[0] / 3.0
    # tol: closed form, a few roundings (libm sqrt is exact)
    assert unit == pytest.approx(math.sqrt(math.pi / 2) * math.sqrt(7.0 / 8.0), rel=1e-12)
    x = np.random.default_rng(3).standard_normal((200_000, N_RECORDS))
    d = np.median(x, axis=1) - x[:, 0]
    assert np.std(d) == pytest.approx(0.958, abs=0.01) and np.std(d) < unit
    assert np.mean(np.abs(d) > 3.0 * unit) < 2 * (1 - 0.99865)  # (two-sided, z = 3: 0.0007 here)
    # no whole evaluation yet: one record bounds nothing, so every point, however bad, runs on (own spread at 2)
    calls: list[int] = []
    ident = identification.Identification(_stand_in(calls), _mean_targets(), 10.0, race)
    ident.evaluate(np.array([[5.0, 5.0], [4.0, -4.0]]), 1, bound=0.0)
    assert calls[:2] == [1, 1] and all(d >= 2 for d in ident.depth.values())
    # after whole evaluations: the search's worst trials stop on their first record, worse than the best point
    full_ident, full = _run(identification.Racing.doubling(2, N_RECORDS, 3.0))
    ident, out = _run(race)
    one = [k for k, d in ident.depth.items() if d == 1]
    assert len(one) >= 0.3 * len(ident.depth)
    for k in one:
        assert _full_cost(np.array(ident.records[k]["params"])) > ident.best_cost
    assert ident.depth[ident.best_key] == N_RECORDS
    # tol: the same mean of the same records, summed in the same order
    assert ident.best_cost == pytest.approx(_full_cost(out["best"]), rel=1e-12)
    # (575 pairs against 600 when written)
    assert ident.record_evaluations < full_ident.record_evaluations
    step = (PARAMS[0].high - PARAMS[0].low) / (CFG["profile_points"] - 1)
    _agree_within_tolerance(out, full, step, np.zeros(2))


def _agree_within_tolerance(a: dict, b: dict, step: float, truth: np.ndarray) -> None:
    """Two identifications give the same answer within their tolerance: each optimum inside the other's interval,
    ``truth`` inside both, the interval ends within one profile ``step`` of each other."""
    for i in range(len(truth)):
        assert b["intervals"][i, 0] <= a["best"][i] <= b["intervals"][i, 1]
        assert a["intervals"][i, 0] <= b["best"][i] <= a["intervals"][i, 1]
        assert a["intervals"][i, 0] <= truth[i] <= a["intervals"][i, 1]
        assert b["intervals"][i, 0] <= truth[i] <= b["intervals"][i, 1]
    np.testing.assert_allclose(a["intervals"], b["intervals"], atol=step)


def test_the_polish_starts_the_profiles_at_the_optimum_and_agrees_with_the_method_without_it():
    # one generation of 4 x 2 candidates stops short of the optimum (0, 0) of the noisy correlated quadratic: without
    # the polish a profile point beats it by more than PROFILE_GAIN and the profiles are made twice; with it once
    race = identification.Racing.doubling(2, N_RECORDS, 3.0)
    runs = {}
    for polish in (False, True):
        calls: list[int] = []
        ident = identification.Identification(_stand_in(calls), _mean_targets(), 10.0, race)
        cfg = dict(CFG, generations=1, population=4, polish=polish)
        runs[polish] = ident, identification.identify(ident, PARAMS, np.array([2.0, -1.0]), cfg)
    (plain_ident, plain), (ident, out) = runs[False], runs[True]
    assert plain["polish"] is None and plain_ident.roles and 5 not in plain_ident.roles.values()
    assert plain["profile_rounds"] == 2 and out["profile_rounds"] == 1
    # what it did: from the search's best point (objective 7.6) to within PROFILE_GAIN of the best of all, its
    # polls counted in the records with role 5, within its budget, the last at most the walks' step
    p = out["polish"]
    assert p["start_objective"] == pytest.approx(7.62, abs=0.01) and p["moves"] >= 1
    assert p["objective"] < p["start_objective"] and p["objective"] - ident.best_cost <= identification.PROFILE_GAIN
    # (a point the search asked for keeps its role)
    assert sum(r == 5 for r in ident.roles.values()) <= p["evaluations"] <= identification.POLISH_EVALUATIONS * 2
    assert p["first_step"] == pytest.approx(1.0 / (CFG["profile_points"] - 1)) and \
        p["last_step"] <= identification.PROFILE_STEP
    # the best point ran on every record; it costs fewer (candidate, record) pairs than the second round it saves
    assert ident.depth[ident.best_key] == N_RECORDS
    assert ident.record_evaluations < 0.95 * plain_ident.record_evaluations
    # the same answer within the tolerance, the truth (0, 0) inside both (one profile step: 1)
    step = (PARAMS[0].high - PARAMS[0].low) / (CFG["profile_points"] - 1)
    _agree_within_tolerance(out, plain, step, np.zeros(2))
    assert abs(ident.best_cost - plain_ident.best_cost) < 0.01


def test_a_compass_poll_keeps_inside_the_bounds_and_skips_the_profiled_parameter():
    lo, hi = np.array([0.0, 0.0, 10.0]), np.array([1.0, 2.0, 20.0])
    pts, polls = identification._compass(np.array([0.98, 1.0, 10.0]), 0.1, lo, hi, skip=1)
    # x0: +0.1 clipped to 1.0 (an offset of 0.02), -0.1; x2: +1 only (the lower bound cancels -1)
    assert polls == [(0, pytest.approx(0.02)), (0, pytest.approx(-0.1)), (2, pytest.approx(1.0))]
    # tol: clipping and one addition of exact decimals, a few roundings
    np.testing.assert_allclose(pts, [[1.0, 1.0, 10.0], [0.88, 1.0, 10.0], [0.98, 1.0, 11.0]])
    # the parabola through (-h, c-), (0, c0), (h, c+) has its vertex at h (c- - c+) / (2 (c- - 2 c0 + c+)):
    # c = (x - 0.3)^2 polled at 0 +- 1 gives 0.3; x1 (curving down) stays
    x = np.array([0.0, 0.0])
    _, polls = identification._compass(x, 0.5, np.array([-1.0, -1.0]), np.array([1.0, 1.0]))
    c = np.array([(1 - 0.3)**2, (-1 - 0.3)**2, -1.0, -1.0])
    # tol: the parabola's vertex of exact inputs, tens of roundings
    np.testing.assert_allclose(identification._vertex(x, 0.09, polls, c, np.array([-1.0, -1.0]),
                                                      np.array([1.0, 1.0])), [0.3, 0.0])


def test_a_profile_walk_races_every_point_and_takes_none_stopped_early():
    """A walk's predicted point (against the slice point), polls and vertex (against the current point) are all
    raced, and one stopped early (a partial ensemble) is never taken, however low its partial metric: every
    profile point is a whole evaluation."""
    lo, hi = np.zeros(3), np.ones(3)
    metric = study.cost
    start, slice_point, slice_res = np.full(3, 0.5), np.array([0.6, 0.5, 0.5]), np.array([2.0])

    def slice_at(v: float) -> tuple[np.ndarray, np.ndarray]:
        x = slice_point.copy()
        x[0] = v
        return x, slice_res

    w = identification._Walk(0, np.array([0.6, 0.8]), start, np.array([1.0, 1.0, 0.0]), lo, hi, metric, 100.0, slice_at)
    pts = w.candidates()  # the prediction (0.6, 0.6, 0.5), then the poll around it
    # tol: the prediction is additions of exact decimals, a few roundings
    np.testing.assert_allclose(pts[0], [0.6, 0.6, 0.5])
    assert len(pts) == 5 and [w.bound(x) for x in pts] == [4.0] * 5  # (the slice point's objective)
    np.testing.assert_array_equal(w.reference(), slice_point)
    # the prediction and the second poll stopped early with partial objectives far below the rest
    res = np.array([[0.1], [1.0], [0.05], [1.5], [1.9]])
    w.update(pts, res, [False, True, False, True, True])
    np.testing.assert_array_equal(w.x, pts[1])  # (the best whole point: not the prediction, not the partial poll)
    np.testing.assert_array_equal(w.res, [1.0])
    new = w.candidates()
    assert len(new) == 3 and all(w.bound(x) == 1.0 for x in new)  # (the prediction is known: not asked again)
    w.update(new, np.array([[1.2], [1.3], [1.4]]), [True, True, True])
    vertex = w.candidates()  # nothing better: the parabolas' vertex, raced against the current point
    assert len(vertex) == 1 and w.bound(vertex[0]) == 1.0
    np.testing.assert_array_equal(w.reference(), pts[1])
    w.update(vertex, np.array([[0.0]]), [False])
    point, r = w.found[0.6]
    np.testing.assert_array_equal(point, pts[1])
    np.testing.assert_array_equal(r, [1.0])
    assert w.value == 0.8 and not w.done


# --------------------------------------------------------------- racing against the full method on the twin
TRUE = {"dmw.rms_nm": 0.14, "lubricant.work_of_adhesion_j_m2": 0.07}

#: The twin (tests/twin.py) on 4 DMW records, its targets the ensemble's values at TRUE
ENSEMBLE_TWIN = """
targets = ["fhm_flying", "contact_force"]
fhm_flying_tolerance_percent = 0.3
contact_force_tolerance_mn = 0.05
population = 4
generations = 2
profile_points = 5
profile_evaluations = 8
batch_size = 4
realisations = 4
"""


def _ensemble_twin(write_scene, paper_config, tmp_path):
    """The twin on 4 DMW records (:data:`ENSEMBLE_TWIN`): its scene's path, the scene, its free parameters, its
    targets, the protrusions they need, their inputs and the truth's whole evaluation (at :data:`TRUE`)."""
    import twin
    from pipeline.config.scene import load_scene
    path = write_scene(twin.scene_text(ENSEMBLE_TWIN).format(paper=paper_config))
    scene = load_scene(path)
    params = study.parse_parameters(scene["identify"]["parameters"], str(path), "identify.parameters")
    tl = study.targets(scene)
    inputs = evaluations.prepare_inputs(scene, tmp_path / "truth")
    prots = study.target_protrusions(tl)
    whole = evaluations.evaluate(scene, params, [TRUE[p.name] for p in params], prots, inputs, 4)
    return path, scene, params, tl, prots, inputs, whole


def _twin_targets(tl, whole) -> list[str]:
    """The ``--set`` options that make the truth's ensemble values the twin's targets."""
    from pipeline.physics import paper
    values, _ = study.residuals(whole, tl, 10.0)
    return [f"identify.{paper.TARGETS[t.name].value.key}={float(v)!r}" for t, v in zip(tl, values)]


@pytest.mark.slow  # (two identifications of the real slider on 4 DMW records: ~1 min on the shared 2 cores)
def test_twin_racing_agrees_with_the_full_method_within_the_tolerance(write_scene, paper_config, tmp_path):
    path, scene, params, tl, prots, inputs, whole = _ensemble_twin(write_scene, paper_config, tmp_path)
    # the parts of an ensemble are the whole, bit for bit (the racing stages join them)
    parts = [evaluations.evaluate(scene, params, [TRUE[p.name] for p in params], prots, inputs, 4, seg)
             for seg in ((0, 2), (2, 4))]
    joined = evaluations.join_parts(parts)
    for k, v in whole["outputs"].items():
        np.testing.assert_array_equal(np.array(joined["outputs"][k], float), np.array(v, float))
    assert joined["seeds"] == whole["seeds"]
    # the scoring on the record's arrays is the xarray rules' on its dataset, to the last bit, on the slider's record
    import scoring_reference
    for got, want in zip(study.score(whole, tl, 10.0), scoring_reference.xarray_score(whole, tl, 10.0)):
        np.testing.assert_array_equal(got, want)
    sets = _twin_targets(tl, whole)
    race, full = _identified_with_and_without(path, sets, "racing", tmp_path)
    assert full.attrs["racing"].startswith("off") and race.attrs["racing"].startswith("stages of 2, 4 DMW records")
    # the full method runs every evaluation on every record; racing stops some after 2
    assert np.all(full["records"].values == 4)
    assert full.attrs["record_evaluations"] == 4 * full.sizes["evaluation"]
    assert full.attrs["simulations_run"] == full.attrs["record_evaluations"] * len(prots)
    stopped = race["records"].values < 4
    assert stopped.any() and race.attrs["record_evaluations"] == int(race["records"].sum())
    assert race.attrs["record_evaluations"] < full.attrs["record_evaluations"]
    # the best point ran on every record; every trial of the search stopped early has a partial objective above
    # it (a profile poll within tolerance races on the largest |r| against its walk's point instead)
    i_best = int(race.attrs["best_evaluation"])
    assert race["records"][i_best] == 4
    search = stopped & (race["role"].values == 1)
    assert search.any() and np.all(race["objective"].values[search] > race.attrs["best_objective"])
    _same_answer(race, full, params, scene)


def _identified_with_and_without(path, sets: list[str], option: str, tmp_path) -> tuple[xr.Dataset, xr.Dataset]:
    """identify.nc of the twin scene ``path`` (with the ``--set`` strings ``sets``) with ``identify.<option>``
    on, then off, each in a folder of its own."""
    on, off = _identified_by(path, sets, option, ("true", "false"), tmp_path)
    return on, off


def _identified_by(path, sets: list[str], option: str, values: Sequence[str], tmp_path) -> list[xr.Dataset]:
    """identify.nc of the twin scene ``path`` (with the ``--set`` strings ``sets``) for each of ``values`` of
    ``identify.<option>``, each in a folder of its own."""
    from pipeline.config.scene import load_scene
    from pipeline.runner import ensure
    runs = []
    for v in values:
        sc = load_scene(path, sets + [f"identify.{option}={v}"])
        out = ensure("identify", sc, tmp_path / f"{option}-{v}", scheduler="synchronous")
        runs.append(xr.open_dataset(out, engine="netcdf4").load())
    return runs


def _same_answer(one: xr.Dataset, other: xr.Dataset, params, scene) -> None:
    """Two identifications of the twin give the same answer within the tolerance: both within tolerance, each
    optimum inside the other's interval and the truth inside both; the interval ends within one profile step
    of each other."""
    assert one.attrs["within_tolerance"] == other.attrs["within_tolerance"] == 1
    for p in params:
        step = (p.high - p.low) / (scene["identify"]["profile_points"] - 1)
        a, b = one.sel(parameter=p.name), other.sel(parameter=p.name)
        lo_a, hi_a = a["interval"].values
        lo_b, hi_b = b["interval"].values
        assert lo_b <= float(a["best"]) <= hi_b and lo_a <= float(b["best"]) <= hi_a, (p.name, a["best"], b["best"])
        assert lo_a <= TRUE[p.name] <= hi_a and lo_b <= TRUE[p.name] <= hi_b
        np.testing.assert_allclose([lo_a, hi_a], [lo_b, hi_b], atol=step)


@pytest.mark.slow  # (two identifications of the real slider on 4 DMW records: ~1 min on the shared 2 cores)
def test_twin_polish_agrees_with_the_method_without_it_within_the_tolerance(write_scene, paper_config, tmp_path):
    # one generation of 4 x 2 candidates, racing on: the search stops short of the truth, the polish takes it the
    # rest of the way before the profiles
    path, scene, params, tl, prots, inputs, whole = _ensemble_twin(write_scene, paper_config, tmp_path)
    sets = _twin_targets(tl, whole) + ["identify.generations=1"]
    on, off = _identified_with_and_without(path, sets, "polish", tmp_path)
    assert "polish" not in off.attrs and not np.any(off["role"].values == 5)
    assert on.attrs["polish_objective"] < on.attrs["polish_start_objective"] and on.attrs["polish_moves"] >= 1
    assert int(np.sum(on["role"].values == 5)) <= on.attrs["polish_evaluations"] <= \
        identification.POLISH_EVALUATIONS * len(params)
    # the profiles' rounds and the pairs: fewer with the polish where the search stopped short (1 round and 230
    # (candidate, record) pairs against 2 and 276 when written)
    assert on.attrs["profile_rounds"] == 1 < off.attrs["profile_rounds"]
    assert on.attrs["record_evaluations"] < off.attrs["record_evaluations"]
    _same_answer(on, off, params, scene)


@pytest.mark.slow  # (two identifications of the real slider on 4 DMW records: ~1 min on the shared 2 cores)
def test_twin_one_record_first_stage_agrees_with_the_two_record_one_within_the_tolerance(write_scene, paper_config,
                                                                                          tmp_path):
    # racing stages of 1, 2, 4 records against 2, 4: a candidate's first record alone is a partial ensemble,
    # bounded by the pooled record-to-record spreads of the whole evaluations (its own is unknown)
    path, scene, params, tl, prots, inputs, whole = _ensemble_twin(write_scene, paper_config, tmp_path)
    one, two = _identified_by(path, _twin_targets(tl, whole), "racing_records", ("1", "2"), tmp_path)
    assert one.attrs["racing"].startswith("stages of 1, 2, 4 DMW records")
    assert two.attrs["racing"].startswith("stages of 2, 4 DMW records")
    # some candidates stopped after their first record, and the pairs are the records held
    records = one["records"].values
    assert np.any(records == 1) and not np.any(two["records"].values == 1)
    assert one.attrs["record_evaluations"] == int(records.sum())
    # the best point ran on every record; a search trial stopped on one record has a partial objective above it
    assert records[int(one.attrs["best_evaluation"])] == 4
    first = (records == 1) & (one["role"].values == 1)
    assert first.any() and np.all(one["objective"].values[first] > one.attrs["best_objective"])
    # fewer (candidate, record) pairs (229 against 248 when written, the same best point)
    assert one.attrs["record_evaluations"] < two.attrs["record_evaluations"]
    # the same answer within the tolerance: each optimum inside the other's interval, the truth inside both, the
    # interval ends within one profile step
    _same_answer(one, two, params, scene)
