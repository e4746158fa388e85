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
