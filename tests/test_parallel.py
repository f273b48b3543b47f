"""The local Dask cluster's workers: environment."""

import contextlib
import os
import shutil

import pytest

from testbed.parallel import open_client


def _env():
    return {k: os.environ.get(k) for k in ("MALLOC_TRIM_THRESHOLD_", "OMP_NUM_THREADS", "LP_NUM_THREADS",
                                        "OPENCV_FOR_THREADS_NUM")} | {"cv2_threads": _cv2_threads()}


def _cv2_threads():
    import cv2

    return cv2.getNumThreads()


def test_workers_keep_glibc_malloc_defaults_and_one_opencv_thread():
    # Dask's nanny would set MALLOC_TRIM_THRESHOLD_, which makes numpy temporaries slow
    with open_client(1) as client:
        envs = list(client.run(_env).values())
        assert list(client.nthreads().values()) == [1]                   # one thread per worker
    assert envs == [{"MALLOC_TRIM_THRESHOLD_": None, "OMP_NUM_THREADS": "1", "LP_NUM_THREADS": "1",
                     "OPENCV_FOR_THREADS_NUM": "1", "cv2_threads": 1}]     # one OpenCV thread too


def _sigint_handler():
    import signal

    return signal.getsignal(signal.SIGINT) == signal.SIG_IGN


def test_local_workers_ignore_ctrl_c():
    # Ctrl-C reaches the whole process group: the client stops the cluster, the workers
    # must not each print a KeyboardInterrupt traceback (end to end: test_dataset_worker_death)
    with open_client(2) as client:
        assert list(client.run(_sigint_handler).values()) == [True, True]


class Terminated(Exception):
    pass


def _terminated(signum, frame):
    raise Terminated


@pytest.mark.parametrize("signame", ["SIGINT", "SIGTERM"])
def test_a_signal_while_a_local_cluster_starts_waits_for_it_then_closes_it(monkeypatch, signame):
    """A half-started LocalCluster printed tracebacks: Ctrl-C (SIGINT), or a batch scheduler's
    SIGTERM, is held until it has started, then stops the run and the cluster is closed as usual."""
    import signal

    import distributed

    events = []

    class Cluster:
        def __init__(self, **kwargs):
            os.kill(os.getpid(), getattr(signal, signame))        # while the workers start
            events.append("started")

        def close(self):
            events.append("cluster closed")

    class Client:
        def __init__(self, cluster):
            events.append("client")

        def close(self):
            events.append("client closed")

    monkeypatch.setattr(distributed, "LocalCluster", Cluster)
    monkeypatch.setattr(distributed, "Client", Client)
    before = signal.signal(signal.SIGTERM, _terminated)
    try:
        with pytest.raises(KeyboardInterrupt if signame == "SIGINT" else Terminated), open_client(2):
            events.append("body")
    finally:
        signal.signal(signal.SIGTERM, before)
    assert events == ["started", "client", "client closed", "cluster closed"]


def test_a_local_clusters_warnings_as_it_starts_are_not_shown(monkeypatch):
    """Only those: the process's own warnings are shown afterwards."""
    import warnings

    import distributed

    events = []
    _fake_cluster(monkeypatch, events)
    started = distributed.LocalCluster

    def cluster(**kwargs):
        warnings.warn("Port 8787 is already in use.", UserWarning, stacklevel=1)
        return started(**kwargs)

    monkeypatch.setattr(distributed, "LocalCluster", cluster)
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        with open_client(1):
            pass
        warnings.warn("this process's own", UserWarning, stacklevel=1)     # shown as before
    assert [str(w.message) for w in shown] == ["this process's own"]
    assert events == [("cluster", 1), "client closed", "cluster closed"]


