"""The paper's TFC footprint, pad pressure, air and disk speed, and a coarse Reynolds solve of it, for the tests
of the bulge's air bearing (pipeline/physics/bulge_bearing.py, pipeline/physics/reynolds.py)."""

from __future__ import annotations

import numpy as np

from pipeline.physics import reynolds as rey

NM, UM = 1e-9, 1e-6
A_SEMI, B_SEMI = 3 * UM, 25 * UM  # the paper's TFC footprint semi-axes
P_PAD = 1e6
PAB = P_PAD * np.pi * A_SEMI * B_SEMI
#: air at 20 C: viscosity [Pa s], mean free path at 1 atm [m]; the paper's disk speed [m/s]
AIR = dict(viscosity=1.81e-5, mean_free_path=65e-9, ambient_pressure=101325.0)
U = 19.5
COARSE = rey.ReynoldsGrid(cells_per_a=16, cells_per_b=8)


def solve(g, delta, **kw):
    args = dict(p_pad=P_PAD, a=A_SEMI, b=B_SEMI, speed=U, grid=COARSE, **AIR)
    args.update(kw)
    return rey.reynolds_solve(g, delta, **args)
