"""Single-summit adhesion (pipeline.physics.adhesion; docs/model.md, section "Single asperity"): the
meniscus force ``2 pi R dgamma`` and the Lennard-Jones force that joins it at ``s = eps``, against hand
values."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics import adhesion


# Hand-computed case: R = 1 um, E' = 100 GPa, H = 2 GPa, nu = 0.3 (K = 0.454 + 0.41*0.3 = 0.577)
R, E, H, NU = 1e-6, 100e9, 2e9, 0.3


DG, EPS = 0.106, 0.3e-9


def test_meniscus_force_hand_value():
    # 2 pi R dgamma = 2 pi * 1e-6 * 0.106 = 6.660176e-7 N
    assert adhesion.meniscus_force(R, DG) == pytest.approx(6.660176e-7, rel=1e-6)


def test_lennard_jones_joins_meniscus_at_eps():
    # (8/3) pi dgamma R (1 - 1/4) = 2 pi R dgamma at s = eps (docs/model.md, section "Single asperity": "joins continuously")
    # tol: the law at its join is the meniscus force, a few roundings
    assert adhesion.lennard_jones_force(EPS, R, DG, EPS) == pytest.approx(
        adhesion.meniscus_force(R, DG), rel=1e-14)


def test_lennard_jones_hand_value_and_bound():
    # s = 2 eps: (8/3) pi 0.106 * 1e-6 * (1/4 - 1/1024) = 8.880236e-7 * 0.2490234 = 2.211387e-7 N
    # tol: the law's closed form at 2 eps, a few roundings
    assert adhesion.lennard_jones_force(2 * EPS, R, DG, EPS) == pytest.approx(
        8 / 3 * np.pi * DG * R * (0.25 - 0.25 / 256), rel=1e-14)
    assert adhesion.lennard_jones_force(2 * EPS, R, DG, EPS) == pytest.approx(2.211387e-7, rel=1e-6)
    s = EPS * np.logspace(0, 3, 200)
    F = adhesion.lennard_jones_force(s, R, DG, EPS)
    assert np.all(F <= adhesion.meniscus_force(R, DG) * (1 + 1e-14))
    assert np.all(np.diff(F) < 0)          # decays monotonically beyond s = eps
    # gaps below eps are clamped (no s^-8 overflow)
    assert adhesion.lennard_jones_force(0.0, R, DG, EPS) == pytest.approx(adhesion.meniscus_force(R, DG))


# --------------------------------------------------------------------------------------------
# Work of adhesion rising with penetration into the bonded layer
# --------------------------------------------------------------------------------------------

def test_penetration_work_of_adhesion_ramps_across_the_bonded_layer():
    """W(p) = dgamma at and above the film surface, dgamma_solid at and beyond the solid, linear between."""
    t, w0, ws = 0.75e-9, 0.109, 0.12
    p = np.array([-1e-9, 0.0, 0.25 * t, 0.5 * t, t, 3 * t])
    W = adhesion.penetration_work_of_adhesion(p, t, w0, ws)
    assert W[0] == W[1] == w0
    assert W[4] == W[5] == ws
    # tol: a linear ramp in a few IEEE roundings, no libm
    assert W[2] == pytest.approx(w0 + 0.25 * (ws - w0), rel=1e-15)
    # tol: a linear ramp in a few IEEE roundings, no libm
    assert W[3] == pytest.approx(0.5 * (w0 + ws), rel=1e-15)
    # equal values: the lubricant's everywhere, exactly
    assert np.array_equal(adhesion.penetration_work_of_adhesion(p, t, w0, w0), np.full(p.shape, w0))
    # a film of zero thickness: a step at the solid
    np.testing.assert_array_equal(adhesion.penetration_fraction(np.array([-1e-12, 0.0, 1e-12]), 0.0), [0, 0, 1])
