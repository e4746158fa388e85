"""The plot panels of pipeline.analyses.plots on hand-made histories and sweeps: each draws on the axes it is given
and returns them (the API's promise for composing figures), or on a new figure's without one, with its y label."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import plots


def _history(n=400):
    t = np.arange(n) * 1.5e-6
    c = (t > 2e-4).astype(float)
    T = "elapsed_time"
    return xr.Dataset({"clearance": (T, 0.5 - c + 0.1 * np.sin(t * 1e5), {"units": "nm"}),
                       "in_contact": (T, c), "contact_force": (T, c * 1.5, {"units": "mN"}),
                       "net_force": (T, c - 1.0, {"units": "mN"})}, coords={T: (T, t)})


def _sweep(realisations=0):
    x = np.array([9.0, 9.5, 10.0])
    if not realisations:
        return xr.Dataset({"fhm_bv": ("protrusion", [12.0, 30.0, 25.0], {"units": "%"}),
                           "regime": ("protrusion", [0, 1, 2])}, coords={"protrusion": x})
    f = np.arange(x.size * realisations, dtype=float).reshape(x.size, realisations) + 1.0
    return xr.Dataset({"fhm_bv": (("protrusion", "realisation"), f, {"units": "%"}),
                       "fhm_bv_mean": ("protrusion", f.mean(1)), "fhm_bv_std": ("protrusion", f.std(1)),
                       "touchdown_probability": ("protrusion", [0.0, 0.5, 1.0]),
                       "bouncing_bv": (("protrusion", "realisation"), f),
                       "bouncing_bv_spread": (("protrusion", "q"), np.stack([f.min(1), f.max(1)], 1)),
                       "bouncing_bv_median": ("protrusion", np.median(f, 1)),
                       "bv_exceedance_probability": ("protrusion", [0.0, 0.3, 1.0])},
                      coords={"protrusion": x, "realisation": np.arange(realisations)})


PANELS = [
    (plots.plot_clearance, lambda: (_history(), 10.0, 2), {"transient_ms": 0.1}, "clearance [nm]"),
    (plots.plot_forces, lambda: (_history(),), {}, "force [mN]"),
    (plots.plot_fhm, lambda: (_sweep(),), {"touchdown_nm": 9.5}, "FHM / BV (peak-to-peak / FH0) [%]"),
    (plots.plot_touchdown_probability, lambda: (_sweep(3),), {}, "touchdown probability [-]"),
    (plots.plot_ensemble_fhm, lambda: (_sweep(3),), {}, "FHM / BV (peak-to-peak / FH0) [%]"),
    (plots.plot_band, lambda: (_sweep(3),), {"band_nm": (9.5, 10.0)}, "bouncing BV (0 where flying) [%]"),
    (plots.plot_band_probabilities, lambda: (_sweep(3),), {}, "probability / fraction [-]"),
]


@pytest.mark.parametrize("draw, args, kw, ylabel", PANELS, ids=lambda v: getattr(v, "__name__", ""))
def test_a_panel_draws_on_the_axes_it_is_given_and_returns_them(draw, args, kw, ylabel):
    fig, (mine, other) = plots.new_figure(2, 1)
    assert draw(*args(), ax=mine, **kw) is mine
    assert mine.get_ylabel() == ylabel and mine.lines and not other.lines and not other.get_ylabel()
    fresh = draw(*args(), **kw)  # no axes given: a new figure's
    assert fresh is not mine and fresh.figure is not fig and fresh.get_ylabel() == ylabel


def _statics():
    """A statics map on 0-15 nm: one flying state from 11 nm down to 1.5 nm at 9.6 nm, a contact state from
    7.2 nm on (clearance -0.1 to -0.7 nm), an unstable one between them (state slot 2)."""
    x = np.round(np.arange(0.0, 15.01, 0.2), 1)
    c = np.full((x.size, 3), np.nan)
    kind, stable = np.zeros((x.size, 3), int), np.zeros((x.size, 3), int)
    flying = x <= 9.6
    c[flying, 0] = 11.0 - 9.5 / 9.6 * x[flying]
    stable[:, 0] = 1
    contact = x >= 7.2
    c[contact, 1] = -0.1 - 0.6 * (x[contact] - 7.2) / 7.8
    kind[:, 1], stable[:, 1] = 1, 1
    both = flying & contact
    c[both, 2] = 0.1 + (x[both] - 7.2) * 0.4
    return xr.Dataset({"clearance": (("protrusion", "state"), c, {"units": "nm"}),
                       "state_type": (("protrusion", "state"), kind), "stable": (("protrusion", "state"), stable),
                       "barrier": (("protrusion", "state"), np.where(np.isfinite(c), 1e-13, np.nan), {"units": "J"})},
                      coords={"protrusion": ("protrusion", x, {"units": "nm"})})


def test_the_statics_panel_shows_every_protrusion_and_clearance_of_the_map_and_near_criterion_the_fold():
    st = _statics()
    ax = plots.plot_statics_states(st)
    lo, hi = ax.get_xlim()
    assert lo <= 0.0 and hi >= 15.0                           # the stage's whole range, not from ~6 nm on
    bottom, top = ax.get_ylim()
    assert top >= 11.0 and bottom <= -0.7                     # the flying branch up to 11 nm, the contact one
    near = plots.plot_statics_states(st, near_criterion=True)
    assert near.get_xlim()[0] == pytest.approx(7.2 - 1.0 - 0.1) and near.get_ylim()[1] == pytest.approx(3.2)


def test_the_forces_legend_lies_beside_the_axes_not_on_a_curve():
    ax = plots.plot_forces(_history())
    fig = ax.figure
    fig.canvas.draw()
    legend = ax.get_legend().get_window_extent()
    assert legend.x0 >= ax.get_window_extent().x1              # right of the plotting area: covers no force


def test_a_dataset_with_heater_power_gets_a_top_axis_in_mw_and_one_without_none():
    sweep = _sweep()
    assert plots.heater_power_axis(plots.plot_fhm(sweep), sweep) is None
    assert not plots.plot_fhm(sweep).child_axes
    powered = sweep.assign_coords(heater_power=("protrusion", sweep["protrusion"].values / 0.125, {"units": "mW"}))
    ax = plots.plot_fhm(powered)
    (top,) = ax.child_axes
    assert top.get_xlabel() == "heater power [mW]"
    forward, inverse = top._functions        # (matplotlib keeps the pair it was given; no public getter)
    # tol: linear interpolation between table rows: a product and a sum, a few roundings
    np.testing.assert_allclose(forward(np.array([9.0, 9.5, 10.0])), [72.0, 76.0, 80.0], rtol=1e-12)  # 0.125 nm/mW
    # tol: the end rows of the table, one product: a rounding
    np.testing.assert_allclose(forward(np.array([8.0, 11.0])), [64.0, 88.0], rtol=1e-12)   # beyond: the end rows
    # tol: two linear interpolations back and forth: a few roundings each
    np.testing.assert_allclose(inverse(forward(np.linspace(8.0, 11.0, 13))), np.linspace(8.0, 11.0, 13), rtol=1e-12)
