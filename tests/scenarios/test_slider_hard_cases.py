"""Hard cases of the slider dynamics on the paper scene: they must stay finite, physical and converged.

Every case starts from configs/paper-2009.toml (pipeline.config.scene.load_scene) with contact.k = 0.445 and a
short run (duration 1.0 ms, transient 0.3 ms), and changes one thing:

* deep interference: protrusion 15 nm (the top of the paper's range);
* zero air-bearing damping (damping_ratio 0);
* a surface 100 x rougher: sigma x 100 with R x 100 and eta / 10^4, so that sigma*eta*R, hence the
  McCool bandwidth alpha = 2412.74 (sigma eta R)^2, and sigma_s/R, hence the plasticity index (and
  the hardness derived from it) stay the same: a geometrically scaled copy of the paper surface.
  (sigma x 100 alone would give alpha ~ 1.6e4, a different kind of surface.) The interface table is
  scaled with it (step 1 nm, up to 300 nm);
* a surface 10 x smoother: sigma / 10, R / 10, eta x 100 (same alpha and psi), table step 0.001 nm;
* a step in the DMW: the paper record plus a 0.5 nm jump at t = 0.5 ms, inside the steady window;
* a very stiff contact: composite_modulus_gpa x 100 with hardness_gpa fixed at the paper value.

Convergence: the hard-case solver is the scene's (rtol 1e-6, atol 1e-4 nm, 20 ns dwell) with
max_step 50 ns instead of 250 ns, which resolves the contact mode (0.9 MHz in the paper scene at
11 nm, 1.4 MHz on the smooth surface; see test_smooth_surface_converges_at_the_default_max_step for
what 250 ns does), and output_step 10 ns instead of 250 ns, so that the time means of summarize()
(sample means on the output grid) do not alias a contact flag that switches every 20-40 ns in a
sliding mode (at 250 ns that sampling error is ~1-2 % of the mean contact force). At 50 ns the steps
are mostly pinned at max_step, so halving rtol/atol alone (the brief's criterion) changes little;
the test also halves max_step. Headline outputs fhm_bv, clearance, contact_force must agree within
1 % relative or 1e-3 nm absolute (FHM converted to nm of peak-to-peak separation; forces relative
only). In the two sliding-mode cases (rough_x100, stiff_contact) the FHM is the amplitude of the
chattering about d = k sigma, an O(dwell) artefact (test_sliding_mode_outputs_versus_the_dwell), and
is left out of the max_step comparison.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from convergence import assert_converged, deltas

from pipeline.model import assembly, copies, outcomes, running
from pipeline.physics import microwaviness as pdmw
from pipeline.config.scene import SCHEMA, load_scene
from pipeline.model import dmw_record
from pipeline.model.interface_tables import build_tables, roughness_statistics
from pipeline.model import state as st
from pipeline.runner import ensure

NM = 1e-9
K = 0.445
HARD_SOLVER = {"duration_ms": 1.0, "transient_ms": 0.3, "max_step_ns": 50.0, "output_step_ns": 10.0}
NAN_OUTSIDE_CONTACT = {"mean_pressure", "friction_coefficient", "shear_stress"}


@pytest.fixture(scope="module")
def base(paper_config):
    return load_scene(paper_config).replace(contact={"k": K}, solver=HARD_SOLVER)


@pytest.fixture(scope="module")
def record(base, tmp_path_factory):
    """The scene's DMW record (displacement [nm], sample rate [Hz]), as the dmw stage makes it."""
    s = dmw_record.settings(base)
    if s["source"] == "synthetic":
        w = pdmw.synthesize(s["rms_nm"], s["band_hz"], s["exponent"], s["duration_s"], s["sample_rate_hz"],
                            s["seed"])
        return w, s["sample_rate_hz"]
    _, w, fs = dmw_record.load(ensure("dmw", base, tmp_path_factory.mktemp("dmw")))
    return w, fs


@pytest.fixture(scope="module")
def paper_hardness(base):
    ds = build_tables(base, roughness_statistics(base))
    return float(ds["hardness"]), float(ds["composite_modulus"])


