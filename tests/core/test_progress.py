"""Progress of long work: lines with an ETA in a log, a bar on a terminal, -q and -vv."""

from __future__ import annotations

import logging
import os
import re
import sys
import time
import warnings

import pytest

from pipeline import cli, fanout, progress
from pipeline.config.scene import load_scene
from pipeline.config.limits import POLISH_EVALUATIONS
from pipeline.stages import identify
import twin

LINE = re.compile(r"^(\w+)(?: \(([^)]*)\))?: (\d+)/(\d+) (\w+) done, elapsed (\d+:\d\d), ETA (\d+:\d\d|\?)"
                  r"(?: \((.*)\))?$")


def _lines(text: str, label: str) -> list[tuple[int, int, str, str]]:
    """``(k, N, unit, note)`` of every progress line of ``label`` in ``text``."""
    return [(k, n, unit, note) for _, k, n, unit, note, _ in _phase_lines(text, label)]


def _phase_lines(text: str, label: str) -> list[tuple[str, int, int, str, str, int]]:
    """``(phase, k, N, unit, note, elapsed [s])`` of every progress line of ``label`` in ``text``."""
    found = [LINE.match(line) for line in text.splitlines()]
    return [(m[2] or "", int(m[3]), int(m[4]), m[5], m[8] or "",
             int(m[6].split(":")[0]) * 60 + int(m[6].split(":")[1])) for m in found if m and m[1] == label]


class FakeClock:
    """A clock [s] that moves only when told."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def _slow(x: int) -> int:
    time.sleep(0.12)
    return x


@pytest.fixture()
def info_logging():
    """The command line's logging (INFO of ``pipeline`` on stderr), put back as it was afterwards."""
    logger = logging.getLogger("pipeline")
    level, handlers = logger.level, list(logger.handlers)
    cli._logging(0)
    yield logger
    logger.setLevel(level)
    logger.handlers[:] = handlers


def test_a_fan_out_in_a_log_writes_counted_lines_with_an_eta_at_the_interval(monkeypatch, capsys, info_logging):
    monkeypatch.setenv("HDI_PROGRESS_S", "0.2")
    monkeypatch.delenv("CI", raising=False)
    got = []
    with progress.stage("demo"):
        fanout.run_tasks(_slow, [(i,) for i in range(8)], scheduler="synchronous", on_done=got.append)
    assert got == list(range(8))  # (progress is output only)
    err = capsys.readouterr().err
    lines = _lines(err, "demo")
    assert len(lines) >= 3, err  # ~1 s of work at 0.2 s: several lines, then the last
    counts = [k for k, n, unit, _ in lines]
    assert all(n == 8 and unit == "tasks" for _, n, unit, _ in lines)
    assert counts == sorted(counts) and counts[0] < 8 and counts[-1] == 8, counts
    assert "ETA" in err and "\r" not in err  # (no bar written into a log)


def test_progress_counts_from_this_runs_rate_and_says_units_and_notes():
    clock = FakeClock()
    p = progress.Progress(10, unit="batch", label="sweep", initial=4, timer=clock)  # a resumed sweep: 4 done before
    clock.now += 60.0
    p.update(2, note="best objective 0.5")
    assert p.line() == "sweep: 6/10 batches done, elapsed 1:00, ETA 2:00 (best objective 0.5)"
    p.update(5)  # more than foreseen: the total follows
    assert p.line().startswith("sweep: 11/11 batches done") and "ETA 0:00" in p.line()
    budget = progress.Progress(20, unit="evaluation", label="identify")  # a budget, an upper bound
    budget.update(5)
    budget.update(0, note="ended early", total=5)  # ... that ended early: the total follows down
    assert budget.line().startswith("identify: 5/5 evaluations done") and "ETA 0:00" in budget.line()
    assert progress.clock(3725) == "1:02:05"


def test_phases_have_their_own_total_and_eta_and_one_elapsed_clock():
    # each phase has its own total (a total that grew as it ran, 276 -> 293 -> 317, would say nothing) and the
    # elapsed time runs on across phases
    clock = FakeClock()
    p = progress.Progress(5, unit="generation", label="identify", timer=clock)
    p.phase("search", 5, unit="generation")
    clock.now += 50.0
    p.update(note="best objective 3")
    assert p.line() == "identify (search): 1/5 generations done, elapsed 0:50, ETA 3:20 (best objective 3)"
    clock.now += 50.0
    p.update(4)
    p.phase("profiles, round 1 of at most 3", 40, unit="evaluation")
    # (the note goes on: the best objective so far)
    assert p.line() == ("identify (profiles, round 1 of at most 3): 0/40 evaluations done, elapsed 1:40, ETA ? "
                        "(best objective 3)")
    clock.now += 20.0
    p.update(10)  # the ETA from this phase's rate (2 s an evaluation), the elapsed time from the start
    assert p.line().startswith("identify (profiles, round 1 of at most 3): 10/40 evaluations done, elapsed 2:00, "
                               "ETA 1:00")
    p.update(0, total=10)  # a budget that ended early: lowered to what was spent, never raised
    assert p.line().startswith("identify (profiles, round 1 of at most 3): 10/10 evaluations done, elapsed 2:00")


