"""Feasibility of a parameter study's box: the model's own rules at the box's edges and corners, before sampling.

A study (``hdi identify``, ``hdi sensitivity``) varies scene keys within bounds. Where part of the box
lies outside what the model can evaluate, every evaluation there fails, and a screening over the box
has no indices (McCool's relations at ``roughness.summit_density_per_um2 = 5`` with the paper's sigma
and R: no summit-height variance). :func:`check_box` evaluates, before any evaluation, the rules a
candidate meets when it is built (:func:`problem`), each the model's own:

* the scene's validation and cross-checks (:func:`pipeline.analyses.free_parameters.with_values`, e.g. ``f1 < f2``);
* McCool's relations of explicit roughness statistics need the bandwidth ``alpha = 2412.74 (sigma eta
  R)^2 > 0.8968`` (:data:`pipeline.physics.asperity_statistics.ALPHA_MIN`; docs/model.md, section
  "Asperity statistics");
* the plasticity limits (:func:`pipeline.physics.material_bounds.check_materials`): the hardness derived
  from the plasticity index (or the index from the hardness) within the bounds of real solids and
  measured surfaces; a warning for one scene, a refusal for a study's box (its results may be meaningless),
  unless the scene itself is outside them (its box is then held to the other rules);
* the air bearing's modal inversion (:func:`pipeline.model.assembly.slider_from_scene`): a real stiffness
  pair of the two frequencies that the scene's root rule accepts, pad dampers >= 0;
* the contact criterion k without a calibration (:func:`pipeline.model.scene_inputs.contact_k`) and a
  ``[dmw]`` key only with a synthetic record (:func:`pipeline.candidates.candidate_inputs`).

Points (:func:`check_box`): the *reference* (each key's scene value when within its bounds, else the middle
of the bounds); each *bound alone* (the others at the reference), where a failure names the key, the bound
and the limit (bisection between the bound and the reference); the *corners* of each group of coupled
keys (the sections that enter one rule together: ``roughness`` + ``materials``, ``slider`` +
``air_bearing`` + ``tfc``; any other section alone), the others at the reference, where a failure names the
fewest bounds of the corner that fail together. Rules that involve keys of two groups are met at their
bounds alone only. A scene with AFM scans takes its statistics from the scans: its roughness keys enter no
rule, and the plasticity limits are checked by the interface stage on the scans' statistics.
"""

from __future__ import annotations

import itertools
import warnings
from typing import Any, Callable, Sequence

import numpy as np

from .free_parameters import Parameter, parse_parameters, scene_value, with_values
from ..config.schema import SceneError
from ..model import scene_inputs
from ..model.interface_tables import interface_parameters
from ..model.assembly import slider_from_scene
from ..physics.asperity_statistics import ALPHA_MIN, bandwidth_alpha, explicit_statistics
from ..physics.material_bounds import PhysicsWarning

#: Sections whose keys enter one rule together (their corners are checked jointly).
COUPLED = (("roughness", "materials"), ("slider", "air_bearing", "tfc"))
#: Largest group of keys whose 2^n corners are all checked; a larger group: the corners of each pair.
MAX_CORNER_KEYS = 8
#: Bisection of a limit: to this fraction of the distance between the bound and the reference.
LIMIT_TOLERANCE = 1e-4


def _where(scene: Any) -> str:
    return str(scene.path) if getattr(scene, "path", None) else "<scene>"


def _strip(message: str, where: str) -> str:
    """A scene error's message without its leading ``<file>: `` (the refusal names the file once)."""
    return message[len(where) + 2:] if message.startswith(where + ": ") else message


def problem(scene: Any, params: Sequence[Parameter], values: Sequence[float], plasticity: bool = True) -> str | None:
    """Why the candidate of ``scene`` with ``params`` at ``values`` cannot be evaluated (one line), or
    ``None`` when the model's rules (module docstring) accept it; ``plasticity=False`` leaves out the
    plasticity limits."""
    where = _where(scene)
    try:
        cand = with_values(scene, params, values)
    except SceneError as exc:
        return _strip(str(exc), where)
    r = cand["roughness"]
    if not r["afm"]:
        sr = cand.si.roughness
        sigma, R, eta = sr.sigma, sr.summit_radius, sr.summit_density
        alpha = bandwidth_alpha(sigma, eta, R)
        if not alpha > ALPHA_MIN:
            return (f"McCool's bandwidth alpha = {alpha:.3g} < {ALPHA_MIN} (sigma {r['sigma_nm']:g} nm, R "
                    f"{r['summit_radius_um']:g} um, eta {r['summit_density_per_um2']:g} um^-2): no summit-height "
                    "variance")
        try:
            stats = explicit_statistics(sigma, R, eta)
        except ValueError as exc:
            return str(exc)
        if plasticity and scene_inputs.needs_interface(cand):
            with warnings.catch_warnings():
                warnings.simplefilter("error", PhysicsWarning)
                try:
                    interface_parameters(cand, stats)
                except PhysicsWarning as exc:
                    return f"plasticity limits: {exc}"
                except ValueError as exc:
                    return str(exc)
    if cand.has("dmw") and cand["dmw"]["source"] != "synthetic" and any(p.parts[0] == "dmw" for p in params):
        return "a [dmw] key is a free parameter, but dmw.source is a measured record (used as measured)"
    try:
        slider_from_scene(cand)
        scene_inputs.contact_k(cand)
    except (SceneError, ValueError) as exc:
        return _strip(str(exc), where)
    return None


