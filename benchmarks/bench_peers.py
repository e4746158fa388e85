"""The project's kernel against the best library integrators a competent user would call instead, in the same run
(:mod:`benchmarks.peers`: numbalsoda's DOP853 and LSODA with a numba cfunc right-hand side of the naive
baseline's model, the same tables, DMW spline, tolerances and the project's static start).

Per scene (the paper scene, ``contact.k = 0.445``, 2 ms: flying 5 nm, sliding 11 nm; :data:`SCENES`): each
peer runs once and is checked against the kernel (:func:`benchmarks.peers.agreement`: FHM/BV within 1 %, mean
clearance within 0.1 %); then the kernel (``dynamics.integrate`` on the arguments ``run_model`` gives it) and
every peer that agrees are called alternately, :data:`ROUNDS` rounds, each call's CPU time of this thread
(``time.thread_time``). Rows: the kernel's, then one per peer and scene with ``speedup_of_kernel`` (the peer's
median over the kernel's, the same rounds: above 1 the kernel is faster), its RHS evaluations and agreement. A
peer that disagrees is void (a ``failed`` row with the numbers, ``void: true``, not timed); without numbalsoda
(``make bench-peers-setup`` installs it: a Fortran compiler and the ``bench`` extra) each peer's row says why
(``peer_installed: false``). The naive rows of bench_dynamics stay the floor.
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path
from typing import Any, Callable

from benchmarks.common import ROOT, record, record_failure
from benchmarks.naive import physics
from benchmarks.peers import METHODS, Peer, agreement, alternate, load_peers, speedup_of_kernel
from pipeline.config.scene import load_scene
from pipeline.model import assembly, dynamics, outcomes, running
from pipeline.model.state import ACCEPTED, RHS_CALLS, SWITCHES
from pipeline.stages.simulate import model_inputs

CONFIG = ROOT / "configs" / "paper-2009.toml"
K = 0.445
#: (label, protrusion [nm]) of the two scenes
SCENES = (("flying", 5.0), ("sliding", 11.0))
#: Alternated rounds of every contender (each ~3-15 ms a call)
ROUNDS = 41
KERNEL = "peers: the project's kernel (dynamics.integrate), {label} {prot:g} nm"
PEER = "peers: numbalsoda {peer} (numba cfunc RHS), {label} {prot:g} nm (speedup_of_kernel = peer / kernel)"


def kernel_call(model: Any, protrusion: float) -> tuple[Callable[[], Any], Any]:
    """The kernel's call of one run, on the arguments :func:`pipeline.model.running.run_model` hands
    ``dynamics.integrate`` (captured once), and that run."""
    seen: list[tuple] = []
    real = dynamics.integrate
    dynamics.integrate = lambda *a: (seen.append(a), real(*a))[1]
    try:
        run = running.run_model(model, protrusion)
    finally:
        dynamics.integrate = real
    args = seen[-1]
    return (lambda: real(*args)), run


def compare(results: list[dict], label: str, prot: float, kernel: Callable[[], Any], kernel_run: dict[str, Any],
            peers: dict[str, Peer | str], rounds: int = ROUNDS, kernel_extra: dict[str, Any] | None = None) -> None:
    """The rows of one scene: the kernel's and one per peer (module docstring). ``kernel_run``: the kernel's
    steady-window scalars (``fhm_bv`` [%], ``clearance`` [m]); ``peers``: name -> :class:`benchmarks.peers.Peer`
    (or anything with ``run()`` and ``call()``), or why it cannot be had (a string)."""
    verdicts: dict[str, dict[str, Any]] = {}
    contenders: dict[str, Callable[[], Any]] = {"kernel": kernel}
    for name, peer in peers.items():
        if isinstance(peer, str):
            continue
        res = peer.run()  # (the first call: numbalsoda's and the RHS's compile or cache load)
        verdicts[name] = {**agreement(res, kernel_run), "rhs_evaluations": res.get("rhs_evaluations"),
                          "peer_fhm_bv": res.get("fhm_bv"), "peer_clearance": res.get("clearance")}
        if verdicts[name]["agrees"]:
            contenders[name] = peer.call
    kernel()  # (warm)
    times = alternate(contenders, rounds)
    k_med = statistics.median(times["kernel"])
    record(results, KERNEL.format(label=label, prot=prot), times["kernel"], scene=label,
           clock="thread_time (CPU of this thread)",
           rounds=rounds, fhm_bv=kernel_run["fhm_bv"], clearance=kernel_run["clearance"], **(kernel_extra or {}))
    for name, peer in peers.items():
        row = PEER.format(peer=name, label=label, prot=prot)
        if isinstance(peer, str):
            record_failure(results, row, peer, peer=name, scene=label, peer_installed=False)
        elif not verdicts[name]["agrees"]:
            record_failure(results, row, f"void: {verdicts[name]['why']}", peer=name, scene=label, void=True,
                           **verdicts[name])
        else:
            record(results, row, times[name], peer=name, scene=label, rounds=rounds,
                   speedup_of_kernel=speedup_of_kernel(times[name], times["kernel"]), kernel_median_s=k_med,
                   clock="thread_time (CPU of this thread)", **verdicts[name])


def run(results: list[dict]) -> None:
    """Append the peer rows of both scenes to ``results``."""
    scene = load_scene(CONFIG, [f"contact.k={K}"])
    solvers = load_peers()
    with tempfile.TemporaryDirectory() as tmp:
        interface, rec = model_inputs(scene, Path(tmp))
    model = assembly.build_model(scene, interface, rec, K)
    for label, prot in SCENES:
        kernel, run_ = kernel_call(model, prot * 1e-9)
        y0, _ = running.start(model, prot * 1e-9)
        ph = physics(scene, interface, rec, K, prot)
        peers: dict[str, Peer | str] = {
            name: solve if isinstance(solve, str) else Peer(name, solve, ph, y0, tighten=METHODS[name][1])
            for name, solve in solvers.items()}
        info = run_.info
        compare(results, label, prot, kernel, outcomes.summarize(run_), peers,
                kernel_extra={"rhs_evaluations": int(info[RHS_CALLS]), "steps": int(info[ACCEPTED]),
                              "switches": int(info[SWITCHES])})


if __name__ == "__main__":  # pragma: no cover
    import json
    rows: list[dict] = []
    run(rows)
    print(json.dumps(rows, indent=2, default=str))
