"""The outcome rules of a run: its time series (:func:`histories`, the paper's Figs 3-5), the
steady-window scalars of the sweep (:func:`summarize`), the regime and the touch rule (:func:`touched`).

Steady-window definitions (over ``transient_ms <= t <= duration_ms``, sampled every
``output_step_ns``):

* ``fhm_bv`` [%]: peak-to-peak of the separation ``d`` over ``FH0`` (or 3 std, ``solver.fhm_measure``);
  called FHM while flying and BV (bouncing vibration) in contact, as in the paper. The extremes
  are the exact ones tracked by the integrator, not those of the output samples.
* ``clearance``/``min_clearance`` [nm]: mean/minimum of ``c = d - k sigma`` (the minimum exact, as above).
* ``interference`` [nm]: mean of ``-c`` over the samples in contact (NaN if none).
* forces [mN]: time means over the window (zero while out of contact, but for the continuous lubricant
  shear of ``contact.friction_switching = "continuous"``); ``net_force`` is the
  vertical interface force on the slider, contact + contact damping - adhesion.
* ``friction_coefficient`` [1]: mean friction / mean contact force.
* ``mean_pressure``, ``shear_stress`` [MPa]: total contact / friction force over total real area,
  over the samples in contact; ``real_area`` [um2]: mean real area while in contact.
* ``contact_fraction`` [1]: fraction of the window's samples in contact.
* ``contact_switches_per_ms`` [1/ms]: transitions of the contact mode in the window per ms
  (:func:`contact_switch_rate`, counted by the kernel).
* ``regime``: 0 flying (no contact in the steady window, :func:`touched`), 2 surfing (steady
  sliding: in contact in at least 99 % of the samples), 1 bouncing (otherwise, including contacts
  shorter than the output step).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from .dmw_record import disk_speed_m_s
from .forces import separation_at
from .frictional_heating import heated_areas
from .kernel_inputs import HEAT_STEP, InterfaceTables, interface_tables
from .piecewise import disk_history, ppval
from .running import Run
from .state import MENISCUS, THETA, THETA_RATE, WINDOW_SWITCHES, Z, Z_RATE
from ..physics.fhm import fhm
from ..physics.flash_temperature import Thermal, contact_temperature
from ..physics.geometry import effective_radius
from ..validity import check_run
from ..variables import Regime


#: Regime codes (:class:`pipeline.variables.Regime`, the ``flag_values`` of the ``regime`` variable).
FLYING, BOUNCING, SURFING = Regime.FLYING, Regime.BOUNCING, Regime.SURFING
SURFING_FRACTION = 0.99


def histories(run: Run, steady: bool = False) -> dict[str, np.ndarray]:
    """Time series of a run [SI]: separation, clearance, forces, friction coefficient, stresses.

    Only the quantities of the scene's effects are returned (no adhesion history without the
    adhesion effect, and so on). ``steady``: at the steady window's samples only (:func:`steady_window`),
    and only the series :func:`summarize` reads (not the ratios ``mean_pressure``,
    ``friction_coefficient``, ``shear_stress``): each sample's value is computed alone, so these are
    the full histories' values at those samples, bit for bit, for a third less work (the parameter
    studies keep no history: docs/performance.md, section "The Python of a pair").
    """
    m, p = run.model, run.p
    Y, t, c = run.state, run.time, run.contact
    if steady:
        win = steady_window(run)
        Y, t, c = Y[win], t[win], c[win]
    if m.dmw is not None:
        w, wdot = disk_history(m.dmw, p, t)
    else:
        w, wdot = np.zeros_like(t), np.zeros_like(t)
    d = separation_at(p, Y[:, Z], Y[:, THETA], w)
    if m.heating is not None:  # the frictional heat's protrusion, the state's last column (state.output_size)
        out_heat = Y[:, -1]
        d = d - out_heat
    out: dict[str, np.ndarray] = {"separation": d, "disk_displacement": w, "z": Y[:, Z], "pitch": Y[:, THETA]}
    out["clearance"] = d - m.k_sigma
    if m.heating is not None:
        out["thermal_protrusion"] = out_heat
    x0, h, An = p["tab_x0"], p["tab_h"], run.nominal_area  # (item access: a record's attribute is ~10x slower)
    tabs = interface_tables(m, run.protrusion, An)  # (those the kernel ran with: contact.area_model)
    if m.heating is not None:  # A_n at delta + delta_f, as the kernel reads it (frictional_heating.heat_tables)
        An = heated_areas(HEAT_STEP, run.heat_areas, out_heat) if run.heat_areas is not None else An
    net = np.zeros_like(t)
    if tabs.adhesion is not None:  # (the meniscus state q is the adhesion pressure when it is on)
        out["adhesion_force"] = An * (Y[:, MENISCUS] if m.meniscus is not None else ppval(tabs.adhesion, x0, h, d))
        if m.meniscus is not None and tabs.adhesion.shape[1] == 8:  # the part acting at once (dynamics.Tables)
            out["adhesion_force"] += An * ppval(np.ascontiguousarray(tabs.adhesion[:, 4:]), x0, h, d)
        net -= out["adhesion_force"]
    if m.contact is not None:
        dc = d[c] if c.any() else None  # (the separation at the samples in contact, for every table)

        def on_contact(table: np.ndarray, upper: float = np.inf) -> np.ndarray:
            """``A_n`` times a table at the samples in contact (its laws are off elsewhere: 0)."""
            v = np.zeros_like(t)
            if dc is not None:
                v[c] = (An[c] if np.ndim(An) else An) * np.clip(ppval(table, x0, h, dc), 0.0, upper)
            return v

        out["in_contact"] = c
        fc = on_contact(tabs.contact)
        ddot = Y[:, Z_RATE] - m.slider.l_c * Y[:, THETA_RATE] - wdot
        out["contact_force"] = fc
        out["contact_damping_force"] = np.where(c, -p["c_c"] * ddot, 0.0)
        net += fc + out["contact_damping_force"]
        # (clipped to [0, A_n] (flat section; the footprint when integrated): the spline through the
        # capped table may overshoot by ~1e-6 at the cap)
        area = on_contact(tabs.area, tabs.area_cap)
        out["real_area"] = area
        if steady:  # (the ratios below are histories of their own: summarize takes ratios of sums)
            if tabs.friction is not None:
                out["friction_force"] = _friction(tabs, on_contact, An, x0, h, d)
            out["net_force"] = net
            return out
        with np.errstate(invalid="ignore", divide="ignore"):
            out["mean_pressure"] = np.where(c & (area > 0), fc / np.where(area > 0, area, 1.0), np.nan)
            if tabs.friction is not None:
                ff = out["friction_force"] = _friction(tabs, on_contact, An, x0, h, d)
                out["friction_coefficient"] = np.where(c & (fc > 0), ff / np.where(fc > 0, fc, 1.0), np.nan)
                out["shear_stress"] = np.where(c & (area > 0), ff / np.where(area > 0, area, 1.0), np.nan)
    if m.adhesion is not None or m.contact is not None:
        out["net_force"] = net
    return out


def _friction(tabs: InterfaceTables, on_contact: Callable[[np.ndarray], np.ndarray], An: float, x0: float, h: float, d: np.ndarray) -> np.ndarray:
    """The friction force history [N] of :func:`histories`: the friction table in contact, and the
    continuous lubricant shear beside at every sample when the table holds two (forces.py)."""
    two = tabs.friction.shape[1] == 8
    ff = on_contact(np.ascontiguousarray(tabs.friction[:, :4]) if two else tabs.friction)
    if two:
        ff = ff + An * np.maximum(ppval(np.ascontiguousarray(tabs.friction[:, 4:]), x0, h, d), 0.0)
    return ff


def steady_window(run: Run) -> slice:
    """The output samples of a run's steady window, ``transient <= t``: as a slice of ``run.time``, from
    the first such sample on (the output times never decrease, :func:`pipeline.model.running.run_model`),
    so that a series' window is a view, not a copy (a boolean selection copied the whole state, ~0.1 ms a
    run)."""
    return slice(int(np.searchsorted(run.time, run.model.transient - 1e-15, side="left")), None)


def summarize(run: Run, hist: dict[str, np.ndarray] | None = None) -> dict[str, float]:
    """Steady-window scalars of a run (SI units; definitions in the module docstring), from its
    histories ``hist`` (:func:`histories`), or, when None, from those of the steady window alone
    (``histories(run, steady=True)``: the same numbers, bit for bit)."""
    m = run.model
    if hist is None:
        hist, win = histories(run, steady=True), slice(None)
    else:
        win = steady_window(run)
    d = hist["separation"][win]
    c = hist["clearance"][win]
    lo, hi = run.d_extremes
    exact = np.isfinite(lo) and np.isfinite(hi)
    # peak-to-peak of the exact extremes (between samples too) when the kernel found them
    exact_pp = m.fhm_measure == "peak-to-peak" and exact
    fhm_bv = float(fhm(np.array([lo, hi]) if exact_pp else d, m.p["FH0"], m.fhm_measure))
    out = {
        "fhm_bv": fhm_bv,
        "clearance": float(np.mean(c)),
        "min_clearance": float(lo - m.k_sigma) if exact else float(np.min(c)),
        "nominal_area": run.nominal_area,
        "protrusion_radius": float(effective_radius(run.protrusion, m.half_length, m.section_depth))
        if np.isfinite(m.section_depth) else np.nan,
    }
    if "adhesion_force" in hist:
        out["adhesion_force"] = float(np.mean(hist["adhesion_force"][win]))
    if "net_force" in hist:
        out["net_force"] = float(np.mean(hist["net_force"][win]))
    if "in_contact" in hist:
        inc = hist["in_contact"][win]
        frac = float(np.mean(inc))
        out["contact_fraction"] = frac
        out["regime"] = FLYING if not touched(run) else (SURFING if frac >= SURFING_FRACTION else BOUNCING)
        out["contact_switches_per_ms"] = contact_switch_rate(run)  # [1/s]; the dataset's unit is 1/ms
        fc = hist["contact_force"][win]
        area = hist["real_area"][win]
        out["contact_force"] = float(np.mean(fc))
        out["interference"] = float(np.mean(-c[inc])) if inc.any() else np.nan
        out["real_area"] = float(np.mean(area[inc])) if inc.any() else np.nan
        fc_sum, area_sum = fc.sum(), area.sum()
        out["mean_pressure"] = float(fc_sum / area_sum) if area_sum > 0 else np.nan
        if "friction_force" in hist:
            ff = hist["friction_force"][win]
            out["friction_force"] = float(np.mean(ff))
            out["friction_coefficient"] = float(ff.sum() / fc_sum) if fc_sum > 0 else np.nan
            # (the friction in contact: the continuous lubricant shear also acts out of contact)
            out["shear_stress"] = float(np.where(inc, ff, 0.0).sum() / area_sum) if area_sum > 0 else np.nan
    if m.heating is not None:
        out.update(heating_summary(m, hist["thermal_protrusion"][win], out.get("friction_force", 0.0),
                                   out.get("real_area", np.nan)))
    out["validity"] = int(_validity(run, hist, win))
    return out


def heating_summary(model: Any, delta_f: np.ndarray, friction_force: float, real_area: float) -> dict[str, float]:
    """The frictional heat's scalars of a steady window (docs/model.md, section "Frictional heating"): the mean
    heat's protrusion ``delta_f`` [m] of its samples ``delta_f``, the mean friction power ``Q V`` [W] of the mean
    friction force [N], and the flash temperature rise [K] of that power over the mean real area [m^2] as one
    circular spot (:func:`pipeline.physics.flash_temperature.contact_temperature`, the default
    :class:`pipeline.physics.flash_temperature.Thermal`): the micro-contacts' own rise is lower, the real area
    being many smaller spots (their count is the interface's, not the run's); NaN without contact."""
    V = disk_speed_m_s(model.scene["dmw"])
    power = float(friction_force) * V
    th = Thermal()
    rise = contact_temperature(power, real_area, 1.0, V, th.k_slider, th.k_disk, th.diffusivity_disk)
    return {"thermal_protrusion": float(np.mean(delta_f)), "friction_power": power,
            "flash_temperature": rise["temperature"]}


def contact_switch_rate(run: Run) -> float:
    """Transitions of the contact mode (``d < k sigma``) in the steady window per unit time [1/s]: the
    kernel's count (:data:`pipeline.model.state.WINDOW_SWITCHES`, every switch, also those between output
    samples) over the window's length (``contact_switches_per_ms`` in the datasets, [1/ms]). Near 0 for
    a run flying or in steady contact, a few per ms for bouncing, thousands per ms for a sliding mode
    held on the criterion (docs/model.md, section "Switched and continuous friction")."""
    window = run.model.duration - run.model.transient
    return float(run.info[WINDOW_SWITCHES]) / window if window > 0 else np.nan


def touched(run: Run) -> bool:
    """Whether a run touched in the steady window: in contact at an output sample of the window, or
    the exact minimum of the separation below ``k sigma`` (a contact shorter than the output step
    falls between samples but not past the integrator's exact extremes). The one rule of the regime
    (:func:`summarize`) and of the calibration; from a summary, ``min_clearance < 0`` says the same
    whenever the kernel tracked the extremes."""
    win = steady_window(run)
    return bool(run.contact[win].any() or run.d_extremes[0] < run.model.k_sigma)


def touched_in_summary(min_clearance: Any) -> Any:
    """:func:`touched` read from the steady-window summary: the exact minimum clearance ``d - k sigma``
    (``min_clearance``, any unit) below zero; ``False`` where it is NaN (not evaluated)."""
    with np.errstate(invalid="ignore"):
        return np.asarray(min_clearance) < 0


def _validity(run: Run, hist: dict[str, np.ndarray], win: np.ndarray | slice) -> int:
    """The :class:`pipeline.validity.Validity` bits of a run's steady window."""
    m, s = run.model, run.model.slider
    fh0 = float(m.p["FH0"])
    lo = run.d_extremes[0] if np.isfinite(run.d_extremes[0]) else float(np.min(hist["separation"][win]))
    tables = m.contact is not None or m.adhesion is not None
    forces = [np.max(np.abs(hist[n][win])) for n in ("contact_force", "adhesion_force") if n in hist]
    return check_run(fh0=fh0, arms=(s.l_f, s.l_r), z=hist["z"][win], pitch=hist["pitch"][win], d_min=lo,
                     table_floor=float(m.p["tab_x0"]) if tables else None,
                     force=float(max(forces)) if forces else 0.0, load=(s.k_f + s.k_r) * fh0)
