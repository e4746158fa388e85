"""Hard cases of the whole chain (interface tables -> slider dynamics) beyond scenarios/test_slider_hard_cases.py.

Every case starts from configs/paper-2009.toml with contact.k = 0.445 and a short run (duration
1.0 ms, transient 0.3 ms) at the scene's own solver (rtol 1e-6, atol 1e-4 nm, max_step 500 ns),
unless it says otherwise, and checks:

* finiteness of every history (the contact-only ratios mean_pressure, friction_coefficient and
  shear_stress are NaN out of contact, and wherever their denominator is zero);
* physical bounds: contact_fraction in [0, 1], forces >= 0, real area <= nominal area, friction
  coefficient >= 0, regime in {0, 1, 2} and consistent with the contact fraction;
* convergence where it is expected: halving rtol/atol (and then also max_step) changes the headline
  outputs fhm_bv, clearance and contact_force by < 1 % relative or < 1e-3 nm absolute (FHM converted
  to nm of peak-to-peak separation; the force relative only).

The cases (the brief's numbering):

1. very large air-bearing damping (damping ratio 0.9 and 0.99), flying and surfing;
2. roughness from 0.05 to 5 nm, geometrically scaled copies of the paper surface (McCool's alpha and
   the plasticity index kept), each at a protrusion that puts it in contact (d ~ 0);
3. asperity statistics at the edge of McCool's validity (alpha -> 0.8968);
4. the Lennard-Jones law at vanishing gap, and the adhesion table near the lubricant surface d = t,
   including t = 0;
5. a DMW at the Nyquist limit of its sampling (band up to fs/2, and a sinusoid one bin below fs/2);
6. 20 ms runs: energy of undamped free vibration, and the drift of a long surfing run;
7. property-based runs over random physical parameter sets (hypothesis).

Genuine bugs found are marked ``xfail(strict=True)`` with the file, function, repro and proposed
fix in the reason; the measured numbers are in the comments of each test:

* statistics.summit_sigma returns NaN for 0.8968 < alpha <= 0.8968155 (ALPHA_MIN is rounded);
* the interface tables start at table_min_sigma*sigma_s, which the dynamics leaves (steady state
  near McCool's limit, deep starts), and the kernel extrapolates them linearly; together with the
  uncapped GW real-area fraction, the real area of a run can exceed the nominal area;
* (fixed: the integrator's exact extremes of d and its contact-switch search missed DMW content
  faster than the step, a DMW at the Nyquist limit; they now split each step at the DMW knots);
* DP5 at the default max_step (500 ns) damps an undamped slider numerically (76 % of the energy
  in 20 ms).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst
from scipy import integrate

from convergence import assert_converged, deltas
from pipeline.model import piecewise as pw
from pipeline.model import assembly, copies, outcomes, running
from pipeline.physics import air_bearing as ab
from pipeline.physics import asperity
from pipeline.physics import microwaviness as pdmw
from pipeline.physics import isbl
from pipeline.physics.adhesion import lennard_jones_force, meniscus_force
from pipeline.physics.asperity_statistics import ALPHA_MIN, bandwidth_alpha, summit_sigma
from pipeline.config.scene import load_scene
from pipeline.model import dmw_record
from pipeline.model.interface_tables import build_tables, interface_parameters, roughness_statistics
from pipeline.model import state as st

NM = 1e-9
K = 0.445
FH0 = 11 * NM
SHORT = {"duration_ms": 1.0, "transient_ms": 0.3}
#: outputs that are ratios over the contact (NaN where their denominator is zero)
RATIOS = {"mean_pressure", "friction_coefficient", "shear_stress"}
#: summary outputs defined only in contact
CONTACT_ONLY = RATIOS | {"interference", "real_area"}
PAPER_ALPHA = 2412.74 * (0.52e-9 * 13.3e12 * 5e-6) ** 2   # 2.885 (sigma 0.52 nm, eta 13.3 um^-2, R 5 um)


# ---------------------------------------------------------------------------------------------
# helpers

@pytest.fixture(scope="module")
def base(paper_config):
    return load_scene(paper_config).replace(contact={"k": K}, solver=SHORT)


def scene_record(scene, duration_s=None):
    """The scene's synthetic DMW record (displacement [nm], sample rate [Hz]), as the dmw stage makes it."""
    s = dmw_record.settings(scene)
    dur = s["duration_s"] if duration_s is None else duration_s
    return pdmw.synthesize(s["rms_nm"], s["band_hz"], s["exponent"], dur, s["sample_rate_hz"], s["seed"]), \
        s["sample_rate_hz"]


@pytest.fixture(scope="module")
def record(base):
    return scene_record(base)


def build(scene, record=None):
    """Model and interface dataset of a scene (tables in memory; the scene's own DMW by default)."""
    interface = build_tables(scene, roughness_statistics(scene))
    if "dmw" in scene.effects and record is None:
        record = scene_record(scene)
    k = scene["contact"]["k"] if "contact" in scene.effects else None
    return assembly.build_model(scene, interface, record if "dmw" in scene.effects else None, k), interface


def simulate(model, delta, y0=None):
    run = running.run_model(model, delta, y0=y0)
    hist = outcomes.histories(run)
    return run, hist, outcomes.summarize(run, hist)


def scaled_roughness(scene, sigma_nm):
    """The scene's surface scaled geometrically to rms ``sigma_nm``: R x f, eta / f^2 (f = sigma ratio),
    so that sigma*eta*R (McCool's alpha) and sigma_s/R (the plasticity index, hence H) are kept."""
    r = scene["roughness"]
    f = sigma_nm / r["sigma_nm"]
    return {"sigma_nm": sigma_nm, "summit_radius_um": r["summit_radius_um"] * f,
            "summit_density_per_um2": r["summit_density_per_um2"] / f**2}


def density_for_alpha(alpha, sigma, R):
    """Summit density [m^-2] that gives McCool's bandwidth ``alpha = 2412.74 (sigma eta R)^2``."""
    return np.sqrt(alpha / 2412.74) / (sigma * R)


