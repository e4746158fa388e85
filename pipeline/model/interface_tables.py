"""The ISBL interface tables of a scene, in memory: roughness statistics and materials to tables.

:func:`build_tables` returns the ``interface.nc`` dataset (contact, adhesion and friction pressures,
real-area and contact fractions versus separation, docs/model.md, section "ISBL interface"); the
interface stage writes it, and the parameter studies and the accuracy stage build candidates' tables
with the same function. Only what the scene's effects need is computed.

With ``interface.model = "deterministic"`` the contact tables (``contact_pressure``,
``real_area_fraction``, ``friction_stress``) get a leading ``model`` dimension holding the statistical
and the deterministic tables (FFT boundary elements on the measured surface,
:mod:`pipeline.model.deterministic_tables`), plus the solved points (``solved_*``); the default,
``"statistical"``, gives exactly the statistical dataset.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..physics import isbl
from ..physics.asperity import critical_interference
from ..physics.friction import FRICTION_LAWS, shear_strength
from ..physics.material_bounds import check_materials
from ..physics.asperity_statistics import (composite_modulus, explicit_statistics, hardness_from_plasticity_gw,
                                  plasticity_index_gw, plasticity_index_ke)
from ..config.grid import TOL_NM, label
from ..config.fields import fields
from ..io import file_hash
from ..units import MPA, NM, UM
from ..variables import INTERFACE
from . import roughness_statistics as rough
from .deterministic_tables import MODELS, deterministic_tables

log = logging.getLogger(__name__)

#: The scene keys the interface tables are made of (:func:`build_tables` of :func:`roughness_statistics`).
FIELDS = fields("scene.effects", "roughness.*", "materials.*", "lubricant.thickness_nm",
                "lubricant.work_of_adhesion_j_m2", "lubricant.intermolecular_distance_nm",
                "lubricant.bridge_work_of_adhesion_j_m2", "lubricant.solid_work_of_adhesion_j_m2",
                "solver.table_step_nm", "solver.table_min_sigma", "solver.table_max_nm", "solver.quadrature_nodes",
                "solver.quadrature_panels", "solver.contact_grid_points", "air_bearing.flying_height_nm",
                "interface.model", "interface.adhesion")
#: The scene keys the tables read through a value derived from them (:func:`deepest_protrusion_nm`,
#: :func:`lubricant_shear_on`, :func:`summit_friction_law`): a change that leaves the value changes nothing.
DERIVED_FIELDS = fields("tfc.protrusion_nm", "sweep.protrusion_nm", "lubricant.shear_stress_mpa",
                        "contact.friction_law")


def roughness_statistics(scene: Any, roughness: str | Path | xr.Dataset | None = None) -> dict[str, float]:
    """Combined-surface statistics [SI] for the scene: from AFM scans or the explicit values.

    With ``[roughness] afm``, the statistics of the ``combined`` surface (route ``[roughness] route``)
    of ``roughness``: a current ``roughness.nc`` (path or dataset) when the caller has one (a stage's
    upstream), else computed here from the scans (:func:`pipeline.model.roughness_statistics.build_dataset`, the
    numbers the roughness stage writes). Otherwise ``sigma_nm``, ``summit_radius_um`` and
    ``summit_density_per_um2`` give ``sigma_s`` and ``y_s`` by McCool's relations (docs/model.md,
    section "Asperity statistics").

    Returns
    -------
    dict with ``sigma``, ``sigma_s``, ``y_s``, ``R`` [m], ``eta`` [m^-2], ``alpha`` [1], ``source``.
    """
    r = scene["roughness"]
    if r["afm"]:
        if roughness is None:
            detrend = r.get("detrend", "plane")
            files = [Path(f) for f in r["afm"]]
            roughness = rough.build_dataset(rough.summaries(files, r.get("channel"), detrend), scene, detrend)
        st = rough.combined_statistics(roughness, route=r["route"])
        return {"sigma": st["sigma_nm"] * NM, "sigma_s": st["sigma_s_nm"] * NM, "y_s": st["y_s_nm"] * NM,
                "R": st["summit_radius_um"] * UM, "eta": st["summit_density_per_um2"] / UM**2,
                "alpha": st["alpha"], "source": f"AFM ({r['route']} route): {', '.join(r['afm'])}"}
    sr = scene.si.roughness
    return {**explicit_statistics(sr.sigma, sr.summit_radius, sr.summit_density),
            "source": "explicit statistics"}


#: The statistics of a roughness set as :func:`used_statistics` gives them: its scene key (units in the name)
#: and the ``interface.nc`` variable (dataset units) it is read from.
USED_STATISTICS = (("sigma_nm", "sigma"), ("summit_radius_um", "summit_radius"),
                   ("summit_density_per_um2", "summit_density"), ("plasticity_index", "plasticity_index_gw"),
                   ("y_s_nm", "y_s"))


def used_statistics(scene: Any, interface: xr.Dataset | None = None) -> dict[str, Any]:
    """The roughness statistics the scene's interface model used, in the units of the scene keys.

    ``sigma_nm`` [nm], ``summit_radius_um`` [um], ``summit_density_per_um2`` [um^-2], the GW plasticity index
    ``plasticity_index`` [1] (docs/model.md, section "Asperity statistics") and the summit offset ``y_s_nm``
    [nm], plus ``source`` (``interface.nc``'s ``roughness_source``). ``interface``: the scene's interface
    tables (the interface stage's ``interface.nc``), ``None`` for a scene that reads none (flying only), whose
    statistics are then computed here as the stage would (:func:`build_tables` without tables, no quadrature).
    With ``[roughness] afm`` every number is the scans' (the interface stage's); with explicit statistics
    sigma, R and eta are the given keys exactly (the dataset's unit conversion is not always exact:
    13.3 um^-2 reads back as 13.300000000000002) and psi and y_s follow from them.
    """
    if interface is None:
        stats = roughness_statistics(scene)
        interface = xr.Dataset(interface_scalars(scene, stats)[1], attrs={"roughness_source": stats["source"]})
    out: dict[str, Any] = {key: float(interface[var]) for key, var in USED_STATISTICS}
    r = scene["roughness"]
    if not r["afm"]:
        out.update({key: float(r[key]) for key in ("sigma_nm", "summit_radius_um", "summit_density_per_um2")})
    out["source"] = str(interface.attrs.get("roughness_source", ""))
    return out


def roughness_record(table: dict[str, Any], statistics: dict[str, Any]) -> dict[str, Any]:
    """A roughness set as ``sweep.nc``'s attribute ``roughness_sets`` records it: its ``[roughness]`` table with
    the statistics its interface model used (:func:`used_statistics`) in place of the keys (an AFM set's ``sigma_nm``, ... are the scans', not the
    scene's unused defaults), the plasticity index, the summit offset ``y_s_nm``, where they came from
    (``statistics_source``) and, for an AFM set, each scan's SHA-256 (``afm_sha256``: path -> hex digest)."""
    record = dict(table)
    record.update({key: value for key, value in statistics.items() if key != "source"})
    record["statistics_source"] = statistics.get("source", "")
    if table.get("afm"):
        record["afm_sha256"] = {str(f): file_hash(f) for f in table["afm"]}
    return record


def interface_parameters(scene: Any, stats: dict[str, float]) -> isbl.Interface:
    """The :class:`~pipeline.physics.isbl.Interface` of a scene and its roughness statistics.

    ``E'`` from the two moduli (or ``composite_modulus_gpa``); ``H`` from ``hardness_gpa`` or, when
    absent, from the GW plasticity index (docs/model.md, section "Parameters": ``H`` is set so that psi(GW) = 0.52).
    """
    si = scene.si
    m, lub = si.materials, si.lubricant
    nu = m.poisson_ratio
    E = m.composite_modulus if m.composite_modulus else composite_modulus(m.disk_modulus, m.tfc_modulus, nu)
    H = m.hardness if m.hardness else hardness_from_plasticity_gw(m.plasticity_index, E, stats["sigma_s"], stats["R"])
    check_materials(E, H, stats["sigma_s"], stats["R"], derived="plasticity_index" if m.hardness else "hardness")
    return isbl.Interface(sigma_s=stats["sigma_s"], eta=stats["eta"], R=stats["R"], E=E, H=H, nu=nu,
                          t=lub.thickness, dgamma=lub.work_of_adhesion, eps=lub.intermolecular_distance,
                          dgamma_bridge=lub.bridge_work_of_adhesion, friction_law=summit_friction_law(scene),
                          dgamma_solid=lub.solid_work_of_adhesion)


def summit_friction_law(scene: Any) -> str:
    """The friction law whose per-summit form the scene's ``friction_stress`` table integrates: the scene's
    ``contact.friction_law`` when it has one (:attr:`pipeline.physics.friction.FrictionLaw.summit`, e.g.
    ``"kogut-etsion"``), else ``"shear-strength"`` (the table the other laws read, ``eta int tau_y A phi dz``).
    The interface stage keys on this (its ``derived``), not on the law's name."""
    law = scene["contact"]["friction_law"]
    return law if FRICTION_LAWS.lookup(law).summit is not None else "shear-strength"


def needed_quantities(effects: frozenset[str], lubricant_shear: bool = False) -> tuple[str, ...]:
    """The ISBL quantities a set of effects needs (empty for a flying-only scene); ``lubricant_shear``:
    the lubricant-shear friction term is on (``lubricant.shear_stress_mpa > 0``), which reads the wetted
    area (:func:`lubricant_shear_on`)."""
    q = []
    if "contact" in effects:
        q += ["contact_pressure", "real_area_fraction", "contact_fraction"]
    if "friction" in effects:
        q += ["friction_stress"] + (["wetted_area_fraction"] if lubricant_shear else [])
    if "adhesion" in effects:
        q += ["adhesion_pressure"]
    return tuple(q)


def lubricant_shear_on(scene: Any) -> bool:
    """Whether the scene's friction has the lubricant-shear term (``lubricant.shear_stress_mpa > 0`` with
    the friction effect): the tables then hold ``wetted_area_fraction``. Its value does not change the
    tables, only whether it is on (the interface stage keys on this, not on the stress)."""
    return "friction" in scene.effects and scene["lubricant"]["shear_stress_mpa"] > 0


def separation_labels(lo_nm: float, hi_nm: float, step_nm: float) -> np.ndarray:
    """The tables' uniform separation grid [nm]: whole multiples of ``step_nm`` from at or below
    ``lo_nm`` to at least ``hi_nm``, rounded like the protrusion grid (:func:`pipeline.config.grid.label`),
    so ``interface.sel(separation=0.0)`` hits a label (``lo + step * i`` gave -4.8999999999999995)."""
    first, n = separation_rows(lo_nm, hi_nm, step_nm)
    return label(step_nm * (first + np.arange(n)))


def separation_rows(lo_nm: float, hi_nm: float, step_nm: float) -> tuple[int, int]:
    """The tables' grid (:func:`separation_labels`) as its first label's multiple of ``step_nm`` and its row count."""
    first = math.floor(lo_nm / step_nm + TOL_NM)
    return first, math.ceil((hi_nm - first * step_nm) / step_nm - TOL_NM) + 1


def table_floor(scene: Any, sigmas: tuple[float, ...], deepest_nm: float) -> float:
    """The lowest separation [m] the tables must reach: ``solver.table_min_sigma`` times each of ``sigmas``
    [m] (the summits', the surface's), and 1 nm below the deepest nominal interference, the flying height
    less ``deepest_nm`` (:func:`deepest_protrusion_nm`); below the table the kernel extrapolates linearly."""
    n_sigma = scene["solver"]["table_min_sigma"]
    return min(*(n_sigma * s for s in sigmas), (scene["air_bearing"]["flying_height_nm"] - deepest_nm - 1.0) * NM)


def interface_scalars(scene: Any, stats: dict[str, float]) -> tuple[isbl.Interface, dict[str, xr.Variable]]:
    """The interface parameters of a scene and its roughness statistics (:func:`interface_parameters`) and
    the 0-d variables of ``interface.nc`` that describe them (roughness, materials, lubricant; dataset units)."""
    p = interface_parameters(scene, stats)
    # dataset units and long names: pipeline/variables.py INTERFACE; values in SI here
    scalars = {
        "sigma": stats["sigma"], "sigma_s": p.sigma_s, "y_s": stats["y_s"], "summit_radius": p.R,
        "summit_density": p.eta, "bandwidth_alpha": stats["alpha"], "composite_modulus": p.E, "hardness": p.H,
        "critical_interference": critical_interference(p.R, p.E, p.H, p.nu),
        "shear_strength": shear_strength(p.H),
        "plasticity_index_gw": plasticity_index_gw(p.E, p.H, p.sigma_s, p.R),
        "plasticity_index_ke": plasticity_index_ke(p.E, p.H, p.sigma_s, p.R, p.nu),
        "lubricant_thickness": p.t, "work_of_adhesion": p.dgamma, "intermolecular_distance": p.eps,
    }
    if p.dgamma_bridge is not None:
        scalars["bridge_work_of_adhesion"] = p.dgamma_bridge
    if p.dgamma_solid is not None:
        scalars["solid_work_of_adhesion"] = p.dgamma_solid
    return p, {k: INTERFACE[k].from_si(v, ()) for k, v in scalars.items()}


def build_tables(scene: Any, stats: dict[str, float]) -> xr.Dataset:
    """Compute the interface dataset of a scene for given roughness statistics (no I/O)."""
    p, data = interface_scalars(scene, stats)
    sol = scene["solver"]
    wanted = needed_quantities(scene.effects, lubricant_shear_on(scene))
    coords = {}
    if wanted:
        # The table must reach past the Gaussian window (TAIL sigma_s), where the contact terms vanish,
        # so that holding the last value beyond the table is exact for them (very rough surfaces).
        d_max = max(scene.si.solver.table_max, (isbl.TAIL + 0.5) * p.sigma_s)
        # ... and start below every separation the slider can reach (table_floor)
        d_min = table_floor(scene, (p.sigma_s, stats["sigma"]), deepest_protrusion_nm(scene))
        d_nm = separation_labels(d_min / NM, d_max / NM, sol["table_step_nm"])
        d = d_nm * NM
        tables = isbl.isbl_tables(d, p, quantities=wanted, nodes=sol["quadrature_nodes"],
                                  panels=sol["quadrature_panels"])
        coords["separation"] = INTERFACE["separation"].data(d_nm, ("separation",))
        for name, values in tables.items():
            data[name] = INTERFACE[name].from_si(values, ("separation",))
        if scene["interface"]["model"] == "deterministic":  # both models side by side on `model`
            data.update(deterministic_variables(scene, stats, p, d, tables, wanted))
            coords["model"] = INTERFACE["model"].data(list(MODELS), ("model",))
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({
        "roughness_source": stats.get("source", ""),
        "plasticity_index_form": "both: plasticity_index_gw (GW 1966) and plasticity_index_ke (CEB/KE)",
        "adhesion_model": scene["interface"]["adhesion"],
        "quadrature": f"composite Gauss-Legendre, {sol['quadrature_panels']} panels x "
                      f"{sol['quadrature_nodes']} nodes per population range, |z| <= {isbl.TAIL} sigma_s",
        "quantities": " ".join(wanted) if wanted else "none (flying-only scene: no interface tables)",
        **({"friction_stress_law": p.friction_law} if p.friction_law != "shear-strength" else {}),
        "references": "Greenwood & Williamson 1966; Kogut & Etsion 2002; Stanley, Etsion & Bogy 1990; "
                      "Vakis, Lee & Polycarpou 2009",
    })
    return ds


def deterministic_variables(scene: Any, stats: dict[str, float], p: isbl.Interface, d: np.ndarray,
                            tables: dict[str, np.ndarray], wanted: tuple[str, ...]) -> dict[str, xr.Variable]:
    """The tables of both models on ``(model, separation)`` and the deterministic solved series.

    The statistical values are ``tables`` (SI); the deterministic ones come from
    :func:`pipeline.model.deterministic_tables.deterministic_tables` on the same grid ``d`` [m].
    """
    det, solved = deterministic_tables(scene, stats["y_s"], p.E, p.H, d, wanted)
    out = {name: INTERFACE[name].from_si(np.stack([tables[name], det[name]]), ("model", "separation"),
                                         **{"model_note": "deterministic: FFT boundary elements on the measured "
                                                          "surface (ContactMechanics); datum d = u - y_s"})
           for name in det}
    s = ("solved",)
    if solved["skipped"]:
        log.warning("interface: %d of the deterministic loads did not converge and are left out: %s MPa",
                    len(solved["skipped"]), ", ".join(f"{x / MPA:.4g}" for x in solved["skipped"]))
    if solved["first_contact"] > d[-1]:  # beyond the grid the kernel holds the last value
        log.warning("interface: the deterministic first contact, %.3g nm, lies beyond the tables' end, %.3g nm "
                    "(solver.table_max_nm): raise it to tabulate the first contacts", solved["first_contact"] / NM,
                    d[-1] / NM)
    out.update({
        "solved_separation": INTERFACE["solved_separation"].from_si(solved["separation"], s),
        "solved_contact_pressure": INTERFACE["solved_contact_pressure"].from_si(solved["contact_pressure"], s),
        "solved_real_area_fraction": INTERFACE["solved_real_area_fraction"].from_si(solved["real_area_fraction"], s),
        "solved_iterations": INTERFACE["solved_iterations"].from_si(solved["iterations"], s),
        "contact_grid_points": INTERFACE["contact_grid_points"].from_si(solved["grid_points"], ()),
        "contact_pixel_size": INTERFACE["contact_pixel_size"].from_si(solved["pixel_size"], ()),
        "contact_rms_slope": INTERFACE["contact_rms_slope"].from_si(solved["rms_slope"], ()),
    })
    return out


def deepest_protrusion_nm(scene: Any) -> float:
    """The deepest protrusion [nm] the tables must reach: the scene's own or its sweep's last.

    The tables depend on this value, not on ``tfc.protrusion_nm`` itself (the interface stage's ``derived``): a
    protrusion changed within the sweep's range leaves them, and the sweep that reads them, current.
    """
    return max(scene["tfc"]["protrusion_nm"], scene["sweep"]["protrusion_nm"]["stop"])
