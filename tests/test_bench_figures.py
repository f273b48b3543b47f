"""What the benchmark scripts print is what their docstrings and docs/performance.md say."""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def bench_json(script: str, *args: str) -> dict:
    run = subprocess.run([sys.executable, str(ROOT / "bench" / f"{script}.py"), *args, "--json"], check=False,
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout)


@pytest.mark.render
def test_rendering_post_ms_is_the_step_beyond_its_opengl_part():
    """post_ms, "the CPU post-processing", was step_ms - floor_ms: negative once the step drew
    only the people (the floor draws the whole scene), not the time of anything."""
    out = bench_json("rendering", "--steps", "3")
    assert out["post_ms"] == pytest.approx(out["step_ms"] - out["people_ms"], abs=0.11)


def test_studies_bench_prints_its_ratios():
    """The studies bench printed the exact limit's and the 2000-camera hull's times and the
    1- and 2-worker study times, but no ratio of either (README: benches print ratios)."""
    run = subprocess.run([sys.executable, str(ROOT / "bench" / "studies.py"), "--study", "1"], check=False,
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    limits = re.findall(r"in ([\d.]+) s; 2000 cameras .* in ([\d.]+) s \(the exact limit ([\d.]+)x faster\)",
                        run.stdout)
    assert len(limits) == 2, run.stdout
    for exact, hull, ratio in limits:      # the times as printed: 3 and 2 decimals
        assert within_rounding(float(ratio), 0.05, float(hull), 0.005, float(exact), 0.0005)
    study = dict(re.findall(r"(\d) worker\(s\): ([\d.]+) s", run.stdout))
    speedup = re.search(r"2 workers ([\d.]+)x one", run.stdout)
    assert speedup and set(study) == {"1", "2"}, run.stdout
    assert within_rounding(float(speedup[1]), 0.005, float(study["1"]), 0.05, float(study["2"]), 0.05)


def within_rounding(ratio: float, r_step: float, a: float, a_step: float, b: float, b_step: float) -> bool:
    """Whether ``ratio`` (printed to +-r_step) can be a / b, given a and b printed to +-a_step, +-b_step."""
    low, high = (a - a_step) / (b + b_step), (a + a_step) / max(b - b_step, 1e-9)
    return low - r_step <= ratio <= high + r_step