def assert_physical(run, hist, s):
    """Finite histories, forces >= 0, real area <= nominal area, friction coefficient >= 0, contact
    fraction in [0, 1], regime consistent; summary likewise."""
    assert np.all(np.isfinite(run.state))
    inc = hist.get("in_contact", np.zeros(run.time.size, bool))
    for name, v in hist.items():
        v = np.asarray(v)
        if name in RATIOS:
            denom = hist["real_area"] if name != "friction_coefficient" else hist["contact_force"]
            defined = inc & (denom > 0)
            assert np.all(np.isfinite(v[defined])), name
            assert np.all(v[defined] >= 0), name
            assert np.all(np.isnan(v[~defined])), name          # NaN only where undefined
        else:
            assert np.all(np.isfinite(v)), name
    for name in ("contact_force", "friction_force", "adhesion_force", "real_area"):
        if name in hist:
            assert np.all(hist[name] >= 0), name
    if "contact_force" in hist:
        assert np.all(hist["contact_force"][~inc] == 0) and np.all(hist["real_area"][~inc] == 0)
        assert run.nominal_area > 0
        assert np.all(hist["real_area"] <= run.nominal_area * (1 + 1e-9)), \
            f"real area up to {hist['real_area'].max() / run.nominal_area:.3f} x the nominal area"
    if "friction_force" in hist:
        assert np.all(hist["friction_force"][~inc] == 0)
    if "contact_fraction" in s:
        frac = s["contact_fraction"]
        assert 0.0 <= frac <= 1.0
        assert s["regime"] in (outcomes.FLYING, outcomes.BOUNCING, outcomes.SURFING)
        # flying: no sample in contact and the exact minimum of d above k sigma (outcomes.summarize)
        touched = frac > 0 or run.d_extremes[0] < run.model.k_sigma
        assert (s["regime"] == outcomes.FLYING) == (not touched)
        assert (s["regime"] == outcomes.SURFING) == (frac >= outcomes.SURFING_FRACTION)
    for name, v in s.items():
        if name == "protrusion_radius":
            assert v > 0            # inf for a flat slider (protrusion 0) or beyond float range (1e-313 nm)
            continue
        if name in CONTACT_ONLY:
            if s.get("contact_fraction", 0) == 0:
                assert np.isnan(v), name
                continue
            if name in ("mean_pressure", "shear_stress", "real_area") and not s["real_area"] > 0:
                continue
            if name == "friction_coefficient" and not s["contact_force"] > 0:
                continue
        assert np.isfinite(v), name
    for name in ("contact_force", "friction_force", "adhesion_force"):
        if name in s:
            assert s[name] >= 0, name
    if "friction_coefficient" in s and np.isfinite(s["friction_coefficient"]):
        assert s["friction_coefficient"] >= 0
    if "real_area" in s and np.isfinite(s["real_area"]):
        assert s["real_area"] <= run.nominal_area * (1 + 1e-9)


def refine(model, delta, max_step=True):
    """Headline changes when rtol/atol are halved, and when max_step is halved as well."""
    s = outcomes.summarize(running.run_model(model, delta))
    half = copies.with_solver(model, rtol=model.rtol / 2, atol=model.atol / 2)
    out = {"rtol/atol halved": deltas(s, outcomes.summarize(running.run_model(half, delta)))}
    if max_step:
        half_all = copies.with_solver(half, max_step=model.max_step / 2)
        out["rtol/atol/max_step halved"] = deltas(s, outcomes.summarize(running.run_model(half_all, delta)))
    return out


def assert_refines(model, delta, max_step=True, skip=()):
    for what, d in refine(model, delta, max_step).items():
        assert_converged(d, what, skip)


# ---------------------------------------------------------------------------------------------
# 1. very large damping

@pytest.mark.parametrize("zeta", [0.9, 0.99])
@pytest.mark.parametrize("protrusion", [5.0, 11.0], ids=["flying-5nm", "surfing-11nm"])
def test_very_large_damping_is_finite_physical_and_converged(base, record, zeta, protrusion):
    # Pad dampers for a modal damping ratio of 0.9/0.99 (air_bearing.pad_damping) are ~18-20 x the
    # paper's: the modes are nearly critically damped and the step controller rejects more steps
    # (456 of 2691 at 0.99 flying, against 0 at 0.05). Measured relative changes (rtol/atol | + max_step):
    #   0.9  flying   fhm 3.6e-5 | 6.8e-5,  clearance 2e-7 | 7e-8
    #   0.99 flying   fhm 1.2e-4 | 6.7e-5,  clearance 5e-8 | 3e-7
    #   0.9  surfing  fhm 2.2e-5 | 2.2e-5,  clearance 3e-9, contact force 5e-9 (the stiffness cap sets the steps)
    #   0.99 surfing  fhm 5.8e-5 | 5.8e-5,  clearance 4e-10, contact force 8e-10
    interface = build_tables(base, roughness_statistics(base))
    model = assembly.build_model(base, interface, record, K, damping_ratio=zeta)
    assert model.info["damping_ratio"] == zeta
    assert model.slider.c_f > 0 and model.slider.c_r > 0
    run, hist, s = simulate(model, protrusion * NM)
    assert_physical(run, hist, s)
    assert s["regime"] == (outcomes.FLYING if protrusion == 5.0 else outcomes.SURFING)
    assert_refines(model, protrusion * NM)


def test_flying_fhm_falls_monotonically_with_damping(base, record):
    # More pad damping ties the slider to the disk under its pads (the damper transmits the disk's
    # velocity), so the flying FHM falls towards the rigid-following floor. Measured at 5 nm with the
    # stiff-rear bearing (docs/model.md, section "Air bearing"): FHM 10.52 (0.02), 7.32 (0.05), 3.65 (0.2), 3.168 (0.9),
    # 3.201 % (0.99). Near critical damping the floor is flat and may rise slightly: the pad dampers
    # transmit the disk's velocity, and above sqrt(2) times a natural frequency a base-excited
    # oscillator transmits more with more damping (1.0 % more at 0.99; the pitch-first bearing fell 1.7 %).
    interface = build_tables(base, roughness_statistics(base))
    fhm = {}
    for zeta in (0.02, 0.05, 0.2, 0.9, 0.99):
        run, hist, s = simulate(assembly.build_model(base, interface, record, K, damping_ratio=zeta), 5 * NM)
        assert s["regime"] == outcomes.FLYING
        fhm[zeta] = s["fhm_bv"]
    seq = [fhm[z] for z in (0.02, 0.05, 0.2, 0.9)]
    assert np.all(np.diff(seq) < 0), fhm
    assert fhm[0.99] < fhm[0.05] and fhm[0.9] < fhm[0.05]
    assert fhm[0.99] <= fhm[0.9] * 1.02, fhm


# ---------------------------------------------------------------------------------------------
# 2. roughness from 0.05 to 5 nm

