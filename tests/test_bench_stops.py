"""Ctrl-C stops a benchmark script with one line and leaves none of its folders behind."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def start(script: str, args: list[str], tmp: Path) -> subprocess.Popen:
    env = os.environ | {"TMPDIR": str(tmp)}
    return subprocess.Popen([sys.executable, str(ROOT / "bench" / f"{script}.py"), *args], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)


def wait_for(tmp: Path, pattern: str, proc: subprocess.Popen, seconds: float) -> None:
    end = time.monotonic() + seconds
    while not any(tmp.rglob(pattern)):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < end, f"no {pattern} in {seconds} s"
        time.sleep(0.05)


def left_behind(tmp: Path) -> list[str]:
    """What the bench left in its temporary folder (Dask's own scratch space aside)."""
    return sorted(p.name for p in tmp.iterdir() if p.name != "dask-scratch-space")


def test_manifest_bench_stops_on_ctrl_c(tmp_path):
    proc = start("manifest", ["--json"], tmp_path)         # the default run: about a minute
    wait_for(tmp_path, "bench-manifest.*/whole/manifest.json", proc, 120)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err == "manifest.py: interrupted\n" and out == ""
    assert left_behind(tmp_path) == []


@pytest.mark.render
def test_dataset_bench_stops_on_ctrl_c_during_the_warm_up(tmp_path):
    """Ctrl-C at a terminal reaches the Dask workers too: a worker's warm-up episode was
    written to a folder of its own, which nothing removed once the worker had stopped."""
    proc = start("dataset", ["--frames", "12", "--episodes", "1", "--repeat", "1"], tmp_path)
    wait_for(tmp_path, "bench-warm.*", proc, 300)
    os.killpg(proc.pid, signal.SIGINT)                     # as Ctrl-C: the whole process group
    out, err = proc.communicate(timeout=300)
    assert left_behind(tmp_path) == []
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "dataset.py: interrupted" and out == ""
    assert "Traceback" not in err, err
