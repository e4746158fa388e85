"""Friction laws (pipeline.physics.friction; docs/model.md, sections "Single asperity", "Static friction of the
summits" and "Switched and continuous friction"): the shear strength ``tau_y = H / (2.8 sqrt 3)`` against a
hand value, the single-summit static-friction laws (Kogut-Etsion sliding inception, Brizmer-Kligerman-Etsion
full stick) at their limits, at the critical load and in their monotonicity, and the split of the friction
tables into the switched solid part and the continuous lubricant shear."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics import asperity, friction
from pipeline.physics.friction import FRICTION_LAWS, FRICTION_SWITCHING, friction_parts


# Hand-computed case: R = 1 um, E' = 100 GPa, H = 2 GPa, nu = 0.3 (K = 0.454 + 0.41*0.3 = 0.577)
R, E, H, NU = 1e-6, 100e9, 2e9, 0.3


def test_shear_strength_and_friction_force():
    # tau_y = H / (2.8 sqrt 3) = 2e9 / 4.849742 = 4.123930e8 Pa (docs/model.md, section "Single asperity")
    assert friction.shear_strength(H) == pytest.approx(4.123930e8, rel=1e-6)
    A = np.array([0.0, 1e-15])
    np.testing.assert_allclose(friction.friction_force(A, H), [0.0, 4.123930e8 * 1e-15], rtol=1e-6)
    with pytest.raises(ValueError, match="friction law"):
        friction.friction_force(A, H, law="coulomb")


def test_friction_parts_split_or_sum_the_lubricant_shear():
    solid = np.array([0.0, 1.0e6, 3.0e8])
    lub = np.array([2.0e6, 0.5e6, 0.1e6])
    switched, always = friction_parts("criterion", solid, lub)
    np.testing.assert_array_equal(switched, solid + lub)  # (what build_model summed before the option)
    assert always is None
    switched, always = friction_parts("continuous", solid, lub)
    np.testing.assert_array_equal(switched, solid)
    np.testing.assert_array_equal(always, lub)
    for how in FRICTION_SWITCHING:  # without the lubricant term both are the switched solid friction
        switched, always = friction_parts(how, solid, None)
        assert switched is solid and always is None
    with pytest.raises(ValueError, match="contact.friction_switching = 'sometimes'"):
        friction_parts("sometimes", solid, lub)


# --------------------------------------------------------------------------------------------
# Static friction of one summit: Kogut-Etsion sliding inception, Brizmer-Kligerman-Etsion full stick
# --------------------------------------------------------------------------------------------

WC = asperity.critical_interference(R, E, H, NU)
LC = asperity.critical_load(R, E, H, NU)


def _ke(x):
    return friction.ke_sliding_inception(np.asarray(x, dtype=float) * WC, R, E, H, NU)


def test_ke_sliding_inception_at_the_critical_load_and_its_limits():
    (c, e), (a2, a1, a0) = friction.KE_SLIDING_FITS
    # at the critical interference (the elastic branch's end) Q_max = c L_c: mu = c there (P = L_c)
    # tol: a power of 1.0 and two products: a few roundings, no libm difference (1 ** e is exact)
    assert _ke(1.0) == pytest.approx(c * LC, rel=1e-12)
    # tol: the Hertz load at w_c is L_c within the roundings of w_c^1.5 and the KE02 constants (~10 eps)
    assert _ke(1.0) / asperity.contact_load(WC, R, E, H, NU) == pytest.approx(c, rel=1e-12)
    # light load: Q_max ~ x^e (the ratio of two small interferences)
    # tol: two pow calls (a few ulps each, on any libm) and a division
    assert _ke(1e-3) / _ke(1e-4) == pytest.approx(10.0**e, rel=1e-12)
    # just past w_c the elastic-plastic branch: a2 + a1 + a0, within 10 % of the elastic one (as the KE02 fits)
    # tol: the quadratic moves by ~(2 a2 + a1) 1e-12 relative between x = 1 and 1 + 1e-12, below 1e-9
    assert _ke(1.0 + 1e-12) == pytest.approx((a2 + a1 + a0) * LC, rel=1e-9)
    assert abs(_ke(1.0 + 1e-12) / _ke(1.0) - 1.0) < 0.1
    # the limiting preload: the branch's root (x = 12.26), above which the summit sustains no tangential load
    xl = friction.ke_limiting_interference()
    assert xl == pytest.approx(12.262087, rel=1e-6) and a2 * xl**2 + a1 * xl + a0 == pytest.approx(0.0, abs=1e-12)
    assert _ke(xl * (1 - 1e-9)) == pytest.approx(0.0, abs=1e-8 * LC) and _ke(xl * (1 + 1e-9)) == 0.0
    # none without contact, none from fully plastic summits
    np.testing.assert_array_equal(_ke([-1.0, 0.0, 50.0, 110.0, 111.0, 1e4]), 0.0)


def test_ke_friction_coefficient_falls_with_load():
    # the summit's coefficient Q_max / P decreases monotonically with its load over the range it carries any
    x = np.geomspace(1e-4, friction.ke_limiting_interference() * 0.999, 2001)
    mu = _ke(x) / asperity.contact_load(x * WC, R, E, H, NU)
    assert np.all(np.diff(mu) < 0)
    assert np.all(_ke(x) > 0)
    # in the elastic range the law is within 6 % of the shear strength times the Hertz area: sliding
    # inception there is failure on the contact area, where the shear yields at tau_y = Y / sqrt(3)
    xe = np.geomspace(1e-2, 1.0, 50)
    ratio = _ke(xe) / (friction.shear_strength(H) * asperity.hertz_area(xe * WC, R))
    assert np.all(np.abs(ratio - 1.0) < 0.06)


def test_bke_friction_coefficient_limits_and_value_at_the_critical_load():
    a, e = friction.BKE_STICK_FIT
    # at the critical load: a coth(a) = 0.27 / tanh(0.27) = 1.024183
    # tol: the same operations (1 ** e exact, one tanh, one division) on the same numbers
    assert friction.bke_friction_coefficient(1.0) == pytest.approx(a / np.tanh(a), rel=1e-14)
    assert friction.bke_friction_coefficient(1.0) == pytest.approx(1.024183, rel=1e-6)
    # heavy load: the asymptote a; light load: P*^(-e) (coth y ~ 1/y)
    # tol: tanh(a 1e12^e) is 1 to the last bit (its argument is ~4e3): a / 1 within one rounding
    assert friction.bke_friction_coefficient(1e12) == pytest.approx(a, rel=1e-12)
    assert friction.bke_friction_coefficient(1e-10) * 1e-10**e == pytest.approx(1.0, rel=1e-6)
    P = np.geomspace(1e-6, 1e4, 1001)
    mu = friction.bke_friction_coefficient(P)
    assert np.all(np.diff(mu) < 0) and np.all(mu > a)
    assert np.all(np.diff(mu * P) > 0)  # the tangential load itself rises with the normal load


def test_bke_full_stick_per_summit():
    x = np.array([0.3, 1.0, 5.0, 100.0])
    P = asperity.contact_load(x * WC, R, E, H, NU)
    Q = friction.bke_full_stick(x * WC, R, E, H, NU)
    # tol: the same operations on the same numbers (a division and a product more at most: 2 eps)
    np.testing.assert_allclose(Q, friction.bke_friction_coefficient(P / LC) * P, rtol=1e-14)
    assert Q[1] == pytest.approx(1.024183 * LC, rel=1e-6)  # at w_c, P = L_c
    x = np.geomspace(1e-4, 110.0, 3001)
    Q = friction.bke_full_stick(x * WC, R, E, H, NU)
    # rising with load within each branch (the contact law's own steps at x = 1 and 6 aside)
    for lo, hi in ((0, 1), (1, 6), (6, 110)):
        m = (x > lo) & (x <= hi)
        assert np.all(np.diff(Q[m]) > 0)
    np.testing.assert_array_equal(friction.bke_full_stick(np.array([-1.0, 0.0, 110.5, 1e3]) * WC, R, E, H, NU), 0.0)


def test_per_summit_laws_read_their_own_table():
    p_c = np.array([0.0, 1e6, 5e8])
    tab = np.array([0.0, 2e5, 3e8])
    for name in ("kogut-etsion", "brizmer-kligerman-etsion"):
        law = FRICTION_LAWS.lookup(name)
        assert law.summit is not None
        assert friction.friction_stress_table(name, p_c, tab) is tab
    for name in ("shear-strength", "coefficient"):
        assert FRICTION_LAWS.lookup(name).summit is None
    assert FRICTION_LAWS["kogut-etsion"].summit.breaks() == (friction.ke_limiting_interference(),)
    assert FRICTION_LAWS["brizmer-kligerman-etsion"].summit.breaks() == ()
