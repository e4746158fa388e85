"""The compiled static Newton solve (pipeline.model.static_solver) against its definition, the Python
Newton of pipeline.physics.equilibrium.newton on the same forces: the same state to the Newton tolerance,
stiffness, convergence, stability and iteration count; and its 2x2 linear solve against numpy's.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.model import kernel_inputs
from pipeline.units import NM
from pipeline.model import static_solver
from pipeline.model.start import SCALE, static_forces
from pipeline.physics import equilibrium as eq
from slider_scenes import build, make_scene


#: modal damping 0.05: the slower mode (120 kHz) decays as exp(-zeta omega t), 1/(zeta omega) = 26.5 us,
#: so a 0.3 ms transient leaves exp(-11.3) ~ 1e-5 of the start's offset (< 1 nm) in the window
#: tolerances 1e3 below the scene's (rtol 1e-6, atol 1e-4 nm), whose own error in the window's exact
#: minimum is ~1e-3 nm (measured: the accuracy stage's rtol knob): the comparison is then of states,
#: not of integration errors (rtol 1e-9: 2e-6 nm in the minimum clearance at 5 nm)
SOLVER = {"duration_ms": 0.6, "transient_ms": 0.3, "rtol": 1e-9, "atol_nm": 1e-7}


#: Newton's convergence test (pipeline.physics.equilibrium.newton): updates below 1e-10 of the scale
NEWTON_TOL = 1e-10 * SCALE


def test_the_compiled_newton_reports_what_the_python_newton_reports():
    # the Equilibrium of one solve: state, stiffness, convergence, stability, iterations, residual
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact"), solver=SOLVER))
    R, flying, solve = static_forces(
        lambda mu: kernel_inputs.run_parameters(model, mu))
    for delta, y0, max_step in ((4 * NM, np.zeros(2), None), (12 * NM, np.array([1 * NM, 0.0]), 0.05 * SCALE)):
        c = solve(delta, y0, max_step=max_step, max_iter=200)
        p = eq.newton(lambda y: R(y, delta), y0, scale=SCALE, max_step=max_step, max_iter=200)
        assert c.converged and p.converged and c.stable == p.stable and c.iterations == p.iterations
        assert np.all(np.abs(c.y - p.y) <= NEWTON_TOL)
        np.testing.assert_allclose(c.stiffness, p.stiffness, rtol=1e-6)
        assert c.residual == pytest.approx(p.residual, abs=1e-12)
    # an unstable state (the saddle of the adhesion fold's other branch) is reported unstable by both:
    # Newton from deep below the flying state at a protrusion just before the fold
    fold = eq.branch_fold(R, 2 * model.p["FH0"], y_start=np.zeros(2), scale=SCALE, accept=flying, step=1 * NM,
                          mu_tol=1e-3 * NM, solve=solve)
    delta = fold - 0.05 * NM
    start = solve(delta, np.zeros(2)).y - np.array([0.5 * NM, 0.0])
    c = solve(delta, start, max_iter=200)
    p = eq.newton(lambda y: R(y, delta), start, scale=SCALE, max_iter=200)
    assert c.converged and p.converged and not c.stable and not p.stable
    assert np.all(np.abs(c.y - p.y) <= NEWTON_TOL)


def test_the_compiled_solve_of_two_equations():
    # the 2x2 solve (partial pivoting) against numpy's, a zero pivot reported as singular
    rng = np.random.default_rng(3)
    x = np.empty(2)
    for _ in range(200):
        J, b = rng.normal(size=(2, 2)) * 10.0 ** rng.integers(-6, 6, size=2), rng.normal(size=2)
        assert static_solver._solve2(J, b, x)
        # tol: the 200 seeded systems' componentwise condition is at most 4e3: < 10 eps x 4e3 either solve
        np.testing.assert_allclose(x, np.linalg.solve(J, b), rtol=1e-9)
    assert static_solver._solve2(np.array([[0.0, 1.0], [2.0, 0.0]]), np.array([1.0, 4.0]), x)  # needs the pivot
    np.testing.assert_array_equal(x, [2.0, 1.0])
    assert not static_solver._solve2(np.array([[1.0, 2.0], [2.0, 4.0]]), np.ones(2), x)
    assert not static_solver._solve2(np.zeros((2, 2)), np.ones(2), x)
    # and it runs without the GIL, like the kernel (the point of compiling it: parallel threads)
    assert static_solver._newton.targetoptions["nogil"]
