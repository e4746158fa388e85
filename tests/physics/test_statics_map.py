"""The statics map's equilibria (pipeline.physics.statics_map) on a force with a known potential: the double well
``f(u) = u - u^3`` (``V = u^4/4 - u^2/2``) has stable states at -1 and 1, an unstable one at 0 and barriers of 1/4,
and a force that jumps through zero at a break holds a switch state there."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics.statics_map import path_equilibria


def test_the_double_well_has_its_three_states_their_stability_and_barriers():
    states = path_equilibria(lambda u: u - u**3, np.linspace(-1.7, 1.75, 70), xtol=1e-12)
    assert [s.stable for s in states] == [True, False, True] and not any(s.switch for s in states)
    # tol: Brent's method to xtol = 1e-12 on simple zeros of slope -2 and 1
    np.testing.assert_allclose([s.u for s in states], [-1.0, 0.0, 1.0], rtol=0, atol=1e-11)
    # the potential from the first state: V(0) - V(-1) = 1/4, V(1) - V(-1) = 0 (adaptive quadrature of a cubic)
    assert states[0].potential == 0.0
    assert states[1].potential == pytest.approx(0.25, abs=1e-10)
    assert states[2].potential == pytest.approx(0.0, abs=1e-10)
    assert states[0].barrier == pytest.approx(0.25, abs=1e-10) and states[2].barrier == pytest.approx(0.25, abs=1e-10)
    assert np.isnan(states[1].barrier)  # (an unstable state has none)


def test_a_force_that_jumps_through_zero_at_a_break_holds_a_switch_state_there():
    # pushing up below 0.5, down above it: the one equilibrium is on the break, stable, a single well
    states = path_equilibria(lambda u: 1.0 if u < 0.5 else -1.0, np.linspace(0.0, 1.0, 11), breaks=(0.5,))
    assert len(states) == 1 and states[0].switch and states[0].stable and states[0].u == 0.5
    assert np.isnan(states[0].barrier)
