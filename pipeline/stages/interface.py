"""Stage ``interface``: ISBL tables versus separation for the scene's roughness and materials.

Writes ``interface.nc``: ``contact_pressure``, ``adhesion_pressure``, ``friction_stress`` [MPa],
``real_area_fraction``, ``contact_fraction`` [1] on a uniform ``separation`` grid [nm] (from the
mean of summit heights; the grid is the solver's ``table_step_nm`` from ``table_min_sigma``
summit sigmas to ``table_max_nm``), plus the interface parameters as scalar variables.

Only what the scene's effects need is computed: no ``adhesion`` effect, no adhesion column;
no ``friction``, no friction column; a scene with neither ``contact`` nor ``adhesion`` (flying only)
gets no tables at all.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..io import read_dataset
from ..physics import isbl
from ..physics.asperity import critical_interference
from ..physics.friction import shear_strength
from ..physics.statistics import (composite_modulus, explicit_statistics, hardness_from_plasticity_gw,
                                  plasticity_index_gw, plasticity_index_ke)
from ..physics.material_bounds import check_materials
from ..variables import INTERFACE
from ..runner import Inputs, Stage, build, ensure

NM, UM = 1e-9, 1e-6


def roughness_statistics(scene: Any, out: Path | None = None,
                         roughness_nc: Path | None = None) -> dict[str, float]:
    """Combined-surface statistics [SI] for the scene: from AFM scans or the explicit values.

    With ``[roughness] afm``, the statistics of the ``combined`` surface of a ``roughness.nc`` (route
    ``[roughness] route``): ``roughness_nc`` when the caller has it current (a stage's upstream),
    else the one in ``out`` made current first (:func:`pipeline.runner.ensure`; in a temporary folder
    when ``out`` is ``None``). Otherwise ``sigma_nm``, ``summit_radius_um`` and ``summit_density_per_um2``
    give ``sigma_s`` and ``y_s`` by McCool's relations (SPEC.md section 1).

    Returns
    -------
    dict with ``sigma``, ``sigma_s``, ``y_s``, ``R`` [m], ``eta`` [m^-2], ``alpha`` [1], ``source``.
    """
    r = scene["roughness"]
    if r["afm"]:
        from . import roughness as roughness_stage
        if roughness_nc is not None:
            st = roughness_stage.combined_statistics(roughness_nc, route=r["route"])
        elif out is None:
            import tempfile
            with tempfile.TemporaryDirectory() as tmp:
                st = roughness_stage.combined_statistics(ensure("roughness", scene, tmp), route=r["route"])
        else:
            st = roughness_stage.combined_statistics(ensure("roughness", scene, out), route=r["route"])
        return {"sigma": st["sigma_nm"] * NM, "sigma_s": st["sigma_s_nm"] * NM, "y_s": st["y_s_nm"] * NM,
                "R": st["summit_radius_um"] * UM, "eta": st["summit_density_per_um2"] / UM**2,
                "alpha": st["alpha"], "source": f"AFM ({r['route']} route): {', '.join(r['afm'])}"}
    return {**explicit_statistics(r["sigma_nm"], r["summit_radius_um"], r["summit_density_per_um2"]),
            "source": "explicit statistics"}


def interface_parameters(scene: Any, stats: dict[str, float]) -> isbl.Interface:
    """The :class:`~pipeline.physics.isbl.Interface` of a scene and its roughness statistics.

    ``E'`` from the two moduli (or ``composite_modulus_gpa``); ``H`` from ``hardness_gpa`` or, when
    absent, from the GW plasticity index (SPEC.md section 6: ``H`` is set so that psi(GW) = 0.52).
    """
    m, lub = scene["materials"], scene["lubricant"]
    nu = m["poisson_ratio"]
    E = (m["composite_modulus_gpa"] * 1e9 if m["composite_modulus_gpa"]
         else composite_modulus(m["disk_modulus_gpa"] * 1e9, m["tfc_modulus_gpa"] * 1e9, nu))
    H = (m["hardness_gpa"] * 1e9 if m["hardness_gpa"]
         else hardness_from_plasticity_gw(m["plasticity_index"], E, stats["sigma_s"], stats["R"]))
    check_materials(E, H, stats["sigma_s"], stats["R"],
                    derived="plasticity_index" if m["hardness_gpa"] else "hardness")
    return isbl.Interface(sigma_s=stats["sigma_s"], eta=stats["eta"], R=stats["R"], E=E, H=H, nu=nu,
                          t=lub["thickness_nm"] * NM, dgamma=lub["work_of_adhesion_j_m2"],
                          eps=lub["intermolecular_distance_nm"] * NM)


def needed_quantities(effects: frozenset[str]) -> tuple[str, ...]:
    """The ISBL quantities a set of effects needs (empty for a flying-only scene)."""
    q = []
    if "contact" in effects:
        q += ["contact_pressure", "real_area_fraction", "contact_fraction"]
    if "friction" in effects:
        q += ["friction_stress"]
    if "adhesion" in effects:
        q += ["adhesion_pressure"]
    return tuple(q)


def separation_labels(lo_nm: float, hi_nm: float, step_nm: float) -> np.ndarray:
    """The tables' uniform separation grid [nm]: whole multiples of ``step_nm`` from at or below
    ``lo_nm`` to at least ``hi_nm``, rounded to 1e-9 nm like the protrusion grid
    (:func:`pipeline.stages.sweep_grid.range_grid`), so ``interface.sel(separation=0.0)`` hits a label
    (``lo + step * i`` gave -4.8999999999999995)."""
    first = math.floor(lo_nm / step_nm + 1e-9)
    n = math.ceil((hi_nm - first * step_nm) / step_nm - 1e-9) + 1
    return np.round(step_nm * (first + np.arange(n)), 9)


def build_tables(scene: Any, stats: dict[str, float]) -> xr.Dataset:
    """Compute the interface dataset of a scene for given roughness statistics (no I/O)."""
    p = interface_parameters(scene, stats)
    sol = scene["solver"]
    wanted = needed_quantities(scene.effects)
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
    data = {k: INTERFACE[k].from_si(v, ()) for k, v in scalars.items()}
    coords = {}
    if wanted:
        # The table must reach past the Gaussian window (TAIL sigma_s), where the contact terms vanish,
        # so that holding the last value beyond the table is exact for them (very rough surfaces).
        d_max = max(sol["table_max_nm"] * NM, (isbl.TAIL + 0.5) * p.sigma_s)
        # ... and start below every separation the slider can reach: table_min_sigma summit (and
        # surface) sigmas, and 1 nm below the deepest nominal interference FH0 - protrusion of the scene
        # and its sweep (below the table the kernel extrapolates linearly).
        fh0 = scene["air_bearing"]["flying_height_nm"]
        d_min = min(sol["table_min_sigma"] * p.sigma_s, sol["table_min_sigma"] * stats["sigma"],
                    (fh0 - deepest_protrusion_nm(scene) - 1.0) * NM)
        d_nm = separation_labels(d_min / NM, d_max / NM, sol["table_step_nm"])
        d = d_nm * NM
        tables = isbl.isbl_tables(d, p, quantities=wanted, nodes=sol["quadrature_nodes"],
                                  panels=sol["quadrature_panels"])
        coords["separation"] = INTERFACE["separation"].data(d_nm, ("separation",))
        for name, values in tables.items():
            data[name] = INTERFACE[name].from_si(values, ("separation",))
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({
        "roughness_source": stats.get("source", ""),
        "plasticity_index_form": "both: plasticity_index_gw (GW 1966) and plasticity_index_ke (CEB/KE)",
        "quadrature": f"composite Gauss-Legendre, {sol['quadrature_panels']} panels x "
                      f"{sol['quadrature_nodes']} nodes per population range, |z| <= {isbl.TAIL} sigma_s",
        "quantities": " ".join(wanted) if wanted else "none (flying-only scene: no interface tables)",
        "references": "Greenwood & Williamson 1966; Kogut & Etsion 2002; Stanley, Etsion & Bogy 1990; "
                      "Vakis, Lee & Polycarpou 2009",
    })
    return ds


def deepest_protrusion_nm(scene: Any) -> float:
    """The deepest protrusion [nm] the tables must reach: the scene's own or its sweep's last.

    The tables depend on this value, not on ``tfc.protrusion_nm`` itself (:attr:`STAGE` ``derived``): a
    protrusion changed within the sweep's range leaves them, and the sweep that reads them, current.
    """
    return max(scene["tfc"]["protrusion_nm"], scene["sweep"]["protrusion_nm"]["stop"])


def compute(scene: Any, inputs: Inputs) -> xr.Dataset:
    """The ``interface.nc`` dataset of the scene (see module docstring)."""
    rough = None
    if scene["roughness"]["afm"]:  # upstream: current for these inputs (checked by key), not rebuilt
        inputs.dataset("roughness.nc", stage="roughness")
        rough = inputs.path("roughness.nc")
    return build_tables(scene, roughness_statistics(scene, inputs.out, roughness_nc=rough))


STAGE = Stage(
    "interface", compute, outputs=("interface.nc",),
    reads=("roughness", "materials", "lubricant", "solver.table_step_nm", "solver.table_min_sigma",
           "solver.table_max_nm", "solver.quadrature_nodes", "solver.quadrature_panels", "scene.effects",
           "air_bearing.flying_height_nm"),
    derived=lambda scene: {"deepest_protrusion_nm": deepest_protrusion_nm(scene)},
    upstream=lambda scene: ("roughness",) if scene["roughness"]["afm"] else (),
    order=30, main_job=True, doc="ISBL tables versus separation, interface.nc")


def run(scene: Any, out: Path, **options: Any) -> Path:
    """``interface.nc`` in ``out``, recomputed only when its inputs changed (:func:`pipeline.runner.build`)."""
    return build("interface", scene, out, **options)["interface"][0]


def load(path: Path) -> xr.Dataset:
    """Read ``interface.nc`` (clear error when missing)."""
    return read_dataset(path, stage="interface")