@pytest.mark.parametrize(("answer", "message"), [
    (None, "cannot reach a Dask scheduler at tcp://127.0.0.1:{port} (no answer within 1 s)"),
    (b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n", "tcp://127.0.0.1:{port} is not a Dask scheduler"),
])
def test_a_port_that_is_not_a_dask_scheduler_is_one_line(answer, message):
    """The dashboard's port accepts and never answers: Client waited forever; a server that
    answers something else crashed it with a 3 EiB allocation."""
    import socket
    import threading

    from testbed.parallel import check_scheduler

    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    held = []

    def serve():
        conn, _ = server.accept()
        held.append(conn)
        conn.recv(4096)
        if answer is not None:
            conn.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    try:
        with pytest.raises(ValueError) as info:
            check_scheduler(f"tcp://127.0.0.1:{port}", 1.0)
        assert str(info.value).startswith(f"scheduler: {message.format(port=port)}")
        assert "\n" not in str(info.value)
    finally:
        for conn in held:
            conn.close()
        server.close()


def test_a_port_out_of_range_is_a_bad_address_not_an_unreachable_one():
    """Dask's resolver takes a port modulo 65536 (99999 -> 34463): refused as an address that
    cannot be used, not reported as a scheduler tried for the whole timeout."""
    from testbed.parallel import check_scheduler

    with pytest.raises(ValueError) as info:
        check_scheduler("tcp://127.0.0.1:99999", 1.0)
    assert str(info.value) == "scheduler: cannot use the address tcp://127.0.0.1:99999 (port 99999 is not in 1..65535)"
    with pytest.raises(ValueError) as info:             # one past the last port: port 0
        check_scheduler("tcp://127.0.0.1:65536", 1.0)
    assert str(info.value) == "scheduler: cannot use the address tcp://127.0.0.1:65536 (port 65536 is not in 1..65535)"


def test_an_unreachable_scheduler_says_why():
    """Nothing listening, or a host name that does not resolve (a typo), was reported as "Timed
    out trying to connect ... after 5 s" or "no answer within 5 s", as if a firewall dropped
    the packets: Dask retries such a connection until its timeout, and the reason was lost."""
    import socket

    from testbed.parallel import check_scheduler

    with socket.create_server(("127.0.0.1", 0)) as server:
        port = server.getsockname()[1]              # closed again: nothing listens there
    with pytest.raises(ValueError) as info:
        check_scheduler(f"tcp://127.0.0.1:{port}", 1.0)
    assert str(info.value) == (f"scheduler: cannot reach a Dask scheduler at tcp://127.0.0.1:{port} "
                               "(Connection refused; tried for 1 s)")
    try:
        socket.getaddrinfo("camtask-no-such-host.invalid", 8786)
    except socket.gaierror as exc:
        why = exc.strerror                          # "Name or service not known", or no DNS at all
    else:
        pytest.skip("this machine's resolver answers for a .invalid name")
    with pytest.raises(ValueError) as info:
        check_scheduler("tcp://camtask-no-such-host.invalid:8786", 1.0)
    assert str(info.value) == ("scheduler: cannot reach a Dask scheduler at tcp://camtask-no-such-host.invalid:8786 "
                               f"({why}; tried for 1 s)")


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs openssl for a self-signed certificate")
def test_a_tls_scheduler_set_up_in_the_dask_config_passes_the_check(tmp_path):
    """The check connects as Client does, with the Dask config's TLS settings for a client
    (the scheduler's own are given to it, not set in the config)."""
    import subprocess

    import dask
    from distributed import LocalCluster
    from distributed.security import Security

    from testbed.parallel import check_scheduler

    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=localhost", "-days", "1",
                    "-keyout", str(key), "-out", str(cert)], check=True, capture_output=True)
    tls = {"distributed.comm.tls.ca-file": str(cert), "distributed.comm.require-encryption": True,
           "distributed.comm.tls.client.cert": str(cert), "distributed.comm.tls.client.key": str(key)}
    scheduler = Security(tls_ca_file=str(cert), require_encryption=True, tls_scheduler_cert=str(cert),
                         tls_scheduler_key=str(key), tls_client_cert=str(cert), tls_client_key=str(key))
    with dask.config.set(tls), LocalCluster(n_workers=0, processes=False, protocol="tls", dashboard_address=None,
                                            security=scheduler) as cluster:
        assert cluster.scheduler_address.startswith("tls://")
        check_scheduler(cluster.scheduler_address, 5.0)        # raises unless it answered as a scheduler


def _sigint_blocked():
    import signal

    return signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, [])


def test_local_workers_start_with_ctrl_c_blocked():
    """A worker still importing (numpy, distributed: a second or more on a busy machine)
    when Ctrl-C reached the process group printed a page of KeyboardInterrupt traceback:
    dask_setup ignores SIGINT only once the imports are done. The workers start with it
    blocked (inherited from the threads that spawn them); this process gets it back."""
    import signal

    with open_client(2) as client:
        assert list(client.run(_sigint_blocked).values()) == [True, True]
        assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])


