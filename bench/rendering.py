"""Benchmark one 16-camera render step against the bare OpenGL floor, in one process.

    .venv/bin/python bench/rendering.py [--steps 10] [--json]

step_ms  : production path, ``Renderer.render``: the people drawn over the stored room +
           reads of the people's rectangles (people_ms) + lens distortion (cv2.remap of the
           regions the people can change, over the cached distorted background) + labels
           + gain + pooled noise
floor_ms : the whole scene (room + people) drawn for the same 16 cameras into the same
           framebuffer and read back with one glReadPixels, nothing else (``Rasteriser.draw``)
post_ms  : step_ms - people_ms, the step beyond its OpenGL part: distortion, labels, gain,
           noise (the CPU post-processing)
*_cpu_ms : median process CPU time of the same calls (every thread of the process,
           llvmpipe's included): less sensitive to other processes' load than wall time
load     : os.getloadavg() at the end (1, 5, 15 min)
people_ms: what the production step does in OpenGL: the room's colour + depth copied
           into each camera's people rectangle, the people's triangles drawn, the
           rectangles read back (``Renderer._draw_people``; no room triangles);
           a part of step_ms
Figures are medians over three interleaved rounds of ``--steps // 3`` steps (at least 3),
each after two warm-up steps; ``ratios`` are the three rounds' step/floor ratios (their
spread).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))   # this checkout's packages first


CPU = {}   # per measured function name: process CPU times (all threads, llvmpipe's too), s


def median_ms(fn, steps: int, name: str = "") -> float:
    for _ in range(2):
        fn()
    times = []
    for _ in range(steps):
        c = time.process_time()
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
        CPU.setdefault(name, []).append(time.process_time() - c)
    return float(np.median(times) * 1e3)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=10)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    if args.steps < 3:
        p.error(f"--steps: expected an integer >= 3 (three rounds of steps // 3), got {args.steps}")

    from render import Renderer
    from render.renderer import _boxes
    from scene import load_scene

    scene = load_scene("lab")
    positions = np.array([[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]])
    rng = np.random.default_rng(0)
    with Renderer(scene) as r:
        # interleave the two measurements so machine load affects both alike
        step, floor, people = [], [], []
        r.render(positions, rng=rng)                # the cached background
        idx = np.arange(len(r.numbers))
        boxes = [_boxes(b, r.canvas_size) for b in r._rects(idx, positions)]
        k = args.steps // 3
        for _ in range(3):
            step.append(median_ms(lambda: r.render(positions, rng=rng), k, "step"))
            floor.append(median_ms(lambda: r.raster.draw(r.view_projs, positions), k, "floor"))
            people.append(median_ms(lambda: r._draw_people(idx, positions, boxes), k, "people"))
        r._work[...] = r._canvas                    # leave the renderer clean
        backend = r.backend
    out = {
        "cameras": len(scene.cameras),
        "backend": backend,
        "image": [640, 480],
        "step_ms": round(float(np.median(step)), 1),
        "floor_ms": round(float(np.median(floor)), 1),
        "people_ms": round(float(np.median(people)), 1),
        "LP_NUM_THREADS": os.environ.get("LP_NUM_THREADS"),
        "cpus": len(os.sched_getaffinity(0)),
    }
    for name in ("step", "floor", "people"):
        out[f"{name}_cpu_ms"] = round(float(np.median(CPU[name]) * 1e3), 1)
    out["load"] = [round(x, 2) for x in os.getloadavg()]
    out["ratios"] = [round(a / b, 2) for a, b in zip(step, floor)]
    out["post_ms"] = round(out["step_ms"] - out["people_ms"], 1)
    out["ratio"] = round(out["step_ms"] / out["floor_ms"], 2)
    out["steps_per_s"] = round(1000.0 / out["step_ms"], 2)
    if args.json:
        print(json.dumps(out))
    else:
        print(f"16-camera step (production: draw + read + distortion + labels + noise): {out['step_ms']:.1f} ms "
              f"({out['steps_per_s']:.2f} steps/s)")
        print(f"bare OpenGL floor (same meshes, draw + glReadPixels):                 {out['floor_ms']:.1f} ms")
        print(f"people only (room copy + people's triangles + rectangle reads):       {out['people_ms']:.1f} ms")
        print(f"ratio {out['ratio']:.2f}x (rounds {out['ratios']}); backend {backend}; {out['cpus']} CPUs")
    return 0


if __name__ == "__main__":
    from testbed.stops import run_main

    sys.exit(run_main(main, Path(__file__).name))
