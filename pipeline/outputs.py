"""Names, units and meanings of the dynamic outputs (the contract of DESIGN.md), and dataset builders.

Runs produce SI values (:mod:`pipeline.slider`); datasets hold the paper's units. The tables here
are the single place where a name gets its unit, scale and ``long_name``.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np
import xarray as xr

from .slider import REGIMES

#: Steady-window scalars: name -> (units, factor from SI, long_name).
SCALARS: dict[str, tuple[str, float, str]] = {
    "fhm_bv": ("%", 1.0, "flying-height modulation (flying) / bouncing vibration (contact), peak-to-peak over FH0"),
    "clearance": ("nm", 1e9, "mean clearance d - k sigma over the steady window"),
    "min_clearance": ("nm", 1e9, "minimum clearance over the steady window"),
    "interference": ("nm", 1e9, "mean interference -(d - k sigma) while in contact"),
    "contact_force": ("mN", 1e3, "time-mean asperity contact force"),
    "friction_force": ("mN", 1e3, "time-mean friction force"),
    "adhesion_force": ("mN", 1e3, "time-mean adhesion force (attractive)"),
    "net_force": ("mN", 1e3, "time-mean vertical interface force on the slider (contact + damping - adhesion)"),
    "friction_coefficient": ("1", 1.0, "friction coefficient: mean friction / mean contact force"),
    "mean_pressure": ("MPa", 1e-6, "mean contact pressure over the real area while in contact"),
    "shear_stress": ("MPa", 1e-6, "mean shear stress over the real area while in contact"),
    "real_area": ("um2", 1e12, "mean real contact area while in contact"),
    "nominal_area": ("um2", 1e12, "nominal contact area of the TFC bulge"),
    "protrusion_radius": ("um", 1e6, "effective radius of the bulge in the sliding direction"),
    "contact_fraction": ("1", 1.0, "fraction of the steady window spent in contact"),
    "regime": ("1", 1.0, "regime of the steady window"),
}

#: Time histories: name -> (units, factor from SI, long_name).
HISTORIES: dict[str, tuple[str, float, str]] = {
    "separation": ("nm", 1e9, "separation d of the TFC surface from the mean of summit heights"),
    "clearance": ("nm", 1e9, "clearance d - k sigma"),
    "disk_displacement": ("nm", 1e9, "disk displacement (DMW) under the TFC point"),
    "contact_force": ("mN", 1e3, "asperity contact force"),
    "contact_damping_force": ("mN", 1e3, "contact damping force"),
    "friction_force": ("mN", 1e3, "friction force"),
    "adhesion_force": ("mN", 1e3, "adhesion force (attractive)"),
    "net_force": ("mN", 1e3, "vertical interface force on the slider (contact + damping - adhesion)"),
    "friction_coefficient": ("1", 1.0, "friction coefficient F_friction / F_contact"),
    "mean_pressure": ("MPa", 1e-6, "mean contact pressure over the real area"),
    "shear_stress": ("MPa", 1e-6, "shear stress over the real area"),
    "real_area": ("um2", 1e12, "real contact area"),
    "in_contact": ("1", 1.0, "contact criterion d < k sigma satisfied (1) or not (0)"),
}

REGIME_ATTRS = {"flag_values": np.array(sorted(REGIMES), dtype=np.int8),
                "flag_meanings": " ".join(REGIMES[k] for k in sorted(REGIMES)),
                "rule": "flying: no contact in the steady window; surfing: in contact >= 99 % of it; "
                        "bouncing: otherwise"}


def scalar_variable(name: str, values: np.ndarray, dims: Iterable[str]) -> xr.Variable:
    """A scalar output in dataset units with its attributes (``regime`` as int8 flags)."""
    units, factor, long_name = SCALARS[name]
    if name == "regime":
        data = np.where(np.isfinite(values), values, -1).astype(np.int8)
        return xr.Variable(tuple(dims), data, attrs={"units": units, "long_name": long_name, **REGIME_ATTRS})
    return xr.Variable(tuple(dims), np.asarray(values, float) * factor, attrs={"units": units, "long_name": long_name})


def history_variable(name: str, values: np.ndarray, dims: Iterable[str]) -> xr.Variable:
    """A time history in dataset units with its attributes."""
    units, factor, long_name = HISTORIES[name]
    if name == "in_contact":
        return xr.Variable(tuple(dims), np.asarray(values).astype(np.int8), attrs={"units": units, "long_name": long_name})
    return xr.Variable(tuple(dims), np.asarray(values, float) * factor, attrs={"units": units, "long_name": long_name})