@pytest.mark.parametrize("sigma_nm", [0.05, 0.5, 5.0])
def test_roughness_scale_in_contact_is_finite_physical_and_converged(base, record, sigma_nm):
    # Scaled copies of the paper surface (alpha = 2.885 and psi = 0.52 kept, so H is the paper's),
    # table step 0.05 nm x min(f, 1) (0.0048 nm for sigma 0.05) up to 30 nm x max(f, 1), each at the
    # protrusion FH0 - k sigma / 2, so that the nominal attitude sits inside the contact threshold.
    # Output every 10 ns: at 5 nm roughness the run slides along d = k sigma (a Filippov sliding
    # mode, ~39000 switches per ms) and 250-ns sampling aliases the chattering contact flag
    # (contact force changes 1-4 % between solvers at 250 ns, 0.2 % at 10 ns).
    # Measured (rtol/atol | + max_step), relative:
    #   sigma 0.05  surfing  fhm 4.3e-5 | 4.3e-5,  clearance 2e-10 (6e-11 nm), force 4e-10
    #   sigma 0.5   surfing  fhm 7e-6 | 7e-6,      clearance 1e-10 (9e-11 nm), force 3e-10
    #   sigma 5     sliding  fhm 0.045 % | 0.15 %, clearance 0.03 % | 0.05 % (1e-8 nm), force 0.13 % | 0.17 %
    # Steady d min / table floor [nm]: -0.240 / -0.268, -0.417 / -2.68, 2.22 / -26.8 (the first is close).
    f = sigma_nm / base["roughness"]["sigma_nm"]
    scene = base.replace(roughness=scaled_roughness(base, sigma_nm),
                         solver={"table_step_nm": 0.05 * min(f, 1.0), "table_max_nm": 30.0 * max(f, 1.0),
                                 "output_step_ns": 10.0})
    model, interface = build(scene, record)
    # tol: McCool's alpha from the statistics it was set by, a few roundings
    assert float(interface["bandwidth_alpha"]) == pytest.approx(PAPER_ALPHA, rel=1e-9)
    # tol: H is set from psi = 0.52: a round trip of a few roundings and a sqrt
    assert float(interface["plasticity_index_gw"]) == pytest.approx(0.52, rel=1e-9)
    for name in ("contact_pressure", "adhesion_pressure", "friction_stress", "real_area_fraction",
                 "contact_fraction"):
        v = interface[name].values
        assert np.all(np.isfinite(v)) and np.all(v >= 0), name
    delta = FH0 - 0.5 * K * sigma_nm * NM
    run, hist, s = simulate(model, delta)
    assert_physical(run, hist, s)
    assert s["contact_fraction"] > 0.5
    # the steady state stays inside the interface table (no extrapolation below it)
    assert run.d_extremes[0] >= interface["separation"].values[0] * NM
    assert_refines(model, delta)


# ---------------------------------------------------------------------------------------------
# 3. McCool's statistics at the edge of validity

def edge_scene(base, alpha, **solver):
    eta = density_for_alpha(alpha, 0.52e-9, 5e-6)
    return base.replace(roughness={"sigma_nm": 0.52, "summit_radius_um": 5.0,
                                   "summit_density_per_um2": eta * 1e-12}, solver=solver)


@pytest.mark.parametrize("alpha", [0.8969, 0.9, 0.95])
def test_mccool_edge_statistics_tables_and_run(base, record, alpha):
    # sigma_s = sigma sqrt(1 - 0.896815/alpha): 0.0050 nm (0.8969), 0.0309 nm (0.9), 0.123 nm (0.95),
    # against 0.335 nm for the paper surface (alpha 1.631). With psi = 0.52 kept, H falls with sigma_s
    # (0.18, 0.45, 0.90 GPa). The tables stay finite and monotone; the surfing run stays finite and
    # physical, but below alpha ~ 0.9 it runs below the table's floor (steady d down to -1.38 nm at
    # 0.8969 and -0.63 nm at 0.9, floors -0.04 and -0.25 nm; -0.50 vs -0.98 nm at 0.95): see
    # test_mccool_edge_outputs_do_not_depend_on_the_table_floor.
    scene = edge_scene(base, alpha)
    stats = roughness_statistics(scene)
    # tol: McCool's alpha from the statistics it was set by, a few roundings
    assert stats["alpha"] == pytest.approx(alpha, rel=1e-12)
    sigma = stats["sigma"]
    assert 0 < stats["sigma_s"] < 0.25 * sigma
    # tol: McCool's relation rearranged (cancellation 1 - 0.9 at the edge: x10), a few roundings
    assert stats["sigma_s"] == pytest.approx(sigma * np.sqrt(1 - 3.717e-4 * 2412.74 / alpha), rel=1e-9)
    # tol: McCool's relation, a few roundings and a sqrt
    assert stats["y_s"] == pytest.approx(4 * sigma / np.sqrt(np.pi * alpha), rel=1e-12)
    model, interface = build(scene, record)
    for name in ("contact_pressure", "friction_stress", "real_area_fraction", "contact_fraction",
                 "adhesion_pressure"):
        v = interface[name].values
        assert np.all(np.isfinite(v)) and np.all(v >= 0), name
        if name == "friction_stress":
            # friction is carried by elastic and elastic-plastic summits only (docs/model.md, section "ISBL interface"): deep in
            # the fully plastic range it falls again; it never exceeds the shear strength
            assert np.all(v <= float(interface["shear_strength"]) * (1 + 1e-12)), name
        elif name != "adhesion_pressure":
            assert np.all(np.diff(v) <= 0), name
    d = interface["separation"].values
    assert np.all(np.diff(interface["adhesion_pressure"].values[d >= 0]) <= 0)
    run, hist, s = simulate(model, 11 * NM)
    assert_physical(run, hist, s)
    assert s["regime"] == outcomes.SURFING


@pytest.mark.parametrize("alpha", [0.5, 0.85, 0.8967])
def test_mccool_below_the_limit_raises_a_clear_error(base, alpha):
    scene = edge_scene(base, alpha)
    with pytest.raises(ValueError, match="alpha"):
        roughness_statistics(scene)
    eta = density_for_alpha(alpha, 0.52e-9, 5e-6)
    with pytest.raises(ValueError, match=r"alpha = 0\.\d+ <= 0\.8968"):
        summit_sigma(0.52e-9, eta, 5e-6)


