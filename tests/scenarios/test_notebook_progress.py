"""Progress from Python as a notebook user meets it: no logging configured, stderr no
terminal. Each case runs in a fresh interpreter, as a notebook kernel is one: pytest's own log capture
puts a handler on the root logger, which a user's process does not have."""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

#: A tiny scene: short runs, fixed k (no calibration), the paper scene's inputs otherwise.
SMALL = ["solver.duration_ms=0.3", "solver.transient_ms=0.1", "contact.k=0.5"]


def _python(code: str, tmp_path: Path, env_extra: dict | None = None) -> subprocess.CompletedProcess:
    """``code`` in a fresh interpreter, stdout and stderr captured (pipes: no terminal)."""
    import os
    env = {k: v for k, v in os.environ.items() if k not in ("CI", "DASK_SCHEDULER_ADDRESS")}
    env.update(env_extra or {})
    script = textwrap.dedent(code).format(config=str(REPO / "configs" / "paper-2009.toml"), small=SMALL,
                                          out=str(tmp_path / "results"))
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, cwd=tmp_path,
                          timeout=600)


@pytest.mark.slow
def test_api_calls_show_stage_messages_and_progress_without_logging_and_progress_false_silences_them(tmp_path):
    done = _python("""
        import logging, sys
        import pipeline as hdi
        assert not logging.getLogger().handlers and not logging.getLogger("pipeline").hasHandlers()
        scene = hdi.load_scene({config!r}, {small!r})
        hdi.run_stage("dmw", scene, {out!r})
        print("--- model", file=sys.stderr)
        model = hdi.build_model(scene, {out!r})
        print("--- simulate", file=sys.stderr)
        ds = hdi.simulate(model, [9.0, 10.0])
        print("--- quiet", file=sys.stderr)
        quiet = hdi.simulate(model, [9.0, 10.0], progress=False)
        hdi.run_stage("dmw", scene, {out!r}, force=True, progress=False)
        print("--- after", file=sys.stderr)
        assert quiet.fhm_bv.equals(ds.fhm_bv)  # (output only)
        # the handler lived for the calls only: the caller's logging is as it was
        assert not logging.getLogger("pipeline").hasHandlers()
        assert logging.getLogger("pipeline").level == logging.NOTSET
        print("ok")
        """, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
    err = done.stderr
    first, rest = err.split("--- model\n")
    model, rest = rest.split("--- simulate\n")
    simulated, rest = rest.split("--- quiet\n")
    quiet, after = rest.split("--- after\n")
    # the stage's messages, as `hdi dmw` writes them
    assert re.search(r"^dmw: computing \(", first, re.M), err
    assert re.search(r"^dmw: wrote dmw\.nc .*\(\d+\.\d s\)$", first, re.M), err
    assert re.search(r"^interface: computing", model, re.M), err  # (the model's inputs made current)
    # the runs counted, the end said however short (a line: stderr is no terminal, no notebook)
    ends = re.findall(r"^simulate: (\d+)/(\d+) runs done, elapsed \d+:\d\d, ETA 0:00$", simulated, re.M)
    assert ends == [("2", "2")], simulated
    assert "\r" not in err  # (no bar drawn into a pipe)
    assert quiet == "" and after == "", (quiet, after)


@pytest.mark.slow
def test_configured_logging_gets_each_line_once(tmp_path):
    done = _python("""
        import logging, sys
        logging.basicConfig(level=logging.INFO, format="LOG %(message)s")
        import pipeline as hdi
        scene = hdi.load_scene({config!r}, {small!r})
        hdi.run_stage("dmw", scene, {out!r})
        assert logging.getLogger("pipeline").handlers == []  # (nothing attached beside the caller's own)
        """, tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    computing = [line for line in lines if "dmw: computing" in line]
    assert len(computing) == 1 and computing[0].startswith("LOG dmw: computing"), done.stderr
