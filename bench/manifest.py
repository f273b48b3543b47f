"""Seconds a run spends on manifest.json: serialised whole after every episode, against ManifestWriter.

    .venv/bin/python bench/manifest.py [--episodes 100] [--frames 300] [--every 6] [--json]

Entries like a lab run's (16 cameras x 3 images a frame, a 64-digit checksum each: ~1.4 MB
of JSON for 300 frames) are listed one after the other, as ``generate`` lists finished
episodes, ``--every`` seconds of run apart (simulated: the writer's clock is moved on, no
sleeping). ``whole`` is ``json.dumps`` of the whole manifest and an atomic write after every
episode (what ``generate`` did before ManifestWriter); ``writer`` is ManifestWriter (each
entry serialised once, rewrites paced). Both write the same bytes (checked). Prints the
cumulative seconds of each and their ratio, measured in this one run.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))   # this checkout's packages first


def entry(index: int, frames: int) -> dict:
    files = {f"{sub}/cam{c:02d}/{f:06d}.png": os.urandom(32).hex()
             for sub in ("frames", "masks", "silhouettes") for c in range(1, 17) for f in range(frames)}
    return {"index": index, "name": f"episode_{index:04d}", "seed": 0, "spawn_key": [index], "frames": frames,
            "files": files}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--episodes", type=int, default=100, help="episodes of the run (default 100)")
    p.add_argument("--frames", type=int, default=300, help="frames per episode (default 300)")
    p.add_argument("--every", type=float, default=6.0,
                   help="seconds of run between finished episodes (default 6: 2 workers, ~25 frames/s)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    for name in ("episodes", "frames"):
        if getattr(args, name) < 1:
            p.error(f"--{name}: expected an integer >= 1, got {getattr(args, name)}")
    if not args.every >= 0 or args.every == float("inf"):
        p.error(f"--every: expected a number of seconds >= 0, got {args.every}")

    from testbed.episodes import EpisodeConfig
    from testbed.generate import MANIFEST, ManifestWriter, manifest, write_json_atomic

    config = EpisodeConfig("lab", None, None, args.frames, 0)
    root = Path(tempfile.mkdtemp(prefix="bench-manifest."))
    seconds = {"whole": 0.0, "writer": 0.0}
    try:
        for name in seconds:
            (root / name).mkdir()
        writer = ManifestWriter(root / "writer", config, args.episodes, {})
        writer.flush()
        done: dict[int, dict] = {}
        for i in range(args.episodes):
            e = entry(i, args.frames)
            t = time.perf_counter()
            done[i] = e
            write_json_atomic(root / "whole" / MANIFEST, manifest(config, args.episodes, done))
            seconds["whole"] += time.perf_counter() - t
            writer.ready_at -= args.every              # the run went on meanwhile
            t = time.perf_counter()
            writer.add(e)
            seconds["writer"] += time.perf_counter() - t
        t = time.perf_counter()
        writer.flush()
        seconds["writer"] += time.perf_counter() - t
        same = (root / "whole" / MANIFEST).read_bytes() == (root / "writer" / MANIFEST).read_bytes()
        size = (root / "whole" / MANIFEST).stat().st_size
    finally:
        shutil.rmtree(root, ignore_errors=True)
    out = {"episodes": args.episodes, "frames": args.frames, "every_s": args.every, "manifest_mb": round(size / 2**20, 1),
           "whole_s": round(seconds["whole"], 2), "writer_s": round(seconds["writer"], 2),
           "ratio": round(seconds["whole"] / seconds["writer"], 1), "same_bytes": same}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{args.episodes} episodes x {args.frames} frames, one finished every {args.every:g} s: "
              f"manifest {out['manifest_mb']} MB, same bytes: {same}")
        print(f"whole manifest after every episode: {out['whole_s']:.2f} s")
        ratio = out["ratio"]
        print(f"ManifestWriter                    : {out['writer_s']:.2f} s  (whole / writer = {ratio:.1f})")
    return 0 if same else 1


if __name__ == "__main__":
    from testbed.stops import run_main

    sys.exit(run_main(main, Path(__file__).name))