# Regression test (fixed): pipeline/physics/asperity_statistics.py:summit_sigma: ALPHA_MIN = 0.8968 is the
# rounded root of the radicand, whose constants give 3.717e-4 * 2412.74 = 0.8968155; for 0.8968 <
# alpha <= 0.8968155 sigma**2 - 3.717e-4/(eta R)**2 < 0, so summit_sigma returns NaN
# (RuntimeWarning) instead of raising, and the NaN reaches isbl.Interface (error 'Interface.sigma_s
# = nan', no mention of alpha). Repro: summit_sigma(0.52e-9, density_for_alpha(0.89681, 0.52e-9,
# 5e-6), 5e-6) -> nan. Fix: raise when the radicand is <= 0 (or set ALPHA_MIN = 3.717e-4 * 2412.74).
def test_summit_sigma_just_above_alpha_min_is_positive_or_rejected():
    for alpha in (0.89681, 0.896815):
        assert alpha > ALPHA_MIN
        eta = density_for_alpha(alpha, 0.52e-9, 5e-6)
        assert bandwidth_alpha(0.52e-9, eta, 5e-6) > ALPHA_MIN
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                s = summit_sigma(0.52e-9, eta, 5e-6)
        except ValueError as exc:
            assert "alpha" in str(exc)
        else:
            assert np.isfinite(s) and s > 0, f"summit_sigma = {s} at alpha = {alpha}"


# Regression test (fixed): pipeline/stages/interface.py:build_tables (grid from
# isbl.separation_grid(table_min_sigma * sigma_s, ...)): the tables start at
# table_min_sigma*sigma_s = -0.25 nm for alpha = 0.9 (sigma_s = 0.031 nm), but adhesion pulls the
# surfing slider to d = -0.58 nm (-19 sigma_s), so the kernel extrapolates the tables linearly below
# their range (piecewise._ppval) for the whole steady window (d down to -0.625 nm): FHM 0.826 %
# against 0.541 % with the table extended to -40 sigma_s, clearance -0.808 against -0.756 nm. Repro:
# alpha 0.9 (eta 7.43 um^-2, sigma 0.52 nm, R 5 um) at 11 nm. Fix: start the grid at
# min(table_min_sigma*sigma_s, table_min_sigma*sigma, FH0 - max protrusion - margin), and make the
# kernel report (status) rather than extrapolate when d leaves the table.
def test_mccool_edge_outputs_do_not_depend_on_the_table_floor(base, record):
    model, interface = build(edge_scene(base, 0.9), record)
    run, _, s = simulate(model, 11 * NM)
    wide, _ = build(edge_scene(base, 0.9, table_min_sigma=-40.0), record)
    s_wide = outcomes.summarize(running.run_model(wide, 11 * NM))
    assert run.d_extremes[0] >= interface["separation"].values[0] * NM, \
        f"steady d down to {run.d_extremes[0] / NM:.3f} nm, table from {interface['separation'].values[0]:.3f} nm"
    assert_converged(deltas(s, s_wide), "table floor -8 -> -40 sigma_s")


# ---------------------------------------------------------------------------------------------
# 4. Lennard-Jones at vanishing gap

@pytest.mark.parametrize("R, dgamma, eps", [(5e-6, 0.106, 0.3e-9), (20e-9, 0.2, 0.05e-9), (1e-6, 1e-3, 1e-9)])
def test_single_summit_adhesion_joins_the_meniscus_continuously(R, dgamma, eps):
    # A summit at z = d - t (gap s = eps) switches from the LJ law to the meniscus 2 pi R dgamma: the
    # values agree (LJ: (8/3) (1 - 1/4) = 2) and so do the slopes (dF/ds = 0 at s = eps), so the
    # composite law of z is C1 there. At and below s = eps the gap is clamped: no s^-8 overflow.
    fm = meniscus_force(R, dgamma)
    with np.errstate(all="raise"):
        # tol: the law at its join is the meniscus force, a few roundings
        assert lennard_jones_force(eps, R, dgamma, eps) == pytest.approx(fm, rel=1e-14)
        for h in (1e-3, 1e-5, 1e-7):
            step = lennard_jones_force(eps * (1 + h), R, dgamma, eps) - fm
            assert abs(step) <= 10 * fm * h**2          # C1 join: the change is second order in h
        tiny = np.array([0.0, -1e-9, 1e-300, 5e-324, 0.5 * eps, eps * (1 - 1e-15)])
        # tol: the clamped law is the meniscus force, a few roundings
        np.testing.assert_allclose(lennard_jones_force(tiny, R, dgamma, eps), fm, rtol=1e-14)
        far = lennard_jones_force(np.geomspace(eps, 1e-3, 200), R, dgamma, eps)
        assert np.all(np.isfinite(far)) and np.all(np.diff(far) <= 0) and far[-1] > 0
    # the composite single-summit law across z = d - t (d, t arbitrary)
    d, t = 0.4e-9, 0.75e-9
    z = (d - t) + eps * np.array([-1e-6, -1e-9, 0.0, 1e-9, 1e-6])
    law = np.where(z < d - t, lennard_jones_force(d - t - z + eps, R, dgamma, eps), fm)
    # tol: the law's own second-order change, 8 fm h^2 = 1e-11 at h = 1e-6
    np.testing.assert_allclose(law, fm, rtol=1e-10)                 # 8 fm h^2 with h = 1e-6


def adhesion_slope(p, d):
    """d p_a / d d [Pa/m] from the ISBL integral differentiated under the integral sign.

    p_a = eta [fm (F(d + 110 w_c) - F(d - t)) + int_{-inf}^{d-t} F_LJ(d - t - z + eps) phi(z) dz]; the
    boundary terms of the two ranges cancel (F_LJ(eps) = fm), leaving
    eta [fm phi(d + 110 w_c) + int F_LJ'(d - t - z + eps) phi(z) dz].
    """
    s = p.sigma_s
    C = 8.0 / 3.0 * np.pi * p.dgamma * p.R

    def phi(z):
        return np.exp(-0.5 * (z / s) ** 2) / (s * np.sqrt(2 * np.pi))

    def dF(g):
        return C * (-2 * p.eps**2 / g**3 + 2 * p.eps**8 / g**9)

    top = d - p.t
    pts = [top - p.eps * m for m in (1, 3, 10, 30) if top - p.eps * m > -isbl.TAIL * s]
    integral = integrate.quad(lambda z: dF(d - p.t - z + p.eps) * phi(z), -isbl.TAIL * s, top, points=pts or None,
                              limit=500, epsabs=0, epsrel=1e-11)[0]
    return p.eta * (meniscus_force(p.R, p.dgamma) * phi(d + 110 * p.w_c) + integral)


