"""The slider's rigid body and its air bearing: mass properties, modal inversion, damping, rear law.

Two degrees of freedom: vertical displacement ``z`` of the centre of gravity (CG, up positive) and
pitch ``theta`` (positive: leading edge up, trailing edge down, so a point at ``x`` ahead of the CG
moves by ``z + x theta``). The front air bearing acts ``l_f`` ahead of the CG, the rear one ``l_r``
behind it (docs/model.md, section "Slider dynamics"). The laws at the TFC point (the gap-power stiffening):
:mod:`pipeline.physics.tfc_laws`.

References
----------
.. [Meirovitch] L. Meirovitch, Fundamentals of Vibrations (2001), ch. 7 (two-DOF modal analysis).
.. [Zeng01] Q. H. Zeng, D. B. Bogy, "A simplified 4-DOF suspension model for dynamic load/unload
   simulation and its application", J. Tribol. 122 (2000) 274-279 (lumped air-bearing springs).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .variants import Entry, Registry, Variant


@dataclass(frozen=True)
class Slider:
    """Rigid slider and air-bearing parameters (SI units).

    Attributes
    ----------
    m : mass [kg]; I : pitch inertia about the CG [kg m^2]
    l_f, l_r, l_c : arms of the front pad, rear pad, TFC point from the CG [m] (front ahead, others behind)
    friction_arm : the friction force's moment arm about the CG [m] (``slider.friction_arm``: the CG height
        over the air-bearing surface, or the slider's thickness; :func:`pipeline.physics.geometry.friction_arm`)
    k_f, k_r : front and rear bearing stiffness [N/m]; c_f, c_r : their dampers [N s/m]
    g0 : rear reference gap [m]; n : rear exponent [1]
    """

    m: float
    I: float
    l_f: float
    l_r: float
    l_c: float
    friction_arm: float
    k_f: float
    k_r: float
    c_f: float
    c_r: float
    g0: float
    n: float

    @property
    def mass_matrix(self) -> np.ndarray:
        """``M = diag(m, I)``: the mass matrix on ``(z, theta)``.

        Returns
        -------
        numpy.ndarray
            The 2 x 2 matrix ``[kg, 0; 0, kg m^2]``.

        References
        ----------
        docs/model.md, section "Slider dynamics" (the rigid slider's equations of motion ``m z'' = ...``,
        ``I theta'' = ...``).
        """
        return np.diag([self.m, self.I])

    @property
    def stiffness_matrix(self) -> np.ndarray:
        """Linearised stiffness ``K`` in coordinates ``(z, theta)`` (:func:`pad_matrix` of ``k_f``, ``k_r``).

        Returns
        -------
        numpy.ndarray
            The 2 x 2 matrix ``[N/m, N/rad; N, N m/rad]``.

        References
        ----------
        [ZB00] Q. H. Zeng, D. B. Bogy, J. Tribol. 122 (2000) 274-279 (lumped air-bearing springs); docs/model.md,
        sections "Slider dynamics" and "Air bearing".
        """
        return pad_matrix(self.k_f, self.k_r, self.l_f, self.l_r)

    @property
    def damping_matrix(self) -> np.ndarray:
        """Damping ``C`` of the two pad dampers in ``(z, theta)`` (:func:`pad_matrix` of ``c_f``, ``c_r``).

        Returns
        -------
        numpy.ndarray
            The 2 x 2 matrix ``[N s/m, N s/rad; N s, N m s/rad]``.

        References
        ----------
        [ZB00] Q. H. Zeng, D. B. Bogy, J. Tribol. 122 (2000) 274-279 (lumped air-bearing springs); docs/model.md,
        sections "Slider dynamics" and "Air bearing".
        """
        return pad_matrix(self.c_f, self.c_r, self.l_f, self.l_r)

    @property
    def rear_preload(self) -> float:
        """``F_r0 = k_r g0 / n``: the rear law's stiffness at ``g0`` equals ``k_r``.

        Returns
        -------
        float
            The rear law's preload ``F_r0`` [N].

        References
        ----------
        docs/model.md, section "Slider dynamics" (the rear law ``F_r = F_r0 [(g0/g)^n - 1]`` [recon]).
        """
        return self.k_r * self.g0 / self.n


def pad_matrix(a_f: float, a_r: float, l_f: float, l_r: float) -> np.ndarray:
    """``[[a_f + a_r, a_f l_f - a_r l_r], [., a_f l_f^2 + a_r l_r^2]]`` for pads at ``+l_f`` and ``-l_r``.

    Parameters
    ----------
    a_f, a_r : front and rear pad coefficients: stiffnesses [N/m] or dampers [N s/m]
    l_f, l_r : arms of the front pad ahead of and the rear pad behind the CG [m]

    Returns
    -------
    numpy.ndarray
        The 2 x 2 matrix on ``(z, theta)``: ``[N/m, N/rad; N, N m/rad]`` for stiffnesses (``N s/m``, ... for
        dampers).

    References
    ----------
    [Meirovitch] L. Meirovitch, Fundamentals of Vibrations (2001), ch. 7; [Zeng01]; docs/model.md, section
    "Air bearing".
    """
    return np.array([[a_f + a_r, a_f * l_f - a_r * l_r],
                     [a_f * l_f - a_r * l_r, a_f * l_f**2 + a_r * l_r**2]])


def mass_properties(length: float, width: float, thickness: float, density: float) -> tuple[float, float]:
    """Mass [kg] and pitch inertia about the CG [kg m^2] of a uniform block.

    ``m = rho L W T``, ``I = m (L^2 + T^2) / 12`` (pitch about the width axis). The paper's femto
    slider (0.85 x 0.70 x 0.23 mm, 4250 kg/m^3) gives 0.58 mg and 3.75e-14 kg m^2 (docs/model.md, section "Parameters").

    Parameters
    ----------
    length, width, thickness : the block's sides L, W, T [m]
    density : rho [kg/m^3]

    Returns
    -------
    (float, float)
        The mass m [kg] and the pitch inertia I [kg m^2].

    References
    ----------
    [VLP09] (the femto slider); docs/model.md, section "Parameters".
    """
    m = density * length * width * thickness
    return m, m * (length**2 + thickness**2) / 12.0


def stiffness_roots(f1: float, f2: float, m: float, I: float, l_f: float, l_r: float) -> list[tuple[float, float]]:
    """Both ``(k_f, k_r)`` pairs [N/m] giving the natural frequencies ``f1 < f2`` [Hz].

    From ``w1^2 w2^2 = k_f k_r (l_f + l_r)^2 / (m I)`` and
    ``w1^2 + w2^2 = k_f (1/m + l_f^2/I) + k_r (1/m + l_r^2/I)`` (docs/model.md, section "Slider dynamics"):
    ``b k_r^2 - S k_r + a P = 0``, with ``P = k_f k_r``. Returns the root with the larger rear
    stiffness first.

    Raises
    ------
    ValueError
        When no real positive pair exists (the frequencies are too far apart for this geometry).

    Parameters
    ----------
    f1, f2 : the natural frequencies [Hz], ``f1 < f2``
    m : slider mass [kg]; I : pitch inertia about the CG [kg m^2]
    l_f, l_r : front and rear pad arms about the CG [m]

    Returns
    -------
    list of (float, float)
        The ``(k_f, k_r)`` pairs [N/m], the larger rear stiffness first.

    References
    ----------
    [Meirovitch] L. Meirovitch, Fundamentals of Vibrations (2001), ch. 7; [Zeng01]; docs/model.md, section
    "Air bearing".
    """
    w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
    P = w1**2 * w2**2 * m * I / (l_f + l_r) ** 2
    S = w1**2 + w2**2
    a, b = 1 / m + l_f**2 / I, 1 / m + l_r**2 / I
    disc = S**2 - 4 * a * b * P
    if disc < 0:
        raise ValueError(f"no real air-bearing stiffness gives {f1:g} and {f2:g} Hz for this slider "
                         f"(discriminant {disc:.3g} < 0)")
    roots = []
    for sign in (+1, -1):
        k_r = (S + sign * np.sqrt(disc)) / (2 * b)
        roots.append((P / k_r, k_r))
    return roots


def modes(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Natural angular frequencies [rad/s] (ascending) and mass-normalised mode shapes (columns).

    Parameters
    ----------
    K : stiffness matrix on ``(z, theta)`` (:func:`pad_matrix`) [N/m, N/rad; N, N m/rad]
    M : mass matrix ``diag(m, I)`` [kg, kg m^2]

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The angular frequencies [rad/s], ascending, and the mass-normalised mode shapes (columns
        ``(z, theta)``) [kg^-1/2].

    References
    ----------
    [Meirovitch] L. Meirovitch, Fundamentals of Vibrations (2001), ch. 7; [Zeng01]; docs/model.md, section
    "Air bearing".
    """
    from scipy.linalg import eigh
    w2, phi = eigh(K, M)
    return np.sqrt(w2), phi


