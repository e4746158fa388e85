"""Benchmarks of the slider dynamics (pipeline.model.dynamics via pipeline.model.running), against the naive baseline.

Rows (targets from the task brief):

1. one paper scene (2 ms at the scene's default accuracy, k = 0.445) after compilation: integration
   plus steady-window statistics, median, target < 50 ms (sliding 11 nm and flying 5 nm);
2. import + first call in a fresh process with the numba on-disk cache warm (subprocess, median of 3
   after one warm-up process; the wall time includes the interpreter's start), target < 2 s. The
   process ends as an ``hdi`` command does (:func:`pipeline.cli.entry`: ``os._exit`` once its output
   is flushed), so the wall time does not count the interpreter's teardown (~0.3 s of numba/HDF5
   finalisers) that no ``hdi`` command pays; the row keeps it apart as ``teardown_s`` (a second
   process that exits normally);
3. a scene with only ``["air_bearing"]`` against the full scene (what disabled effects cost: ratio);
4. project versus naive (``benchmarks/naive.py``: scipy ``solve_ivp`` RK45 with a Python right-hand
   side, same physics, same accuracy, same tolerances) per scene, flying 5 nm and sliding 11 nm,
   both measured in this run; target speed-up >= 100 (the project row's ``target_s`` is the naive
   median / 100);
5. the paper sweep (76 protrusions, one roughness, one damping) sequentially in one process: the
   project over all 76, the naive over a subset, scaled to 76 (said in the row name);
6. the right-hand side's cost per call along the kernel's own trajectory (flying 5 nm, sliding 11 nm;
   target <= 50 ns): the kernel's states at as many evenly spread times as it evaluated its right-hand
   side, with its contact mode there, evaluated by the step's code (the disk looked up, then
   :func:`pipeline.model.forces.rhs_at` inlined, :func:`rhs_per_call`), beside the out-of-line
   :func:`pipeline.model.forces.rhs_slots` called at the same points (what each stage paid before the
   step inlined its right-hand side) and the kernel's own time per evaluation; CPU time of this thread.
   Both loops are compiled as the step is, with its products and sums fused (the kernel's ``fastmath`` flag,
   :data:`pipeline.model.compiled.OPTIONS`) and without numba's reference counts
   (:data:`pipeline.model.compiled.BORROWING`): compiled with them, the loop pays an atomic
   reference-count pair per table slot at every call of the inlined right-hand side (its arrays handed to
   inlined helpers), which the step never pays (measured once: 60.1 / 78.9 ns per call against 26.7 / 42.2 ns,
   docs/performance.md, section "The right-hand side's row").
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

from numba import njit

from benchmarks.common import record, timeit
from benchmarks.naive import simulate_naive
from pipeline.model import assembly, dynamics as dyn, outcomes, running
from pipeline.model.compiled import BORROWING, OPTIONS
from pipeline.model.forces import rhs_at, rhs_slots
from pipeline.model.piecewise import disk3
from pipeline.model.state import MENISCUS, RHS_CALLS, THETA, THETA_RATE, Z, Z_RATE
from pipeline.config.scene import load_scene
from pipeline.stages.simulate import model_inputs
from pipeline.config.grid import protrusion_grid

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "paper-2009.toml"
K = 0.445
NAIVE_SUBSET = 6  # protrusions of the sweep the naive baseline runs (evenly spread)

FRESH = textwrap.dedent("""
    import time
    t0 = time.perf_counter()
    import sys
    from pipeline.io import read_dataset
    from pipeline.config.scene import load_scene
    from pipeline.model import assembly, dmw_record, outcomes, running
    t1 = time.perf_counter()
    out = sys.argv[1]
    scene = load_scene(sys.argv[2], ["contact.k=%(k)s"])
    interface = read_dataset(out + "/interface.nc", stage="interface")
    _, w, fs = dmw_record.load(out + "/dmw.nc")
    model = assembly.build_model(scene, interface, (w, fs), %(k)s)
    s = outcomes.summarize(running.run_model(model, 11e-9))
    t2 = time.perf_counter()
    print({"import_s": t1 - t0, "first_call_s": t2 - t1, "total_s": t2 - t0, "fhm_bv": s["fhm_bv"]}, flush=True)
    if sys.argv[3] == "fast-exit":
        import os
        os._exit(0)
