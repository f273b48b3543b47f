"""``camtask render SCENE --frames N --seed S --out DIR``: render a dataset to disk.

People walk by the random-waypoint model (:func:`scene.motion.random_waypoint`); the
layout is described in :mod:`testbed.dataset` and docs/dataset.md.
"""

from __future__ import annotations

import argparse
import platform
import sys
from importlib import metadata
from pathlib import Path

import numpy as np


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "render", help="render RGB frames, label masks and calibration of a scene to a directory",
        description="Render frames, exact label masks, background frames and OpenCV calibration files "
                    "of a calibrated scene, people walking by the random-waypoint model.")
    p.add_argument("scene", metavar="SCENE", help="scene YAML file or built-in name (lab)")
    p.add_argument("--frames", type=int, default=10, help="number of frames (default 10)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", required=True, help="output directory (must not exist or be empty)")
    p.add_argument("--people", type=int, default=None, help="number of people (default: the scene's)")
    p.add_argument("--cameras", default=None, help="comma-separated camera numbers, e.g. 1,3,5 (default all)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing non-empty --out")
    p.set_defaults(func=run)


def parse_cameras(text: str | None):
    """``"1,3,5"`` -> (1, 3, 5); None stays None."""
    if text is None:
        return None
    try:
        return tuple(int(x) for x in text.split(",") if x.strip())
    except ValueError:
        raise ValueError(f"--cameras: expected comma-separated camera numbers, got {text!r}") from None


def versions() -> dict:
    out = {"python": platform.python_version()}
    for dist in ("numpy", "opencv-python-headless", "pyrender2", "PyOpenGL", "trimesh", "shapely", "camtask"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            pass
    return out


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from render import Renderer
    from scene import load_scene
    from scene.config import BUILTIN_SCENES, scene_path
    from testbed.dataset import DatasetWriter, check_output_dir
    from testbed.episode import walk, with_people

    if args.frames < 1:
        raise ValueError(f"--frames: expected a number >= 1, got {args.frames}")
    check_output_dir(args.out, args.overwrite)
    source = scene_path(args.scene) if args.scene in BUILTIN_SCENES else Path(args.scene)
    scene = with_people(load_scene(args.scene), args.people)
    cameras = parse_cameras(args.cameras)
    motion_rng, sensor_rng = np.random.default_rng(args.seed).spawn(2)
    people = scene.people
    track = walk(scene, args.frames, motion_rng)
    with Renderer(scene, cameras) as renderer, \
            DatasetWriter(args.out, renderer.cameras, overwrite=args.overwrite) as writer:
        writer.write_background(renderer.background().rgb)
        for f in tqdm(range(args.frames), desc="render", unit="frame", file=sys.stderr):
            frames = renderer.render(track[f], rng=sensor_rng)
            writer.write_frame(f, frames.rgb, frames.labels, track[f], people.radius, people.height)
        writer.write_meta({
            "seed": args.seed,
            "scene": scene.name,
            "scene_file": str(source),
            "scene_yaml": Path(source).read_text(),
            "people": people.count,
            "cameras": list(renderer.numbers),
            "frames": args.frames,
            "dt": scene.dt,
            "backend": renderer.backend,
            "background": "clean: no sensor noise, no gain jitter",
            "versions": versions(),
        })
    print(f"wrote {args.frames} frames x {len(renderer.numbers)} cameras to {args.out}", file=sys.stderr)
    return 0
