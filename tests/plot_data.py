"""Hand-made histories and sweeps, in dataset units, for the tests of the figure panels
(pipeline/analyses/plots/): a clearance and force history, a sweep and an ensemble sweep; the check every panel
passes (:func:`check_panel`)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from pipeline.analyses import plots


def history(n=400):
    t = np.arange(n) * 1.5e-6
    c = (t > 2e-4).astype(float)
    T = "elapsed_time"
    return xr.Dataset({"clearance": (T, 0.5 - c + 0.1 * np.sin(t * 1e5), {"units": "nm"}),
                       "in_contact": (T, c), "contact_force": (T, c * 1.5, {"units": "mN"}),
                       "net_force": (T, c - 1.0, {"units": "mN"})}, coords={T: (T, t)})


def sweep(realisations=0):
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


def check_panel(draw, args: tuple, kw: dict, ylabel: str) -> None:
    """A panel ``draw(*args, ax=..., **kw)`` draws on the axes it is given and returns them (the API's promise
    for composing figures), or on a new figure's without one, with its y label ``ylabel``."""
    fig, (mine, other) = plots.new_figure(2, 1)
    assert draw(*args, ax=mine, **kw) is mine
    assert mine.get_ylabel() == ylabel and mine.lines and not other.lines and not other.get_ylabel()
    fresh = draw(*args, **kw)  # no axes given: a new figure's
    assert fresh is not mine and fresh.figure is not fig and fresh.get_ylabel() == ylabel
