"""``camtask run``: the tasked network on a rendered scene, closed in a loop over time."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "run", help="run the tasked camera network on a rendered scene",
        description="Render the tasked cameras of SCENE frame by frame, turn their frames into "
                    "scanlines, build the visual hull, track, and task the next frame's cameras.")
    add_loop_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON document (frames and summary)")
    p.add_argument("--video", metavar="FILE.mp4", help="write a video of tasked frames and the top view")
    p.set_defaults(func=run)


def add_loop_arguments(p: argparse.ArgumentParser) -> None:
    from tasking import TASKERS

    p.add_argument("scene", metavar="SCENE.yaml", help="scene file or built-in name (lab)")
    p.add_argument("--tasker", default="incremental", help=f"one of {', '.join(TASKERS)} (default incremental)")
    p.add_argument("--k", type=int, default=6, help="cameras tasked per frame (default 6)")
    p.add_argument("--m", type=int, default=None,
                   help="cameras swapped per incremental update (default 1; incremental alone)")
    p.add_argument("--update-every", type=int, default=None, metavar="U",
                   help="re-task every U frames (default 1; not with uniform, which never re-tasks)")
    p.add_argument("--feedback", default=None, choices=("hull", "tracks"),
                   help="object estimates for tasking: previous hull centres (paper; default) or confirmed tracks "
                        "(not with uniform, which never re-tasks)")
    p.add_argument("--no-near-field", dest="near_field", action="store_false",
                   help="carve the hull from each camera's centre, as the paper's cameras, not only beyond its "
                        "blind radius (a person close to a camera, below its image, can then fall outside it)")
    p.add_argument("--frames", type=int, default=30, help="frames to run (default 30, 4 s at 7.5 Hz)")
    p.add_argument("--people", type=int, default=None, help="people in the room (default: the scene's)")
    p.add_argument("--params", metavar="FILE", help="pipeline parameters YAML (default assets/pipeline/default.yaml)")
    p.add_argument("--seed", type=int, default=0, help="seed of the walk and the sensor noise (default 0)")


#: Memory a run holds until its end, for the summary and ``--json``: each frame's results
#: (scanlines, hull polygons, positions, tracks, their JSON), a fixed part and a part per
#: tasked camera (and its scanline's byte per column) and per person, over the walk's 16
#: bytes per person. Measured 11-17 kB a frame with 3 people and 15-40 kB with 20 (6 and 16
#: of the lab's 640-column cameras tasked); these err above.
FRAME_BYTES, CAMERA_BYTES, PERSON_BYTES = 8000, 360, 1000 + 16
#: Seconds before the walk's progress bar shows (a short walk shows none).
WALK_BAR_DELAY = 1.0


def check_frames_fit(frames: int, k: int, people: int, option: str = "--frames", columns: int = 640) -> None:
    """Raise a one-line ValueError naming ``option`` when ``frames`` frames of ``k`` tasked
    cameras of ``columns``-pixel-wide scanlines and ``people`` people would hold more memory
    than is available now (before the walk: --frames 10**8 walked for hours, then filled the
    memory frame by frame). The renderer's ~1 GB, whatever ``frames``, is not counted."""
    from testbed.memory import check_fits

    check_fits(option, frames, "frames", FRAME_BYTES + (CAMERA_BYTES + columns) * k + PERSON_BYTES * people,
               "until the run ends (the walk and each frame's results, for the summary)")


def loop_options(args) -> tuple[int, int, str]:
    """``--m``, ``--update-every`` and ``--feedback``, 1, 1 and hull when not given; a
    one-line ValueError when one is given to a tasker that does not use it (``--m`` is
    incremental greedy's alone, uniform never re-tasks), as the studies refuse them: it was
    recorded as the run's own."""
    from scene.checks import check_int, used_or_refused
    from tasking import TASKERS, check_choice

    check_choice("--tasker", args.tasker, TASKERS)
    used_or_refused("--m", args.m, args.tasker == "incremental", "the cameras incremental greedy swaps per update",
                    f"--tasker {args.tasker} swaps none (got --m {args.m})")
    if args.update_every is not None:
        check_int("--update-every", args.update_every, minimum=1)      # as the studies: the value first
    for name, value, what in (("--update-every", args.update_every, "the re-tasking period of every tasker but uniform"),
                              ("--feedback", args.feedback, "the estimates the tasker re-tasks from")):
        used_or_refused(name, value, args.tasker != "uniform", what, "--tasker uniform never re-tasks")
    return ((1 if args.m is None else args.m), (1 if args.update_every is None else args.update_every),
            args.feedback or "hull")