def node_position(shape: np.ndarray) -> float:
    """Position ahead of the CG [m] that does not move in a mode ``(z, theta)`` (``inf`` for pure bounce).

    Parameters
    ----------
    shape : a mode shape ``(z, theta)`` [m, rad]

    Returns
    -------
    float
        The node's position ahead of the CG [m] (``-z / theta``; ``inf`` where ``theta = 0``).

    References
    ----------
    [Meirovitch] L. Meirovitch, Fundamentals of Vibrations (2001), ch. 7; [Zeng01]; docs/model.md, section
    "Air bearing".
    """
    return -shape[0] / shape[1] if shape[1] != 0 else np.inf


def _stiff_rear(root: dict) -> bool:
    return root["k_r"] > root["k_f"]


def _pitch_first(root: dict) -> bool:
    return bool(root["mode1_pitch_like"])


def _bounce_first(root: dict) -> bool:
    return not root["mode1_pitch_like"]


#: Rules picking one root of the modal inversion (``air_bearing.stiffness_root``): the behaviour is a
#: predicate on the root's ``info`` entry (``k_f``, ``k_r`` [N/m], ``mode1_pitch_like``).
STIFFNESS_ROOTS: Registry[Variant] = Registry("air_bearing.stiffness_root", {
    "stiff-rear": Variant(behaviour=_stiff_rear,
                          summary="the root with k_r > k_f: the trailing pad the stiffest [recon]",
                          source='docs/model.md, section "Air bearing"'),
    "pitch-first": Variant(behaviour=_pitch_first, summary="the root whose lower mode is pitch-like (the first "
                                                           "reconstruction)",
                           source='docs/model.md, section "Slider dynamics"'),
    "bounce-first": Variant(behaviour=_bounce_first, summary="the root whose lower mode is bounce-like",
                            source='docs/model.md, section "Slider dynamics"'),
})


