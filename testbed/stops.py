"""Ctrl-C and SIGTERM that no finalizer can swallow.

Python raises a signal's exception in whatever Python code runs when it comes, a
finalizer (``__del__``) too, where it is printed as "Exception ignored in ..." and
lost: a Ctrl-C that landed in a Dask future's ``__del__`` (run when an episode's future
is dropped) let the render go on to finish and exit 0. The handlers here also record the
signal, and the loops that wait for work call :func:`check`, which raises it again;
the finalizer's "Exception ignored" traceback is not printed.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a batch scheduler's time limit), raised where Ctrl-C would be, so a
    run stops as cleanly: temporary folders removed, the manifest listing what finished."""


#: The signals that came while :func:`handled` was in place (cleared when it ends).
_came: list[int] = []


def _stop(signum: int) -> KeyboardInterrupt:
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def _handler(signum, frame) -> None:
    _came.append(signum)
    raise _stop(signum)


def _unraisable(hook):
    """``sys.unraisablehook`` that keeps quiet about a recorded signal's exception (it is
    raised again at the next :func:`check`, and the command says so in one line)."""
    def quiet(unraisable) -> None:
        if not (_came and isinstance(unraisable.exc_value, KeyboardInterrupt)):
            hook(unraisable)
    return quiet


def check() -> None:
    """Raise the Ctrl-C or SIGTERM that came (and may have been swallowed), if any."""
    if _came:
        raise _stop(_came[0])


@contextlib.contextmanager
def handled() -> Iterator[None]:
    """SIGTERM raises :class:`Terminated` and Ctrl-C KeyboardInterrupt (unless Ctrl-C is
    ignored, as under ``nohup``), both recorded for :func:`check`, for the ``with`` block;
    in another thread than the main one (where handlers run) this does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _came.clear()
    previous = {signal.SIGTERM: signal.signal(signal.SIGTERM, _handler)}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, _handler)
    hook, sys.unraisablehook = sys.unraisablehook, _unraisable(sys.unraisablehook)
    try:
        yield
    finally:
        sys.unraisablehook = hook
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
        _came.clear()


def interruption(exc: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM behind ``exc``, if any: a signal that lands while numba's
    dispatcher calls back into Python (to unpickle a constant) comes out as ``SystemError:
    CPUDispatcher(...) returned a result with an exception set``, caused by it."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def report_stop(exc: BaseException, prog: str) -> int | None:
    """For an ``exc`` that is (or was caused by) a Ctrl-C or SIGTERM, print one line on
    stderr, "PROG: interrupted" or "PROG: terminated", and return the exit status (130,
    143); else None (the caller re-raises)."""
    stop = interruption(exc)
    if stop is None:
        return None
    terminated = isinstance(stop, Terminated)
    print(f"{prog}: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
    return 128 + int(signal.SIGTERM if terminated else signal.SIGINT)


def run_main(main, prog: str) -> int:
    """Exit status of a script's ``main()`` run under :func:`handled`: a Ctrl-C or SIGTERM
    ends it with one line on stderr, "PROG: interrupted" (130) or "PROG: terminated" (143),
    once its ``finally`` blocks have run (temporary folders removed), not a traceback."""
    with handled():
        try:
            return int(main() or 0)
        except (KeyboardInterrupt, SystemError) as exc:
            code = report_stop(exc, prog)
            if code is None:
                raise
            return code
