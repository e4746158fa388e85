"""What a first run compiles ahead from the scene alone (pipeline.model.ahead): the kernel's background compile
from the scene's stand-in arguments, and the Python entry points compiled while the process waits for it,
only then; a scene whose stand-ins cannot be made starts nothing. (That the stand-ins' signatures are those
of the real calls: tests/model/test_kernel_inputs.py and tests/model/test_compiled.py.)"""

from __future__ import annotations

import pytest

from pipeline.config.loading import load_scene, shipped_scenes
from pipeline.model import ahead, compiled
from pipeline.model import dynamics as dyn
from pipeline.model import kernel_inputs


class _Running:
    """A background compile's process that runs until waited for."""

    def poll(self):
        return None

    def wait(self):
        return 0


@pytest.fixture
def scene():
    return load_scene(shipped_scenes()["paper-2009-identified"])


def test_the_kernel_compiles_ahead_and_the_entry_points_while_waiting(scene, monkeypatch):
    started: list = []
    compiled_now: list = []
    monkeypatch.setattr(compiled, "_AHEAD", {})
    monkeypatch.setattr(compiled, "_IDLE", [])

    def start(*args):  # (as dynamics.compile_kernel_ahead does when nothing has the kernel: a process runs)
        started.append(compiled.signature(dyn._integrate, dyn.kernel_arguments(*args)))
        compiled._AHEAD["kernel"] = _Running()
        return True

    monkeypatch.setattr(ahead.dyn, "compile_kernel_ahead", start)
    monkeypatch.setattr(ahead, "compile_entry_points", lambda eps, **kw: compiled_now.extend(f for f, _ in eps))
    ahead.compile_kernel_ahead(scene)
    # the kernel for the scene's stand-in arguments, started at once, and its leaf callees compiled at once, the
    # last it asks for first (the background compile then loads them); the entry points not yet
    assert started == [compiled.signature(dyn._integrate, dyn.kernel_arguments(
        *kernel_inputs.stand_in_arguments(scene)))]
    assert [f.py_func.__name__ for f in compiled_now] == ["stiffness_cap", "knot_extrema"]
    compiled.wait_ahead()  # the first integration waits: the entry points are compiled meanwhile
    # (what every run's summary calls first, then what only the statics map calls)
    assert [f.py_func.__name__ for f in compiled_now[2:]] == ["separation_at", "disk_history", "_path",
                                                              "_rhs_python"]
    assert not compiled.pending()


def test_nothing_to_wait_for_compiles_nothing_ahead(scene, monkeypatch):
    # the kernel cached or compiled (or HDI_COMPILE_AHEAD=0): no process, so no work queued for a wait
    compiled_now: list = []
    monkeypatch.setattr(compiled, "_AHEAD", {})
    monkeypatch.setattr(compiled, "_IDLE", [])
    monkeypatch.setattr(ahead.dyn, "compile_kernel_ahead", lambda *args: None)
    monkeypatch.setattr(ahead, "compile_entry_points", lambda eps, **kw: compiled_now.append(eps))
    ahead.compile_kernel_ahead(scene)
    compiled.wait_ahead()
    assert compiled_now == [] and compiled._IDLE == []


def test_a_leaf_that_fails_to_compile_ahead_is_only_a_lost_head_start(scene, monkeypatch):
    # (the background compile compiles it itself; the entry points are still queued for the wait)
    queued: list = []
    monkeypatch.setattr(compiled, "_AHEAD", {"kernel": _Running()})
    monkeypatch.setattr(compiled, "_IDLE", [])
    monkeypatch.setattr(ahead.dyn, "compile_kernel_ahead", lambda *args: True)

    def compile_entry_points(eps, **kw):
        if eps[0][0] is ahead.dyn.stiffness_cap:
            raise RuntimeError("numba: a typing error")
        queued.append(eps)

    monkeypatch.setattr(ahead, "compile_entry_points", compile_entry_points)
    ahead.compile_kernel_ahead(scene)
    assert queued == [] and len(compiled._IDLE) == 1
    compiled.wait_ahead()
    assert [f.py_func.__name__ for f, _ in queued[0]] == ["separation_at", "disk_history", "_path", "_rhs_python"]


def test_an_adopted_early_compile_is_left_its_leaves(scene, monkeypatch):
    # the console script's compile, started before the command's imports, is ahead: this process compiles
    # only the entry points, while it waits
    compiled_now: list = []
    monkeypatch.setattr(compiled, "_AHEAD", {"kernel": _Running()})
    monkeypatch.setattr(compiled, "_IDLE", [])
    monkeypatch.setattr(ahead.dyn, "compile_kernel_ahead", lambda *args: False)
    monkeypatch.setattr(ahead, "compile_entry_points", lambda eps, **kw: compiled_now.extend(f for f, _ in eps))
    ahead.compile_kernel_ahead(scene)
    assert compiled_now == []
    compiled.wait_ahead()
    assert [f.py_func.__name__ for f in compiled_now] == ["separation_at", "disk_history", "_path", "_rhs_python"]


class _Dispatcher:
    """A compiled function's dispatcher that records its compiles (types: the arguments' Python types)."""

    def __init__(self, name: str, log: list):
        self.name, self.log, self.overloads = name, log, {}

    def typeof_pyval(self, value):
        return type(value).__name__

    def compile(self, sig):
        self.log.append(self.name)
        self.overloads[sig] = None


def test_entry_points_compile_while_the_background_compile_runs_and_no_longer(monkeypatch):
    # once the kernel is compiled, the caller would wait for the rest: each is compiled where it is first called
    log: list = []
    done_after = 2

    class Compiling:
        def poll(self):
            return None if len(log) < done_after else 0

    monkeypatch.setattr(compiled, "_AHEAD", {"kernel": Compiling()})
    points = [(_Dispatcher(name, log), (1.0,)) for name in ("a", "b", "c")]
    ahead.compile_entry_points(points, while_compiling=True)
    assert log == ["a", "b"]
    ahead.compile_entry_points(points)  # (not only while compiling: all, those compiled already skipped)
    assert log == ["a", "b", "c"]


def test_a_scene_whose_stand_ins_fail_starts_nothing(scene, monkeypatch):
    # (a rear law that does not compile: the model's assembly says so in its own words, later)
    def fail(scene):
        raise ValueError("air_bearing.rear_law = 'broken': its force does not compile")

    started: list = []
    monkeypatch.setattr(ahead, "stand_in_arguments", fail)
    monkeypatch.setattr(ahead.dyn, "compile_kernel_ahead", lambda *args: started.append(args))
    ahead.compile_kernel_ahead(scene)
    assert started == []
