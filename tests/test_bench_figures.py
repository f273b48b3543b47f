"""What the benchmark scripts print is what their docstrings and docs/performance.md say."""

import json
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
