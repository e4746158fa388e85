"""The TFC-point laws (pipeline.physics.tfc_laws): the gap-power stiffening spring is zero at the nominal gap, its
stiffness is minus the derivative of its force and k_t [(g0/g)^p - 1] in closed form, and below the floor it
continues linearly with the floor's slope."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics import tfc_laws

G0, K_T = 5.0e-9, 2.0e5  # FH0 [m], stiffness scale [N/m]


@pytest.mark.parametrize("p", [0.5, 1.0, 2.0])
def test_the_force_is_zero_at_the_nominal_gap_and_its_stiffness_is_minus_its_derivative(p):
    g_n = G0 - 1.0e-9
    F, k = tfc_laws.tfc_stiffening_force(np.array([g_n]), g_n, G0, K_T, p)
    assert F[0] == 0.0
    g = np.linspace(1.0e-9, 8.0e-9, 15)
    h = 1.0e-13
    up, _ = tfc_laws.tfc_stiffening_force(g + h, g_n, G0, K_T, p)
    down, _ = tfc_laws.tfc_stiffening_force(g - h, g_n, G0, K_T, p)
    _, k = tfc_laws.tfc_stiffening_force(g, g_n, G0, K_T, p)
    # tol: a central difference of step 1e-13 m on a force of ~1e-4 N: truncation ~h^2 k'', rounding ~1e-16 F / h
    np.testing.assert_allclose(-(up - down) / (2 * h), k, rtol=1e-5, atol=1e-3)
    # tol: the closed form by the same operations
    np.testing.assert_allclose(k, K_T * ((G0 / g) ** p - 1.0), rtol=1e-14)
    delta = G0 - g_n
    assert np.array_equal(tfc_laws.gap_power_force(g, delta, G0, K_T, p),
                          tfc_laws.tfc_stiffening_force(g, G0 - delta, G0, K_T, p)[0])


def test_below_the_floor_the_force_continues_linearly_with_the_floors_stiffness():
    floor = tfc_laws.TFC_MIN_GAP * G0
    g = np.array([0.0, 0.25 * floor, 0.5 * floor, floor])
    F, k = tfc_laws.tfc_stiffening_force(g, G0, G0, K_T, 1.5)
    k_floor = tfc_laws.stiffening_stiffness(floor, G0, K_T, 1.5)
    assert np.all(k[:3] == k_floor)
    # tol: a force of ~1e-3 N as a sum of two terms of its size: a few roundings
    np.testing.assert_allclose(np.diff(F), -k_floor * np.diff(g), rtol=1e-9)
    assert np.all(np.diff(F) < 0)  # the force falls as the gap opens


def test_the_registry_holds_the_gap_power_law_and_the_option_without_one():
    law = tfc_laws.TFC_STIFFENING.lookup("gap-power")
    assert law.behaviour is law and law.force is tfc_laws.gap_power_force and law.closed_form == "gap-power"
    assert tfc_laws.TFC_STIFFENING.lookup("none") is tfc_laws.NO_TFC_LAW and tfc_laws.NO_TFC_LAW.force is None
