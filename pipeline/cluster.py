"""The dask.distributed side of the fan-out (:mod:`pipeline.fanout`): the client of a scheduler and its
dashboard link, the check of every worker's code, the results folder every task checks it sees
(:func:`shared_folder`), and the watch of a batch while the client waits for it.

Before a batch is sent to a cluster, every worker's :func:`pipeline.code_version.code_key` of the
task's module is compared with this process's (:func:`check_code`), and each task checks it again on
the worker that runs it (a worker that joined later): a worker that imported other code (started
before an update, or from another install) would write parts stamped with this code's inputs key, so
it ends the command with one line naming the worker and both keys (:class:`ClusterError`).

On a cluster the client watches the progress while it waits: when for :data:`CLUSTER_WAIT_S` seconds
(environment variable ``HDI_CLUSTER_WAIT_S``) no task finished and none was running on a worker (the
last worker was lost, the scheduler has none, or they are all busy with other work), the command ends
with one line (:class:`ClusterError`); finished tasks have written their outputs, so a rerun resumes.
A scheduler lost mid-batch (its connection broken: dask cancels the futures) ends it the same way.

A worker or a scheduler that is there but does not move (stopped with SIGSTOP, swapping, its machine
unreachable while its connections stay open) is a stall (:class:`Watch`): when a worker that holds tasks of
the batch sends the scheduler no heartbeat, or the scheduler answers no question, for longer than the stall
bound, the command ends with one line naming it (:class:`ClusterError`), and a rerun resumes. The bound is
:data:`STALL_S` (``HDI_STALL_S``), or several times the longest gap between two heartbeats seen so far if
that is longer (a loaded worker's event loop answers late): it follows dask's heartbeats, not the tasks' run
times, so a batch that runs for hours on a live worker is never taken for a stall.
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import os
import socket
import time
from concurrent.futures import CancelledError
from pathlib import Path
from typing import Any, Callable, Iterator

from .code_version import code_key
from .progress import env_seconds

#: The fan-out's logger: its messages name the fan-out whichever of its modules sends them.
log = logging.getLogger("pipeline.fanout")

#: Seconds a dask.distributed cluster may go without finishing or running a task of the batch before
#: the command ends (module docstring); ``HDI_CLUSTER_WAIT_S`` overrides it.
CLUSTER_WAIT_S = 60.0
#: Seconds a worker holding tasks of the batch may send no heartbeat, and the scheduler may leave a question
#: unanswered, before the command ends as stalled (module docstring); ``HDI_STALL_S`` overrides it.
STALL_S = 60.0
#: The stall bound is at least this many times the longest gap between two heartbeats of a worker seen so far.
STALL_HEARTBEATS = 5
#: Seconds between two looks at the cluster while waiting for results.
_POLL_S = 1.0
#: Seconds to wait for a dask scheduler to answer a connection (dask's own default is 30 s), when the
#: command starts (:func:`pipeline.scheduler.check_scheduler`) and to count its threads.
CONNECT_TIMEOUT_S = 3.0
#: Seconds a batch's client waits for the scheduler (dask's default: a busy scheduler of a long study
#: answering late is no reason to stop); past them the command ends in one line.
CLIENT_TIMEOUT_S = 30.0


#: The loggers of dask.distributed and of what it runs on (tornado, asyncio), whose levels distributed sets from
#: its own configuration when it is imported (:func:`dask_log_level`).
DASK_LOGGERS = ("distributed", "distributed.client", "distributed.gc", "distributed.scheduler", "distributed.nanny",
                "distributed.core", "distributed.http.proxy", "tornado", "tornado.application", "asyncio")
#: The level :func:`dask_log_level` keeps those loggers at (``None``: dask's own configuration).
_DASK_LEVEL: list[int | None] = [None]


def dask_log_level(level: int | None) -> None:
    """Keep the loggers of :data:`DASK_LOGGERS` at ``level``, now and after this module imports distributed
    (whose import sets their levels again, from its configuration): how the command line keeps dask's own
    messages and tracebacks (an ERROR with a traceback per broken connection when the scheduler is killed)
    out of the terminal, where the one line of :class:`ClusterError` says what happened (``-v`` shows them).
    ``None``: leave them as dask configures them."""
    _DASK_LEVEL[0] = level
    keep_dask_level()


def keep_dask_level() -> None:
    """Apply :func:`dask_log_level`'s level (after an import of distributed)."""
    if _DASK_LEVEL[0] is not None:
        for name in DASK_LOGGERS:
            logging.getLogger(name).setLevel(_DASK_LEVEL[0])


