"""The bulge lift table (pipeline.model.bulge_table): declared variables, the closed-form table, the Reynolds
table read back at an off-grid protrusion and gap against direct solves, and the file round trip."""

from __future__ import annotations

import numpy as np
import pytest

from cf_check import cf_report
from pipeline.model import bulge_table as bt
from pipeline import variables as vs
from pipeline.io import read_dataset, write_dataset
from pipeline.physics import bulge_bearing as bb, reynolds

NM, UM = 1e-9, 1e-6
PAPER = dict(p_pad=1e6, a=3 * UM, b=25 * UM, speed=19.5)
COARSE = reynolds.ReynoldsGrid(cells_per_a=16, cells_per_b=8)


@pytest.fixture(scope="module")
def reynolds_ds():
    return bt.bulge_table(model="reynolds", gaps=bt.table_gaps(0.05, 20.0, 17),
                          protrusions=bt.table_protrusions(12.0, 1.0), grid=COARSE, **PAPER)


def test_every_variable_is_declared_with_its_units(reynolds_ds):
    for name in list(reynolds_ds.coords) + list(reynolds_ds.data_vars):
        decl = vs.declared("bulge", name)
        assert reynolds_ds[name].attrs.get("units", "") == decl.units, name
        assert reynolds_ds[name].attrs["long_name"] == decl.long_name


def test_ph_limit_table_is_the_closed_form():
    gaps, dls = bt.table_gaps(), bt.table_protrusions()
    ds = bt.bulge_table(model="ph-limit", gaps=gaps, protrusions=dls, **PAPER)
    F, k = bb.ph_lift(gaps[None, :], dls[:, None], 1e6, 3 * UM, 25 * UM)
    assert np.array_equal(ds["bulge_lift"].values, F / 1e-3)
    assert np.array_equal(ds["bulge_stiffness"].values, k)
    assert ds["protrusion"].values[[0, -1]].tolist() == pytest.approx([0.0, 15.0])
    assert ds["apex_gap"].values[[0, -1]].tolist() == pytest.approx([0.05, 20.0])
    assert np.all(ds["bulge_lift"].values[0] == 0)  # zero protrusion, zero lift


def test_reynolds_table_read_back_off_grid_matches_direct_solves(reynolds_ds):
    """At a protrusion between rows and gaps between nodes, lift and stiffness interpolated from the table
    (ratio to the closed form, :func:`pipeline.model.bulge_table.lift_at`) match direct solves: lift to 1e-3,
    stiffness (against central differences of solves) to 1e-2."""
    dl, g = 9.7 * NM, np.array([0.8, 1.3, 1.7, 4.2]) * NM
    F, k = bt.lift_at(reynolds_ds, g, dl)
    kw = dict(profile="ellipsoid", grid=COARSE, viscosity=bt.AIR_VISCOSITY, mean_free_path=bt.AIR_MEAN_FREE_PATH,
              ambient_pressure=bt.AMBIENT_PRESSURE, **PAPER)
    direct = reynolds.reynolds_solve(g, dl, **kw)["lift"]
    assert F == pytest.approx(direct, rel=1e-3)
    h = 1e-3 * g
    fd = -(reynolds.reynolds_solve(g + h, dl, **kw)["lift"] - reynolds.reynolds_solve(g - h, dl, **kw)["lift"]) / (2 * h)
    assert k == pytest.approx(fd, rel=1e-2)
    # and the lift's stiffness is that of the table's own variable at its nodes
    i = int(np.argmin(np.abs(reynolds_ds["protrusion"].values - 10.0)))
    nodes = reynolds_ds["apex_gap"].values * NM
    Fn, kn = bt.lift_at(reynolds_ds, nodes[1:-1], 10.0 * NM)
    # tol: the table's nodes read back through its spline and a unit product, a few roundings
    assert Fn * 1e3 == pytest.approx(reynolds_ds["bulge_lift"].values[i, 1:-1], rel=1e-12)
    # tol: the spline's slope at its nodes against the stored stiffness, tens of roundings of the slope
    assert kn == pytest.approx(reynolds_ds["bulge_stiffness"].values[i, 1:-1], rel=1e-9)


def test_reynolds_table_is_near_the_ph_limit_at_the_paper_speed(reynolds_ds):
    """At 19.5 m/s and 1 MPa the bearing number of the pad gap is ~50 and the lift within a few per
    cent of the p h = const limit (measured ratios 0.98-1.03 over the table at gaps below 11 nm)."""
    r = (reynolds_ds["bulge_lift"] / reynolds_ds["bulge_lift_ph_limit"]).values[1:]
    small = reynolds_ds["apex_gap"].values < 11.0
    assert np.all(np.abs(r[:, small] - 1) < 0.04)


def test_file_round_trip_is_cf_clean(reynolds_ds, tmp_path):
    path = write_dataset(reynolds_ds, tmp_path / "bulge.nc", stage="bulge")
    back = read_dataset(path)
    # tol: NetCDF stores float64 as it is: exact
    assert np.allclose(back["bulge_lift"].values, reynolds_ds["bulge_lift"].values, rtol=0, atol=0)
    failures, raised = cf_report(path)
    assert not failures.get(3) and not raised, (failures, raised)


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="air_bearing.bulge = 'none'"):
        bt.bulge_table(model="none", gaps=bt.table_gaps(), protrusions=bt.table_protrusions(), **PAPER)
    with pytest.raises(ValueError, match="gaps"):
        bt.table_gaps(2.0, 1.0)
