"""Two named deviations from the paper (docs/model.md, section "Deviations", items 18-19).

(a) ``contact.area_model``: the interface stresses summed over the bulge's gap field,
``F(d) = 2 pi a b int_0^1 p(d + delta u) (1 - u) du``: the model's per-protrusion tables feed the kernel and
the histories alike, against the closed form of exponential laws. The integral itself
(:func:`pipeline.physics.geometry.ellipsoid_force`, :func:`~pipeline.physics.geometry.ellipsoid_table_integral`)
against the footprint integral, closed forms and the limit ``delta -> 0`` is tested in
tests/physics/test_geometry.py.
(b) ``slider.friction_arm``: the friction moment's arm ``T/2`` or ``T``.

The interface is a synthetic one (exponential laws) written as the interface stage writes it; scenes
are built in code.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.config.scene import SceneError, scene_from_dict
from pipeline.model import dynamics as dyn
from pipeline.model import forces as fo
from pipeline.model import piecewise as pw
from pipeline.model import assembly, kernel_inputs, outcomes, running
from pipeline.physics import geometry as g

NM, UM, MPA = 1e-9, 1e-6, 1e6
A, B = 3 * UM, 25 * UM  # [paper] semi-axes of the bulge
H = 0.05 * NM            # table step [m]
L_C, L_A = 0.4 * NM, 1.0 * NM  # decay lengths of the synthetic contact and adhesion laws [m]


def closed_exponential(d: np.ndarray, delta: float, length: float) -> np.ndarray:
    """``int_0^1 exp(-(d + delta u)/length) (1 - u) du`` in closed form: with ``k = delta/length``,
    ``exp(-d/length) (k - 1 + exp(-k)) / k^2`` (written with expm1 so small k keeps its digits)."""
    k = delta / length
    return np.exp(-np.asarray(d) / length) * (k - (-np.expm1(-k))) / k**2


GRID = np.arange(-3.0, 25.0 + 1e-9, 0.05) * NM


# ------------------------------------------------------------------------------------------------
# (a) in the model


def synthetic_interface() -> xr.Dataset:
    """Contact 50 MPa exp(-d/0.4 nm), real-area fraction 0.1 exp(-d/0.4 nm) (above 1 below -0.9 nm: the
    cap), friction 300 MPa x that fraction, adhesion 40 MPa exp(-d/1 nm), as the interface stage writes them."""
    d = GRID / NM
    area = 0.1 * np.exp(-GRID / L_C)
    return xr.Dataset({"contact_pressure": ("separation", 50 * np.exp(-GRID / L_C)),
                       "real_area_fraction": ("separation", area),
                       "friction_stress": ("separation", 300 * area),
                       "adhesion_pressure": ("separation", 40 * np.exp(-GRID / L_A)),
                       "sigma": 0.52, "y_s": 0.69}, coords={"separation": d})


EFFECTS = ["air_bearing", "pitch", "adhesion", "contact", "friction"]


def model(contact=None, slider=None, effects=EFFECTS, k=1.0):
    scene = scene_from_dict({
        "scene": {"effects": list(effects)},
        "air_bearing": {"flying_height_nm": 11.0, "frequencies_khz": [120.0, 300.0], "rear_exponent": 2.0,
                        "damping_ratio": 0.05},
        "solver": {"duration_ms": 0.2, "transient_ms": 0.1},
        "contact": {"k": k, **(contact or {})},
        "slider": slider or {},
    })
    return assembly.build_model(scene, synthetic_interface(), None, k)


def test_flat_section_is_the_default_and_today():
    base, named = model(), model(contact={"area_model": "flat-section"})
    assert base.area_model == "flat-section"
    p, tables, _ = kernel_inputs.run_parameters(named, 11 * NM)
    assert tables.contact is named.contact and tables.adhesion is named.adhesion
    assert tables.friction is named.friction
    a, b = running.run_model(base, 11 * NM), running.run_model(named, 11 * NM)
    np.testing.assert_array_equal(a.state, b.state)
    ha, hb = outcomes.histories(a), outcomes.histories(b)
    for name in ha:
        np.testing.assert_array_equal(ha[name], hb[name])


def test_integrated_tables_feed_the_kernel_and_the_histories():
    delta = 11 * NM
    m = model(contact={"area_model": "integrated"})
    p, tables, _ = kernel_inputs.run_parameters(m, delta)
    An = p["A_n"]
    # tol: the same nominal-area formula on the same numbers
    assert An == pytest.approx(float(g.nominal_area(delta, A, B, 3 * 0.52 * NM)), rel=1e-14)
    # at the nodes, A_n times the kernel's tables is the integrated force of the same stresses
    nodes = GRID[GRID + delta <= GRID[-1]]
    scale = 2 * np.pi * A * B
    contact = An * pw.ppval(tables.contact, p.tab_x0, p.tab_h, nodes)
    exact = scale * 50 * MPA * closed_exponential(nodes, delta, L_C)
    assert contact == pytest.approx(exact, rel=2e-6)
    adhesion = An * pw.ppval(tables.adhesion, p.tab_x0, p.tab_h, nodes)
    assert adhesion == pytest.approx(scale * 40 * MPA * closed_exponential(nodes, delta, L_A), rel=2e-6)
    # ... far less than the flat section's at the apex gap (the rim of A_n is delta u higher)
    flat = An * pw.ppval(m.contact, p.tab_x0, p.tab_h, nodes)
    assert np.all(contact < 0.5 * flat)
    # the run and its histories read the same tables: contact force, real area (the local fraction
    # capped at 1 before summing) and friction at the samples in contact
    run = running.run_model(m, delta)
    hist = outcomes.histories(run)
    c = hist["in_contact"]
    assert c.any()
    d = hist["separation"][c]
    assert hist["contact_force"][c] == pytest.approx(scale * 50 * MPA * closed_exponential(d, delta, L_C),
                                                     rel=1e-5)
    it = kernel_inputs.interface_tables(m, delta, An)
    assert np.array_equal(it.contact, tables.contact)  # (the same tables, kept or computed again)
    capped = pw.piecewise_coefficients(np.minimum(0.1 * np.exp(-GRID / L_C), 1.0), H, 3)
    area = scale * pw.ppval(pw.piecewise_coefficients(g.ellipsoid_table_integral(capped, H, delta), H, 3),
                             p.tab_x0, p.tab_h, d)
    # tol: the same integrated spline read by the kernel and by ppval, a few roundings
    assert hist["real_area"][c] == pytest.approx(area, rel=1e-12)
    assert np.all(hist["real_area"] <= np.pi * A * B)
    # tol: a quotient of the two stored histories, one rounding
    assert hist["mean_pressure"][c] == pytest.approx(hist["contact_force"][c] / hist["real_area"][c], rel=1e-12)
    s = outcomes.summarize(run, hist)
    assert s["nominal_area"] == An  # A_n stays the flat section's: the report's "A_n at 11 nm"


def test_unknown_options_are_one_line_errors():
    for section, key in (("contact", "area_model"), ("slider", "friction_arm")):
        with pytest.raises(SceneError) as err:
            scene_from_dict({section: {key: "elsewhere"}})
        text = str(err.value)
        assert "\n" not in text and f"{section}.{key} = 'elsewhere'" in text and "expected one of" in text


# ------------------------------------------------------------------------------------------------
# (b) the friction arm


def test_gimbal_arm_doubles_the_friction_moment():
    cg, gimbal = model(), model(slider={"friction_arm": "gimbal"})
    T = 0.23e-3
    assert cg.p["friction_arm"] == T / 2 and gimbal.p["friction_arm"] == T
    assert gimbal.info["friction_arm"] == "gimbal"
    # the kernel's pitch acceleration at a state in contact, with and without the friction table: the
    # friction's share is -arm Q / I, twice as large with the gimbal's arm
    delta = 11 * NM
    share = []
    for m in (cg, gimbal):
        p, tables, variants = kernel_inputs.run_parameters(m, delta)
        y = np.array([-0.2 * NM, -1e-6, 0.0, 0.0])
        assert fo.separation_at(p, y[0], y[1], 0.0) < p["k_sigma"]
        with_q, without = np.empty(4), np.empty(4)
        dyn.rhs(0.0, y, p, tables, variants, True, with_q)
        dyn.rhs(0.0, y, p, tables._replace(friction=None), variants, True, without)
        d = fo.separation_at(p, y[0], y[1], 0.0)
        Q = p["A_n"] * float(pw.ppval(tables.friction, p.tab_x0, p.tab_h, np.array([d]))[0])
        # tol: a difference of two moment sums (cancellation < 4, measured), tens of roundings
        assert (with_q[3] - without[3]) * p["I"] == pytest.approx(-p["friction_arm"] * Q, rel=1e-9)
        share.append(with_q[3] - without[3])
        assert with_q[2] == without[2]  # (no vertical force)
    # tol: a ratio of two such differences (cancellation < 4, measured): tens of roundings
    assert share[1] / share[0] == pytest.approx(2.0, rel=1e-12)


def test_gimbal_arm_about_doubles_the_static_gap_opening():
    # the static contact equilibrium at 11 nm without friction, with the arm T/2 and with T: the friction
    # moment pitches the leading edge down and opens the TFC gap; with twice the arm nearly twice as much
    # (a little less: the opening lowers the contact force and with it the friction)
    delta = 11 * NM
    opening = {}
    base = model(effects=EFFECTS[:-1])
    p, _, _ = kernel_inputs.run_parameters(base, delta)
    y0, note = running.start(base, delta)
    assert "contact" in note
    d0 = fo.separation_at(p, y0[0], y0[1], 0.0)
    for arm in ("cg", "gimbal"):
        m = model(slider={"friction_arm": arm})
        y, note = running.start(m, delta)
        assert "contact" in note
        opening[arm] = fo.separation_at(p, y[0], y[1], 0.0) - d0
    assert opening["cg"] > 0
    assert 1.5 < opening["gimbal"] / opening["cg"] < 2.0
