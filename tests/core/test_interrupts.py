"""Signals (pipeline.interrupts): a SIGTERM that a C library's error check caught and dropped is raised again
at the next check, the handler is never left ignored and is restored on leaving, and a second signal while the
first unwinds does not cut the clean-up short; SIGQUIT and SIGUSR1/2 answered like SIGTERM, the group signals
blocked for the processes a command starts, and its background processes dying with it."""

from __future__ import annotations

import os
import signal
import sys

import pytest


def test_a_signal_swallowed_where_it_was_raised_is_raised_again_at_the_next_check():
    from pipeline import interrupts
    with interrupts.handling():
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10_000):  # (the handler runs between two of these bytecodes)
                pass
        except BaseException:        # what a C library's error check did with it
            pass
        assert signal.getsignal(signal.SIGTERM) is interrupts._handler   # never left ignored
        with pytest.raises(interrupts.Terminated):
            interrupts.check()
        assert interrupts.pending() == signal.SIGTERM
        interrupts.answered()
        interrupts.check()           # answered: nothing more to raise
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL


def test_a_second_signal_while_the_first_unwinds_does_not_cut_the_clean_up_short():
    from pipeline import interrupts
    cleaned = []
    with interrupts.handling():
        with pytest.raises(interrupts.Terminated):
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                for _ in range(10_000):
                    pass
            finally:
                os.kill(os.getpid(), signal.SIGTERM)   # (a batch system's repeated cancel)
                for _ in range(10_000):
                    pass
                cleaned.append(True)
        assert cleaned == [True] and interrupts.pending() == signal.SIGTERM
        interrupts.answered()


def test_sighup_unwinds_like_sigterm_and_names_itself():
    """A closed terminal (SIGHUP) is answered like SIGTERM: Terminated carrying the signal, exit status 129."""
    from pipeline import interrupts
    old = signal.signal(signal.SIGHUP, signal.SIG_DFL)  # (as from a terminal: a session under nohup ignores it)
    try:
        _sighup_unwinds(interrupts)
    finally:
        signal.signal(signal.SIGHUP, old)


def _sighup_unwinds(interrupts) -> None:
    with interrupts.handling():
        assert signal.getsignal(signal.SIGHUP) is interrupts._handler
        with pytest.raises(interrupts.Terminated) as caught:
            os.kill(os.getpid(), signal.SIGHUP)
            for _ in range(10_000):
                pass
        assert interrupts.signal_of(caught.value) == signal.SIGHUP and interrupts.pending() == signal.SIGHUP
        interrupts.answered()
    assert signal.getsignal(signal.SIGHUP) is signal.SIG_DFL
    assert interrupts.exit_code(signal.SIGHUP) == 129
    assert interrupts.describe(signal.SIGHUP).startswith("hung up (SIGHUP")
    assert interrupts.describe(signal.SIGTERM) == "terminated (SIGTERM)"
    assert interrupts.signal_of(KeyboardInterrupt()) == signal.SIGINT
    assert interrupts.signal_of(interrupts.Terminated()) == signal.SIGTERM


def test_a_command_under_nohup_keeps_ignoring_sighup():
    """``nohup hdi ...`` starts with SIGHUP ignored: the handler is not installed over that, and the
    disposition is the same after the block."""
    from pipeline import interrupts
    old = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with interrupts.handling():
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
            assert signal.getsignal(signal.SIGTERM) is interrupts._handler
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, old)


def test_a_forked_worker_gets_the_default_sighup_back(monkeypatch):
    """A worker forked inside the block must not unwind its copy of the parent on SIGHUP: its default again."""
    from pipeline import interrupts
    monkeypatch.setattr(interrupts, "die_with_parent", lambda parent: None)
    old_int = signal.getsignal(signal.SIGINT)
    old_hup = signal.signal(signal.SIGHUP, signal.SIG_DFL)
    try:
        with interrupts.handling():
            interrupts.default_in_child()
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_DFL
            assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGHUP, old_hup)


