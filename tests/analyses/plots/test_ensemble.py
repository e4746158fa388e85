"""The ensemble panels (pipeline/analyses/plots/ensemble.py) on hand-made ensemble sweeps: each draws on the axes
it is given and returns them, or on a new figure's without one, with its y label."""

from __future__ import annotations

import pytest

from pipeline.analyses import plots
import plot_data


PANELS = [
    (plots.plot_touchdown_probability, lambda: (plot_data.sweep(3),), {}, "touchdown probability [-]"),
    (plots.plot_ensemble_fhm, lambda: (plot_data.sweep(3),), {}, "FHM / BV (peak-to-peak / FH0) [%]"),
    (plots.plot_band, lambda: (plot_data.sweep(3),), {"band_nm": (9.5, 10.0)}, "bouncing BV (0 where flying) [%]"),
    (plots.plot_band_probabilities, lambda: (plot_data.sweep(3),), {}, "probability / fraction [-]"),
]


@pytest.mark.parametrize("draw, args, kw, ylabel", PANELS, ids=lambda v: getattr(v, "__name__", ""))
def test_a_panel_draws_on_the_axes_it_is_given_and_returns_them(draw, args, kw, ylabel):
    plot_data.check_panel(draw, args(), kw, ylabel)
