"""The figures' shared parts (pipeline/analyses/plots/common.py): the heater-power top axis of a dataset with a
``heater_power`` coordinate."""

from __future__ import annotations

import numpy as np

from pipeline.analyses import plots
import plot_data


def test_a_dataset_with_heater_power_gets_a_top_axis_in_mw_and_one_without_none():
    sweep = plot_data.sweep()
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