class ClusterError(ValueError):
    """The cluster cannot run the batch: a worker does not see the results folder or runs other code, no
    worker ran a task for :data:`CLUSTER_WAIT_S`, a task killed its workers, or the scheduler was lost or
    is none (the command line says it in one line)."""


#: The results folder every task of a batch checks its worker sees (:func:`shared_folder`; ``None``: no check).
SHARED_FOLDER: contextvars.ContextVar[str | None] = contextvars.ContextVar("hdi_shared_folder", default=None)


@contextlib.contextmanager
def shared_folder(path: str | Path) -> Iterator[str]:
    """Within the block, every task sent to a dask.distributed worker first checks that the worker sees
    the folder ``path`` (made absolute: a worker's working directory is not ours)."""
    folder = str(Path(path).absolute())
    token = SHARED_FOLDER.set(folder)
    try:
        yield folder
    finally:
        SHARED_FOLDER.reset(token)


def cluster_wait_s() -> float:
    """:data:`CLUSTER_WAIT_S` [s], or the environment variable ``HDI_CLUSTER_WAIT_S``
    (:func:`pipeline.progress.env_seconds`; a bad value is a :class:`ClusterError`)."""
    try:
        return env_seconds("HDI_CLUSTER_WAIT_S", CLUSTER_WAIT_S)
    except ValueError as exc:
        raise ClusterError(str(exc)) from None


def stall_s() -> float:
    """:data:`STALL_S` [s], or the environment variable ``HDI_STALL_S`` (a bad value is a :class:`ClusterError`)."""
    try:
        return env_seconds("HDI_STALL_S", STALL_S)
    except ValueError as exc:
        raise ClusterError(str(exc)) from None


def new_client(address: str, timeout: float) -> Any:
    """A ``distributed.Client`` of the scheduler at ``address`` (``timeout`` [s] to connect), never the
    process's default client: its user makes it current where it submits (:func:`connect`), so a default
    client of the user's process stays the default, and dask's ``scheduler`` option is set only for that span
    (distributed's ``as_current`` sets it for the whole process and puts it back).

    A Client whose constructor fails is closed here. Left alone, the failed constructor's frames kept it
    alive (and a caller's exception keeps those through ``__context__``), and the garbage collector ran its
    ``__del__`` at an arbitrary later moment: inside the next Client's event-loop start, where it deadlocked
    (a failed connection, then a new Client in the same process). The object is made first and initialised
    second so that this function holds it when ``__init__`` raises."""
    from distributed import Client
    keep_dask_level()
    client = Client.__new__(Client)
    try:
        client.__init__(address, timeout=timeout, set_as_default=False)
    except BaseException:
        with contextlib.suppress(Exception):  # (the constructor's error is the one to report)
            client.close()
        raise
    return client


@contextlib.contextmanager
def connect(address: str, timeout: float | None = None) -> Iterator[Any]:
    """A ``distributed.Client`` of the scheduler at ``address``; one that does not answer within ``timeout``
    [s] (default :data:`CONNECT_TIMEOUT_S`) is :class:`ClusterError`."""
    try:
        client = new_client(address, CONNECT_TIMEOUT_S if timeout is None else timeout)
    except (OSError, TimeoutError) as exc:
        raise ClusterError(f"dask scheduler {address}: did not answer ({exc}); start it again, or run locally "
                           "(--scheduler threads)") from None
    except Exception as exc:  # noqa: BLE001 (fail closed: garbage after a dask-like handshake, e.g. struct.error)
        raise ClusterError(f"dask scheduler {address}: answers, but not as a dask scheduler ({type(exc).__name__}); "
                           "give the scheduler's address, or run locally (--scheduler threads)") from None
    # (current in this thread only: the fan-out's ``distributed.wait`` looks for it there; the process's
    # default client stays the user's)
    with client, client.as_current():
        yield client


def cluster_threads(address: str) -> int:
    """The threads of the workers the scheduler at ``address`` has now (at least 1): how many tasks
    :func:`split` makes for it (a dask-jobqueue cluster of 64 single-threaded workers runs 64)."""
    with connect(address) as client:
        return max(1, sum(client.nthreads().values()))


