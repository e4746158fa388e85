"""The statics panel (pipeline/analyses/plots/statics.py) on a hand-made statics map."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import plots


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
