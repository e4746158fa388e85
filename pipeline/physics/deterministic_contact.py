"""Deterministic elastic contact of a measured rough surface against a flat (FFT boundary elements).

The statistical interface (:mod:`pipeline.physics.isbl`) sums single-summit laws over a Gaussian
distribution of summit heights and ignores the elastic interaction of neighbouring contacts. Here the
same height map is pressed against a flat and the elastic half-space problem is solved on every pixel:
contact pressure and real-area fraction versus the mean separation, with no summit identification,
no spectral moments and with the long-range elastic interaction included
(docs/deterministic_interface.md).

Method
------
Small-slope, frictionless, non-adhesive contact of a rigid rough surface (heights ``h``) with an
elastic half-space of contact modulus ``E'`` (the two-body problem maps onto this one, Johnson 1985,
eq. 4.22). The half-space is periodic (the map is repeated, Stanley & Kato 1997 Fourier kernel
``u_q = 2 p_q / (E' |q|)``), the non-negative-gap / non-negative-pressure problem is solved by the
constrained conjugate gradients of Polonsky & Keer (1999) under a prescribed mean pressure. Both come
from ContactMechanics (``PeriodicFFTElasticHalfSpace``, ``constrained_conjugate_gradients``; Pastewka &
Robbins 2016), the contact-mechanics library of the SurfaceTopography family the roughness stage
already uses (why this library: docs/deterministic_interface.md).

The q = 0 stiffness of the half-space is set to zero (``stiffness_q0 = 0``): the mean displacement of
the elastic surface stays zero, so the rigid surface's offset gives the **mean interfacial separation**
``u = <gap>`` directly (Persson 2007; Pastewka et al. 2013). ``u`` is measured from the mean plane of
the rough surface; the statistical tables measure their separation ``d`` from the mean of summit
heights, ``y_s`` above it, so ``d = u - y_s`` (:func:`tabulate`). In the sparse-contact limit the
local deformations cover a vanishing fraction of the area and ``u`` is the GW flat-to-mean-plane
distance, the datum the statistical model uses.

Units: everything inside is in nanometres (heights, lateral sizes) and in units of ``E'`` (pressures
as ``p / E'``): the solver's force tolerance is absolute, so SI numbers (1e-9 m, 1e11 Pa) would
defeat it. The public functions take and return the units their docstrings state.

References
----------
.. [PK99] I. A. Polonsky, L. M. Keer, Wear 231 (1999) 206-219 (constrained conjugate gradients).
.. [SK97] H. M. Stanley, T. Kato, J. Tribol. 119 (1997) 481-485 (FFT half-space kernel).
.. [PR16] L. Pastewka, M. O. Robbins, Appl. Phys. Lett. 108 (2016) 221601 (ContactMechanics).
.. [Persson07] B. N. J. Persson, Phys. Rev. Lett. 99 (2007) 125502 (mean interfacial separation).
.. [Hyun04] S. Hyun, L. Pei, J.-F. Molinari, M. O. Robbins, Phys. Rev. E 70 (2004) 026117
   (light-contact area ``A/A0 = kappa p / (E' h'_rms)``, kappa ~ 2).
.. [Johnson85] K. L. Johnson, Contact Mechanics, Cambridge (1985).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Light-contact proportionality of real area and load used to place the solved loads,
#: ``A/A0 = KAPPA p / (E' h'_rms)`` [Hyun04]; only the spacing of the series depends on it.
KAPPA = 2.0

#: Real-area fractions at which the series is solved by default (log-spaced between these), [1].
AREA_RANGE = (1e-3, 0.6)


@dataclass(frozen=True)
class ContactSeries:
    """Contact of a rough surface against a flat at a series of loads (one row per load).

    Attributes
    ----------
    mean_gap : mean interfacial separation from the rough surface's mean plane [nm], decreasing
    pressure : mean contact pressure per nominal area [units of E'], increasing
    area_fraction : real contact area per nominal area [1] (pixels carrying pressure)
    iterations : conjugate-gradient iterations of each solve [1]
    onset_gap : separation at first contact, highest height above the mean plane [nm]
    grid : the grid points ``(nx, ny)`` of the map solved
    pixel_size : lateral pixel size [nm] (geometric mean of x and y)
    skipped : the loads [units of E'] whose solve did not converge within ``MAXITER`` (left out)
    """

    mean_gap: np.ndarray
    pressure: np.ndarray
    area_fraction: np.ndarray
    iterations: np.ndarray
    onset_gap: float
    grid: tuple[int, int]
    pixel_size: float
    skipped: tuple[float, ...] = ()


def rms_slope(heights: np.ndarray, physical_sizes: tuple[float, float]) -> float:
    """Rms gradient ``h'_rms = sqrt(<|grad h|^2>)`` [1] of a periodic map (central differences).

    Parameters
    ----------
    heights : 2-D map [nm]
    physical_sizes : lateral sizes ``(Lx, Ly)`` [nm]

    Returns
    -------
    float
        The rms slope h'_rms [1].

    References
    ----------
    [PK99], [SK97], [PR16] (the FFT boundary-element solver, ContactMechanics), [Hyun04];
    docs/deterministic_interface.md.
    """
    h = np.asarray(heights, float)
    dx, dy = (s / n for s, n in zip(physical_sizes, h.shape))
    gx = (np.roll(h, -1, 0) - np.roll(h, 1, 0)) / (2 * dx)
    gy = (np.roll(h, -1, 1) - np.roll(h, 1, 1)) / (2 * dy)
    return float(np.sqrt(np.mean(gx**2 + gy**2)))


def resample(heights: np.ndarray, max_points: int | None) -> np.ndarray:
    """The map with at most ``max_points`` per side (Fourier truncation; never refined).

    The solver treats the map as periodic, so periodic (Fourier) resampling is the consistent one:
    it removes the wavelengths shorter than twice the new pixel and nothing else.

    Parameters
    ----------
    heights : 2-D map [any length unit]
    max_points : largest number of grid points per side (``None``: the map as it is)

    Returns
    -------
    numpy.ndarray
        The map [unit of ``heights``], at most ``max_points`` per side.

    References
    ----------
    [PK99], [SK97], [PR16] (the FFT boundary-element solver, ContactMechanics), [Hyun04];
    docs/deterministic_interface.md.
    """
    h = np.asarray(heights, float)
    if max_points is None or max(h.shape) <= max_points:
        return h
    from scipy.signal import resample as fourier_resample
    for axis in (0, 1):
        if h.shape[axis] > max_points:
            h = fourier_resample(h, max_points, axis=axis)
    return h


def combine_maps(maps: list[tuple[np.ndarray, tuple[float, float]]]) -> tuple[np.ndarray, tuple[float, float]]:
    """The sum of several height maps on the grid of the first one [nm] (disk + head against a flat).

    Further maps are read periodically (each is repeated beyond its scan, as the solver repeats the
    sum) and bilinearly interpolated at the first map's pixel centres; the sum is re-centred on its
    mean. The roughness stage combines the same scans by adding spectral moments (surface.combine),
    which agrees with this sum in ``sigma`` only when the scans cover the same area at the same pixel.

    Parameters
    ----------
    maps : ``(heights [nm], (Lx, Ly) [nm])`` per scan, heights of shape ``(nx, ny)``

    Returns
    -------
    (numpy.ndarray, (float, float))
        The summed heights [nm] on the first map's grid and that map's sizes ``(Lx, Ly)`` [nm].

    Raises
    ------
    ValueError
        For no map.

    References
    ----------
    [PK99], [SK97], [PR16] (the FFT boundary-element solver, ContactMechanics), [Hyun04];
    docs/deterministic_interface.md.
    """
    if not maps:
        raise ValueError("combine_maps: expected at least one height map")
    h0, sizes = maps[0]
    total = np.array(h0, float)
    nx, ny = total.shape
    x = (np.arange(nx) + 0.5) * sizes[0] / nx
    y = (np.arange(ny) + 0.5) * sizes[1] / ny
    X, Y = np.meshgrid(x, y, indexing="ij")
    from scipy.ndimage import map_coordinates
    for h, (lx, ly) in maps[1:]:
        h = np.asarray(h, float)
        i = X / (lx / h.shape[0]) - 0.5  # fractional pixel index of each target point
        j = Y / (ly / h.shape[1]) - 0.5
        total += map_coordinates(h, [i, j], order=1, mode="grid-wrap")
    return total - total.mean(), (float(sizes[0]), float(sizes[1]))


def _substrate(shape: tuple[int, int], sizes: tuple[float, float], periodic: bool):
    from ContactMechanics import FreeFFTElasticHalfSpace, PeriodicFFTElasticHalfSpace
    if periodic:
        return PeriodicFFTElasticHalfSpace(shape, 1.0, sizes, stiffness_q0=0.0)
    return FreeFFTElasticHalfSpace(shape, 1.0, sizes)


#: Largest number of conjugate-gradient iterations of one solve [1]. Converging solves of the bundled
#: scans take 20-330 at 256^2; a scan with a sudden plateau contact (spot_1-1000nm.ibw) can stall.
MAXITER = 2000


class ConvergenceError(RuntimeError):
    """The constrained conjugate gradients did not converge within the iteration limit."""


def _solve(substrate, heights: np.ndarray, sizes: tuple[float, float], *, pressure: float | None = None,
           offset: float | None = None, initial: np.ndarray | None = None, maxiter: int = MAXITER):
    """One constrained-CG solve [PK99] (E' = 1); returns the ContactMechanics result."""
    from ContactMechanics.Optimization import constrained_conjugate_gradients
    from SurfaceTopography import Topography
    topo = Topography(np.asarray(heights, float), sizes, periodic=True)
    area = sizes[0] * sizes[1]
    kw = {"maxiter": maxiter, "initial_displacements": initial}
    if pressure is not None:
        # force tolerance relative to the load: the solver's default is absolute
        kw.update(external_force=pressure * area, forcetol=1e-8 * pressure * area)
    else:
        kw.update(offset=offset)
    res = constrained_conjugate_gradients(substrate, topo, **kw)
    if not res.success:
        raise ConvergenceError(f"deterministic contact: the constrained conjugate gradients did not converge "
                           f"({res.message}; {res.nit} iterations)")
    return res


def contact_at_load(heights: np.ndarray, physical_sizes: tuple[float, float], pressure: float
                    ) -> dict[str, float]:
    """Periodic contact of a rigid rough map against an elastic flat at one mean pressure.

    Parameters
    ----------
    heights : 2-D map [nm] (any mean)
    physical_sizes : ``(Lx, Ly)`` [nm]
    pressure : mean pressure per nominal area [units of E']

    Returns
    -------
    dict with ``mean_gap`` [nm] (from the map's mean plane), ``area_fraction`` [1], ``pressure``
    [units of E'] (the solved total force over the nominal area) and ``iterations``.

    References
    ----------
    [PK99], [SK97], [PR16] (the FFT boundary-element solver, ContactMechanics), [Hyun04];
    docs/deterministic_interface.md.
    """
    h = np.asarray(heights, float)
    sub = _substrate(h.shape, physical_sizes, True)
    res = _solve(sub, h, physical_sizes, pressure=pressure)
    return _state(res, h, physical_sizes)


def _state(res, h: np.ndarray, sizes: tuple[float, float]) -> dict[str, float]:
    f = np.asarray(res.jac)
    # mean displacement of the elastic surface is zero (stiffness_q0 = 0): <gap> = -(offset + <h>)
    return {"mean_gap": float(-(res.offset + h.mean())), "area_fraction": float(np.mean(f > 0)),
            "pressure": float(f.sum() / (sizes[0] * sizes[1])), "iterations": int(res.nit)}


def contact_series(heights: np.ndarray, physical_sizes: tuple[float, float], *, points: int = 20,
                   area_range: tuple[float, float] = AREA_RANGE) -> ContactSeries:
    """Contact of a rough map against a flat at ``points`` loads spanning ``area_range`` of real area.

    The loads are log-spaced so that the expected real-area fractions ``KAPPA p / h'_rms`` [Hyun04]
    span ``area_range`` (the actual fractions are what the solver finds); the lowest is raised to at
    least a few pixels in contact. Each solve starts from the previous displacements. A load whose
    solve does not converge within :data:`MAXITER` iterations is left out (``skipped``): the tables
    then interpolate across it.

    Parameters
    ----------
    heights : 2-D map [nm]; physical_sizes : ``(Lx, Ly)`` [nm]
    points : number of loads [1]; area_range : smallest and largest targeted area fraction [1]

    Returns
    -------
    ContactSeries
        The solved loads: mean gaps [nm], pressures [units of E'], area fractions [1], iterations [-].

    References
    ----------
    [PK99], [SK97], [PR16] (the FFT boundary-element solver, ContactMechanics), [Hyun04];
    docs/deterministic_interface.md.
    """
    h = np.asarray(heights, float)
    slope = rms_slope(h, physical_sizes)
    lo = max(area_range[0], 4.0 / h.size)
    targets = np.geomspace(lo, area_range[1], points)
    sub = _substrate(h.shape, physical_sizes, True)
    gap, p, a, it, skipped = [], [], [], [], []
    disp = None
    for target in targets:
        load = target * slope / KAPPA
        try:
            res = _solve(sub, h, physical_sizes, pressure=load, initial=disp)
        except ConvergenceError:  # leave the load out; the tables interpolate across it
            skipped.append(float(load))
            disp = None
            continue
        disp = np.asarray(res.x).copy()
        s = _state(res, h, physical_sizes)
        gap.append(s["mean_gap"]), p.append(s["pressure"]), a.append(s["area_fraction"]), it.append(s["iterations"])
    if len(gap) < 2:
        raise ConvergenceError(f"deterministic contact: only {len(gap)} of {points} loads converged within "
                               f"{MAXITER} iterations; no table can be made from them")
    dx, dy = (s_ / n for s_, n in zip(physical_sizes, h.shape))
    return ContactSeries(mean_gap=np.array(gap), pressure=np.array(p), area_fraction=np.array(a),
                         iterations=np.array(it), onset_gap=float(h.max() - h.mean()), grid=h.shape,
                         pixel_size=float(np.sqrt(dx * dy)), skipped=tuple(skipped))


def tabulate(series: ContactSeries, gap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pressure and real-area fraction of a series at mean separations ``gap`` [nm] (table grid).

    Monotone cubic (PCHIP) interpolation through the solved points and the first-contact point
    ``(onset_gap, 0)``; zero beyond first contact. Below the smallest solved separation (towards full
    contact, where the mean gap tends to zero and no state with a negative mean gap exists) the
    pressure continues linearly with the last solved stiffness and the area fraction linearly, capped
    at 1: the tables only have to stay monotone and finite there, which the dynamics needs.

    Parameters
    ----------
    series : the solved series; gap : mean separations from the mean plane [nm]

    Returns
    -------
    pressure [units of E'], area fraction [1], each of the shape of ``gap``

    References
    ----------
    [PK99], [SK97], [PR16] (the FFT boundary-element solver, ContactMechanics), [Hyun04];
    docs/deterministic_interface.md.
    """
    from scipy.interpolate import PchipInterpolator
    g = np.asarray(gap, float)
    order = np.argsort(series.mean_gap)
    x = np.append(series.mean_gap[order], series.onset_gap)
    keep = np.concatenate([np.diff(x) > 0, [True]])  # strictly increasing abscissae
    x = x[keep]
    out = []
    for y_solved, cap in ((series.pressure, np.inf), (series.area_fraction, 1.0)):
        y = np.append(y_solved[order], 0.0)[keep]
        f = PchipInterpolator(x, y, extrapolate=False)
        v = np.where(g >= x[-1], 0.0, f(np.clip(g, x[0], x[-1])))
        slope = (y[1] - y[0]) / (x[1] - x[0])  # < 0: more load at smaller separation
        v = np.where(g < x[0], y[0] + slope * (g - x[0]), v)
        out.append(np.clip(v, 0.0, cap))
    return out[0], out[1]


def hertz_check(radius: float, indentation: float, size: float, points: int) -> dict[str, float]:
    """Non-periodic contact of a rigid sphere (paraboloid) indenting an elastic flat (test helper).

    Parameters
    ----------
    radius : sphere radius [nm]; indentation : rigid-body approach below first contact [nm]
    size : side of the square domain [nm]; points : grid points per side

    Returns
    -------
    dict with ``load`` [units of E' nm^2] and ``contact_radius`` [nm] (from the contact area)

    References
    ----------
    [Johnson85] (the Hertz load and contact radius the solver must give); docs/deterministic_interface.md.
    """
    x = (np.arange(points) - points / 2 + 0.5) * size / points
    X, Y = np.meshgrid(x, x, indexing="ij")
    h = -(X**2 + Y**2) / (2 * radius)
    sizes = (float(size), float(size))
    sub = _substrate(h.shape, sizes, False)
    res = _solve(sub, h, sizes, offset=indentation - h.max())
    f = np.asarray(res.jac)[: points, : points]
    area = np.count_nonzero(f > 0) * (size / points) ** 2
    return {"load": float(f.sum()), "contact_radius": float(np.sqrt(area / np.pi))}