def prepare(args):
    """Validate the arguments and draw the walk: (scene, config, params, truth, sensor rng)."""
    from tqdm import tqdm

    from pipeline import load_params
    from pipeline.params import params_option
    from pipeline.rectify import check_column_threshold
    from scene import load_scene
    from testbed.cli import check_seed
    from testbed.episode import check_people_renderable, check_renderable, walk, with_people
    from testbed.loop import LoopConfig
    from testbed.output import check_output_file

    if args.frames < 1:
        raise ValueError(f"--frames: expected a number >= 1, got {args.frames}")
    check_seed(args.seed)
    if args.video is not None:
        check_output_file("--video", args.video, ".mp4")
    scene = with_people(load_scene(args.scene), args.people)
    check_renderable(scene, "SCENE")
    if scene.people.count == 0:
        option = "--people" if args.people is not None else f"people.count of {args.scene}"
        raise ValueError(f"{option}: expected at least 1 person to track, got 0")
    check_people_renderable(scene, "--people" if args.people is not None else f"people.count of {args.scene}")
    config = LoopConfig(args.tasker, args.k, *loop_options(args), args.near_field).check(
        len(scene.cameras), as_options=True)
    params = load_params(args.params, "--params")
    check_column_threshold(params.column_threshold, scene.cameras, params_option(args.params))
    check_frames_fit(args.frames, config.k, scene.people.count, columns=scene.cameras[0].width)
    motion_rng, sensor_rng = np.random.default_rng(args.seed).spawn(2)
    # the walk is drawn before the first frame: ~0.2 ms a frame for 3 people, ~4 ms for 49,
    # so minutes for a million frames; its own bar shows after a second, then goes
    with tqdm(total=args.frames, initial=1, desc="walk", unit="frame", file=sys.stderr, dynamic_ncols=True,
              delay=WALK_BAR_DELAY, leave=False) as bar:
        truth = walk(scene, args.frames, motion_rng, progress=bar.update)
    return scene, config, params, truth, sensor_rng


def run(args: argparse.Namespace) -> int:
    scene, config, params, truth, sensor_rng = prepare(args)
    results, summary, _ = execute(scene, config, params, truth, sensor_rng, args.video)
    summary["seed"] = args.seed
    if args.json:
        json.dump({"summary": summary, "frames": [r.to_json() for r in results]}, sys.stdout, indent=1,
                  allow_nan=False)
        print()
    else:
        print(format_summary(summary))
    if args.video is not None:
        print(f"video: {Path(args.video)}", file=sys.stderr)
    return 0


def execute(scene, config, params, truth, sensor_rng, video=None):
    """Run the live loop, optionally writing ``video``.

    Returns (frame results, summary, bearings: camera number -> (W,) radians).

    The video file appears only if the run completes (Ctrl-C leaves none behind).
    """
    from testbed.loop import LiveSource, run_loop, summarise

    writer = None
    if video:
        from testbed.video import VideoWriter
        writer = VideoWriter(video, fps=scene.frame_rate)
    source = LiveSource(scene, params, sensor_rng, keep_frames=writer is not None)
    results = []
    ok = False
    try:
        painter = _painter(scene, source) if writer else None
        for r in run_loop(scene, config, truth, source, progress=True):
            if writer:
                writer.write(painter(r))
                r.rgb = None
            results.append(r)
        ok = True
    finally:
        try:
            source.close()
        finally:                                # an interrupt in source.close() must not keep the partial video
            if writer:
                writer.close(ok=ok)
    summary = summarise(results, scene)
    summary.update(tasker=config.tasker, k=config.k,        # null where the tasker has no use for them
                   m=config.m if config.tasker == "incremental" else None,
                   update_every=None if config.tasker == "uniform" else config.update_every,
                   feedback=None if config.tasker == "uniform" else config.feedback, near_field=config.near_field, people=scene.people.count,
                   scene=scene.name)
    return results, summary, source.bearings


def _painter(scene, source):
    from testbed.topview import TopView, level_view, mosaic

    view = TopView(scene, width=720)
    rows = max(p.rectifier.out_height for p in source.pipes.values())    # one size for every frame of the video

    def paint(result):
        top = view.draw(result, source.bearings)
        level = np.stack([level_view(rgb, source.pipes[n].rectifier, rows) for rgb, n in zip(result.rgb, result.tasked)])
        tiles = mosaic(level, result.scanlines, result.tasked, width=720)   # column j over scanline column j
        return np.vstack([tiles, top])
    return paint


def format_summary(s: dict) -> str:
    t = s.get("tracking", {})
    lines = [
        (f"{s['scene']}: {s['people']} people, {s['frames']} frames, tasker {s['tasker']} "
         f"k={s['k']}" + ("" if s["m"] is None else f" m={s['m']}")
         + ("" if s["update_every"] is None else f" update every {s['update_every']}")),
        f"  mean hull area      {s['hull_area']:.3f} m^2",
        f"  mean residual       {s['residual']:.3f}  (hull area / occupied area - 1)",
        f"  bits per frame      {s['bits_per_frame']:.0f}  (run-length coded scanlines)",
        f"  camera switches     {s['camera_switches']}",
    ]
    if t:
        num = lambda v, digits: "-" if v is None else f"{v:.{digits}f}"
        lines.append(f"  tracking            MSE {num(t['mse'], 4)} m^2  MOTA {num(t['mota'], 3)}  "
                     f"MOTP {num(t['motp'], 3)} m  IDF1 {num(t['idf1'], 3)}")
        lines.append(f"                      false positives {t['false_positives']} track-frames  misses {t['misses']} "
                     f"person-frames  id switches {t['switches']}  (matched within {t['max_distance']:.2f} m)")
    return "\n".join(lines)