def case_scene(base, name, paper_hardness):
    r = base["roughness"]
    if name == "rough_x100":
        rough = base.replace(roughness={"sigma_nm": r["sigma_nm"] * 100, "summit_radius_um": r["summit_radius_um"] * 100,
                                        "summit_density_per_um2": r["summit_density_per_um2"] / 1e4},
                             solver={"table_step_nm": 1.0, "table_max_nm": 300.0})
        # y_s scales with sigma (69 nm here): FH0 is raised by it so that the nominal attitude at 11 nm
        # protrusion keeps d = 0 (docs/model.md, section "Separation datum"). The sliding mode about d = k sigma this case is about
        # needs a contact force at k sigma above the bearing's pull: with the stiff-rear bearing
        # (docs/model.md, section "Air bearing") this surface sits in steady contact 10 nm below k sigma (2 switches), so the
        # case keeps the softer pitch-first root (measured: 27027 switches at the 20 ns dwell).
        fh0 = base["air_bearing"]["flying_height_nm"] + roughness_statistics(rough)["y_s"] / NM
        return rough.replace(air_bearing={"flying_height_nm": fh0, "stiffness_root": "pitch-first"})
    if name == "smooth_div10":
        return base.replace(roughness={"sigma_nm": r["sigma_nm"] / 10, "summit_radius_um": r["summit_radius_um"] / 10,
                                       "summit_density_per_um2": r["summit_density_per_um2"] * 100},
                            solver={"table_step_nm": 0.001, "table_max_nm": 15.0})
    if name == "zero_damping":
        return base.replace(air_bearing={"damping_ratio": 0.0})
    if name == "zero_damping_frictionless":
        effects = [e for e in base["scene"]["effects"] if e != "friction"]
        return base.replace(air_bearing={"damping_ratio": 0.0}, scene={"effects": effects})
    if name == "stiff_contact":
        H, E = paper_hardness
        return base.replace(materials={"composite_modulus_gpa": 100 * E, "hardness_gpa": H})
    return base


def build(scene, record):
    interface = build_tables(scene, roughness_statistics(scene))
    return assembly.build_model(scene, interface, record, scene["contact"]["k"]), interface


def case_record(name, record):
    w, fs = record
    if name == "dmw_step":
        t = np.arange(w.size) / fs
        return w + np.where(t >= 0.5e-3, 0.5, 0.0), fs
    return record


def assert_physical(run, hist, summary):
    """Every history finite (the documented NaN-outside-contact ones where defined), forces >= 0,
    real area within the nominal area, fractions in [0, 1]."""
    assert np.all(np.isfinite(run.state))
    inc = hist["in_contact"]
    for name, v in hist.items():
        v = np.asarray(v)
        if name in NAN_OUTSIDE_CONTACT:
            defined = inc & (hist["real_area"] > 0) & (hist["contact_force"] > 0)
            assert np.all(np.isfinite(v[defined])), name
            assert np.all(np.isnan(v[~inc])), name
            assert np.all(v[defined] >= 0), name
        else:
            assert np.all(np.isfinite(v)), name
    for name in ("contact_force", "friction_force", "adhesion_force", "real_area"):
        assert np.all(hist[name] >= 0), name
    assert np.all(hist["contact_force"][~inc] == 0) and np.all(hist["friction_force"][~inc] == 0)
    assert run.nominal_area > 0
    assert np.all(hist["real_area"] <= run.nominal_area * (1 + 1e-12))
    assert 0.0 <= summary["contact_fraction"] <= 1.0
    for name, v in summary.items():
        if summary["contact_fraction"] > 0 or name not in {"interference", "real_area", "mean_pressure",
                                                            "friction_coefficient", "shear_stress"}:
            assert np.isfinite(v), name
    for name in ("contact_force", "friction_force", "adhesion_force"):
        assert summary[name] >= 0, name
    assert summary["real_area"] <= run.nominal_area or np.isnan(summary["real_area"])


CASES = [
    # name, protrusion [nm], sliding mode
    ("deep_interference", 15.0, False),
    ("zero_damping", 11.0, False),
    ("rough_x100", 11.0, True),
    ("smooth_div10", 11.0, False),
    ("dmw_step", 11.0, False),
    ("stiff_contact", 11.0, True),
]


