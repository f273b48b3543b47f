"""A Ctrl-C or SIGTERM that lands in a finalizer (``__del__``) is not lost: Python prints it
as "Exception ignored in ..." and goes on; a render whose Ctrl-C landed in a Dask future's
``__del__`` went on to finish and exit 0."""

import os
import signal

import pytest

from testbed import stops


class _Dropped:
    def __init__(self, signum):
        self.signum = signum

    def __del__(self):                          # as distributed's Future.__del__ when Ctrl-C lands there
        os.kill(os.getpid(), self.signum)


@pytest.mark.parametrize("signum, raised", [(signal.SIGINT, KeyboardInterrupt), (signal.SIGTERM, stops.Terminated)])
def test_a_signal_swallowed_by_a_finalizer_is_raised_at_the_next_check(signum, raised):
    import sys

    shown = []
    before = signal.signal(signal.SIGINT, signal.default_int_handler)     # as a terminal's python has it
    hook, sys.unraisablehook = sys.unraisablehook, shown.append
    try:
        with stops.handled():
            _Dropped(signum)                    # dropped at once: its __del__ gets the signal, which is ignored
            with pytest.raises(raised):
                stops.check()
        stops.check()                           # forgotten once the command is over
        assert shown == []                      # no "Exception ignored in ..." traceback beside the one line
        assert sys.unraisablehook == shown.append
    finally:
        sys.unraisablehook = hook
        signal.signal(signal.SIGINT, before)


def test_the_render_loop_checks(tmp_path, monkeypatch):
    """End to end in this process: the signal swallowed while an episode's future is dropped."""
    from testbed import cli, generate

    real = generate.in_flight
    calls = []

    def in_flight(client, *threads):            # called in the loop, after each finished episode is dropped
        calls.append(1)
        if len(calls) == 2:
            _Dropped(signal.SIGINT)
        return real(client, *threads)

    monkeypatch.setattr(generate, "in_flight", in_flight)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        code = cli.main(["render", "lab", "--episodes", "3", "--frames", "1", "--cameras", "2", "--workers", "1",
                         "--out", str(tmp_path / "d")])
    finally:
        signal.signal(signal.SIGINT, before)
    assert code == 130


def test_a_script_stopped_in_numbas_dispatcher_ends_in_one_line(capsys):
    """run_main (the bench scripts' entry) caught KeyboardInterrupt alone: a Ctrl-C that numba's
    dispatcher turned into "SystemError: CPUDispatcher(...) returned a result with an exception
    set" (the pipeline's compiled kernels) ended in tracebacks, as camtask's commands once did."""
    def numba_interrupted():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("CPUDispatcher(<function angle_mask>) returned a result with an exception set") from exc

    assert stops.run_main(numba_interrupted, "scanlines.py") == 130
    assert capsys.readouterr().err == "scanlines.py: interrupted\n"

    def broken():
        raise SystemError("a real bug")

    with pytest.raises(SystemError, match="a real bug"):
        stops.run_main(broken, "scanlines.py")


class _Raising:
    def __init__(self, exc):
        self.exc = exc

    def __del__(self):                          # Python hands this to sys.unraisablehook
        raise self.exc


def test_a_signal_in_ordinary_code_is_raised_at_once():
    import time

    with stops.handled(), pytest.raises(stops.Terminated):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)                           # not reached: the handler raises where the signal lands


def test_other_finalizer_errors_still_reach_the_hook():
    """Only a recorded signal's exception is kept quiet: another error in a finalizer, or a
    KeyboardInterrupt raised by code rather than by a signal, is passed to the hook as before."""
    import sys

    shown = []
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    hook, sys.unraisablehook = sys.unraisablehook, lambda u: shown.append(type(u.exc_value))
    try:
        with stops.handled():
            _Raising(RuntimeError("in a finalizer"))
            _Raising(KeyboardInterrupt())       # no signal came: not ours to hide
            assert shown == [RuntimeError, KeyboardInterrupt]
            _Dropped(signal.SIGINT)             # a signal swallowed: its exception is quiet ...
            _Raising(RuntimeError("after the signal"))    # ... but not everything after it
            assert shown == [RuntimeError, KeyboardInterrupt, RuntimeError]
            with pytest.raises(KeyboardInterrupt):
                stops.check()
    finally:
        sys.unraisablehook = hook
        signal.signal(signal.SIGINT, before)


def test_the_handlers_before_are_restored():
    def mine(signum, frame):
        pass

    before = signal.signal(signal.SIGTERM, mine), signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with stops.handled():
            assert signal.getsignal(signal.SIGTERM) is not mine
            assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler
        assert signal.getsignal(signal.SIGTERM) is mine
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        signal.signal(signal.SIGINT, signal.SIG_IGN)              # as under nohup: Ctrl-C stays ignored
        with stops.handled():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGTERM, before[0])
        signal.signal(signal.SIGINT, before[1])


def test_in_another_thread_handled_does_nothing():
    import threading

    seen = []

    def work():
        before = signal.getsignal(signal.SIGTERM)
        with stops.handled():
            seen.append(signal.getsignal(signal.SIGTERM) is before)

    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert seen == [True]


def test_interruption_follows_causes_then_contexts_and_ends_on_a_cycle():
    stop = KeyboardInterrupt()
    caused = SystemError("numba")
    caused.__cause__ = stop                     # raise ... from stop, outside any except block
    assert stops.interruption(caused) is stop
    during = SystemError("numba")
    during.__context__ = stop                   # raised while handling stop, no "from"
    assert stops.interruption(during) is stop
    both = SystemError("numba")
    both.__cause__, both.__context__ = stop, RuntimeError("handled first")
    assert stops.interruption(both) is stop     # the cause first, as Python shows it
    assert stops.interruption(RuntimeError("no signal")) is None
    a, b = RuntimeError("a"), RuntimeError("b")
    a.__cause__, b.__context__ = b, a           # a cycle (raise a from b while handling a)
    assert stops.interruption(a) is None


def test_a_scripts_exit_status_is_what_its_main_returns():
    assert stops.run_main(lambda: None, "x.py") == 0
    assert stops.run_main(lambda: 3, "x.py") == 3
