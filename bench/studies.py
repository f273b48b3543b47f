"""Benchmarks for the studies: the "infinite"-camera case and the cameras study.

    .venv/bin/python bench/studies.py            # limit: 2000-camera hull vs exact
    .venv/bin/python bench/studies.py --study 50 # also the cameras study, 1 and 2 workers

Prints wall times and their ratios, measured in this one run: the exact limit against the
2000-camera hull, 2 workers against 1; numbers for docs/performance.md (## Studies).
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = str(Path(__file__).resolve().parent.parent)
sys.path.insert(0, ROOT)                                            # this checkout's packages first

from testbed.stops import Terminated


def bench_limit(objects: int, seed: int) -> None:
    from scene.motion import random_drop
    from testbed.studies import core
    from testbed.studies.limit import limit_residual

    room = core.circle_room()
    centers = random_drop(room, np.full(objects, 0.1), np.random.default_rng(seed))
    obj = np.pi * 0.01
    t = time.perf_counter()
    raw, pruned = limit_residual(centers, 0.1)
    t_exact = time.perf_counter() - t
    xy, yaw = core.circle_cameras(2000)
    t = time.perf_counter()
    h_raw, h_pruned, _ = core.hull_residual(xy, yaw, centers, 0.1, room)
    t_hull = time.perf_counter() - t
    print(f"{objects} objects, seed {seed}: exact limit {raw / obj:.4f} raw / {pruned / obj:.4f} pruned "
          f"in {t_exact:.3f} s; 2000 cameras {h_raw:.4f} raw / {h_pruned:.4f} pruned in {t_hull:.2f} s "
          f"(the exact limit {t_hull / t_exact:.1f}x faster)")


def bench_study(trials: int, workers: int) -> float:
    code = ("import sys, testbed.cli as c; c.COMMANDS = ('testbed.commands.study',)\n"
            "if __name__ == '__main__': sys.exit(c.main(sys.argv[1:]))")
    argv = [sys.executable, "-c", code, "study", "cameras", "--trials", str(trials),
            "--workers", str(workers), "--json", "--no-progress"]
    t = time.perf_counter()
    env = os.environ | {"PYTHONPATH": os.pathsep.join(filter(None, (ROOT, os.environ.get("PYTHONPATH"))))}
    with subprocess.Popen(argv, stdout=subprocess.DEVNULL, env=env) as study:    # this checkout's camtask
        try:
            code = study.wait()
        except KeyboardInterrupt as stop:
            stop_child(study, signal.SIGTERM if isinstance(stop, Terminated) else signal.SIGINT)
            raise
    if code:     # camtask has said why on stderr
        sys.exit(f"{Path(__file__).name}: camtask study cameras --trials {trials} --workers {workers} "
                 f"exited with status {code}")
    return time.perf_counter() - t


def stop_child(child: subprocess.Popen, signum: int) -> None:
    """Let ``child`` stop as camtask does on Ctrl-C (its Dask cluster closed): it has the signal
    too when it came from the terminal; if not, it is sent on after a second; killed after 60 s."""
    try:
        child.wait(timeout=1)
    except subprocess.TimeoutExpired:
        child.send_signal(signum)
        try:
            child.wait(timeout=60)
        except subprocess.TimeoutExpired:
            child.kill()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--study", type=int, default=0, metavar="TRIALS",
                   help="also time `camtask study cameras --trials TRIALS` with 1 and 2 workers")
    a = p.parse_args()
    if a.study < 0:
        p.error(f"--study: expected a number of trials >= 0 (0: no study), got {a.study}")
    for objects, seed in ((5, 0), (10, 0)):
        bench_limit(objects, seed)
    if a.study:
        seconds = {}
        for w in (1, 2):
            seconds[w] = bench_study(a.study, w)
            print(f"cameras study, {a.study} trials, {w} worker(s): {seconds[w]:.1f} s")
        print(f"cameras study, {a.study} trials: 2 workers {seconds[1] / seconds[2]:.2f}x one")


if __name__ == "__main__":
    from testbed.stops import run_main

    sys.exit(run_main(main, Path(__file__).name))