def test_the_display_is_a_bar_on_a_terminal_lines_elsewhere_and_none_when_quiet_or_nested(monkeypatch,
                                                                                            info_logging):
    monkeypatch.delenv("CI", raising=False)
    assert progress.display() == "lines"  # (pytest's captured stderr is no terminal)
    with progress.Progress(3) as outer:
        assert outer.mode == "lines"
        assert progress.display() == "off"  # an inner count (a generation's fan-out) leaves the display to it
    assert progress.display() == "lines"
    info_logging.setLevel(logging.WARNING)  # hdi -q
    assert progress.display() == "off"


def test_on_a_pseudo_terminal_a_bar_counts_and_log_lines_go_above_it(monkeypatch, info_logging):
    import pty
    import fcntl
    import struct
    import termios
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # (a terminal 100 wide)
    tty = os.fdopen(slave, "w")
    try:
        shown = warnings.showwarning
        monkeypatch.setattr(sys, "stderr", tty)
        monkeypatch.delenv("CI", raising=False)
        with progress.stage("demo"), progress.Progress(3, unit="generation") as bar:
            assert bar.mode == "bar"
            for i in range(3):
                logging.getLogger("pipeline.demo").info("message %d", i)
                bar.update(note=f"best cost {3 - i}")
            warnings.warn("a warning above the bar", UserWarning)
            bar.phase("second", 2, unit="evaluation")  # a phase of its own: the bar counts again, its label says it
            bar.update(2)
        tty.flush()
        monkeypatch.undo()
    finally:
        tty.close()
    text = b""
    while True:
        try:
            chunk = os.read(master, 65536)
        except OSError:  # (the terminal's other end is closed: everything is read)
            break
        if not chunk:
            break
        text += chunk
    os.close(master)
    out = text.decode()
    assert "3/3" in out and "best cost 1" in out and "demo" in out, out
    assert "demo (second)" in out and "2/2" in out and "evaluation" in out, out
    # each message is a line of its own (tqdm cleared the bar before it and drew it again after)
    rows = re.split(r"[\r\n]+", out)
    expected = {"message 0", "message 1", "message 2", "UserWarning: a warning above the bar"}
    assert expected <= {r.strip() for r in rows}, rows
    assert sys.stderr is not tty and warnings.showwarning is shown  # (both given back)


SCENE = twin.scene_text("""
targets = ["contact_force"]
contact_force_mn = 0.1
population = 4
generations = 4
profile_points = 3
batch_size = 4
realisations = 1
""")


def _slow_batch(base, params, rows, protrusions, inputs):
    """A stand-in for the slider (outputs linear in the parameters) that takes its time."""
    time.sleep(0.1)
    return twin.stub_records(rows, protrusions, lambda x: {
        "fhm_bv": 10.0 * float(x[0]), "contact_fraction": 1.0, "min_clearance": -0.1, "contact_force": float(x[1]),
        "interference": 0.5, "mean_pressure": 400.0})