def choose_stiffness(f1: float, f2: float, m: float, I: float, l_f: float, l_r: float, length: float,
                     root: str = "stiff-rear") -> tuple[float, float, dict]:
    """Pick one ``(k_f, k_r)`` root of the modal inversion by a named rule (:data:`STIFFNESS_ROOTS`).

    ``"stiff-rear"`` (default, docs/model.md, section "Air bearing") takes the root with ``k_r > k_f``: the trailing pad of a
    femto slider is the stiffest part of its bearing (order ``n F / h ~ 0.01 N / 10 nm = 1e6 N/m``).
    A mode is *pitch-like* when its node (the point that does not move) lies on the slider,
    ``|x_node| < L/2``, and *bounce-like* otherwise; ``"pitch-first"`` (the first reconstruction,
    docs/model.md, section "Slider dynamics") takes the root whose lower mode is pitch-like, ``"bounce-first"`` the other.

    For the paper slider (m = 0.58 mg, I = 3.75e-14 kg m^2, l_f = 0.30 mm, l_r = 0.40 mm) at
    120/300 kHz the two roots and their mode shapes (node positions ahead of the CG) are:

    * stiff-rear: ``k_f = 1.54e5``, ``k_r = 5.83e5`` N/m; 120 kHz mode node at -0.459 mm (just behind
      the trailing edge at -0.425 mm: a bounce-like mode rocking about the trailing pad), 300 kHz
      mode node at +0.141 mm (pitch about a point between CG and leading pad);
    * pitch-first: ``k_f = 8.47e5``, ``k_r = 1.06e5`` N/m; 120 kHz node at +0.340 mm (pitch about the
      leading pad), 300 kHz node at -0.190 mm.

    Parameters
    ----------
    f1, f2 : the natural frequencies [Hz], ``f1 < f2``
    m : slider mass [kg]; I : pitch inertia about the CG [kg m^2]
    l_f, l_r : front and rear pad arms about the CG [m]
    length : slider length L [m] (a mode's node on the slider: pitch-like)
    root : the rule, a name of :data:`STIFFNESS_ROOTS`

    Returns
    -------
    k_f, k_r : float
        The front and rear pad stiffnesses [N/m].
    info : dict
        Both roots, their node positions [m], which one was taken and why.

    References
    ----------
    [Meirovitch] (two-DOF modal analysis), [Zeng01] (lumped air-bearing springs); docs/model.md, section "Air
    bearing".
    """
    rule = STIFFNESS_ROOTS.lookup(root).behaviour
    info: dict = {"roots": [], "chosen": None}
    chosen = None
    for k_f, k_r in stiffness_roots(f1, f2, m, I, l_f, l_r):
        w, phi = modes(pad_matrix(k_f, k_r, l_f, l_r), np.diag([m, I]))
        nodes = [node_position(phi[:, i]) for i in range(2)]
        first_pitch = abs(nodes[0]) < length / 2
        entry = {"k_f": k_f, "k_r": k_r, "node_mode1": nodes[0], "node_mode2": nodes[1],
                 "mode1_pitch_like": first_pitch}
        info["roots"].append(entry)
        if chosen is None and rule(entry):
            chosen = (k_f, k_r)
    if chosen is None:
        raise ValueError(f"no stiffness root of {f1:g}/{f2:g} Hz satisfies the {root!r} rule; roots: {info['roots']}")
    info["chosen"] = root
    return chosen[0], chosen[1], info


