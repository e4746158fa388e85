"""The air-bearing force laws at the TFC point: the gap-power stiffening spring ``k_t [(g0/g)^p - 1]``
(:func:`tfc_stiffening_force`, :func:`gap_power_force`, with the potential and stiffness the numba kernel compiles,
:func:`stiffening_potential`, :func:`stiffening_stiffness`), the shape of such a law's registry entry
(:class:`TfcLaw`) and the registry of ``air_bearing.tfc_stiffening`` (:data:`TFC_STIFFENING`; the bulge's own air
bearing, ``air_bearing.bulge``: :mod:`pipeline.physics.bulge_bearing`).

References
----------
docs/model.md, section "Gap-power stiffening" (Vakis, Hadjicostis & Polycarpou 2012, [VHP12]).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .variants import Entry, Registry


#: Gap below which the stiffening law is continued linearly, as a fraction of ``g0`` [1]: the law is
#: singular at zero gap (reached only in deep contact, where the contact force dominates).
TFC_MIN_GAP = 0.02


def stiffening_potential(s, g0: float, q: float):
    """``G(s) = g0^q s^(1-q) / (1-q) - s`` (``g0 ln s - s`` for ``q = 1``) [m] of the TFC stiffening law,
    gap ``s`` [m] (see :func:`tfc_stiffening_force`): ``-dG/ds`` is the stiffness over ``k_t``.

    Parameters
    ----------
    s : gap [m]
    g0 : reference gap [m] (FH0)
    q : exponent [1]

    Returns
    -------
    float or numpy.ndarray
        G(s) [m], the shape of ``s``.

    References
    ----------
    [VHP12] (the bearing's stiffening as the TFC clearance closes); docs/model.md, section "Gap-power stiffening".
    """
    return g0 * np.log(s) - s if q == 1.0 else g0**q * s ** (1.0 - q) / (1.0 - q) - s


def stiffening_stiffness(g, g0: float, k_t: float, q: float):
    """Added stiffness ``k_t [(g0/g)^q - 1]`` [N/m] of the TFC stiffening law at gap ``g`` [m] (docs/model.md, section "Gap-power stiffening").

    Parameters
    ----------
    g : gap at the TFC point [m]
    g0 : reference gap [m] (FH0)
    k_t : stiffness scale [N/m]
    q : exponent [1]

    Returns
    -------
    float or numpy.ndarray
        The added stiffness [N/m], the shape of ``g``.

    References
    ----------
    [VHP12] (the bearing's stiffening as the TFC clearance closes); docs/model.md, section "Gap-power stiffening".
    """
    return k_t * ((g0 / g) ** q - 1.0)


def tfc_stiffening_force(g: np.ndarray, g_n: float, g0: float, k_t: float, p: float) -> tuple[np.ndarray, np.ndarray]:
    """Force [N] (up positive) and stiffness [N/m] of the TFC stiffening spring at the TFC gap ``g`` [m].

    docs/model.md, section "Gap-power stiffening" (named option ``"gap-power"``, our form): as the TFC clearance closes the air
    pressure under the bulge rises and the local bearing stiffens (Vakis, Hadjicostis & Polycarpou,
    J. Phys. D 45 135402 (2012)). Added stiffness ``k(g) = k_t [(g0/g)^p - 1]`` with ``g0 = FH0``: zero at
    the nominal flying gap, so the modal stiffness of the bearing is unchanged there. The force is its
    integral from the nominal gap of the current protrusion ``g_n = FH0 - delta``,
    ``F = int_g^{g_n} k(s) ds = k_t [G(g_n) - G(g)]``, ``G(s) = g0^p s^(1-p) / (1-p) - s``
    (``g0 ln s - s`` for ``p = 1``): zero at the nominal attitude, so the static flying attitude
    (the paper's assumption) is unchanged. Below ``TFC_MIN_GAP g0`` it continues linearly.

    Parameters
    ----------
    g : gap at the TFC point to the mean of surface heights [m]
    g_n : nominal gap ``FH0 - delta`` [m]; g0 : reference gap ``FH0`` [m]
    k_t : stiffness scale [N/m]; p : exponent [1]

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The force [N] (up positive) and the stiffness [N/m], the shape of ``g``.

    References
    ----------
    [VHP12] (the bearing's stiffening as the TFC clearance closes); docs/model.md, section "Gap-power stiffening".
    """
    g = np.asarray(g, dtype=float)
    gm = TFC_MIN_GAP * g0

    def G(s):
        return stiffening_potential(np.maximum(s, gm), g0, p)

    k_min = stiffening_stiffness(gm, g0, k_t, p)
    F = k_t * (G(g_n) - G(g)) + np.where(g < gm, k_min * (gm - g), 0.0)
    k = np.where(g < gm, k_min, stiffening_stiffness(np.maximum(g, gm), g0, k_t, p))
    return F, k


def gap_power_force(g: np.ndarray, delta: float, g0: float, k_t: float, p: float) -> np.ndarray:
    """Force [N] of the ``"gap-power"`` stiffening law at the gaps ``g`` [m] for the protrusion ``delta`` [m]:
    :func:`tfc_stiffening_force` with the reference gap ``g0 = FH0`` [m], nominal gap ``FH0 - delta``,
    stiffness scale ``k_t`` [N/m] and exponent ``p`` [1].

    Parameters
    ----------
    g : gaps at the TFC point [m]
    delta : protrusion [m]
    g0 : reference gap FH0 [m]
    k_t : stiffness scale [N/m]
    p : exponent [1]

    Returns
    -------
    numpy.ndarray
        The force [N] (up positive), the shape of ``g``.

    References
    ----------
    [VHP12] (the bearing's stiffening as the TFC clearance closes); docs/model.md, section "Gap-power stiffening".
    """
    return tfc_stiffening_force(g, g0 - delta, g0, k_t, p)[0]


@dataclass(frozen=True)
class TfcLaw(Entry):
    """An air-bearing force law at the TFC point: its force and how the kernel evaluates it; a registry entry
    (:class:`pipeline.physics.variants.Entry`: ``summary``, ``source``, ``parameters``) that is its own behaviour.

    Attributes
    ----------
    force : ``force(g, delta, **parameters) -> F``: force [N] (up positive, the lift of the air on the slider)
        at the gaps ``g`` [m] (an array, gap at the TFC point to the mean of surface heights) for the
        protrusion ``delta`` [m], given the numbers named by ``parameters``; ``None``: no law (the
        option that leaves the model without one, ``"none"``)
    closed_form : name of the kernel's compiled closed form of the same law (``"gap-power"``:
        :func:`pipeline.model.forces._stiffening`), or ``None``: the model assembly tabulates ``force``
        per protrusion and the kernel evaluates the table (:func:`pipeline.model.kernel_inputs.tfc_table`)
    gap_range : lowest and highest gap of the table as fractions of ``FH0`` [1]: linear continuation
        below (the law's slope at the lowest gap), constant above
    points : knots of the table (uniform in the gap)
    table : name of the stage whose dataset the law reads (e.g. ``"bulge"``: a force solved once per
        scene and tabulated), or ``None``; such a law's ``force`` takes the table as the keyword
        ``table`` (the model assembly binds it, :func:`pipeline.model.assembly.build_model`)
    parameters : (an :class:`~pipeline.physics.variants.Entry` field) ``(keyword of force, "section.name")``
        pairs: the scene value in SI units (:func:`pipeline.config.si.to_si`, e.g.
        ``"air_bearing.flying_height"`` [m]) the model assembly passes as that keyword
        (:func:`pipeline.model.assembly.law_parameters`); the law reads no scene
    """

    force: Callable[..., np.ndarray] | None
    closed_form: str | None = None
    gap_range: tuple[float, float] = (TFC_MIN_GAP, 3.0)
    points: int = 4001
    table: str | None = None

    @property
    def behaviour(self) -> "TfcLaw":
        """The law itself (the model tabulates its ``force`` or runs its ``closed_form``)."""
        return self


#: The entry of an option that leaves the TFC-point law out (``"none"``: bit-identical to the model without it).
NO_TFC_LAW = TfcLaw(None, summary="no law: the model without it", source='docs/model.md, section "Model variants"')

#: Air-bearing force laws at the TFC point (``air_bearing.tfc_stiffening``): ``"none"`` = the model
#: without one. A new law: its ``force`` function in a physics module and one line here (``TfcLaw(force)``).
TFC_STIFFENING: Registry[TfcLaw] = Registry("air_bearing.tfc_stiffening", {
    "none": NO_TFC_LAW,
    "gap-power": TfcLaw(gap_power_force, closed_form="gap-power",
                        summary="k(g) = k_t [(g0/g)^p - 1], force zero at the nominal gap",
                        source='docs/model.md, section "Gap-power stiffening" (Vakis, Hadjicostis & Polycarpou 2012)',
                        parameters=(("g0", "air_bearing.flying_height"), ("k_t", "air_bearing.tfc_stiffness"),
                                    ("p", "air_bearing.tfc_stiffening_exponent"))),
})