def test_ctrl_c_while_the_workers_import_prints_one_line(tmp_path):
    """End to end: Ctrl-C to the whole process group as soon as the worker processes exist."""
    import signal
    import subprocess
    import sys
    import time

    import psutil

    args = [sys.executable, "-m", "testbed.cli", "study", "cameras", "--objects", "1", "--cameras", "4",
            "--trials", "40", "--workers", "2", "--no-progress"]   # 2 tasks of 20 trials: 2 workers
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    me = psutil.Process(proc.pid)

    def importing():
        # a worker process that has started Python and is importing (before that, SIGINT just
        # ends it): one whose resident memory has grown past a bare interpreter's
        with contextlib.suppress(psutil.Error):
            return any("spawn_main" in " ".join(c.cmdline()) and c.memory_info().rss > 40e6
                       for c in me.children(recursive=True))
        return False

    deadline = time.time() + 60
    while proc.poll() is None and not importing() and time.time() < deadline:
        time.sleep(0.002)
    os.killpg(proc.pid, signal.SIGINT)
    err = proc.communicate(timeout=120)[1]
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.strip() == "camtask study: interrupted"


def test_ctrl_c_while_the_local_cluster_closes_lets_it_close(monkeypatch):
    """A second Ctrl-C (the first one's close takes seconds) interrupted client.close(): the
    cluster was left to Dask's atexit hook (~10 s more), and its workers could still rename a
    finished episode into DIR after the render had removed the unlisted ones."""
    import signal

    import distributed

    events = []

    class Cluster:
        def __init__(self, **kwargs):
            events.append("started")

        def close(self):
            events.append("cluster closed")

    class Client:
        def __init__(self, cluster):
            pass

        def close(self):
            os.kill(os.getpid(), signal.SIGINT)         # the second Ctrl-C
            events.append("client closed")

    monkeypatch.setattr(distributed, "LocalCluster", Cluster)
    monkeypatch.setattr(distributed, "Client", Client)
    with pytest.raises(KeyboardInterrupt), open_client(2):
        raise KeyboardInterrupt                          # the first one
    assert events == ["started", "client closed", "cluster closed"]


def test_a_port_that_is_not_a_number_says_so():
    """Python's own words for it were "invalid literal for int() with base 10: 'abc'"."""
    from testbed.parallel import check_scheduler

    for address, port in [("tcp://127.0.0.1:abc", "abc"), ("tcp://127.0.0.1:8786/", "8786/"),
                          ("tls://[::1]:x1", "x1"), ("tcp://127.0.0.1:", "")]:
        with pytest.raises(ValueError) as info:
            check_scheduler(address, 1.0)
        assert str(info.value) == f"scheduler: cannot use the address {address} (port {port!r} is not a number)"
    with pytest.raises(ValueError) as info:         # no port at all: Dask's words
        check_scheduler("tcp://127.0.0.1", 1.0)
    assert str(info.value) == "scheduler: cannot use the address tcp://127.0.0.1 (missing port number in address '127.0.0.1')"


def test_dask_setup_makes_a_worker_ignore_sigint(monkeypatch):
    import signal

    from testbed import parallel

    calls = []
    monkeypatch.setattr(signal, "signal", lambda *args: calls.append(args))
    parallel.dask_setup(None)
    assert calls == [(signal.SIGINT, signal.SIG_IGN)]


def test_children_ignore_ctrl_c_leaves_another_thread_and_an_already_blocked_sigint_alone():
    """Only the main thread blocks SIGINT (only it gets Ctrl-C); one that was blocked before
    stays blocked."""
    import signal
    import threading

    from testbed.parallel import children_ignore_ctrl_c

    def blocked():
        return signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, [])

    seen = []

    def other_thread():
        with children_ignore_ctrl_c():
            seen.append(blocked())
        seen.append(blocked())

    thread = threading.Thread(target=other_thread)
    thread.start()
    thread.join()
    assert seen == [False, False]
    with children_ignore_ctrl_c():
        assert blocked()
    assert not blocked()
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        with children_ignore_ctrl_c():
            assert blocked()
        assert blocked()
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def test_chunk_and_default_workers():
    import os

    from testbed.parallel import chunk, default_workers

    assert chunk(0, 3) == []
    assert chunk(6, 3) == [(0, 3), (3, 6)]
    assert chunk(7, 3) == [(0, 3), (3, 6), (6, 7)]
    assert chunk(3, 0) == [(0, 1), (1, 2), (2, 3)]           # a size below 1 counts as 1
    assert chunk(3, 2.9) == [(0, 2), (2, 3)]
    assert default_workers() == len(os.sched_getaffinity(0))


