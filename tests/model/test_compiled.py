"""How the kernel's functions are compiled (pipeline.model.compiled): every kernel function is cached on
disk, releases the GIL and uses numpy's error model (a division by zero is inf, not an exception); its
cache folder is named by the code key of its module and everything that module imports, so an edited law
inlined into the kernel gets a new folder; the decoration leaves numba's global cache folder as it was.
A function compiled without reference counts (compiled.BORROWING: the step, the right-hand side) keeps none
and cannot allocate.
One signature per entry point for the main scene, whatever the stage runs; the background compile of a first
run lands in the cache and is loaded, not compiled again; a compile says so, once."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import numpy as np
import pytest

from pipeline.code_version import code_key
from pipeline.model import compiled, piecewise, static_solver


def test_cache_folder_is_named_by_the_modules_code_key():
    folder = compiled.cache_folder("pipeline.model.dynamics")
    assert os.path.basename(folder) == "numba-" + code_key("pipeline.model.dynamics")[:16]
    # dynamics imports more of the package than piecewise: their code keys, and so their folders, differ
    assert compiled.cache_folder("pipeline.model.piecewise") != folder
    assert compiled.cache_folder("pipeline.model.piecewise") == compiled.cache_folder("pipeline.model.piecewise")


def test_kernel_functions_carry_the_options_and_their_cache_folder():
    for fn, module in ((piecewise.ppval, "pipeline.model.piecewise"), (static_solver._newton,
                                                                       "pipeline.model.static_solver")):
        assert fn.targetoptions["nogil"] and fn.targetoptions["error_model"] == "numpy", fn
        assert type(fn._cache).__name__ == "FunctionCache"  # cache=True (a plain njit has a NullCache)
        assert os.path.dirname(fn._cache._cache_path) == compiled.cache_folder(module)


def test_kernel_jit_compiles_with_the_options_and_restores_the_cache_folder(monkeypatch, tmp_path):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))

    @compiled.kernel_jit("pipeline.model.piecewise", inline="always")
    def ratio(a, b):
        return a / b

    assert numba.config.CACHE_DIR == str(tmp_path)  # (set around the decoration only)
    assert ratio.targetoptions["nogil"] and ratio.targetoptions["inline"] == "always"
    assert os.path.dirname(ratio._cache._cache_path) == compiled.cache_folder("pipeline.model.piecewise")
    assert ratio(1.0, 0.0) == np.inf and np.isnan(ratio(0.0, 0.0))  # numpy's error model: no ZeroDivisionError
    with pytest.raises(TypeError):
        compiled.kernel_jit("pipeline.model.piecewise", nogil=False)(lambda x: x)  # options cannot be overridden
    assert numba.config.CACHE_DIR == str(tmp_path)


def _reference_count_calls(dispatcher) -> int:
    """The calls of numba's reference counting (``NRT_incref``, ``NRT_decref``) in the optimised LLVM of
    ``dispatcher``'s one compiled signature (compiled in this process: cached code cannot be inspected)."""
    (llvm,) = dispatcher.inspect_llvm().values()
    return llvm.count("call void @NRT_incref(") + llvm.count("call void @NRT_decref(")


def test_a_borrowing_function_keeps_no_reference_counts_and_refuses_an_allocation(monkeypatch, tmp_path):
    # the pattern numba cannot prune (docs/kernel.md, section "Reference counts of the inlined helpers"): an
    # inlined helper whose array argument's last use is conditional, then a compiled call (its exception exit)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    module = "pipeline.model.piecewise"
    helper = compiled.kernel_jit(module)(lambda a, i: a[i] * 2.0)

    @compiled.kernel_jit(module, inline="always")
    def scaled(table, x, out, flag):
        if flag:
            x = x * table[0]
        out[0] = x
        return x

    def body(name):
        def fn(table, x, out, flag):
            y = scaled(table, x, out, flag)
            out[1] = helper(out, 0) + y
        fn.__name__ = fn.__qualname__ = name  # (two functions: numba's cache index does not key on the options)
        return fn

    counted = compiled.kernel_jit(module)(body("counted"))
    borrowing = compiled.kernel_jit(module, **compiled.BORROWING)(body("borrowing"))
    results = []
    for fn in (counted, borrowing):
        out = np.zeros(2)
        fn(np.array([3.0]), 2.0, out, True)
        results.append(out)
    # the same numbers (2 * 3 = 6, then 2 * 6 + 6 = 18); the reference counts of the arrays gone
    assert results[0].tolist() == results[1].tolist() == [6.0, 18.0]
    assert _reference_count_calls(counted) >= 2 and _reference_count_calls(borrowing) == 0

    # an allocation does not compile there (it would never be freed), in the function or in one it calls
    def allocates(out):
        buf = np.empty(1)
        buf[0] = 1.0
        out[0] = buf[0]

    make = compiled.kernel_jit(module)(lambda n: np.zeros(n))

    def calls_an_allocation(out):
        out[0] = make(1)[0]

    for fn in (allocates, calls_an_allocation):
        with pytest.raises(numba.core.errors.TypingError, match="returning of array passed into the function"):
            compiled.kernel_jit(module, **compiled.BORROWING)(fn)(np.zeros(1))


