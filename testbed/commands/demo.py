"""``camtask demo``: the tasked network on the rendered lab, with a video and a summary."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "demo", help="run the tasked network on the lab and write a video, a summary and a top view",
        description="Three people walk in the rendered lab for a few seconds; incremental greedy "
                    "tasks 6 of the 16 cameras. Writes OUT/run.mp4, OUT/summary.json, OUT/topview.png.")
    p.add_argument("--out", default="out/demo", help="output folder (default out/demo)")
    p.add_argument("--frames", type=int, default=45, help="frames (default 45, 6 s at 7.5 Hz)")
    p.add_argument("--seed", type=int, default=1, help="seed (default 1)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import cv2

    from pipeline.files import write_atomic
    from render.gl import signals_held
    from testbed.commands.run import execute, format_summary, prepare
    from testbed.topview import TopView

    ns = argparse.Namespace(scene="lab", tasker="incremental", k=6, m=1, update_every=1, feedback="hull",
                            near_field=True,
                            frames=args.frames, people=3, params=None, seed=args.seed, video=None)
    scene, config, params, truth, rng = prepare(ns)     # checks the arguments
    out = check_out_folder(args.out)
    t0 = time.perf_counter()
    # the video is finished under a name of this run's own and renamed with the other two
    # files at the end: stopped after the video, the run left a new run.mp4 beside the
    # summary.json and topview.png of an earlier demo (another --seed), as if one run's
    staged = out / f".run.staged-{os.getpid()}.mp4"
    try:
        results, summary, bearings = execute(scene, config, params, truth, rng, staged)
        summary["seed"] = args.seed         # no wall-clock time: same seed, same bytes
        seconds = round(time.perf_counter() - t0, 1)
        doc = {"summary": summary, "frames": [r.to_json() for r in results]}
        view = TopView(scene, width=720)
        for r in results:                   # draw every frame so the tracks have their tails
            top = view.draw(r, bearings)
        png = cv2.imencode(".png", top[..., ::-1])[1].tobytes()
        with signals_held():                # the three files change together
            write_atomic(out / "summary.json", json.dumps(doc, indent=1, allow_nan=False).encode())
            write_atomic(out / "topview.png", png)
            os.replace(staged, out / "run.mp4")
    finally:
        staged.unlink(missing_ok=True)
    print(format_summary(summary))
    print(f"\nwrote {out / 'run.mp4'}, {out / 'summary.json'}, {out / 'topview.png'} "
          f"({seconds} s)", file=sys.stderr)
    return 0


#: What the demo writes in ``--out``.
FILES = ("run.mp4", "summary.json", "topview.png")


def check_out_folder(path: str) -> Path:
    """``--out`` as a folder that exists or is made, where files can be created, outside
    any dataset's episode, and where none of the demo's three files is a folder or a
    device (else found at the end only, after the others had been replaced); else a
    one-line ValueError naming ``--out``."""
    from testbed.output import check_output_file

    if not path:                # Path("") is the current folder
        raise ValueError(f"--out: expected a folder name, got {path!r}")
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out: {out} exists and is not a folder")
    for name in FILES:                  # and its folder: made, writable, not in an episode
        check_output_file("--out", out / name)
    out.mkdir(parents=True, exist_ok=True)
    return out
