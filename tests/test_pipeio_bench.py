"""The benchmark scripts in bench/ import the packages, not each other, also under pytest."""

import importlib.util
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = sorted((ROOT / "bench").glob("*.py"))


def test_no_bench_script_is_named_like_a_module():
    """Run as ``python bench/x.py`` (or collected by pytest), bench/ comes first on sys.path:
    a bench/tasking.py would be imported for ``import tasking``."""
    assert SCRIPTS
    for path in SCRIPTS:
        assert not (ROOT / path.stem).exists(), f"{path.name} shadows the package {path.stem}"
        assert importlib.util.find_spec(path.stem) is None, f"{path.name} shadows the module {path.stem}"


def test_pytest_collects_bench_with_the_tests():
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "--collect-only", "bench", "tests/test_cli.py"],
                         check=False, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "ERROR" not in run.stdout and " tests collected" in run.stdout