ROOT = Path(__file__).resolve().parents[2]

#: Runs the main scene's model (the calibrated k of `make run`) at a flying, a touchdown and a contact
#: protrusion, a run from a given start (the heater steps) and the statics map, in one fresh process, and
#: prints the kernel entry points' signature counts and whether the first run's background-compile
#: signature (a model's, and the scene's stand-ins') is the one the kernel was called with, and whether the
#: entry points called from Python were called with the types a first run compiles them for while it waits.
PLAN = """
import collections, json, sys
import numpy as np
from numba.core import event
compiles = collections.Counter()  # numba's compile event: a compile, not a cache load

class Count(event.Listener):
    def on_start(self, ev):
        compiles[ev.data["dispatcher"].py_func.__name__] += 1

    def on_end(self, ev):
        pass

event.register("numba:compile", Count())
import pipeline as hdi
from pipeline.model import ahead as first_run, compiled, dynamics as dyn, kernel_inputs, running, static_solver, statics
from pipeline.model.kernel_inputs import run_parameters
from pipeline.model.state import N_STATE
from pipeline.units import NM
scene = hdi.load_scene("configs/paper-2009-identified.toml", ["solver.duration_ms=0.4", "solver.transient_ms=0.1"])
model = hdi.build_model(scene, sys.argv[1], k=1.0736)
hdi.simulate(model, [5.0, 9.8, 11.0])
run = running.run_model(model, 11.0 * NM)
running.run_model(model, 11.2 * NM, y0=run.state[-1])
statics.statics_map(model, np.array([5.0, 11.0]) * NM)
p, tables, variants = run_parameters(model, 5.0 * NM)
ahead = compiled.signature(dyn._integrate, dyn.kernel_arguments(
    np.zeros(N_STATE), dyn.Grid(1e-3, np.zeros(3)), p, tables, variants, dyn.Solver(1e-6, model.atol, 1e-7, 10)))
stand_in = compiled.signature(dyn._integrate, dyn.kernel_arguments(*kernel_inputs.stand_in_arguments(scene)))
entry_points = [compiled.signature(f, args) in f.signatures for f, args in first_run.python_entry_points(scene)]
leaves = {f.py_func.__name__: [compiled.signature(f, args)] == list(f.signatures)
          for f, args in dyn.leaf_calls(*kernel_inputs.stand_in_arguments(scene))}
kernel = ("_integrate", "step", "switch_point", "knot_extrema", "stiffness_cap", "extrema_matter", "separation",
          "rhs_slots", "_newton")
from pipeline.model import forces, stepper

def increments(f):  # NRT_incref calls in its LLVM, where this process compiled it (cached code: not inspectable)
    return sum(ir.count("call void @NRT_incref(") for ir in f.inspect_llvm().values()) if compiles[
        f.py_func.__name__] else None

print(json.dumps({"increments": {"step": increments(stepper.step), "rhs_slots": increments(forces.rhs_slots),
                                 "stiffness_cap": increments(stepper.stiffness_cap),
                                 "extrema_matter": increments(stepper.extrema_matter),
                                 "switch_point": increments(stepper.switch_point),
                                 "separation": increments(forces.separation), "_integrate": increments(dyn._integrate)},
"integrate": len(dyn._integrate.signatures), "newton": len(static_solver._newton.signatures),
                  "ahead_is_called": [ahead] == list(dyn._integrate.signatures),
                  "stand_in_is_called": [stand_in] == list(dyn._integrate.signatures),
                  "entry_points_are_called": entry_points, "leaves_are_called": leaves,
                  "compiles": {name: compiles[name] for name in kernel}}))
"""


