"""Benchmark: ms per 640x480 frame, production pipeline vs a straightforward reference.

    .venv/bin/python bench/scanlines.py [--dir RENDER_DIR] [--frames N] [--repeat R] [--json]

One OpenCV thread (cv2.setNumThreads(1)). Both implementations process the same frames
of all 16 lab cameras (a render directory, or synthetic lab frames) from the same
background model; the scanlines must be identical. Times are the best of ``--repeat``
passes over the sequence for production and of ``max(1, --repeat // 2)`` for the much
slower reference, divided by frames x cameras: wall clock (``*_ms``) and CPU time of this
process (``*_cpu_ms``, less sensitive to other load on the machine).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))   # this checkout's packages first

import scene
from pipeline import Pipeline, background_model, load_params
from pipeline.reference import ReferencePipeline


def load_data(args):
    if args.dir:
        from pipeline.io import RenderDir
        from testbed.commands.scanlines import episode_dir
        r = RenderDir(episode_dir(Path(args.dir)))        # a render directory, or a dataset of one episode
        n = min(args.frames, len(r))
        return r.cameras, r.background(), np.stack([r.frames(i) for i in range(n)])
    from pipeline.synthetic import synthetic_sequence
    cams = scene.load_scene("lab").cameras
    bg, frames, _ = synthetic_sequence(cams, args.frames, np.random.default_rng(0))
    return cams, bg, frames


def best_time(make, frames, repeat):
    """Best wall-clock and best CPU (process) time of ``repeat`` passes, and the scanlines."""
    best, best_cpu, out = np.inf, np.inf, None
    for _ in range(repeat):
        pipe = make()
        t0, c0 = time.perf_counter(), time.process_time()
        out = [pipe.process(f) for f in frames]
        best_cpu = min(best_cpu, time.process_time() - c0)
        best = min(best, time.perf_counter() - t0)
    return best, best_cpu, np.stack(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", help="render directory, or a dataset of one episode (default: synthetic lab frames)")
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    for name in ("frames", "repeat"):
        if getattr(args, name) < 1:
            ap.error(f"--{name}: expected an integer >= 1, got {getattr(args, name)}")
    cv2.setNumThreads(1)
    try:
        cams, bg, frames = load_data(args)
    except (ValueError, OSError) as exc:        # not a render directory, a frame that cannot be read
        if args.dir is None:                    # the synthetic frames: not the user's input
            raise
        ap.error(f"--dir: {exc}")
    params = load_params()
    model = background_model(bg)
    n = frames.shape[0] * frames.shape[1]
    t_prod, c_prod, s_prod = best_time(lambda: Pipeline(cams, params, model), frames, args.repeat)
    t_ref, c_ref, s_ref = best_time(lambda: ReferencePipeline(cams, params, model), frames,
                                    max(1, args.repeat // 2))
    res = {"production_ms": 1e3 * t_prod / n, "reference_ms": 1e3 * t_ref / n,
           "production_cpu_ms": 1e3 * c_prod / n, "reference_cpu_ms": 1e3 * c_ref / n,
           "identical": bool(np.array_equal(s_prod, s_ref)), "frames": int(frames.shape[0]),
           "cameras": int(frames.shape[1]), "resolution": [int(frames.shape[3]), int(frames.shape[2])],
           "source": args.dir or "synthetic lab"}
    res["speedup"] = res["reference_ms"] / res["production_ms"]
    if args.json:
        print(json.dumps(res))
    else:
        print(f"{res['frames']} frames x {res['cameras']} cameras, {res['resolution'][0]}x{res['resolution'][1]} "
              f"({res['source']}), one OpenCV thread")
        print(f"production {res['production_ms']:.2f} ms/frame (CPU {res['production_cpu_ms']:.2f}), "
              f"reference {res['reference_ms']:.2f} ms/frame (CPU {res['reference_cpu_ms']:.2f}), "
              f"speed-up {res['speedup']:.1f}x, identical scanlines: {res['identical']}")
    return 0 if res["identical"] else 1


if __name__ == "__main__":
    from testbed.stops import run_main

    sys.exit(run_main(main, Path(__file__).name))
