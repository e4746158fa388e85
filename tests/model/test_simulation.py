"""Heater stepping (``sweep.protocol = "stepping"``; docs/model.md, section "Heater stepping";
pipeline.model.simulation): each protrusion from the end state of the previous one, up then down.

Scenes are built in code (tests/slider_scenes.py's ``make_scene``), without DMW so that the steady
states are equilibria and the comparisons are at the solver's tolerance.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from pipeline.config.scene import load_scene
from pipeline.io import read_dataset
from pipeline.model import outcomes, running
from pipeline.model.simulation import chain_protrusions, histories_of, simulate, summary_of
from pipeline.stages import sweep as sweep_stage
from pipeline.units import NM
from pipeline.model import state as st
from slider_scenes import build, make_scene

ROOT = Path(__file__).resolve().parents[2]
SHORT = {"duration_ms": 0.3, "transient_ms": 0.1}
ATOL_NM = 1e-4  # the scene's solver.atol_nm: the integrator's length tolerance


def test_chain_protrusions_reads_the_passes():
    p = np.array([1.0, 2.0, 3.0, 4.0])
    # touches from 3 on the way up, still at 2 on the way down: take-off at 1
    assert chain_protrusions(p, np.array([0, 0, 1, 1], bool), np.array([0, 1, 1, 1], bool)) == (3.0, 1.0)
    # no hysteresis: the first free protrusion down is the one below touchdown
    assert chain_protrusions(p, np.array([0, 0, 1, 1], bool), np.array([0, 0, 1, 1], bool)) == (3.0, 2.0)
    td, to = chain_protrusions(p, np.zeros(4, bool), np.zeros(4, bool))  # never touches
    assert np.isnan(td) and np.isnan(to)
    td, to = chain_protrusions(p, np.array([0, 0, 0, 1], bool), np.ones(4, bool))  # stuck to the bottom
    assert td == 4.0 and np.isnan(to)


def test_stepping_without_adhesion_reaches_the_independent_steady_states():
    # contact without adhesion: one steady state per protrusion, whatever the start, so both passes
    # of the chain end where the independent runs do (to the solver's tolerance), and the take-off is
    # the grid point below touchdown (hysteresis = one step: none beyond the grid's resolution)
    model = build(make_scene(["air_bearing", "pitch", "contact"], solver=SHORT))
    prot = [9.0, 10.0, 11.0, 12.0, 13.0]
    chain = simulate(model, prot, protocol="stepping")
    free = simulate(model, prot)
    for direction in ("up", "down"):
        step = chain.sel(direction=direction)
        np.testing.assert_allclose(step["clearance"], free["clearance"], rtol=0, atol=ATOL_NM)
        np.testing.assert_allclose(step["contact_force"], free["contact_force"], rtol=1e-5, atol=0)
        np.testing.assert_array_equal(step["regime"], free["regime"])
    # the chain's first step is an independent run (solver.start), bit for bit
    assert float(chain["clearance"].sel(direction="up")[0]) == float(free["clearance"][0])
    touched = outcomes.touched_in_summary(free["min_clearance"].values)
    td = prot[int(np.argmax(touched))]
    assert float(chain["touchdown_protrusion"]) == td == 11.0
    assert float(chain["takeoff_protrusion"]) == td - 1.0
    assert float(chain["hysteresis"]) == 1.0
    assert chain["hysteresis"].attrs["units"] == "nm"


def test_adhesion_holds_contact_on_the_way_down():
    # with adhesion the slider snaps in at the fold of the flying equilibria (docs/model.md, section
    # "Touchdown mechanism") and, once in contact, adhesion holds it there below that protrusion
    scene = make_scene(["air_bearing", "pitch", "adhesion", "contact"], solver={**SHORT, "start": "static"})
    model = build(scene)
    prot = [3.0, 4.0, 5.0, 6.0, 7.0, 7.4, 7.8, 8.0, 8.2]
    chain = simulate(model, prot, protocol="stepping")
    td, to = float(chain["touchdown_protrusion"]), float(chain["takeoff_protrusion"])
    # touchdown is the first grid protrusion past the fold: no static flying equilibrium there
    notes = {p: running.start(model, p * NM)[1] for p in prot}
    flying = [p for p in prot if notes[p].startswith("static flying equilibrium")]
    assert td == min(p for p in prot if p not in flying)
    assert flying == [p for p in prot if p < td]
    assert to <= td
    below = [p for p in prot if to < p < td]  # in contact on the way down, flying on the way up
    assert below, f"no hysteresis beyond the grid step: touchdown {td} nm, take-off {to} nm"
    up, down = chain["regime"].sel(direction="up"), chain["regime"].sel(direction="down")
    for p in below:
        assert int(up.sel(protrusion=p)) == outcomes.FLYING and int(down.sel(protrusion=p)) != outcomes.FLYING
    assert float(chain["hysteresis"]) == pytest.approx(td - to)


def test_independent_simulate_keeps_histories_and_counters():
    model = build(make_scene(["air_bearing", "pitch"], solver=SHORT))
    ds = simulate(model, [4.0, 5.0], histories=[5.0], counters=True)
    hist, summary = histories_of(ds.sel(protrusion=[5.0])), summary_of(ds)
    run = running.run_model(model, 5.0 * NM)
    np.testing.assert_array_equal(hist["separation"].values[0], outcomes.histories(run)["separation"] / NM)
    assert int(hist["steps"][0]) == run.info[st.ACCEPTED]
    assert set(summary.dims) == {"protrusion"} and "steps" not in summary


def test_a_failed_protrusion_is_nan_with_its_reason(monkeypatch):
    model = build(make_scene(["air_bearing", "pitch", "contact"], solver=SHORT))
    timings: dict[str, float] = {}
    good = simulate(model, [4.0, 5.0], on_error="nan", timings=timings)
    assert "errors" not in good.attrs and timings["kernel_seconds"] > 0
    run_model = running.run_model

    def failing(m, delta, **kw):  # the integrator gives up at 4 nm
        if abs(delta - 4.0 * NM) < 1e-3 * NM:
            raise running.IntegrationError("integration failed at protrusion 4 nm: too many steps")
        return run_model(m, delta, **kw)

    monkeypatch.setattr(running, "run_model", failing)
    ds = simulate(model, [4.0, 5.0], on_error="nan")
    assert ds.attrs["errors"] == "4 nm: integration failed at protrusion 4 nm: too many steps"
    assert np.isnan(float(ds["clearance"][0])) and float(ds["clearance"][1]) == float(good["clearance"][1])
    assert int(ds["regime"][0]) == ds["regime"].encoding["_FillValue"]
    with pytest.raises(running.IntegrationError):
        simulate(model, [4.0, 5.0])


STEPPING_SWEEP = [
    'scene.effects=["air_bearing","pitch","contact"]',
    "contact.k=0.445",
    "solver.duration_ms=0.3",
    "solver.transient_ms=0.1",
    "sweep.protrusion_nm={start=9.0, stop=12.0, step=1.0}",
    "sweep.damping_ratio=[0.05, 0.1]",
    "sweep.batch_size=1",  # ignored by stepping: one batch per chain
    'sweep.protocol="stepping"',
]


def _values(path: Path) -> xr.Dataset:
    ds = read_dataset(path)
    del ds.attrs["history"]
    return ds


def test_stepping_sweep_runs_one_batch_per_chain_and_resumes(tmp_path):
    scene = load_scene(ROOT / "configs" / "paper-2009.toml", STEPPING_SWEEP)
    prot, _, damp, batches = sweep_stage.plan(scene)
    assert len(batches) == len(damp) == 2 and all(len(b.protrusions) == len(prot) for b in batches)
    full = sweep_stage.run_sweep(scene, tmp_path / "full", scheduler="synchronous")
    with pytest.raises(KeyboardInterrupt):
        sweep_stage.run_sweep(scene, tmp_path / "resumed", scheduler="synchronous", stop_after=1)
    done: list[str] = []
    resumed = sweep_stage.run_sweep(scene, tmp_path / "resumed", scheduler="synchronous", on_batch=done.append)
    assert len(done) == 1
    a = _values(full)
    xr.testing.assert_identical(a, _values(resumed))
    assert a["clearance"].dims == ("protrusion", "roughness", "damping", "direction")
    assert list(a["direction"].values) == ["up", "down"]
    assert a["touchdown_protrusion"].dims == ("roughness", "damping")
    # the top of a chain closes both passes
    top = a.isel(protrusion=-1)
    np.testing.assert_array_equal(top["clearance"].sel(direction="up"), top["clearance"].sel(direction="down"))
    # touchdown where the chain's upward pass first touches
    touched = outcomes.touched_in_summary(a["min_clearance"].sel(direction="up").values)
    first = prot[np.argmax(touched, axis=0)]
    np.testing.assert_array_equal(a["touchdown_protrusion"].values, first)


def test_scalars_are_the_numbers_of_the_dataset(monkeypatch):
    """``scalars`` (the parameter studies' path) gives the numbers ``simulate(..., on_error="nan")`` puts in its
    dataset, in its units and dtypes, a failed protrusion's regime its fill value, and the same failures."""
    from pipeline.model import simulation
    from pipeline.variables import SCALARS
    model = build(make_scene(["air_bearing", "pitch", "dmw", "adhesion", "contact", "friction"]))
    real = running.run_model

    def failing(m, delta, **kwargs):  # (one protrusion fails as an integration may)
        if abs(delta - 7.0 * NM) < 1e-3 * NM:
            raise running.IntegrationError("a stand-in failure")
        return real(m, delta, **kwargs)
    monkeypatch.setattr(running, "run_model", failing)
    prots = [5.0, 7.0, 12.0]
    ds = simulate(model, prots, on_error="nan")
    values, errors = simulation.scalars(model, prots)
    assert list(values) == list(ds.data_vars) and "regime" in values
    for name, v in values.items():
        assert v.dtype == ds[name].dtype, name
        np.testing.assert_array_equal(v, ds[name].values, err_msg=name)
    assert values["regime"][1] == SCALARS["regime"].fill_value and np.isnan(values["fhm_bv"][1])
    assert errors == ["7 nm: a stand-in failure"] and ds.attrs["errors"] == errors[0]
