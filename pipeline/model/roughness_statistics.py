"""Asperity statistics of a scene's combined rough surface, in memory: AFM scans or explicit values.

The roughness stage writes what :func:`build_dataset` returns (``roughness.nc``); the interface tables
read the ``combined`` row of it (:func:`combined_statistics`). Both routes of docs/model.md, section
"Asperity statistics": ``spectral`` (McCool/Nayak moments) and ``summits`` (direct count).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import xarray as xr

from ..io import DatasetError, read_dataset
from ..physics import asperity_statistics as st
from ..physics import surface as sf
from . import afm_scan
from ..units import NM_IN_UM, PER_NM2_IN_PER_UM2
from ..variables import ROUGHNESS

ROUTES = ("spectral", "summits")


COMBINED = "combined"


def _unique_labels(files: Sequence[Path]) -> list[str]:
    """File stems, made unique (``name``, ``name-2``, ...) and never ``"combined"``."""
    labels: list[str] = []
    for f in files:
        base = f.stem or f.name
        if base == COMBINED:
            base = f"{base}-file"
        label, n = base, 2
        while label in labels:
            label, n = f"{base}-{n}", n + 1
        labels.append(label)
    return labels


def _materials(scene: Any) -> dict[str, float]:
    """Composite modulus E' [GPa], hardness H [GPa] and Poisson ratio of the scene (NaN without a scene)."""
    if scene is None:
        return {"E": math.nan, "H": math.nan, "nu": math.nan}
    mat = scene["materials"]
    E = mat.get("composite_modulus_gpa")
    if E is None:
        E = st.composite_modulus(mat["disk_modulus_gpa"], mat["tfc_modulus_gpa"], mat["poisson_ratio"])
    H = mat.get("hardness_gpa")
    return {"E": float(E), "H": math.nan if H is None else float(H), "nu": float(mat["poisson_ratio"])}


def _plasticity(E: float, H: float, nu: float, sigma_s: float, R: float) -> tuple[float, float]:
    """GW and CEB/KE plasticity indices (NaN when an input is missing) [GW66, KE03]."""
    if not all(np.isfinite([E, H, nu, sigma_s, R])) or R <= 0 or sigma_s < 0:
        return math.nan, math.nan
    return (float(st.plasticity_index_gw(E, H, sigma_s, R)), float(st.plasticity_index_ke(E, H, sigma_s, R, nu)))


