"""Physical bounds of derived material parameters (pipeline.physics.material_bounds.check_materials): a
hardness or plasticity index outside its bounds warns with the numbers (``H/E'``, ``psi``), one warning per
quantity out of bounds."""

from __future__ import annotations

import pytest

from pipeline.physics.material_bounds import PhysicsWarning, check_materials


def test_plasticity_index_derived_from_a_given_hardness_outside_bounds_warns():
    E, sigma_s, R = 94e9, 0.4e-9, 5e-6
    # H = 0.01 GPa: H/E' = 1.1e-4 and psi = 9400 * sqrt(8e-5) = 84 (inside 0.05-100): only the hardness warns
    with pytest.warns(PhysicsWarning) as rec:
        check_materials(E, 0.01e9, sigma_s, R, derived="plasticity_index")
    assert len(rec) == 1 and "0.000106 E'" in str(rec[0].message)
    # a very smooth, very hard pair: psi = (94/20) sqrt(1e-12/1e-4) = 4.7e-4 < 0.05
    with pytest.warns(PhysicsWarning, match=r"psi = 0.00047 .* outside 0.05-100"):
        check_materials(E, 20e9, 1e-12, 1e-4, derived="plasticity_index")
