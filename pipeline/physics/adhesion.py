"""Single-summit adhesion: Lennard-Jones surface law outside the lubricant, meniscus inside.

References
----------
.. [Israelachvili] J. N. Israelachvili, Intermolecular and Surface Forces, 3rd ed. (2011): the
   Lennard-Jones 3-9 surface interaction and the Derjaguin approximation.
.. [Stanley90] H. M. Stanley, I. Etsion, D. B. Bogy, "Adhesion of contacting rough surfaces in the
   presence of sub-boundary lubrication", J. Tribol. 112 (1990) 98-104 (the SBL model).
.. [CML] UC Berkeley Computer Mechanics Laboratory, flying-touchdown (ISBL) code documentation: the
   sub-boundary-lubrication adhesion tables used as the external check of docs/model.md, section "Adhesion".
"""

from __future__ import annotations

import numpy as np


def meniscus_force(R: float, dgamma: float) -> float:
    """Adhesive force of a summit wetted by the lubricant, ``2 pi R dgamma`` [N] [Stanley90].

    Parameters
    ----------
    R : summit radius [m]
    dgamma : work of adhesion [J/m^2]

    Returns
    -------
    float
        The meniscus force [N] (attractive, positive).

    References
    ----------
    [Stanley90] H. M. Stanley, I. Etsion, D. B. Bogy, J. Tribol. 112 (1990) 98-104 (module docstring;
    docs/model.md, section "Adhesion").
    """
    return 2.0 * np.pi * R * dgamma


def lennard_jones_force(s: np.ndarray, R: float, dgamma: float, eps: float) -> np.ndarray:
    """Attractive force [N] of a summit at gap ``s`` [m] (gap measured from the lubricant surface + eps).

    ``F = (8/3) pi dgamma R [(eps/s)^2 - (1/4)(eps/s)^8]`` (LJ 3-9 surface law with the Derjaguin
    approximation, [Israelachvili] ch. 13; form of [Stanley90]). At ``s = eps`` it equals the meniscus
    value ``2 pi R dgamma``: the two join continuously. For ``s < eps`` (not reached by the ISBL
    integrals) the gap is clamped to ``eps`` so the repulsive ``s^-8`` term can never overflow.

    Parameters
    ----------
    s : gap ``d - t - z + eps`` [m]
    R : summit radius [m]
    dgamma : work of adhesion [J/m^2]
    eps : intermolecular distance [m]

    Returns
    -------
    numpy.ndarray
        The force [N] at each gap (attractive, positive), the shape of ``s``.

    References
    ----------
    [Israelachvili] J. N. Israelachvili, Intermolecular and Surface Forces, 3rd ed. (2011), ch. 13;
    [Stanley90] (module docstring); docs/model.md, section "Adhesion".
    """
    r = eps / np.maximum(np.asarray(s, dtype=float), eps)
    r2 = r * r
    return 8.0 / 3.0 * np.pi * dgamma * R * (r2 - 0.25 * r2**4)
