"""The bench's row recording on a shared machine (benchmarks/common.py, benchmarks/run.py):
every row carries the load at its start and end and the CPU count, rows started above 0.75 x CPUs are
flagged noisy, and ``BENCH_STUDY=0`` leaves the study module out of the selection without running it."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

from benchmarks import common, run


class FakeLoad:
    """A load source returning the given 1-minute loads in turn, on ``cpus`` CPUs."""

    def __init__(self, loads: list[float], cpus: int = 2) -> None:
        self.loads, self.cpus = list(loads), cpus

    def __call__(self) -> dict[str, float]:
        return {"load_1min": self.loads.pop(0), "cpus": self.cpus}


@pytest.fixture
def fake_load(monkeypatch: pytest.MonkeyPatch):
    def use(loads: list[float], cpus: int = 2) -> None:
        monkeypatch.setattr(common, "LOAD_SOURCE", FakeLoad(loads, cpus))
        monkeypatch.setattr(common, "_row_start", None)
    return use


def test_row_records_load_at_start_and_end(fake_load, capsys: pytest.CaptureFixture[str]) -> None:
    fake_load([0.4, 1.1])
    common.row_start()
    results: list[dict] = []
    row = common.record(results, "row", [0.3, 0.1, 0.2], target_s=1.0)
    assert results == [row]
    assert (row["median_s"], row["min_s"], row["max_s"], row["n"]) == (0.2, 0.1, 0.3, 3)  # timings untouched
    assert (row["load_start"], row["load_end"], row["cpus"]) == (0.4, 1.1, 2)
    assert row["noisy"] is False and "noisy_reason" not in row
    out = capsys.readouterr().out
    assert "load 0.40->1.10/2" in out and "NOISY" not in out


def test_row_above_threshold_is_flagged(fake_load, capsys: pytest.CaptureFixture[str]) -> None:
    # 2 CPUs: the limit is 0.75 x 2 = 1.5 (the load 1.5); 1.6 at the start flags the row
    fake_load([1.6, 1.2])
    common.row_start()
    row = common.record([], "busy row", [0.01])
    assert row["noisy"] is True
    assert "1.60 at the start > 1.5" in row["noisy_reason"]
    assert "NOISY" in capsys.readouterr().out


def test_threshold_scales_with_cpus_and_uses_the_start(fake_load) -> None:
    # 4 CPUs: limit 3.0, so 2.9 at the start is quiet, even though the row's own load raised the end to 3.5
    fake_load([2.9, 3.5, 3.1], cpus=4)
    common.row_start()
    results: list[dict] = []
    first = common.record(results, "first", [0.01])
    assert first["noisy"] is False and first["load_end"] == 3.5
    # the next row starts where the first ended (3.5 > 3.0): flagged
    second = common.record(results, "second", [0.01])
    assert (second["load_start"], second["load_end"], second["noisy"]) == (3.5, 3.1, True)


def test_load_sample_is_this_machine() -> None:
    s = common.load_sample()
    assert s["load_1min"] >= 0.0 and 1 <= s["cpus"] <= (os.cpu_count() or 1)


def test_bench_study_0_leaves_the_studies_out() -> None:
    names = [p.stem for p in (Path(run.__file__).parent).glob("bench_*.py")]
    assert "bench_study" in names and "bench_study" in run.STUDY_MODULES
    assert run.study_enabled({}) and run.study_enabled({"BENCH_STUDY": "1"})
    assert not run.study_enabled({"BENCH_STUDY": "0"})
    everything = run.selected_modules(names)
    assert everything == sorted(names)
    without = run.selected_modules(names, study=run.study_enabled({"BENCH_STUDY": "0"}))
    assert without == sorted(n for n in names if n != "bench_study")
    assert run.selected_modules(names, only="study", study=False) == []
    assert run.selected_modules(names, only="dmw") == ["bench_dmw"]


def test_main_does_not_run_a_left_out_module(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """With BENCH_STUDY=0 main imports no study module: a run of only 'study' writes an empty result."""
    imported: list[str] = []
    monkeypatch.setattr(run.importlib, "import_module", lambda name: imported.append(name))
    monkeypatch.setenv("BENCH_STUDY", "0")
    out = tmp_path / "b.json"
    monkeypatch.setattr(sys, "argv", ["run", "--only", "study", "--out", str(out)])
    run.main()
    assert imported == []
    data = json.loads(out.read_text())
    assert data["results"] == [] and data["meta"]["study"] is False