def test_default_workers_are_the_cores_this_process_may_use(monkeypatch):
    """Not all the machine's: taskset or a batch scheduler may give it fewer."""
    from testbed.parallel import default_workers

    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 5, 7})
    assert default_workers() == 3


def _no_cluster(monkeypatch):
    import distributed

    def refuse(*args, **kwargs):
        raise AssertionError("no cluster was to be started")

    monkeypatch.setattr(distributed, "LocalCluster", refuse)
    monkeypatch.setattr(distributed, "Client", refuse)


def test_a_negative_worker_count_is_refused_unless_a_scheduler_is_given(monkeypatch):
    _no_cluster(monkeypatch)
    with pytest.raises(ValueError) as info, open_client(-1):
        pass
    assert str(info.value) == "workers: expected an integer >= 0, got -1"
    with open_client(0) as client:                  # 0: this process
        assert client is None
    with pytest.raises(ValueError) as info, open_client(0, scheduler="tcp://127.0.0.1:0"):
        pass                                        # not this process: the scheduler's cluster
    assert "port 0 is not in 1..65535" in str(info.value)
    with pytest.raises(ValueError) as info, open_client(-1, scheduler="tcp://127.0.0.1:0"):
        pass                                        # workers are ignored: the address is checked
    assert "port 0 is not in 1..65535" in str(info.value)


def test_a_client_that_cannot_connect_after_the_check_is_one_line(monkeypatch):
    import distributed

    from testbed import parallel

    checked = []
    monkeypatch.setattr(parallel, "check_scheduler", lambda address, timeout: checked.append((address, timeout)))
    for exc, why in [(OSError("Timed out trying to connect to tcp://10.0.0.5:8786 after 2 s\nmore"),
                      "Timed out trying to connect to tcp://10.0.0.5:8786 after 2 s"),
                     (TimeoutError(), "TimeoutError"), (ValueError("bad\nmore"), "bad")]:
        def client(address, timeout, exc=exc):
            assert (address, timeout) == ("tcp://10.0.0.5:8786", "2.0s")
            raise exc

        monkeypatch.setattr(distributed, "Client", client)
        with pytest.raises(ValueError) as info, open_client(scheduler="10.0.0.5:8786", connect_timeout=2.0):
            pass
        assert str(info.value) == f"scheduler: cannot reach a Dask scheduler at tcp://10.0.0.5:8786 ({why})"
    assert checked == [("tcp://10.0.0.5:8786", 2.0)] * 3


def test_a_scheduler_client_silences_dask_logs_while_open_and_is_closed(monkeypatch):
    import logging

    import distributed

    from testbed import parallel

    events = []

    class Client:
        def __init__(self, address, timeout):
            events.append(address)

        def close(self):
            events.append("closed")

    monkeypatch.setattr(parallel, "check_scheduler", lambda address, timeout: None)
    monkeypatch.setattr(distributed, "Client", Client)
    loggers = [logging.getLogger(name) for name in ("distributed", "distributed.client")]
    before = [log.level for log in loggers]
    monkeypatch.setattr(loggers[1], "level", logging.DEBUG)
    with pytest.raises(RuntimeError), open_client(scheduler="tls://h:1") as client:
        assert isinstance(client, Client)
        assert [log.level for log in loggers] == [logging.CRITICAL] * 2
        raise RuntimeError
    assert events == ["tls://h:1", "closed"]
    assert [log.level for log in loggers] == [before[0], logging.DEBUG]


def _fake_cluster(monkeypatch, events, *, fail_cluster=False, fail_client=False):
    import distributed

    from testbed import parallel

    class Cluster:
        def __init__(self, **kwargs):
            if fail_cluster:
                raise RuntimeError("cluster")
            events.append(("cluster", kwargs["n_workers"]))

        def close(self):
            events.append("cluster closed")

    class Client:
        def __init__(self, cluster):
            if fail_client:
                raise RuntimeError("client")

        def close(self):
            events.append("client closed")

    monkeypatch.setattr(distributed, "LocalCluster", Cluster)
    monkeypatch.setattr(distributed, "Client", Client)
    monkeypatch.setattr(parallel, "stop_workers", lambda cluster: events.append("workers stopped"))
    monkeypatch.setattr(parallel, "default_workers", lambda: 3)