def test_the_main_scene_compiles_one_signature_per_kernel_entry_point(tmp_path):
    # a fresh process: the test session's other scenes add their own signatures to the dispatchers
    out = subprocess.run([sys.executable, "-c", PLAN, str(tmp_path / "results")], cwd=ROOT, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    plan = json.loads(out.stdout.strip().splitlines()[-1])
    # flying, touchdown and contact runs, a given start and the statics map share one kernel and one static
    # solver (a second signature would be a second compile of 15 s or 6 s of CPU in a first run)
    # ... whose types the runner's compile ahead knows from the scene alone (its stand-in arguments), and so
    # are those of the entry points called from Python, which a first run compiles while it waits
    # (the kernel's leaf callees: loaded with the cached kernel, not called from Python; the slow test below)
    assert {k: v for k, v in plan.items() if k not in ("compiles", "increments", "leaves_are_called")} == {
        "integrate": 1, "newton": 1, "ahead_is_called": True, "stand_in_is_called": True,
        "entry_points_are_called": [True, True, True, True]}


@pytest.mark.slow  # (the kernel and the static solver compiled from an empty cache: ~30 s of CPU)
def test_the_main_scene_compiles_each_kernel_function_once(tmp_path):
    # an empty cache, everything compiled in this process (no background compile): the kernel, its separately
    # compiled helpers (the step, the switch's bisection, the extrema across DMW knots, the step's cap from the
    # interface stiffness, the separation), the static solver and its right-hand side once each (no DMW, no
    # meniscus state; the kernel's step inlines its own: docs/kernel.md, section "The right-hand side in the step")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), HDI_COMPILE_AHEAD="0")
    out = subprocess.run([sys.executable, "-c", PLAN, str(tmp_path / "results")], cwd=ROOT, capture_output=True,
                         text=True, timeout=900, env=env)
    assert out.returncode == 0, out.stderr[-2000:]
    plan = json.loads(out.stdout.strip().splitlines()[-1])
    assert plan["compiles"] == {"_integrate": 1, "step": 1, "switch_point": 1, "knot_extrema": 1, "stiffness_cap": 1,
                                "extrema_matter": 1, "separation": 1, "rhs_slots": 1, "_newton": 1}
    # the kernel's compile asked its leaf callees for exactly the signatures a process waiting for the kernel's
    # background compile compiles them for first (pipeline.model.dynamics.leaf_calls; a wrong one would be
    # compiled for nothing, and the background compile would compile the right one itself)
    assert plan["leaves_are_called"] == {"stiffness_cap": True, "knot_extrema": True}
    # the step (with the right-hand side inlined), the static solver's right-hand side, the step's cap and the separation
    # without reference counts (pipeline.model.compiled.BORROWING; 15, 4 and 2 increments before, docs/kernel.md);
    # the kernel's own 8 are its allocations and returns, as many as with the separation inlined (commit 87f72a2):
    # calling it from the loop added none
    assert plan["increments"] == {"step": 0, "rhs_slots": 0, "stiffness_cap": 0, "extrema_matter": 0, "switch_point": 0,
                                  "separation": 0, "_integrate": 8}


#: A small cached kernel in its own module, compiled ahead in a fresh process with an empty cache.
TINY = """
import numba

@numba.njit(cache=True)
def tiny(x):
    return 2.0 * x + 1.0
"""

AHEAD = """
import sys
from numba import typeof
from pipeline.model import compiled
from tiny_kernel import tiny
compiled.announce(tiny, "the tiny kernel")
sig = (typeof(1.5),)
before = compiled.is_cached(tiny, sig)
started = compiled.compile_ahead(tiny, (1.5,), "the tiny kernel") and compiled.pending()
compiled.wait_ahead()
after = compiled.is_cached(tiny, sig)
value = tiny(1.5)
print(before, started, after, compiled.pending(), value, tiny.stats.cache_hits[sig], tiny.stats.cache_misses[sig])
"""


def _ahead(tmp_path: Path, **env: str) -> subprocess.CompletedProcess:
    (tmp_path / "tiny_kernel.py").write_text(textwrap.dedent(TINY))
    environ = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    environ.update(NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]),
                   **env)
    if "HDI_COMPILE_AHEAD" not in env:
        environ.pop("HDI_COMPILE_AHEAD", None)
    return subprocess.run([sys.executable, "-c", AHEAD], cwd=tmp_path, env=environ, capture_output=True, text=True,
                          timeout=300)