""") % {"k": K}


def _fresh_process(folder: Path, repeat: int = 3, exit_: str = "fast-exit") -> tuple[list[float], dict]:
    """Wall times of fresh interpreters doing import + first call (after one warm-up process), ending
    as ``hdi`` does (``exit_="fast-exit"``) or with the interpreter's normal teardown (``"normal"``)."""
    cmd = [sys.executable, "-c", FRESH, str(folder), str(CONFIG), exit_]
    env = {"PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "PATH": "/usr/bin:/bin"}
    subprocess.run(cmd, check=True, capture_output=True, env=env, cwd=ROOT)  # warm the numba cache
    times, inner = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = subprocess.run(cmd, check=True, capture_output=True, text=True, env=env, cwd=ROOT)
        times.append(time.perf_counter() - t0)
        inner.append(eval(res.stdout.strip().splitlines()[-1], {}))  # a dict of floats we printed
    mid = {k: statistics.median(d[k] for d in inner) for k in ("import_s", "first_call_s", "total_s")}
    return times, mid


#: The right-hand side's loops are compiled as the kernel's functions are (:data:`pipeline.model.compiled.OPTIONS`:
#: fused products and sums included) and without reference counts, but not cached on disk: numba's cache would not
#: see a change of the kernel's modules they inline.
HARNESS = {**OPTIONS, "cache": False, **BORROWING}


@njit(**HARNESS)
def _inlined(T, Y, C, p, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus):
    """The step's right-hand side (the disk at the time, then :func:`pipeline.model.forces.rhs_at` inlined) at
    the times ``T`` [s], states ``Y`` and modes ``C``; returns a sum of the results (kept: nothing is pruned)."""
    acc = 0.0
    for j in range(T.shape[0]):
        wc, vc, wf, vf, wr, vr = disk3(p, dmw, T[j])
        q = 0.0
        if meniscus is not None:
            q = Y[j, MENISCUS]
        a_z, a_theta, a_vz, a_vtheta, dq = rhs_at(p, C[j], Y[j, Z], Y[j, THETA], Y[j, Z_RATE], Y[j, THETA_RATE], q,
                                                  wc, vc, wf, vf, wr, vr, contact, adhesion, friction, tfc, pitch,
                                                  rear_law, gap_power, meniscus)
        acc += a_z + a_theta + a_vz + a_vtheta + dq
    return acc


@njit(**HARNESS)
def _out_of_line(T, Y, C, p, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power, meniscus):
    """:func:`pipeline.model.forces.rhs_slots` (compiled on its own, called) at the same points as
    :func:`_inlined`; returns a sum of the results."""
    acc = 0.0
    for j in range(T.shape[0]):
        rhs_slots(T[j], Y[j], p, C[j], out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
                  meniscus)
        for i in range(out.shape[0]):
            acc += out[i]
    return acc


def _cpu_per_point(fn, n: int, repeat: int = 21) -> list[float]:
    """CPU times of this thread [s] of ``fn()`` over ``n`` points, per point (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.thread_time()
        fn()
        times.append((time.thread_time() - t0) / n)
    return times


def rhs_per_call(model: assembly.Model, protrusion: float) -> dict:
    """The right-hand side's cost per call [s] along the kernel's trajectory at ``protrusion`` [m] (row 6):
    ``inlined`` (the step's), ``out_of_line`` (:func:`pipeline.model.forces.rhs_slots` called) and ``kernel``
    (the kernel's time over its evaluations), each a list of per-point CPU times; ``evaluations``, and
    ``contact_fraction`` of the points."""
    seen = []
    real = dyn.integrate
    dyn.integrate = lambda *a: (seen.append(a), real(*a))[1]
    try:
        run_ = running.run_model(model, protrusion)
    finally:
        dyn.integrate = real
    y0, grid, p, tab, var, solver = seen[-1]
    n = int(run_.info[RHS_CALLS])
    T = np.linspace(0.0, grid.t_end, n)
    Y, C, _, _ = dyn.integrate(y0, dyn.Grid(grid.t_end, T), p, tab, var, solver)
    Y = np.ascontiguousarray(Y)
    slots = dyn._slots(tab, var)  # (the compiled functions' slots: without the loop's heating slot)
    out = np.empty(Y.shape[1])
    args = dyn.kernel_arguments(y0, grid, p, tab, var, solver)
    return {"inlined": _cpu_per_point(lambda: _inlined(T, Y, C, p, *slots), n),
            "out_of_line": _cpu_per_point(lambda: _out_of_line(T, Y, C, p, out, *slots), n),
            "kernel": _cpu_per_point(lambda: dyn._integrate(*args), n),
            "evaluations": n, "contact_fraction": float(np.mean(C))}


def run(results: list[dict]) -> None:
    """Append the dynamics benchmark rows to ``results``."""
    scene = load_scene(CONFIG, [f"contact.k={K}"])
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        t0 = time.perf_counter()
        interface, rec = model_inputs(scene, folder)
        t_inputs = time.perf_counter() - t0
        model = assembly.build_model(scene, interface, rec, K)

        def project(prot_nm: float):
            return lambda: outcomes.summarize(running.run_model(model, prot_nm * 1e-9))

        # (1) one paper scene at default accuracy
        proj = {}
        for label, prot in (("sliding", 11.0), ("flying", 5.0)):
            run_ = running.run_model(model, prot * 1e-9)
            proj[prot] = record(results, f"dynamics: paper scene 2 ms, {label} {prot:g} nm (run + summarize)",
                                timeit(project(prot), repeat=21), target_s=0.05, steps=int(run_.info[1]),
                                rejected=int(run_.info[2]), rhs_evaluations=int(run_.info[4]))

        # (6) the right-hand side per call along the kernel's own trajectory
        for label, prot in (("flying", 5.0), ("sliding", 11.0)):
            cost = rhs_per_call(model, prot * 1e-9)
            med = {k: statistics.median(cost[k]) for k in ("inlined", "out_of_line", "kernel")}
            record(results, f"dynamics: right-hand side per call along the kernel's trajectory, {label} {prot:g} nm "
                   "(the step's, inlined; CPU time per call; target <= 50 ns)", cost["inlined"], target_s=50e-9,
                   ns_per_call=med["inlined"] * 1e9, out_of_line_ns_per_call=med["out_of_line"] * 1e9,
                   kernel_ns_per_evaluation=med["kernel"] * 1e9, rhs_evaluations=cost["evaluations"],
                   contact_fraction=cost["contact_fraction"])

        # (2) import + first call in a fresh process (numba cache warm)
        times, inner = _fresh_process(folder)
        teardown = statistics.median(_fresh_process(folder, exit_="normal")[0]) - statistics.median(times)
        record(results, "dynamics: fresh process, import + first call (subprocess wall time)", times,
               target_s=2.0, teardown_s=teardown, **{f"inner_{k}": v for k, v in inner.items()})

        # (3) what the effects cost: air bearing only versus the full scene
        ab_scene = scene.replace(scene={"effects": ["air_bearing"]})
        ab_model = assembly.build_model(ab_scene, None, None, None)
        ab = timeit(lambda: outcomes.summarize(running.run_model(ab_model, 11e-9)), repeat=21)
        full = statistics.median(timeit(project(11.0), repeat=21))
        record(results, "dynamics: air_bearing-only scene, 11 nm (ratio = full / air_bearing-only)", ab,
               ratio_full_to_air_bearing=full / statistics.median(ab), full_median_s=full,
               steps=int(running.run_model(ab_model, 11e-9).info[1]))

        # (4) project versus naive, per scene
        for label, prot in (("flying", 5.0), ("sliding", 11.0)):
            naive_times = timeit(lambda: simulate_naive(scene, interface, rec, K, prot), repeat=3, warmup=0)
            t_naive = statistics.median(naive_times)
            t_proj = statistics.median(timeit(project(prot), repeat=21))
            n = simulate_naive(scene, interface, rec, K, prot)
            p = outcomes.summarize(running.run_model(model, prot * 1e-9))
            record(results, f"naive baseline (solve_ivp RK45 + Python rhs), {label} {prot:g} nm", naive_times,
                   rhs_evaluations=int(n["rhs_evaluations"]))
            record(results, f"dynamics vs naive, {label} {prot:g} nm (project; target speed-up >= 100)",
                   [t_proj], target_s=t_naive / 100.0, speedup=t_naive / t_proj, naive_median_s=t_naive,
                   fhm_bv_rel_diff=abs(n["fhm_bv"] / p["fhm_bv"] - 1),
                   clearance_rel_diff=abs(n["clearance"] / p["clearance"] - 1))
        # the literal first version: np.interp on the DMW record too (BV within ~0.5 %)
        lin = timeit(lambda: simulate_naive(scene, interface, rec, K, 11.0, dmw_interpolation="linear"),
                     repeat=3, warmup=0)
        t_proj = statistics.median(timeit(project(11.0), repeat=21))
        record(results, "naive baseline with np.interp on the DMW record (linear), sliding 11 nm", lin,
               speedup=statistics.median(lin) / t_proj,
               fhm_bv_rel_diff=abs(simulate_naive(scene, interface, rec, K, 11.0, dmw_interpolation="linear")
                                   ["fhm_bv"] / outcomes.summarize(running.run_model(model, 11e-9))["fhm_bv"] - 1))

        # (5) the paper sweep, sequential
        grid = protrusion_grid(scene)

        def sweep() -> None:
            for prot in grid:
                outcomes.summarize(running.run_model(model, prot * 1e-9))

        sweep_times = timeit(sweep, repeat=3)
        t_sweep = statistics.median(sweep_times)
        subset = grid[np.linspace(0, grid.size - 1, NAIVE_SUBSET).round().astype(int)]
        t0 = time.perf_counter()
        for prot in subset:
            simulate_naive(scene, interface, rec, K, float(prot))
        t_naive_sweep = (time.perf_counter() - t0) / subset.size * grid.size
        record(results, f"dynamics: paper sweep {grid.size} protrusions, sequential (project; tables + record "
               f"once: {t_inputs:.2f} s, not included)", sweep_times, speedup=t_naive_sweep / t_sweep,
               protrusions=int(grid.size))
        record(results, f"naive: paper sweep {grid.size} protrusions, ESTIMATED from {subset.size} protrusions "
               f"({', '.join(f'{p:g}' for p in subset)} nm) x {grid.size}/{subset.size}", [t_naive_sweep],
               estimated=True, subset_nm=json.dumps([float(p) for p in subset]))


if __name__ == "__main__":  # pragma: no cover
    rows: list[dict] = []
    run(rows)
    print(json.dumps(rows, indent=2))
