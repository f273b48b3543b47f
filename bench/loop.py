"""Benchmark: the whole tasked loop on the lab, in frames per second, with the share of each stage.

One frame: render the k tasked cameras, run their node pipelines, build the hull from
their scanlines, step the tracker, and take one incremental-greedy tasking step.
Target: >= 7.5 Hz (the paper's real-time frame rate) for k = 6 of 16 on 2 cores.

    .venv/bin/python bench/loop.py [--frames 40] [--k 6] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))   # this checkout's packages first


def main(argv=None) -> int:
    from scene import load_scene
    from testbed.episode import walk
    from testbed.loop import LiveSource, LoopConfig, run_loop

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--frames", type=int, default=40)
    p.add_argument("--k", type=int, default=6)
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    if args.frames < 1:
        p.error(f"--frames: expected an integer >= 1, got {args.frames}")

    scene = load_scene("lab")
    try:
        config = LoopConfig("incremental", args.k, m=1).check(len(scene.cameras), as_options=True)
    except ValueError as exc:
        p.error(str(exc))
    motion, sensor = np.random.default_rng(0).spawn(2)
    truth = walk(scene, args.frames + 5, motion)
    source = LiveSource(scene, None, sensor)
    central = defaultdict(float)
    try:
        loop = run_loop(scene, config, truth, source, seconds=central)
        for _ in range(5):                       # warm-up: GL buffers, first greedy
            next(loop)
        source.seconds.clear()
        central.clear()
        t0 = time.perf_counter()
        for _ in range(args.frames):
            next(loop)
        wall = time.perf_counter() - t0
    finally:
        source.close()
    stages = {**source.seconds, **central}
    ms = {k: 1000 * v / args.frames for k, v in stages.items()}
    out = {"hz": args.frames / wall, "frame_ms": 1000 * wall / args.frames, "k": args.k,
           "stages_ms": {k: round(v, 2) for k, v in ms.items()}}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"tasked loop, lab, incremental k={args.k} of 16, {args.frames} frames")
        print(f"  {out['hz']:.2f} Hz  ({out['frame_ms']:.1f} ms per frame; target >= 7.5 Hz)")
        for k, v in sorted(ms.items(), key=lambda kv: -kv[1]):
            print(f"  {k:<9} {v:7.2f} ms  {100 * v / out['frame_ms']:5.1f} %")
    return 0


if __name__ == "__main__":
    from testbed.stops import run_main

    sys.exit(run_main(main, Path(__file__).name))
