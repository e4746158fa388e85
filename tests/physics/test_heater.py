"""The heater's actuation (pipeline.physics.heater; docs/model.md, section "Heater power"): power to
protrusion and back are inverses (linear law and table), a table is linear between its rows, and a table
that is not monotonic, a power outside its rows or a negative value is refused."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, strategies as st

from pipeline.physics import heater

MW, NM = 1e-3, 1e-9


@given(st.floats(1e-3, 10.0), st.floats(0.0, 500.0))
def test_the_linear_law_and_its_inverse_give_back_the_power(eff_nm_per_mw, p_mw):
    act = heater.linear(eff_nm_per_mw * 1e-6)
    d = act.protrusion_of(p_mw * MW)
    # tol: the same product in another order: two roundings
    assert float(d) == pytest.approx(eff_nm_per_mw * p_mw * NM, rel=1e-12)
    # tol: the product divided back: two roundings
    assert float(act.power_of(d)) == pytest.approx(p_mw * MW, rel=1e-12, abs=1e-300)


def test_a_table_is_linear_between_its_rows_and_inverted_exactly_at_them():
    power = np.array([0.0, 40.0, 80.0, 120.0]) * MW
    prot = np.array([0.0, 5.0, 9.0, 11.0]) * NM          # a falling efficiency: 0.125, 0.1, 0.05 nm/mW
    act = heater.tabulated(power, prot)
    # tol: np.interp at a row returns the row value exactly (slope times a zero offset); both directions
    np.testing.assert_allclose(act.protrusion_of(power), prot, rtol=0, atol=0)
    # tol: np.interp at a row returns the row value exactly, in this direction too
    np.testing.assert_allclose(act.power_of(prot), power, rtol=0, atol=0)
    # tol: linear interpolation halfway along a row of round numbers: a few roundings
    assert float(act.protrusion_of(60.0 * MW)) == pytest.approx(7.0 * NM, rel=1e-14)   # halfway along row 2-3
    # tol: linear interpolation halfway along a row of round numbers: a few roundings
    assert float(act.power_of(10.0 * NM)) == pytest.approx(100.0 * MW, rel=1e-14)
    p = np.linspace(0.0, 120.0, 241) * MW
    # tol: two linear interpolations back and forth: a few roundings each
    np.testing.assert_allclose(act.power_of(act.protrusion_of(p)), p, rtol=1e-12, atol=1e-18)


@pytest.mark.parametrize("power, prot, message", [
    ([0.0, 50.0, 40.0], [0.0, 5.0, 6.0], "power is not strictly increasing at row 3 of 3"),
    ([0.0, 50.0, 100.0], [0.0, 6.0, 6.0], "protrusion is not strictly increasing at row 3 of 3"),
    ([0.0, 50.0, 100.0], [0.0, 7.0, 5.0], "protrusion is not strictly increasing at row 3 of 3"),
    ([0.0, 50.0], [0.0, 5.0, 9.0], "2 powers and 3 protrusions"),
    ([10.0], [1.0], "at least 2 rows"),
    ([-1.0, 50.0], [0.0, 5.0], "a power is negative or not finite"),
])
def test_a_table_that_is_not_monotonic_or_not_a_table_is_refused(power, prot, message):
    with pytest.raises(ValueError, match=message):
        heater.tabulated(np.array(power) * MW, np.array(prot) * NM)


def test_nothing_is_extrapolated_and_a_negative_power_or_efficiency_is_refused():
    act = heater.tabulated(np.array([10.0, 50.0]) * MW, np.array([1.0, 5.0]) * NM)
    with pytest.raises(ValueError, match="outside the actuation table"):
        act.protrusion_of(60.0 * MW)
    with pytest.raises(ValueError, match="outside the actuation table"):
        act.power_of(0.5 * NM)
    assert heater.within(np.array([10.0, 50.0]) * MW, act.power) and not heater.within(9.0 * MW, act.power)
    with pytest.raises(ValueError, match="negative"):
        heater.linear(1e-7).protrusion_of(-1.0 * MW)
    for bad in (0.0, -1e-7, np.nan):
        with pytest.raises(ValueError, match="expected a positive number"):
            heater.linear(bad)