# ------------------------------------------------------------------ every signal the same way
@pytest.mark.parametrize("name, code, words", [
    ("SIGQUIT", 131, "quit (SIGQUIT)"), ("SIGUSR1", 138, "ended by SIGUSR1"), ("SIGUSR2", 140, "ended by SIGUSR2")])
def test_sigquit_and_sigusr_unwind_like_sigterm_and_name_themselves(name, code, words):
    """Their default killed the command at once (SIGQUIT with a core dump), leaving the folder lock and the
    staging folder for the next run to clean."""
    from pipeline import interrupts
    signum = getattr(signal, name)
    old = signal.signal(signum, signal.SIG_DFL)
    try:
        with interrupts.handling():
            assert signal.getsignal(signum) is interrupts._handler
            with pytest.raises(interrupts.Terminated) as caught:
                os.kill(os.getpid(), signum)
                for _ in range(10_000):
                    pass
            assert interrupts.signal_of(caught.value) == signum
            interrupts.answered()
        assert signal.getsignal(signum) is signal.SIG_DFL
    finally:
        signal.signal(signum, old)
    assert interrupts.exit_code(signum) == code
    assert interrupts.message("hdi sweep", signum) == f"hdi sweep: {words}; finished work is kept, run again to resume"


def test_an_ignored_signal_stays_ignored_but_sigterm_and_sigint_are_always_answered():
    from pipeline import interrupts
    names = ("SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2", "SIGTERM", "SIGINT")
    old = {n: signal.signal(getattr(signal, n), signal.SIG_IGN) for n in names}
    try:
        with interrupts.handling():
            got = {n: signal.getsignal(getattr(signal, n)) for n in names}
            with interrupts.handling():  # (nested: the console script's around the command's)
                assert signal.getsignal(signal.SIGTERM) is interrupts._handler
            assert signal.getsignal(signal.SIGTERM) is interrupts._handler
        assert {n: signal.getsignal(getattr(signal, n)) for n in names} == dict.fromkeys(names, signal.SIG_IGN)
    finally:
        for n, h in old.items():
            signal.signal(getattr(signal, n), h)
    assert got == {**dict.fromkeys(names[:4], signal.SIG_IGN), "SIGTERM": interrupts._handler,
                   "SIGINT": interrupts._handler}


def test_a_signal_within_deferred_is_recorded_and_not_raised():
    from pipeline import interrupts
    with interrupts.handling():
        with interrupts.deferred():
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10_000):
                pass
            assert interrupts.pending() == signal.SIGTERM
        with pytest.raises(interrupts.Terminated):  # (answered after the block, at the next check)
            interrupts.check()
        interrupts.answered()


def _blocked(tid: int | str = "self") -> int:
    """The blocked-signal mask of thread ``tid`` of this process (``self``: the calling thread), from /proc."""
    path = "/proc/thread-self/status" if tid == "self" else f"/proc/self/task/{tid}/status"
    with open(path) as fh:
        return int(next(line for line in fh if line.startswith("SigBlk:")).split()[1], 16)


def _bits(*signums: int) -> int:
    return sum(1 << (s - 1) for s in signums)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and pthread_sigmask of Linux")
