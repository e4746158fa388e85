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
