"""A/B measurement of the dynamics kernel alone: instruction counts (callgrind) and interleaved timings.

The kernel's own cost, free of the model assembly around it, compared between two checkouts of the
package (e.g. the named-parameter kernel against the positional-vector one of commit e6348f9).

``capture``: run the paper scene (``contact.k = 0.445``) through ``slider.run_model`` at three
settings and pickle the arguments the kernel's ``integrate`` receives (air bearing only at 11 nm,
flying 5 nm, sliding 11 nm)::

    PYTHONPATH=CHECKOUT python benchmarks/kernel_ab.py capture OUT.pkl

``call``: load the pickle, call ``integrate`` once (compilation or cache load), then switch callgrind's
instrumentation on, zero its counters, make ``N`` calls and dump (``callgrind_control`` from the
process itself): the dump's total over ``N`` is the instructions of one integration, whatever the
machine's load (the polling of ``callgrind_control`` adds ~0.05 M instructions, measured)::

    PYTHONPATH=CHECKOUT valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file=OUT.%p \
        python benchmarks/kernel_ab.py call OUT.pkl CASE N         (then: grep summary OUT.*.1)

``starts OUT.pkl Y0.npz`` then ``graft OTHER.pkl Y0.npz`` (each under its own checkout): the other
checkout's captured cases get this one's start states, so both kernels integrate the same problem.

(CHECKOUT on ``PYTHONPATH``, the script run by its path: the checkout's ``pipeline`` wins over an
editable install of another one.) ``time``: the median over ``R`` rounds of ``N`` calls of one case;
two checkouts cannot share a process (one package name), so run A and B alternately
(``benchmarks/bench_kernel_ab.py`` does, against commit 87de7e7, in ``make bench``).
"""

from __future__ import annotations

import pickle
import statistics
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

ROOT = Path(__file__).resolve().parents[1]
CASES = ("air_bearing_11", "flying_5", "sliding_11")
#: The contact criterion of the captured paper scene [1].
K = 0.445


def _layered() -> bool:
    """Whether the checkout on the path is the layered package (``pipeline/model``; an editable install
    of another checkout would otherwise answer ``import pipeline.model``)."""
    import pipeline
    return (Path(pipeline.__path__[0]) / "model").is_dir()


def _modules():
    if _layered():
        from pipeline.model import dynamics as dyn
        from pipeline.config.scene import load_scene
        try:  # (model/slider.py split into assembly, running, ...)
            from pipeline.model import assembly, running
            sl = SimpleNamespace(build_model=assembly.build_model, run_model=running.run_model,
                                 __file__=assembly.__file__)
        except ImportError:
            from pipeline.model import slider as sl
    else:  # commit e6348f9
        from pipeline import dynamics as dyn, slider as sl
        from pipeline.scene import load_scene
    from pipeline.stages.simulate import model_inputs
    return dyn, sl, load_scene, model_inputs


def capture(out: Path) -> None:
    dyn, sl, load_scene, model_inputs = _modules()
    config = Path(sl.__file__).resolve().parents[1]
    config = (config if (config / "configs").is_dir() else config.parent) / "configs" / "paper-2009.toml"
    scene = load_scene(config, [f"contact.k={K}"])
    seen = []
    real = dyn.integrate
    dyn.integrate = lambda *a: (seen.append(a), real(*a))[1]
    try:
        with tempfile.TemporaryDirectory() as tmp:
            interface, rec = model_inputs(scene, Path(tmp))
            ab_model = sl.build_model(scene.replace(scene={"effects": ["air_bearing"]}), None, None, None)
            model = sl.build_model(scene, interface, rec, K)
            sl.run_model(ab_model, 11e-9)
            sl.run_model(model, 5e-9)
            sl.run_model(model, 11e-9)
    finally:
        dyn.integrate = real
    out.write_bytes(pickle.dumps(dict(zip(CASES, seen))))


def _load(path: Path, case: str):
    if _layered():  # only the kernel's module (valgrind runs the imports 50x slower)
        from pipeline.model import dynamics as dyn
    else:
        from pipeline import dynamics as dyn
    return dyn.integrate, pickle.loads(path.read_bytes())[case]


def _callgrind(option: str) -> None:
    """``callgrind_control OPTION`` on this process; the interpreter keeps running meanwhile (valgrind
    reads the command while the process executes code, not while it blocks in a system call)."""
    import os
    import subprocess
    proc = subprocess.Popen(["callgrind_control", option, str(os.getpid())], stdout=subprocess.DEVNULL)
    while proc.poll() is None:
        sum(range(1000))


def call(path: Path, case: str, n: int) -> None:
    """One call (compilation or cache load), then, under callgrind, instrumentation on, counters zeroed,
    ``n`` calls, and a dump: the dump's total over ``n`` is the instructions of one call."""
    integrate, args = _load(path, case)
    integrate(*args)
    _callgrind("--instr=on")
    _callgrind("-z")
    for _ in range(n):
        integrate(*args)
    _callgrind("-d")


def digest(result) -> str:
    """SHA-256 of the bytes of the states, contact flags and extremes ``integrate`` returned (``result[0]``,
    ``[1]``, ``[3]``; not the counters, which gained a slot after 87de7e7): equal digests, bit-identical results."""
    import hashlib
    import numpy as np
    h = hashlib.sha256()
    for i in (0, 1, 3):
        h.update(np.ascontiguousarray(result[i]).tobytes())
    return h.hexdigest()


def starts(path: Path, out: Path) -> None:
    """Save the start state ``y0`` of each captured case (``.npy`` files in a ``.npz``)."""
    import numpy as np
    np.savez(out, **{case: np.asarray(args[0]) for case, args in pickle.loads(path.read_bytes()).items()})


def graft(path: Path, npz: Path) -> None:
    """Give each captured case of ``path`` the start state saved by :func:`starts` (from another checkout), so
    two kernels integrate the same problem: the start state is the model's (its static solution), not the
    kernel's, and may differ in the last bits between checkouts (87de7e7's at ~1e-8 relative)."""
    import numpy as np
    cases, y0 = pickle.loads(path.read_bytes()), np.load(npz)
    for case, args in cases.items():
        if y0[case].shape != np.shape(args[0]):
            raise ValueError(f"{npz}: start state of {case} has shape {y0[case].shape}, expected {np.shape(args[0])}")
        cases[case] = (y0[case].copy(),) + tuple(args[1:])
    path.write_bytes(pickle.dumps(cases))


def timing(path: Path, case: str, n: int, rounds: int) -> None:
    """The median over ``rounds`` rounds of ``n`` calls of one case [ms]; a second line ``digest HEX`` of the
    results (:func:`digest`), for an A/B that checks the two kernels agree bit for bit."""
    integrate, args = _load(path, case)
    first = integrate(*args)
    t = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(n):
            integrate(*args)
        t.append((time.perf_counter() - t0) / n)
    print(f"{case} {statistics.median(t) * 1e3:.4f} ms (min {min(t) * 1e3:.4f})")
    print(f"digest {digest(first)}")


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "capture":
        capture(Path(sys.argv[2]))
    elif cmd == "call":
        call(Path(sys.argv[2]), sys.argv[3], int(sys.argv[4]))
    elif cmd == "starts":
        starts(Path(sys.argv[2]), Path(sys.argv[3]))
    elif cmd == "graft":
        graft(Path(sys.argv[2]), Path(sys.argv[3]))
    elif cmd == "time":
        timing(Path(sys.argv[2]), sys.argv[3], int(sys.argv[4]), int(sys.argv[5]))