_ANNOUNCED: set[str] = set()


def announce(client: Any, address: str) -> None:
    """Log (INFO) the dashboard link of the scheduler at ``address``, once per process, if it has one
    (as dask shows it: a scheduler without bokeh serves a page saying to install it there)."""
    if address in _ANNOUNCED:
        return
    _ANNOUNCED.add(address)
    try:
        services = client.scheduler_info(n_workers=0).get("services", {})
        link = client.dashboard_link if "dashboard" in services else None
    except (OSError, TimeoutError, KeyError):  # (no link is no reason to stop)
        return
    if link:
        log.info("dask scheduler %s: dashboard %s", address, link)


def _worker_code_key(module: str) -> str:
    """:func:`pipeline.code_version.code_key` of ``module`` in the process that runs this (a worker)."""
    return code_key(module)


def task_code(fn: Callable[..., Any]) -> tuple[str, str]:
    """The module of task function ``fn`` and its code key in this process (``""`` outside ``pipeline``)."""
    module = getattr(fn, "__module__", None) or ""
    return module, code_key(module)


def _stale(worker: str, module: str, theirs: str, ours: str) -> ClusterError:
    """The one line that refuses a worker whose code is not ours."""
    return ClusterError(f"dask worker {worker} runs other code than this hdi: code key of {module} {theirs[:12] or '-'} "
                        f"there, {ours[:12] or '-'} here; restart the workers from this version of pipeline "
                        "(install it where they run) and run again")


def run_everywhere(client: Any, fn: Callable[..., Any], *args: Any, on_error: str = "raise") -> dict:
    """``client.run(fn, *args, on_error=on_error)`` (``fn`` on every worker, outside the task graph) within the
    stall bound (:func:`stall_s`): the scheduler waits for every worker's answer, and a worker stopped with
    SIGSTOP never gives one (a rerun against it waited forever). On the bound, :class:`ClusterError` naming
    the workers whose heartbeat did not move over the next few seconds (:func:`_silent_workers`).
    (``Client.run`` takes no timeout: it is ``Client.sync`` of ``Client._run``, called here with one.)"""
    bound = stall_s()
    try:
        return client.sync(client._run, fn, *args, on_error=on_error, callback_timeout=bound)
    except TimeoutError:
        silent = _silent_workers(client)
        who = f"dask worker(s) {', '.join(silent)}" if silent else "a dask worker or the scheduler"
        raise ClusterError(f"{who} did not answer for {bound:g} s (stopped, or the machine is unreachable; "
                           "HDI_STALL_S sets the wait); restart or remove it and run again") from None


def _silent_workers(client: Any) -> list[str]:
    """The workers whose heartbeat (the scheduler's ``last_seen``) does not move within three polls (none
    named when the scheduler itself does not answer within them)."""
    look_s = 3 * _POLL_S
    try:
        first = client.sync(client.scheduler.identity, n_workers=-1, callback_timeout=look_s).get("workers", {})
        time.sleep(look_s)
        then = client.sync(client.scheduler.identity, n_workers=-1, callback_timeout=look_s).get("workers", {})
    except (OSError, TimeoutError):
        return []
    return sorted(w for w, info in then.items() if w in first and info.get("last_seen") == first[w].get("last_seen"))


def check_code(client: Any, fn: Callable[..., Any]) -> None:
    """Every worker of ``client`` has this process's code key of ``fn``'s module, else :class:`ClusterError`
    naming the first worker (by address) that differs (a worker that cannot even run the check imports
    an older ``pipeline``)."""
    module, ours = task_code(fn)
    keys = run_everywhere(client, _worker_code_key, module, on_error="return")
    for worker, theirs in sorted(keys.items()):
        if isinstance(theirs, (OSError, TimeoutError)):  # (distributed's CommClosedError is an OSError)
            raise ClusterError(f"dask worker {worker} does not answer ({type(theirs).__name__}: {theirs}): it is "
                               "stopped, or its machine is unreachable; restart it or remove it from the cluster, "
                               "and run again")
        if isinstance(theirs, BaseException):
            raise ClusterError(f"dask worker {worker} runs other code than this hdi: it cannot check its code key "
                               f"({type(theirs).__name__}: {theirs}); restart the workers from this version of "
                               "pipeline (install it where they run) and run again")
        if theirs != ours:
            raise _stale(worker, module, theirs, ours)


