"""Dask glue: map a picklable function over task arguments, in order, with a progress bar.

Three ways to run, chosen by the command line and passed down here:

- ``workers=0``: in this process, one task after the other (tests, debugging);
- ``workers=W`` (default: the number of cores): a private ``LocalCluster`` of ``W``
  processes with one thread each, llvmpipe's and OpenCV's included (:data:`WORKER_ENV`);
- ``scheduler="tcp://host:port"``: an existing Dask cluster. An unreachable address is
  a one-line ``ValueError`` raised by :func:`open_client` before any work starts.

Results never depend on the worker count: callers derive every random stream from the
task's arguments (a seed and an index), never from the worker running it.

>>> run_tasks(pow, [(2, 3), (3, 2)], workers=0, progress=False)
[8, 9]
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
import warnings
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from tqdm import tqdm

from testbed import stops

__all__ = ["chunk", "default_workers", "open_client", "run_tasks"]


#: Environment of every local worker process: one thread each for Mesa's llvmpipe
#: (renderers in workers) and OpenCV. Both ignore OMP_NUM_THREADS (which Dask sets to 1)
#: and start a thread per core in every worker: with as many workers as cores, their
#: parallel loops then wait for threads that another worker has descheduled. Two dataset
#: workers on 2 cores ran 1.56-1.71x faster than one with OpenCV's default threads,
#: 1.62-1.92x with one thread each (docs/performance.md).
WORKER_ENV = {"LP_NUM_THREADS": "1", "OPENCV_FOR_THREADS_NUM": "1"}


def dask_setup(worker) -> None:
    """Dask preload of every local worker process: ignore SIGINT.

    Ctrl-C in a terminal reaches the whole process group; the client process turns it into
    one "interrupted" line and closes the cluster, which stops the workers. Without this,
    each worker process printed its own KeyboardInterrupt traceback on the way out.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def children_ignore_ctrl_c() -> Iterator[None]:
    """Block SIGINT in this thread while the local cluster starts.

    The threads Dask starts meanwhile (its event loop, each nanny's process watcher) inherit
    the mask, and so do the worker processes they spawn (a signal mask survives fork and
    exec): a Ctrl-C that reaches the terminal's process group while a worker still imports
    numpy or distributed stays pending there, never delivered, instead of printing its
    KeyboardInterrupt traceback before :func:`dask_setup` ignores SIGINT. Workers the nanny
    restarts later start from the same threads. This thread gets SIGINT back on the way out
    (a Ctrl-C that came meanwhile is delivered then, to the handler in place).
    """
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    from multiprocessing import resource_tracker

    # started first: multiprocessing starts it with SIGINT and SIGTERM blocked, then unblocks
    # both in the starting thread, whatever they were (Dask's event loop would lose the mask)
    resource_tracker.ensure_running()
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        if signal.SIGINT not in before:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def default_workers() -> int:
    """Number of cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def chunk(n: int, size: int) -> list[tuple[int, int]]:
    """Split ``range(n)`` into ``[start, stop)`` pieces of at most ``size``.

    >>> chunk(5, 2)
    [(0, 2), (2, 4), (4, 5)]
    """
    size = max(1, int(size))
    return [(s, min(s + size, n)) for s in range(0, n, size)]


@contextlib.contextmanager
def open_client(workers: int | None = None, scheduler: str | None = None,
                connect_timeout: float = 5.0) -> Iterator[Any]:
    """Yield a ``distributed.Client`` (or ``None`` for ``workers=0``), closed afterwards.

    workers : int >= 0 or None (the number of cores); ignored when ``scheduler`` is given
    scheduler : address of an existing scheduler, e.g. ``"tcp://10.0.0.5:8786"``
    connect_timeout : seconds to wait for ``scheduler`` before giving up
    Local workers get :data:`WORKER_ENV` and ignore SIGINT (:func:`dask_setup`: Ctrl-C stops
    the run here, once); an existing cluster keeps its own environment.
    """
    if scheduler is None and workers is not None and int(workers) < 0:
        raise ValueError(f"workers: expected an integer >= 0, got {workers}")
    if scheduler is None and workers == 0:
        yield None
        return
    if scheduler is not None:
        with _scheduler_client(scheduler, connect_timeout) as client:
            yield client
    else:
        with _local_client(default_workers() if workers is None else int(workers)) as client:
            yield client


@contextlib.contextmanager
def _scheduler_client(scheduler: str, connect_timeout: float) -> Iterator[Any]:
    """A client of the scheduler at ``scheduler`` (``tcp://`` added when no protocol is
    given), its Dask log lines silenced while it is open."""
    from distributed import Client

    address = scheduler if "://" in scheduler else f"tcp://{scheduler}"
    check_scheduler(address, connect_timeout)
    try:
        client = Client(address, timeout=f"{connect_timeout}s")
    except (OSError, TimeoutError, ValueError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"scheduler: cannot reach a Dask scheduler at {address} ({msg})") from None
    # a lost scheduler is the run's own one-line error; Dask's logs would add a traceback
    loggers = [logging.getLogger(name) for name in ("distributed", "distributed.client")]
    levels = [log.level for log in loggers]
    try:
        for log in loggers:
            log.setLevel(logging.CRITICAL)
        yield client
    finally:
        client.close()
        for log, level in zip(loggers, levels, strict=True):
            log.setLevel(level)


@contextlib.contextmanager
def _local_client(n: int) -> Iterator[Any]:
    """A client of a new local cluster of ``n`` worker processes (one thread each, see
    :func:`open_client`), closed afterwards; its workers are killed if they have not
    stopped by themselves :data:`STOP_TIMEOUT` s after an exception."""
    import dask
    from distributed import Client, LocalCluster

    # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers; any explicit glibc
    # threshold turns off glibc's dynamic mmap threshold, so every large numpy temporary
    # is mmapped and page-faulted afresh: the node pipeline ran 2.2x slower (98 vs 217
    # ms per 16-camera frame, docs/performance.md). Workers keep glibc's defaults.
    spawn_env = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ").items()
                 if not k.startswith("MALLOC_")}
    from render.gl import signals_held

    cluster = client = None
    stopped = False                     # left by an exception: Ctrl-C, SIGTERM, an error
    try:
        # Ctrl-C and SIGTERM wait until the cluster has started, then stop the run as usual:
        # half-started, it printed tracebacks (a nanny that failed to start, an atexit
        # assertion). The worker processes start with SIGINT blocked (children_ignore_ctrl_c):
        # one still importing when a Ctrl-C reached the terminal's process group printed a
        # page of KeyboardInterrupt traceback (1-5 s after the start on a busy machine).
        with signals_held(), children_ignore_ctrl_c():
            with warnings.catch_warnings(), dask.config.set({"distributed.nanny.pre-spawn-environ": spawn_env}):
                warnings.simplefilter("ignore", UserWarning)  # "port 8787 in use" when several clusters run
                cluster = LocalCluster(
                    n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                    silence_logs=logging.CRITICAL, env=dict(WORKER_ENV), preload=[__name__],
                )
            client = Client(cluster)
        yield client
    except BaseException:
        stopped = True
        raise
    finally:
        # a second Ctrl-C (or SIGTERM) while the cluster closes waits until it has closed:
        # interrupted, the close was left to Dask's atexit hook (~10 s more), and a worker
        # could still rename an episode into DIR after the caller had removed the unlisted ones
        with signals_held():
            if client is not None:
                client.close()
            if cluster is not None:
                if stopped:
                    stop_workers(cluster)
                cluster.close()


#: Seconds a local worker gets to close by itself when a run stops before it is killed.
STOP_TIMEOUT = 0.5


def stop_workers(cluster, timeout: float = STOP_TIMEOUT) -> None:
    """Close the worker processes of a local ``cluster`` within about ``timeout`` seconds,
    killing those still busy; return once they have exited.

    A run stopped by Ctrl-C, SIGTERM or an error gives no task a result any more (the
    caller then removes the episodes its manifest does not list), yet Dask's nanny lets a
    busy worker finish its task for up to 4 s (0.8 of its 5 s close timeout) before
    killing it: Ctrl-C took 4.1-4.5 s to return with episodes of 20 frames.
    """
    import asyncio

    async def close_all() -> None:
        await asyncio.gather(*(w.close(timeout=timeout, reason="run stopped") for w in list(cluster.workers.values())),
                             return_exceptions=True)

    with contextlib.suppress(Exception):        # cluster.close() below has the last word
        cluster.sync(close_all)


class _BadAddress(Exception):
    """An address Dask cannot connect to at all (why, in its own words)."""


def wait_for_a_worker(client, scheduler: str) -> None:
    """Return once the cluster at ``scheduler`` has a worker; while it has none, say so
    first (one line on stderr): a run on a cluster that no worker has joined yet would
    otherwise wait without a word."""
    if not client.scheduler_info().get("workers"):
        print(f"warning: --scheduler: no worker has joined {scheduler} yet; waiting for one (Ctrl-C stops)",
              file=sys.stderr)
        client.wait_for_workers(1)


#: The protocols of a Dask scheduler that this process can reach over the network.
NETWORK_SCHEMES = ("tcp", "tls", "ws", "wss")


def check_scheduler(address: str, timeout: float) -> None:
    """A one-line ValueError unless a Dask scheduler at ``address`` answers "identity" within
    ``timeout`` seconds. ``Client`` alone waited forever on a port that accepts and never
    answers (the dashboard's, an HTTP server) and crashed on one that answers garbage."""
    import asyncio

    from distributed.comm import connect
    from distributed.security import Security

    scheme = address.split("://", 1)[0]
    if scheme not in (*NETWORK_SCHEMES, "inproc"):      # inproc: a scheduler of this process (tests)
        raise ValueError(f"scheduler: cannot use the address {address} (protocol {scheme!r}; expected "
                         f"{', '.join(s + '://' for s in NETWORK_SCHEMES)})")
    if scheme == "inproc" and address.split("://", 1)[1].count("/") != 2:    # Dask: "not enough values to unpack"
        raise ValueError(f"scheduler: cannot use the address {address} (an inproc address is "
                         "inproc://HOST/PID/N, a scheduler inside this process)")
    try:
        port = (_host_port(address) or (None, None))[1]
    except ValueError as exc:                   # no port, or not a number
        raise ValueError(f"scheduler: cannot use the address {address} ({exc})") from None
    if port is not None and not 0 < port < 65536:   # Dask's resolver takes it modulo 65536: another port
        raise ValueError(f"scheduler: cannot use the address {address} (port {port} is not in 1..65535)")
    security = Security().get_connection_args("client")     # as Client's: the Dask config's TLS settings

    async def identity():
        try:
            comm = await connect(address, timeout=timeout, **security)
        except (ValueError, TypeError) as exc:      # a malformed address or TLS settings: nothing was sent
            raise _BadAddress(str(exc).splitlines()[0] if str(exc) else type(exc).__name__) from None
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        reply = asyncio.run(asyncio.wait_for(identity(), timeout))
    except _BadAddress as exc:
        raise ValueError(f"scheduler: cannot use the address {address} ({exc})") from None
    except (TimeoutError, OSError):
        why = _why_unreachable(address)
        why = f"{why}; tried for {timeout:g} s" if why else f"no answer within {timeout:g} s"
        raise ValueError(f"scheduler: cannot reach a Dask scheduler at {address} ({why})") from None
    except Exception as exc:  # noqa: BLE001 - whatever the other end sent, it was not Dask's answer
        raise ValueError(f"scheduler: {address} is not a Dask scheduler ({type(exc).__name__})") from None
    if not (isinstance(reply, dict) and reply.get("type") == "Scheduler"):
        raise ValueError(f"scheduler: {address} is not a Dask scheduler (it answered {str(reply)[:60]!r})")


def _host_port(address: str) -> tuple[str, int] | None:
    """(host, port) of a TCP-based Dask ``address`` (tcp, tls, ws, wss), else None; a
    ValueError in Dask's words when the port is missing, "port 'x' is not a number" when
    it is not one (Python's words were "invalid literal for int() with base 10: 'x'")."""
    from distributed.comm.addressing import parse_address, parse_host_port

    scheme, location = parse_address(address)
    if scheme not in NETWORK_SCHEMES:
        return None
    try:
        return parse_host_port(location)
    except ValueError as exc:
        if not str(exc).startswith("invalid literal for int()"):
            raise                               # "missing port number in address ...", "invalid address ..."
        raise ValueError(f"port {location.rpartition(':')[2]!r} is not a number") from None


def _why_unreachable(address: str, timeout: float = 1.0) -> str | None:
    """Why a TCP connection to ``address`` fails now ("Connection refused", "Name or service
    not known"), or None (it connects, or times out). Dask retries such a connection until
    its timeout and then says "Timed out trying to connect", or its last attempt was cut
    short and the reason lost: a typo in a host name read as a firewall dropping packets."""
    import socket

    if (where := _host_port(address)) is None:
        return None
    try:
        with socket.create_connection(where, timeout=timeout):
            return None
    except OSError as exc:
        return exc.strerror                 # None for a time-out


def run_tasks(
    func: Callable[..., Any],
    tasks: Sequence[tuple],
    *,
    client: Any = None,
    workers: int | None = 0,
    scheduler: str | None = None,
    progress: bool = True,
    desc: str | None = None,
    weights: Sequence[float] | None = None,
) -> list:
    """Return ``[func(*args) for args in tasks]``, computed in parallel, in task order.

    func : a picklable (module-level) function
    tasks : list of argument tuples
    client : an open ``distributed.Client`` (from :func:`open_client`); if ``None``, one
        is opened for this call from ``workers`` / ``scheduler`` (``workers=0``: in-process)
    weights : relative cost of each task, used only for the progress bar
    A task's exception is re-raised here.
    """
    tasks = list(tasks)
    w = [1.0] * len(tasks) if weights is None else [float(x) for x in weights]
    bar = tqdm(total=sum(w), desc=desc, disable=not progress, file=sys.stderr,
               unit="trial" if weights is not None else "task", dynamic_ncols=True,
               bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} [{elapsed}<{remaining}]")
    try:
        if client is None:      # workers=0 and no scheduler: open_client gives None, run here
            with open_client(workers, scheduler) as own:
                return _run_on(own, func, tasks, w, bar)
        return _run_on(client, func, tasks, w, bar)
    finally:
        bar.close()


def _run_on(client, func, tasks, w, bar) -> list:
    if client is None:
        out = []
        for args, wi in zip(tasks, w):
            out.append(func(*args))
            bar.update(wi)
        return out
    from distributed import as_completed

    futures = [client.submit(func, *args, pure=False) for args in tasks]
    index = {f.key: i for i, f in enumerate(futures)}
    results: list = [None] * len(tasks)
    try:
        for fut in as_completed(futures):
            stops.check()                       # a Ctrl-C that a future's finalizer swallowed
            i = index[fut.key]
            results[i] = fut.result()
            bar.update(w[i])
    finally:
        for f in futures:
            f.cancel()
    return results
