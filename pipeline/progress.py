"""Progress of long work: a bar on a terminal, periodic log lines elsewhere, nothing when quiet.

Every fan-out (:func:`pipeline.fanout.run_tasks`) counts its tasks through a :class:`Progress`, and the
work that is not one fan-out counts its own steps (the sweep its batches, ``hdi identify`` its
phases: its search's generations, each round of profiles, the scoring, with the best objective so far;
``hdi accuracy`` its runs). How a :class:`Progress` shows
itself is chosen when it starts (:func:`display`):

* ``"off"``: the ``pipeline`` logger does not show INFO (``hdi -q``, or a library caller whose own
  logging configuration leaves INFO out), the call asked for none (``progress=False`` of the API:
  :func:`shown`), or another :class:`Progress` is running in this context: the outer one owns the display
  (the generations of ``hdi identify``, not each generation's fan-out);
* ``"bar"``: stderr is an interactive terminal and ``CI`` is not set, or the code runs in a Jupyter
  kernel: a ``tqdm.auto`` bar with its ETA (a widget in a notebook, text on a terminal); while it
  runs, the ``pipeline`` log lines (tqdm's logging redirect) and the warnings are written above it, not
  over it;
* ``"lines"``: otherwise (a batch job's log, a pipe, a file): every :func:`interval_s` seconds (default
  :data:`INTERVAL_S`, environment variable ``HDI_PROGRESS_S``) one INFO line
  ``"<stage>: k/N <unit>s done, elapsed M:SS, ETA M:SS"``, and one at the end when the work took that
  long (a shorter one says its end at DEBUG, ``hdi -vv``), and always at INFO within a call of the
  Python API (:func:`shown`) and on a dask.distributed cluster (:attr:`Progress.end_line`), where a run
  of seconds would otherwise say nothing.

A Python caller (:mod:`pipeline.api`) sees what ``hdi`` shows without configuring logging: within
:func:`shown`, when no handler would take the ``pipeline`` log records (neither the ``pipeline`` logger
nor the root has one), one that writes INFO lines to stderr is attached for the call's duration
(:class:`StderrHandler`, the command line's own); a caller who configured logging keeps their
configuration, and nothing is written twice.

Work in phases of different kinds (``hdi identify``: the search's generations, each round of profiles'
evaluations, the scoring of the evaluations) counts each phase with a total of its own, fixed when the
phase starts (:meth:`Progress.phase`): ``"<stage> (<phase>): k/N <unit>s done, elapsed M:SS, ETA M:SS"``,
the ETA from the phase's own rate, the elapsed time one clock from the start of the whole work. A total
known only as an upper bound (a budget) may be lowered when the phase ends early, never raised.

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
from typing import Any, Callable, Iterator

log = logging.getLogger(__name__)

#: Seconds between two progress lines when stderr is not a terminal; ``HDI_PROGRESS_S`` overrides it.
INTERVAL_S = 30.0

_LABEL_DEFAULT = "hdi"
_LABEL: contextvars.ContextVar[str] = contextvars.ContextVar("hdi_progress_label", default=_LABEL_DEFAULT)
#: The :class:`Progress` whose display runs in this context (it owns the display: :func:`display`).
_ACTIVE: contextvars.ContextVar["Progress | None"] = contextvars.ContextVar("hdi_progress_active", default=None)
#: Within :func:`shown`: ``True`` (an API call that shows its progress) or ``False`` (``progress=False``).
_SHOWN: contextvars.ContextVar[bool | None] = contextvars.ContextVar("hdi_progress_shown", default=None)


class LineFormat(logging.Formatter):
    """Progress and stage messages as plain lines; warnings and errors say so and name the stage that
    gives them (``warning: dmw: ...``: the stage of :func:`stage`, unless the message starts with it)."""

    def format(self, record: logging.LogRecord) -> str:
        text = super().format(record)
        if record.levelno < logging.WARNING:
            return text
        name = _LABEL.get()
        if name != _LABEL_DEFAULT and not text.startswith(f"{name}:"):
            text = f"{name}: {text}"
        return f"{record.levelname.lower()}: {text}"


class StderrHandler(logging.StreamHandler):
    """Writes to whatever ``sys.stderr`` is now (the command line may be called repeatedly in one process,
    a notebook replaces ``sys.stderr`` per cell), as :class:`LineFormat` lines."""

    def __init__(self) -> None:
        super().__init__()
        self.setFormatter(LineFormat("%(message)s"))

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:
        pass


@contextlib.contextmanager
def shown(enabled: bool = True) -> Iterator[bool]:
    """Within the block (one call of :mod:`pipeline.api`), progress and the stages' messages reach a
    Python caller who configured no logging; ``enabled=False`` shows no progress at all (module docstring).

    With ``enabled``, when no handler would take the ``pipeline`` log records (``hasHandlers()`` is false:
    nothing configured), a :class:`StderrHandler` is attached to the ``pipeline`` logger and, if that
    logger has no level of its own, its level set to INFO, both undone at the end of the block. Logging
    that is configured (the command line's, ``logging.basicConfig``) is left as it is: no line twice. A
    block inside another (``build_model`` calling ``simulation_inputs``) changes nothing. Yields whether
    progress is shown.
    """
    if _SHOWN.get() is not None:  # (the outer call decided)
        yield bool(_SHOWN.get())
        return
    logger = logging.getLogger("pipeline")
    handler = StderrHandler() if enabled and not logger.hasHandlers() else None
    level = logger.level
    if handler is not None:
        logger.addHandler(handler)
        if level == logging.NOTSET:
            logger.setLevel(logging.INFO)
    token = _SHOWN.set(bool(enabled))
    try:
        yield bool(enabled)
    finally:
        _SHOWN.reset(token)
        if handler is not None:
            logger.removeHandler(handler)
            logger.setLevel(level)


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


def end_line() -> None:
    """The display running in this context (the :class:`Progress` that owns it: a fan-out's own, or the
    work around it, such as the sweep's batches) says its end at INFO however short the work was
    (:attr:`Progress.end_line`): a fan-out on a cluster calls it."""
    owner = _ACTIVE.get()
    if owner is not None:
        owner.end_line = True


def in_notebook() -> bool:
    """Whether this process is a Jupyter kernel, where ``tqdm.auto`` draws a widget (the test
    ``tqdm.autonotebook`` makes: a kernel's shell module is imported; not a Qt console or Spyder)."""
    if "ipykernel.zmqshell" not in sys.modules:
        return False
    return not any(name == "QT_API" or name.startswith("SPYDER") for name in os.environ)


def display() -> str:
    """How a :class:`Progress` starting now shows itself: ``"off"``, ``"bar"`` or ``"lines"`` (module
    docstring)."""
    if _ACTIVE.get() is not None or _SHOWN.get() is False or not logging.getLogger("pipeline").isEnabledFor(logging.INFO):
        return "off"
    if in_notebook():
        return "bar"
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
    timer : the clock [s] of the elapsed time and the ETA (default :func:`time.perf_counter`; a test's own)
    phase : the name of the first phase, where the work is in phases (:meth:`phase`)

    The attribute ``end_line`` (default: within an API call, :func:`shown`) makes the ``"lines"``
    display say the end at INFO however short the work was (a fan-out on a cluster sets it: :func:`end_line`).

    Work in phases (a total each, one elapsed clock): :meth:`phase`.
    """

    def __init__(self, total: int, unit: str = "task", label: str | None = None, initial: int = 0,
                 timer: Callable[[], float] = time.perf_counter, phase: str = ""):
        self._now = timer
        self.total, self.unit, self.initial = int(total), unit, int(initial)
        self.label = label or _LABEL.get()
        self.done = self.initial
        self.note = ""
        self.mode = "off"
        self.name = phase  # the current phase (:meth:`phase`); "" for work in one piece
        self._t0 = self._now()
        self._phase_t0 = self._t0  # (the ETA counts from the phase's start, the elapsed time from _t0)
        self._lines = 0
        self._bar: Any = None
        self._redirect: Any = None
        self._showwarning: Any = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._token: contextvars.Token | None = None
        self.end_line = bool(_SHOWN.get())

    def __enter__(self) -> "Progress":
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def start(self) -> "Progress":
        """Choose the display (:func:`display`) and start it; returns ``self``."""
        self.mode = display()
        self._t0 = self._phase_t0 = self._now()
        if self.mode == "off":
            return self
        self._token = _ACTIVE.set(self)
        if self.mode == "bar":
            from tqdm.auto import tqdm  # (a widget in a notebook, text on a terminal)
            from tqdm.contrib.logging import logging_redirect_tqdm
            self._redirect = logging_redirect_tqdm(loggers=[logging.getLogger("pipeline")])
            self._redirect.__enter__()
            self._showwarning = warnings.showwarning

            def show(message: Any, category: Any, filename: str, lineno: int, file: Any = None,
                     line: str | None = None) -> None:  # (a warning above the bar too, as formatted)
                text = warnings.formatwarning(message, category, filename, lineno, line)
                tqdm.write(text.rstrip("\n"), file=sys.stderr)

            warnings.showwarning = show
            self._bar = tqdm(total=self.total, initial=self.initial, unit=self.unit, desc=self._label(),
                             file=sys.stderr, dynamic_ncols=True)
        else:
            self._thread = threading.Thread(target=self._tick, args=(interval_s(),), daemon=True,
                                            name="hdi-progress")
            self._thread.start()
        return self

    def phase(self, name: str, total: int, unit: str | None = None) -> None:
        """Start the phase ``name`` of ``total`` steps (of ``unit``, default: the unit so far): the count
        starts again from 0 with its own total and ETA; the elapsed time goes on (module docstring). The
        phase that ends says its end as :meth:`close` does (the first phase, named when the work started,
        starts again without a word if nothing was counted yet)."""
        if self.name and self._thread is not None and (name != self.name or self.done > self.initial):
            self._say_end()
        self.name, self.total, self.done, self.initial = name, int(total), 0, 0
        self.unit = unit or self.unit
        self._phase_t0 = self._now()
        self._lines = 0
        if self._bar is not None:
            self._bar.reset(total=self.total)
            self._bar.unit = self.unit
            self._bar.start_t = self._bar._time() - (self._now() - self._t0)  # (one clock, in tqdm's)
            self._bar.set_description_str(self._label(), refresh=True)

    def _label(self) -> str:
        """The label, with the phase where there is one."""
        return f"{self.label} ({self.name})" if self.name else self.label

    def update(self, n: int = 1, note: str | None = None, total: int | None = None) -> None:
        """``n`` more steps done; ``note`` (e.g. ``"best objective 0.12"``) is shown beside the count;
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
        now = self._now()
        elapsed, ran_for = now - self._t0, now - self._phase_t0
        ran = self.done - self.initial
        left = self.total - self.done
        eta = clock(ran_for / ran * left) if ran > 0 else ("0:00" if left <= 0 else "?")
        units = self.unit + ("es" if self.unit.endswith(("s", "sh", "ch", "x")) else "s")
        text = f"{self._label()}: {self.done}/{self.total} {units} done, elapsed {clock(elapsed)}, ETA {eta}"
        return f"{text} ({self.note})" if self.note else text

    def _tick(self, every: float) -> None:
        """The ``"lines"`` display: a line every ``every`` seconds until :meth:`close`."""
        while not self._stop.wait(every):
            self._lines += 1
            log.info(self.line())

    def _say_end(self) -> None:
        """The ``"lines"`` display's last line of the work (or of a phase): INFO when it took an interval
        or more (or :attr:`end_line` is set), else DEBUG."""
        long = self.end_line or self._lines > 0 or self._now() - self._phase_t0 >= interval_s()
        log.log(logging.INFO if long else logging.DEBUG, self.line())

    def close(self) -> None:
        """End the display: the bar closes; the lines say the end (module docstring)."""
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
            self._thread = None
            self._say_end()
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


def compile_notice(what: str, seconds: float | None = None) -> None:
    """Say that ``what`` is being compiled (numba; first run only), or, with ``seconds`` [s] (measured here,
    on this machine), that it was compiled in that time: an INFO line of the ``pipeline`` logger, or, for a
    library caller that set up no logging at all (a notebook), the same line on stderr, so a first call's
    long pause is explained. No time is promised before it is measured (a compile's time depends on the
    machine and its load: 12 s to over a minute)."""
    text = (f"compiling {what} (first run only)" if seconds is None
            else f"compiled {what} in {seconds:.1f} s (first run only: cached for the next runs)")
    logger = logging.getLogger("pipeline")
    if logger.hasHandlers():
        log.info(text)
    else:
        print(text, file=sys.stderr, flush=True)
