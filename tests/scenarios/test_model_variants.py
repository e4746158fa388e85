"""Model variants are open: a new air-bearing law at the TFC point is its function plus one registry
line (pipeline.physics.tfc_laws.TFC_STIFFENING), tabulated per protrusion into the kernel's generic
TFC-point slot (pipeline.model.kernel_inputs.tfc_table, pipeline.model.dynamics.Tables.tfc) with no kernel change.

The laws registered here live in test-local entries (monkeypatch: the module's registry is restored
after each test). Scenes are built in code with explicit values for what a test depends on.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import fsolve

from pipeline.model import dynamics as dyn
from pipeline.model import forces as fo
from pipeline.model import assembly, kernel_inputs, outcomes, running
from pipeline.physics import air_bearing as ab
from pipeline.physics import tfc_laws
from pipeline.units import NM
from variant_scenes import make_scene, record
from pipeline.model import state as st

LIFT = 1.0e-4  # [N] the dummy law's constant force


def constant_lift(g: np.ndarray, delta: float) -> np.ndarray:
    """A dummy law: ``LIFT`` [N] up at every gap [m] and protrusion."""
    return np.full_like(g, LIFT)


@pytest.mark.slow  # (compiles a kernel variant of its own: 14-26 s with an empty numba cache)
def test_a_new_tfc_law_is_its_function_and_one_registry_line(monkeypatch):
    # the whole change a new variant needs: its law (above) and one line in its registry
    monkeypatch.setitem(tfc_laws.TFC_STIFFENING, "constant-lift", tfc_laws.TfcLaw(constant_lift))
    scene = make_scene(["air_bearing", "pitch"], tfc_stiffening="constant-lift")
    model = assembly.build_model(scene, None, None, None)
    assert model.tfc_stiffening is None and model.tfc_tabulated == (tfc_laws.TFC_STIFFENING["constant-lift"],)
    run = running.run_model(model, 5 * NM)
    # static equilibrium under the lift at the TFC point (l_c behind the CG), linear front pad and
    # power-law rear pad: F_f + F_r + L = 0, l_f F_f - l_r F_r - l_c L = 0; the damped transient
    # (zeta 0.05 at 120 kHz: 27 us) is gone after 1 ms
    s = model.slider

    def residual(x):  # x = (z [nm], theta [urad]), residuals over the lift
        z, theta = x[0] * NM, x[1] * 1e-6
        F_f = -s.k_f * (z + s.l_f * theta)
        F_r = float(ab.rear_force(s.g0 + z - s.l_r * theta, s.g0, s.n, s.rear_preload))
        return [(F_f + F_r + LIFT) / LIFT, (s.l_f * F_f - s.l_r * F_r - s.l_c * LIFT) / (s.l_c * LIFT)]

    z_lin, theta_lin = np.linalg.solve(s.stiffness_matrix, [LIFT, -s.l_c * LIFT])
    x, _, ok, msg = fsolve(residual, [z_lin / NM, theta_lin * 1e6], full_output=True)
    assert ok == 1, msg
    z, theta = x[0] * NM, x[1] * 1e-6
    assert z > 0 and theta < 0  # lifted, trailing edge up
    assert abs(z / z_lin - 1) > 1e-3  # (the rear law's nonlinearity is resolved, not the tangent)
    assert run.state[-1, st.Z] == pytest.approx(z, rel=1e-6)
    assert run.state[-1, st.THETA] == pytest.approx(theta, rel=1e-6)
    # the separation at the TFC point opens by z - l_c theta from its nominal value
    nominal = running.run_model(assembly.build_model(make_scene(["air_bearing", "pitch"]), None, None, None), 5 * NM)
    d, d_nominal = outcomes.histories(run)["separation"], outcomes.histories(nominal)["separation"]
    assert d[-1] - d_nominal[-1] == pytest.approx(z - s.l_c * theta, rel=1e-6)


@pytest.mark.slow  # (compiles a kernel variant of its own: 14-26 s with an empty numba cache)
def test_tabulated_law_reproduces_the_compiled_gap_power_law(monkeypatch):
    # The gap-power law registered a second time without its compiled form goes through the table:
    # force and stiffness at the TFC point and the whole run agree with the closed form.
    monkeypatch.setitem(tfc_laws.TFC_STIFFENING, "gap-power-tabulated", replace(tfc_laws.TFC_STIFFENING["gap-power"], closed_form=None))
    law = {"tfc_stiffness_n_m": 3.0e5, "tfc_stiffening_exponent": 1.5}
    effects = ["air_bearing", "pitch", "dmw"]
    compiled = make_scene(effects, tfc_stiffening="gap-power", **law)
    tabulated = make_scene(effects, tfc_stiffening="gap-power-tabulated", **law)
    rec = record(compiled)
    m_c, m_t = assembly.build_model(compiled, None, rec, None), assembly.build_model(tabulated, None, rec, None)
    assert m_t.tfc_stiffening is None and m_c.tfc_tabulated == ()
    delta = 5 * NM
    c, x0, h = kernel_inputs.tfc_table(m_t, delta)
    p = dyn.with_values(m_t.p, delta=delta, tfc_x0=x0, tfc_h=h)
    # measured: force within 3e-8 of its largest value over 0.25-30 nm, stiffness within 5e-8
    # relative above 1 nm (the spline's error grows towards the law's singular end at g_min = 0.22 nm)
    g = np.linspace(1.0, 20.0, 40) * NM
    F, k = tfc_laws.tfc_stiffening_force(g, 11 * NM - delta, 11 * NM, 3.0e5, 1.5)
    kernel = np.array([fo.tfc_air_force(p, None, c, gi) for gi in g])
    np.testing.assert_allclose(kernel[:, 0], F, rtol=0, atol=1e-7 * np.abs(F).max())
    np.testing.assert_allclose(kernel[:, 1], k, rtol=1e-6)
    # the runs: separation within 2.5e-12 nm, FHM within 1.4e-12 relative (measured)
    run_c, run_t = running.run_model(m_c, delta), running.run_model(m_t, delta)
    d_c, d_t = outcomes.histories(run_c)["separation"], outcomes.histories(run_t)["separation"]
    assert np.abs(d_t - d_c).max() < 1e-9 * NM
    s_c, s_t = outcomes.summarize(run_c), outcomes.summarize(run_t)
    # tol: two laws that agree to 1e-9 nm in the separation (asserted above): the FHM to that over 10 nm
    assert s_t["fhm_bv"] == pytest.approx(s_c["fhm_bv"], rel=1e-9)
    # and the law matters: without it the FHM differs by far more than the table's error
    s_none = outcomes.summarize(running.run_model(assembly.build_model(make_scene(effects), None, rec, None), delta))
    assert abs(s_none["fhm_bv"] - s_c["fhm_bv"]) > 100 * abs(s_t["fhm_bv"] - s_c["fhm_bv"])


def test_an_unknown_compiled_form_is_refused(monkeypatch):
    monkeypatch.setitem(tfc_laws.TFC_STIFFENING, "bogus", tfc_laws.TfcLaw(constant_lift, closed_form="bogus"))
    with pytest.raises(ValueError, match="air_bearing.tfc_stiffening = 'bogus': no compiled form 'bogus'"):
        assembly.build_model(make_scene(["air_bearing"], tfc_stiffening="bogus"), None, None, None)
