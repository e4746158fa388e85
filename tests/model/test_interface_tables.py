"""The interface parameters of a scene (pipeline.model.interface_tables; docs/model.md, section "Plasticity
index"): the hardness derived from a fixed plasticity index, ``H = E'/psi sqrt(sigma_s/R)``,
against the paper's numbers, with a warning when it is outside physical bounds."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import pytest

from pipeline.config.scene import load_scene
from pipeline.model import interface_tables
from pipeline.physics.material_bounds import PhysicsWarning

PAPER = Path(__file__).resolve().parents[2] / "configs" / "paper-2009.toml"


def test_hardness_derived_from_a_fixed_psi_outside_physical_bounds_warns():
    """The paper's psi = 0.52 with the statistics of the di-5 AFM scan (sigma_s = 1.53 nm,
    R = 14.7 nm) implies H = E'/psi sqrt(sigma_s/R) = 58.5 GPa > 0.3 E'."""
    scene = load_scene(PAPER)
    stats = {"sigma": 1.6e-9, "sigma_s": 1.53e-9, "y_s": 0.5e-9, "R": 14.7e-9, "eta": 1e15, "alpha": 3.0}
    with pytest.warns(PhysicsWarning, match=r"H = 58\.\d GPa \(derived from materials.plasticity_index = 0.52"):
        p = interface_tables.interface_parameters(scene, stats)
    assert p.E / 1e9 == pytest.approx(94.19, rel=1e-3)     # E' of the paper's materials (tests/physics/test_asperity_statistics.py)
    # tol: H is set from psi = 0.52: a round trip of a few roundings and a sqrt
    assert p.H == pytest.approx(p.E / 0.52 * math.sqrt(1.53 / 14.7), rel=1e-12)
    # the paper's own statistics give H = 1.68 GPa = 0.018 E': no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", PhysicsWarning)
        interface_tables.interface_parameters(scene, interface_tables.roughness_statistics(scene))


IDENTIFIED = Path(__file__).resolve().parents[2] / "configs" / "paper-2009-identified.toml"


def test_solid_work_of_adhesion_changes_the_adhesion_table_alone():
    """lubricant.solid_work_of_adhesion_j_m2 reaches the tables through the interface parameters: at the lubricant's
    own value every table is today's bit for bit; above it only the adhesion columns rise, by the closed form of
    pipeline.physics.isbl.penetration_adhesion at the scene's parameters."""
    import numpy as np
    from pipeline.physics import isbl
    base = load_scene(IDENTIFIED)
    stats = interface_tables.roughness_statistics(base)
    today = interface_tables.build_tables(base, stats)
    w = base["lubricant"]["work_of_adhesion_j_m2"]
    same = interface_tables.build_tables(load_scene(IDENTIFIED, [f"lubricant.solid_work_of_adhesion_j_m2={w}"]), stats)
    assert float(same["solid_work_of_adhesion"]) == w
    for name, var in today.data_vars.items():
        assert np.array_equal(var.values, same[name].values), name
    scene = load_scene(IDENTIFIED, ["lubricant.solid_work_of_adhesion_j_m2=0.149"])
    more = interface_tables.build_tables(scene, stats)
    changed = {n for n, v in today.data_vars.items() if not np.array_equal(v.values, more[n].values)}
    assert changed == {"adhesion_pressure", "adhesion_pressure_bridges", "adhesion_pressure_menisci"}
    p = interface_tables.interface_parameters(scene, stats)
    b, m = isbl.penetration_adhesion(today["separation"].values * 1e-9, p)
    # tol: a difference of two tables (~3 MPa) against their closed-form change: the cancellation costs ~table / change (<1e3) eps, far below 1e-9
    np.testing.assert_allclose((more["adhesion_pressure"] - today["adhesion_pressure"]).values * 1e6, b + m,
                               rtol=1e-9, atol=1e-9 * (b + m).max())
