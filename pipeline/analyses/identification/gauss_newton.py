"""The Gauss-Newton correlation at the optimum: the central-difference Jacobian, the correlation matrix and the
points it evaluates.
"""

from __future__ import annotations


import numpy as np

from .records import Identification


#: Central-difference step of the Gauss-Newton Jacobian, a fraction of each parameter's range [1].
GN_STEP = 0.02


# ----------------------------------------------------------------------------------- correlation
def residual_jacobian(ident: Identification, best: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The central-difference Jacobian of the residuals at ``best`` in parameters scaled to their
    bounds (one fan-out, role 3), shape (targets, parameters)."""
    gn_pts, plus, minus = _gauss_newton_points(best, lo, hi)
    _, _, r_gn = ident.evaluate(np.array(gn_pts), 3)
    return np.stack([(r_gn[2 * i] - r_gn[2 * i + 1]) / ((plus[i] - minus[i]) / (hi[i] - lo[i]))
                     for i in range(len(best))], axis=1)


def gn_correlation(J: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: the Gauss-Newton correlation matrix and standard deviations [parameter units] from ``J``."""
    n = len(lo)
    JTJ = J.T @ J
    w, V = np.linalg.eigh(JTJ)
    tiny = w <= max(w.max(), 0.0) * 1e-10
    C = (V[:, ~tiny] / w[~tiny]) @ V[:, ~tiny].T
    var_u = np.diag(C).copy()
    free = np.abs(V[:, tiny]).max(axis=1) > 1e-6 if tiny.any() else np.zeros(n, bool)
    var_u[free] = np.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = C / np.sqrt(np.outer(np.diag(C), np.diag(C)))
    corr[free, :] = np.nan
    corr[:, free] = np.nan
    return corr, np.sqrt(var_u) * (hi - lo)


def _gauss_newton_points(best: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[list, np.ndarray, np.ndarray]:
    """The central-difference points of the Jacobian at ``best`` (steps of :data:`GN_STEP` of each
    parameter's range, kept inside the bounds): ``(points, plus, minus)``."""
    h = GN_STEP * (hi - lo)
    plus = np.minimum(best + h, hi)
    minus = np.maximum(best - h, lo)
    points = []
    for i in range(len(best)):
        a, b = best.copy(), best.copy()
        a[i], b[i] = plus[i], minus[i]
        points += [a, b]
    return points, plus, minus