def pad_damping(k_f: float, k_r: float, m: float, I: float, l_f: float, l_r: float, zeta: float) -> tuple[float, float]:
    """Front and rear pad dampers [N s/m] that give both modes the damping ratio ``zeta``.

    Projecting the pad damping ``C(c_f, c_r)`` on the mass-normalised modes gives two linear
    equations ``phi_i^T C phi_i = 2 zeta w_i`` for ``(c_f, c_r)``. The small off-diagonal modal
    term that pad dampers also produce is kept (not a proportional damping); the exact damping
    ratios of the resulting system are reported by :func:`damping_ratios`.

    Parameters
    ----------
    k_f, k_r : pad stiffnesses [N/m]
    m : slider mass [kg]; I : pitch inertia [kg m^2]
    l_f, l_r : pad arms about the CG [m]
    zeta : the modal damping ratio [1]

    Returns
    -------
    (float, float)
        The front and rear dampers c_f, c_r [N s/m].

    References
    ----------
    [Meirovitch] L. Meirovitch, Fundamentals of Vibrations (2001), ch. 7; [Zeng01]; docs/model.md, section
    "Air bearing".
    """
    w, phi = modes(pad_matrix(k_f, k_r, l_f, l_r), np.diag([m, I]))
    A = np.empty((2, 2))
    for i in range(2):
        A[i, 0] = (phi[0, i] + l_f * phi[1, i]) ** 2
        A[i, 1] = (phi[0, i] - l_r * phi[1, i]) ** 2
    c = np.linalg.solve(A, 2 * zeta * w)
    if np.any(c < 0):
        raise ValueError(f"pad dampers for damping ratio {zeta} would be negative ({c}); "
                         "this geometry cannot damp both modes equally with two pads")
    return float(c[0]), float(c[1])


