"""One in-memory API from a model to results: :func:`simulate` runs protrusions and returns a dataset.

Every caller that turns runs into data (the ``simulate`` stage, the sweep's batches, the parameter
studies' evaluations, the accuracy stage) calls :func:`simulate` instead of looping over
:func:`pipeline.model.running.run_model`, :func:`~pipeline.model.outcomes.histories` and
:func:`~pipeline.model.outcomes.summarize` and building its own dataset (the parameter studies' evaluations
call :func:`scalars`, the same numbers without the dataset). The variables are those of
:mod:`pipeline.variables` (steady-window scalars :data:`~pipeline.variables.SCALARS`, time histories
:data:`~pipeline.variables.HISTORIES`, the heater-stepping outputs :data:`~pipeline.variables.STEPPING`),
in dataset units.

Protocols (scene key ``sweep.protocol``, docs/model.md, section "Heater stepping"):

* ``"independent"``: each protrusion from its own start state (``solver.start``,
  :func:`pipeline.model.running.start`);
* ``"stepping"``: the protrusions form one *chain*, run in increasing order and then back down, each
  step from the end state (positions and velocities at the end of the run) of the step before, as the
  heater is stepped in the experiment; the first step starts by ``solver.start``. The top protrusion is
  run once and closes both passes. Each step replays the DMW record from its start, as an independent
  run does (the kernel's record is not periodic in time; only the slider's state carries over).
  Outputs per chain: the touchdown protrusion (first protrusion of the upward pass whose steady window
  touches, :func:`pipeline.model.outcomes.touched`), the take-off protrusion (first protrusion of the
  downward pass whose steady window no longer touches) and their difference, the hysteresis.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Sequence

import numpy as np
import xarray as xr

from ..config.grid import same_point
from ..config.scene import PROTOCOLS
from ..units import MS, NM
from ..variables import HISTORIES, RUN, RUN_GRID_COORDS, RUN_GRID_DIMS, SCALARS, STEPPING, TIME, coordinate, history, scalar
from . import assembly, outcomes, running
from .state import STEP_COUNTERS

#: The passes of a stepping chain (values of the ``direction`` coordinate).
DIRECTIONS = ("up", "down")

#: The integrator's counters of a run (``Run.info[STEP_COUNTERS]``: :mod:`pipeline.model.state`), kept with ``counters=True``.
COUNTERS = ("steps", "rejected_steps", "contact_switches")

#: The failures :func:`simulate` records as NaN with ``on_error="nan"`` (a failed integration, a
#: model that cannot run at a protrusion, a floating-point trap).
RUN_ERRORS = (running.IntegrationError, ValueError, FloatingPointError)


def simulate(model: assembly.Model, protrusions: Sequence[float], *, histories: Sequence[float] = (),
             protocol: str = "independent", counters: bool = False, on_error: str = "raise",
             timings: dict[str, float] | None = None, on_run: Callable[[], Any] | None = None) -> xr.Dataset:
    """Run the model at ``protrusions`` [nm] and return their steady-window scalars (and histories).

    Parameters
    ----------
    model : the assembled model (:func:`pipeline.model.assembly.build_model`)
    protrusions : TFC protrusions [nm]; with ``protocol="stepping"`` in increasing order
    histories : protrusions [nm] whose time histories are kept (those of ``protrusions`` that equal one
        of them to the grid tolerance, :func:`pipeline.config.grid.same_point`), as variables
        ``h_<name>`` on dims ``(hist_protrusion, time)`` (the sweep part files' layout; :func:`histories_of`
        gives them the ``histories.nc`` layout); with stepping, those of the upward pass
    protocol : ``"independent"`` or ``"stepping"`` (module docstring)
    counters : keep the integrator's counters (:data:`COUNTERS`, dim ``protrusion``)
    on_error : ``"raise"`` (the first failed run raises) or ``"nan"`` (independent only: a failed
        protrusion's scalars are NaN, the regime its fill value; ``attrs["errors"]`` lists the
        failures as ``"<protrusion> nm: <message>"``, ``"; "``-separated)
    timings : when given, ``timings["kernel_seconds"]`` is increased by the wall time spent in
        :func:`pipeline.model.running.run_model` (kept out of the dataset: equal inputs, equal dataset)
    on_run : called after each run (a failed one too), :func:`run_count` times in all: the API counts
        them on its progress display (output only; the dataset does not depend on it)

    Returns
    -------
    xarray.Dataset
        Variables of :data:`pipeline.variables.SCALARS` on dim ``protrusion`` (and ``direction`` with
        stepping, plus :data:`pipeline.variables.STEPPING`'s chain outputs), in dataset units.
    """
    if protocol not in PROTOCOLS:
        raise ValueError(f"protocol {protocol!r}: expected one of {PROTOCOLS}")
    if on_error not in ("raise", "nan"):
        raise ValueError(f"on_error {on_error!r}: expected 'raise' or 'nan'")
    prot = np.asarray(protrusions, dtype=float)
    if protocol == "stepping":
        if on_error != "raise":
            raise ValueError("on_error = 'nan' is for independent runs (a chain needs every step's end state)")
        return _stepping(model, prot, histories, counters, timings, on_run)
    rows, info, kept, errors = _independent(model, prot, histories, on_error, timings, on_run)
    ds = xr.Dataset(_scalars(rows, ("protrusion",)), coords={"protrusion": coordinate("protrusion", prot)})
    if counters:
        for name, values in zip(COUNTERS, np.stack(info).T):
            ds[name] = HISTORIES[name].data(values, ("protrusion",))
    if kept:
        ds = ds.assign(_histories(kept)).assign_coords(_history_coords(kept))
    if errors:
        ds.attrs["errors"] = "; ".join(errors)
    return ds


def scalars(model: assembly.Model, protrusions: Sequence[float],
            timings: dict[str, float] | None = None) -> tuple[dict[str, np.ndarray], list[str]]:
    """The steady-window scalars of independent runs at ``protrusions`` [nm] as ``simulate(model, protrusions,
    on_error="nan", timings=timings)`` holds them, without the dataset (the parameter studies' path, one
    per (candidate, DMW record): docs/performance.md, section "The Python of a pair"): name -> the
    variable's values (dataset units and dtype, a failed protrusion's flags their fill value), and the
    failures as ``"<protrusion> nm: <message>"`` (the dataset's ``errors`` attribute, split)."""
    rows, _, _, errors = _independent(model, np.asarray(protrusions, dtype=float), (), "nan", timings, None)
    return {name: SCALARS[name].stored(SCALARS[name].scaled(values)) for name, values in _columns(rows).items()}, errors


def _independent(model: assembly.Model, prot: np.ndarray, histories: Sequence[float], on_error: str,
                 timings: dict[str, float] | None, on_run: Callable[[], Any] | None
                 ) -> tuple[list[dict[str, float] | None], list[np.ndarray], list[tuple[float, running.Run, dict]], list[str]]:
    """The independent runs of :func:`simulate` at ``prot`` [nm]: their steady-window scalars (SI; None: a
    failed run), counters, kept histories ``(protrusion [nm], run, histories)`` and failures."""
    rows: list[dict[str, float] | None] = []
    kept: list[tuple[float, running.Run, dict]] = []
    info: list[np.ndarray] = []
    errors: list[str] = []
    for delta in prot:
        keep = _kept(delta, histories)
        try:
            run, hist, row = _run(model, float(delta), None, timings, keep)
        except RUN_ERRORS as exc:
            if on_error == "raise":
                raise
            errors.append(f"{delta:g} nm: {exc}")
            rows.append(None)
            info.append(np.full(3, -1))
            if on_run is not None:
                on_run()
            continue
        if on_run is not None:
            on_run()
        rows.append(row)
        info.append(run.info[STEP_COUNTERS])
        if keep:
            kept.append((float(delta), run, hist))
    return rows, info, kept, errors


def histories_of(ds: xr.Dataset) -> xr.Dataset:
    """The time histories of a :func:`simulate` result as ``histories.nc`` holds them: variables named
    as :data:`pipeline.variables.HISTORIES` on dims ``(protrusion, time)``, with the integrator's
    counters when kept (the histories must be those of every protrusion)."""
    names = [n for n in ds.data_vars if n.startswith("h_")]
    hp = ds["hist_protrusion"].values
    data = {n[2:]: xr.Variable(("protrusion", TIME), ds[n].values, ds[n].attrs, ds[n].encoding)
            for n in names}
    for name in COUNTERS:
        if name in ds:
            data[name] = ds[name].variable
    return xr.Dataset(data, coords={"protrusion": coordinate("protrusion", hp), TIME: ds[TIME].variable})


def summary_of(ds: xr.Dataset) -> xr.Dataset:
    """The steady-window scalars of a :func:`simulate` result (``summary.nc``, a sweep's part)."""
    drop = [n for n in ds.data_vars if n.startswith("h_") or n in COUNTERS]
    return ds.drop_vars(drop).drop_dims([d for d in ("hist_protrusion", TIME) if d in ds.dims])


def _run(model: assembly.Model, delta_nm: float, y0: np.ndarray | None,
         timings: dict[str, float] | None, keep: bool = True) -> tuple[running.Run, dict | None, dict]:
    """One protrusion [nm]: its run, histories (``keep``; else None: the scalars from the steady window's
    alone, the same numbers) and steady-window scalars (SI)."""
    t0 = time.perf_counter()
    run = running.run_model(model, delta_nm * NM, y0=y0)
    if timings is not None:
        timings["kernel_seconds"] = timings.get("kernel_seconds", 0.0) + time.perf_counter() - t0
    hist = outcomes.histories(run) if keep else None
    return run, hist, outcomes.summarize(run, hist)


def _kept(delta: float, histories: Sequence[float]) -> bool:
    """Whether the histories of the protrusion ``delta`` [nm] are kept (the grid's point rule)."""
    return any(same_point(delta, h) for h in histories)


def _scalars(rows: list[dict[str, float] | None], dims: tuple[str, ...],
             shape: tuple[int, ...] | None = None) -> dict[str, xr.Variable]:
    """Scalar variables from per-protrusion summaries (SI; ``None``: a failed run, NaN)."""
    return {name: scalar(name, values if shape is None else values.reshape(shape), dims)
            for name, values in _columns(rows).items()}


def _columns(rows: list[dict[str, float] | None]) -> dict[str, np.ndarray]:
    """Per-protrusion summaries (SI; ``None``: a failed run) as one array per quantity, NaN where a
    summary lacks it, in the order the quantities first appear."""
    names: list[str] = []
    for r in rows:
        for name in r or ():
            if name not in names:
                names.append(name)
    return {name: np.array([r[name] if r is not None and name in r else np.nan for r in rows]) for name in names}


def _histories(kept: list[tuple[float, running.Run, dict]]) -> dict[str, xr.Variable]:
    return {"h_" + name: history(name, np.stack([k[2][name] for k in kept]), ("hist_protrusion", TIME))
            for name in kept[0][2] if name in HISTORIES}


def _history_coords(kept: list[tuple[float, running.Run, dict]]) -> dict[str, xr.Variable]:
    return {"hist_protrusion": coordinate("hist_protrusion", np.array([k[0] for k in kept])),
            TIME: coordinate(TIME, kept[0][1].time)}


def run_count(protocol: str, n: int) -> int:
    """Runs :func:`simulate` makes at ``n`` protrusions: ``n`` independent ones, or a stepping chain's
    ``2 n - 1`` (up, then down from the top without running the top twice)."""
    return max(2 * n - 1, 0) if protocol == "stepping" else n


def _stepping(model: assembly.Model, prot: np.ndarray, histories: Sequence[float], counters: bool,
              timings: dict[str, float] | None, on_run: Callable[[], Any] | None = None) -> xr.Dataset:
    """One heater-stepping chain over ``prot`` [nm] (module docstring; docs/model.md, section
    "Heater stepping")."""
    if prot.size == 0 or np.any(np.diff(prot) <= 0):
        raise ValueError(f"a stepping chain needs protrusions in increasing order, got {prot.tolist()}")
    n = prot.size
    rows: dict[str, list] = {d: [None] * n for d in DIRECTIONS}
    info = np.zeros((n, len(DIRECTIONS), len(COUNTERS)), dtype=np.int64)
    touch = np.zeros((n, len(DIRECTIONS)), dtype=bool)
    kept: list[tuple[float, running.Run, dict]] = []
    y0 = None  # the first step starts by solver.start
    order = [(i, 0) for i in range(n)] + [(i, 1) for i in range(n - 2, -1, -1)]
    for i, j in order:
        keep = j == 0 and _kept(prot[i], histories)
        run, hist, rows[DIRECTIONS[j]][i] = _run(model, float(prot[i]), y0, timings, keep)
        if on_run is not None:
            on_run()
        y0 = run.state[-1].copy()  # the end state: where the next heater step starts
        info[i, j] = run.info[STEP_COUNTERS]
        touch[i, j] = outcomes.touched(run)
        if keep:
            kept.append((float(prot[i]), run, hist))
    # the top of the chain closes both passes: its one run is the downward pass's first step
    rows["down"][n - 1], info[n - 1, 1], touch[n - 1, 1] = rows["up"][n - 1], info[n - 1, 0], touch[n - 1, 0]
    flat = [rows[d][i] for i in range(n) for d in DIRECTIONS]
    dims = ("protrusion", "direction")
    ds = xr.Dataset(_scalars(flat, dims, (n, len(DIRECTIONS))),
                    coords={"protrusion": coordinate("protrusion", prot),
                            "direction": coordinate("direction", np.array(DIRECTIONS))})
    if counters:
        for k, name in enumerate(COUNTERS):
            ds[name] = HISTORIES[name].data(info[:, :, k], dims)
    if "contact" in model.effects:
        td, to = chain_protrusions(prot, touch[:, 0], touch[:, 1])
        ds["touchdown_protrusion"] = STEPPING["touchdown_protrusion"].data(td, ())
        ds["takeoff_protrusion"] = STEPPING["takeoff_protrusion"].data(to, ())
        ds["hysteresis"] = STEPPING["hysteresis"].data(td - to, ())
    if kept:
        ds = ds.assign(_histories(kept)).assign_coords(_history_coords(kept))
    return ds


def chain_protrusions(protrusions: np.ndarray, touched_up: np.ndarray,
                      touched_down: np.ndarray) -> tuple[float, float]:
    """Touchdown and take-off protrusions [nm] of a stepping chain (docs/model.md, section "Heater stepping").

    ``protrusions`` [nm] increasing; ``touched_up``/``touched_down``: whether each protrusion's steady
    window touched (:func:`pipeline.model.outcomes.touched`) on the upward / downward pass. Touchdown: the
    first protrusion of the upward pass that touches (NaN if none); take-off: the first protrusion of
    the downward pass, from the top, that no longer touches (NaN when the top does not touch, or when
    the chain stays in contact down to its lowest protrusion).
    """
    up = np.flatnonzero(touched_up)
    td = float(protrusions[up[0]]) if up.size else np.nan
    to = np.nan
    if touched_down[-1]:
        free = np.flatnonzero(~np.asarray(touched_down)[::-1])
        if free.size:
            to = float(protrusions[len(protrusions) - 1 - free[0]])
    return td, to


def model_attrs(model: assembly.Model, k_source: str) -> dict[str, Any]:
    """Global attributes describing the assembled model (stiffness roots, damping, k)."""
    info = model.info
    extra: dict[str, Any] = {}
    if model.tfc_stiffening is not None:
        extra = {"tfc_stiffness_n_m": float(model.tfc_stiffening.k_t), "tfc_stiffening_exponent": float(model.tfc_stiffening.q)}
    if info["friction_law"] == "coefficient":
        extra["friction_coefficient"] = float(info["friction_coefficient"])
    return extra | {
        "k": model.k if np.isfinite(model.k) else "none",
        "k_source": k_source,
        "k_sigma_nm": model.k_sigma / NM,
        "front_stiffness_n_m": info["k_f"], "rear_stiffness_n_m": info["k_r"],
        "front_damper_n_s_m": info["c_f"], "rear_damper_n_s_m": info["c_r"],
        "stiffness_roots": str([{k: float(v) for k, v in r.items()} for r in info["roots"]]),
        "stiffness_root_chosen": info["chosen"],
        "stiffness_roots_note": "node_mode1/2: position ahead of the CG [m] that does not move in the "
                                "120/300 kHz modes; 'stiff-rear' takes k_r > k_f (docs/model.md, section 'Air bearing')",
        "rear_law": info["rear_law"],
        "tfc_stiffening": info["tfc_stiffening"],
        "friction_law": info["friction_law"],
        "summit_offset_y_s_nm": info["y_s"] / NM,
        "separation_datum": "d = FH0 - delta + z - l_c theta - w - y_s: to the mean of summit heights (docs/model.md, section 'Separation datum')",
        "damping_ratio": info["damping_ratio"],
        "steady_window": f"{model.transient / MS:g} ms to {model.duration / MS:g} ms",
        "fhm_measure": model.fhm_measure,
    }


def run_values(model: assembly.Model, k_source: str) -> dict[str, xr.Variable]:
    """The numbers of :func:`model_attrs` as the 0-d variables of :data:`pipeline.variables.RUN`
    (dataset units), so that datasets of several runs combine with each run's own values.

    ``k`` is NaN without a contact law (its attribute says ``"none"``); the TFC stiffening and the
    coefficient of the coefficient friction law are present only when the model has them.
    """
    info = model.info
    si = {"k": model.k if np.isfinite(model.k) else np.nan, "k_sigma": model.k_sigma,
          "front_stiffness": info["k_f"], "rear_stiffness": info["k_r"],
          "front_damper": info["c_f"], "rear_damper": info["c_r"], "damping_ratio": info["damping_ratio"],
          "summit_offset": info["y_s"], "steady_window_start": model.transient, "steady_window_end": model.duration}
    if model.tfc_stiffening is not None:
        si |= {"tfc_stiffness": model.tfc_stiffening.k_t, "tfc_stiffening_exponent": model.tfc_stiffening.q}
    if info["friction_law"] == "coefficient":
        si["friction_law_coefficient"] = info["friction_coefficient"]
    out = {name: RUN[name].from_si(float(v), ()) for name, v in si.items()}
    out["k_source"] = RUN["k_source"].data(np.array(k_source, dtype=object), ())
    return out


#: The global attributes of :func:`model_attrs` that hold a run value of :data:`pipeline.variables.RUN_GRID_DIMS`
#: (a grid with several values along its dimension has no one number for them: :func:`grid_run_values`).
GRID_ATTRS = {"k_sigma_nm": "k_sigma", "summit_offset_y_s_nm": "summit_offset", "front_damper_n_s_m": "front_damper",
              "rear_damper_n_s_m": "rear_damper", "damping_ratio": "damping_ratio"}


def grid_run_values(models: dict[tuple[str, float], assembly.Model], labels: Sequence[str], damping: Sequence[float],
                    k_source: str) -> dict[str, xr.Variable]:
    """The run values (:func:`run_values`) of a sweep's grid of models, one model per roughness set and
    damping ratio [1] (``models[(label, damping)]``): those of :data:`pipeline.variables.RUN_GRID_DIMS` along
    ``roughness`` or ``damping`` (in the order of ``labels`` and ``damping``), the others 0-d. Those of
    :data:`pipeline.variables.RUN_GRID_COORDS` are the grid's coordinate (the damping ratios themselves) and
    are left out.

    Raises
    ------
    ValueError
        When a value differs between models where its declaration says it cannot (a run value that
        depends on the grid but is not declared in ``RUN_GRID_DIMS``): the dataset would state one model's
        number for all.
    """
    values = {key: run_values(m, k_source) for key, m in models.items()}
    first = values[(labels[0], damping[0])]
    out: dict[str, xr.Variable] = {}
    for name, var in first.items():
        dim = RUN_GRID_DIMS.get(name)
        for (label, d), vals in values.items():  # every model agrees with the one the layout keeps
            kept = values[(label if dim == "roughness" else labels[0], d if dim == "damping" else damping[0])][name]
            if not np.array_equal(vals[name].values, kept.values, equal_nan=vals[name].dtype.kind == "f"):
                raise ValueError(f"run value {name!r} differs between the models of roughness {label!r}, damping "
                                 f"{d} and of the grid's first ({vals[name].values} != {kept.values}): declare it "
                                 "in pipeline.variables.RUN_GRID_DIMS")
        if dim is None:
            out[name] = var
            continue
        along = [values[(label, damping[0])] for label in labels] if dim == "roughness" \
            else [values[(labels[0], d)] for d in damping]
        series = np.array([float(v[name].values) for v in along])
        if name in RUN_GRID_COORDS:
            coord = np.asarray(labels if dim == "roughness" else damping, dtype=float)
            if not np.array_equal(series, coord):
                raise ValueError(f"run value {name!r} ({series}) is not the grid's {dim!r} coordinate ({coord})")
            continue
        out[name] = xr.Variable((dim,), series, attrs=var.attrs, encoding=var.encoding)
    return out
