"""The ``camtask`` command line: a thin dispatcher over command modules.

Each command lives in its own module under ``testbed/commands/`` and exposes
``add_parser(subparsers)``, which registers an ``argparse`` sub-parser whose
``func`` default is called with the parsed namespace and returns an exit code.
Library code never reads argv; only this module does.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import os
import signal
import sys

from testbed import stops

#: Command modules, in the order ``camtask --help`` lists them.
COMMANDS = (
    "testbed.commands.render",
    "testbed.commands.export",
    "testbed.commands.verify",
    "testbed.commands.study",
    "testbed.commands.scanlines",
    "testbed.commands.tune",
    "testbed.commands.run",
    "testbed.commands.demo",
)


class UsageError(Exception):
    """A user mistake on the command line, printed as one line with exit code 2."""


class RunError(Exception):
    """A run stopped by the machine (a full disk, a worker that kept dying), printed as one
    line with exit code 1."""


#: The largest ``--seed``: NumPy's SeedSequence takes no negative integer, Optuna's
#: samplers (``camtask tune``) none from 2**32 up; every command takes the same range.
SEED_MAX = 2**32 - 1


def check_seed(value: int) -> int:
    """``--seed`` of any command, checked before any work starts."""
    if not 0 <= value <= SEED_MAX:
        raise ValueError(f"--seed: expected an integer in 0..{SEED_MAX}, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="camtask",
        description="Rendered synthetic-sensor testbed for camera tasking and occupancy reasoning.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        importlib.import_module(name).add_parser(sub)
    return parser


def _stdout_closed() -> bool:
    """Whether standard output is a pipe whose reader has gone.

    Flushing again is not enough: the failed write dropped the buffer, so a second flush
    has nothing to write and succeeds. The pipe itself says so: polled, a pipe's write end
    reports an error once no reader is left (Linux, macOS).
    """
    import select

    try:
        sys.stdout.flush()
    except BrokenPipeError:
        return True
    except (OSError, ValueError):
        return False
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(events & select.POLLERR for _, events in poller.poll(0))
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):   # no file behind it
        return False


def _prog(argv: list[str] | None) -> str:
    """"camtask COMMAND" for a stop before the arguments are parsed: the first word of
    ``argv`` if it names a command, as the later messages do; else "camtask"."""
    words = sys.argv[1:] if argv is None else argv
    command = words[0] if words else None
    return f"camtask {command}" if command in {m.rsplit(".", 1)[1] for m in COMMANDS} else "camtask"


def main(argv: list[str] | None = None) -> int:
    # OpenCV's own warnings ("findDecoder imread_(...)") would print beside the one-line
    # error a command gives for the same file; set before OpenCV is imported (workers inherit it)
    os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
    # SIGTERM is caught from the first line on: importing the commands (numpy, OpenCV,
    # shapely) takes 0.3-1.2 s, and a `kill` meanwhile ended the process without a word.
    # This module imports nothing heavy at its top for the same reason.
    with stops.handled():          # recorded too: a Ctrl-C that lands in a finalizer is not lost
        return _dispatch(argv)


def _dispatch(argv: list[str] | None) -> int:
    try:
        # no pyrender / PyOpenGL import: only ctypes and scene.checks
        from render.gl import BackendError

        parser = build_parser()     # imports every command module: numpy, OpenCV, shapely
        args = parser.parse_args(argv)
    except BaseException as exc:    # Ctrl-C or SIGTERM in the first second: one line, no traceback
        code = stops.report_stop(exc, _prog(argv))   # (one in an extension module's import can come out chained)
        if code is None:
            raise
        return code
    try:
        return int(args.func(args) or 0)
    except (ValueError, UsageError, FileNotFoundError, FileExistsError) as exc:
        print(f"camtask {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError as exc:          # `camtask study ... | head`: the reader has all it wants
        if not _stdout_closed():                # a pipe to something else: a real failure
            print(f"camtask {args.command}: error: {exc}", file=sys.stderr)
            return 1
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())   # no second error at exit
        return 128 + signal.SIGPIPE
    except (OSError, RunError, BackendError) as exc:    # the machine, not the input: a full disk, no OpenGL
        print(f"camtask {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except MemoryError as exc:              # NumPy's says how much it asked for ("Unable to allocate 45 GiB ...")
        print(f"camtask {args.command}: error: out of memory ({str(exc) or 'no details'})", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, SystemError) as exc:     # SystemError: a signal in numba's dispatcher
        code = stops.report_stop(exc, f"camtask {args.command}")
        if code is None:
            raise
        return code


if __name__ == "__main__":  # pragma: no cover
    # python -m testbed.cli: run the imported module's main, so that the exception classes the
    # commands raise (testbed.cli.RunError, UsageError) are the ones it catches
    from testbed.cli import main as _main

    sys.exit(_main())
