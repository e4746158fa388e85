"""Gas flow in a nanometre gap: the Boltzmann Poiseuille flow rate and the rough-gap flow factors.

Pure functions on numbers used by the rough bulge bearing (:func:`pipeline.physics.reynolds.reynolds_solve`
with ``slip="boltzmann"`` and a :class:`RoughGap`; docs/model.md, section "Rough-gap bulge bearing").

Poiseuille flow rate of molecular gas lubrication
-------------------------------------------------
Fukui & Kaneko solved the linearised Boltzmann (BGK) equation for the Poiseuille flow between two
parallel plates with diffuse reflection (J. Tribol. 110 (1988) 253) and published a database and a
closed-form fit of its flow-rate coefficient ``Q_P(D)`` (J. Tribol. 112 (1990) 78), with the inverse
Knudsen number ``D = sqrt(pi) / (2 Kn)``, ``Kn = lambda / h``. Its ratio to the continuum value
``Q_con = D / 6`` multiplies the Poiseuille term of the Reynolds equation:
``Q = Q_P(D) / Q_con(D) = 6 Q_P(D) / D`` (:func:`poiseuille_factor`). The fit (three pieces,
:data:`FK_FIT`) is continuous to 0.3 % at its joins (D = 0.15 and 5); the model blends the pieces over
+-5 % of D there (:func:`fk_flow_rate`). For large ``D`` it reads
``Q = 1 + 6 (2 x 1.0162 / sqrt(pi)) Kn + O(Kn^2) = 1 + 6 x 1.1466 Kn``: first-order slip with the
kinetic-theory slip coefficient 1.1466 instead of Burgdorfer's 1.

Rough-gap flow factors (average flow model)
-------------------------------------------
Patir & Cheng averaged the Reynolds equation over a Gaussian rough gap (J. Lubr. Technol. 100 (1978) 12,
pressure flow factor; 101 (1979) 220, shear flow factor). With ``h`` the nominal gap (between the mean
planes of the two surfaces), ``sigma`` the combined rms roughness and ``H = h / sigma``, the mean flow
per unit width along the sliding direction is

``q = - phi_x Q h^3 / (12 mu) dp/dx + U/2 (h_T + sigma phi_s)``

(the disk moves at ``U``, the slider is at rest) with, for isotropic roughness (Peklenik number 1):

* the mean local gap ``h_T = sigma [H Phi(H) + phi(H)]`` (``Phi``, ``phi``: normal CDF and density; the
  local gap is 0 where the surface heights overlap) (:func:`mean_gap`);
* the pressure flow factor ``phi_x = 1 - 0.90 exp(-0.56 H)``, fitted for ``H > 0.5`` (PC 1978, table 1,
  gamma = 1) (:func:`pressure_flow_factor`);
* the shear flow factor ``phi_s = (V_r1 - V_r2) Phi_s(H)``, ``Phi_s = 1.899 H^0.98 exp(-0.92 H + 0.05 H^2)``
  for ``H <= 5`` and ``1.126 exp(-0.25 H)`` above (PC 1979, table 2, gamma = 1), with ``V_r1``, ``V_r2``
  the shares of the variance of the moving (disk) and stationary (slider) surfaces
  (:func:`shear_flow_factor`). The roughness of the moving surface carries air in its valleys
  (``phi_s > 0``); that of the stationary one holds it back.

Validity: the fits are for ``H > 0.5`` (PC); the factors approach the smooth gap as ``H`` grows
(``phi_x -> 1`` like ``exp(-0.56 H)``: within 1 % of 1 above ``H = 8``; ``phi_s -> 0`` more slowly,
``0.006`` at ``H = 20``). Below ``H = 0.5`` the model continues them: ``phi_x`` falls linearly from
its value at 0.5 to 0 at ``H = 0``, the percolation limit of an isotropic Gaussian gap (half of the area
closed: by the symmetry of the height field the open and the closed parts percolate together), and
``Phi_s`` follows its fit, which vanishes like ``H^0.98`` there.

The gas film's share of the load
--------------------------------
Where the two surfaces touch or the lubricant bridges the gap, no air acts on the slider. The model takes
out of the film the area fraction whose local gap ``h - z`` (``z`` the combined height, Gaussian with
``sigma``) is below a wetting gap ``t_w`` (the lubricant thickness: in the ISBL model bridges form there,
docs/model.md, section "Two adhesion populations"): ``alpha = Phi((t_w - h) / sigma)``
(:func:`closed_fraction`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Fukui & Kaneko's (1990) fit of the Poiseuille flow-rate coefficient, ``Q_P = c0 D + c1 + c2/D + c3/D^2``
#: on ``D >= 5``, ``0.15 <= D < 5`` and ``D < 0.15`` (fitted down to 0.01): ``(lower bound of D, (c0, c1, c2, c3))``.
FK_FIT = ((5.0, (1.0 / 6.0, 1.0162, 1.0653, -2.1354)),
          (0.15, (0.13852, 1.25087, 0.15653, -0.00969)),
          (0.0, (-2.22919, 2.10673, 0.01653, -0.0000694)))

#: The kinetic-theory velocity-slip coefficient the fit carries at small Kn: ``Q = 1 + 6 SLIP_FK Kn + ...`` [1].
SLIP_FK = 2.0 * 1.0162 / np.sqrt(np.pi)

#: Patir & Cheng's isotropic constants: pressure flow factor ``(C, r)``; shear flow factor ``(A1, a1, a2, a3, A2)``.
PC_PRESSURE = (0.90, 0.56)
PC_SHEAR = (1.899, 0.98, 0.92, 0.05, 1.126)
#: Lower end of the fits' range ``H = h / sigma`` [1] (PC 1978, 1979).
PC_MIN_H = 0.5


#: Half-width in ``ln D`` of the blend of two neighbouring pieces of :data:`FK_FIT` at their join [1].
FK_BLEND = 0.05


def _fk_piece(D: np.ndarray, c: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    c0, c1, c2, c3 = c
    return c0 * D + c1 + c2 / D + c3 / D**2, c0 - c2 / D**2 - 2.0 * c3 / D**3


def fk_flow_rate(D) -> tuple[np.ndarray, np.ndarray]:
    """Fukui & Kaneko's Poiseuille flow-rate coefficient ``Q_P(D)`` [1] and ``dQ_P/dD`` at the inverse Knudsen
    numbers ``D = sqrt(pi) h / (2 lambda)`` (> 0): the fit :data:`FK_FIT` of their linearised-Boltzmann database.

    The fit's pieces differ by up to 0.3 % at their joins (D = 5 and 0.15); a jump would stall Newton's
    method, so within ``|ln(D / D_join)| < FK_BLEND`` the two pieces are blended with a cubic smoothstep
    weight in ``ln D`` (continuous value and slope; elsewhere the published pieces exactly).

    Parameters
    ----------
    D : inverse Knudsen numbers [1], > 0

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``Q_P`` [1] and ``dQ_P/dD`` [1], the shape of ``D``.

    References
    ----------
    [FK88] S. Fukui, R. Kaneko, J. Tribol. 110 (1988) 253-262; [FK90] J. Tribol. 112 (1990) 78-83 (the fit);
    docs/model.md, section "Rough-gap bulge bearing".
    """
    D = np.asarray(D, dtype=float)
    (j_hi, c_hi), (j_lo, c_mid), (_, c_lo) = FK_FIT
    pieces = [_fk_piece(D, c) for c in (c_hi, c_mid, c_lo)]
    Q, dQ = np.where(D >= j_hi, pieces[0][0], np.where(D >= j_lo, pieces[1][0], pieces[2][0])), \
        np.where(D >= j_hi, pieces[0][1], np.where(D >= j_lo, pieces[1][1], pieces[2][1]))
    for join, (qa, da), (qb, db) in ((j_hi, pieces[0], pieces[1]), (j_lo, pieces[1], pieces[2])):
        s = (np.log(D / join) + FK_BLEND) / (2.0 * FK_BLEND)  # 0 -> 1 across the join, upper piece at 1
        m = (s > 0.0) & (s < 1.0)
        if m.any():
            sm = s[m]
            w = sm * sm * (3.0 - 2.0 * sm)
            dw = 6.0 * sm * (1.0 - sm) / (2.0 * FK_BLEND * D[m])  # dw/dD
            Q[m] = w * qa[m] + (1.0 - w) * qb[m]
            dQ[m] = w * da[m] + (1.0 - w) * db[m] + dw * (qa[m] - qb[m])
    return Q, dQ


def poiseuille_factor(kn) -> tuple[np.ndarray, np.ndarray]:
    """The Boltzmann Poiseuille flow factor ``Q = 6 Q_P(D) / D`` [1] (flow rate over the continuum no-slip
    value) at the Knudsen numbers ``kn = lambda / h`` (> 0), and ``dQ/dKn``; ``D = sqrt(pi) / (2 Kn)``
    (Fukui & Kaneko 1988, 1990; module docstring).

    Parameters
    ----------
    kn : Knudsen numbers lambda / h [1], > 0

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``Q`` [1] and ``dQ/dKn`` [1], the shape of ``kn``.

    References
    ----------
    [FK88] S. Fukui, R. Kaneko, J. Tribol. 110 (1988) 253-262; [FK90] J. Tribol. 112 (1990) 78-83 (the fit);
    docs/model.md, section "Rough-gap bulge bearing".
    """
    kn = np.asarray(kn, dtype=float)
    D = 0.5 * np.sqrt(np.pi) / kn
    Qp, dQp = fk_flow_rate(D)
    q = 6.0 * Qp / D
    dq_dD = 6.0 * (dQp * D - Qp) / D**2
    return q, dq_dD * (-D / kn)


def mean_gap(H) -> np.ndarray:
    """Mean local gap ``h_T / sigma = H Phi(H) + phi(H)`` [1] of a Gaussian rough gap at ``H = h / sigma``
    (local gap ``max(h - z, 0)``, ``z`` Gaussian; Patir & Cheng 1978). ``-> H`` above ``H ~ 3``, ``0.399`` at 0.

    Parameters
    ----------
    H : nominal gap over the rms roughness, h / sigma [1]

    Returns
    -------
    numpy.ndarray
        The mean local gap over sigma, h_T / sigma [1], the shape of ``H``.

    References
    ----------
    [PC78] N. Patir, H. S. Cheng, J. Lubr. Technol. 100 (1978) 12-17; [PC79] (the shear flow factor);
    docs/model.md, section "Rough-gap bulge bearing".
    """
    from scipy.special import ndtr  # (here: the schema imports this module; model.ahead.NOT_IMPORTED_EARLY)
    H = np.asarray(H, dtype=float)
    return H * ndtr(H) + np.exp(-0.5 * H * H) / np.sqrt(2.0 * np.pi)


def pressure_flow_factor(H) -> np.ndarray:
    """Patir & Cheng's (1978) pressure flow factor ``phi_x = 1 - 0.90 exp(-0.56 H)`` [1] of isotropic roughness
    at ``H = h / sigma``, for ``H >= 0.5``; below, linear to 0 at ``H = 0`` (percolation, module docstring).

    Parameters
    ----------
    H : nominal gap over the rms roughness, h / sigma [1]

    Returns
    -------
    numpy.ndarray
        The pressure flow factor phi_x [1], the shape of ``H``.

    References
    ----------
    [PC78] N. Patir, H. S. Cheng, J. Lubr. Technol. 100 (1978) 12-17; [PC79] (the shear flow factor);
    docs/model.md, section "Rough-gap bulge bearing".
    """
    H = np.asarray(H, dtype=float)
    C, r = PC_PRESSURE
    fit = 1.0 - C * np.exp(-r * np.maximum(H, PC_MIN_H))
    return np.where(H >= PC_MIN_H, fit, fit * np.maximum(H, 0.0) / PC_MIN_H)


def shear_flow_factor(H, disk_share: float = 1.0) -> np.ndarray:
    """Patir & Cheng's (1979) shear flow factor ``phi_s = (V_r1 - V_r2) Phi_s(H)`` [1] of isotropic roughness at
    ``H = h / sigma`` (>= 0), ``V_r1 = disk_share`` the moving disk's share of the roughness variance,
    ``V_r2 = 1 - disk_share`` the slider's (module docstring).

    Parameters
    ----------
    H : nominal gap over the rms roughness, h / sigma [1]
    disk_share : the disk's share of the roughness variance V_r1 [1], in [0, 1]

    Returns
    -------
    numpy.ndarray
        The shear flow factor phi_s [1], the shape of ``H``.

    References
    ----------
    [PC79] N. Patir, H. S. Cheng, J. Lubr. Technol. 101 (1979) 220-229; docs/model.md, section "Rough-gap
    bulge bearing".
    """
    H = np.maximum(np.asarray(H, dtype=float), 0.0)
    A1, a1, a2, a3, A2 = PC_SHEAR
    Hl = np.minimum(H, 5.0)  # (the piece used up to 5; its exp would overflow at large H)
    low = A1 * Hl**a1 * np.exp(-a2 * Hl + a3 * Hl * Hl)
    high = A2 * np.exp(-0.25 * H)
    return (2.0 * disk_share - 1.0) * np.where(H <= 5.0, low, high)


def closed_fraction(h, sigma: float, wet_gap: float) -> np.ndarray:
    """Area fraction ``Phi((t_w - h) / sigma)`` [1] of a Gaussian rough gap whose local gap is below the wetting
    gap ``t_w = wet_gap`` [m] (solid or lubricant contact: no air there), at the nominal gaps ``h`` [m].

    Parameters
    ----------
    h : nominal gaps [m]
    sigma : rms roughness of the gap [m]
    wet_gap : the wetting gap t_w [m]

    Returns
    -------
    numpy.ndarray
        The closed area fraction alpha [1], the shape of ``h``.

    References
    ----------
    [PC78] N. Patir, H. S. Cheng, J. Lubr. Technol. 100 (1978) 12-17; [PC79] (the shear flow factor);
    docs/model.md, section "Rough-gap bulge bearing".
    """
    from scipy.special import ndtr  # (as in mean_gap)
    return ndtr((wet_gap - np.asarray(h, dtype=float)) / sigma)


@dataclass(frozen=True)
class RoughGap:
    """The roughness of a gas-bearing gap (Patir-Cheng average flow, module docstring).

    Attributes
    ----------
    sigma : combined rms roughness [m] (> 0)
    disk_share : the moving disk's share of the roughness variance ``V_r1`` [1] in [0.5, 1] (below 0.5
        the fitted ``phi_s`` would close the Couette gap ``h_T + sigma phi_s`` near ``H = 0.5``)
    wet_gap : gap below which the local gap holds no air [m] (>= 0; the lubricant thickness)
    """

    sigma: float
    disk_share: float = 1.0
    wet_gap: float = 0.0

    def __post_init__(self):
        if not self.sigma > 0 or not 0.5 <= self.disk_share <= 1.0 or not self.wet_gap >= 0:
            raise ValueError(f"RoughGap: expected sigma > 0 [m], disk_share in [0.5, 1], wet_gap >= 0 [m]; got "
                             f"{self.sigma}, {self.disk_share}, {self.wet_gap}")

    def couette_gap(self, h) -> np.ndarray:
        """``h_T + sigma phi_s`` [m]: the gap the moving disk fills at the nominal gaps ``h`` [m].

        Parameters
        ----------
        h : nominal gaps [m]

        Returns
        -------
        numpy.ndarray
            The Couette gap [m], the shape of ``h``.

        References
        ----------
        [PC78] N. Patir, H. S. Cheng, J. Lubr. Technol. 100 (1978) 12-17; [PC79] (the shear flow factor);
        docs/model.md, section "Rough-gap bulge bearing".
        """
        H = np.asarray(h, dtype=float) / self.sigma
        return self.sigma * (mean_gap(H) + shear_flow_factor(H, self.disk_share))

    def pressure_factor(self, h) -> np.ndarray:
        """``phi_x`` [1] at the nominal gaps ``h`` [m] (:func:`pressure_flow_factor`).

        Parameters
        ----------
        h : nominal gaps [m]

        Returns
        -------
        numpy.ndarray
            ``phi_x`` [1], the shape of ``h``.

        References
        ----------
        [PC78] N. Patir, H. S. Cheng, J. Lubr. Technol. 100 (1978) 12-17; [PC79] (the shear flow factor);
        docs/model.md, section "Rough-gap bulge bearing".
        """
        return pressure_flow_factor(np.asarray(h, dtype=float) / self.sigma)

    def air_fraction(self, h) -> np.ndarray:
        """``1 - alpha`` [1]: the area fraction where the air acts (:func:`closed_fraction`).

        Parameters
        ----------
        h : nominal gaps [m]

        Returns
        -------
        numpy.ndarray
            The air's area fraction [1], the shape of ``h``.

        References
        ----------
        [PC78] N. Patir, H. S. Cheng, J. Lubr. Technol. 100 (1978) 12-17; [PC79] (the shear flow factor);
        docs/model.md, section "Rough-gap bulge bearing".
        """
        return 1.0 - closed_fraction(h, self.sigma, self.wet_gap)
