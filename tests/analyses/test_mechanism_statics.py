"""Statics maps of the mechanisms (pipeline.analyses.mechanism_statics) on the identified paper scene: a
mechanism at zero (no heat; the solid work of adhesion at the lubricant's) is today's statics bit for bit, and
linear near it; the frictional heat's protrusion solves its fixed point
and, at small eta_f, is the linear response eta_f Q V, whose effect on the interference is the statics'
finite-difference slope times it; the friction moment's effect on the contact state is the linear
response of the state's stiffness to the moment; the free TFC point's lift per newton of friction is the
bearing's compliance, linear in the arm; the contact state's forces are those of the kernel's steady run
without the DMW."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analyses import mechanism_statics as ms
from pipeline.config.scene import load_scene
from pipeline.model import statics as st
from pipeline.model.dmw_record import disk_speed_m_s
from pipeline.model.start import SCALE, static_forces
from pipeline.model import kernel_inputs
from pipeline.physics.equilibrium import jacobian
from pipeline.units import NM
from slider_scenes import build, synthetic_record

#: The identified scene's calibrated k until 2026-12-02's evening, an input of these tests (1.0728 since: docs/model.md,
#: section "The two k of the shipped scenes")
K_MAIN = 1.0736


@pytest.fixture(scope="module")
def model(repo_root):
    scene = load_scene(repo_root / "configs" / "paper-2009-identified.toml")
    return build(scene, synthetic_record(scene, duration_s=2.2e-3), k=K_MAIN)


def _deepest_contact(model, mu):
    found = [s for s in st.states_at(model, mu) if s["type"] == st.CONTACT and s["stable"]]
    return min(found, key=lambda s: s["clearance"])


def test_a_mechanism_at_zero_is_todays_statics_bit_for_bit(model):
    prot = [9.4, 9.6, 10.0, 11.0]
    ds = ms.mechanism_map([ms.Case("none", 0.0, model), ms.Case("frictional-heating", 0.0, model)], prot)
    for name in ms.MAP:
        if ms.MAP[name].dims == ("case", "protrusion"):
            a, b = ds[name].values
            assert np.array_equal(a, b, equal_nan=True), name
    for j, p in enumerate(prot):
        states = st.states_at(model, p * NM)
        flying = [s for s in states if s["type"] == st.FLYING and s["stable"]]
        assert ds["flying"].values[0, j] == bool(flying)
        assert ds["interference"].values[0, j] == -_deepest_contact(model, p * NM)["clearance"] / NM
    assert np.all(ds["thermal_protrusion"].values == 0.0)
    # the band's precondition as the statics map sees it: flying and contact together below the fold only
    assert ds["coexist"].values[0].tolist() == [1, 1, 0, 0]


def test_heating_fixed_point_and_its_linear_response(model):
    V = disk_speed_m_s(model.scene["dmw"])
    p = 11.0 * NM
    s0 = _deepest_contact(model, p)
    Q0 = ms.contact_quantities(model, p, s0)["friction_force"]
    # the fixed point delta_f = eta_f V Q(delta + delta_f)
    eta = 0.05 * ms.NM_PER_MW
    x, s, gain = ms.heated_contact(model, p, eta, V)
    Q = ms.contact_quantities(model, p + x, s)["friction_force"]
    assert abs(x - eta * V * Q) < 2 * ms.HEAT_TOL
    assert 0 < gain < 1  # no thermal runaway at these values
    # linear response: delta_f -> eta_f Q V, the interference's change -> its slope in the protrusion times it
    eta = 1e-4 * ms.NM_PER_MW
    x, s, _ = ms.heated_contact(model, p, eta, V)
    # tol: second order in eta_f Q V ~ 2e-3 nm against the map's loop gain ~1e-4
    assert x == pytest.approx(eta * Q0 * V, rel=1e-3)
    h = 0.01 * NM
    slope = (_deepest_contact(model, p + h)["clearance"] - _deepest_contact(model, p - h)["clearance"]) / (2 * h)
    # tol: the central difference's curvature error over +-0.01 nm, and the states' 1e-6-nm resolution
    assert (s["clearance"] - s0["clearance"]) == pytest.approx(slope * x, rel=0.02)


def test_friction_moment_response_of_the_contact_state(model):
    """Scaling the friction arm moves the contact state by ``K^-1`` of the moment's change (the state's own
    stiffness, both freedoms): the model's forces carry the friction moment."""
    p = 11.0 * NM
    s0 = _deepest_contact(model, p)
    arm = model.slider.friction_arm
    eps = 1e-3
    s1 = _deepest_contact(ms.with_friction_arm(model, arm * (1 + eps)), p)
    R, _, _ = static_forces(lambda mu: kernel_inputs.run_parameters(model, mu))
    y = np.array([s0["z"], s0["theta"]])
    Kst = -jacobian(lambda v: R(v, p), y, SCALE)
    Q = ms.contact_quantities(model, p, s0)["friction_force"]
    dy = np.linalg.solve(Kst, np.array([0.0, -arm * eps * Q]))
    du = dy[0] - model.slider.l_c * dy[1]  # the TFC point's height z - l_c theta: the clearance's change
    assert du > 0  # the friction moment lifts the TFC point
    # tol: the response is first order in eps = 1e-3 (second-order terms ~1e-3 of it) and the states'
    # 1e-6-nm resolution against a change of ~1e-4 nm
    assert s1["clearance"] - s0["clearance"] == pytest.approx(du, rel=0.05)
    # without the arm the contact state is deeper
    assert _deepest_contact(ms.with_friction_arm(model, 0.0), p)["clearance"] < s0["clearance"]


