"""The bulge's air-bearing table: lift and stiffness versus protrusion and apex gap (``bulge.nc``).

:func:`bulge_table` builds the dataset of one scene once, from the model ``air_bearing.bulge``
(``"ph-limit"`` or ``"reynolds"``, docs/model.md, section "Bulge air bearing"; physics in
:mod:`pipeline.physics.bulge_bearing`); :func:`scene_table` is that of a scene's keys (the ``bulge``
stage, ``bulge.nc``, :mod:`pipeline.stages.bulge`). :func:`from_dataset` is how the dynamics reads it
back (in SI): the table's lift divided by the closed form is smooth in ``ln g`` (the closed form carries
the logarithm of the gap), so a run at one protrusion takes that ratio at its protrusion and multiplies
the exact closed form by it (:func:`pipeline.physics.bulge_bearing.table_lift`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..physics import bulge_bearing as bb
from ..physics.reynolds import ReynoldsGrid, reynolds_table
from ..physics import gas_flow
from ..config.grid import TOL_NM
from ..config.fields import fields
from .dmw_record import disk_speed_m_s
from .interface_tables import deepest_protrusion_nm
from ..units import NM, UM
from ..variables import BULGE


#: Air at 20 C and 1 atm: dynamic viscosity [Pa s] (CRC Handbook of Chemistry and Physics, "Viscosity
#: of gases"), mean free path [m] at the ambient pressure [Pa] (the 65 nm usual in slider air-bearing
#: simulation, e.g. Fukui & Kaneko, J. Tribol. 110 (1988) 253, used with ``lambda = lambda_a p_a / p``).
AIR_VISCOSITY = 1.81e-5
AIR_MEAN_FREE_PATH = 65e-9
AMBIENT_PRESSURE = 101325.0

#: The bulge bearings (``air_bearing.bulge``, :data:`pipeline.physics.bulge_bearing.BULGE_LAWS`) this module
#: tabulates (:func:`bulge_table`): the closed form, or a Reynolds solve (smooth or rough gap); ``"none"``
#: has no table. A new law that reads the bulge table needs its solve here.
MODELS = ("ph-limit", "reynolds", "rough-reynolds")

#: The scene keys the table is made of (:func:`scene_table`; the last three only with ``"rough-reynolds"``,
#: :func:`scene_roughness`), besides the deepest protrusion (:func:`table_stop_nm`, of :data:`DERIVED_FIELDS`).
FIELDS = fields("air_bearing.bulge", "air_bearing.pad_pressure_mpa", "air_bearing.bulge_profile",
                "air_bearing.bulge_slip", "tfc.half_length_um", "tfc.half_width_um", "dmw.radius_mm", "dmw.rpm",
                "solver.bulge_cells_per_a", "solver.bulge_cells_per_b", "roughness.sigma_nm",
                "air_bearing.disk_roughness_share", "lubricant.thickness_nm")
#: The keys of the deepest protrusion (:func:`table_stop_nm`): the table depends on that value only.
DERIVED_FIELDS = fields("tfc.protrusion_nm", "sweep.protrusion_nm")


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
                ambient_pressure: float = AMBIENT_PRESSURE, grid: ReynoldsGrid = ReynoldsGrid(),
                roughness: gas_flow.RoughGap | None = None) -> xr.Dataset:
    """The bulge lift table of a scene as a dataset (variables :data:`pipeline.variables.BULGE`).

    Parameters
    ----------
    model : ``"ph-limit"`` (closed form), ``"reynolds"`` (slip-corrected Reynolds solve per protrusion) or
        ``"rough-reynolds"`` (the Reynolds solve of the rough gap with the Boltzmann flow rate, ``slip`` ignored)
    p_pad : pad pressure [Pa]; a, b : footprint semi-axes along / across sliding [m]; speed : disk speed [m/s]
    gaps : apex gaps [m] (increasing, > 0; :func:`table_gaps`); protrusions : [m] (>= 0; :func:`table_protrusions`)
    profile : ``"ellipsoid"`` or ``"paraboloid"``; slip : :data:`pipeline.physics.reynolds.SLIP_MODELS`
    viscosity [Pa s], mean_free_path [m] at ambient_pressure [Pa]; grid : the Reynolds solver's settings
    roughness : the gap's roughness (:class:`pipeline.physics.gas_flow.RoughGap`), required by ``"rough-reynolds"``

    Returns
    -------
    Dataset on ``(protrusion, apex_gap)`` [nm] with ``bulge_lift`` [mN], ``bulge_stiffness`` [N/m],
    ``bulge_lift_ph_limit`` [mN], ``bearing_number`` [1], ``pad_pressure`` [MPa], and the settings as
    attributes (no timing: equal inputs give equal datasets).
    """
    bb.BULGE_LAWS.lookup(model)  # (a name not registered: the registry's one line)
    if model not in MODELS:
        raise ValueError(f"air_bearing.bulge = {model!r}: no table of this law; expected one of {list(MODELS)} for a "
                         "table ('none' needs no table)")
    gaps = np.asarray(gaps, dtype=float)
    protrusions = np.asarray(protrusions, dtype=float)
    if np.any(protrusions < 0):
        raise ValueError("bulge table: protrusions must be >= 0 [m]")
    rough = model == "rough-reynolds"
    if rough:
        if roughness is None:
            raise ValueError("bulge table: air_bearing.bulge = 'rough-reynolds' needs the gap's roughness")
        slip = "boltzmann"
    if model in ("reynolds", "rough-reynolds"):
        t = reynolds_table(gaps, protrusions, p_pad=p_pad, a=a, b=b, speed=speed, viscosity=viscosity,
                           mean_free_path=mean_free_path, ambient_pressure=ambient_pressure, profile=profile,
                           slip=slip, grid=grid, roughness=roughness if rough else None)
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
        "bulge_model": model, "bulge_profile": profile, "slip_model": slip if model != "ph-limit" else "n/a",
        "footprint_semi_axes_um": np.array([a, b]) / UM, "disk_speed_m_s": speed,
        "air_viscosity_pa_s": viscosity, "mean_free_path_nm": mean_free_path / NM,
        "ambient_pressure_pa": ambient_pressure,
        "reynolds_grid": (f"cells_per_a={grid.cells_per_a} cells_per_b={grid.cells_per_b} margin_a={grid.margin_a} "
                          f"margin_b={grid.margin_b} tol={grid.tol}") if model != "ph-limit" else "n/a",
    })
    if rough:
        ds.attrs.update({"roughness_sigma_nm": roughness.sigma / NM, "disk_roughness_share": roughness.disk_share,
                         "wetting_gap_nm": roughness.wet_gap / NM})
    return ds


def from_dataset(ds: xr.Dataset) -> bb.LiftTable:
    """The table of a ``bulge.nc`` dataset in SI, as the dynamics reads it (:class:`pipeline.physics.bulge_bearing.LiftTable`:
    the lift's ratio to the closed form and its slope in ``ln g``)."""
    a, b = (float(v) * UM for v in ds.attrs["footprint_semi_axes_um"])
    return bb.lift_table(ds["apex_gap"].values * BULGE["apex_gap"].si_unit,
                         ds["protrusion"].values * BULGE["protrusion"].si_unit,
                         ds["bulge_lift"].values * BULGE["bulge_lift"].si_unit,
                         p_pad=float(ds["pad_pressure"].values) * BULGE["pad_pressure"].si_unit, a=a, b=b,
                         profile=ds.attrs["bulge_profile"])


def lift_at(ds: xr.Dataset, g, protrusion: float, g_min: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Lift [N] and stiffness ``-dF/dg`` [N/m] at apex gaps ``g`` [m] and one protrusion [m] from a ``bulge.nc``
    dataset (:func:`pipeline.physics.bulge_bearing.table_lift` of :func:`from_dataset`); ``g_min`` [m]
    (default: the table's smallest gap) is the floor below which the force is held."""
    return bb.table_lift(from_dataset(ds), g, protrusion, g_min)


#: The table's protrusion step [nm] and the protrusion it reaches at least [nm] (the ratio to the closed
#: form is smooth in the protrusion: linear interpolation between rows 0.5 nm apart errs by < 1e-3,
#: tests/stages/test_bulge.py).
PROTRUSION_STEP_NM = 0.5
PROTRUSION_STOP_NM = 15.0


def table_stop_nm(scene: Any) -> float:
    """The deepest protrusion [nm] of a scene's table: :data:`PROTRUSION_STOP_NM`, or the scene's deepest
    protrusion (:func:`pipeline.model.interface_tables.deepest_protrusion_nm`) rounded up to the step when
    deeper. The ``bulge`` stage depends on this value, not on the protrusion keys themselves."""
    deepest = deepest_protrusion_nm(scene)
    return max(PROTRUSION_STOP_NM, float(np.ceil(deepest / PROTRUSION_STEP_NM - TOL_NM)) * PROTRUSION_STEP_NM)


def scene_table(scene: Any, p_pad: float | None = None) -> xr.Dataset:
    """The ``bulge.nc`` dataset of a scene (:func:`bulge_table` of its keys): model ``air_bearing.bulge``,
    pad pressure ``air_bearing.pad_pressure_mpa`` (or ``p_pad`` [Pa] when given, which the key is then not
    read for: the node tables of :mod:`pipeline.model.bulge_pads`), profile ``air_bearing.bulge_profile``, slip model
    ``air_bearing.bulge_slip``, the roughness of :func:`scene_roughness` (rough law), footprint semi-axes
    ``tfc.half_length_um``, ``tfc.half_width_um``, the disk speed of ``[dmw] radius_mm, rpm``
    (:func:`pipeline.model.dmw_record.disk_speed_m_s`), the Reynolds grid
    ``solver.bulge_cells_per_a``, ``solver.bulge_cells_per_b``; gaps :func:`table_gaps`, protrusions
    :func:`table_protrusions` up to :func:`table_stop_nm`."""
    a, sol = scene["air_bearing"], scene["solver"]
    si = scene.si
    grid = ReynoldsGrid(cells_per_a=sol["bulge_cells_per_a"], cells_per_b=sol["bulge_cells_per_b"])
    rough = scene_roughness(scene)
    p_pad = si.air_bearing.pad_pressure if p_pad is None else float(p_pad)
    return bulge_table(model=a["bulge"], p_pad=p_pad, a=si.tfc.half_length,
                       b=si.tfc.half_width, speed=disk_speed_m_s(scene["dmw"]), gaps=table_gaps(),
                       protrusions=table_protrusions(table_stop_nm(scene), PROTRUSION_STEP_NM),
                       profile=a["bulge_profile"], slip=a["bulge_slip"], grid=grid, roughness=rough)


def scene_roughness(scene: Any) -> gas_flow.RoughGap | None:
    """The roughness of the bulge's gap for ``air_bearing.bulge = "rough-reynolds"`` (else ``None``): the
    combined ``roughness.sigma_nm``, the disk's share ``air_bearing.disk_roughness_share`` of its variance and
    the wetting gap ``lubricant.thickness_nm`` (docs/model.md, section "Rough-gap bulge bearing")."""
    if scene["air_bearing"]["bulge"] != "rough-reynolds":
        return None
    si = scene.si
    return gas_flow.RoughGap(sigma=si.roughness.sigma, disk_share=scene["air_bearing"]["disk_roughness_share"],
                             wet_gap=si.lubricant.thickness)