def test_a_local_cluster_that_fails_to_start_closes_what_did_start(monkeypatch):
    import signal

    events = []
    _fake_cluster(monkeypatch, events, fail_cluster=True)
    with pytest.raises(RuntimeError, match="cluster"), open_client(2):
        pass
    assert events == []                                 # nothing to close
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])
    _fake_cluster(monkeypatch, events, fail_client=True)
    with pytest.raises(RuntimeError, match="client"), open_client(2):
        pass
    assert events == [("cluster", 2), "workers stopped", "cluster closed"]


def test_a_local_cluster_stops_its_workers_only_when_the_run_stops(monkeypatch):
    events = []
    _fake_cluster(monkeypatch, events)
    with open_client() as client:                   # None: the number of cores
        assert client is not None
    assert events == [("cluster", 3), "client closed", "cluster closed"]
    events.clear()
    with pytest.raises(KeyboardInterrupt), open_client(1):
        raise KeyboardInterrupt
    assert events == [("cluster", 1), "client closed", "workers stopped", "cluster closed"]


def test_an_address_dask_cannot_connect_to_says_why_without_a_wait():
    """A tls:// address with no TLS settings in the Dask config: nothing is sent."""
    from testbed.parallel import check_scheduler

    with pytest.raises(ValueError) as info:
        check_scheduler("tls://127.0.0.1:8786", 5.0)
    assert str(info.value).startswith("scheduler: cannot use the address tls://127.0.0.1:8786 (TLS expects "
                                      "a `ssl_context` argument")
    assert "\n" not in str(info.value)



@pytest.mark.parametrize("address", ["inproc://x", "inproc://", "inproc://h/1/2/3"])
def test_a_malformed_inproc_address_names_the_form_it_takes(address):
    """Dask's words were "not enough values to unpack (expected 3, got 1)"."""
    from testbed.parallel import check_scheduler

    with pytest.raises(ValueError) as info:
        check_scheduler(address, 5.0)
    assert str(info.value) == (f"scheduler: cannot use the address {address} (an inproc address is "
                               "inproc://HOST/PID/N, a scheduler inside this process)")


class _Comm:
    """A Dask comm that answers ``reply`` to an identity request."""

    def __init__(self, reply, log):
        self.reply, self.log = reply, log

    async def write(self, msg):
        self.log.append(msg)

    async def read(self):
        return self.reply

    def abort(self):
        self.log.append("aborted")


@pytest.mark.parametrize(("reply", "why"), [
    ({"type": "Worker", "id": "w"}, "it answered \"{'type': 'Worker', 'id': 'w'}\""),
    ("x" * 100, "it answered " + repr("x" * 60)),
    ([1, 2], "it answered '[1, 2]'"),
    (None, None),                                # Dask's connect raised without a message
    ({"id": "s"}, "it answered \"{'id': 's'}\""),
    ({"type": "Scheduler", "id": "s"}, ""),
])
def test_what_a_server_answers_decides_if_it_is_a_dask_scheduler(monkeypatch, reply, why):
    import distributed.comm

    from testbed.parallel import check_scheduler

    log, seen = [], []

    async def connect(address, timeout, **kwargs):
        seen.append((address, timeout))
        if reply is None:
            raise TypeError
        return _Comm(reply, log)

    monkeypatch.setattr(distributed.comm, "connect", connect)
    address = "tcp://127.0.0.1:65535"                # the highest port there is
    if why == "":
        check_scheduler(address, 2.5)
    else:
        with pytest.raises(ValueError) as info:
            check_scheduler(address, 2.5)
        assert str(info.value) == (f"scheduler: cannot use the address {address} (TypeError)" if why is None
                                   else f"scheduler: {address} is not a Dask scheduler ({why})")
    assert seen == [(address, 2.5)]
    assert log == ([] if reply is None else [{"op": "identity", "reply": True}, "aborted"])


