"""The profiles (pipeline/analyses/identification/profiles.py) on plain functions: a slice holds the other
parameters at the optimum, a profile re-optimises them; the interval's interpolated crossings; the compass poll
and the profile walk.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analyses import identification, study
from pipeline.analyses.identification import profiles
from identification_cases import OFFSET, PARAMS, RHO, _cfg, _identification, _quadratic


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


def test_a_compass_poll_keeps_inside_the_bounds_and_skips_the_profiled_parameter():
    lo, hi = np.array([0.0, 0.0, 10.0]), np.array([1.0, 2.0, 20.0])
    pts, polls = profiles.compass_poll(np.array([0.98, 1.0, 10.0]), 0.1, lo, hi, skip=1)
    # x0: +0.1 clipped to 1.0 (an offset of 0.02), -0.1; x2: +1 only (the lower bound cancels -1)
    assert polls == [(0, pytest.approx(0.02)), (0, pytest.approx(-0.1)), (2, pytest.approx(1.0))]
    # tol: clipping and one addition of exact decimals, a few roundings
    np.testing.assert_allclose(pts, [[1.0, 1.0, 10.0], [0.88, 1.0, 10.0], [0.98, 1.0, 11.0]])
    # the parabola through (-h, c-), (0, c0), (h, c+) has its vertex at h (c- - c+) / (2 (c- - 2 c0 + c+)):
    # c = (x - 0.3)^2 polled at 0 +- 1 gives 0.3; x1 (curving down) stays
    x = np.array([0.0, 0.0])
    _, polls = profiles.compass_poll(x, 0.5, np.array([-1.0, -1.0]), np.array([1.0, 1.0]))
    c = np.array([(1 - 0.3)**2, (-1 - 0.3)**2, -1.0, -1.0])
    # tol: the parabola's vertex of exact inputs, tens of roundings
    np.testing.assert_allclose(profiles.parabola_vertex(x, 0.09, polls, c, np.array([-1.0, -1.0]),
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

    w = profiles._Walk(0, np.array([0.6, 0.8]), start, np.array([1.0, 1.0, 0.0]), lo, hi, metric, 100.0, slice_at)
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