def reference(scene: Any, params: Sequence[Parameter]) -> np.ndarray:
    """Each key's value in ``scene`` when within its bounds, else the middle of its bounds."""
    out = []
    for p in params:
        v = scene_value(scene, p)
        out.append(v if np.isfinite(v) and p.low <= v <= p.high else 0.5 * (p.low + p.high))
    return np.asarray(out, float)


def groups(params: Sequence[Parameter]) -> list[list[int]]:
    """Indices of the parameters in each group of coupled sections (:data:`COUPLED`; others by section)."""
    out: dict[str, list[int]] = {}
    for i, p in enumerate(params):
        section = p.parts[0]
        name = next((" ".join(g) for g in COUPLED if section in g), section)
        out.setdefault(name, []).append(i)
    return list(out.values())


def _corners(idx: list[int]) -> list[tuple[tuple[int, int], ...]]:
    """Corners of the keys ``idx`` as tuples of (index, 0 low / 1 high); every pair's for a large group."""
    sets = [idx] if len(idx) <= MAX_CORNER_KEYS else [list(c) for c in itertools.combinations(idx, 2)]
    seen, out = set(), []
    for s in sets:
        for sides in itertools.product((0, 1), repeat=len(s)):
            corner = tuple(zip(s, sides))
            if len(s) > 1 and corner not in seen:
                seen.add(corner)
                out.append(corner)
    return out


def _limit(check: Callable[[np.ndarray], str | None], x: np.ndarray, j: int, bad: float, good: float) -> float:
    """The value of parameter ``j`` nearest ``bad`` at which ``check`` passes (bisection towards ``good``)."""
    tol = LIMIT_TOLERANCE * abs(good - bad)
    while abs(good - bad) > tol:
        mid = 0.5 * (bad + good)
        y = x.copy()
        y[j] = mid
        if check(y) is None:
            good = mid
        else:
            bad = mid
    return good


def check_box(scene: Any, params: Sequence[Parameter], field: str) -> None:
    """Refuse a box of ``params`` that the model cannot evaluate everywhere (module docstring).

    Parameters
    ----------
    scene : the base scene of the study
    params : the free parameters with their bounds
    field : the scene key of the bounds, for the message (``"sensitivity.parameters"``)

    Raises
    ------
    SceneError
        One line naming the scene file, ``field``, the key(s), the bound(s), the rule that fails there
        and, for a bound alone, the limit of the key where the rules pass.
    """
    where = _where(scene)
    ref = reference(scene, params)
    # a scene outside the plasticity limits itself runs with a warning (the interface stage's): its box is
    # held to the scene's other rules only, not refused for what the scene already does
    plastic = not (problem(scene, params, ref) or "").startswith("plasticity limits")

    def check(x: np.ndarray) -> str | None:
        return problem(scene, params, x, plastic)

    why = check(ref)
    if why is not None:
        at = ", ".join(f"{p.name} = {v:g}" for p, v in zip(params, ref))
        raise SceneError(f"{where}: {field}: the box's reference point ({at}) is infeasible: {why}")
    for j, p in enumerate(params):
        for side, bound in (("low", p.low), ("high", p.high)):
            x = ref.copy()
            x[j] = bound
            why = check(x)
            if why is not None:
                lim = _limit(check, ref, j, bound, ref[j])
                # (to the bisection's resolution: 7.415, not 7.415312; 0 where the limit is 0)
                digits = max(0, int(np.ceil(-np.log10(LIMIT_TOLERANCE * abs(ref[j] - bound)))))
                text = np.format_float_positional(round(lim, digits), trim="-")
                unit = "" if p.units == "1" else f" {p.units}"
                raise SceneError(f"{where}: {field}: {p.name} {side} bound {bound:g} is infeasible: {why}; feasible "
                                 f"{'from' if side == 'low' else 'up to'} about {text}{unit}")
    for g in groups(params):
        for corner in _corners(g):
            x = ref.copy()
            for j, s in corner:
                x[j] = (params[j].low, params[j].high)[s]
            why = check(x)
            if why is None:
                continue
            culprits = list(corner)
            for item in corner:  # the fewest bounds that fail together: give back each one that is not needed
                if len(culprits) == 1:
                    break
                y = x.copy()
                y[item[0]] = ref[item[0]]
                rest = check(y)
                if rest is not None:
                    x, why = y, rest
                    culprits.remove(item)
            names = ", ".join(f"{params[j].name} {('low', 'high')[s]} bound {x[j]:g}" for j, s in culprits)
            raise SceneError(f"{where}: {field}: the corner {names} is infeasible: {why}; narrow one of these bounds")


def check_study(scene: Any, section: str) -> None:
    """:func:`check_box` of the ``[section] parameters`` of ``scene`` (``"identify"``, ``"sensitivity"``)."""
    field = f"{section}.parameters"
    check_box(scene, parse_parameters(scene[section]["parameters"], _where(scene), field), field)


def box_check(section: str) -> Callable[[Any], None]:
    """The check of a study stage (:attr:`pipeline.runner.Stage.check`): :func:`check_study` of ``section``."""
    def check(scene: Any) -> None:
        check_study(scene, section)
    check.__doc__ = f"The box of [{section}] parameters: feasible at its bounds and corners (one-line refusal)."
    return check