def test_free_tfc_point_lift_is_the_bearings_compliance_and_linear_in_the_arm(model):
    lift = ms.friction_lift(model)
    s = model.slider
    a = np.array([1.0, -s.l_c])
    compliance = np.linalg.inv(s.stiffness_matrix)
    # tol: the same few products of the same numbers, a few roundings
    assert lift == pytest.approx(float(a @ compliance @ np.array([0.0, -s.friction_arm])), rel=1e-12)
    assert lift > 0
    # tol: doubling the arm is exact in binary; the solve's rounding
    assert ms.friction_lift(ms.with_friction_arm(model, 2 * s.friction_arm)) == pytest.approx(2 * lift, rel=1e-12)
    assert ms.friction_lift(ms.with_friction_arm(model, 0.0)) == 0.0


def test_map_flash_temperature_and_refusals(model, repo_root):
    from pipeline.model.interface_tables import build_tables, roughness_statistics
    scene = model.scene
    iface = build_tables(scene, roughness_statistics(scene))
    ds = ms.mechanism_map([ms.Case("none", 0.0, model)], [11.0], interface=iface)
    d = ds.isel(case=0, protrusion=0)
    assert ds["flash_temperature"].attrs["units"] == "K"
    assert float(d["flash_temperature"]) > 0 and 0 < float(d["heat_partition"]) < 1
    # the friction power is Q V; the summits in contact eta A_n P(z > d)
    V = disk_speed_m_s(scene["dmw"])
    # tol: a product and a sum of the same numbers, a few roundings
    assert float(d["friction_power"]) == pytest.approx(float(d["friction_force"]) * V, rel=1e-12)  # mN x m/s = mW
    assert 0 < float(d["contact_count"]) < float(iface["summit_density"]) * 1e12 * 62.1e-12
    # without the interface dataset: no count, no flash temperature
    assert np.isnan(ms.mechanism_map([ms.Case("none", 0.0, model)], [11.0])["flash_temperature"]).all()
    with pytest.raises(ValueError, match="mechanism 'heat' is not one of"):
        ms.mechanism_map([ms.Case("heat", 0.0, model)], [11.0])


@pytest.mark.parametrize("name", ["paper-2009-identified.toml", "paper-2009-two-population-identified.toml"])
def test_contact_quantities_are_the_kernels_forces_at_rest(repo_root, name):
    """Without the DMW a run at 11 nm settles on the static contact state: its steady-window forces are the
    map's (the one-population scene; the two-population scene with its meniscus state's two adhesion tables
    and the lubricant shear)."""
    from dataclasses import replace
    from pipeline.model import outcomes, running
    scene = load_scene(repo_root / "configs" / name)
    k = K_MAIN if name == "paper-2009-identified.toml" else 0.978
    m = replace(build(scene, synthetic_record(scene, duration_s=2.2e-3), k=k), dmw=None)
    p = 11.0 * NM
    s = _deepest_contact(m, p)
    q = ms.contact_quantities(m, p, s)
    out = outcomes.summarize(running.run_model(m, p))
    # tol: the run's transient decays to the static state within the window (1e-6 of the forces here)
    for key in ("contact_force", "friction_force", "adhesion_force"):
        assert out[key] == pytest.approx(q[key], rel=1e-4), key
    assert out["interference"] == pytest.approx(-s["clearance"], rel=1e-4)