def build_dataset(summaries: Sequence[sf.SurfaceSummary], scene: Any = None, detrend: str = "") -> xr.Dataset:
    """The ``roughness.nc`` dataset of some surfaces plus their ``"combined"`` surface.

    Parameters
    ----------
    summaries : per-surface results (:func:`pipeline.model.afm_scan.summarise_file` or ``from_statistics``)
    scene : the scene (materials for the plasticity index), or ``None``
    detrend : detrend mode used (recorded)
    """
    surfaces = list(summaries) + [sf.combine(summaries, label=COMBINED)]
    mat = _materials(scene)
    n = len(surfaces)
    cols = {k: np.full((n, 2), np.nan) for k in
            ("sigma", "sigma_s", "y_s", "R", "eta", "alpha", "psi", "psi_ke")}
    for i, s in enumerate(surfaces):
        for j, r in enumerate((s.spectral, s.summits)):
            cols["sigma"][i, j], cols["sigma_s"][i, j], cols["y_s"][i, j] = r.sigma, r.sigma_s, r.y_s
            cols["R"][i, j], cols["eta"][i, j], cols["alpha"][i, j] = r.R * NM_IN_UM, r.eta * PER_NM2_IN_PER_UM2, r.alpha
            cols["psi"][i, j], cols["psi_ke"][i, j] = _plasticity(mat["E"], mat["H"], mat["nu"], r.sigma_s, r.R)
    sm = ("surface", "route")
    per = ("surface",)
    gw = "Greenwood & Williamson 1966"
    formulas = {
        "sigma_s": "spectral: sqrt(sigma^2 - 3.717e-4/(eta R)^2) (McCool 1986); summits: std of counted summit "
                   "heights",
        "y_s": "spectral: 4 sigma/sqrt(pi alpha) (McCool 1986); summits: direct",
        "summit_radius": "spectral: 0.375 sqrt(pi/m4) (Nayak 1971, McCool 1986); "
                         "summits: 1/mean(-(d2z/dx2 + d2z/dy2)/2) at summits",
        "summit_density": "spectral: m4/(6 pi sqrt(3) m2) (Nayak 1971); summits: 8-neighbour maxima per interior area",
        "bandwidth_alpha": "spectral: m0 m4/m2^2; summits: 2412.74 (sigma eta R)^2 (McCool 1986) with the counted "
                           "eta and R",
        "plasticity_index": f"(E'/H) sqrt(sigma_s/R) ({gw})",
        "plasticity_index_ke": "(2E'/(pi K H)) sqrt(sigma_s/R), K = 0.454 + 0.41 nu (Kogut & Etsion 2003)",
    }
    per_route = {"sigma": "sigma", "sigma_s": "sigma_s", "y_s": "y_s", "summit_radius": "R", "summit_density": "eta",
                 "bandwidth_alpha": "alpha", "plasticity_index": "psi", "plasticity_index_ke": "psi_ke"}
    per_surface = {"pixel_size": [s.pixel_size for s in surfaces], "m0": [s.m0 for s in surfaces],
                   "m2": [s.m2 for s in surfaces], "m4": [s.m4 for s in surfaces],
                   "summit_count": [s.summits.count for s in surfaces]}
    data = {name: ROUGHNESS[name].data(cols[col], sm, **({"formula": formulas[name]} if name in formulas else {}))
            for name, col in per_route.items()}
    data.update({name: ROUGHNESS[name].data(np.array(values), per) for name, values in per_surface.items()})
    ds = xr.Dataset(data, coords={"surface": ROUGHNESS["surface"].data([s.label for s in surfaces], per),
                                  "route": ROUGHNESS["route"].data(ROUTES, ("route",))})
    files = {s.label: s.source for s in summaries if s.source}
    attrs: dict[str, Any] = {
        "source_files": files,
        "channels": {s.label: s.channel for s in summaries if s.channel},
        "detrend": detrend,
        "plasticity_index_form": "plasticity_index: GW (E'/H) sqrt(sigma_s/R) [Greenwood & Williamson 1966]; "
                                 "plasticity_index_ke: CEB/KE (2E'/(pi K H)) sqrt(sigma_s/R); "
                                 "NaN where the scene gives no hardness_gpa",
        "composite_modulus_gpa": mat["E"],
        "hardness_gpa": mat["H"],
        "combination_rule": "combined: spectral moments m0, m2, m4 add (sigma^2 adds); the summit route "
                            "cannot be combined across scans (NaN except sigma) unless there is one surface",
        "references": "Nayak, J. Lubr. Technol. 93 (1971) 398; McCool, Wear 107 (1986) 37; "
                      "Greenwood & Williamson, Proc. R. Soc. A 295 (1966) 300",
        "warnings": [w for s in surfaces for w in s.warnings],
    }
    if scene is not None:
        attrs["route"] = scene["roughness"].get("route", "spectral")
    for label, path in files.items():
        attrs["source_file_" + re.sub(r"[^A-Za-z0-9_]", "_", label)] = Path(path).name
    ds.attrs = attrs
    return ds


def summaries(files: Sequence[Path], channel: str | None, detrend: str) -> list[sf.SurfaceSummary]:
    """Both routes' statistics of each AFM file (labels: unique file stems)."""
    labels = _unique_labels(files)
    return [afm_scan.summarise_file(f, channel=channel, detrend_mode=detrend, label=lab) for f, lab in zip(files, labels)]


def combined_statistics(path: str | Path | xr.Dataset, route: str = "spectral") -> dict[str, float]:
    """Statistics of the ``"combined"`` surface of a ``roughness.nc`` for the interface model.

    Parameters
    ----------
    path : the ``roughness.nc`` file, or its dataset in memory (:func:`build_dataset`)
    route : ``"spectral"`` or ``"summits"``

    Returns
    -------
    dict with ``sigma_nm``, ``sigma_s_nm``, ``y_s_nm``, ``summit_radius_um``, ``summit_density_per_um2``,
    ``alpha``

    Raises
    ------
    pipeline.io.DatasetError
        When the file is missing or incomplete, or the route has no combined statistics (the summit
        route for several scans).
    """
    if route not in ROUTES:
        raise ValueError(f"route {route!r}: expected one of {ROUTES}")
    names = ("sigma", "sigma_s", "y_s", "summit_radius", "summit_density", "bandwidth_alpha")
    ds = path if isinstance(path, xr.Dataset) else read_dataset(path, stage="roughness", variables=names)
    # a dataset in memory is named by its source file when it has one, never by its (many-line) repr
    where = ds.encoding.get("source", "the roughness dataset in memory") if ds is path else path
    if COMBINED not in ds["surface"].values:
        raise DatasetError(f"{where}: no '{COMBINED}' surface")
    row = ds.sel(surface=COMBINED, route=route)
    keys = ("sigma_nm", "sigma_s_nm", "y_s_nm", "summit_radius_um", "summit_density_per_um2", "alpha")
    result = {k: float(row[n]) for k, n in zip(keys, names)}
    if not all(np.isfinite(result[k]) for k in ("sigma_nm", "summit_radius_um", "summit_density_per_um2")):
        raise DatasetError(f"{where}: the {route!r} route has no combined statistics (the summit route cannot "
                           f"combine several scans); use route='spectral'")
    return result
