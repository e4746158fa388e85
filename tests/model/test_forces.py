"""The rear-bearing law registry (``air_bearing.rear_law``, :data:`pipeline.physics.air_bearing.REAR_LAWS`):
a law registered with one line is what the kernel runs, and a law the kernel cannot compile is refused
when the model is built, with one line."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.model import forces as fo
from pipeline.model import running
from pipeline.model import state as st
from pipeline.physics import air_bearing as ab
from slider_scenes import build, make_scene

NM = 1e-9


def twice_linear(g, g0, n, F0, k_r):
    """A test law: the linear law with twice the stiffness, ``2 k_r (g0 - g)`` [N]."""
    return 2.0 * k_r * (g0 - g)


def _plain_helper(g):
    return g


def calls_plain_python(g, g0, n, F0, k_r):
    """A law calling a plain Python function: numba cannot compile it."""
    return k_r * (g0 - _plain_helper(g))


def bounce_frequency(law: str) -> tuple[float, float]:
    """Measured and predicted bounce frequency [Hz] of the undamped slider with the pitch locked, the air
    bearing only, rear law ``law`` (linear in the gap): ``z`` oscillates at ``sqrt((k_f + k) / m) / 2 pi``,
    ``k`` the law's stiffness."""
    model = build(make_scene(["air_bearing"], air_bearing={"rear_law": law, "damping_ratio": 0.0},
                             solver={"duration_ms": 0.5, "transient_ms": 0.0}))
    run = running.run_model(model, 5 * NM, y0=np.array([0.5 * NM, 0.0, 0.0, 0.0]))
    assert run.info[st.STATUS] == st.OK
    z, t = run.state[:, st.Z], run.time
    i = np.flatnonzero(np.sign(z[:-1]) != np.sign(z[1:]))
    crossings = t[i] - z[i] * (t[i + 1] - t[i]) / (z[i + 1] - z[i])  # (linear between samples)
    measured = 0.5 / np.mean(np.diff(crossings))
    s = model.slider
    k = -(ab.REAR_LAWS[law].force(s.g0 + 1e-9, s.g0, s.n, s.rear_preload, s.k_r)) / 1e-9  # the law's stiffness
    return measured, np.sqrt((s.k_f + k) / s.m) / (2 * np.pi)


@pytest.mark.slow  # (compiles a kernel variant of its own: 14-26 s with an empty numba cache)
def test_a_registered_rear_law_is_the_one_the_kernel_runs(monkeypatch):
    monkeypatch.setitem(ab.REAR_LAWS, "twice-linear", ab.RearLaw(twice_linear, summary="F_r = 2 k_r (g0 - g) (a test)"))
    linear, linear_predicted = bounce_frequency("linear")
    twice, twice_predicted = bounce_frequency("twice-linear")
    assert linear == pytest.approx(linear_predicted, rel=1e-4)
    assert twice == pytest.approx(twice_predicted, rel=1e-4)
    assert twice / linear > 1.2  # (k_r is 79 % of the bounce stiffness: the doubled law is far apart)


def test_a_rear_law_without_a_compiled_form_is_refused(monkeypatch):
    scene = make_scene(["air_bearing"], air_bearing={"rear_law": "linear"})
    for name, law, message in (("none", ab.RearLaw(None, summary="no function"), "has no compiled form"),
                               ("plain", ab.RearLaw(calls_plain_python, summary="calls Python"), "does not compile")):
        monkeypatch.setitem(ab.REAR_LAWS, name, law)
        with pytest.raises(ValueError, match=f"air_bearing.rear_law = '{name}': .*{message}") as exc:
            build(scene.replace(air_bearing={"rear_law": name}))
        assert "\n" not in str(exc.value)
    with pytest.raises(ValueError, match="air_bearing.rear_law = 'cubic': expected one of"):
        fo.rear_law_ref("cubic")


def test_the_built_in_rear_laws_are_the_kernels():
    """The kernel's rear force is the registry's function (the power law clamped at its ``min_gap``)."""
    s = build(make_scene(["air_bearing"])).slider
    for name, gap in (("power", 0.7 * s.g0), ("linear", 0.7 * s.g0), ("power", 1e-6 * s.g0)):
        law = ab.REAR_LAWS[name]
        g = max(gap, law.min_gap * s.g0) if law.min_gap is not None else gap
        expected = law.force(g, s.g0, s.n, s.rear_preload, s.k_r)
        assert _kernel_rear_force(fo.rear_law_ref(name), gap, s) == expected


def _kernel_rear_force(ref, g, s):
    from numba import njit

    @njit
    def rear(ref, g, g0, n, F0, k_r):
        return fo.call_rear_law(ref, g, g0, n, F0, k_r)

    return rear(ref, g, s.g0, s.n, s.rear_preload, s.k_r)
