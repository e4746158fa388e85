"""The dask scheduler a run uses, checked before anything runs (``--scheduler``; the fan-out that then uses it:
:mod:`pipeline.fanout`, :mod:`pipeline.cluster`).

:func:`scheduler_address` resolves ``--scheduler`` (a local fan-out, an address or a scheduler file) or, without
it, ``DASK_SCHEDULER_ADDRESS``; :func:`check_scheduler` then probes the address: a dask scheduler must answer the
handshake within :data:`pipeline.cluster.CONNECT_TIMEOUT_S` (instead of dask's 30 s, a hang on an HTTP port or a
traceback on a banner, :func:`_dask_handshake`) and have a worker within :data:`WORKER_WAIT_S`
(:func:`check_workers_attached`). A mistake ends in one line naming the option (:class:`pipeline.options.OptionError`).
"""

from __future__ import annotations

import json
import os
import socket
import struct
from pathlib import Path
from urllib.parse import urlsplit


from .file_errors import os_error_line
from .paths import looked_for, special_kind
from . import cluster
from .cluster import CONNECT_TIMEOUT_S
from .fanout import LOCAL
from .options import OptionError, first_line, flag, given


#: Seconds a scheduler without workers is given to get one (batch jobs starting) before giving up.
WORKER_WAIT_S = 30.0
#: Largest handshake [bytes] a dask server sends (it is ~100 bytes; a banner read as a length is huge).
_HANDSHAKE_MAX = 1 << 20


#: The environment variable dask itself reads for its ``scheduler-address`` setting.
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"


given_option = given  # (scheduler_address's argument is named ``given``)


def scheduler_address(given: str | None) -> tuple[str | None, str]:
    """The scheduler a run uses and how an error names it: ``--scheduler`` (a local fan-out, an address,
    or a scheduler file), else :data:`SCHEDULER_ENV`, else ``None`` (local threads).

    A scheduler file is the JSON ``dask scheduler --scheduler-file FILE`` writes: a ``--scheduler``
    ending in ``.json``, or naming an existing file. dask's YAML config files are not read (importing
    dask would cost every local run ~0.5 s).
    """
    if given is not None and not isinstance(given, (str, os.PathLike)):
        raise OptionError(f"{given_option('scheduler', given, text=True)}: expected an address (tcp://HOST:PORT), a "
                          f"scheduler file or one of {', '.join(LOCAL)}, got {type(given).__name__}")
    given = os.fspath(given) if given is not None else None
    if given is None:
        env = os.environ.get(SCHEDULER_ENV, "").strip()
        return (env, f"{SCHEDULER_ENV}={env}") if env else (None, "")
    where = given_option("scheduler", given)
    if given not in LOCAL and "://" not in given and special_kind(given) is not None:
        # (checked before opening: reading a FIFO waits for a writer forever)
        raise OptionError(f"{where}: is {special_kind(given)}; expected the JSON file `dask scheduler "
                          "--scheduler-file FILE` writes, or tcp://HOST:PORT")
    if given in LOCAL or "://" in given or not (given.endswith(".json") or Path(given).is_file()):
        return given, where
    try:
        with open(given, encoding="utf-8") as f:
            identity = json.load(f)
    except FileNotFoundError:
        raise OptionError(f"{where}: no such scheduler file{looked_for(given)} (expected tcp://HOST:PORT, or the JSON file "
                          "`dask scheduler --scheduler-file FILE` writes)") from None
    except OSError as exc:
        raise OptionError(f"{where}: {os_error_line(exc)}") from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise OptionError(f"{where}: not a dask scheduler file ({exc}); expected the JSON file "
                          "`dask scheduler --scheduler-file FILE` writes") from None
    address = identity.get("address") if isinstance(identity, dict) else None
    if not isinstance(address, str) or not address:
        raise OptionError(f"{where}: field \"address\": expected the scheduler's address (tcp://HOST:PORT), "
                          f"got {address!r}")
    return address, f"{where} (address {address})"


def _leave(named: str) -> str:
    """How to run locally instead, for an error about the scheduler ``named``."""
    if named.startswith(SCHEDULER_ENV):
        return f"or unset {SCHEDULER_ENV} (or give {given('scheduler', 'threads')}) to run locally"
    return f"or leave {flag('scheduler')} out to use a local cluster"


