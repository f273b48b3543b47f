"""camtask's dispatcher: what every command pays at start-up, and Ctrl-C during it."""

import subprocess
import sys

from testbed import cli

#: Modules that take ~0.5-1 s each to import and only some commands need.
HEAVY = ("sklearn", "scipy.optimize", "scipy.stats")


def test_building_the_parser_leaves_the_heavy_imports_to_the_commands_that_use_them():
    code = ("import sys, testbed.cli as c; c.build_parser(); "
            f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == ""


def test_the_clustering_tasker_and_the_tracker_still_import_what_they_use():
    import numpy as np

    from tasking.clustering import cluster_axes
    from tasking.tracker import Tracker, TrackerParams

    centres, sizes = cluster_axes(np.array([0.1, 0.12, 1.5, 1.52]), 2, seed=0)
    assert np.round(np.sort(centres), 2).tolist() == [0.11, 1.51] and sizes.tolist() == [2, 2]
    tracker = Tracker(TrackerParams(confirm_hits=1))
    tracker.step(np.array([[1.0, 1.0]]))                # births a track
    ids, xy = tracker.step(np.array([[1.0, 1.0]]))      # matched: linear_sum_assignment
    assert ids.tolist() == [0] and np.allclose(xy, [[1.0, 1.0]])


def test_ctrl_c_while_the_commands_import_is_one_line(monkeypatch, capsys):
    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "build_parser", interrupted)
    assert cli.main(["--help"]) == 130
    assert capsys.readouterr().err == "camtask: interrupted\n"


def test_ctrl_c_while_pyrender_imports_is_not_swallowed():
    """trimesh imports its optional parts inside ``except BaseException``: Ctrl-C there was
    lost and the run exited 0. It is held during the import and delivered after it."""
    import os
    import signal

    import pytest

    from render.gl import signals_held

    reached = []
    # pytest started with SIGINT ignored (`pytest &` in a script, nohup) inherits SIG_IGN:
    # the test sends Ctrl-C, so it needs Python's own handler whatever the runner did
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt), signals_held():
            try:                                        # what trimesh does with its imports
                os.kill(os.getpid(), signal.SIGINT)
            except BaseException:  # noqa: BLE001, S110
                pass
            reached.append(True)
        assert reached == [True] and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, before)


def test_a_reader_that_stops_reading_ends_the_command_quietly(monkeypatch, capsys):
    """`camtask study ... | head`: printed "error: [Errno 32] Broken pipe" and exited 1. A
    broken pipe elsewhere (a socket, a subprocess) is still an error."""
    import io
    import signal

    from testbed.commands import study

    def stopped_reading(args):
        raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(study, "run", stopped_reading)
    assert cli.main(["study", "cameras"]) == 1                      # stdout is fine
    assert capsys.readouterr().err == "camtask study: error: [Errno 32] Broken pipe\n"

    class Closed(io.StringIO):
        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(sys, "stdout", Closed())
    assert cli.main(["study", "cameras"]) == 128 + signal.SIGPIPE
    assert capsys.readouterr().err == ""


def test_a_pipe_whose_reader_has_gone_is_told_from_its_dropped_buffer(monkeypatch, capsys):
    """`camtask study ... | head -1` said "error: [Errno 32] Broken pipe" in most runs: the
    failed flush drops what was buffered, so flushing again succeeded and the pipe looked fine."""
    import os
    import signal

    from testbed.commands import study

    read, write = os.pipe()
    os.close(read)                                          # `head` has what it wanted
    with os.fdopen(write, "w") as stdout:
        monkeypatch.setattr(sys, "stdout", stdout)

        def printed_a_table(args):
            print("a table the reader no longer wants\n" * 2000)   # past the buffer: BrokenPipeError, dropped
        monkeypatch.setattr(study, "run", printed_a_table)
        assert cli.main(["study", "cameras"]) == 128 + signal.SIGPIPE
        assert capsys.readouterr().err == ""
        monkeypatch.undo()


def test_ctrl_c_that_numba_turned_into_a_system_error_is_one_line(monkeypatch, capsys):
    """Ctrl-C while numba's dispatcher called back into Python (to unpickle a constant, as in
    the pipeline's angle_mask) came out as "SystemError: CPUDispatcher(...) returned a result
    with an exception set" after two tracebacks, exit code 1."""
    import pytest

    from testbed.commands import verify
    from testbed.stops import Terminated

    def numba_interrupted(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("CPUDispatcher(<function angle_mask>) returned a result with an exception set") from exc

    monkeypatch.setattr(verify, "run", numba_interrupted)
    assert cli.main(["verify", "x"]) == 130
    assert capsys.readouterr().err == "camtask verify: interrupted\n"

    def terminated(args):
        try:
            raise Terminated
        except KeyboardInterrupt as exc:
            raise SystemError("returned a result with an exception set") from exc

    monkeypatch.setattr(verify, "run", terminated)
    assert cli.main(["verify", "x"]) == 143
    assert capsys.readouterr().err == "camtask verify: terminated\n"

    def broken(args):
        raise SystemError("a real bug")

    monkeypatch.setattr(verify, "run", broken)
    with pytest.raises(SystemError, match="a real bug"):
        cli.main(["verify", "x"])


def test_a_broken_pipe_beside_a_stdout_that_cannot_be_flushed_is_an_error(monkeypatch, capsys):
    """A standard output closed, or failing for another reason, says nothing of a reader
    that has gone: the BrokenPipeError (from a socket, a subprocess) is the command's error."""
    import io

    from testbed.commands import study

    def broken(args):
        raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(study, "run", broken)
    for error in (OSError(5, "Input/output error"), ValueError("I/O operation on closed file.")):
        class Failing(io.StringIO):
            def flush(self, error=error):
                raise error
        monkeypatch.setattr(sys, "stdout", Failing())
        assert cli.main(["study", "cameras"]) == 1
        assert capsys.readouterr().err == "camtask study: error: [Errno 32] Broken pipe\n"


def test_out_of_memory_is_one_line_with_what_numpy_asked_for(monkeypatch, capsys):
    from testbed.commands import verify

    for error, says in ((MemoryError("Unable to allocate 45.0 GiB for an array with shape (100000, 640, 480, 3)"),
                         "Unable to allocate 45.0 GiB for an array with shape (100000, 640, 480, 3)"),
                        (MemoryError(), "no details")):
        def out_of_memory(args, error=error):
            raise error
        monkeypatch.setattr(verify, "run", out_of_memory)
        assert cli.main(["verify", "x"]) == 1
        assert capsys.readouterr().err == f"camtask verify: error: out of memory ({says})\n"


def test_a_broken_pipe_beside_a_stdout_pipe_still_read_is_an_error(monkeypatch, capsys):
    import os

    from testbed.commands import study

    def broken(args):
        raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(study, "run", broken)
    read, write = os.pipe()                                 # its reader is still there
    try:
        with os.fdopen(write, "w") as stdout:
            monkeypatch.setattr(sys, "stdout", stdout)
            assert cli.main(["study", "cameras"]) == 1
            assert capsys.readouterr().err == "camtask study: error: [Errno 32] Broken pipe\n"
            monkeypatch.undo()
    finally:
        os.close(read)
