"""The ``hdi`` command (pipeline/cli.py) through :func:`pipeline.cli.main`: a stage run prints where its dataset
is and exits 0, a second run recomputes nothing (the file is not rewritten); bad input is exit 2 with one line
``hdi STAGE: error: ...`` naming the file and key; ``--help-keys`` prints a section of the schema; the help
lists every stage of the registry and ``run``; argparse's own errors exit 2."""

from __future__ import annotations

import re

import pytest

from pipeline import cli, runner
from pipeline.config.loading import shipped_scenes


def test_a_stage_prints_its_dataset_and_a_second_run_recomputes_nothing(tmp_path, paper_config, capsys):
    out = tmp_path / "out"
    assert cli.main(["dmw", str(paper_config), "--out", str(out), "-q"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed == [f"{'dmw':>10}: {out / 'dmw.nc'}"]
    first = (out / "dmw.nc").stat().st_mtime_ns
    assert cli.main(["dmw", str(paper_config), "--out", str(out), "-q"]) == 0
    assert (out / "dmw.nc").stat().st_mtime_ns == first
    # an override that the stage reads makes it current again
    assert cli.main(["dmw", str(paper_config), "--out", str(out), "-q", "--set", "dmw.seed=5"]) == 0
    assert (out / "dmw.nc").stat().st_mtime_ns != first


@pytest.mark.parametrize("args, message", [
    (["--set", "dmw.rms_um=0.3"], r"dmw\.rms_um: wrong unit 'um'; expected 'nm'"),   # a key in the wrong unit
    (["--set", "dmw.rms_nm=-1"], r"--set dmw\.rms_nm=-1: dmw\.rms_nm = -1: expected a number in \[0, 1000\] nm"),
    (["--set", "nonsense"], r"--set 'nonsense': expected section\.key=value")],
    ids=["wrong-unit", "out-of-range", "no-equals-sign"])
def test_bad_input_is_one_line_with_exit_2(tmp_path, paper_config, capsys, args, message):
    assert cli.main(["dmw", str(paper_config), "--out", str(tmp_path / "out"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hdi dmw: error: ")
    assert re.search(message, err[0]), err[0]
    assert not (tmp_path / "out" / "dmw.nc").exists()


def test_a_missing_scene_file_and_two_scene_files_are_one_line(tmp_path, paper_config, capsys):
    assert cli.main(["dmw", str(tmp_path / "missing.toml"), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err  # one line: the path tried and the shipped scenes a name could mean
    assert err.startswith(f"hdi dmw: error: {tmp_path / 'missing.toml'}: scene file does not exist")
    assert err.count("\n") == 1 and err.endswith("shipped scene: " + ", ".join(shipped_scenes()) + "\n")
    assert cli.main(["dmw", str(paper_config), str(paper_config)]) == 2
    assert capsys.readouterr().err.startswith("hdi dmw: error: hdi dmw: expected one scene file, got ")


def test_help_keys_prints_a_section_and_an_unknown_section_is_refused(capsys):
    with pytest.raises(SystemExit) as done:
        cli.main(["--help-keys", "dmw"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert "rms_nm" in text and "sample_rate_mhz" in text and "flying_height_nm" not in text
    with pytest.raises(SystemExit) as done:
        cli.main(["--help-keys", "nosuchsection"])
    assert done.value.code == 2 and capsys.readouterr().err.startswith("hdi: error: ")


def test_the_help_lists_every_stage_and_run_and_a_bad_stage_exits_2(capsys):
    with pytest.raises(SystemExit) as done:
        cli.main(["--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    for name in runner.registry():
        assert f"\n  {name:<11} " in text, name
    assert "\n  run         the main job: roughness dmw interface" in text
    with pytest.raises(SystemExit) as done:
        cli.main(["nosuchstage", "x.toml"])
    assert done.value.code == 2 and "invalid choice: 'nosuchstage'" in capsys.readouterr().err


# ------------------------------------------------------------------ a signal is answered before what it broke
class _GoneStream:
    """A stderr whose reader is gone: the terminal closed (EIO), or ``| tee log`` ended by the same hang-up."""

    def write(self, text):
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self):
        raise BrokenPipeError(32, "Broken pipe")


@pytest.mark.parametrize("failure", [ValueError("dask scheduler tcp://h:1: lost with 3 of 4 tasks unfinished"),
                                     RuntimeError("BrokenProcessPool"), BrokenPipeError(32, "Broken pipe")],
                         ids=["cluster-error", "unexpected", "broken-pipe"])
def test_a_signal_that_made_the_stage_fail_is_what_the_command_answers(tmp_path, paper_config, capsys, monkeypatch,
                                                                        failure):
    """A hang-up kills the workers (or the reader of the pipe) as well as hdi: the error that follows is its
    effect. It was ``error: ...`` with exit 2, or a traceback, not the signal's line and 129."""
    import signal
    from pipeline import interrupts

    def build(self, targets, force=False):
        interrupts._PENDING.append(signal.SIGHUP)
        raise failure

    monkeypatch.setattr(runner.Runner, "build", build)
    assert cli.main(["sweep", str(paper_config), "--out", str(tmp_path), "-q"]) == 129
    assert capsys.readouterr().err.strip().splitlines() == [
        "hdi sweep: hung up (SIGHUP: the terminal closed); finished work is kept, run again to resume"]
    assert interrupts.pending() is None


def test_a_hang_up_under_a_pipe_is_exit_129_though_its_line_cannot_be_written(tmp_path, paper_config, monkeypatch):
    """``hdi sweep ... 2>&1 | tee log`` and the terminal closed: the last line's write failed with a broken
    pipe, and the command ended with exit 1 (a traceback no one saw), not 129."""
    import signal
    import sys
    from pipeline import interrupts
    from pipeline.interrupts import Terminated

    def build(self, targets, force=False):
        interrupts._PENDING.append(signal.SIGHUP)
        raise Terminated(signal.SIGHUP)

    monkeypatch.setattr(runner.Runner, "build", build)
    monkeypatch.setattr(sys, "stderr", _GoneStream())
    assert cli.main(["sweep", str(paper_config), "--out", str(tmp_path), "-q"]) == 129
    assert interrupts.pending() is None
