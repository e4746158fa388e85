"""Stage ``bulge_pads``: the bulge table of an identification with a free pad pressure, ``bulge_pads.nc``.

When ``hdi identify`` frees ``air_bearing.pad_pressure_mpa`` and the scene's bulge law reads a table
(``air_bearing.bulge = "reynolds"`` or ``"rough-reynolds"``; :func:`pipeline.model.scene_inputs.table_stages`),
each candidate would solve its own Reynolds table (10-25 s). This stage solves it instead at
:data:`pipeline.model.bulge_pads.NODES` pad pressures spanning the parameter's bounds (evenly in ``ln p_pad``,
:func:`pipeline.model.bulge_pads.pad_nodes`) and, to measure the interpolation, half-way between them
(:func:`pipeline.model.bulge_pads.check_pads`); a candidate reads its table interpolated in ``p_pad``
(:func:`pipeline.model.bulge_pads.table_at`, :func:`pipeline.candidates.candidate_inputs`). It runs only as
an upstream stage of ``identify`` (:func:`pipeline.evaluations.pad_bounds` says when), never in ``hdi run``.

Writes ``bulge_pads.nc``: the node tables stacked on ``pad_node`` (each node's ``bulge.nc`` variables and
``bulge_lift_ratio``, the lift over its closed form), and the attributes ``pad_nodes_mpa``, ``check_pads_mpa``,
``check_lift_error`` (the largest relative lift error of the interpolant at each check pressure [1]) and
``max_lift_error``. Its inputs key: the bulge table's keys but the pad pressure
(:data:`pipeline.model.bulge_table.FIELDS`), the deepest protrusion and the nodes (derived values).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..config.fields import fields
from ..evaluations import PAD_KEY, pad_bounds
from ..model import bulge_pads as bp
from ..model.bulge_table import DERIVED_FIELDS, FIELDS, table_stop_nm
from ..runner import Inputs, Stage

def _nodes(scene: Any) -> list[float]:
    bounds = pad_bounds(scene)
    return [] if bounds is None else [float(p) for p in bp.pad_nodes(*bounds)]


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """``bulge_pads.nc`` of the scene (module docstring)."""
    pads = np.array(_nodes(scene))
    if pads.size == 0:
        raise ValueError(f"{scene.path or '<scene>'}: the bulge_pads stage needs {PAD_KEY} among identify.parameters "
                         "and a tabulated bulge law (air_bearing.bulge = \"reynolds\" or \"rough-reynolds\")")
    stack = bp.node_tables(scene, pads)
    checks = bp.check_pads(pads)
    errors = bp.interpolation_error(stack, bp.node_tables(scene, checks))
    stack.attrs.update({
        "pad_nodes_mpa": pads, "check_pads_mpa": checks, "check_lift_error": errors,
        "max_lift_error": float(errors.max()),
        "interpolation": "the lift over its p h = const closed form, cubic spline (not-a-knot) in ln p_pad through the "
                         "nodes (linear with fewer than 4), times the exact closed form; check_lift_error: the largest "
                         "relative lift error [1] against an exact solve at each check pad pressure",
    })
    return stack


def _derived(scene: Any) -> dict[str, Any]:
    nodes = _nodes(scene)
    return {"table_stop_nm": table_stop_nm(scene), "pad_nodes_mpa": nodes} if nodes else {}


#: The keys of the stage: the bulge table's but the pad pressure, whose nodes are derived from the bounds, and
#: the TFC-point laws' (:func:`pipeline.model.scene_inputs.table_stages`).
READS = fields(*(k for k in FIELDS if k != PAD_KEY), "air_bearing.tfc_stiffening", "identify.parameters")

STAGE = Stage(
    "bulge_pads", compute, outputs=("bulge_pads.nc",), reads=READS,
    unkeyed=(*DERIVED_FIELDS, "identify.parameters"), derived=_derived, order=36,
    applies=lambda scene: pad_bounds(scene) is not None,
    doc="the bulge table at a few pad pressures spanning identify's bounds of p_pad, bulge_pads.nc "
        "(upstream of identify when p_pad is free)")
