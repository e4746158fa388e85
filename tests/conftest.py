"""Shared fixtures: the repository root, the paper scene, and a helper to write scene files."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from pipeline.config.scene import load_scene

#: The repository root (this file is tests/conftest.py).
REPO = Path(__file__).resolve().parent.parent
PAPER_CONFIG = REPO / "configs" / "paper-2009.toml"
os.environ.pop("DASK_SCHEDULER_ADDRESS", None)  # (hdi honours it: a developer's cluster must not get the suite's runs)


@pytest.fixture(autouse=True)
def _dask_default_scheduler_left_alone():
    """A test that leaves dask's default scheduler changed (a ``distributed.Client`` made the default and not
    closed, or one that failed in its constructor) fails here, not the later test whose xarray write it
    breaks ("Requested dask.distributed scheduler but no Client active"). Only where dask is imported."""
    config = sys.modules.get("dask.config")
    before = config.get("scheduler", None) if config is not None else None
    yield
    config = sys.modules.get("dask.config")
    if config is not None and config.get("scheduler", None) != before:
        pytest.fail(f"the test left dask's default scheduler set to {config.get('scheduler', None)!r} "
                    f"(it was {before!r})")


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def paper_config() -> Path:
    """Path of configs/paper-2009.toml."""
    return PAPER_CONFIG


@pytest.fixture()
def paper_scene():
    """The paper scene, freshly loaded (tests may not share a mutated scene)."""
    return load_scene(PAPER_CONFIG)


@pytest.fixture()
def write_scene(tmp_path):
    """``write_scene(text, name="scene.toml") -> Path``: a scene file in ``tmp_path``."""

    def _write(text: str, name: str = "scene.toml") -> Path:
        path = tmp_path / name
        path.write_text(text)
        return path

    return _write


def pytest_sessionfinish(session, exitstatus):
    """In CI a skipped test is a failure (every input the suite reads lives in the repository);
    an expected skip must be an ``xfail`` instead. Exit status 5 (no test ran) fails as pytest
    itself reports it."""
    import os

    if not os.environ.get("CI"):
        return
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    skipped = reporter.stats.get("skipped", []) if reporter is not None else []
    if skipped and exitstatus == 0:
        reporter.write_line(f"CI: {len(skipped)} test(s) skipped; a skip in CI is a failure "
                            "(mark an expected one xfail)", red=True)
        session.exitstatus = 1
