"""The paper's panels (pipeline/analyses/plots/paper.py) on hand-made histories and sweeps: each draws on the axes
it is given and returns them (the API's promise for composing figures), or on a new figure's without one, with its
y label; the forces legend beside the axes."""

from __future__ import annotations

import pytest

from pipeline.analyses import plots
import plot_data


PANELS = [
    (plots.plot_clearance, lambda: (plot_data.history(), 10.0, 2), {"transient_ms": 0.1}, "clearance [nm]"),
    (plots.plot_forces, lambda: (plot_data.history(),), {}, "force [mN]"),
    (plots.plot_fhm, lambda: (plot_data.sweep(),), {"touchdown_nm": 9.5}, "FHM / BV (peak-to-peak / FH0) [%]"),
]


@pytest.mark.parametrize("draw, args, kw, ylabel", PANELS, ids=lambda v: getattr(v, "__name__", ""))
def test_a_panel_draws_on_the_axes_it_is_given_and_returns_them(draw, args, kw, ylabel):
    plot_data.check_panel(draw, args(), kw, ylabel)


def test_the_forces_legend_lies_beside_the_axes_not_on_a_curve():
    ax = plots.plot_forces(plot_data.history())
    fig = ax.figure
    fig.canvas.draw()
    legend = ax.get_legend().get_window_extent()
    assert legend.x0 >= ax.get_window_extent().x1              # right of the plotting area: covers no force
