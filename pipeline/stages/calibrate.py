"""Stage ``calibrate``: the contact-criterion constant k from the measured touchdown.

The paper's procedure (SPEC.md section 4): contact (``d < k sigma`` at any time of the steady
window) must happen at the measured touchdown protrusion (9.8 nm) and not at the previous
actuation step (9.6 nm). For a protrusion ``delta`` let ``k*(delta)`` be the smallest k that gives
contact; touching is monotone in k (a larger k switches contact on at a larger separation), so the
admissible set is the interval ``k*(onset) < k <= k*(previous)``.

Each ``k*`` is found by bisection on k (to ``touchdown.k_tolerance``), bracketed by the physically
meaningful range ``touchdown.k_range`` (default [-3, 3], contact probabilities 0.1 % to 99.9 %):
when the bracket's ends already agree (contact at both, or at neither), ``k*`` lies outside the
range and is reported as such. The chosen k is the middle of the admissible interval: it keeps
the largest margin to both conditions (the width is the uncertainty the 0.2 nm actuation step
leaves). When the interval is empty within the range, no k is written (``k_calibrated = NaN``)
and the outcome says why.

The contact probabilities of a k are ``P(|z| > k sigma) = 2 Q(|k|)`` (two-sided, the paper's
convention: SPEC.md 7.1) and ``P(z > k sigma) = Q(k)`` (one-sided) for Gaussian heights of rms
``sigma`` (the sigma of the criterion); the paper's calibrated k corresponds to 32.8 % two-sided,
k = 0.978.

``calibration.nc`` also holds the touchdown-versus-k curve: for each of ``touchdown.curve_points``
values of k in the range, the first protrusion of the ``[sweep]`` grid that touches (bisection over
the grid, touching being monotone in protrusion), NaN when none does.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .. import slider as sl
from ..io import is_current, var, write_dataset
from ..physics.statistics import contact_probabilities
from .simulate import model_inputs
from .sweep_grid import protrusion_grid

log = logging.getLogger(__name__)
NM = 1e-9


def touches(model: sl.Model, delta_nm: float, k: float) -> bool:
    """Whether the scene at protrusion ``delta_nm`` [nm] with criterion ``k`` is in contact in the window."""
    run = sl.run_model(replace(model, k=float(k)), delta_nm * NM)
    win = run.time >= model.transient - 1e-15
    return bool(run.contact[win].any())


def k_threshold(model: sl.Model, delta_nm: float, k_range: tuple[float, float], tol: float) -> tuple[float, str, int]:
    """Smallest k [1] giving contact at ``delta_nm``, by bisection within ``k_range``.

    Returns ``(k*, status, simulations)`` with status ``"found"``, ``"below range"`` (contact even at
    the lowest k: ``k*`` is below the range, returned as its lower end) or ``"above range"`` (no contact
    even at the highest k: returned as the upper end).
    """
    lo, hi = k_range
    n = 2
    if touches(model, delta_nm, lo):
        return lo, "below range", 1
    if not touches(model, delta_nm, hi):
        return hi, "above range", n
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        n += 1
        if touches(model, delta_nm, mid):
            hi = mid
        else:
            lo = mid
    return hi, "found", n


def touchdown_protrusion(model: sl.Model, k: float, grid_nm: np.ndarray) -> float:
    """First protrusion of ``grid_nm`` [nm] that touches with criterion ``k`` (NaN if none), by bisection."""
    if not touches(model, grid_nm[-1], k):
        return np.nan
    if touches(model, grid_nm[0], k):
        return float(grid_nm[0])
    lo, hi = 0, len(grid_nm) - 1  # lo never touches, hi touches
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if touches(model, grid_nm[mid], k):
            hi = mid
        else:
            lo = mid
    return float(grid_nm[hi])


def probabilities(k: float) -> tuple[float, float]:
    """One-sided ``Q(k)`` and two-sided ``2 Q(|k|)`` contact probabilities of criterion ``k`` [1]
    (:func:`pipeline.physics.statistics.contact_probabilities`, in this order)."""
    two, one = contact_probabilities(k)
    return one, two


def calibrate(scene: Any, out: Path, force: bool = False) -> xr.Dataset:
    """Run the calibration of a scene (no I/O of its own result); returns ``calibration.nc``'s dataset."""
    if not scene.has("contact"):
        raise ValueError("calibration needs the contact effect in scene.effects")
    interface, record = model_inputs(scene, out, force)
    td = scene["touchdown"]
    model = sl.build_model(scene, interface, record, k=0.0)
    k_range = tuple(td["k_range"])
    tol = td["k_tolerance"]
    k_on, st_on, n_on = k_threshold(model, td["onset_nm"], k_range, tol)
    k_prev, st_prev, n_prev = k_threshold(model, td["previous_nm"], k_range, tol)
    log.info("k*(%.2f nm) = %.4f (%s), k*(%.2f nm) = %.4f (%s)", td["onset_nm"], k_on, st_on,
             td["previous_nm"], k_prev, st_prev)
    onset, prev = td["onset_nm"], td["previous_nm"]
    if st_on == "found" and st_prev in ("found", "above range") and k_on < k_prev:
        k_low, k_high = k_on, k_prev
        k_cal = 0.5 * (k_low + k_high)
        outcome = (f"admissible k in ({k_low:.4f}, {k_high:.4f}]; chosen the middle, {k_cal:.4f}, for the largest "
                   f"margin to both conditions (contact at {onset} nm, none at {prev} nm)")
    else:
        k_low = k_high = k_cal = np.nan
        reasons = []
        if st_on == "below range":
            reasons.append(f"at {onset} nm contact happens for every k >= {k_range[0]}")
        if st_prev == "below range":
            reasons.append(f"at {prev} nm contact already happens for every k >= {k_range[0]}, so no k in range "
                           f"avoids contact at the previous step")
        if st_on == "above range":
            reasons.append(f"at {onset} nm no k <= {k_range[1]} gives contact")
        if st_on == "found" and st_prev == "found" and k_on >= k_prev:
            reasons.append(f"k*({onset}) = {k_on:.4f} >= k*({prev}) = {k_prev:.4f}: touching is not monotone "
                           "in protrusion here")
        outcome = "no admissible k in the range " + str(list(k_range)) + ": " + "; ".join(reasons)
    grid = protrusion_grid(scene)
    ks = np.linspace(k_range[0], k_range[1], td["curve_points"])
    curve = np.array([touchdown_protrusion(model, k, grid) for k in ks])
    finite = curve[np.isfinite(curve)]
    if finite.size == curve.size and np.ptp(finite) == 0:
        outcome += (f". The touchdown protrusion is {finite[0]:g} nm for every k in the range: contact does not "
                    "depend on the criterion here, the slider is pulled into contact (adhesive snap-in) before "
                    "the separation reaches any k sigma of the range")
    p1, p2 = probabilities(k_cal) if np.isfinite(k_cal) else (np.nan, np.nan)
    data = {
        "touchdown": var(curve, "k", "nm", "first protrusion of the sweep grid in contact"),
        "k_calibrated": var(k_cal, (), "1", "calibrated contact criterion constant k (NaN: none admissible)"),
        "k_low": var(k_low, (), "1", "lower (exclusive) end of the admissible k interval"),
        "k_high": var(k_high, (), "1", "upper (inclusive) end of the admissible k interval"),
        "k_onset": var(k_on, (), "1", f"smallest k giving contact at the touchdown protrusion ({st_on})"),
        "k_previous": var(k_prev, (), "1", f"smallest k giving contact at the previous step ({st_prev})"),
        "contact_probability_one_sided": var(p1, (), "1", "P(z > k sigma) of the calibrated k"),
        "contact_probability_two_sided": var(p2, (), "1", "P(|z| > k sigma) of the calibrated k"),
        "sigma": var(model.sigma / NM, (), "nm", "rms roughness of the criterion d < k sigma"),
    }
    ds = xr.Dataset(data, coords={"k": var(ks, "k", "1", "contact criterion constant")})
    ds.attrs.update({"outcome": outcome, "touchdown_onset_nm": onset, "touchdown_previous_nm": prev,
                     "k_range": str(list(k_range)), "k_tolerance": tol,
                     "simulations": n_on + n_prev,
                     "method": "bisection on k for each protrusion; touchdown curve by bisection over the grid",
                     "paper": "the paper's calibrated k corresponds to a 32.8 % two-sided contact probability (k = 0.978)"})
    return ds


def run(scene: Any, out: Path, force: bool = False, **options: Any) -> Path:
    """Write ``out/calibration.nc`` (see the module docstring) and say the outcome.

    Not recomputed when ``calibration.nc`` was made from the same scene (protrusion, sweep and
    report settings aside) and its inputs, unless ``force``.
    """
    out = Path(out)
    path = out / "calibration.nc"
    if not force and is_current(path, scene, "calibrate"):
        with xr.open_dataset(path, engine="netcdf4") as old:
            print(f"  calibration (up to date): {old.attrs.get('outcome', '')}")
        return path
    ds = calibrate(scene, out, force)
    print(f"  calibration: {ds.attrs['outcome']}")
    if np.isfinite(float(ds["k_calibrated"])):
        print(f"  k = {float(ds['k_calibrated']):.4f}; contact probability "
              f"{float(ds['contact_probability_two_sided']):.3f} (two-sided, the paper's convention), "
              f"{float(ds['contact_probability_one_sided']):.3f} (one-sided)")
    inputs = [p for p in (out / "interface.nc", out / "dmw.nc") if p.is_file()]
    return write_dataset(ds, out / "calibration.nc", scene, stage="calibrate", inputs=inputs)
