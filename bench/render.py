"""Benchmark one 16-camera render step against the bare OpenGL floor, in one process.

    PYOPENGL_PLATFORM=egl .venv/bin/python bench/render.py [--steps 10] [--json]

step_ms  : production path, ``Renderer.render``: draw + glReadPixels (RGB and labels in
           one RGBA read) + lens distortion (cv2.remap of the regions the people can
           change, over the cached distorted background) + labels + gain + pooled noise
floor_ms : the same meshes drawn for the same 16 cameras into the same framebuffer
           and read back with one glReadPixels, nothing else (``Rasteriser.draw``)
post_ms  : step_ms - floor_ms, the CPU post-processing
Figures are medians over ``--steps`` steps after two warm-up steps, measured in three
interleaved rounds; ``ratios`` are the three rounds' step/floor ratios (their spread).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def median_ms(fn, steps: int) -> float:
    for _ in range(2):
        fn()
    times = []
    for _ in range(steps):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times) * 1e3)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=10)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)

    from render import Renderer
    from scene import load_scene

    scene = load_scene("lab")
    positions = np.array([[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]])
    rng = np.random.default_rng(0)
    with Renderer(scene) as r:
        # interleave the two measurements so machine load affects both alike
        step, floor = [], []
        for _ in range(3):
            step.append(median_ms(lambda: r.render(positions, rng=rng), max(1, args.steps // 3)))
            floor.append(median_ms(lambda: r.raster.draw(r.view_projs, positions), max(1, args.steps // 3)))
        backend = r.backend
    out = {
        "cameras": len(scene.cameras),
        "backend": backend,
        "image": [640, 480],
        "step_ms": round(float(np.median(step)), 1),
        "floor_ms": round(float(np.median(floor)), 1),
        "LP_NUM_THREADS": os.environ.get("LP_NUM_THREADS"),
        "cpus": len(os.sched_getaffinity(0)),
    }
    out["ratios"] = [round(a / b, 2) for a, b in zip(step, floor)]
    out["post_ms"] = round(out["step_ms"] - out["floor_ms"], 1)
    out["ratio"] = round(out["step_ms"] / out["floor_ms"], 2)
    out["steps_per_s"] = round(1000.0 / out["step_ms"], 2)
    if args.json:
        print(json.dumps(out))
    else:
        print(f"16-camera step (production: draw + read + distortion + labels + noise): {out['step_ms']:.1f} ms "
              f"({out['steps_per_s']:.2f} steps/s)")
        print(f"bare OpenGL floor (same meshes, draw + glReadPixels):                 {out['floor_ms']:.1f} ms")
        print(f"ratio {out['ratio']:.2f}x (rounds {out['ratios']}); backend {backend}; {out['cpus']} CPUs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