def check_scheduler(address: str | None, timeout: float = CONNECT_TIMEOUT_S,
                    worker_wait: float = WORKER_WAIT_S) -> str | None:
    """The scheduler the run uses (:func:`scheduler_address`), checked: absent, a local one
    (``synchronous``, ``threads``, ``processes``: :mod:`pipeline.fanout`), or a ``[tcp://]HOST:PORT``
    where a dask scheduler answers the handshake within ``timeout`` [s] and has a worker within
    ``worker_wait`` [s] (``tls://``: the connection alone is checked, the handshake is encrypted).

    Returns
    -------
    str or None
        The address (or local name) to hand the stages; ``None``: the local default.
    """
    address, named = scheduler_address(address)
    if address is None or address in LOCAL:
        return address
    leave = _leave(named)
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    if parts.scheme not in ("tcp", "tls"):
        raise OptionError(f"{named}: expected tcp://HOST:PORT (or tls://, or a scheduler file), got scheme "
                          f"{parts.scheme!r}")
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host, port = None, None
    if not host or port is None:
        raise OptionError(f"{named}: expected tcp://HOST:PORT (or a scheduler file)")
    # (the handshake is read here, not by distributed.Client: against an HTTP server the client hangs
    # past its own timeout, and it reads a banner such as SSH's as a frame length, a MemoryError)
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            what = _dask_handshake(sock, timeout) if parts.scheme == "tcp" else None
    except OSError as exc:
        reason = "timed out" if isinstance(exc, socket.timeout) else (exc.strerror or str(exc))
        raise OptionError(f"{named}: no scheduler answers at {host}:{port} ({reason}, "
                          f"{timeout:g} s connect timeout); start one (`dask scheduler`) {leave}") from None
    if what is not None:
        raise OptionError(f"{named}: {host}:{port} answers but is not a dask scheduler ({what}); "
                          f"give the scheduler's address (tcp://HOST:8786 by default, not the dashboard's "
                          f"8787) {leave}")
    check_workers_attached(address, timeout, worker_wait, named)
    return address


def _dask_handshake(sock: socket.socket, timeout: float) -> str | None:
    """Why the service on ``sock`` is not a dask.distributed server (``None``: it is one).

    A dask server speaks first: on accepting a connection it sends its handshake (the comm protocol
    of ``distributed.comm.tcp``: an 8-byte little-endian length, then msgpack frames naming
    ``pickle-protocol`` and ``compression``). An HTTP server (a dashboard, a web service) waits for a
    request instead, and other services send a banner: both are told apart here without sending a
    byte, where ``distributed.Client`` would hang or read the banner as a length of exabytes.
    """
    sock.settimeout(timeout)
    head = b""
    try:
        while len(head) < 8:
            chunk = sock.recv(8 - len(head))
            if not chunk:
                return "it closed the connection without a handshake"
            head += chunk
        (size,) = struct.unpack("<Q", head)
        if not 0 < size <= _HANDSHAKE_MAX:
            return f"it sent {head[:8]!r} instead of a dask handshake"
        body = b""
        while len(body) < size:
            chunk = sock.recv(min(65536, size - len(body)))
            if not chunk:
                break
            body += chunk
    except socket.timeout:
        return f"no dask handshake within {timeout:g} s" + (", as an HTTP server or dashboard does" if not head else "")
    return None if b"pickle-protocol" in body and b"compression" in body else "its first message is no dask handshake"


def check_workers_attached(address: str, timeout: float = CONNECT_TIMEOUT_S,
                           worker_wait: float = WORKER_WAIT_S, named: str | None = None) -> None:
    """The dask scheduler at ``address`` has at least one worker, or gets one within ``worker_wait`` [s]
    (workers submitted as batch jobs may still be starting); its dashboard link is logged
    (:func:`pipeline.cluster.announce`). ``named``: how an error names the scheduler."""
    import logging
    named = named or given("scheduler", address)
    try:
        with cluster.new_client(address, timeout) as client:
            cluster.announce(client, address)
            if client.scheduler_info().get("workers"):
                return
            logging.getLogger("pipeline").info("scheduler %s has no workers; waiting up to %g s for one",
                                               address, worker_wait)
            try:
                client.wait_for_workers(1, timeout=worker_wait)
                return
            except (TimeoutError, OSError):
                pass
    except (OSError, TimeoutError) as exc:
        raise OptionError(f"{named}: the dask scheduler did not answer ({exc})") from None
    except Exception as exc:  # noqa: BLE001 (fail closed: a server imitating the handshake sent garbage after it,
        # and dask's frame reader raised struct.error; whatever dask raises on it is no scheduler)
        raise OptionError(f"{named}: answers with a dask-like handshake but not as a dask scheduler "
                          f"({type(exc).__name__}: {first_line(exc)}); give the scheduler's address "
                          f"(tcp://HOST:8786 by default) {_leave(named)}") from None
    raise OptionError(f"{named}: the dask scheduler has no workers ({worker_wait:g} s waited); "
                      f"start some (`dask worker {address}`) {_leave(named)}")