@pytest.mark.parametrize("t_nm, eps_nm", [(0.75, 0.3), (0.0, 0.3), (2.0, 0.3), (0.0, 0.05)])
def test_adhesion_pressure_is_smooth_across_the_lubricant_surface(base, t_nm, eps_nm):
    # Across d = t the wetted range and the LJ range of the integral meet (z = d - t = 0, where the
    # Gaussian weight peaks). The table must be continuous with a bounded derivative there: on a
    # 1e-6 nm grid the neighbour-to-neighbour change is the slope times the step (no jump), the
    # finite-difference slope equals the differentiated integral (adhesion_slope) to 1e-6 (measured
    # 4e-8), and the interpolated table the kernel uses has a slope within 5 % of it near d = t.
    # No floating-point overflow/invalid/divide anywhere (np.errstate raise), even for eps = 0.05 nm.
    scene = base.replace(lubricant={"thickness_nm": t_nm, "intermolecular_distance_nm": eps_nm})
    p = interface_parameters(scene, roughness_statistics(scene))
    t = p.t
    with np.errstate(over="raise", invalid="raise", divide="raise", under="ignore"):
        for half in (1e-3, 1e-6):
            d = t + np.linspace(-half, half, 2001) * NM
            pa = isbl.isbl_tables(d, p, quantities=("adhesion_pressure",))["adhesion_pressure"]
            assert np.all(np.isfinite(pa)) and np.all(pa > 0)
            slope = abs(adhesion_slope(p, t))
            assert np.max(np.abs(np.diff(pa))) <= 1.01 * slope * (d[1] - d[0]) + 1e-9 * pa.max()
        for off in (-0.1, 0.0, 0.1, 1.0):
            dd = t + off * NM
            h = 1e-4 * NM
            pa = isbl.isbl_tables(np.array([dd - h, dd + h]), p, quantities=("adhesion_pressure",))["adhesion_pressure"]
            assert (pa[1] - pa[0]) / (2 * h) == pytest.approx(adhesion_slope(p, dd), rel=1e-6)
        interface = build_tables(scene, roughness_statistics(scene))
    x = interface["separation"].values * NM
    c = pw.piecewise_coefficients(interface["adhesion_pressure"].values * 1e6, x[1] - x[0], 3)
    xs = t + np.linspace(-0.3, 0.3, 13) * NM
    hh = 1e-5 * NM
    spline_slope = (pw.ppval(c, x[0], x[1] - x[0], xs + hh) - pw.ppval(c, x[0], x[1] - x[0], xs - hh)) / (2 * hh)
    exact = np.array([adhesion_slope(p, v) for v in xs])
    assert np.all(np.isfinite(spline_slope))
    np.testing.assert_allclose(spline_slope, exact, rtol=0.05)


def test_zero_lubricant_thickness_run_is_finite_physical_and_converged(base, record):
    # t = 0: the lubricant surface is the summit tops, d = t = 0 is the mean summit plane. Surfing at
    # 11 nm. Measured (rtol/atol | + max_step): fhm 1.8e-4, clearance 3e-8 (2e-8 nm), force 5e-8.
    scene = base.replace(lubricant={"thickness_nm": 0.0})
    model, interface = build(scene, record)
    assert float(interface["lubricant_thickness"]) == 0.0
    run, hist, s = simulate(model, 11 * NM)
    assert_physical(run, hist, s)
    assert s["contact_fraction"] > 0
    assert_refines(model, 11 * NM)


# ---------------------------------------------------------------------------------------------
# 5. DMW at the Nyquist limit

NYQUIST = {"band_khz": [10.0, 2000.0], "sample_rate_mhz": 4.0, "rms_nm": 0.163}  # the rms these cases were measured with


@pytest.fixture(scope="module")
def nyquist(base):
    """Scene with the DMW band up to the Nyquist frequency of 4 MS/s, its record, and a 0.05 nm
    sinusoid at fs/2 - one bin (1.99909 MHz on the 1.1 ms record: two samples per period, beating)."""
    scene = base.replace(dmw=NYQUIST, solver={"output_step_ns": 10.0})
    w, fs = scene_record(scene)
    n = w.size
    k_lo, k_hi = pdmw.band_bins(n, fs, (10e3, 2000e3))
    assert k_hi == n // 2                                    # the band really reaches the Nyquist bin
    assert abs(np.fft.rfft(w)[-1]) > 0                       # and the Nyquist bin is populated
    t = np.arange(n) / fs
    sine = 0.05 * np.sin(2 * np.pi * (fs / 2 - fs / n) * t)
    interface = build_tables(scene, roughness_statistics(scene))
    return scene, interface, {"band": (w, fs), "band+sine": (w + sine, fs), "sine": (sine, fs)}


@pytest.mark.parametrize("kind, protrusion", [("band", 5.0), ("band", 11.0), ("band+sine", 11.0), ("sine", 11.0)])
def test_nyquist_dmw_run_is_finite_physical_and_converged_in_rtol(nyquist, kind, protrusion):
    # Measured changes with rtol/atol halved (relative, nm of peak-to-peak for FHM):
    #   band       5 nm  fhm 0.009 % (1.3e-4 nm)   11 nm  fhm 0.08 % (7.8e-4 nm), force 3e-5
    #   band+sine 11 nm  fhm 0.009 % (1e-4 nm), clearance 5e-5, force 3e-5
    #   sine      11 nm  fhm 0.21 % (2.7e-4 nm), force 3e-5
    # (DMW rms 0.163 nm, as measured; with the corrected paper scene's 0.266 nm the band+sine run at
    # 11 nm bounces, in contact 96 % of the window, and its BV and clearance move by 1.1 and 1.6 %
    # with rtol/atol halved: impacts driven by content at the Nyquist limit.)
    scene, interface, records = nyquist
    model = assembly.build_model(scene, interface, records[kind], K)
    run, hist, s = simulate(model, protrusion * NM)
    assert_physical(run, hist, s)
    assert s["regime"] == (outcomes.FLYING if protrusion == 5.0 else outcomes.SURFING)
    assert_refines(model, protrusion * NM, max_step=False)