def test_hdi_identify_in_a_log_counts_generations_with_the_best_cost_and_q_and_vv(tmp_path, paper_config,
                                                                                  monkeypatch, capsys):
    path = tmp_path / "twin.toml"
    path.write_text(SCENE.format(paper=paper_config))
    assert load_scene(path)["identify"]["generations"] == 4
    monkeypatch.setattr(identify, "evaluate_batch", _slow_batch)
    monkeypatch.setenv("HDI_PROGRESS_S", "0.05")
    monkeypatch.delenv("CI", raising=False)
    logger = logging.getLogger("pipeline")
    level, handlers = logger.level, list(logger.handlers)
    try:
        argv = ["identify", str(path), "--out", str(tmp_path / "out"), "--scheduler", "synchronous"]
        assert cli.main(argv) == 0
        err = capsys.readouterr().err
        lines = _phase_lines(err, "identify")
        gens = [(k, n, note) for phase, k, n, unit, note, _ in lines if phase == "search"]
        assert gens, err
        assert all(n == 4 for _, n, _ in gens)
        counts = [k for k, _, _ in gens]
        # a generation is a 0.1-s batch, the interval 0.05 s: a line or more per generation, then the end
        assert counts == sorted(counts) and len(set(counts)) >= 4 and counts[-1] == 4, counts
        costs = [float(note.removeprefix("best objective ")) for k, _, note in gens if k > 0]
        assert costs and costs == sorted(costs, reverse=True)  # the best so far only improves
        # then the polish of the search's optimum counts its evaluations (a total of its budget, 2 parameters x
        # POLISH_EVALUATIONS, lowered to what it spent when it ends); then each round of profiles counts its
        # evaluations, with a total fixed when it starts (2 parameters x (3 profile points + the optimum) + 2 x 2
        # Jacobian points + 2 x the re-optimisation's budget of 40), lowered to what was spent when the round
        # ends; then the scoring of every evaluation
        phases = list(dict.fromkeys(phase for phase, *_ in lines))
        assert phases[:3] == ["search", "polish", "profiles, round 1 of at most 3"], phases
        assert set(phases) <= {"search", "polish", "scoring",
                               *(f"profiles, round {r} of at most 3" for r in (1, 2, 3))}, phases
        budget = 2 * POLISH_EVALUATIONS
        polish = [(k, n) for ph, k, n, unit, _, _ in lines if ph == "polish"]
        assert all(unit == "evaluations" for ph, _, _, unit, _, _ in lines if ph == "polish")
        assert {n for _, n in polish[:-1]} <= {budget} and polish[-1][0] == polish[-1][1] <= budget, polish
        for phase in (ph for ph in phases if ph.startswith("profiles")):
            evals = [(k, n) for ph, k, n, unit, _, _ in lines if ph == phase]
            assert all(unit == "evaluations" for ph, _, _, unit, _, _ in lines if ph == phase)
            # stable while it runs; the total lowered when the round ends may show on a progress line printed
            # between the lowering and the end line (a loaded host's timer thread), never before a line of the budget
            lowered = [i for i, (_, n) in enumerate(evals) if n != 2 * 4 + 4 + 2 * 40]
            assert {evals[i][1] for i in lowered} <= {evals[-1][1]}, evals
            assert lowered == list(range(len(evals) - len(lowered), len(evals))), evals
            assert evals[-1][0] == evals[-1][1] <= 2 * 4 + 4 + 2 * 40, evals
            assert [k for k, _ in evals] == sorted(k for k, _ in evals)
        # one clock: the elapsed time never goes back from one phase to the next
        elapsed = [e for *_, e in lines]
        assert elapsed == sorted(elapsed), elapsed
        # one name for the objective: the notes and the last line say "best objective", the same number
        assert "best cost" not in err
        final = [line for line in err.splitlines() if "evaluations (" in line and "best objective" in line]
        assert len(final) == 1, err
        import xarray as xr
        ds = xr.open_dataset(tmp_path / "out" / "identify.nc", engine="netcdf4")
        assert f"best objective {ds.attrs['best_objective']:.4g} (evaluation {ds.attrs['best_evaluation']})" in final[0]
        assert lines[-1][4] == f"best objective {ds.attrs['best_objective']:.4g}"
        # -q: no progress and no stage messages; the dataset's path still on stdout
        assert cli.main([*argv, "--force", "-q"]) == 0
        out = capsys.readouterr()
        assert out.err == "" and out.out.strip().endswith("identify.nc")
        # -vv: the debug messages too (the fan-outs of each generation, run in this process)
        assert cli.main([*argv, "--force", "-vv"]) == 0
        err = capsys.readouterr().err
        assert logger.level == logging.DEBUG
        assert "fan-out:" in err and "in this process, one after the other" in err
        assert _lines(err, "identify")
        # the scoring of the evaluations after the profiles is a phase of its own (its end at DEBUG when short)
        assert [n for phase, k, n, *_ in _phase_lines(err, "identify") if phase == "scoring"][-1] == \
            len(evaluations_of(tmp_path / "out"))
    finally:
        logger.setLevel(level)
        logger.handlers[:] = handlers


def evaluations_of(out) -> list:
    """The records of the evaluation store of ``hdi identify`` in ``out``."""
    from pipeline.evaluations import EvaluationStore
    return list(EvaluationStore(out / "identify.evals.jsonl").records)