@pytest.mark.parametrize("name, protrusion, sliding", CASES, ids=[c[0] for c in CASES])
def test_hard_case_is_finite_physical_and_converged(base, record, paper_hardness, name, protrusion, sliding):
    # Measured changes (rtol/atol halved | rtol, atol and max_step halved), relative (absolute):
    #   deep_interference  fhm 3e-8 | 1e-8,  clearance 5e-13 | 1e-11,  contact_force 2e-12 | 2e-10
    #   zero_damping       fhm 0 | 0.06 % (7e-4 nm), clearance 0 | 0.01 % (6e-5 nm), force 0 | 3e-5
    #   rough_x100         fhm 0 | (skipped; 0.5 %), clearance 0 | 0.02 % (5e-8 nm), force 0 | 0.06 %
    #   smooth_div10       fhm 0 | 3e-6,     clearance 0 | 6e-11,    contact_force 0 | 3e-10
    #   dmw_step           fhm 0 | 2e-5,     clearance 0 | 2e-7,     contact_force 0 | 8e-8
    #   stiff_contact      fhm 0 | (skipped; 14 %, 5e-3 nm), clearance 0 | 0.4 % (4e-5 nm), force 0 | 6e-5
    # (0 = bit-identical: with max_step 50 ns and the 20 ns dwell the steps do not depend on rtol/atol.)
    scene = case_scene(base, name, paper_hardness)
    model, interface = build(scene, case_record(name, record))
    if name in ("rough_x100", "smooth_div10"):
        # the scaled copies keep the bandwidth and the plasticity index of the paper surface
        ref = build_tables(base, roughness_statistics(base))
        # tol: scaled copies: alpha is scale-free, a few roundings of the scale
        assert float(interface["bandwidth_alpha"]) == pytest.approx(float(ref["bandwidth_alpha"]), rel=1e-9)
        # tol: scaled copies: psi is scale-free, a few roundings of the scale
        assert float(interface["plasticity_index_gw"]) == pytest.approx(float(ref["plasticity_index_gw"]), rel=1e-9)
    if name == "stiff_contact":
        # tol: a product by 100, a few roundings
        assert float(interface["composite_modulus"]) == pytest.approx(100 * paper_hardness[1], rel=1e-12)
        # tol: the same hardness, through NetCDF float64
        assert float(interface["hardness"]) == pytest.approx(paper_hardness[0], rel=1e-12)

    delta = protrusion * NM
    run = running.run_model(model, delta)
    hist = outcomes.histories(run)
    s = outcomes.summarize(run, hist)
    assert_physical(run, hist, s)
    assert s["contact_fraction"] > 0  # every case is in contact at these protrusions

    half_tol = copies.with_solver(model, rtol=model.rtol / 2, atol=model.atol / 2)
    s_tol = outcomes.summarize(running.run_model(half_tol, delta))
    assert_converged(deltas(s, s_tol), f"{name}, rtol/atol halved")
    half_all = copies.with_solver(half_tol, max_step=model.max_step / 2)
    s_all = outcomes.summarize(running.run_model(half_all, delta))
    assert_converged(deltas(s, s_all), f"{name}, rtol/atol/max_step halved", skip=("fhm_bv",) if sliding else ())


# The brief's criterion at the scene's own solver, where the steps are set by the error control and
# the stiffness cap. Undamped cases are the exception: with nothing dissipating, phase errors of the
# contact mode accumulate over the 2 ms and the default solver errs by several per cent (measured for
# undamped, frictionless surfing at 11 nm: FHM/BV 9.65 % at the defaults against 9.05 % converged); they
# converge under refinement from rtol 1e-8, which the test checks. With friction and no damping the
# friction moment -friction_arm A_n tau(d), a circulatory force, destabilises surfing: no convergence is
# expected and only finiteness and physical bounds are checked (test_hard_case_is_finite_...).
@pytest.mark.parametrize("name, protrusion, rtol", [("deep_interference", 15.0, None),
                                                    ("zero_damping_frictionless", 11.0, 1e-8),
                                                    ("dmw_step", 11.0, None)])
def test_default_solver_converges_under_tolerance_halving(base, record, paper_hardness, name, protrusion, rtol):
    scene = case_scene(base, name, paper_hardness).replace(
        solver={"max_step_ns": SCHEMA["solver"]["max_step_ns"].default,
                "output_step_ns": SCHEMA["solver"]["output_step_ns"].default})
    model, _ = build(scene, case_record(name, record))
    if rtol is not None:
        model = copies.with_solver(model, rtol=rtol, atol=model.atol * rtol / model.rtol)
    delta = protrusion * NM
    s = outcomes.summarize(running.run_model(model, delta))
    s_half = outcomes.summarize(running.run_model(copies.with_solver(model, rtol=model.rtol / 2, atol=model.atol / 2), delta))
    assert_converged(deltas(s, s_half), f"{name} at the default solver")


def test_dmw_step_is_followed_and_settles(base, record):
    # The 0.5 nm jump in the record is a 0.5 nm jump of the disk under each point (the pads see it
    # 0.9-37 us before the TFC point). The slider, surfing at 11 nm, must follow it: a transient of
    # d (measured 1.16 nm peak-to-peak in the 0.1 ms after the jump, BV of the window 10.6 % against
    # 0.41 % without the step) that dies out, leaving the same mean separation (measured: equal to
    # 1e-4 nm) and the same vibration as the run without the step (late peak-to-peak 0.0418 nm in both).
    runs = {}
    for label, rec in (("plain", record), ("step", case_record("dmw_step", record))):
        model, _ = build(base, rec)
        run = running.run_model(model, 11 * NM)
        runs[label] = (run.time, outcomes.histories(run))
    t, h = runs["step"]
    _, h0 = runs["plain"]
    d, d0 = h["separation"], h0["separation"]
    before, after, jump = (t > 0.4e-3) & (t < 0.49e-3), t > 0.9e-3, (t > 0.5e-3) & (t < 0.6e-3)
    assert h["disk_displacement"][after].mean() - h["disk_displacement"][before].mean() > 0.4 * NM
    assert abs(d[after].mean() - d[before].mean()) < 0.01 * NM
    assert np.ptp(d[jump]) > 10 * np.ptp(d0[jump])
    assert np.ptp(d[after]) == pytest.approx(np.ptp(d0[after]), rel=0.01)