def test_shielded_blocks_the_group_signals_for_what_it_starts_and_loses_none(tmp_path):
    """Threads and processes started within the block keep the terminal's group signals blocked; a signal
    to this process meanwhile is handled all the same (it was ignored here while dask's cluster started)."""
    import subprocess
    import threading
    from pipeline import interrupts
    group = _bits(*interrupts.SHIELDED)
    seen: dict = {}
    old = signal.signal(signal.SIGHUP, signal.SIG_DFL)
    try:
        with interrupts.handling():
            with pytest.raises(interrupts.Terminated) as caught:
                with interrupts.shielded():
                    assert _blocked() & group == group and not _blocked() & _bits(signal.SIGTERM)

                    def started() -> None:
                        seen["thread"] = _blocked()
                        child = subprocess.run([sys.executable, "-c", "print(open('/proc/self/status').read())"],
                                               capture_output=True, text=True, check=True)
                        seen["child"] = int(next(ln for ln in child.stdout.splitlines()
                                                 if ln.startswith("SigBlk:")).split()[1], 16)
                    t = threading.Thread(target=started)
                    t.start()
                    t.join()
                    os.kill(os.getpid(), signal.SIGHUP)  # (a hang-up while the cluster starts)
                    for _ in range(10_000):
                        pass
                for _ in range(10_000):  # (delivered here at the latest, when the mask is put back)
                    pass
            assert interrupts.signal_of(caught.value) == signal.SIGHUP
            interrupts.answered()
    finally:
        signal.signal(signal.SIGHUP, old)
    assert seen["thread"] & group == group and seen["child"] & group == group
    assert not seen["child"] & _bits(signal.SIGTERM)  # (dask's nanny stops its worker with SIGTERM)
    assert not _blocked() & group  # (put back)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG of Linux")
def test_a_background_process_dies_with_its_killed_parent_and_leaves_the_group_signals_to_it(tmp_path):
    """A background compile outlived a killed ``hdi`` (SIGKILL, or a hang-up before the handlers were set)
    for up to its ~27 s of CPU: now it dies with it, and a terminal's Ctrl-C or Ctrl-\\\\ is the parent's."""
    import subprocess
    import time
    import psutil
    call = f"open({str(tmp_path / 'started')!r}, 'w').close(); import time; time.sleep(60)"
    parent = subprocess.Popen([sys.executable, "-c", (
        "import time\n"
        "from pipeline.model.first_run import background_process\n"
        f"print(background_process({call!r}).pid, flush=True)\n"
        "time.sleep(60)\n")], stdout=subprocess.PIPE, text=True)
    child = None
    try:
        child = psutil.Process(int(parent.stdout.readline()))
        deadline = time.monotonic() + 60
        while not (tmp_path / "started").exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        for name in ("SIGINT", "SIGQUIT", "SIGHUP"):  # (what a terminal sends its whole group)
            child.send_signal(getattr(signal, name))
        time.sleep(0.3)
        assert child.is_running() and child.status() != psutil.STATUS_ZOMBIE
        parent.kill()
        parent.wait(timeout=10)
        child.wait(timeout=10)  # (psutil.TimeoutExpired: it outlived its parent)
    finally:
        parent.kill()
        if child is not None and child.is_running():
            child.kill()


def _catches(pid: int, signum: int) -> bool:
    """Whether process ``pid`` has a handler for ``signum`` (its ``SigCgt`` mask, from /proc)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            return bool(int(next(ln for ln in fh if ln.startswith("SigCgt:")).split()[1], 16) & (1 << (signum - 1)))
    except (FileNotFoundError, StopIteration):
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc of Linux")
def test_a_signal_during_the_console_scripts_imports_is_one_line_and_its_exit_code(tmp_path):
    """The console script imports the command line for 1-6 s before the command's handlers were set: a
    SIGTERM then killed it without a line (exit -15), a Ctrl-C printed a KeyboardInterrupt traceback."""
    import subprocess
    import time
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    code = "import sys; sys.argv = ['hdi'] + sys.argv[1:]; from pipeline.launch import entry; entry()"
    proc = subprocess.Popen([sys.executable, "-c", code, "dmw", str(root / "configs" / "paper-2009.toml"), "--out",
                             str(tmp_path / "out")], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    deadline = time.monotonic() + 30
    while not _catches(proc.pid, signal.SIGTERM) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.002)
    proc.send_signal(signal.SIGTERM)  # (at once: the command line is still being imported)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "Traceback" not in err, err
    assert err.strip().splitlines() == ["hdi: terminated (SIGTERM); finished work is kept, run again to resume"]
    assert not (tmp_path / "out").exists()