# Regression test (fixed): the exact extremes of d were taken at step ends and at the extrema of one
# cubic through d and d' at the step's ends, but d contains the DMW spline with knots every 250 ns
# while steps are up to 500 ns, so peaks between knots were missed (flying at 5 nm, band
# [10, 2000] kHz + 0.05 nm sine at fs/2 - one bin: minimum missed by 0.0099 nm, rtol/atol halving
# moved fhm_bv by 0.59 %). Fixed in pipeline/model/stepper.py:knot_extrema (then dynamics.py:_d_extrema): the step is split at the DMW
# knots and each piece's extrema are taken in closed form (d is a cubic between two knots).
@pytest.mark.parametrize("kind", ["sine", "band+sine"])
def test_nyquist_dmw_exact_extremes_bound_the_samples_and_converge(nyquist, kind):
    scene, interface, records = nyquist
    model = assembly.build_model(scene, interface, records[kind], K)
    run, hist, s = simulate(model, 5 * NM)
    win = run.time >= model.transient - 1e-15
    d = hist["separation"][win]
    # exact extremes enclose every sample of d: both come from the same state interpolant and the
    # same DMW spline (1e-5 nm of slack; the paper scene misses by < 1e-6 nm)
    assert run.d_extremes[0] <= d.min() + 1e-5 * NM and run.d_extremes[1] >= d.max() - 1e-5 * NM, \
        (np.array(run.d_extremes) / NM, d.min() / NM, d.max() / NM)
    assert_refines(model, 5 * NM, max_step=False)


# Regression test (fixed by splitting the event search at the DMW knots, stepper.knot_extrema):
# pipeline/model/stepper.py:first_wrong_side: the contact criterion is checked at the step end,
# at the extrema of the step's Hermite cubic of d and at 3 interior points, but the DMW term of d
# varies between its 250-ns knots inside a 500-ns step: excursions of d below k sigma driven by DMW
# content near the Nyquist frequency are missed. Repro: no adhesion, 11 nm, band [10, 2000] kHz
# record + 0.05 nm sine at fs/2 - one bin: 8 samples (10 ns) flying with d up to 0.0031 nm below k
# sigma (none with max_step 50 ns, none without the sine). Fix: also test the criterion at the DMW
# knots inside the step and at the extrema of the exact piecewise cubic of d (as for the extremes),
# or cap max_step at the DMW sample interval.
def test_nyquist_dmw_contact_flag_matches_the_criterion(base, nyquist):
    scene0, _, records = nyquist
    scene = scene0.replace(scene={"effects": ["air_bearing", "pitch", "dmw", "contact", "friction"]})
    model, _ = build(scene, records["band+sine"])
    run, hist, s = simulate(model, 11 * NM)
    assert s["regime"] == outcomes.BOUNCING and run.info[st.SWITCHES] > 100
    flag, c, t = hist["in_contact"], hist["clearance"], run.time
    change_t = t[1:][flag[1:] != flag[:-1]]
    idx = np.searchsorted(change_t, t, side="right") - 1
    since = np.where(idx >= 0, t - change_t[np.maximum(idx, 0)], np.inf)
    held = since <= scene["solver"]["min_dwell_ns"] * 1e-9 + 2 * model.output_step  # within the dwell
    bad = (flag != (c < 0)) & ~held & (np.abs(c) > 1e-12)
    assert not bad.any(), f"{bad.sum()} samples in the wrong mode, |c| up to {np.abs(c[bad]).max() / NM:.4f} nm"


# ---------------------------------------------------------------------------------------------
# 6. very long runs

def free_vibration(base, max_step_ns=None, amplitude=0.01 * NM):
    """Undamped flying slider (air bearing + pitch, no DMW) released from both modes at once, each
    displacing the TFC point by ``amplitude``; 20 ms, output every 1 us."""
    solver = {"duration_ms": 20.0, "transient_ms": 0.0, "output_step_ns": 1000.0}
    if max_step_ns is not None:
        solver["max_step_ns"] = max_step_ns
    scene = base.replace(scene={"effects": ["air_bearing", "pitch"]}, air_bearing={"damping_ratio": 0.0},
                         solver=solver)
    model = assembly.build_model(scene, None, None, None)
    s = model.slider
    _, phi = ab.modes(s.stiffness_matrix, s.mass_matrix)
    x = sum(phi[:, i] / (phi[0, i] - s.l_c * phi[1, i]) for i in range(2)) * amplitude
    return running.run_model(model, 5 * NM, y0=np.r_[x, 0.0, 0.0])


def energies(run):
    """Linearised (0.5 v'Mv + 0.5 x'Kx) and exact energy [J] of every sample; the exact one uses the
    rear law's potential V(g) = F0 [g0^n g^(1-n)/(n-1) + g] (its force is -dV/dg), zero at g0."""
    s = run.model.slider
    x, v = run.state[:, :2], run.state[:, 2:]
    kin = 0.5 * np.einsum("ni,ij,nj->n", v, s.mass_matrix, v)
    lin = kin + 0.5 * np.einsum("ni,ij,nj->n", x, s.stiffness_matrix, x)
    F0, g0, n = s.rear_preload, s.g0, s.n

    def V(g):
        return F0 * (g0**n * g ** (1 - n) / (n - 1) + g)

    g = g0 + x[:, 0] - s.l_r * x[:, 1]
    exact = kin + 0.5 * s.k_f * (x[:, 0] + s.l_f * x[:, 1]) ** 2 + (V(g) - V(g0))
    return lin, exact


def test_undamped_free_vibration_conserves_energy_over_20ms(base):
    # 20 ms of the two free modes (2400 + 6000 periods), 0.01 nm each at the TFC point, default
    # rtol/atol, max_step 40 ns (h omega_2 = 0.075). DP5 is not symplectic: its energy error is a
    # steady numerical damping ~ h^5 (measured drift of the exact energy -4.9e-5 at 40 ns, -1.5e-4
    # at 50 ns, -4.7e-3 at 100 ns, -0.12 at 200 ns; see the xfail below for the default 500 ns).
    # The linearised energy 0.5 v'Mv + 0.5 x'Kx is not a constant of the motion: the rear law's
    # cubic term makes it oscillate by 1.6e-4 of E at 0.01 nm (1.6e-5 at 0.001 nm), so its drift is
    # measured at t_end and between the means of the first and last 2 ms (-4.5e-5); the exact
    # energy (with the rear law's potential) is checked sample by sample. 500 000 steps, 0.1 s.
    run = free_vibration(base, max_step_ns=40.0)
    assert np.all(np.isfinite(run.state))
    lin, exact = energies(run)
    e0 = exact[0]
    assert lin[0] == pytest.approx(e0, rel=1e-3)
    assert abs(exact[-1] - e0) / e0 < 1e-4, (exact[-1] - e0) / e0
    assert np.max(np.abs(exact - e0)) / e0 < 1e-4
    assert abs(lin[-1] - lin[0]) / lin[0] < 1e-4, (lin[-1] - lin[0]) / lin[0]
    w = run.time.size // 10                                   # 2 ms
    assert abs(lin[-w:].mean() - lin[:w].mean()) / lin[0] < 1e-4
    assert np.max(np.abs(lin - exact)) / e0 < 3e-4            # the rear nonlinearity, 1.6e-4 measured


