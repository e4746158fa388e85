"""The first run's kernel compile started by the console script before its imports (pipeline.model.first_run,
pipeline.launch): which command lines name a scene, the adoption of that compile by the runner's compile-ahead
when the signatures agree (and its end otherwise, or when nothing adopts it), and, end to end, a first run in
which the kernel is compiled once, by that process, and found in the cache afterwards."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from pipeline.model import ahead, compiled, first_run

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("argv, expected", [
    (["run", "configs/paper-2009.toml"], ("configs/paper-2009.toml", [])),
    (["sweep", "sweep-3x3", "--set", "contact.k=0.5", "--out", "x", "--set=tfc.protrusion_nm=9", "-q"],
     ("sweep-3x3", ["contact.k=0.5", "tfc.protrusion_nm=9"])),
    (["identify", "a.toml", "--workers", "2", "--write-scene", "b.toml", "--force"], ("a.toml", [])),
    (["roughness", "scene.toml"], ("scene.toml", [])),
    # not a scene's command: help, version, AFM files, options first, two inputs, nothing
    (["run", "a.toml", "--help"], None), (["--version"], None), (["run", "a.toml", "--help-keys"], None),
    (["roughness", "scan.spm"], None), (["-q", "run", "a.toml"], None), (["run", "a.toml", "b.toml"], None),
    (["run"], None), ([], None),
])
def test_the_scene_of_a_command_line(argv, expected):
    assert first_run.scene_arguments(argv) == expected


class _Dispatcher:
    """A stand-in of the kernel's dispatcher: its name, types of its own, nothing compiled or cached."""

    py_func = SimpleNamespace(__module__=first_run.KERNEL[0], __name__=first_run.KERNEL[1])

    overloads: dict = {}

    @staticmethod
    def typeof_pyval(value):
        return type(value).__name__


def _early(tmp_path: Path, key: tuple | None, seconds: float = 30.0) -> first_run.Early:
    """A process standing in for the console script's compile: its key written (unless None) in its folder,
    with a leftover of its temporary write beside it, then it runs."""
    folder = tmp_path / "early"
    folder.mkdir()
    (folder / "key.pkl.123.tmp").write_bytes(b"")
    early = first_run.Early(subprocess.Popen([sys.executable, "-c", f"import time; time.sleep({seconds})"]),
                            str(folder))
    if key is not None:
        Path(early.key_path).write_bytes(pickle.dumps(key))
    return early


@pytest.fixture
def clean(monkeypatch):
    monkeypatch.setattr(compiled, "_AHEAD", {})
    monkeypatch.setattr(compiled, "_IDLE", [])
    monkeypatch.setattr(compiled, "_EARLY", None)
    monkeypatch.setattr(compiled, "is_cached", lambda dispatcher, sig: False)
    monkeypatch.delenv("HDI_COMPILE_AHEAD", raising=False)


def test_the_runner_adopts_the_early_compile_of_the_same_signature(tmp_path, clean, monkeypatch):
    said: list = []
    monkeypatch.setattr(compiled.progress, "compile_notice", lambda what, seconds=None: said.append((what, seconds)))
    args = (1.5, 2)
    key = (*first_run.KERNEL, compiled.signature(_Dispatcher, args))
    early = _early(tmp_path, key, seconds=0.5)
    compiled.adopt_early(early)
    compiled.adopt_early(None)  # (nothing started: the one handed over stays)
    # no process of its own (so it says it started none): the early one is the compile under way, said once
    assert compiled.compile_ahead(_Dispatcher, args, "the kernel") is False
    proc = early.proc
    assert compiled._AHEAD == {key: proc} and compiled._EARLY is None
    assert said == [("the kernel in a background process", None)]  # (no time promised)
    assert not os.path.exists(early.folder)
    compiled.wait_ahead()
    assert proc.returncode == 0 and not compiled.pending()
    # then the time it took, measured here from the notice: the early process sleeps 0.5 s from its start
    assert len(said) == 2 and said[1][0] == "the kernel in a background process" and 0.0 < said[1][1] < 60.0


