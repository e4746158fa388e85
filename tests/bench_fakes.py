"""Fakes for the bench's row recording (benchmarks/common.py), shared by the bench's tests: a load source that
returns given 1-minute loads in turn, and fixed reference times, so a row's load fields are known."""

from __future__ import annotations

import pytest

from benchmarks import common


class FakeLoad:
    """A load source returning the given 1-minute loads in turn, on ``cpus`` CPUs."""

    def __init__(self, loads: list[float], cpus: int = 2) -> None:
        self.loads, self.cpus = list(loads), cpus

    def __call__(self) -> dict[str, float]:
        return {"load_1min": self.loads.pop(0), "cpus": self.cpus}


def use_fake_load(monkeypatch: pytest.MonkeyPatch, loads: list[float], cpus: int = 2) -> None:
    """Rows recorded from now on read ``loads`` in turn and the reference times 0.01 s (compiled) and 0.02 s
    (Python), from a clean start (no row started)."""
    monkeypatch.setattr(common, "LOAD_SOURCE", FakeLoad(loads, cpus))
    monkeypatch.setattr(common, "REFERENCE_SOURCE", lambda: {"ref_compiled_s": 0.01, "ref_python_s": 0.02})
    monkeypatch.setattr(common, "_row_start", None)
    monkeypatch.setattr(common, "_reference", {})
