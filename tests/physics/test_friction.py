"""Friction laws (pipeline.physics.friction; docs/model.md, sections "Single asperity" and "Switched and
continuous friction"): the shear strength ``tau_y = H / (2.8 sqrt 3)`` against a hand value, and the split
of the friction tables into the switched solid part and the continuous lubricant shear."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics import friction
from pipeline.physics.friction import FRICTION_SWITCHING, friction_parts


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