def test_a_kernel_compiled_ahead_is_loaded_from_the_cache_not_compiled_again(tmp_path):
    out = _ahead(tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    # not cached before; a background process started; cached after it; the call loads it (a cache hit,
    # no miss: this process compiled nothing) and computes 2 * 1.5 + 1
    assert out.stdout.split() == ["False", "True", "True", "False", "4.0", "1", "0"]
    # said once, by this process (no logging set up: on stderr); the background process says nothing
    assert out.stderr.count("compiling the tiny kernel") == 1
    # no time promised; the time it took said when it is done, as measured on this machine
    lines = out.stderr.strip().splitlines()
    assert lines[0] == "compiling the tiny kernel in a background process (first run only)", out.stderr
    assert re.fullmatch(r"compiled the tiny kernel in a background process in \d+\.\d s \(first run only: cached "
                        r"for the next runs\)", lines[1]), out.stderr


def test_without_compile_ahead_the_process_compiles_and_says_so(tmp_path):
    out = _ahead(tmp_path, HDI_COMPILE_AHEAD="0")
    assert out.returncode == 0, out.stderr[-2000:]
    # nothing started; the call compiles here (a miss, no hit), announced by numba's compile event
    assert out.stdout.split() == ["False", "False", "False", "False", "4.0", "0", "1"]
    lines = out.stderr.strip().splitlines()
    assert lines[0] == "compiling the tiny kernel (first run only)" and len(lines) == 2, out.stderr
    seconds = float(re.fullmatch(r"compiled the tiny kernel in (\d+\.\d) s \(first run only: cached for the next "
                                 r"runs\)", lines[1]).group(1))
    assert 0.0 <= seconds < 300.0


def test_a_cached_kernel_starts_nothing_and_says_nothing(tmp_path):
    assert _ahead(tmp_path).returncode == 0
    out = _ahead(tmp_path)  # the same cache folder, now holding the kernel
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["True", "False", "True", "False", "4.0", "1", "0"]
    assert "compiling" not in out.stderr


@pytest.mark.parametrize("handler", [True, False])
def test_the_compile_notice_is_a_log_line_or_stderr(handler, caplog, capsys, monkeypatch):
    import logging

    from pipeline import progress
    monkeypatch.setattr(logging.Logger, "hasHandlers", lambda self: handler)
    # (none left by an earlier test: `hdi`'s main attaches its stderr handler once per process)
    monkeypatch.setattr(logging.getLogger("pipeline"), "handlers", [])
    with caplog.at_level(logging.INFO, logger="pipeline"):
        progress.compile_notice("the dynamics kernel for this scene's effects")
        progress.compile_notice("the dynamics kernel for this scene's effects", 25.43)
    lines = ["compiling the dynamics kernel for this scene's effects (first run only)",
             "compiled the dynamics kernel for this scene's effects in 25.4 s (first run only: cached for the next runs)"]
    assert [r.getMessage() for r in caplog.records] == (lines if handler else [])
    assert capsys.readouterr().err == ("" if handler else "\n".join(lines) + "\n")


class _Process:
    """A background compile's process as wait_ahead sees it: running until waited for, or over."""

    def __init__(self, running: bool):
        self.running, self.waited = running, False

    def poll(self):
        return None if self.running else 0

    def wait(self):
        self.waited, self.running = True, False
        return 0


def test_work_while_waiting_runs_during_a_compile_and_only_then(monkeypatch):
    done: list[str] = []
    monkeypatch.setattr(compiled, "_IDLE", [])
    monkeypatch.setattr(compiled, "_AHEAD", {})
    compiled.while_waiting(lambda: done.append("dropped"))  # nothing under way: dropped
    proc = _Process(running=True)
    compiled._AHEAD["kernel"] = proc
    compiled.while_waiting(lambda: done.append("first"))
    compiled.while_waiting(lambda: 1 / 0)  # a failure is only a lost head start
    compiled.while_waiting(compiled.import_modules(("json", "csv")))
    compiled.while_waiting(lambda: done.append("second"))
    compiled.wait_ahead()
    # in order, before the wait; the process waited for, nothing left pending
    assert done == ["first", "second"] and proc.waited and not compiled.pending() and compiled._IDLE == []
    # a compile over before the wait: the work is not done (it would only delay the process)
    compiled._AHEAD["kernel"] = _Process(running=False)
    compiled.while_waiting(lambda: done.append("late"))
    compiled.wait_ahead()
    assert done == ["first", "second"] and compiled._IDLE == []


def test_a_background_compile_nothing_waited_for_ends_with_the_command(monkeypatch):
    # an interrupted command (SIGTERM reaches its process alone) must not leave its compile running
    monkeypatch.setattr(compiled, "_IDLE", [])
    monkeypatch.setattr(compiled, "_AHEAD", {})
    running = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    over = subprocess.Popen([sys.executable, "-c", "pass"])
    over.wait()
    compiled._AHEAD.update({"kernel": running, "other": over})
    compiled.while_waiting(lambda: None)
    compiled.stop_ahead()
    assert running.returncode == -15 and over.returncode == 0  # (ended by SIGTERM; one already over untouched)
    assert not compiled.pending() and compiled._IDLE == []
    compiled.stop_ahead()  # (nothing left: nothing to do)
