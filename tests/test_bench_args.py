"""A bad argument to a benchmark script is one line naming the option, before any work."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

CASES = [
    ("manifest", ["--episodes", "0"], "--episodes"),
    ("manifest", ["--episodes", "2", "--frames", "1", "--every", "-1"], "--every"),
    ("taskers", ["--repeat", "0"], "--repeat"),
    ("scanlines", ["--frames", "0"], "--frames"),
    ("scanlines", ["--dir", "{missing}", "--frames", "1", "--repeat", "1"], "--dir"),
    ("rendering", ["--steps", "0"], "--steps"),
    ("loop", ["--frames", "0"], "--frames"),
    ("loop", ["--k", "17", "--frames", "1"], "--k"),
    ("studies", ["--study", "-1"], "--study"),
    ("dataset", ["--episodes", "0", "--frames", "1", "--repeat", "1"], "--episodes"),
    ("dataset", ["--frames", "0", "--episodes", "1", "--repeat", "1"], "--frames"),
]


@pytest.mark.parametrize(("script", "args", "option"), CASES, ids=[f"{c[0]} {' '.join(c[1])}" for c in CASES])
def test_bad_argument_is_one_line(script, args, option, tmp_path):
    args = [a.format(missing=tmp_path / "missing") for a in args]
    run = subprocess.run([sys.executable, str(ROOT / "bench" / f"{script}.py"), *args], check=False, cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 2, run.stdout[-2000:] + run.stderr[-2000:]
    assert "Traceback" not in run.stderr, run.stderr[-2000:]
    assert run.stdout == ""
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith(f"{script}.py: error: {option}"), run.stderr
