"""Geometry of the TFC protrusion: an ellipsoidal bulge, its nominal contact area, how the interface
stresses are summed over it, and the lever arm of the friction force on the slider.

The bulge is half an ellipsoid with semi-axes ``a`` (sliding direction), ``b`` (across the track)
and height ``delta`` (the protrusion) (docs/model.md, section "Nominal area", [paper]). The nominal contact area is its
section by a plane a depth ``s_n`` above the lowest point.

Two named deviations from the paper (docs/model.md, section "Deviations", items 18 and 19):

* ``contact.area_model`` (:data:`AREA_MODELS`): ``"flat-section"``, the paper's, takes the stresses at
  the apex separation ``d`` times the flat ``A_n``; ``"integrated"`` sums the same stresses over the
  ellipsoid's own gap field (:func:`ellipsoid_force`, :func:`ellipsoid_table_integral`).
* ``slider.friction_arm`` (:data:`FRICTION_ARMS`): the friction force's moment arm about the CG,
  ``T/2`` (reacted through the CG, the default) or ``T`` (reacted at the gimbal on the slider's back).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .variants import Registry, Variant

#: The friction force's moment arm about the CG (scene key ``slider.friction_arm``): the behaviour is the
#: arm as a fraction of the slider thickness ``T`` [1]: ``"cg"`` the drag reacted through the CG, a height
#: ``T/2`` above the air-bearing surface (the default, a uniform block); ``"gimbal"`` reacted at the gimbal
#: dimple on the slider's back, ``T`` above it, as a head-gimbal assembly does.
FRICTION_ARMS: Registry[Variant] = Registry("slider.friction_arm", {
    "cg": Variant(behaviour=0.5, summary="T/2: the drag reacted through the CG (the paper's 2-DOF model)",
                  source='docs/model.md, section "Deviations", item 19'),
    "gimbal": Variant(behaviour=1.0, summary="T: the drag reacted at the gimbal on the slider's back",
                      source='docs/model.md, section "Deviations", item 19'),
})


def section_fraction(delta: np.ndarray, s_n: float) -> np.ndarray:
    """``u = s_n / delta`` capped at 1 [1] (``1`` when ``delta = 0``: the whole footprint).

    Parameters
    ----------
    delta : protrusion [m]
    s_n : section depth [m]

    Returns
    -------
    numpy.ndarray
        ``u`` [1], the shape of ``delta``.

    References
    ----------
    [VLP09] (the bulge as half an ellipsoid, 3 x 25 um, A_n = 62 um^2); docs/model.md, section "Nominal area".
    """
    delta = np.asarray(delta, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(delta > 0, np.minimum(s_n / np.where(delta > 0, delta, 1.0), 1.0), 1.0)


def nominal_area(delta: np.ndarray, a: float, b: float, s_n: float) -> np.ndarray:
    """Nominal contact area ``A_n = pi a b (2u - u^2)``, ``u = min(s_n/delta, 1)`` [m^2].

    Section of the ellipsoid ``(x/a)^2 + (y/b)^2 + ((h - delta)/delta)^2 = 1`` at height ``s_n``
    above its apex (docs/model.md, section "Nominal area"). The paper's 62 um^2 at ``delta = 11 nm`` follows for
    ``s_n = 1.56 nm``. For ``u -> 0`` it tends to the paraboloid value ``2 pi a b s_n / delta``.

    Parameters
    ----------
    delta : protrusion [m]
    a, b : semi-axes along and across the sliding direction [m]
    s_n : section depth [m]

    Returns
    -------
    numpy.ndarray
        The nominal area A_n [m^2], the shape of ``delta``.

    References
    ----------
    [VLP09] (the bulge as half an ellipsoid, 3 x 25 um, A_n = 62 um^2); docs/model.md, section "Nominal area".
    """
    u = section_fraction(delta, s_n)
    return np.pi * a * b * (2.0 * u - u * u)


def effective_radius(delta: np.ndarray, a: float, s_n: float) -> np.ndarray:
    """Radius of the circular arc through the apex and both ends of the section chord [m].

    The half-chord in the sliding direction is ``c = a sqrt(2u - u^2)`` at height
    ``h = min(s_n, delta)``; the arc through ``(0, 0)`` and ``(+-c, h)`` has radius
    ``(c^2 + h^2) / (2h)`` (docs/model.md, section "Nominal area"). As ``u -> 0`` it tends to the apex radius of
    curvature of the ellipse, ``a^2 / delta``. Infinite for ``delta = 0`` (a flat slider).

    Parameters
    ----------
    delta : protrusion [m]
    a : semi-axis along the sliding direction [m]
    s_n : section depth [m]

    Returns
    -------
    numpy.ndarray
        The effective radius [m] (``inf`` where ``delta = 0``), the shape of ``delta``.

    References
    ----------
    [VLP09] (the bulge as half an ellipsoid, 3 x 25 um, A_n = 62 um^2); docs/model.md, section "Nominal area".
    """
    delta = np.asarray(delta, dtype=float)
    u = section_fraction(delta, s_n)
    c2 = a * a * (2.0 * u - u * u)
    h = np.minimum(s_n, delta)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(h > 0, (c2 + h * h) / (2.0 * np.where(h > 0, h, 1.0)), np.inf)


def lowest_point_offset(delta: float, a: float, theta: float) -> tuple[float, float]:
    """Where the lowest point of a pitched bulge lies, relative to its apex.

    Pitching the slider by ``theta`` (trailing edge down positive) moves the lowest point of the
    ellipse ``x = a sin(phi)``, ``h = delta (1 - cos(phi))`` to where its slope equals ``theta``:
    ``tan(phi) = a theta / delta``. Exact for the ellipse; for sub-milliradian pitch the height
    change is ``~ -a^2 theta^2 / (2 delta)``, picometres for the paper's bulge (docs/model.md, section "Nominal area").

    Parameters
    ----------
    delta : protrusion [m] (> 0)
    a : semi-axis along sliding [m]
    theta : pitch angle [rad]

    Returns
    -------
    (x_shift [m], dz [m]) : shift of the lowest point along sliding, and its height change
        relative to the apex in the pitched frame (``<= 0``: the lowest point is lower).

    References
    ----------
    [VLP09] (the bulge as half an ellipsoid, 3 x 25 um, A_n = 62 um^2); docs/model.md, section "Nominal area".
    """
    if delta <= 0:
        return 0.0, 0.0
    phi = np.arctan(a * theta / delta)
    x = a * np.sin(phi)
    dz = delta * (1.0 - np.cos(phi)) - theta * x
    return float(x), float(dz)


def friction_arm(thickness: float, arm: str) -> float:
    """The friction force's moment arm about the CG [m] for a slider of thickness ``thickness`` [m]
    by the named rule ``arm`` (:data:`FRICTION_ARMS`: ``"cg"`` gives ``T/2``, ``"gimbal"`` ``T``).

    Raises
    ------
    ValueError
        For a rule not in :data:`FRICTION_ARMS` (the message lists them).

    Parameters
    ----------
    thickness : slider thickness T [m]
    arm : a name of :data:`FRICTION_ARMS`

    Returns
    -------
    float
        The moment arm [m].

    References
    ----------
    [VLP09] (the friction moment about the CG); docs/model.md, section "Slider dynamics".
    """
    return thickness * FRICTION_ARMS.lookup(arm).behaviour  # (x 0.5 is exact: the same bits as T / 2)


def ellipsoid_force(stress: Callable[[np.ndarray], np.ndarray], d: float, delta: float, a: float, b: float,
                    nodes: int = 200) -> float:
    """The force [N] of a stress law ``stress(gap [m]) -> [Pa]`` summed over the bulge's gap field, by
    Gauss-Legendre quadrature of the one-dimensional form (a reference for smooth laws; the model uses
    :func:`ellipsoid_table_integral`, exact for its piecewise-cubic tables).

    The bulge ``(x/a)^2 + (y/b)^2 + ((h - delta)/delta)^2 = 1`` lies ``h = delta (1 - sqrt(1 - r^2))``
    above its apex, ``r^2 = (x/a)^2 + (y/b)^2 <= 1``, so the gap over the point ``(x, y)`` of its
    footprint is ``d + h``. With ``x = a r cos(phi)``, ``y = b r sin(phi)`` (``dx dy = a b r dr dphi``)
    and ``u = 1 - sqrt(1 - r^2)`` (``r dr = (1 - u) du``)::

        F(d) = int int p(d + h) dx dy = 2 pi a b int_0^1 p(d + delta u) (1 - u) du

    (docs/model.md, section "Deviations", item 18). For ``delta -> 0`` it is ``pi a b p(d)``, the flat
    footprint; for a step law ``p = P0`` below ``d0`` it is ``P0`` times the section at depth ``d0 - d``,
    :func:`nominal_area`. The footprint only: the slider's flat face around the bulge (gap ``d + delta``)
    is outside it, as it is outside ``A_n``.

    Parameters
    ----------
    stress : the law, vectorised over gaps [m]
    d : apex separation [m]; delta : protrusion [m] (>= 0); a, b : semi-axes [m]
    nodes : Gauss-Legendre nodes on ``u`` in [0, 1]

    Returns
    -------
    float
        The force [N] over the bulge's footprint.

    References
    ----------
    docs/model.md, section "Deviations", item 18 (the bulge's gap field); [VLP09] (the ellipsoid).
    """
    if delta <= 0:
        return float(np.pi * a * b * np.asarray(stress(np.array([d])), float)[0])
    x, w = np.polynomial.legendre.leggauss(nodes)
    u = 0.5 * (x + 1.0)
    return float(2.0 * np.pi * a * b * 0.5 * np.sum(w * np.asarray(stress(d + delta * u), float) * (1.0 - u)))


def _piece_moments(c: np.ndarray, r: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """``(int_0^r q(s) ds, int_0^r q(s) s ds)`` of the cubics ``q(s) = c0 s^3 + c1 s^2 + c2 s + c3``
    (``c[:, 0]`` ... ``c[:, 3]``), exactly."""
    c0, c1, c2, c3 = c[:, 0], c[:, 1], c[:, 2], c[:, 3]
    m0 = r * (c3 + r * (c2 / 2 + r * (c1 / 3 + r * c0 / 4)))
    m1 = r * r * (c3 / 2 + r * (c2 / 3 + r * (c1 / 4 + r * c0 / 5)))
    return m0, m1


def ellipsoid_table_integral(c: np.ndarray, h: float, delta: float) -> np.ndarray:
    """``I(d_i) = int_0^1 p(d_i + delta u) (1 - u) du`` [unit of p] at every node ``d_i = x0 + i h`` of a
    piecewise-cubic table ``p``, exactly (the force over the bulge is ``2 pi a b I``, :func:`ellipsoid_force`).

    The table is the kernel's (:func:`pipeline.model.piecewise.piecewise_coefficients`: ``n`` rows
    ``c0..c3`` of ``p(x_k + s) = c0 s^3 + c1 s^2 + c2 s + c3`` on ``0 <= s <= h``). Since every ``d_i`` is
    a node, ``[d_i, d_i + delta]`` is whole pieces plus one partial piece of length
    ``delta - h floor(delta/h)``, and on each the integrand is a cubic times a linear weight: its
    integral is taken in closed form (no quadrature error), ``I = (1/delta) sum_k int p(x) (1 - (x - d_i)/delta) dx``.

    Beyond the table's top ``x_n`` nothing is added: rows with ``d_i + delta > x_n`` lose
    ``int_{u_top}^1 p (1 - u) du``, ``u_top = (x_n - d_i)/delta``, which under the kernel's own
    continuation (the last value held) is ``p(x_n) (1 - u_top)^2 / 2``
    (:func:`table_truncation`). Rows with ``d_i + delta <= x_n`` are exact.

    Parameters
    ----------
    c : table coefficients, shape ``(n, 4)`` (``n`` pieces, ``n + 1`` nodes), or ``(n, 4, q)`` for ``q``
        tables on one grid at once
    h : grid step [m]; delta : protrusion [m] (>= 0)

    Returns
    -------
    numpy.ndarray
        I [unit of p, e.g. Pa] at the ``n + 1`` nodes, shape ``(n + 1,)`` or ``(n + 1, q)`` (for ``delta = 0``
        the limit ``p(d_i) / 2``)

    References
    ----------
    docs/model.md, section "Deviations", item 18; :func:`ellipsoid_force` (the same integral by quadrature).
    """
    c = np.asarray(c, dtype=float)
    n = c.shape[0]
    top = ((c[-1, 0] * h + c[-1, 1]) * h + c[-1, 2]) * h + c[-1, 3]
    values = np.concatenate([c[:, 3], top[None, ...]])  # p at the nodes
    if delta <= 0:
        return values / 2.0
    m = int(np.floor(delta / h))
    r = delta - m * h
    if r < 0:  # (rounding of delta / h just above an integer)
        m, r = m - 1, r + h
    # per whole piece k: int_0^h q_k (1 - (j h + s)/delta) ds = (1 - j h/delta) M0_k - M1_k / delta
    M0, M1 = _piece_moments(c, h)
    P0, P1 = _piece_moments(c, r)
    pad = np.zeros((m + 1,) + c.shape[2:])  # (beyond the top: nothing, see the docstring)
    M0, M1 = np.concatenate([M0, pad]), np.concatenate([M1, pad])
    P0, P1 = np.concatenate([P0, pad]), np.concatenate([P1, pad])
    rows = np.arange(n + 1)
    total = np.zeros((n + 1,) + c.shape[2:])
    if m > 0:  # sliding sums over the m whole pieces from each row (np.correlate: one pass per table)
        weights, ones = 1.0 - h * np.arange(m) / delta, np.ones(m)
        M0, M1 = M0.reshape(M0.shape[0], -1), M1.reshape(M1.shape[0], -1)
        whole = np.stack([np.correlate(M0[:, j], weights, "valid")[: n + 1]
                          - np.correlate(M1[:, j], ones, "valid")[: n + 1] / delta for j in range(M0.shape[1])], axis=-1)
        total += whole.reshape(total.shape)
    # the partial piece k = i + m, from x_k over the length r
    total += (1.0 - m * h / delta) * P0[rows + m] - P1[rows + m] / delta
    return total / delta


def table_truncation(top_value: float, x: np.ndarray, delta: float) -> np.ndarray:
    """What :func:`ellipsoid_table_integral` leaves out at the nodes ``x`` [m] of a table whose last value
    is ``top_value`` [unit of p], were the table held at that value beyond its top (the kernel's
    continuation): ``top_value (1 - u_top)^2 / 2``, ``u_top = min(1, (x_n - x)/delta)`` (0 where
    ``x + delta <= x_n``). A bound of what is left out when ``|p|`` does not grow beyond the top.

    Parameters
    ----------
    top_value : the table's last value [unit of p, e.g. Pa]
    x : the table's nodes [m], increasing (``x[-1]`` its top)
    delta : protrusion [m]

    Returns
    -------
    numpy.ndarray
        What is left out at each node [unit of p], the shape of ``x``.

    References
    ----------
    docs/model.md, section "Deviations", item 18.
    """
    x = np.asarray(x, dtype=float)
    if delta <= 0:
        return np.zeros_like(x)
    u_top = np.clip((x[-1] - x) / delta, 0.0, 1.0)
    return top_value * (1.0 - u_top) ** 2 / 2.0


#: How the interface stresses become forces (scene key ``contact.area_model``): the behaviour is ``None``
#: (the stresses at the apex separation times the flat section ``A_n``, the model's own tables) or the
#: integral of the tables over the bulge's gap field, ``(coefficients, h, delta) -> integral`` as
#: :func:`ellipsoid_table_integral` (the model tabulates it per protrusion,
#: :func:`pipeline.model.kernel_inputs.interface_tables`).
AREA_MODELS: Registry[Variant] = Registry("contact.area_model", {
    "flat-section": Variant(summary="stresses at the apex separation d times the flat section A_n (the paper's)",
                            source='docs/model.md, section "Nominal area" [paper]'),
    "integrated": Variant(behaviour=ellipsoid_table_integral,
                          summary="the same stresses integrated over the ellipsoid's gap field "
                                  "d + delta (1 - sqrt(1 - r^2))",
                          source='docs/model.md, section "Deviations", item 18'),
})