def test_an_early_compile_of_another_signature_is_stopped(tmp_path, clean, monkeypatch):
    started: list = []
    early = _early(tmp_path, (*first_run.KERNEL, ("float64",)))
    monkeypatch.setattr(compiled.subprocess, "Popen", lambda *a, **k: started.append(a) or "own")
    compiled.adopt_early(early)
    assert compiled.compile_ahead(_Dispatcher, (1.5, 2), "the kernel") is True
    # the early process compiles what nobody asks for: ended (SIGTERM), and this process starts its own
    assert early.proc.returncode == -15 and len(started) == 1 and list(compiled._AHEAD.values()) == ["own"]
    assert not os.path.exists(early.folder) and compiled._EARLY is None


def test_an_early_compile_that_loaded_no_scene_is_not_waited_for(tmp_path, clean, monkeypatch):
    early = _early(tmp_path, None, seconds=0.2)  # (it ends without a key: the scene did not load)
    monkeypatch.setattr(compiled.subprocess, "Popen", lambda *a, **k: "own")
    compiled.adopt_early(early)
    compiled.compile_ahead(_Dispatcher, (1.5, 2), "the kernel")
    assert early.proc.returncode == 0 and list(compiled._AHEAD.values()) == ["own"]
    assert not os.path.exists(early.folder)


def test_an_early_compile_nothing_adopted_ends_with_the_command(tmp_path, clean):
    early = _early(tmp_path, (*first_run.KERNEL, ("float64",)))
    compiled.adopt_early(early)
    compiled.stop_early()
    assert early.proc.returncode == -15 and compiled._EARLY is None and not os.path.exists(early.folder)
    compiled.stop_early()  # (nothing left: nothing to do)


def test_the_early_compile_writes_its_key_in_a_private_folder_of_its_own(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))  # (empty: a first run)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr(first_run.tempfile, "tempdir", None)  # (TMPDIR read again)
    monkeypatch.delenv("HDI_COMPILE_AHEAD", raising=False)
    commands: list = []
    monkeypatch.setattr(first_run.subprocess, "Popen", lambda cmd, **k: commands.append(cmd) or "proc")
    early = first_run.start(["run", "paper-2009", "--set", "contact.k=0.5"])
    # a new folder only this user may enter (mkdtemp: no other process can have taken its name), empty
    # until the process writes its key there, and the process is told that path
    folder = Path(early.folder)
    assert early.proc == "proc" and folder.parent == tmp_path and folder.name.startswith("hdi-kernel-")
    assert folder.stat().st_mode & 0o777 == 0o700 and list(folder.iterdir()) == []
    assert early.key_path == str(folder / first_run.KEY_FILE)
    guard, call = commands[0][-1].splitlines()[:2]
    # (first: it ignores the terminal's group signals and dies with this process, started from its main thread)
    assert guard == f"from pipeline.interrupts import in_background; in_background({os.getpid()})"
    assert call.endswith(f"compile_scene_kernel('paper-2009', ['contact.k=0.5'], {early.key_path!r})")
    early.discard()
    assert not folder.exists()