def test_a_server_that_answers_after_the_timeout_gives_no_answer(monkeypatch):
    import asyncio

    import distributed.comm

    from testbed.parallel import check_scheduler

    class Late(_Comm):
        async def read(self):
            await asyncio.sleep(0.3)
            return self.reply

    log = []

    async def connect(address, timeout, **kwargs):
        return Late({"type": "Scheduler", "id": "s"}, log)

    monkeypatch.setattr(distributed.comm, "connect", connect)
    with pytest.raises(ValueError) as info:
        check_scheduler("inproc://h/1/2", 0.2)
    assert str(info.value) == "scheduler: cannot reach a Dask scheduler at inproc://h/1/2 (no answer within 0.2 s)"
    assert log == [{"op": "identity", "reply": True}, "aborted"]


def test_an_address_dask_refuses_in_several_lines_is_one_line(monkeypatch):
    import distributed.comm

    from testbed.parallel import check_scheduler

    async def connect(address, timeout, **kwargs):
        raise ValueError("unknown address\nmore about it")

    monkeypatch.setattr(distributed.comm, "connect", connect)
    with pytest.raises(ValueError) as info:
        check_scheduler("tcp://127.0.0.1:8786", 1.0)
    assert str(info.value) == "scheduler: cannot use the address tcp://127.0.0.1:8786 (unknown address)"


def test_only_tcp_based_addresses_are_tried_with_a_socket():
    from distributed.comm.inproc import new_address

    from testbed.parallel import _host_port, _why_unreachable, check_scheduler

    assert _host_port("tcp://10.0.0.5:8786") == ("10.0.0.5", 8786)
    assert _host_port("wss://[::1]:443") == ("::1", 443)
    assert _host_port("ucx://10.0.0.5:8786") is None
    with pytest.raises(ValueError, match="^missing port number in address '10.0.0.5'$"):
        _host_port("tcp://10.0.0.5")                # Dask's words, not tried without a port
    address = new_address()                         # of this process, nothing listens there
    assert _host_port(address) is None and _why_unreachable(address) is None
    with pytest.raises(ValueError) as info:
        check_scheduler(address, 0.25)
    assert str(info.value) == f"scheduler: cannot reach a Dask scheduler at {address} (no answer within 0.25 s)"


def test_why_unreachable_tries_once_within_its_timeout(monkeypatch):
    import socket

    from testbed.parallel import _why_unreachable

    calls = []

    def connect(where, timeout):
        calls.append((where, timeout))
        raise (TimeoutError("timed out") if where[1] == 1 else ConnectionRefusedError(111, "Connection refused"))

    monkeypatch.setattr(socket, "create_connection", connect)
    assert _why_unreachable("tcp://10.0.0.5:1", timeout=0.3) is None            # a time-out: no reason
    assert _why_unreachable("ws://10.0.0.5:2", timeout=0.3) == "Connection refused"
    assert calls == [(("10.0.0.5", 1), 0.3), (("10.0.0.5", 2), 0.3)]


def test_stop_workers_closes_every_worker_with_the_timeout_even_if_one_fails():
    import asyncio

    from testbed.parallel import stop_workers

    closed = []

    class Worker:
        def __init__(self, name, fails):
            self.name, self.fails = name, fails

        async def close(self, timeout, reason):
            if self.fails:
                raise RuntimeError("already gone")
            await asyncio.sleep(0.01)
            closed.append((self.name, timeout, reason))

    class Cluster:
        def __init__(self):
            self.workers = {0: Worker("a", True), 1: Worker("b", False)}

        def sync(self, func):
            return asyncio.run(func())

    stop_workers(Cluster(), timeout=0.2)
    assert closed == [("b", 0.2, "run stopped")]


def test_wait_for_a_worker_says_so_only_when_there_is_none(capsys):
    from testbed.parallel import wait_for_a_worker

    class Client:
        def __init__(self, workers):
            self.workers, self.waited = workers, []

        def scheduler_info(self):
            return {"workers": self.workers}

        def wait_for_workers(self, n):
            self.waited.append(n)

    busy = Client({"tcp://w:1": {}})
    wait_for_a_worker(busy, "tcp://s:8786")
    assert busy.waited == [] and capsys.readouterr().err == ""
    empty = Client({})
    wait_for_a_worker(empty, "tcp://s:8786")
    assert empty.waited == [1]
    assert capsys.readouterr().err == ("warning: --scheduler: no worker has joined tcp://s:8786 yet; "
                                       "waiting for one (Ctrl-C stops)\n")


