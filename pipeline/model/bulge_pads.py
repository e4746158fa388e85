"""The bulge table of a parameter study with a free pad pressure: tables at a few ``p_pad`` nodes, interpolated.

A Reynolds bulge table (:func:`pipeline.model.bulge_table.scene_table`) costs 10-25 s of one core per pad
pressure, so a study whose candidates vary ``air_bearing.pad_pressure_mpa`` would solve it once per candidate.
The lift divided by the closed form ``p h = const`` (:func:`pipeline.physics.bulge_bearing.ph_lift`, which is
proportional to ``p_pad``) depends on ``p_pad`` only through the bearing number and the pad's Knudsen number
(both ``~ 1 / p_pad``), smoothly: :func:`node_tables` solves the table at :data:`NODES` pad pressures spaced
evenly in ``ln p_pad`` over the study's bounds (:func:`pad_nodes`), and :func:`table_at` makes the table of
any pad pressure between them by interpolating that ratio in ``ln p_pad`` (a cubic spline through the nodes,
not-a-knot) and multiplying the exact closed form at that pressure by it; the stiffness follows from the
ratio's slope in ``ln g`` as the solved table's does (:func:`pipeline.physics.reynolds.reynolds_table`).
:func:`interpolation_error` measures the interpolant against exact tables solved half-way between the nodes
(docs/model.md, section "Bulge air bearing", "A free pad pressure").
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..physics import bulge_bearing as bb
from ..units import UM
from ..variables import BULGE
from .bulge_table import scene_table

#: Pad-pressure nodes of a study's table (:func:`pad_nodes`). Measured on the rough-gap band scene over
#: 1.6-2.6 MPa against exact tables at 17 pad pressures (docs/model.md, section "Bulge air bearing"): the
#: largest relative lift error between nodes is 1.1e-2 with 2 nodes (linear), 2.8e-3 with 3 (linear),
#: 3.2e-4 with 5 (cubic) and 1.8e-4 with 9 (cubic, near the solver's own noise): 5 keep it well below 2e-3.
NODES = 5
#: The dimension of the nodes in the stacked dataset (:func:`node_tables`).
NODE_DIM = "pad_node"
#: The variables interpolated in ``ln p_pad`` (the others follow from them and the closed form).
_RATIO = "bulge_lift_ratio"


def pad_nodes(low_mpa: float, high_mpa: float, count: int = NODES) -> np.ndarray:
    """``count`` pad pressures [MPa] from ``low_mpa`` to ``high_mpa``, evenly spaced in ``ln p_pad``."""
    if not 0 < low_mpa < high_mpa or count < 2:
        raise ValueError(f"bulge pad nodes: expected 0 < low ({low_mpa}) < high ({high_mpa}) MPa and >= 2 nodes "
                         f"(got {count})")
    return np.geomspace(low_mpa, high_mpa, count)


def _ratio(ds: xr.Dataset) -> np.ndarray:
    """The lift of a ``bulge.nc`` dataset divided by its closed form [1] (0 on the zero-protrusion row)."""
    lift, ph = ds["bulge_lift"].values, ds["bulge_lift_ph_limit"].values
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(ph > 0, lift / ph, 0.0)


def node_tables(scene: Any, pads_mpa: np.ndarray) -> xr.Dataset:
    """The scene's bulge table at each pad pressure of ``pads_mpa`` [MPa] (increasing), stacked on
    :data:`NODE_DIM`: each node's ``bulge.nc`` variables, ``pad_pressure`` [MPa] on the nodes, and the ratio of
    the lift to the closed form ``bulge_lift_ratio`` [1]; the attributes are the first node's (equal for all)."""
    pads_mpa = np.asarray(pads_mpa, dtype=float)
    if pads_mpa.ndim != 1 or pads_mpa.size < 2 or np.any(np.diff(pads_mpa) <= 0):
        raise ValueError(f"bulge pad nodes: expected >= 2 increasing pad pressures [MPa], got {pads_mpa}")
    si = BULGE["pad_pressure"].si_unit
    tables = [scene_table(scene, p_pad=float(p) * si) for p in pads_mpa]
    stack = xr.concat(tables, dim=NODE_DIM, combine_attrs="override")
    stack[_RATIO] = ((NODE_DIM, "protrusion", "apex_gap"), np.stack([_ratio(t) for t in tables]),
                     {"long_name": "bulge lift over its p h = const closed form", "units": "1"})
    return stack


def node(stack: xr.Dataset, i: int) -> xr.Dataset:
    """The ``bulge.nc`` dataset of the node ``i`` of a stack (:func:`node_tables`), as it was solved."""
    return stack.isel({NODE_DIM: i}).drop_vars(_RATIO)