def test_no_early_compile_when_the_kernel_is_cached_or_ahead_is_off(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(first_run.subprocess, "Popen", lambda *a, **k: pytest.fail("started a compile"))
    monkeypatch.setenv("HDI_COMPILE_AHEAD", "0")
    assert first_run.start(["run", "paper-2009"]) is None
    monkeypatch.delenv("HDI_COMPILE_AHEAD")
    # an index of the kernel where numba writes it (any signature): not a first run
    module, name = first_run.KERNEL
    folder = Path(first_run.cache_folder(module, str(tmp_path))) / "model_0"
    folder.mkdir(parents=True)
    (folder / f"dynamics.{name}-319.py311.nbi").write_bytes(b"")
    assert first_run.kernel_cached() and first_run.start(["run", "paper-2009"]) is None


#: The early compile process's work for every shipped scene, its compile left out: which heavy packages it imported
EARLY_IMPORTS = """
import pickle, sys
from pipeline.model import ahead, compiled
from pipeline.config.loading import shipped_scenes
compiled.compile_quietly = lambda dispatcher, sig: None
keys = 0
for name, path in shipped_scenes().items():
    key_path = sys.argv[1] + "/" + name + ".pkl"
    ahead.compile_scene_kernel(str(path), [], key_path)
    keys += pickle.load(open(key_path, "rb"))[:2] == ("pipeline.model.dynamics", "_integrate")
print(keys, len(shipped_scenes()), [m for m in ahead.NOT_IMPORTED_EARLY if m in sys.modules])
"""


def test_the_early_compile_process_imports_none_of_what_only_the_command_line_needs(tmp_path):
    # xarray, pandas, scipy's interpolate and special: ~3.5 s of CPU in a fresh clone before its compile starts
    done = subprocess.run([sys.executable, "-c", EARLY_IMPORTS, str(tmp_path)], capture_output=True, text=True,
                          timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    keys, scenes, imported = done.stdout.split(" ", 2)
    assert int(scenes) >= 8 and keys == scenes  # (every shipped scene's key written: its stand-ins were made)
    assert imported.strip() == "[]"
    assert set(ahead.NOT_IMPORTED_EARLY) >= {"xarray", "scipy.interpolate"}


#: A console script that says which background compiles its run waited for (the first statement of each one's code)
SPY = """
import sys
from pipeline.model import compiled
_wait = compiled.wait_ahead
def _spy():
    for proc in compiled._AHEAD.values():
        print("waited for:", proc.args[-1].splitlines()[1].split(";")[0], file=sys.stderr)  # (after its guard)
    _wait()
compiled.wait_ahead = _spy
"""


@pytest.mark.slow  # (the kernel's compile in an empty cache: ~15-30 s on the shared 2 cores)
def test_a_first_run_compiles_the_kernel_once_in_the_process_the_console_script_started(tmp_path, monkeypatch):
    cache = tmp_path / "numba"
    env = {k: v for k, v in os.environ.items() if k != "HDI_COMPILE_AHEAD"}
    env.update(NUMBA_CACHE_DIR=str(cache))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    assert not first_run.kernel_cached()
    code = SPY + "from pipeline.launch import entry; sys.argv = ['hdi'] + sys.argv[1:]; entry()"
    done = subprocess.run([sys.executable, "-c", code, "simulate", "paper-2009", "--set", "contact.k=0.978",
                           "--set", "solver.duration_ms=0.8", "--set", "solver.transient_ms=0.3",
                           "--out", str(tmp_path / "out")], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    # said once, as a background compile; this process never compiled the kernel itself (numba's compile
    # event would have said "compiling the dynamics kernel ... (first run only", without "background")
    lines = [ln for ln in done.stderr.splitlines() if "compiling the dynamics kernel" in ln]
    assert len(lines) == 1 and "in a background process" in lines[0], done.stderr
    # and the process the run waited for is the console script's, started before its imports
    waited = [ln for ln in done.stderr.splitlines() if ln.startswith("waited for: ")]
    assert waited == ["waited for: from pipeline.model.ahead import compile_scene_kernel"], done.stderr
    assert first_run.kernel_cached()
    assert (tmp_path / "out" / "summary.nc").is_file()


def test_a_background_process_writes_what_its_call_writes_and_skips_the_teardown(tmp_path):
    # the call's file is complete, the exit code 0, and the interpreter's teardown (here: an atexit handler,
    # as numba and llvmlite register; 0.34-0.40 s after a kernel's compile) never runs
    done, teardown = tmp_path / "done.txt", tmp_path / "teardown.txt"
    call = (f"import atexit; atexit.register(lambda: open({str(teardown)!r}, 'w').write('ran'))\n"
            f"with open({str(done)!r}, 'w') as f: f.write('x' * 100000)")
    assert first_run.background_process(call).wait(timeout=60) == 0
    assert done.read_text() == "x" * 100000 and not teardown.exists()
    # a call that fails ends the usual way: exit code 1, its traceback to the null device
    assert first_run.background_process("raise ValueError('no cache entry')").wait(timeout=60) == 1