def test_a_bad_progress_interval_is_one_line(tmp_path, paper_config, monkeypatch, capsys):
    monkeypatch.setenv("HDI_PROGRESS_S", "soon")
    path = tmp_path / "twin.toml"
    path.write_text(SCENE.format(paper=paper_config))
    assert cli.main(["identify", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "hdi identify: error: HDI_PROGRESS_S=soon: expected a number of seconds > 0"
    assert not (tmp_path / "out").exists()


def test_a_short_fan_out_on_a_cluster_says_where_it_runs_and_its_end(monkeypatch, capsys, info_logging):
    # on a cluster a batch shorter than HDI_PROGRESS_S still says where it runs and when it ends (fan-out line, count)
    import operator
    distributed = pytest.importorskip("distributed")
    monkeypatch.delenv("CI", raising=False)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as lc:
        got = []
        with progress.stage("demo"):
            fanout.run_tasks(operator.neg, [(i,) for i in range(4)], scheduler=lc.scheduler_address,
                             on_done=got.append)
    assert sorted(got) == [-3, -2, -1, 0]
    err = capsys.readouterr().err
    assert re.search(r"^fan-out: 4 tasks on the dask scheduler \S+ \(2 worker threads\)$", err, re.M), err
    assert _lines(err, "demo") == [(4, 4, "tasks", "")], err  # the end, though it took well under 30 s
    # the same batch on local threads keeps its short end at DEBUG (the command line's -vv)
    with progress.stage("demo"):
        fanout.run_tasks(operator.neg, [(i,) for i in range(4)], scheduler="threads", workers=2)
    err = capsys.readouterr().err
    assert "fan-out: 4 tasks on 2 threads" in err and _lines(err, "demo") == []


def test_the_end_line_goes_to_the_display_that_owns_it(monkeypatch, info_logging):
    monkeypatch.delenv("CI", raising=False)
    with progress.Progress(3, unit="batch", label="sweep") as outer:
        assert outer.mode == "lines"  # (as in a log)
        with progress.Progress(5) as inner:  # a fan-out inside: its display is the outer one's
            progress.end_line()
        assert inner.mode == "off" and outer.end_line and not inner.end_line
    progress.end_line()  # (no display running: nothing to say)


def test_an_api_call_shows_its_lines_without_logging_and_progress_false_shows_none(monkeypatch, capsys):
    logger = logging.getLogger("pipeline")
    monkeypatch.setattr(logging.getLogger(), "handlers", [])  # (a user's process: pytest's capture handler gone)
    monkeypatch.setattr(logger, "handlers", [])
    monkeypatch.setattr(logger, "level", logging.NOTSET)
    monkeypatch.delenv("CI", raising=False)
    assert progress.display() == "off"  # no logging configured: a bare library call shows nothing
    with progress.shown(True):
        assert logger.level == logging.INFO and len(logger.handlers) == 1
        assert progress.display() == "lines"
        with progress.shown(True):  # (a call inside a call: the outer one decided)
            assert len(logger.handlers) == 1
        with progress.Progress(2, unit="run", label="simulate") as p:
            logging.getLogger("pipeline.demo").info("demo: computing")
            p.update(2)
    assert logger.handlers == [] and logger.level == logging.NOTSET  # (given back)
    err = capsys.readouterr().err
    assert err.splitlines()[0] == "demo: computing"
    assert re.fullmatch(r"simulate: 2/2 runs done, elapsed 0:00, ETA 0:00", err.splitlines()[1]), err
    with progress.shown(False):
        assert progress.display() == "off" and logger.handlers == []
        with progress.Progress(2, label="simulate") as p:
            p.update(2)
    assert capsys.readouterr().err == ""
    # in a Jupyter kernel: a tqdm.auto bar (the widget), though stderr is no terminal
    monkeypatch.setitem(sys.modules, "ipykernel.zmqshell", object())
    with progress.shown(True):
        assert progress.display() == "bar"


def test_a_warning_line_says_it_is_one_and_names_its_stage():
    """"flying run collapsed at 11.8 nm ..." and "/path/dmw.csv: measured DMW rms ..." came with no stage (the
    first with no severity either): a warning names the stage it is given in, once; INFO lines are as written."""
    fmt = progress.LineFormat("%(message)s")

    def line(level: int, text: str) -> str:
        return fmt.format(logging.LogRecord("pipeline.x", level, __file__, 1, text, None, None))

    with progress.stage("dmw"):
        assert line(logging.WARNING, "/d/dmw.csv: measured DMW rms 0.4 nm") == "warning: dmw: /d/dmw.csv: measured DMW rms 0.4 nm"
        assert line(logging.WARNING, "dmw: already named") == "warning: dmw: already named"
        assert line(logging.INFO, "dmw: computing") == "dmw: computing"
    assert line(logging.ERROR, "outside any stage") == "error: outside any stage"