@pytest.mark.xfail(strict=True, reason=(
    "BUG pipeline/config/scene.py SCHEMA solver.max_step_ns (default 500 ns) with pipeline/model/assembly.py "
    "build_model (no cap for undamped scenes): undamped free vibration loses 76 % of its energy in "
    "20 ms at the default solver (exact and linearised energy alike; 13 % in the default 2 ms run): the "
    "steps sit at max_step, h omega = 0.94 for the 300 kHz mode, where DP5 damps numerically (an "
    "equivalent damping ratio ~2e-5), and the error control never sees it because atol (1e-4 nm) is "
    "absolute and the state is sub-nm. Negligible against the sweep's physical damping (>= 0.02) but "
    "it makes damping_ratio = 0 runs dissipative. Repro: 0.01 nm in both modes, damping 0, 20 ms. "
    "Fix: cap max_step at ~0.075/omega_2 (40 ns) when the scene is undamped, or use a symplectic / "
    "energy-aware integrator for damping 0."))
def test_undamped_energy_is_conserved_at_the_default_solver(base):
    run = free_vibration(base)
    lin, exact = energies(run)
    assert abs(exact[-1] - exact[0]) / exact[0] < 1e-4, (exact[-1] - exact[0]) / exact[0]


def test_long_surfing_run_does_not_drift(base):
    # 20 ms surfing at 11 nm (paper scene, damping 0.05, DMW), transient 0.5 ms.
    # (a) the scene's own 20.1 ms record: mean clearance over the first 2 ms (transient included)
    #     -0.628354 nm and over the last 2 ms -0.628479 nm: 1.26e-4 nm apart; the 2-ms block means
    #     from 2 ms on within 1.6e-5 nm of each other.
    # (b) a record that repeats every 2 ms (one 2-ms synthetic record, periodic by construction, tiled):
    #     the forcing of any whole 2-ms window is the same, so a periodic steady state has the same
    #     mean there; measured 1.1e-6 nm between [0.5, 2.5] ms and [18, 20] ms (first 2 ms, with the
    #     transient: 2.4e-4 nm). 110 000 steps, 0.11 s per run.
    scene = base.replace(solver={"duration_ms": 20.0, "transient_ms": 0.5})
    interface = build_tables(scene, roughness_statistics(scene))
    w, fs = scene_record(scene)
    period, _ = scene_record(scene, duration_s=2e-3)
    tiled = np.tile(period, int(np.ceil(w.size / period.size)))
    for label, rec in (("scene record", (w, fs)), ("2-ms periodic record", (tiled, fs))):
        model = assembly.build_model(scene, interface, rec, K)
        run, hist, s = simulate(model, 11 * NM)
        assert_physical(run, hist, s)
        assert s["regime"] == outcomes.SURFING
        c, t = hist["clearance"], run.time
        first, last = c[t < 2e-3].mean(), c[t >= 18e-3].mean()
        assert abs(last - first) < 1e-3 * NM, (label, (last - first) / NM)
        blocks = [c[(t >= a) & (t < a + 2e-3)].mean() for a in np.arange(2e-3, 19e-3, 2e-3)]
        assert np.ptp(blocks) < 1e-3 * NM, label
        if label == "2-ms periodic record":
            a = c[(t >= 0.5e-3) & (t < 2.5e-3)].mean()
            assert abs(last - a) < 1e-5 * NM, (a - last) / NM


# ---------------------------------------------------------------------------------------------
# Real area above the nominal area (the GW area fraction is not capped; below the table it is extrapolated)

def strong_adhesion_scene(base, **solver):
    """A physical parameter set found by the property test below: smooth (sigma 0.2 nm), alpha 3.43,
    strong adhesion (0.2 J/m^2) through a 0.93 nm lubricant, k = -1, light damping, rms 0.5 nm DMW."""
    eta = density_for_alpha(3.43, 0.2e-9, 5e-6)
    return base.replace(roughness={"sigma_nm": 0.2, "summit_radius_um": 5.0, "summit_density_per_um2": eta * 1e-12},
                        lubricant={"thickness_nm": 0.93, "work_of_adhesion_j_m2": 0.2}, contact={"k": -1.0},
                        air_bearing={"damping_ratio": 0.01}, dmw={"rms_nm": 0.5}, solver=solver)


# Regression test (fixed): pipeline/physics/isbl.py:isbl_tables (real_area_fraction = eta int A phi
# dz, not capped at 1) and pipeline/stages/interface.py:build_tables + pipeline/model/piecewise.py:_ppval
# (linear extrapolation below the table's floor table_min_sigma*sigma_s): the real area of a run
# exceeds the nominal area. (a) deep start: the paper surface scaled to sigma 0.25 nm (alpha, psi
# kept) at 15 nm starts at d = FH0 - delta = -3.9 nm, below the floor -1.34 nm; the extrapolated
# area is 1.47 A_n at t = 0 (the tabulated fraction never exceeds 0.47). (b) strong adhesion (sigma
# 0.2 nm, alpha 3.43, 0.2 J/m^2, k = -1, 4.76 nm; table extended to -40 sigma_s so nothing is
# extrapolated): the touchdown transient reaches d = -1.67 nm (t = 195 us) where the GW fraction
# itself is 1.08. In random physical parameter sets (protrusion 0-15 nm, sigma 0.2-1.5 nm, alpha
# 1.2-5, boundaries favoured) 7 % exceed A_n in their transient. Fix: cap the real-area fraction
# (and with it friction) at 1 in the tables, extend the grid to FH0 - max protrusion - margin, and
# hold the first value (or flag the run) instead of extrapolating below the table.
@pytest.mark.parametrize("case", ["deep-start", "strong-adhesion"])
def test_real_area_stays_below_the_nominal_area(base, record, case):
    if case == "deep-start":
        scene = base.replace(roughness=scaled_roughness(base, 0.25))
        model, interface = build(scene, record)
        delta = 15 * NM
    else:
        # the report's touchdown transient is the snap-in from the nominal attitude: started from its
        # static contact equilibrium (the default start) the run sits in contact at half the cap
        # (max real area 1.56e-11 m^2 = 0.51 A_n, measured) and never tests it
        scene = strong_adhesion_scene(base, table_min_sigma=-40.0, start="nominal")
        model, interface = build(scene)
        delta = 9.0 * NM  # (in contact, the area at the cap A_n, inside the table: measured)
    run, hist, s = simulate(model, delta)
    if case == "strong-adhesion":   # no extrapolation: the whole run stays inside the table
        assert hist["separation"].min() >= interface["separation"].values[0] * NM
    assert_physical(run, hist, s)
    # deep start: fractions 0.22 and the clipped 1 (d = -4.2 nm) checked. The strong-adhesion set no
    # longer touches at the 4.76 nm of the original report with the present model (d >= 3.45 nm in the
    # steady window); at 9 nm it is in contact and its real area reaches the cap A_n
    if case == "strong-adhesion":
        assert hist["real_area"].max() == pytest.approx(run.nominal_area, rel=1e-6)
    assert assert_gw_area(scene, interface, run, hist, samples=8) > 0


