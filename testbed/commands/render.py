"""``camtask render SCENE --episodes E --frames F --seed S --out DIR``: a synthetic dataset.

Each episode is a walk of the scene's people (random waypoints) rendered by every
camera, with exact label masks, unoccluded per-person silhouettes, the node pipeline's
scanlines, ground-truth scanlines and the ground-truth visual hull. Episodes run on Dask
workers (a local cluster by default), each written to a temporary folder and renamed
when complete; ``DIR/manifest.json`` lists the finished ones with checksums. The layout
is in :mod:`testbed.generate`, :mod:`testbed.episodes` and docs/dataset.md.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from pathlib import Path


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "render", help="render a dataset of episodes: frames, masks, silhouettes, scanlines, hulls",
        description="Render episodes of a calibrated scene, people walking by the random-waypoint model: "
                    "frames, exact label masks, per-person silhouettes, background, OpenCV calibration, "
                    "scanlines and the ground-truth visual hull, one folder per episode, with a manifest "
                    "of checksums (docs/dataset.md).")
    p.add_argument("scene", metavar="SCENE", help="scene YAML file or built-in name (lab)")
    p.add_argument("--episodes", type=int, default=1, help="number of episodes (default 1)")
    p.add_argument("--frames", type=int, default=10, help="frames per episode (default 10)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the run (default 0)")
    p.add_argument("--out", required=True, help="output directory (must not exist or be empty)")
    p.add_argument("--people", type=int, default=None, help="number of people (default: the scene's)")
    p.add_argument("--cameras", default=None, help="comma-separated camera numbers in any order, e.g. 1,3,5 (default all)")
    p.add_argument("--format", choices=("png", "video"), default="png",
                   help="RGB frames as PNG files or one lossless FFV1 .mkv per camera (default png)")
    p.add_argument("--params", metavar="FILE", help="pipeline parameters YAML (default assets/pipeline/default.yaml)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: number of cores; at most the episodes to render; "
                        "0, or a single episode to render, runs in this process)")
    g.add_argument("--scheduler", help="address of an existing Dask scheduler (DIR must be shared)")
    m = p.add_mutually_exclusive_group()
    m.add_argument("--resume", action="store_true",
                   help="finish an interrupted run, or extend one with a larger --episodes: keep verified episodes")
    m.add_argument("--overwrite", action="store_true", help="replace an existing non-empty --out")
    p.set_defaults(func=run)


def parse_cameras(text: str | None):
    """``"1,3,5"`` -> (1, 3, 5); None stays None (EpisodeConfig puts them in number order)."""
    if text is None:
        return None
    try:
        return tuple(int(x) for x in text.split(",") if x.strip())
    except ValueError:
        raise ValueError(f"--cameras: expected comma-separated camera numbers, got {text!r}") from None


def check_positive(name: str, value: int) -> int:
    if value < 1:
        raise ValueError(f"{name}: expected an integer >= 1, got {value}")
    return value


def build_config(args: argparse.Namespace):
    """Validate the arguments (no rendering); return the :class:`EpisodeConfig` and its scene."""
    from pipeline.params import load_params, params_option
    from pipeline.rectify import check_column_threshold
    from render.renderer import check_camera_numbers
    from testbed.cli import check_seed
    from testbed.episode import check_renderable
    from testbed.episodes import (
        EpisodeConfig,
        canonical,
        load_episode_scene,
        silhouette_dtype,
        with_scene_text,
    )

    check_positive("--episodes", args.episodes)
    check_positive("--frames", args.frames)
    check_seed(args.seed)
    if args.workers is not None and args.workers < 0:
        raise ValueError(f"--workers: expected an integer >= 0, got {args.workers}")
    config = with_scene_text(EpisodeConfig(scene=args.scene, people=args.people, cameras=parse_cameras(args.cameras),
                                           frames=args.frames, seed=args.seed, fmt=args.format,
                                           params=load_params(args.params, "--params").to_dict()))
    scene = load_episode_scene(config)
    check_renderable(scene, "scene")
    check_camera_numbers("--cameras", config.cameras, [c.number for c in scene.cameras])
    config = canonical(config)                        # --people 3 of a scene of 3: the run without it
    check_column_threshold(config.params["column_threshold"], [c for c in scene.cameras if config.cameras is None
                                                               or c.number in config.cameras],
                           params_option(args.params))
    silhouette_dtype(scene.people.count, "--people" if args.people is not None else "people.count")
    if args.format == "video":
        from testbed.lossless import check_frame_rate, ffmpeg_exe
        check_frame_rate("--format video: the scene's frame_rate", scene.frame_rate)
        ffmpeg_exe()                                  # found only at the first frame's video otherwise
    return config, scene


def run(args: argparse.Namespace) -> int:
    from testbed.generate import check_out, check_space, estimate_bytes, exclusive
    from testbed.parallel import default_workers

    config, scene = build_config(args)
    out = Path(args.out)
    workers = args.workers
    if workers is None and args.scheduler is None:
        # one process per core, never more than there are episodes; one episode runs here
        workers = min(default_workers(), args.episodes)
        workers = 0 if workers == 1 else workers
    elif workers:                                     # a worker more than episodes would only start up
        workers = 0 if args.episodes == 1 else min(workers, args.episodes)   # one episode: in this process
    made = [f for f in (out, *out.parents) if not f.exists()]   # deepest first
    try:
        check_out(out, args.resume, args.overwrite)   # refuse before starting a cluster
        if args.overwrite:
            check_inputs_outside(out, args)            # --overwrite would delete the run's own inputs
        if not args.resume:                           # --resume keeps episodes: checked in _run
            # what --overwrite deletes counts as free: refused before deleting, not after
            check_space(out, estimate_bytes(config, scene, 1), "one episode",
                        freed=tree_bytes(out) if args.overwrite else 0)
        with exclusive(out):                          # until the clean-up after the workers is done
            try:
                return _run(args, config, scene, out, workers)
            except ValueError:                        # bad input found once started: a black background
                if not args.resume:
                    forget_run(out)
                raise
    finally:
        for folder in made:                           # e.g. an unreachable scheduler: leave no trace
            with contextlib.suppress(OSError):        # not empty: a run wrote into it
                folder.rmdir()


def forget_run(out: Path) -> None:
    """Remove the manifest and run_info.json of a run into ``out`` that finished no episode,
    so that the same command, its input fixed, is not refused as a non-empty ``--out``."""
    from testbed.generate import MANIFEST, RUN_INFO, read_manifest

    try:
        manifest = read_manifest(out)
    except ValueError:
        return
    if manifest is not None and not manifest.get("episodes"):
        for name in (MANIFEST, RUN_INFO):
            with contextlib.suppress(FileNotFoundError):
                (out / name).unlink()


def tree_bytes(folder: Path) -> int:
    """Bytes the files under ``folder`` take on disk (what deleting them frees, about)."""
    total = 0
    for root, _, files in os.walk(folder):
        for name in files:
            with contextlib.suppress(OSError):
                total += os.lstat(os.path.join(root, name)).st_blocks * 512
    return total


def check_inputs_outside(out: Path, args: argparse.Namespace) -> None:
    """Refuse --overwrite of a DIR that holds the scene file or --params file of this run."""
    top = out.resolve()
    for option, value in (("SCENE", args.scene), ("--params", args.params)):
        if value and Path(value).is_file() and top in Path(value).resolve().parents:
            raise ValueError(f"--overwrite: {option} {value} lies in {out}, which --overwrite empties; "
                             "move it out of the dataset first")


def _prepare(args: argparse.Namespace, config, out: Path) -> dict[int, dict]:
    """The finished episodes to keep (:func:`testbed.generate.prepare_output`), with a
    progress bar while --resume reads back every kept episode."""
    from tqdm import tqdm

    from testbed.generate import prepare_output

    bars = []

    def verified(files: int, total: int) -> None:
        if not bars:
            bars.append(tqdm(total=total, desc="verify", unit="file", file=sys.stderr, dynamic_ncols=True))
        bars[0].update(files)

    try:
        return prepare_output(out, config, args.episodes, args.resume, args.overwrite, verified)
    finally:
        for bar in bars:
            bar.close()


def _check_space(args: argparse.Namespace, config, scene, out: Path, todo: int) -> None:
    """With --resume or --overwrite, refuse a folder that cannot hold one more episode now
    that the episodes kept are read or the old ones deleted; warn when ``todo`` episodes need
    more than is free."""
    from testbed.generate import check_space, estimate_bytes, free_bytes, size_text

    if args.overwrite or args.resume:
        check_space(out, estimate_bytes(config, scene, 1), "one episode")
    need, (free, where) = estimate_bytes(config, scene, todo), free_bytes(out)
    if free < need:
        print(f"warning: --out: {size_text(free)} free on {where}; {todo} episodes need about "
              f"{size_text(need)}: the run stops when the disk is full (the finished episodes stay "
              "valid; --resume finishes it)", file=sys.stderr)


def _run(args: argparse.Namespace, config, scene, out: Path, workers: int | None) -> int:
    """The run itself, once ``out`` is checked and locked."""
    from tqdm import tqdm

    from testbed.cli import RunError
    from testbed.generate import (
        MANIFEST,
        check_worker_versions,
        check_workers_ffmpeg,
        check_workers_share,
        generate,
        read_manifest,
        remove_unlisted,
    )
    from testbed.parallel import open_client, wait_for_a_worker

    started = False
    try:
        if args.scheduler is None:
            # local workers: no more than the episodes left to render (one, or none: in this
            # process); --overwrite keeps none, but deletes them only once the workers are up
            keep = {} if args.overwrite else _prepare(args, config, out)
            left = args.episodes - len(keep)
            workers = 0 if left <= 1 else min(workers, left)
        with open_client(workers, args.scheduler) as client:
            if args.scheduler is not None:
                wait_for_a_worker(client, args.scheduler)           # checked below, then rendered
                check_worker_versions(client)
                check_workers_share(client, out)
                if config.fmt == "video":
                    check_workers_ffmpeg(client)
            if args.scheduler is not None or args.overwrite:
                keep = _prepare(args, config, out)
            todo = args.episodes - len(keep)
            if todo == 0:
                print(f"{out}: all {args.episodes} episodes already finished", file=sys.stderr)
                return 0
            _check_space(args, config, scene, out, todo)
            with tqdm(total=todo * args.frames, desc="render", unit="frame", file=sys.stderr,
                      dynamic_ncols=True) as bar:
                info = {"workers": workers, "scheduler": args.scheduler,
                        "progress": "frames, per frame in-process, polled from temporary folders on Dask"}
                started = True
                done = generate(config, args.episodes, out, keep, client, progress=bar.update, run_info=info)
    except Exception as exc:                          # a full disk, a lost mount, a worker that kept dying
        text = machine_error(exc, args.scheduler) if started else None
        if text is None:
            raise
        finished = len((read_manifest(out) or {}).get("episodes", []))
        raise RunError(f"{text}; stopped with {finished} of {args.episodes} episodes finished, "
                       f"listed in {out / MANIFEST} (--resume finishes the run)") from None
    finally:
        if started and args.scheduler is None and workers:
            # the local workers have stopped: drop episodes they finished after the manifest's
            # last write and their temporary folders (in-process, generate did; an existing
            # cluster's running episodes cannot be stopped from here; --resume removes what
            # they leave)
            remove_unlisted(out)
    new = len(done) - len(keep)
    print(f"wrote {new} episode{'s' * (new != 1)} x {args.frames} frame{'s' * (args.frames != 1)} to {out} "
          f"({len(done)}/{args.episodes} finished)", file=sys.stderr)
    return 0


def machine_error(exc: BaseException, scheduler: str | None = None) -> str | None:
    """One line for an error of the machine rather than a bug: an OSError, a Dask episode
    whose workers kept dying (``KilledWorker``, whose own text is a paragraph), an episode
    written where this machine does not see it (``NotShared``), or the lost connection to an
    existing cluster's ``scheduler``; else None."""
    from testbed.generate import NotShared, episode_of_key

    if scheduler is not None and "distributed" in sys.modules:
        from distributed.client import FutureCancelledError
        from distributed.comm.core import CommClosedError

        if isinstance(exc, (CommClosedError, FutureCancelledError)):
            reason = getattr(exc, "reason", None) or type(exc).__name__
            return (f"--scheduler: lost the connection to {scheduler} ({reason}); episodes running on its "
                    "workers may still finish into temporary folders")
    if isinstance(exc, (OSError, NotShared)):
        return str(exc)
    if "distributed" not in sys.modules:          # no cluster was used
        return None
    from distributed import KilledWorker

    if not isinstance(exc, KilledWorker):
        return None
    deaths = exc.allowed_failures + 1
    return (f"episode {episode_of_key(exc.task)}: {deaths} worker process{'es' * (deaths > 1)} died running it "
            f"(the last at {exc.last_worker.address}; out of memory?)")
