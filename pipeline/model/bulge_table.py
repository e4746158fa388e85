"""The bulge's air-bearing table: lift and stiffness versus protrusion and apex gap (``bulge.nc``).

Stage-ready (not yet registered with the runner): :func:`bulge_table` builds the dataset of one scene
once, from the model ``air_bearing.bulge`` (``"ph-limit"`` or ``"reynolds"``, docs/model.md, section
"Bulge air bearing"; physics in :mod:`pipeline.physics.bulge_bearing`); :func:`ratio_slice` and
:func:`lift_at` are how the dynamics reads it back: the table's lift divided by the closed form is
smooth in ``ln g`` (the closed form carries the logarithm of the gap), so a run at one protrusion takes
that ratio at its protrusion and multiplies the exact closed form by it.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..physics import bulge_bearing as bb
from ..config.grid import TOL_NM
from ..units import MPA, NM, UM
from ..variables import BULGE


#: Air at 20 C and 1 atm: dynamic viscosity [Pa s] (CRC Handbook of Chemistry and Physics, "Viscosity
#: of gases"), mean free path [m] at the ambient pressure [Pa] (the 65 nm usual in slider air-bearing
#: simulation, e.g. Fukui & Kaneko, J. Tribol. 110 (1988) 253, used with ``lambda = lambda_a p_a / p``).
AIR_VISCOSITY = 1.81e-5
AIR_MEAN_FREE_PATH = 65e-9
AMBIENT_PRESSURE = 101325.0

#: The models with a table (``air_bearing.bulge``; ``"none"`` has none).
MODELS = ("ph-limit", "reynolds")


def table_gaps(low_nm: float = 0.05, high_nm: float = 20.0, points: int = 25) -> np.ndarray:
    """Apex gaps [m] of the table: ``points`` log-spaced from ``low_nm`` to ``high_nm`` (the lift is smooth
    in ``ln g``; the low end is the gap floor of the law)."""
    if not 0 < low_nm < high_nm or points < 4:
        raise ValueError(f"bulge table gaps: expected 0 < low ({low_nm}) < high ({high_nm}) nm and >= 4 points "
                         f"(got {points})")
    return np.geomspace(low_nm, high_nm, points) * NM


def table_protrusions(stop_nm: float = 15.0, step_nm: float = 0.5) -> np.ndarray:
    """Protrusions [m] of the table: ``0, step, ..., >= stop`` [nm] (the ratio to the closed form is smooth in
    the protrusion, so a coarser step than the sweep's is enough)."""
    if step_nm <= 0 or stop_nm <= 0:
        raise ValueError(f"bulge table protrusions: expected positive stop and step (got {stop_nm}, {step_nm} nm)")
    n = int(np.ceil(stop_nm / step_nm - TOL_NM))
    return np.arange(n + 1) * step_nm * NM


def bulge_table(*, model: str, p_pad: float, a: float, b: float, speed: float, gaps: np.ndarray,
                protrusions: np.ndarray, profile: str = "ellipsoid", slip: str = "first-order",
                viscosity: float = AIR_VISCOSITY, mean_free_path: float = AIR_MEAN_FREE_PATH,
                ambient_pressure: float = AMBIENT_PRESSURE, grid: bb.ReynoldsGrid = bb.ReynoldsGrid()) -> xr.Dataset:
    """The bulge lift table of a scene as a dataset (variables :data:`pipeline.variables.BULGE`).

    Parameters
    ----------
    model : ``"ph-limit"`` (closed form) or ``"reynolds"`` (slip-corrected Reynolds solve per protrusion)
    p_pad : pad pressure [Pa]; a, b : footprint semi-axes along / across sliding [m]; speed : disk speed [m/s]
    gaps : apex gaps [m] (increasing, > 0; :func:`table_gaps`); protrusions : [m] (>= 0; :func:`table_protrusions`)
    profile : ``"ellipsoid"`` or ``"paraboloid"``; slip : :data:`pipeline.physics.bulge_bearing.SLIP_MODELS`
    viscosity [Pa s], mean_free_path [m] at ambient_pressure [Pa]; grid : the Reynolds solver's settings

    Returns
    -------
    Dataset on ``(protrusion, apex_gap)`` [nm] with ``bulge_lift`` [mN], ``bulge_stiffness`` [N/m],
    ``bulge_lift_ph_limit`` [mN], ``bearing_number`` [1], ``pad_pressure`` [MPa], and the settings as
    attributes (no timing: equal inputs give equal datasets).
    """
    if model not in MODELS:
        raise ValueError(f"air_bearing.bulge = {model!r}: expected one of {list(MODELS)} for a table "
                         "('none' needs no table)")
    gaps = np.asarray(gaps, dtype=float)
    protrusions = np.asarray(protrusions, dtype=float)
    if np.any(protrusions < 0):
        raise ValueError("bulge table: protrusions must be >= 0 [m]")
    if model == "reynolds":
        t = bb.reynolds_table(gaps, protrusions, p_pad=p_pad, a=a, b=b, speed=speed, viscosity=viscosity,
                              mean_free_path=mean_free_path, ambient_pressure=ambient_pressure, profile=profile,
                              slip=slip, grid=grid)
        lift, stiff, lift_ph, lam = t["lift"], t["stiffness"], t["lift_ph"], t["bearing_number"]
    else:
        lift_ph, stiff = bb.ph_lift(gaps[None, :], protrusions[:, None], p_pad, a, b, profile)
        lift = lift_ph
        lam = 6.0 * viscosity * speed * a / (p_pad * (gaps[None, :] + protrusions[:, None]) ** 2)
    dims = ("protrusion", "apex_gap")
    ds = xr.Dataset(
        {"bulge_lift": BULGE["bulge_lift"].from_si(lift, dims),
         "bulge_stiffness": BULGE["bulge_stiffness"].from_si(stiff, dims),
         "bulge_lift_ph_limit": BULGE["bulge_lift_ph_limit"].from_si(lift_ph, dims),
         "bearing_number": BULGE["bearing_number"].from_si(lam, dims),
         "pad_pressure": BULGE["pad_pressure"].from_si(p_pad, ())},
        coords={"protrusion": BULGE["protrusion"].from_si(protrusions, ("protrusion",)),
                "apex_gap": BULGE["apex_gap"].from_si(gaps, ("apex_gap",))})
    ds.attrs.update({
        "bulge_model": model, "bulge_profile": profile, "slip_model": slip if model == "reynolds" else "n/a",
        "footprint_semi_axes_um": np.array([a, b]) / UM, "disk_speed_m_s": speed,
        "air_viscosity_pa_s": viscosity, "mean_free_path_nm": mean_free_path / NM,
        "ambient_pressure_pa": ambient_pressure,
        "reynolds_grid": (f"cells_per_a={grid.cells_per_a} cells_per_b={grid.cells_per_b} margin_a={grid.margin_a} "
                          f"margin_b={grid.margin_b} tol={grid.tol}") if model == "reynolds" else "n/a",
    })
    return ds


def ratio_slice(ds: xr.Dataset, protrusion: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What a run at one protrusion needs from the table: the lift's ratio to the closed form on the gaps.

    The ratio ``r = bulge_lift / bulge_lift_ph_limit`` is interpolated linearly in the protrusion between
    table rows (rows at zero protrusion have no ratio: below the first positive row its ratio is used).

    Returns
    -------
    ln_gaps : ``ln(g / 1 m)`` of the table's gaps [1]; ratio [1]; dratio : ``dr/d ln g`` [1] (cubic spline)
    """
    from scipy.interpolate import CubicSpline

    d = ds["protrusion"].values * NM
    keep = d > 0
    r = ds["bulge_lift"].values[keep] / ds["bulge_lift_ph_limit"].values[keep]
    d = d[keep]
    j = int(np.clip(np.searchsorted(d, protrusion) - 1, 0, d.size - 2))
    w = float(np.clip((protrusion - d[j]) / (d[j + 1] - d[j]), 0.0, 1.0))
    row = (1 - w) * r[j] + w * r[j + 1]
    ln_g = np.log(ds["apex_gap"].values * NM)
    return ln_g, row, CubicSpline(ln_g, row)(ln_g, 1)


def lift_at(ds: xr.Dataset, g, protrusion: float, g_min: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Lift [N] and stiffness ``-dF/dg`` [N/m] at apex gaps ``g`` [m] and one protrusion [m] from the table.

    ``F = r(ln g) F_ph(g)``, ``k = r k_ph - F_ph (dr/d ln g) / g`` with ``r`` a cubic Hermite interpolant of
    :func:`ratio_slice` (held constant outside the table's gaps) and ``F_ph``, ``k_ph`` the closed form
    (:func:`pipeline.physics.bulge_bearing.ph_lift`) at the table's pad pressure, footprint and profile;
    ``g_min`` [m] (default: the table's smallest gap) is the floor below which the force is held.
    """
    from scipy.interpolate import CubicHermiteSpline

    ln_g, r, dr = ratio_slice(ds, protrusion)
    g = np.asarray(g, dtype=float)
    g_min = float(ds["apex_gap"].values[0] * NM) if g_min is None else g_min
    a, b = (float(v) * 1e-6 for v in ds.attrs["footprint_semi_axes_um"])
    p_pad = float(ds["pad_pressure"].values) * MPA
    F_ph, k_ph = bb.ph_lift(g, protrusion, p_pad, a, b, ds.attrs["bulge_profile"], g_min)
    x = np.clip(np.log(np.maximum(g, g_min)), ln_g[0], ln_g[-1])
    spline = CubicHermiteSpline(ln_g, r, dr)
    rr = spline(x)
    inside = (np.log(np.maximum(g, g_min)) > ln_g[0]) & (np.log(np.maximum(g, g_min)) < ln_g[-1])
    drr = np.where(inside, spline(x, 1), 0.0)
    return rr * F_ph, rr * k_ph - F_ph * drr / np.maximum(g, g_min) * (g >= g_min)
