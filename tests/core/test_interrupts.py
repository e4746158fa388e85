"""Signals (pipeline.interrupts): a SIGTERM that a C library's error check caught and dropped is raised again
at the next check, the handler is never left ignored and is restored on leaving, and a second signal while the
first unwinds does not cut the clean-up short."""

from __future__ import annotations

import os
import signal

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