def damping_ratios(s: Slider) -> tuple[np.ndarray, np.ndarray]:
    """Exact (undamped) natural frequencies ``|lambda| / 2 pi`` [Hz] and damping ratios [1].

    From the eigenvalues ``lambda = -zeta w +- i w sqrt(1 - zeta^2)`` of the first-order system of
    the linearised slider; the damped frequencies are ``w sqrt(1 - zeta^2) / 2 pi``.

    Parameters
    ----------
    s : the slider (its mass, inertia, pad stiffnesses, dampers and arms, SI)

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The natural frequencies [Hz] and the damping ratios [1] of the two modes, ascending.

    References
    ----------
    [Meirovitch] L. Meirovitch, Fundamentals of Vibrations (2001), ch. 7; [Zeng01]; docs/model.md, section
    "Air bearing".
    """
    M, K, C = s.mass_matrix, s.stiffness_matrix, s.damping_matrix
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ K, -Minv @ C]])
    lam = np.linalg.eigvals(A)
    lam = lam[np.imag(lam) > 0] if np.any(np.imag(lam) > 0) else lam[:2]
    lam = lam[np.argsort(np.abs(lam))]
    wn = np.abs(lam)
    return wn / (2 * np.pi), -np.real(lam) / wn


# The laws below that take plain numbers (rear_power_law, rear_linear_law; the TFC point's stiffening_potential
# and stiffening_stiffness: tfc_laws) are the only definitions of these laws: the numba kernel
# (pipeline.model.forces) compiles these same functions, Python code calls them on floats or arrays.

def rear_power_law(g, g0: float, n: float, F0: float, k_r: float):
    """Power rear bearing force ``F0 [(g0/g)^n - 1]`` [N] on gap ``g`` [m] (docs/model.md, section "Slider dynamics", [recon]).

    The arguments of every rear law (:class:`RearLaw`); ``k_r`` is not used (this law's stiffness at
    ``g0`` is ``n F0 / g0``). ``n = 2`` squares rather than calling ``pow()``, the costliest call of the
    kernel's right-hand side.

    Parameters
    ----------
    g : rear gap [m]
    g0 : reference gap [m] (FH0)
    n : exponent [1]
    F0 : force scale [N]
    k_r : rear stiffness [N/m] (not used)

    Returns
    -------
    float or numpy.ndarray
        The rear force [N] (up positive), the shape of ``g``.

    References
    ----------
    [VLP09] (the 2-DOF slider on front and rear bearing springs); docs/model.md, section "Air bearing" ([recon]).
    """
    ratio = g0 / g
    law = ratio * ratio if n == 2.0 else ratio**n
    return F0 * (law - 1.0)


def rear_linear_law(g, g0: float, n: float, F0: float, k_r: float):
    """Linear rear bearing force ``k_r (g0 - g)`` [N] on gap ``g`` [m], stiffness ``k_r`` [N/m] (docs/model.md,
    section "Slider dynamics"); the arguments of every rear law (:class:`RearLaw`), ``n`` and ``F0`` not used.

    Parameters
    ----------
    g : rear gap [m]
    g0 : reference gap [m] (FH0)
    n, F0 : not used (the arguments of every rear law)
    k_r : rear stiffness [N/m]

    Returns
    -------
    float or numpy.ndarray
        The rear force [N] (up positive), the shape of ``g``.

    References
    ----------
    [VLP09] (the 2-DOF slider on front and rear bearing springs); docs/model.md, section "Air bearing" ([recon]).
    """
    return k_r * (g0 - g)