def in_shared_folder(folder: str | None, fn: Callable[..., Any], *args: Any) -> Any:
    """``fn(*args)`` on a worker that sees ``folder`` (``None``: no check); else :class:`ClusterError`."""
    if folder is not None and not os.path.isdir(folder):
        raise ClusterError(f"{folder}: the results folder is not visible on dask worker {socket.gethostname()} "
                           f"(working directory {os.getcwd()}); put it on a file system every worker shares "
                           "and pass it as --out")
    return fn(*args)


def on_worker(folder: str | None, code: tuple[str, str], fn: Callable[..., Any], *args: Any) -> Any:
    """A task on a dask worker: the worker's code key of ``code = (module, key)`` must be ``key`` (a
    worker that joined after :func:`check_code`), then :func:`in_shared_folder`."""
    module, ours = code
    theirs = code_key(module)
    if theirs != ours:
        try:
            from distributed import get_worker
            worker = get_worker().address
        except (ImportError, ValueError):
            worker = socket.gethostname()
        raise _stale(worker, module, theirs, ours)
    return in_shared_folder(folder, fn, *args)


def _result(fut: Any, timeout: float, address: str) -> Any:
    """The result of a finished future (:class:`TimeoutError` when it did not arrive within ``timeout``
    [s]: its worker was lost before sending it, and the task runs again); a task that killed its workers
    is one line."""
    from distributed import KilledWorker
    from distributed.comm import CommClosedError
    try:
        return fut.result(timeout=timeout)
    except KilledWorker as exc:
        raise ClusterError(f"a task was lost with every worker that ran it ({exc}); a worker crashed or ran out "
                           "of memory: see the workers' logs; finished work is kept, run again to resume") from None
    except CommClosedError as exc:  # (the scheduler went away while the result was fetched; a task's own
        # OSError, a full disk on a worker, is raised as it is)
        raise ClusterError(f"dask scheduler {address}: lost while a result was fetched "
                           f"({type(exc).__name__}); finished work is kept, run again to resume") from None


def gather_results(client: Any, futures: list, address: str, wait_s: float, watch: "Watch") -> Iterator[Any]:
    """The futures' results as they arrive; :class:`ClusterError` when for ``wait_s`` [s] none arrived
    and no task of theirs was running on a worker (the last worker lost, none attached, all busy
    elsewhere), or when ``watch`` finds the scheduler or a worker running them stalled."""
    from distributed import wait as wait_any
    order = {fut: i for i, fut in enumerate(futures)}
    pending = set(futures)
    idle_since: float | None = None
    while pending:
        try:
            finished = wait_any(pending, timeout=_POLL_S, return_when="FIRST_COMPLETED").done
        except TimeoutError:
            finished = set()
        except CancelledError:  # (distributed's FuturesCancelledError: the scheduler went away)
            raise _lost(address, len(pending), len(futures)) from None
        arrived = False
        for fut in sorted(finished, key=order.__getitem__):
            asked = time.monotonic()
            left = wait_s if idle_since is None else wait_s - (asked - idle_since)
            try:
                # (bounded: a result whose worker died before sending it never arrives; the task is then
                # computed again, so it stays pending, and the wait counts from when it was asked for)
                result = _result(fut, max(_POLL_S, min(left, watch.bound())), address)
            except TimeoutError:
                idle_since = asked if idle_since is None else idle_since
                continue
            except CancelledError:
                raise _lost(address, len(pending), len(futures)) from None
            pending.discard(fut)
            arrived = True
            yield result
        if arrived and not watch.due():  # (results arriving: a look a poll at most, for the heartbeats)
            idle_since = None
            continue
        running = watch.look(pending) if pending else False
        if arrived or running:
            idle_since = None
            continue
        now = time.monotonic()
        idle_since = now if idle_since is None else idle_since
        if now - idle_since >= wait_s:
            n_workers = watch.workers()
            why = "no worker left" if n_workers == 0 else f"{n_workers} worker(s) ran none of them"
            raise ClusterError(f"dask scheduler {address}: {len(pending)} of {len(futures)} tasks waited {wait_s:g} s "
                               f"with {why} (HDI_CLUSTER_WAIT_S sets the wait); finished work is kept, start "
                               "workers and run again to resume")


