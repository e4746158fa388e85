"""The statics map (docs/model.md, section "Statics map"; pipeline.physics.equilibrium's path functions,
pipeline.model.statics, the ``statics`` stage): every static state, its stability and the barriers out of it.

* analytic force curves with known equilibria and barriers (a cubic; a jump through zero with a well above);
* the relaxed path of a linear 2-DOF spring system, whose path force is known in closed form;
* the paper scene: at a small protrusion one stable flying state, the run's static start; in the adhesion
  hysteresis a flying and a contact state with the barriers between them;
* the two-population scene: a state on the contact criterion at 10.0-10.2 nm (at 10.0 nm
  beside a flying state), slow.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.config.scene import load_scene
from pipeline.model import kernel_inputs, running
from pipeline.model import statics as st
from pipeline.physics.statics_map import path_equilibria, relaxed_path
from pipeline.units import NM, URAD
from pipeline.variables import STATICS
from pipeline.runner import ensure
from slider_scenes import build, synthetic_record


# ------------------------------------------------------------------------------------ analytic curves
def _work(poly: np.poly1d, lo: float, hi: float) -> float:
    """``int_lo^hi poly du``, exactly."""
    P = np.polyint(poly)
    return float(P(hi) - P(lo))


@pytest.mark.parametrize("roots", [(-1.0, 0.0, 1.0), (-1.0, 0.3, 1.6)])
def test_a_cubic_force_has_its_three_equilibria_and_exact_barriers(roots):
    a, b, c = roots
    kappa = 2.5
    f = -kappa * np.poly1d([a, b, c], r=True)  # f = -kappa (u - a)(u - b)(u - c): up below a, down above c
    states = path_equilibria(f, np.linspace(-2.0, 2.5, 91), xtol=1e-14)
    assert [s.u for s in states] == pytest.approx([a, b, c], abs=1e-12)
    assert [s.stable for s in states] == [True, False, True]
    assert not any(s.switch for s in states)
    # the barrier out of each well: the rise of V = -int f du to the saddle at b
    rise_a, rise_c = -_work(f, a, b), _work(f, b, c)
    # tol: a polynomial's exact integral against the solver's, tens of roundings of the roots
    assert states[0].barrier == pytest.approx(rise_a, rel=1e-9)
    # tol: a polynomial's exact integral against the solver's, tens of roundings of the roots
    assert states[2].barrier == pytest.approx(rise_c, rel=1e-9)
    assert np.isnan(states[1].barrier)
    if roots == (-1.0, 0.0, 1.0):  # symmetric: kappa int_{-1}^{0} (u^3 - u) du = kappa / 4 each
        # tol: a polynomial's exact integral on exact roots, a few roundings
        assert states[0].barrier == pytest.approx(kappa / 4, rel=1e-12) and states[2].barrier == pytest.approx(kappa / 4)
    # tol: a polynomial's exact integral against the solver's, tens of roundings of the roots
    assert states[0].potential == 0.0 and states[1].potential == pytest.approx(rise_a, rel=1e-9)


def test_a_jump_through_zero_is_a_stable_state_on_the_break_with_its_barrier():
    # above the break at 0: g = kappa (u - u1)(u2 - u) (down, then up between u1 and u2, then down); below it
    # the force jumps up by J (a contact law switched on at a criterion): held on the break from both sides
    kappa, u1, u2, J = 3.0, 0.4, 1.5, 30.0  # (J > |g| down to the grid start: no zero below the break)
    g = kappa * np.poly1d([u1], r=True) * np.poly1d([-1.0, u2])

    def f(u: float) -> float:
        return float(g(u)) + (J if u < 0 else 0.0)

    states = path_equilibria(f, np.linspace(-1.0, 2.5, 71), breaks=[0.0], xtol=1e-14)
    assert [s.u for s in states] == pytest.approx([0.0, u1, u2], abs=1e-12)
    assert [s.switch for s in states] == [True, False, False]
    assert [s.stable for s in states] == [True, False, True]
    assert states[0].u == 0.0  # exactly on the break, not interpolated across the jump
    # tol: a polynomial's exact integral against the solver's, tens of roundings of the roots
    assert states[0].barrier == pytest.approx(-_work(g, 0.0, u1), rel=1e-9)
    # tol: a polynomial's exact integral against the solver's, tens of roundings of the roots
    assert states[2].barrier == pytest.approx(_work(g, u1, u2), rel=1e-9)
    # the jump pointing outwards (down below, up above) is an unstable state on the break
    flipped = path_equilibria(lambda u: (-1.0 if u < 0 else 1.0) * (1 + u * u), np.linspace(-1, 1, 11), breaks=[0.0])
    assert len(flipped) == 1 and flipped[0].switch and not flipped[0].stable


def test_one_well_has_no_barrier_and_close_roots_within_a_cell_are_not_seen():
    one = path_equilibria(lambda u: -3.0 * (u - 0.25), np.linspace(-1, 1, 9))
    assert len(one) == 1 and one[0].stable and np.isnan(one[0].barrier)
    # two zeros 0.01 apart inside one cell (0.5, 0.75) of the grid: the grid is the resolution (documented)
    pair = np.poly1d([0.55, 0.56], r=True)
    assert path_equilibria(lambda u: float(pair(u)), np.linspace(-1, 1, 9)) == []
    assert len(path_equilibria(lambda u: float(pair(u)), np.linspace(-1, 1, 801))) == 2


def test_the_relaxed_path_of_linear_springs_is_the_point_stiffness():
    # R(y) = F0 - K y, held on a . y = u, the other freedom relaxed: f(u) = -(u - u_eq) / (a K^-1 a),
    # u_eq = a K^-1 F0 (the free equilibrium), exactly (linear algebra; the secant solve is exact on a line)
    K = np.array([[5.0e5, -80.0], [-80.0, 0.07]])  # N/m, N/rad; N m/m, N m/rad: a slider's orders
    F0 = np.array([1e-4, 2e-8])
    l_c = 4.17e-4
    a = np.array([1.0, -l_c])
    us = np.linspace(-3, 3, 13) * NM
    f, s, ok = relaxed_path(lambda y: F0 - K @ y, a, us, s_scale=URAD)
    k_point = 1.0 / (a @ np.linalg.solve(K, a))
    u_eq = a @ np.linalg.solve(K, F0)
    assert ok.all()
    # tol: a 2x2 solve (condition ~ 10), tens of roundings
    assert f == pytest.approx(-(us - u_eq) * k_point, rel=1e-9, abs=1e-15)
    t = np.array([l_c, 1.0])
    for u, sv in zip(us, s):
        y = np.array([u, 0.0]) + sv * t
        assert a @ y == pytest.approx(u, abs=1e-22)
        # relaxed: R . t = 0 to the solve's tolerance (its last update below 1e-10 urad, times t K t)
        assert abs((F0 - K @ y) @ t) <= 1e-10 * URAD * (t @ K @ t)


# --------------------------------------------------------------------------------------- paper scene
@pytest.fixture(scope="module")
def paper_model(paper_config):
    """The paper scene (no bulge lift, the paper's adhesion) at the paper's k = 0.978, tables in memory."""
    scene = load_scene(paper_config)
    return build(scene, synthetic_record(scene, 2.2e-3), k=0.978)


def test_at_a_small_protrusion_the_one_state_is_the_runs_static_start(paper_model):
    delta = 4.0 * NM
    states = st.states_at(paper_model, delta)
    assert len(states) == 1
    (s,) = states
    assert s["stable"] and s["type"] == st.FLYING and np.isnan(s["barrier"])
    y, note = running.start(paper_model, delta)
    assert "flying" in note
    # the start's Newton converges to 1e-10 of its scale; the path's Brent to 1e-6 nm of the TFC height
    assert s["z"] == pytest.approx(y[0], abs=1e-5 * NM) and s["theta"] == pytest.approx(y[1], abs=1e-5 * URAD)
    # with the pitch relaxed the TFC point's stiffness is 1/(a K^-1 a) of the state's 2-DOF stiffness
    from pipeline.physics.equilibrium import jacobian
    from pipeline.model.start import SCALE, static_forces
    R, _, _ = static_forces(lambda mu: kernel_inputs.run_parameters(paper_model, mu))
    K = -jacobian(lambda v: R(v, delta), y[:2], SCALE)
    a = np.array([1.0, -paper_model.slider.l_c])
    assert s["path_stiffness"] == pytest.approx(1.0 / (a @ np.linalg.solve(K, a)), rel=1e-4)
    assert (s["eigenvalues"] > 0).all()
    # far from the disk the interface adds little: the bearing's own stiffness at the TFC point, to 2 %
    assert s["path_stiffness"] == pytest.approx(st.tfc_point_scales(paper_model)[0], rel=0.02)


def test_the_compiled_path_finds_the_states_of_the_python_reference(paper_model):
    # the same secant iteration, compiled on the kernel's forces or from Python on the same forces: the states
    # agree to far below the 1e-6-nm Brent tolerance, the barriers to the quadrature's 1e-8
    for delta in (4.0, 7.0, 11.0):
        fast = st.states_at(paper_model, delta * NM)
        ref = st.states_at(paper_model, delta * NM, compiled=False)
        assert [(s["type"], s["stable"]) for s in fast] == [(s["type"], s["stable"]) for s in ref]
        for a, b in zip(fast, ref):
            assert a["clearance"] == pytest.approx(b["clearance"], abs=1e-7 * NM)
            # tol: both barriers are quadratures to 1e-8 relative: their difference is within 1e-7
            assert a["barrier"] == pytest.approx(b["barrier"], rel=1e-7, nan_ok=True)


@pytest.mark.parametrize("effects", [["air_bearing", "pitch", "dmw"], ["air_bearing", "dmw"]])
def test_on_the_bearing_alone_the_one_state_is_the_nominal_attitude_with_the_bearings_stiffness(paper_config,
                                                                                                 effects):
    # no force at the TFC point: the slider flies at y = 0 and the TFC point's stiffness is the pads' own,
    # 1/(a K^-1 a) with the pitch relaxed, k_f + k_r with it locked (the rear law's stiffness at g0 is k_r)
    scene = load_scene(paper_config, ["scene.effects=[" + ", ".join(f'"{e}"' for e in effects) + "]"])
    model = build(scene, synthetic_record(scene, 2.2e-3))
    (s,) = st.states_at(model, 5.0 * NM)
    assert s["stable"] and s["type"] == st.FLYING
    assert s["z"] == pytest.approx(0.0, abs=1e-6 * NM) and s["theta"] == pytest.approx(0.0, abs=1e-6 * URAD)
    k_b, m_b = st.tfc_point_scales(model)
    K = model.slider.stiffness_matrix
    if "pitch" in effects:
        a = np.array([1.0, -model.slider.l_c])
        # tol: a 2x2 solve (condition ~ 10) and its closed form, tens of roundings
        assert k_b == pytest.approx(1.0 / (a @ np.linalg.solve(K, a)), rel=1e-12)
        # tol: the same closed form, a few roundings
        assert 1.0 / m_b == pytest.approx(1.0 / model.slider.m + model.slider.l_c**2 / model.slider.I, rel=1e-12)
    else:
        assert (k_b, m_b) == (K[0, 0], model.slider.m) and np.isnan(s["eigenvalues"][1])
    assert s["path_stiffness"] == pytest.approx(k_b, rel=1e-5)
    # no criterion without the contact law: the clearance is the separation d, FH0 - delta - y_s at y = 0
    assert s["clearance"] == pytest.approx(model.p["FH0"] - 5.0 * NM - model.p["y_s"], abs=1e-6 * NM)


def test_in_the_adhesion_hysteresis_a_flying_and_a_contact_state_coexist(paper_model):
    # the paper's adhesion folds the flying branch at 7.88 nm (the start's fold search): at 7.0 nm a flying
    # state, a saddle and a contact state; past the fold the contact state alone
    states = st.states_at(paper_model, 7.0 * NM)
    assert [s["stable"] for s in states] == [True, False, True]
    assert [s["type"] for s in states] == [st.FLYING, st.FLYING, st.CONTACT]
    saddle = states[1]
    assert saddle["eigenvalues"][0] < 0 < saddle["eigenvalues"][1]  # one unstable direction: a saddle
    assert saddle["path_stiffness"] < 0
    top, bottom = states[0], states[2]
    assert top["barrier"] > 0 and bottom["barrier"] > 0
    # the potential difference of the wells is the path force's work between them, as the barriers say
    # tol: a difference of the same integrals, tens of roundings
    assert bottom["potential"] - top["potential"] == pytest.approx(top["barrier"] - bottom["barrier"], rel=1e-9)
    fold = paper_model.statics["fold"]
    assert 7.0 * NM < fold < 8.0 * NM
    past = st.states_at(paper_model, 8.0 * NM)
    assert len(past) == 1 and past[0]["type"] == st.CONTACT and past[0]["stable"]
    y, note = running.start(paper_model, 8.0 * NM)
    assert "contact" in note and past[0]["z"] == pytest.approx(y[0], abs=1e-4 * NM)


def test_the_dataset_has_labelled_dims_and_units(paper_model):
    ds = st.statics_map(paper_model, [4.0, 7.0], synthetic_record(paper_model.scene, 2.2e-3))
    assert ds["clearance"].dims == ("protrusion", "state") and ds.sizes["state"] == 3
    assert list(ds["state_count"].values) == [1, 3] and list(ds["stable_count"].values) == [1, 2]
    assert ds["stiffness_eigenvalue"].dims == ("protrusion", "state", "mode")
    for name in (*ds.data_vars, *ds.coords):
        assert ds[name].attrs["units"] == STATICS[name].units, name
    assert np.isnan(ds["clearance"].values[0, 1:]).all() and (ds["state_type"].values[0, 1:] == -1).all()
    # the DMW energy 0.5 k_b sigma_w^2 of the record's rms
    w = synthetic_record(paper_model.scene, 2.2e-3)[0] * NM
    assert float(ds["dmw_energy"]) == pytest.approx(0.5 * float(ds["bearing_stiffness_tfc"]) * np.std(w) ** 2)


# ---------------------------------------------------------------------------- two-population (the lab)
@pytest.mark.slow
def test_the_two_population_scene_has_the_labs_state_on_the_criterion(repo_root):
    """The statics of ``paper-2009-two-population-identified.toml`` at k = 0.978, against a 0.01-nm scan:
    a flying state +0.707 nm at 9.8 nm; at 10.0 nm a flying state +0.483 nm, a saddle +0.064 nm and a stable
    state on the criterion (the scan's -0.001 nm: its linear interpolation across the jump on the 0.01-nm grid),
    barriers 11.3e-15 J out of the flying state and 0.6e-15 J out of the criterion; at 10.2 nm the state on the
    criterion alone (the scan's -0.006 nm); contact states -0.271 and -0.508 nm at 10.4 and 11.0 nm.

    Tolerances: 2e-3 nm on the smooth states (the lab's roots are linear interpolations on a 0.01-nm grid);
    one grid step on the criterion states; the criterion's barrier within one grid cell of the contact law's
    jump (0.12 mN x 0.01 nm = 1.2e-15 J: the lab took the potential at the grid point below the jump).
    """
    scene = load_scene(repo_root / "configs" / "paper-2009-two-population-identified.toml")
    model = build(scene, synthetic_record(scene, 2.2e-3), k=0.978)
    lab_smooth = {9.8: [0.707], 10.4: [-0.271], 11.0: [-0.508]}
    for delta, want in lab_smooth.items():
        states = st.states_at(model, delta * NM)
        assert [s["clearance"] / NM for s in states] == pytest.approx(want, abs=2e-3), delta
        assert all(s["stable"] for s in states)
    ten = st.states_at(model, 10.0 * NM)
    assert [s["type"] for s in ten] == [st.FLYING, st.FLYING, st.CRITERION]
    assert [s["stable"] for s in ten] == [True, False, True]
    assert [s["clearance"] / NM for s in ten[:2]] == pytest.approx([0.483, 0.064], abs=2e-3)
    assert ten[2]["clearance"] == 0.0  # (on the break exactly; the lab's -0.001 nm is within its grid step)
    assert ten[0]["barrier"] == pytest.approx(11.3e-15, abs=0.2e-15)
    assert 0.6e-15 <= ten[2]["barrier"] <= 0.6e-15 + 1.2e-15
    (on,) = st.states_at(model, 10.2 * NM)
    assert on["type"] == st.CRITERION and on["stable"] and abs(on["clearance"] / NM - (-0.006)) <= 0.01
    y, note = running.start(model, 9.8 * NM)
    assert "flying" in note
    assert st.states_at(model, 9.8 * NM)[0]["z"] == pytest.approx(y[0], abs=1e-5 * NM)


# ------------------------------------------------------------------------- the DMW as free parameters
FREE_DMW = ('identify.parameters=[{key = "dmw.rms_nm", low = 0.08, high = 2.0}, '
            '{key = "dmw.exponent", low = -4.5, high = -1.0}]')


def test_the_two_population_scene_frees_the_dmw_exponent_and_rms_within_their_bounds(repo_root):
    from pipeline.analyses import free_parameters
    from pipeline.config.scene import DMW_EXPONENT_BOUNDS
    scene = load_scene(repo_root / "configs" / "paper-2009-two-population.toml")
    params = {p.name: p for p in free_parameters.parse_parameters(scene["identify"]["parameters"], "f", "identify.parameters")}
    assert (params["dmw.exponent"].low, params["dmw.exponent"].high) == DMW_EXPONENT_BOUNDS == (-4.5, -1.0)
    assert (params["dmw.rms_nm"].low, params["dmw.rms_nm"].high) == (0.08, 2.0)
    assert "fhm_flying" in scene["identify"]["targets"]  # the flying FHM is still fitted


@pytest.mark.parametrize("table, culprit", [
    ('[{key = "dmw.exponent", low = -6.0, high = -1.0}]', "dmw.exponent low = -6.0"),
    ('[{key = "dmw.exponent", low = -4.0, high = 0.0}]', "dmw.exponent low = -4.0, high = 0.0"),
    ('[{key = "dmw.rms_nm", low = 0.1, high = 3.0}]', "dmw.rms_nm low = 0.1, high = 3.0"),
])
def test_bounds_beyond_the_band_limited_range_are_refused_naming_the_key(paper_config, table, culprit):
    from pipeline.config.scene import SceneError
    with pytest.raises(SceneError, match=r"identify\.parameters: " + culprit.replace(".", r"\.") + ".*expected bounds within"):
        load_scene(paper_config, [f"identify.parameters={table}"])


@pytest.mark.parametrize("exponent, rms", [(-4.0, 1.8), (-1.5, 0.12)])
def test_an_evaluation_with_both_set_builds_the_record_of_that_rms_and_slope(paper_config, exponent, rms):
    from pipeline import candidates
    from pipeline.analyses import free_parameters
    from pipeline.model.inputs import SimulationInputs
    from pipeline.physics.microwaviness import power_law_fit
    # flying only: the candidate's inputs are its DMW record alone (no interface tables to build)
    scene = load_scene(paper_config, ['scene.effects=["air_bearing", "pitch", "dmw"]', FREE_DMW])
    params = free_parameters.parse_parameters(scene["identify"]["parameters"], "f", "identify.parameters")
    candidate = free_parameters.with_values(scene, params, [rms, exponent])
    w, fs = candidates.candidate_inputs(candidate, SimulationInputs()).record()
    # tol: rms of a record the synthesis scaled to it: ~log2(n) roundings of the mean
    assert np.sqrt(np.mean(w**2)) == pytest.approx(rms, rel=1e-9)  # the synthesis scales to the rms [nm]
    # the slope of the record's periodogram over the 10-500 kHz band: Gaussian bins, each an exponential
    # variable times S(f); the least-squares slope over ~1000 bins has a standard deviation of ~0.05
    c = np.fft.rfft(w)
    f = np.fft.rfftfreq(w.size, 1.0 / fs)
    slope, _ = power_law_fit(f, np.abs(c) ** 2, (10e3, 500e3))
    assert slope == pytest.approx(exponent, abs=0.2)
    base, _ = candidates.candidate_inputs(scene, SimulationInputs()).record()  # the scene's own: -2, 0.5 nm
    assert not np.allclose(base, w)


# ------------------------------------------------------------------------------------------- the stage
def test_the_stage_writes_a_cf_dataset_of_the_sweep_protrusions_and_keeps_it(paper_config, tmp_path):
    from cf_check import cf_report
    from pipeline.io import read_dataset
    scene = load_scene(paper_config, ["contact.k=0.978", "sweep.protrusion_nm={start=6.0, stop=8.0, step=1.0}"])
    path = ensure("statics", scene, tmp_path)
    ds = read_dataset(path)
    assert list(ds["protrusion"].values) == [6.0, 7.0, 8.0]
    assert list(ds["stable_count"].values) == [2, 2, 1]  # the adhesion hysteresis at 6-7 nm (fold 7.88 nm)
    assert ds.attrs["k"] == pytest.approx(0.978) and ds["clearance"].attrs["units"] == "nm"
    assert ds["barrier"].attrs["units"] == "J" and float(ds["dmw_energy"]) > 0
    failures, crashed = cf_report(path)
    assert crashed == [] and failures[3] == [] and failures[2] + failures[1] == []
    mtime = path.stat().st_mtime_ns
    assert ensure("statics", scene, tmp_path) == path and path.stat().st_mtime_ns == mtime  # current: not recomputed
    # the report's figure of it: states and barriers versus protrusion
    from pipeline.analyses import plots
    from pipeline.analyses.report_figures import STATICS_FIGURE
    from pipeline.stages import report
    assert f"figures/{STATICS_FIGURE}" in report.STAGE.output_names(scene) and "statics" in report._upstream(scene)
    png = plots.fig_statics(ds, "paper", tmp_path / STATICS_FIGURE)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_a_statics_grid_beyond_the_scene_limit_is_refused_before_anything_runs(paper_config, tmp_path, capsys):
    from pipeline import cli
    out = tmp_path / "out"
    assert cli.main(["statics", str(paper_config), "--out", str(out), "--set",
                     "sweep.protrusion_nm={start=0.0, stop=15.0, step=1e-5}"]) == 2
    assert "1,500,001 statics protrusions" in capsys.readouterr().err and not (out / "statics.nc").exists()
