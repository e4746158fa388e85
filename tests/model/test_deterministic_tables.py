"""Deterministic interface tables (pipeline.model.deterministic_tables; docs/deterministic_interface.md):
the combined AFM height map has zero mean and the scan's lateral sizes; the tables of the FFT contact solve
follow the hard-wall elastic problem's invariants: the pressure is proportional to E' (the solve is in units
of E'), the friction stress is the shear strength times the real-area fraction (every solved contact slides
at tau_y), pressure and area fall as the separation opens, and first contact is at the highest point of the
map above the summit datum y_s.

A real scan (tests/data/afm/di-3.di) at 32 points a side keeps the solve to seconds.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.config.scene import scene_from_dict
from pipeline.model import afm_scan
from pipeline.model import deterministic_tables as dt
from pipeline.physics.friction import shear_strength

NM = 1e-9
E, H, Y_S = 94e9, 5e9, 0.7e-9   # [Pa], [Pa], [m]
WANTED = ("contact_pressure", "real_area_fraction", "friction_stress")
D = np.linspace(-1.0, 5.0, 13) * NM


@pytest.fixture(scope="module")
def scene(repo_root):
    return scene_from_dict({"roughness": {"afm": [str(repo_root / "tests" / "data" / "afm" / "di-3.di")]},
                            "solver": {"contact_grid_points": 32}})


@pytest.fixture(scope="module")
def tables(scene):
    return dt.deterministic_tables(scene, Y_S, E, H, D, WANTED)


def test_combined_topography_has_zero_mean_and_the_scans_sizes(scene):
    h, sizes = dt.combined_topography(scene, 32)
    assert h.shape == (32, 32) and abs(h.mean()) < 1e-12 * h.std()
    scan = afm_scan.read_topography(scene["roughness"]["afm"][0], channel=scene["roughness"]["channel"],
                                    detrend_mode=scene["roughness"]["detrend"])
    # tol: the same sizes through a unit conversion, a few roundings
    assert sizes == pytest.approx(tuple(float(s) for s in scan.physical_sizes), rel=1e-12)


def test_no_scans_is_an_error_naming_the_key():
    with pytest.raises(ValueError, match=r"interface\.model = 'deterministic' needs measured surfaces: set "
                                         r"roughness\.afm"):
        dt.combined_topography(scene_from_dict({}), 32)


def test_friction_is_the_shear_strength_on_the_real_area(tables):
    t, _ = tables
    assert set(t) == set(WANTED)
    np.testing.assert_array_equal(t["friction_stress"], shear_strength(H) * t["real_area_fraction"])


def test_pressure_and_area_fall_as_the_gap_opens(tables):
    t, solved = tables
    assert np.all(np.diff(t["contact_pressure"]) <= 0) and np.all(np.diff(t["real_area_fraction"]) <= 0)
    assert np.all((t["real_area_fraction"] >= 0) & (t["real_area_fraction"] <= 1))
    assert np.all(np.diff(solved["separation"]) < 0) and np.all(np.diff(solved["contact_pressure"]) > 0)
    assert not solved["skipped"] and solved["grid"] == (32, 32)


def test_first_contact_is_the_highest_point_above_the_datum(scene, tables):
    _, solved = tables
    h, _ = dt.combined_topography(scene, 32)
    # tol: a maximum and a subtraction of the same map, a few roundings (cancellation < 10)
    assert solved["first_contact"] == pytest.approx((h.max() - Y_S / NM) * NM, rel=1e-9)


def test_pressure_scales_with_the_modulus_and_wanted_filters(scene, tables):
    t, _ = tables
    t2, _ = dt.deterministic_tables(scene, Y_S, 2 * E, H, D, ("contact_pressure",))
    assert set(t2) == {"contact_pressure"}
    # tol: the contact solve is linear in E: twice E, twice the pressure up to the solver's rounding
    np.testing.assert_allclose(t2["contact_pressure"], 2 * t["contact_pressure"], rtol=1e-12)
