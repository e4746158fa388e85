"""Running one protrusion (pipeline.model.running): the output grid of ``solver.duration_ms`` and
``output_step``, the start state's note, the separation extremes over the steady window bounding the
sampled separation, and a failed integration raised as one line naming the protrusion and the reason.

The scene is built in code (tests/slider_scenes.py's ``make_scene``): the air bearing and pitch only, so a
run costs milliseconds once the kernel is compiled.
"""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.model import outcomes, running
from pipeline.model import state as st
from slider_scenes import FLYING, NM, build, make_scene


@pytest.fixture(scope="module")
def flying():
    return build(make_scene(FLYING, solver={"duration_ms": 0.2, "transient_ms": 0.1}))


def test_output_grid_and_counters(flying):
    run = running.run_model(flying, 5 * NM)
    n = int(round(flying.duration / flying.output_step)) + 1
    assert run.time.shape == (n,) and run.time[0] == 0.0 and run.time[-1] == pytest.approx(flying.duration)
    # tol: steps of a time grid: rounding of t_i (t/step < 1e4) over the step
    np.testing.assert_allclose(np.diff(run.time), flying.output_step, rtol=1e-9)
    assert run.state.shape == (n, st.N_STATE) and run.contact.shape == (n,)
    assert run.info.shape == (st.N_COUNTERS,) and run.info[st.STATUS] == st.OK
    assert run.info[st.ACCEPTED] > 0 and run.info[st.RHS_CALLS] >= run.info[st.ACCEPTED]
    assert run.protrusion == 5 * NM and run.start.startswith("static flying equilibrium")


def test_a_given_start_is_kept_and_noted(flying):
    y0 = np.array([0.5 * NM, 0.0, 0.0, 0.0])
    run = running.run_model(flying, 5 * NM, y0=y0)
    assert run.start == "given"
    np.testing.assert_array_equal(run.state[0], y0)


def test_extremes_bound_the_sampled_separation_of_the_window(flying):
    # a bouncing start: the exact extremes over t >= transient enclose every sample of the separation there,
    # to 1e-4 nm (measured: the two samples at the window's first 0.25 us lie 3e-5 nm above the tracked
    # maximum, where the window begins inside a step), and the samples reach them to within 5 % of the range
    run = running.run_model(flying, 5 * NM, y0=np.array([0.5 * NM, 0.0, 0.0, 0.0]))
    lo, hi = run.d_extremes
    d = outcomes.histories(run)["separation"][run.time >= flying.transient - 1e-15]
    assert lo <= d.min() + 1e-4 * NM and d.max() <= hi + 1e-4 * NM
    assert d.min() - lo < 0.05 * (hi - lo) and hi - d.max() < 0.05 * (hi - lo)


def test_a_failed_integration_is_one_line(flying):
    with pytest.raises(running.IntegrationError) as exc:
        running.run_model(flying, 5 * NM, max_steps=5)
    msg = str(exc.value)
    assert msg.startswith("integration failed at protrusion 5 nm: too many steps (steps ")
    assert "\n" not in msg
    # the scene keys to change, in the error itself: a calibration's log of a collapsed flying run, a sweep's
    # errors attribute and the command line all quote it (the command line alone had the hint)
    assert msg.endswith("); " + running.HINTS[st.MAX_STEPS])
    for key in ("solver.duration_ms", "solver.min_dwell_ns", "solver.rtol", "tfc.protrusion_nm", "contact.k"):
        assert key in running.HINTS[st.MAX_STEPS]


def test_every_failure_status_names_the_scene_keys_to_change():
    import re
    from pipeline.config.schema import SCHEMA
    assert set(running.HINTS) == set(st.STATUS_TEXT) - {st.OK}
    for hint in running.HINTS.values():
        keys = re.findall(r"\b([a-z_]+)\.([a-z_]+)\b", hint)
        assert keys and all(key in SCHEMA[section] for section, key in keys), hint
