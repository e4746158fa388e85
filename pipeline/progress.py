"""Progress of long work: a bar on a terminal, periodic log lines elsewhere, nothing when quiet.

Every fan-out (:func:`pipeline.fanout.run_tasks`) counts its tasks through a :class:`Progress`, and the
work that is not one fan-out counts its own steps (the sweep its batches, ``hdi identify`` its
generations with the best cost so far, ``hdi accuracy`` its runs). How a :class:`Progress` shows
itself is chosen when it starts (:func:`display`):

* ``"off"``: the ``pipeline`` logger does not show INFO (``hdi -q``, or a library caller that set up no
  logging), or another :class:`Progress` is running in this context: the outer one owns the display
  (the generations of ``hdi identify``, not each generation's fan-out);
* ``"bar"``: stderr is an interactive terminal and ``CI`` is not set: a tqdm bar with its ETA; while it
  runs, the ``pipeline`` log lines (tqdm's logging redirect) and the warnings are written above it, not
  over it;
* ``"lines"``: otherwise (a batch job's log, a pipe, a file): every :func:`interval_s` seconds (default
  :data:`INTERVAL_S`, environment variable ``HDI_PROGRESS_S``) one INFO line
  ``"<stage>: k/N <unit>s done, elapsed M:SS, ETA M:SS"``, and one at the end when the work took that
  long (a shorter one says its end at DEBUG, ``hdi -vv``).

The stage's name comes from :func:`stage` (the runner sets it around each stage it computes). Progress
is output only: nothing it does changes what is computed.
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import os
import sys
import threading
import time
import warnings
from typing import Any, Iterator

log = logging.getLogger(__name__)

#: Seconds between two progress lines when stderr is not a terminal; ``HDI_PROGRESS_S`` overrides it.
INTERVAL_S = 30.0

_LABEL: contextvars.ContextVar[str] = contextvars.ContextVar("hdi_progress_label", default="hdi")
_ACTIVE: contextvars.ContextVar[bool] = contextvars.ContextVar("hdi_progress_active", default=False)


@contextlib.contextmanager
def stage(name: str) -> Iterator[str]:
    """Within the block, progress is reported under ``name`` (a stage's name)."""
    token = _LABEL.set(name)
    try:
        yield name
    finally:
        _LABEL.reset(token)


def env_seconds(name: str, default: float) -> float:
    """A duration [s] set by the environment variable ``name`` (a finite number > 0), else ``default``.

    Raises
    ------
    ValueError
        One line naming the variable, its value and what was expected.
    """
    text = os.environ.get(name)
    if text is None:
        return default
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise ValueError(f"{name}={text}: expected a number of seconds > 0")
    return value


def interval_s() -> float:
    """:data:`INTERVAL_S` [s], or the environment variable ``HDI_PROGRESS_S`` (:func:`env_seconds`)."""
    return env_seconds("HDI_PROGRESS_S", INTERVAL_S)


def display() -> str:
    """How a :class:`Progress` starting now shows itself: ``"off"``, ``"bar"`` or ``"lines"`` (module
    docstring)."""
    if _ACTIVE.get() or not logging.getLogger("pipeline").isEnabledFor(logging.INFO):
        return "off"
    try:
        tty = sys.stderr.isatty()
    except (AttributeError, ValueError):  # (a closed or replaced stderr)
        tty = False
    return "bar" if tty and not os.environ.get("CI") else "lines"


def clock(seconds: float) -> str:
    """``seconds`` as ``M:SS`` or ``H:MM:SS``."""
    s = int(round(seconds))
    h, rest = divmod(s, 3600)
    m, s = divmod(rest, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class Progress:
    """Counts ``total`` steps of long work and shows the count (module docstring).

    Use it as a context manager (or :meth:`start` and :meth:`close`); :meth:`update` after each step.

    Parameters
    ----------
    total : the steps expected (a count past it raises it: :meth:`update`)
    unit : what a step is (``"task"``, ``"batch"``, ``"generation"``)
    label : the name the lines start with (default: the stage's, :func:`stage`)
    initial : steps already done before this run (a resumed sweep); the ETA counts from this run's rate
    """

    def __init__(self, total: int, unit: str = "task", label: str | None = None, initial: int = 0):
        self.total, self.unit, self.initial = int(total), unit, int(initial)
        self.label = label or _LABEL.get()
        self.done = self.initial
        self.note = ""
        self.mode = "off"
        self._t0 = time.perf_counter()
        self._lines = 0
        self._bar: Any = None
        self._redirect: Any = None
        self._showwarning: Any = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._token: contextvars.Token | None = None

    def __enter__(self) -> "Progress":
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def start(self) -> "Progress":
        """Choose the display (:func:`display`) and start it; returns ``self``."""
        self.mode = display()
        self._t0 = time.perf_counter()
        if self.mode == "off":
            return self
        self._token = _ACTIVE.set(True)
        if self.mode == "bar":
            from tqdm import tqdm
            from tqdm.contrib.logging import logging_redirect_tqdm
            self._redirect = logging_redirect_tqdm(loggers=[logging.getLogger("pipeline")])
            self._redirect.__enter__()
            self._showwarning = warnings.showwarning

            def show(message: Any, category: Any, filename: str, lineno: int, file: Any = None,
                     line: str | None = None) -> None:  # (a warning above the bar too, as formatted)
                text = warnings.formatwarning(message, category, filename, lineno, line)
                tqdm.write(text.rstrip("\n"), file=sys.stderr)

            warnings.showwarning = show
            self._bar = tqdm(total=self.total, initial=self.initial, unit=self.unit, desc=self.label,
                             file=sys.stderr, dynamic_ncols=True)
        else:
            self._thread = threading.Thread(target=self._tick, args=(interval_s(),), daemon=True,
                                            name="hdi-progress")
            self._thread.start()
        return self

    def update(self, n: int = 1, note: str | None = None, total: int | None = None) -> None:
        """``n`` more steps done; ``note`` (e.g. ``"best cost 0.12"``) is shown beside the count;
        ``total``: the steps now expected, where the work turned out shorter than foreseen (an upper
        bound of it, as a budget, came to an end early)."""
        self.done += n
        if note is not None:
            self.note = note
        if total is not None and total != self.total:
            self.total = int(total)
            if self._bar is not None:
                self._bar.total = max(self.total, self.done)
                self._bar.refresh()
        if self.done > self.total:  # (work that took more steps than foreseen: the count stays honest)
            self.total = self.done
            if self._bar is not None:
                self._bar.total = self.total
        if self._bar is not None:
            if note is not None:
                self._bar.set_postfix_str(note, refresh=False)
            self._bar.update(n)

    def line(self) -> str:
        """``"<label>: k/N <unit>s done, elapsed M:SS, ETA M:SS"`` (and the note) as of now."""
        elapsed = time.perf_counter() - self._t0
        ran = self.done - self.initial
        left = self.total - self.done
        eta = clock(elapsed / ran * left) if ran > 0 else ("0:00" if left <= 0 else "?")
        units = self.unit + ("es" if self.unit.endswith(("s", "sh", "ch", "x")) else "s")
        text = f"{self.label}: {self.done}/{self.total} {units} done, elapsed {clock(elapsed)}, ETA {eta}"
        return f"{text} ({self.note})" if self.note else text

    def _tick(self, every: float) -> None:
        """The ``"lines"`` display: a line every ``every`` seconds until :meth:`close`."""
        while not self._stop.wait(every):
            self._lines += 1
            log.info(self.line())

    def close(self) -> None:
        """End the display: the bar closes; the lines say the end (module docstring)."""
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
            self._thread = None
            long = self._lines > 0 or time.perf_counter() - self._t0 >= interval_s()
            log.log(logging.INFO if long else logging.DEBUG, self.line())
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        if self._redirect is not None:
            self._redirect.__exit__(None, None, None)
            self._redirect = None
            warnings.showwarning = self._showwarning
        if self._token is not None:
            _ACTIVE.reset(self._token)
            self._token = None