def _lost(address: str, pending: int, total: int) -> ClusterError:
    """The one line of a scheduler lost mid-batch: dask cancels every future it held (``FuturesCancelledError``,
    whose text lists each one over many lines)."""
    return ClusterError(f"dask scheduler {address}: lost with {pending} of {total} tasks unfinished (it stopped, "
                        "or the connection to it broke); finished work is kept, run again to resume")


class Watch:
    """What the client sees of the cluster while it waits for a batch (:func:`gather_results`): which worker holds
    which pending task, and when each worker's heartbeat last moved; a stall ends the command.

    The scheduler's ``last_seen`` of a worker (its clock) is compared only with its own earlier values, so the
    clocks of the client and the scheduler need not agree: a worker's heartbeat *moved* when its ``last_seen``
    changed between two looks, and is stalled when it did not move for :meth:`bound` seconds of this process's
    clock while the worker held tasks of the batch. Every question to the scheduler waits :meth:`bound` seconds
    at most."""

    def __init__(self, client: Any, address: str, floor_s: float) -> None:
        self.client, self.address, self.floor_s = client, address, floor_s
        self.seen: dict[str, tuple[float, float]] = {}  # worker -> (its last_seen, when that value was first seen)
        self.longest_gap = 0.0  # [s] the longest time a worker's heartbeat took to move, seen so far
        self.looked = -float("inf")  # (time.monotonic() of the last look)

    def due(self) -> bool:
        """Whether a poll's time has passed since the last look (:meth:`look`)."""
        return time.monotonic() - self.looked >= _POLL_S

    def bound(self) -> float:
        """The stall bound [s]: :data:`STALL_S` (``HDI_STALL_S``), or :data:`STALL_HEARTBEATS` times the longest
        gap between two moves of a worker's heartbeat seen so far if that is longer."""
        return max(self.floor_s, STALL_HEARTBEATS * self.longest_gap)

    def _ask(self, handler: str, **kwargs: Any) -> Any:
        """The scheduler's answer to ``handler``; :class:`ClusterError` when it gives none within :meth:`bound`."""
        bound = self.bound()
        try:
            return self.client.sync(getattr(self.client.scheduler, handler), callback_timeout=bound, **kwargs)
        except TimeoutError:
            raise ClusterError(f"dask scheduler {self.address}: no answer for {bound:.3g} s (it is stopped, or "
                               "overloaded; HDI_STALL_S sets the wait); finished work is kept, run again to "
                               "resume") from None
        except OSError as exc:
            raise ClusterError(f"dask scheduler {self.address}: stopped answering ({exc}); finished work is kept, "
                               "run again to resume") from None

    def workers(self) -> int:
        """The workers the scheduler has now (0 if it cannot say)."""
        try:
            return len(self._ask("identity", n_workers=-1).get("workers", {}))
        except ClusterError:
            return 0

    def look(self, pending: set) -> bool:
        """Whether a worker runs one of the futures ``pending`` now; :class:`ClusterError` naming a worker that
        holds some of them, running or finished with the result not yet fetched from it (the scheduler's
        ``who_has``), and whose heartbeat has not moved for :meth:`bound` seconds."""
        keys = {f.key for f in pending}
        processing = self._ask("processing")
        done = [f.key for f in pending if getattr(f, "status", None) == "finished"]  # (its result on a worker)
        holding = self._ask("who_has", keys=done) if done else {}
        workers = self._ask("identity", n_workers=-1).get("workers", {})
        now = self.looked = time.monotonic()
        for worker, info in workers.items():
            last = info.get("last_seen")
            before = self.seen.get(worker)
            if before is None or last != before[0]:
                if before is not None:
                    self.longest_gap = max(self.longest_gap, now - before[1])
                self.seen[worker] = (last, now)
        held = {w: sum(k in keys for k in ks) for w, ks in processing.items()}
        results = dict.fromkeys(held, 0)
        for ws in holding.values():
            for w in ws:
                results[w] = results.get(w, 0) + 1
        for worker, n in sorted((w, held.get(w, 0) + results[w]) for w in results):
            since = self.seen.get(worker, (None, now))[1]
            if n and now - since > self.bound():
                raise ClusterError(f"dask worker {worker}: no heartbeat for {now - since:.0f} s while it holds {n} "
                                   f"task(s) of the batch (it is stopped, or its machine is unreachable; "
                                   "HDI_STALL_S sets the wait); finished work is kept, restart or remove the worker "
                                   "and run again to resume")
        return any(held.values())