def table_at(stack: xr.Dataset, p_pad_mpa: float) -> xr.Dataset:
    """The ``bulge.nc`` dataset at the pad pressure ``p_pad_mpa`` [MPa] from the node tables ``stack``.

    At a node: that node's table (:func:`node`). Between nodes: the ratio of the lift to the closed form
    interpolated in ``ln p_pad`` by a cubic spline through the nodes (not-a-knot; linear with 2 or 3 nodes),
    times the exact closed form at ``p_pad``; the stiffness is ``k = r k_ph - F_ph (dr/d ln g) / g`` as the
    solved table's (:func:`pipeline.physics.reynolds.reynolds_table`), the bearing number the node's scaled
    by ``p_node / p_pad``.

    Raises
    ------
    ValueError
        For a pad pressure outside the nodes (an extrapolation is not measured).
    """
    from scipy.interpolate import CubicSpline, make_interp_spline

    pads = stack["pad_pressure"].values
    p = float(p_pad_mpa)
    hit = np.flatnonzero(np.isclose(pads, p, rtol=1e-12, atol=0.0))  # (MPa from Pa: to rounding)
    if hit.size:
        return node(stack, int(hit[0]))
    if not pads[0] < p < pads[-1]:
        raise ValueError(f"air_bearing.pad_pressure_mpa = {p:g}: outside the bulge table's pad nodes "
                         f"{pads[0]:g}-{pads[-1]:g} MPa (the study's bounds)")
    ln_p = np.log(pads)
    ratios = stack[_RATIO].values
    spline = (CubicSpline(ln_p, ratios, axis=0) if pads.size >= 4 else make_interp_spline(ln_p, ratios, k=1, axis=0))
    ratio = spline(np.log(p))
    base = node(stack, int(np.argmin(np.abs(ln_p - np.log(p)))))
    gaps = base["apex_gap"].values * BULGE["apex_gap"].si_unit
    prots = base["protrusion"].values * BULGE["protrusion"].si_unit
    a, b = (float(v) * UM for v in base.attrs["footprint_semi_axes_um"])
    p_si = p * BULGE["pad_pressure"].si_unit
    F_ph, k_ph = bb.ph_lift(gaps[None, :], prots[:, None], p_si, a, b, base.attrs["bulge_profile"])
    stiffness = np.zeros_like(F_ph)
    pos = prots > 0
    if pos.any():
        dr = CubicSpline(np.log(gaps), ratio[pos], axis=1)(np.log(gaps), 1)
        stiffness[pos] = ratio[pos] * k_ph[pos] - F_ph[pos] * dr / gaps
    dims = ("protrusion", "apex_gap")
    lam = base["bearing_number"].values * (float(base["pad_pressure"]) / p)
    return base.assign({"bulge_lift": BULGE["bulge_lift"].from_si(ratio * F_ph, dims),
                        "bulge_stiffness": BULGE["bulge_stiffness"].from_si(stiffness, dims),
                        "bulge_lift_ph_limit": BULGE["bulge_lift_ph_limit"].from_si(F_ph, dims),
                        "bearing_number": BULGE["bearing_number"].from_si(lam, dims),
                        "pad_pressure": BULGE["pad_pressure"].from_si(p_si, ())})


def lift_error(table: xr.Dataset, exact: xr.Dataset) -> float:
    """The largest relative error of ``table``'s lift against ``exact``'s [1], over the rows of positive
    protrusion (where the lift is not zero)."""
    lift, ref = table["bulge_lift"].values, exact["bulge_lift"].values
    pos = exact["protrusion"].values > 0
    return float(np.max(np.abs(lift[pos] / ref[pos] - 1.0)))


def check_pads(pads_mpa: np.ndarray) -> np.ndarray:
    """The pad pressures [MPa] half-way (in ``ln p_pad``) between neighbouring nodes ``pads_mpa``, where
    :func:`interpolation_error` measures the interpolant."""
    pads_mpa = np.asarray(pads_mpa, dtype=float)
    return np.sqrt(pads_mpa[1:] * pads_mpa[:-1])


def interpolation_error(stack: xr.Dataset, exact: xr.Dataset) -> np.ndarray:
    """The largest relative lift error [1] of :func:`table_at` of the nodes ``stack`` at each pad pressure of
    the exact tables ``exact`` (a stack of :func:`node_tables` at :func:`check_pads`), by :func:`lift_error`."""
    return np.array([lift_error(table_at(stack, float(exact["pad_pressure"][i])), node(exact, i))
                     for i in range(exact.sizes[NODE_DIM])])
