"""``camtask scanlines``: frames to scanlines for a render directory or a video.

    camtask scanlines DIR [--params FILE] [--frames N] [--out FILE] [--json]
    camtask scanlines --video FILE_OR_FOLDER --calibration cam.yaml --background N [--params FILE] [--frames N]
                      [--out FILE.npz] [--json]

A render directory gives ``DIR/scanlines.npz`` (``scanlines``, ``gt_scanlines``
(n_frames, n_cams, W) bool, ``bearings`` (n_cams, W) float radians, ``camera_numbers``
(n_cams,) int and, when its people's size is known, ``blind_radius``, ``sight_radius``,
``gt_blind_radius``, ``gt_sight_radius`` (n_cams,) float metres) and the CDnet metrics of the scanline columns and of the foreground
pixels. An episode of a dataset written by ``camtask render`` needs ``--out``: the
dataset's manifest checksums its files. A video (or a folder of images, by the numbers in their names) gives
``scanlines`` (n_frames, 1, W), ``bearings`` (1, W) and ``camera_numbers`` (1,); its
first N frames (``--background N``) are the background and ``--frames`` counts the frames
after them. Files are written atomically, only when the run completes.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from testbed.commands import plain_help


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("scanlines", help="frames to 640-bit scanlines, with metrics",
                              description=plain_help(__doc__), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dir", nargs="?", metavar="DIR", help="render directory (from `camtask render`), or a dataset of one episode")
    p.add_argument("--params", metavar="FILE", help="pipeline parameters YAML (default assets/pipeline/default.yaml)")
    p.add_argument("--frames", type=int, metavar="N",
                   help="process at most this many frames (with --video: after the background frames)")
    p.add_argument("--out", metavar="FILE", help="output .npz (default DIR/scanlines.npz, or VIDEO_scanlines.npz "
                                                 "beside --video; required for an episode of a dataset)")
    p.add_argument("--json", action="store_true", help="print the metrics as one JSON document")
    p.add_argument("--video", metavar="FILE_OR_FOLDER",
                   help="a video file, or a folder of images (frame2 before frame10), instead of a render directory")
    p.add_argument("--calibration", metavar="FILE", help="camera calibration (OpenCV YAML) of the --video camera")
    p.add_argument("--background", type=int, metavar="N",
                   help="with --video: its first N frames are the empty scene, the background")
    p.set_defaults(func=run)


def run(args) -> int:
    from pipeline.params import load_params
    from testbed.cli import UsageError
    from testbed.output import check_output_file

    params = load_params(args.params, "--params")
    if args.out is not None:
        check_output_file("--out", args.out)
    if args.frames is not None and args.frames < 1:
        raise ValueError(f"--frames: expected an integer >= 1, got {args.frames}")
    if args.video is not None:
        if args.dir is not None:
            raise UsageError("give either DIR or --video, not both")
        if args.calibration is None or args.background is None:
            raise UsageError("--video needs --calibration FILE and --background N")
        return _run_video(args, params)
    if args.dir is None:
        raise UsageError("expected a render directory DIR, or --video FILE_OR_FOLDER")
    given = [f"--{k}" for k in ("calibration", "background") if getattr(args, k) is not None]
    if given:                                       # a render directory has its own: ignoring them misleads
        raise UsageError(f"{' and '.join(given)} go{'es' if len(given) == 1 else ''} with --video, not with DIR "
                         "(its calibration/ and background/ are used)")
    return _run_render(args, params)


def _run_render(args, params) -> int:
    from pipeline.core import Pipeline
    from pipeline.io import RenderDir, save_npz_atomic
    from pipeline.params import params_option
    from pipeline.rectify import check_column_threshold
    from pipeline.runs import run_sequence

    render = RenderDir(episode_dir(Path(args.dir)))
    check_column_threshold(params.column_threshold, render.cameras, params_option(args.params))
    out = Path(args.out) if args.out is not None else default_output(render.root, "scanlines.npz")
    n = len(render) if args.frames is None else min(args.frames, len(render))
    render.check_complete(n)
    size = people_size(render.root)                 # before the frames: a bad people.csv stops at once
    pipe = Pipeline(render.cameras, params, render.background())
    with tqdm(total=n, desc="scanlines", unit="frame", file=sys.stderr, disable=args.json) as bar:
        result = run_sequence(pipe, (render.frames(i) for i in range(n)),
                              (render.labels(i) for i in range(n)), progress=lambda: bar.update())
    render.close()                                  # a video episode's decoders, when --frames stopped early
    radii = {}
    if size is not None:                            # where the cameras can see people at all
        height, width = size
        (near, far), (gt_near, gt_far) = (pipe.sight_range(height, truth=t, object_width=width) for t in (False, True))
        radii = {"blind_radius": near, "sight_radius": far, "gt_blind_radius": gt_near, "gt_sight_radius": gt_far}
    save_npz_atomic(out, scanlines=result.scanlines, gt_scanlines=result.gt_scanlines,
                    bearings=result.bearings, camera_numbers=np.array([c.number for c in render.cameras]), **radii)
    metrics = result.metrics() | {"params": params.to_dict(), "out": str(out)}
    _report(metrics, [c.number for c in render.cameras], args.json)
    return 0


def people_size(root: Path) -> tuple[float, float] | None:
    """The height and the diameter (metres) of the shortest and of the thinnest person of
    a render directory: from its people.csv, else (no one walked) from its meta.json's
    scene; None without either."""
    from testbed.dataset import read_people

    if (root / "people.csv").is_file():
        table = read_people(root / "people.csv")
        if table.size:
            return float(np.min(table["height"])), 2 * float(np.min(table["radius"]))
    if (root / "meta.json").is_file():
        from scene import Scene
        from testbed.dataset import read_meta

        meta = read_meta(root, complete=False)
        if meta.get("scene_yaml"):
            people = Scene.from_text(meta["scene_yaml"], str(root / "meta.json")).people
            return float(people.height), 2 * float(people.radius)
    return None


def episode_dir(root: Path) -> Path:
    """A render directory: ``root`` itself, or the one episode of a dataset written by ``camtask render``."""
    if (root / "calibration").is_dir() or not (root / "manifest.json").is_file():
        return root
    episodes = sorted(p for p in root.glob("episode_*") if p.is_dir())
    if len(episodes) != 1:
        raise ValueError(f"DIR: {root} is a dataset of {len(episodes)} episodes; give one episode folder, "
                         f"e.g. {root / 'episode_0000'}")
    return episodes[0]


def default_output(root: Path, name: str) -> Path:
    """``root / name``: where a command run on the render directory ``root`` writes by default.

    Not into an episode of a dataset (a folder ``episode_*`` beside a ``manifest.json``): the
    manifest holds the checksum of each of its files, so a file replaced or added there makes
    ``camtask verify`` fail and ``camtask render --resume`` render the episode again. That
    is a one-line error asking for ``--out``, raised before any work; so is a name there
    that cannot be written (a folder of that name), as for a given ``--out``.
    """
    from testbed.output import check_output_file, episode_of

    real = root.resolve()                           # "." names no episode, its real path does
    if episode_of(root, itself=True) == real:
        dataset = root.parent if root.name == real.name else real.parent
        raise ValueError(f"--out: {root} is an episode of the dataset {dataset}, whose manifest.json "
                         f"checksums its files; give --out FILE to write {name} elsewhere")
    return check_output_file("--out", root / name)


def _run_video(args, params) -> int:
    from pipeline.core import Pipeline
    from pipeline.io import check_camera, iter_video_frames, load_calibration, save_npz_atomic
    from pipeline.params import params_option
    from pipeline.rectify import check_column_threshold
    from pipeline.runs import run_sequence
    from testbed.output import check_output_file

    if args.background < 1:
        raise ValueError(f"--background: expected an integer >= 1, got {args.background}")
    cam = load_calibration(args.calibration, name="--calibration")
    check_camera(cam, f"--calibration: {Path(args.calibration).name}")
    check_column_threshold(params.column_threshold, [cam], params_option(args.params))
    source = Path(args.video).resolve()             # "." has a name once resolved
    out = Path(args.out) if args.out is not None else \
        check_output_file("--out", source.with_name(f"{source.stem}_scanlines.npz"))
    frames = _sized(iter_video_frames(source), source, cam, args.calibration)
    bg = list(itertools.islice(frames, args.background))
    first = next(frames, None)                      # the first frame after the background
    if first is None:
        raise ValueError(f"--background {args.background}: --video {args.video} has {len(bg)} "
                         f"frame{'' if len(bg) == 1 else 's'}; expected more than the {args.background} "
                         "background frames")
    frames = itertools.chain([first], frames)
    background = np.stack(bg)
    if _grey(background):
        print(f"warning: --video: {source} is grey (R = G = B): grey pixels all have the same colour "
              "angle, so only pixels below the brightness floor can be foreground", file=sys.stderr)
    pipe = Pipeline([cam], params, background[:, None])
    rest = (f[None] for f in itertools.islice(frames, args.frames))
    with tqdm(desc="scanlines", unit="frame", file=sys.stderr, disable=args.json) as bar:
        result = run_sequence(pipe, rest, progress=lambda: bar.update())
    save_npz_atomic(out, scanlines=result.scanlines, bearings=result.bearings,
                    camera_numbers=np.array([cam.number]))
    _report(result.metrics() | {"params": params.to_dict(), "out": str(out)}, [cam.number], args.json)
    return 0


def _sized(frames, source: Path, cam, calibration: str):
    """``frames`` (H, W, 3) of ``source``, each as large as the calibration ``cam`` says; else
    a one-line error naming the frame (its file, for a folder), --video and --calibration."""
    from pipeline.io import image_files

    names = [p.name for p in image_files(source)] if source.is_dir() else []
    for i, frame in enumerate(frames):
        if frame.shape[:2] != (cam.height, cam.width):
            what = f"{source / names[i]}" if i < len(names) else \
                f"frame {i} (from 0, background frames included) of {source}"
            raise ValueError(f"--video: {what} is {frame.shape[1]} x {frame.shape[0]} pixels; --calibration "
                             f"{calibration} is for {cam.width} x {cam.height}")
        yield frame


def _grey(images: np.ndarray) -> bool:
    """True when every pixel of ``images`` (..., 3) uint8 has R = G = B."""
    return bool(np.array_equal(images[..., 0], images[..., 1]) and np.array_equal(images[..., 1], images[..., 2]))


def _report(m: dict, numbers, as_json: bool) -> None:
    if as_json:
        print(json.dumps(m))
        return
    print(f"{m['frames']} frames x {m['cameras']} cameras -> {m['out']}")
    print(f"bandwidth: RLE {m['rle_bits_mean']:.1f} bits per scanline on average "
          f"(max {m['rle_bits_max']}), raw {m['raw_bits']}")
    if "f1" not in m:
        return
    print(f"{'camera':>8} {'precision':>9} {'recall':>7} {'F1':>6} {'PWC':>6} {'pixel F1':>9}")
    for num, c, px in zip(numbers, m["per_camera"], m["pixel"]["per_camera"]):
        print(f"{num:>8} {c['precision']:9.3f} {c['recall']:7.3f} {c['f1']:6.3f} {c['pwc']:6.2f} {px['f1']:9.3f}")
    px = m["pixel"]
    print(f"{'all':>8} {m['precision']:9.3f} {m['recall']:7.3f} {m['f1']:6.3f} {m['pwc']:6.2f} {px['f1']:9.3f}")
    print(f"pixels: precision {px['precision']:.3f} recall {px['recall']:.3f} F1 {px['f1']:.3f} "
          f"PWC {px['pwc']:.2f}")
