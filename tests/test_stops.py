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
