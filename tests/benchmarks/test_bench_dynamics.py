"""The bench's own compiled helpers take the arguments the kernel's functions take: the right-hand-side row
(benchmarks/bench_dynamics.py: the step's inlined right-hand side and ``forces.rhs_slots``) and the compile
profile's step (benchmarks/compile_time.py), built from the kernel's arguments as the bench builds them. A slot
added to the kernel (as the frictional heat's, which is the loop's alone) must not break a bench row."""

from __future__ import annotations

import inspect

import numpy as np

from benchmarks import bench_dynamics, compile_time
from pipeline.model import dynamics as dyn
from pipeline.model import forces, kernel_inputs, stepper
from pipeline.model.state import N_STATE
from slider_scenes import ALL, NM, build, make_scene


def arity(dispatcher) -> int:
    return len(inspect.signature(dispatcher.py_func).parameters)


def test_the_bench_helpers_take_the_kernels_slots():
    model = build(make_scene(ALL, dmw={"rms_nm": 0.163}))
    p, tab, var = kernel_inputs.run_parameters(model, 11 * NM)
    slots = dyn._slots(tab, var)
    assert len(slots) == len(dyn.SLOTS) == arity(forces.rhs_slots) - 5  # (t, y, p, in_contact, out)
    assert arity(bench_dynamics._inlined) == 4 + len(slots)             # (T, Y, C, p)
    assert arity(bench_dynamics._out_of_line) == 5 + len(slots)         # (T, Y, C, p, out)
    args = dyn.kernel_arguments(np.zeros(N_STATE), dyn.Grid(1e-3, np.zeros(3)), p, tab, var,
                                dyn.Solver(1e-6, model.atol, 1e-7, 10))
    assert len(args) == arity(dyn._integrate)
    step_args = compile_time._step_arguments(args)
    assert len(step_args) == arity(stepper.step)
    # the step's slots are the kernel's slots (not the loop's heating slot), in order
    assert all(a is b for a, b in zip(step_args[-len(slots):], args[8:8 + len(slots)]))