def test_zero_damping_deep_interference_stays_finite(base, record, paper_hardness):
    # Zero damping at 15 nm: friction (a moment -friction_arm A_n tau(d) that depends on d, a circulatory,
    # non-conservative force) and the DMW pump energy into the slider and nothing takes it out: it
    # bounces violently (measured FHM/BV ~700-1000 %, contact in 5-7 % of the window). This motion is
    # chaotic, so it does not converge under tolerance changes (FHM changes ~15 %); it must still stay
    # finite and physical. The energy is the start's: from the nominal attitude, 4 nm inside the disk,
    # which nothing damps. From its static contact equilibrium (the default start) the same slider
    # stays surfing over the 2 ms (measured): the case is the nominal start's.
    model, _ = build(case_scene(base, "zero_damping", paper_hardness).replace(solver={"start": "nominal"}), record)
    run = running.run_model(model, 15 * NM)
    hist = outcomes.histories(run)
    s = outcomes.summarize(run, hist)
    assert_physical(run, hist, s)
    assert s["regime"] == outcomes.BOUNCING


@pytest.mark.parametrize("name", ["rough_x100", "stiff_contact"])
def test_sliding_mode_outputs_versus_the_dwell(base, record, paper_hardness, name):
    # In these two cases the contact force at d = k sigma exceeds the pull into contact, so the exact
    # solution slides along d = k sigma (a Filippov sliding mode; ~5000 and ~20000 switches per ms).
    # The integrator holds a mode for solver.min_dwell_ns after a switch. Halving the dwell
    # (20 -> 10 -> 5 ns): the mean contact force converges (changes <= 0.4 % measured), while
    # the clearance (overshoot past k sigma) and the FHM shrink with the dwell: they are chattering
    # artefacts of size O(dwell), not physics. Measured (10 ns output): clearance -8.1e-3, -4.8e-3,
    # -2.6e-3 nm and FHM 0.30, 0.18, 0.14 % for the stiff contact; clearance -2.6e-4, -6.5e-5,
    # -1.6e-5 nm and FHM 0.020, 0.0049, 0.0012 % for the rough surface.
    model, _ = build(case_scene(base, name, paper_hardness), record)
    out = []
    for dwell in (20e-9, 10e-9, 5e-9):
        p = model.p.copy()
        p.dwell = dwell
        run = running.run_model(dataclasses.replace(model, p=p), 11 * NM)
        out.append((outcomes.summarize(run), run.info[st.SWITCHES]))
    forces = np.array([s["contact_force"] for s, _ in out])
    clearance = np.array([abs(s["clearance"]) for s, _ in out])
    fhm = np.array([s["fhm_bv"] for s, _ in out])
    assert all(n > 2000 for _, n in out)                       # switching, many times per ms
    assert np.all(np.abs(np.diff(forces)) / forces[1:] < 0.01)   # force: converged to < 1 %
    assert np.all(np.diff(clearance) < 0)                       # overshoot shrinks with the dwell
    assert np.all(np.diff(fhm) < 0)                             # and so does the chattering FHM
    assert clearance[-1] < 1e-3 * NM * 5                        # and is a few thousandths of a nm at most


# Regression test (fixed): pipeline/model/assembly.py build_model (solver defaults): with the default
# max_step 250 ns the contact mode of the smooth surface (~1.4 MHz, A_n dp_c/dd = 1.2e7 N/m on the
# TFC point's effective mass) is integrated at the DP5 stability boundary (h*omega ~ 2.3, 34 %
# rejected steps); its ringing error accumulates to 0.002-0.003 nm (20-30 x atol), FHM is 0.190 %
# against the converged 0.151 % and halving rtol/atol changes it by 13 % (0.0027 nm). Fix: in
# build_model cap max_step below the contact-mode period (e.g. h_max <= 0.5/f_c with f_c from A_n
# max|dp_c/dd| and 1/m + l_c^2/I), and scale the velocity atol with that frequency instead of the
# 300 kHz air-bearing mode.
def test_smooth_surface_converges_at_the_default_max_step(base, record, paper_hardness):
    scene = case_scene(base, "smooth_div10", paper_hardness).replace(solver={"max_step_ns": 250.0})
    model, _ = build(scene, record)
    s = outcomes.summarize(running.run_model(model, 11 * NM))
    s_half = outcomes.summarize(running.run_model(copies.with_solver(model, rtol=model.rtol / 2, atol=model.atol / 2), 11 * NM))
    assert_converged(deltas(s, s_half), "smooth surface at max_step 250 ns")