def test_penetration_adhesion_at_the_lubricants_value_is_todays_map_and_linear_near_it(model):
    """``W_s = dgamma`` (the scene's work of adhesion) gives the tables, hence the map, bit for bit; a small
    step of ``W_s`` moves the contact state linearly (twice the step, twice the shift)."""
    scene = model.scene
    W = scene["lubricant"]["work_of_adhesion_j_m2"]
    record = synthetic_record(scene, duration_s=2.2e-3)

    def with_ws(ws):
        return build(scene.replace(lubricant={"solid_work_of_adhesion_j_m2": ws}), record, k=K_MAIN)

    prot = [9.6, 10.4, 11.0]
    a = ms.mechanism_map([ms.Case("none", 0.0, model)], prot)
    b = ms.mechanism_map([ms.Case("penetration-adhesion", W, with_ws(W))], prot)
    for name in ("flying", "contact", "interference", "contact_force", "adhesion_force", "friction_force"):
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name
    p = 11.0 * NM
    c0 = _deepest_contact(model, p)["clearance"]
    d1 = _deepest_contact(with_ws(W + 1e-4), p)["clearance"] - c0
    d2 = _deepest_contact(with_ws(W + 2e-4), p)["clearance"] - c0
    assert d1 < 0  # more adhesion at solid contact: a deeper contact
    # tol: second order in a 2e-4 J/m^2 step of a pull of ~2.8 mN at 0.109 J/m^2, and the 1e-6-nm states
    assert d2 == pytest.approx(2 * d1, rel=0.02)


def test_the_fold_is_the_static_starts_and_bounds_the_flying_states(model):
    fold = ms.flying_fold(model) / NM
    ds = ms.mechanism_map([ms.Case("none", 0.0, model)], [9.4, 9.6, 9.8, 10.0])
    assert float(ds["fold"][0]) == pytest.approx(fold, abs=1e-12)
    flying = ds["protrusion"].values[ds["flying"].values[0] == 1]
    assert flying.max() < fold < 9.8  # the last flying step before the fold, none after it


def _script(repo_root):
    """docs/experiments/mechanism_statics.py as a module (the map's command line)."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("mechanism_statics_script",
                                                  repo_root / "docs" / "experiments" / "mechanism_statics.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_scripts_scene_options_and_its_datum_case(repo_root):
    """The map's script takes another scene and its overrides (--scene, repeated --set), the main scene by default;
    its roughness-datum variant (the scene with contact.k = 3) is, on the main scene, the shipped section-datum
    scene but for its name and description."""
    script = _script(repo_root)
    default = script.options([])
    assert default.scene == repo_root / "configs" / "paper-2009-identified.toml"
    assert default.sets == [] and default.name == "main scene"
    band = script.options(["--scene", "configs/paper-2009-two-population-rough.toml", "--set",
                           "air_bearing.pad_pressure_mpa=2.2", "--set", "dmw.exponent=-4", "--name", "band scene"])
    assert band.sets == ["air_bearing.pad_pressure_mpa=2.2", "dmw.exponent=-4"] and band.name == "band scene"
    scene = load_scene(repo_root / "configs" / "paper-2009-two-population-rough.toml", band.sets)
    assert scene["air_bearing"]["pad_pressure_mpa"] == 2.2 and scene["dmw"]["exponent"] == -4.0
    datum = load_scene(default.scene, [script.SECTION_DATUM]).config
    shipped = load_scene(repo_root / "configs" / "paper-2009-identified-section-datum.toml").config
    assert datum["contact"]["k"] == 3.0
    for section in shipped:
        keys = set(shipped[section]) - ({"name", "description", "extends"} if section == "scene" else set())
        assert {k: datum[section][k] for k in keys} == {k: shipped[section][k] for k in keys}, section