def rear_force(g: np.ndarray, g0: float, n: float, F0: float) -> np.ndarray:
    """Nonlinear rear bearing force [N] (positive: pushes the slider up) on gap ``g`` [m].

    ``F_r = F0 [(g0/g)^n - 1]`` (:func:`rear_power_law`); zero at ``g = g0``, stiffness ``n F0 / g0`` there.

    Parameters
    ----------
    g : rear gap [m]
    g0 : reference gap [m]
    n : exponent [1]
    F0 : force scale [N]

    Returns
    -------
    numpy.ndarray
        The rear force [N], the shape of ``g``.

    References
    ----------
    [VLP09] (the 2-DOF slider on front and rear bearing springs); docs/model.md, section "Air bearing" ([recon]).
    """
    return rear_power_law(np.asarray(g, dtype=float), g0, n, F0, n * F0 / g0)


def rear_force_linear(g: np.ndarray, g0: float, n: float, F0: float) -> np.ndarray:
    """Linear rear bearing force [N] ``F_r = k_r (g0 - g)`` with ``k_r = n F0 / g0`` [N/m] on gap ``g`` [m]:
    the tangent of :func:`rear_force` at ``g0`` (same modal stiffness, no nonlinearity).

    Parameters
    ----------
    g : rear gap [m]
    g0 : reference gap [m]
    n : exponent [1] of the power law whose tangent this is
    F0 : force scale [N] of that law

    Returns
    -------
    numpy.ndarray
        The rear force [N], the shape of ``g``.

    References
    ----------
    [VLP09] (the 2-DOF slider on front and rear bearing springs); docs/model.md, section "Air bearing" ([recon]).
    """
    return rear_linear_law(np.asarray(g, dtype=float), g0, n, F0, n * F0 / g0)


#: Rear gap below which the power law is evaluated at this gap instead, as a fraction of ``g0`` [1]:
#: the law is singular at zero gap (never reached in practice).
REAR_MIN_GAP = 1e-3


@dataclass(frozen=True)
class RearLaw(Entry):
    """A rear-bearing law (``air_bearing.rear_law``): a registry entry (:class:`pipeline.physics.variants.Entry`:
    ``summary``, ``source``) that is its own behaviour.

    Attributes
    ----------
    force : ``force(g, g0, n, F0, k_r) -> F`` [N] (up positive) at the rear gap ``g`` [m], from the rear
        pad's numbers: reference gap ``g0`` [m], exponent ``n`` [1], preload ``F0 = k_r g0 / n`` [N] and
        stiffness ``k_r`` [N/m] at ``g0``. The law's one definition and its compiled form: the kernel
        compiles it (numba's nopython mode: numbers, ``math`` and numpy functions only) and inlines it
        into its right-hand side (:func:`pipeline.model.forces.call_rear_law`); Python calls it on floats or
        arrays. A law whose ``force`` is ``None`` or does not compile is refused when a model is built
    min_gap : the kernel evaluates the law at ``max(g, min_gap g0)`` (a law singular at zero gap);
        ``None``: at ``g``
    """

    force: Callable[..., float] | None
    min_gap: float | None = None

    @property
    def behaviour(self) -> "RearLaw":
        """The law itself: the kernel compiles its ``force`` (:func:`pipeline.model.forces.rear_law_ref`)."""
        return self


#: Rear bearing laws (``air_bearing.rear_law``), docs/model.md, section "Slider dynamics".
REAR_LAWS: Registry[RearLaw] = Registry("air_bearing.rear_law", {
    "power": RearLaw(rear_power_law, REAR_MIN_GAP, summary="F_r = F_r0 [(g0/g)^n - 1], F_r0 = k_r g0 / n [recon]",
                     source='docs/model.md, section "Slider dynamics"'),
    "linear": RearLaw(rear_linear_law, summary="F_r = k_r (g0 - g)", source='docs/model.md, section "Slider dynamics"'),
})