# ---------------------------------------------------------------------------------------------
# 7. properties over random physical parameter sets

def _floats(lo, hi):
    return hst.floats(lo, hi, allow_subnormal=False)


@hst.composite
def physical_scenes(draw):
    sigma = draw(_floats(0.2, 1.5))                         # nm
    alpha = draw(_floats(1.2, 5.0))
    eta = density_for_alpha(alpha, sigma * NM, 5e-6)        # R = 5 um (the paper's)
    return {
        # 0, or at least 1e-6 nm: a protrusion below ~1e-299 nm is subnormal in metres and only
        # makes geometry.section_fraction/effective_radius warn about overflow (the results, u = 1
        # and an infinite radius, are right)
        "protrusion": draw(hst.one_of(hst.just(0.0), _floats(1e-6, 15.0))),
        "damping": draw(_floats(0.01, 0.3)),
        "roughness": {"sigma_nm": sigma, "summit_radius_um": 5.0, "summit_density_per_um2": eta * 1e-12},
        "alpha": alpha,
        "dmw": {"rms_nm": draw(_floats(0.05, 0.5))},
        "contact": {"k": draw(_floats(-1.0, 2.0))},
        "lubricant": {"thickness_nm": draw(_floats(0.0, 2.0)),
                      # 0, or at least 1e-6 J/m^2: a work of adhesion near the float underflow (2e-308,
                      # drawn by hypothesis) only tests the spline's arithmetic (the adhesion table then
                      # dips to -3e-312 Pa, and histories() does not clamp the adhesion force at 0 as it
                      # does the contact ones)
                      "work_of_adhesion_j_m2": draw(hst.one_of(hst.just(0.0), _floats(1e-6, 0.2)))},
    }


def gw_area_fraction(d, p):
    """Real-area fraction ``eta int_d^inf A(z - d) phi(z) dz`` [1] at separation ``d`` [m] [GW66], by
    adaptive quadrature of the single-summit area :func:`pipeline.physics.asperity.contact_area` [KE02]
    against the Gaussian summit heights: independent of the ISBL tables' Gauss-Legendre panels and
    of the kernel's spline through them."""
    s, wc = p.sigma_s, p.w_c
    lo, hi = max(d, -20 * s), 20 * s                 # the Gaussian weight beyond 20 sigma_s is < 1e-86
    if lo >= hi:
        return 0.0
    pts = [x for x in (d + wc, d + asperity.X_MID * wc, d + asperity.X_PLASTIC * wc) if lo < x < hi]

    def f(z):
        return float(asperity.contact_area(z - d, p.R, p.E, p.H, p.nu)) * np.exp(-0.5 * (z / s) ** 2) \
            / (s * np.sqrt(2 * np.pi))

    return p.eta * integrate.quad(f, lo, hi, points=pts or None, limit=500, epsabs=0, epsrel=1e-10)[0]


def assert_gw_area(scene, interface, run, hist, samples=4):
    """The real area of ``samples`` contact samples inside the table (spread over the run, and the
    deepest one) equals ``A_n min(1, gw_area_fraction(d))`` to 1e-4 (the spline through the 0.05-nm
    table: 3e-6 measured); returns how many samples were checked."""
    d = hist["separation"]
    probe = np.flatnonzero(run.contact & (d >= interface["separation"].values[0] * NM))
    if not probe.size:
        return 0
    p = interface_parameters(scene, roughness_statistics(scene))
    pick = set(probe[np.linspace(0, probe.size - 1, samples).round().astype(int)]) | {probe[np.argmin(d[probe])]}
    for i in sorted(pick):
        expect = run.nominal_area * min(1.0, gw_area_fraction(d[i], p))
        assert hist["real_area"][i] == pytest.approx(expect, rel=1e-4, abs=1e-9 * run.nominal_area), d[i] / NM
    return len(pick)


@settings(max_examples=15, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(prm=physical_scenes())
def test_random_physical_scenes_are_finite_and_physical(paper_config, prm):
    # 0.5 ms runs (transient 0.1 ms), R = 5 um, eta from alpha. Derandomized, so that the suite is
    # reproducible; explorations of 300-600 examples found no violation of the properties below.
    # The real area never exceeds the nominal area (the GW fraction can exceed 1 at deep interference,
    # the outputs clip it: test_real_area_stays_below_the_nominal_area), and where d lies inside the
    # interface table it equals A_n min(1, GW fraction) by independent quadrature (gw_area_fraction)
    # at a few contact samples; below the table the kernel extrapolates it (the steady window leaves
    # the table in 1 of 300 sets: test_mccool_edge_outputs_do_not_depend_on_the_table_floor).
    scene = load_scene(paper_config).replace(
        solver={"duration_ms": 0.5, "transient_ms": 0.1}, air_bearing={"damping_ratio": prm["damping"]},
        roughness=prm["roughness"], dmw=prm["dmw"], contact=prm["contact"], lubricant=prm["lubricant"])
    model, interface = build(scene)
    # tol: McCool's alpha from the statistics it was set by, a few roundings
    assert float(interface["bandwidth_alpha"]) == pytest.approx(prm["alpha"], rel=1e-9)
    for name in ("contact_pressure", "adhesion_pressure", "friction_stress", "real_area_fraction",
                 "contact_fraction"):
        v = interface[name].values
        assert np.all(np.isfinite(v)) and np.all(v >= 0), name
    run, hist, s = simulate(model, prm["protrusion"] * NM)
    assert_physical(run, hist, s)
    assert s["regime"] in (0, 1, 2)
    assert_gw_area(scene, interface, run, hist)