def test_run_tasks_in_this_process_shows_its_progress_in_weights(capsys):
    from testbed.parallel import run_tasks

    assert run_tasks(pow, [(2, 3), (3, 2), (2, 0)], progress=False) == [8, 9, 1]
    assert run_tasks(pow, ((i, 2) for i in range(3)), progress=False) == [0, 1, 4]   # any iterable
    assert capsys.readouterr().err == ""
    assert run_tasks(pow, [(2, 3), (3, 2)], desc="pow") == [8, 9]
    err = capsys.readouterr().err
    assert "pow: 100%" in err and "| 2/2 [" in err
    run_tasks(pow, [(2, 3), (3, 2)], weights=[5, 2])
    assert "| 7/7 [" in capsys.readouterr().err
    run_tasks(pow, [(2, 3), (3, 2), (1, 1)])
    assert "| 3/3 [" in capsys.readouterr().err
    with pytest.raises(ZeroDivisionError) as info:      # held: the bar is closed all the same
        run_tasks(divmod, [(1, 1), (1, 0)])
    err = capsys.readouterr().err
    assert err.endswith("\n") and "| 1/2 [" in err
    del info


class _Future:
    def __init__(self, key, value, log):
        self.key, self.value, self.log = key, value, log

    def result(self):
        if isinstance(self.value, BaseException):
            raise self.value
        return self.value

    def cancel(self):
        self.log.append(("cancel", self.key))


class _Client:
    """submit() computes at once; the futures complete in reverse order (monkeypatched as_completed)."""

    def __init__(self):
        self.log, self.n = [], 0

    def submit(self, func, *args, pure=True):
        self.log.append(("submit", args, pure))
        self.n += 1
        try:
            value = func(*args)
        except Exception as exc:  # noqa: BLE001 - raised by result(), as a Dask future does
            value = exc
        return _Future(f"k{self.n}", value, self.log)


def test_run_tasks_on_a_client_puts_results_in_task_order_and_cancels_the_futures(monkeypatch, capsys):
    import distributed

    from testbed.parallel import run_tasks

    monkeypatch.setattr(distributed, "as_completed", lambda futures: reversed(futures))
    client = _Client()
    assert run_tasks(pow, [(2, 3), (2, 3), (3, 2)], client=client, weights=[1, 1, 2]) == [8, 8, 9]
    assert "| 4/4 [" in capsys.readouterr().err
    assert client.log == [("submit", (2, 3), False), ("submit", (2, 3), False), ("submit", (3, 2), False),
                          ("cancel", "k1"), ("cancel", "k2"), ("cancel", "k3")]
    client = _Client()
    with pytest.raises(ZeroDivisionError):
        run_tasks(divmod, [(1, 0), (4, 2)], client=client, progress=False)
    assert [e for e in client.log if e[0] == "cancel"] == [("cancel", "k1"), ("cancel", "k2")]


def test_run_tasks_on_a_client_raises_a_ctrl_c_that_a_future_swallowed(monkeypatch):
    import signal

    import distributed

    from testbed import stops
    from testbed.parallel import run_tasks

    monkeypatch.setattr(distributed, "as_completed", lambda futures: iter(futures))
    monkeypatch.setattr(stops, "_came", [signal.SIGINT])
    client = _Client()
    with pytest.raises(KeyboardInterrupt):
        run_tasks(pow, [(2, 3)], client=client, progress=False)
    assert client.log[-1] == ("cancel", "k1")


def test_run_tasks_opens_a_client_from_workers_or_scheduler(monkeypatch):
    import distributed

    from testbed import parallel

    opened, clients = [], []

    @contextlib.contextmanager
    def open_client(workers, scheduler):
        opened.append((workers, scheduler))
        clients.append(_Client())
        yield clients[-1]

    monkeypatch.setattr(parallel, "open_client", open_client)
    monkeypatch.setattr(distributed, "as_completed", lambda futures: reversed(futures))
    assert parallel.run_tasks(pow, [(2, 3), (3, 2)], workers=2, progress=False) == [8, 9]
    assert parallel.run_tasks(pow, [(2, 1)], scheduler="tcp://s:1", progress=False) == [2]
    assert opened == [(2, None), (0, "tcp://s:1")]
    assert [[e for e in c.log if e[0] == "submit"] for c in clients] == [      # run there, not here
        [("submit", (2, 3), False), ("submit", (3, 2), False)], [("submit", (2, 1), False)]]
