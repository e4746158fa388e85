"""The identification (pipeline/analyses/identification.py) on plain functions: the profile intervals (a slice
holds the other parameters at the optimum, a profile re-optimises them; issue 26, item 5), the interval's
interpolated crossings, and the whole search on any evaluation callable (no stage, store or fan-out)."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analyses import identification, study

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


def _cfg(method: str = "optimised", budget: int = 80, points: int = 25) -> dict:
    return {"generations": 3, "population": 5, "seed": 1, "profile_points": points, "profile_method": method,
            "profile_evaluations": budget}


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
        out = identification.identify(ident, PARAMS, np.zeros(2), _cfg(budget=budget, points=13))
        roles = np.array(list(ident.roles.values()))
        n4 = int(np.sum(roles == 4))
        assert n4 == out["profile_optimiser_evaluations"] <= 2 * budget
        assert identification.ROLES[4] == "profile-optimiser"
        # the rest is what a slice costs: its points (the grid holds the optimum, the reconstructed point) and
        # Gauss-Newton
        assert np.sum(roles == 2) == 2 * (13 - 1) and np.sum(roles == 3) == 2 * 2
    # 3 evaluations buy one point per parameter: its prediction and the poll around it (1 + 2 x (2 - 1))
    ident = _identification(_quadratic)
    out = identification.identify(ident, PARAMS, np.zeros(2), _cfg(budget=3, points=13))
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
                                   "profile_method": "optimised", "profile_evaluations": 40})
    assert out["within"] and abs(10.0 * out["best"][0] - 9.0) <= 1.0
    # the interval of the first parameter is where |10 x - 9| <= 1; the second is seen by no target
    assert out["intervals"][0] == pytest.approx([0.8, 1.0], abs=1e-9)
    assert np.isinf(out["gn_std"][1]) and np.all(np.isnan(out["correlation"][1]))
    assert ident.roles[ident.keys[0]] == 0 and len(ident.records) == len(set(ident.keys))
