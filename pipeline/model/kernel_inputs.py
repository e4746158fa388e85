"""The kernel's inputs of a model at one protrusion: its parameter record, tables and variants
(:func:`run_parameters`), the interface tables by ``contact.area_model`` (:func:`interface_tables`) and
the tabulated TFC-point force (:func:`tfc_table`); and, before any model exists, the kernel's arguments of a
scene with stand-in numbers (:func:`stand_in_arguments`), whose types are the kernel's signature, so that a
first run starts compiling the kernel ahead at its very start (:func:`pipeline.model.ahead.compile_kernel_ahead`).

Caching rule (one for every cache here): a per-protrusion input is a pure function of its key (the
protrusion [m], with ``A_n`` [m^2] for the interface tables) and of the model's force laws; it is made
on the first ask and kept in a dict on the model (``Model.integrated``, ``Model.tfc_tables``), which
holds at most its size (:data:`INTEGRATED_CACHE`, :data:`TFC_CACHE`) of them, the oldest dropped first
(:func:`_cached`); an entry that depends on no protrusion (the capped real-area table) is never
dropped. A copy of the model with the same force laws may share the dict
(:mod:`pipeline.model.copies`); a copy with other laws gets its own.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import numpy as np

from . import dynamics as dyn
from .assembly import TFC_POINT_LAWS, Model
from .forces import rear_law_ref
from .piecewise import piecewise_coefficients, ppval
from .scene_inputs import needs_interface
from .state import N_STATE
from ..physics import tfc_laws
from ..physics.geometry import AREA_MODELS, nominal_area
from ..units import NM


#: How many entries the integrated interface tables' cache keeps (:func:`interface_tables`): a run asks
#: for its own protrusion several times (the kernel, the histories, the meniscus start), the static
#: start's continuation for many once each.
INTEGRATED_CACHE = 9  # (8 protrusions and the capped real-area table)

#: How many protrusions' tabulated TFC-point forces a model keeps (:func:`tfc_table`): the static starts'
#: continuation ladder (about 2 FH0 / 1 nm protrusions) and a batch's runs.
TFC_CACHE = 64


#: Entries of a cache that depend on no protrusion, never dropped (the module's caching rule).
PERMANENT = frozenset({"capped_area"})


def _cached(cache: dict, key: Any, size: int, make: Callable[[], Any]) -> Any:
    """The entry ``key`` of one of the model's caches, made by ``make()`` on the first ask; the oldest
    per-protrusion entries are dropped so that the cache holds at most ``size`` (the module's caching rule)."""
    found = cache.get(key)
    if found is None:
        found = make()
        while len(cache) >= size:
            try:  # (oldest first, never a PERMANENT entry; another thread may have removed it already)
                cache.pop(next(k for k in cache if k not in PERMANENT), None)
            except (StopIteration, RuntimeError):
                break
        cache[key] = found
    return found


def tfc_table(model: Model, protrusion: float) -> tuple[np.ndarray, float, float] | None:
    """The tabulated TFC-point force of the model at a protrusion [m]: piecewise-cubic coefficients
    (:func:`pipeline.model.piecewise.piecewise_coefficients`, not-a-knot spline) of the sum of the laws of
    ``model.tfc_tabulated`` [N] on a uniform gap grid, its first gap [m] and step [m]; ``None`` without.

    The kernel takes the force and its stiffness ``-dF/dg`` from the same cubic (linear continuation
    below the grid, constant above). The grid spans the laws' ``gap_range`` times ``FH0`` with their
    largest ``points``. Kept in ``model.tfc_tables`` (the module's caching rule, :data:`TFC_CACHE`).
    """
    laws = model.tfc_tabulated
    if not laws:
        return None
    key = float(protrusion)
    return _cached(model.tfc_tables, key, TFC_CACHE, lambda: _tfc_table(laws, model.p.FH0, key))


def _tfc_table(laws: tuple[tfc_laws.TfcLaw, ...], fh0: float, protrusion: float) -> tuple[np.ndarray, float, float]:
    """The table of :func:`tfc_table` made anew: the laws' summed force at ``protrusion`` [m] on their gap
    grid over the flying height ``fh0`` [m]."""
    g = np.linspace(min(law.gap_range[0] for law in laws) * fh0, max(law.gap_range[1] for law in laws) * fh0,
                    max(law.points for law in laws))
    force = sum(np.asarray(law.force(g, protrusion), dtype=float) for law in laws)
    h = float(g[1] - g[0])
    return piecewise_coefficients(force, h, 3), float(g[0]), h


def run_parameters(model: Model, protrusion: float) -> tuple[np.record, dyn.Tables, dyn.Variants]:
    """The kernel's parameters, tables and variants for the model at ``protrusion`` [m]."""
    p = dyn.with_values(model.p, delta=protrusion, A_n=_nominal_area(model, protrusion), k_sigma=model.k_sigma,
                        t_win=model.transient)
    tables, variants = kernel_slots(model, p)
    return p, tables, variants


def _nominal_area(model: Model, protrusion: float) -> float:
    """The model's nominal area ``A_n`` [m^2] at ``protrusion`` [m] (0 without a section depth)."""
    return float(nominal_area(protrusion, model.half_length, model.half_width, model.section_depth)) \
        if np.isfinite(model.section_depth) else 0.0


#: The frictional heat's protrusion grid (:func:`heat_grid`): its step [m] and the span above the heater's
#: protrusion it covers at least [m] (the band scene's heat reaches 4.1 nm at ``eta_f = 0.1``).
HEAT_STEP = 0.5 * NM
HEAT_SPAN = 5.0 * NM


def heat_grid(model: Model, protrusion: float, span: float = HEAT_SPAN) -> tuple:
    """The kernel's heat slot (``dynamics.Variants.heating``) of a heated run at the heater's ``protrusion``
    [m]: ``(eta_f V, tau_f, HEAT_STEP, A_n, tables)``, the nominal areas [m^2] and the TFC tables'
    coefficients (stacked, ``(n, pieces, 4)``; zeros ``(n, 1, 4)`` without a tabulated law) at ``protrusion + j
    HEAT_STEP``, ``j = 0 .. n - 1`` up to ``span`` [m] at least: the kernel reads them at ``delta + delta_f``
    linearly in between (:func:`pipeline.model.frictional_heating.heat_tables`; docs/model.md, section
    "Frictional heating"). The TFC tables' gap grid depends on ``FH0`` alone: one grid for all."""
    n = int(np.ceil(span / HEAT_STEP - 1e-9)) + 1
    mus = protrusion + HEAT_STEP * np.arange(n)
    areas = np.array([_nominal_area(model, mu) for mu in mus])
    tables = [tfc_table(model, float(mu)) for mu in mus]
    stack = np.zeros((n, 1, 4)) if tables[0] is None else np.stack([t[0] for t in tables])
    return _heat_slot(model.heating, areas, stack)


def _heat_slot(heating: tuple[float, float], areas: np.ndarray, tables: np.ndarray) -> tuple:
    """The kernel's heat slot of :func:`heat_grid` from its parts (the types the kernel's signature holds)."""
    return (float(heating[0]), float(heating[1]), HEAT_STEP, np.ascontiguousarray(areas, dtype=float),
            np.ascontiguousarray(tables, dtype=float))


class InterfaceTables(NamedTuple):
    """The interface tables of a model at one protrusion: piecewise cubics versus the separation on the
    grid ``p.tab_x0``, ``p.tab_h`` (``None``: effect off), each to be multiplied by ``A_n``: contact
    pressure, adhesion pressure, friction stress [Pa], real-area fraction [1]; ``area_cap``: the largest
    real area over ``A_n`` [1] (the histories clip the real area to it)."""

    contact: np.ndarray | None
    adhesion: np.ndarray | None
    friction: np.ndarray | None
    area: np.ndarray | None
    area_cap: float = 1.0


def interface_tables(model: Model, protrusion: float, nominal: float) -> InterfaceTables:
    """The interface tables the kernel and the histories use at ``protrusion`` [m], nominal area
    ``nominal`` [m^2] (the ``A_n`` they are multiplied by), by the model's ``contact.area_model``.

    ``"flat-section"`` (the paper's): the model's own tables, the stresses at the apex separation
    ``d`` (``A_n p(d)``), real area capped at ``A_n``. ``"integrated"``: per protrusion, the same stresses
    summed over the bulge's gap field, ``F(d) = 2 pi a b int_0^1 p(d + delta u) (1 - u) du``, tabulated
    at the table's nodes as ``F / A_n`` (exact integral of the tables' cubics,
    :func:`pipeline.physics.geometry.ellipsoid_table_integral`; nothing is taken beyond the table's top,
    :func:`pipeline.physics.geometry.table_truncation`) and splined as the tables are, so the kernel is
    unchanged; the local real-area fraction is capped at 1 before it is summed, so the real area is
    capped at the footprint ``pi a b`` (docs/model.md, section "Deviations", item 18). The last
    :data:`INTEGRATED_CACHE` protrusions' tables are kept on the model (the module's caching rule).
    """
    flat = InterfaceTables(model.contact, model.adhesion, model.friction, model.area)
    integral = AREA_MODELS.lookup(model.area_model).behaviour  # (None: the flat section)
    if integral is None:
        return flat
    key = (float(protrusion), float(nominal))
    return _cached(model.integrated, key, INTEGRATED_CACHE, lambda: _integrated_tables(model, flat, integral, *key))


def _integrated_tables(model: Model, flat: InterfaceTables, integral: Callable[..., np.ndarray], protrusion: float,
                       nominal: float) -> InterfaceTables:
    """The tables of :func:`interface_tables` summed over the bulge by the area model's ``integral``
    (:data:`pipeline.physics.geometry.AREA_MODELS`) at ``protrusion`` [m], over ``A_n = nominal`` [m^2]."""
    if not nominal > 0:
        raise ValueError(f"contact.area_model = {model.area_model!r} needs a nominal area > 0 (got {nominal} m^2)")
    h = float(model.p["tab_h"])
    order = model.scene["solver"]["interpolation_order"]
    scale = 2.0 * np.pi * model.half_length * model.half_width / nominal  # F / A_n = scale * I
    names = [n for n in InterfaceTables._fields[:4] if getattr(flat, n) is not None]
    if "area" in names and "capped_area" not in model.integrated:
        # a patch of the footprint has at most its own area in contact: the local fraction capped at 1
        c = flat.area
        nodes = np.append(c[:, 3], ppval(c, 0.0, h, np.array([c.shape[0] * h])))
        model.integrated["capped_area"] = c if not np.any(nodes > 1.0) else \
            piecewise_coefficients(np.minimum(nodes, 1.0), h, order)
    tables = [model.integrated["capped_area"] if n == "area" else getattr(flat, n) for n in names]
    # (two tables side by side, dynamics.Tables: the adhesion of the meniscus state, the continuous
    # friction; each integrated on its own)
    split = [n for n in names if getattr(flat, n).shape[1] == 8]
    for n in split:
        j = names.index(n)
        names[j:j + 1] = [n, n + "+"]
        tables[j:j + 1] = [getattr(flat, n)[:, :4], getattr(flat, n)[:, 4:]]
    # the tables at once (one grid): the integral, then the spline through its node values
    summed = scale * integral(np.stack(tables, axis=-1), h, protrusion)
    splines = _splines(summed, h, order)
    for n in split:
        j = names.index(n)
        del names[j + 1]
        splines[j:j + 2] = [np.ascontiguousarray(np.hstack(splines[j:j + 2]))]
    tabs = dict.fromkeys(InterfaceTables._fields[:4])
    tabs.update(zip(names, splines))
    # the whole footprint in contact: 2 pi a b int_0^1 (1 - u) du = pi a b
    return InterfaceTables(**tabs, area_cap=scale / 2.0)


def _splines(values: np.ndarray, h: float, order: int) -> list[np.ndarray]:
    """The piecewise-cubic coefficients of each column of ``values`` (nodes x tables) on a grid of step ``h``,
    as :func:`pipeline.model.piecewise.piecewise_coefficients` makes them (the not-a-knot spline of all the
    columns in one solve for ``order`` 3: a third of the cost of one solve per column)."""
    if order != 3:
        return [piecewise_coefficients(values[:, j], h, order) for j in range(values.shape[1])]
    from scipy.interpolate import CubicSpline  # (here: pipeline.model.ahead.NOT_IMPORTED_EARLY)
    c = CubicSpline(h * np.arange(values.shape[0]), values, axis=0).c  # (4, pieces, columns)
    return [np.ascontiguousarray(c[:, :, j].T) for j in range(values.shape[1])]


def kernel_slots(model: Model, p: np.record) -> tuple[dyn.Tables, dyn.Variants]:
    """The kernel's tables and variants for the model at the protrusion ``p.delta`` [m]; sets the
    tabulated TFC-point law's grid in ``p`` (``None`` slots: effects off)."""
    gap_power = None
    delta = p["delta"]
    if model.tfc_stiffening is not None:  # the stiffening force is zero at this protrusion's nominal gap
        gp = model.tfc_stiffening
        gap_power = dyn.with_values(gp, f0=_stiffening_potential(p["FH0"] - delta, gp["g0"], gp["q"], gp["g_min"]))
    tfc = tfc_table(model, delta)
    if tfc is not None:
        tfc, p["tfc_x0"], p["tfc_h"] = tfc
    it = interface_tables(model, delta, p["A_n"])
    tables = dyn.Tables(dmw=model.dmw, contact=it.contact, adhesion=it.adhesion, friction=it.friction, tfc=tfc)
    # (the heat's slot with the one protrusion: the statics' and the start's; a run takes heat_grid's)
    heating = None if model.heating is None else \
        _heat_slot(model.heating, np.array([p["A_n"]]), np.zeros((1, 1, 4)) if tfc is None else tfc[None])
    variants = dyn.Variants(pitch=True if model.pitch is not None else None, rear_law=model.rear_law,
                            gap_power=gap_power, meniscus=model.meniscus, heating=heating)
    return tables, variants


def _stiffening_potential(g: float, g0: float, q: float, g_min: float) -> float:
    """``G(max(g, g_min))`` [m] of the stiffening law (:func:`pipeline.physics.tfc_laws.tfc_stiffening_force`)."""
    return tfc_laws.stiffening_potential(max(g, g_min), g0, q)


def stand_in_arguments(scene: Any) -> tuple[np.ndarray, dyn.Grid, np.record, dyn.Tables, dyn.Variants, dyn.Solver]:
    """The arguments of :func:`pipeline.model.dynamics.integrate` for a run of the scene's model, with stand-in
    numbers of the real arguments' types, from the scene's keys alone (no interface table, DMW record or
    bulge table yet).

    Their numba types are the kernel's signature (:func:`pipeline.model.dynamics.kernel_arguments`): which
    slots are ``None`` (the effects, :func:`kernel_slots`), the rear law (its compiled handle,
    :func:`pipeline.model.forces.rear_law_ref`), the meniscus state, the tables as C-contiguous 2-D float64
    arrays (what :func:`pipeline.model.piecewise.piecewise_coefficients` makes), the :data:`PARAMS
    <pipeline.model.dynamics.PARAMS>` and :data:`GAP_POWER <pipeline.model.dynamics.GAP_POWER>` records;
    none of the numbers. The rules mirror :func:`pipeline.model.assembly.build_model` and
    :func:`kernel_slots`; tests/model/test_kernel_inputs.py checks that the signature equals the one of the
    real model's first run for every shipped scene.
    """
    eff, si = scene.effects, scene.si
    cubic = np.zeros((1, 4))  # (one piece of a piecewise cubic; the real tables have the same type)
    interface = needs_interface(scene)  # (build_model reads interface tables only then)
    tables = {name: cubic if name in eff and interface else None for name in ("contact", "adhesion", "friction")}
    laws = [registry.lookup(scene["air_bearing"][key]) for key, registry in TFC_POINT_LAWS.items()]
    laws = [law for law in laws if law.force is not None]  # ("none": no law)
    meniscus = si.lubricant.meniscus_time if si.lubricant.meniscus_time > 0.0 else None
    heating = _heat_slot((1.0, 1.0), np.ones(1), np.zeros((1, 1, 4))) if si.tfc.frictional_heating > 0.0 else None
    tab = dyn.Tables(dmw=cubic if "dmw" in eff else None, tfc=cubic if any(law.closed_form is None for law in laws)
                     else None, **tables)
    var = dyn.Variants(pitch=True if "pitch" in eff else None, rear_law=rear_law_ref(si.air_bearing.rear_law),
                       gap_power=dyn.params(dyn.GAP_POWER) if any(law.closed_form == "gap-power" for law in laws)
                       else None, meniscus=meniscus, heating=heating)
    y0 = np.zeros(N_STATE)
    return y0, dyn.Grid(1.0, np.zeros(2)), dyn.params(), tab, var, dyn.Solver(1.0, y0.copy(), 1.0, 1)

