"""`camtask` stopped by SIGTERM while it starts: one line and exit status 143, as later."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _python(code: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120,
                          check=False)


def test_sigterm_while_the_commands_import_is_one_line():
    """A `kill` in the first second (the commands' imports) ended the run silently, killed
    by the signal, instead of "camtask run: terminated" and 143."""
    code = ("import os, signal, sys, time\n"
            "import testbed.cli as cli\n"
            "def importing():\n"
            "    os.kill(os.getpid(), signal.SIGTERM)\n"
            "    time.sleep(60)\n"
            "cli.build_parser = importing\n"
            "sys.exit(cli.main(['run', 'lab', '--frames', '2']))\n")
    done = _python(code)
    assert (done.returncode, done.stderr) == (143, "camtask run: terminated\n")


def test_the_dispatcher_imports_nothing_heavy_before_its_handlers_are_in_place():
    """`camtask` imports testbed.cli before main() runs: numpy there (0.2-1 s) was a window
    in which SIGTERM went unhandled."""
    done = _python("import sys, testbed.cli; print(sorted(m for m in ('numpy', 'render', 'scene') "
                   "if m in sys.modules))")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
