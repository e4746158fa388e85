"""Deterministic interface tables for the ``interface`` stage (``interface.model = "deterministic"``).

The combined AFM topography of the scene (``roughness.afm``, summed on the grid of the first scan,
:func:`pipeline.physics.deterministic_contact.combine_maps`) is pressed against a flat by the FFT
boundary-element solver of :mod:`pipeline.physics.deterministic_contact` at a series of loads; the
solved contact pressure and real-area fraction are interpolated onto the statistical tables'
``separation`` grid. Datum: the solver gives the mean interfacial separation ``u`` from the mean plane
of the surface; the tables' ``d`` is measured from the mean of summit heights, ``y_s`` above the mean
plane (the ``y_s`` of the interface's roughness route), so ``d = u - y_s`` (docs/deterministic_interface.md).
Friction follows the same shear-strength law as the statistical model on
the computed real area: every solved contact is elastic, so all of it slides at ``tau_y``.
Adhesion is not solved deterministically (ContactMechanics' hard-wall solver is non-adhesive): the
adhesion table stays the statistical one for both models.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..physics import deterministic_contact as dc
from . import afm_scan
from ..physics.friction import shear_strength
from ..units import NM



#: The values of the ``model`` coordinate of ``interface.nc``, in order.
MODELS = ("statistical", "deterministic")

#: Loads of the solved series (log-spaced in the expected real-area fraction).
SERIES_POINTS = 20


def combined_topography(scene: Any, max_points: int | None) -> tuple[np.ndarray, tuple[float, float]]:
    """The combined height map [nm] of the scene's AFM scans and its lateral sizes [nm].

    Each scan is read and detrended as the roughness stage reads it (``roughness.channel``,
    ``roughness.detrend``); several are summed on the first scan's grid; the sum is resampled to at
    most ``max_points`` per side (``solver.contact_grid_points``).

    Raises
    ------
    ValueError
        When the scene has no AFM scans (the deterministic model needs a measured surface).
    """
    r = scene["roughness"]
    if not r["afm"]:
        raise ValueError("interface.model = 'deterministic' needs measured surfaces: set roughness.afm")
    maps = []
    for f in r["afm"]:
        t = afm_scan.read_topography(f, channel=r["channel"], detrend_mode=r["detrend"])
        maps.append((np.ma.getdata(t.heights()).astype(float), tuple(float(s) for s in t.physical_sizes)))
    h, sizes = dc.combine_maps(maps)
    h = dc.resample(h, max_points)
    return h - h.mean(), sizes


def deterministic_tables(scene: Any, y_s: float, E: float, H: float, d: np.ndarray, wanted: tuple[str, ...]
                         ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The deterministic tables [SI] on the separation grid ``d`` [m], and the solved series.

    Parameters
    ----------
    scene : the scene (AFM scans, ``solver.contact_grid_points``)
    y_s : mean of summit heights above the mean plane [m] (the datum shift ``d = u - y_s``)
    E : composite modulus E' [Pa]; H : hardness [Pa] (shear strength of the friction law)
    d : separation grid of the statistical tables [m]
    wanted : the quantities the scene's effects need (``contact_pressure``, ``real_area_fraction``,
        ``friction_stress``; others are not deterministic and stay statistical)

    Returns
    -------
    ``(tables, solved)``: tables ``contact_pressure`` [Pa], ``real_area_fraction`` [1],
    ``friction_stress`` [Pa] versus ``d`` (those in ``wanted``); ``solved``: the solved series
    (``separation`` [m], ``contact_pressure`` [Pa], ``real_area_fraction`` [1], ``iterations``) and
    the map's ``grid_points``, ``pixel_size`` [m], ``rms_slope`` [1] and ``first_contact``, the
    separation of first contact [m] (highest point of the map minus ``y_s``), ``skipped``: the loads
    [Pa] whose solve did not converge (left out of the tables).
    """
    h, sizes = combined_topography(scene, scene["solver"]["contact_grid_points"])
    series = dc.contact_series(h, sizes, points=SERIES_POINTS)
    p, area = dc.tabulate(series, np.asarray(d, float) / NM + y_s / NM)
    tables = {"contact_pressure": p * E, "real_area_fraction": area,
              "friction_stress": shear_strength(H) * area}
    tables = {k: v for k, v in tables.items() if k in wanted}
    solved = {"separation": (series.mean_gap - y_s / NM) * NM, "contact_pressure": series.pressure * E,
              "real_area_fraction": series.area_fraction, "iterations": series.iterations,
              "grid_points": float(h.shape[0] * h.shape[1]), "pixel_size": series.pixel_size * NM,
              "rms_slope": dc.rms_slope(h, sizes), "grid": h.shape,
              "first_contact": (series.onset_gap - y_s / NM) * NM,
              "skipped": [x * E for x in series.skipped]}
    return tables, solved
