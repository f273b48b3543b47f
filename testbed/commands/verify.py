"""``camtask verify DIR``: check a dataset's files against its manifest.

Every episode that ``DIR/manifest.json`` lists is read back and each file's checksum
compared with the manifest's (BLAKE3; sha256 for manifests of format 1). One line names
each episode with a problem: files changed, missing, or present but not listed. Episode
or temporary folders the manifest does not list (a run stopped before it listed them)
and episodes planned but not yet rendered are reported without failing.

Exit code 0 when every listed episode is intact, 1 when one is not or a file cannot be
read (one line naming it), 2 when DIR has no readable manifest.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from testbed.commands import plain_help


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("verify", help="check a dataset's files against its manifest.json",
                              description=plain_help(__doc__), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dir", metavar="DIR", help="dataset folder written by `camtask render`")
    p.set_defaults(func=run)


def run(args) -> int:
    from tqdm import tqdm

    from scene.checks import names
    from testbed.generate import (
        MANIFEST,
        episode_problems,
        manifest_algorithm,
        problems_text,
        read_manifest,
        unlisted,
    )

    root = Path(args.dir)
    if not root.is_dir():
        what = "not a folder" if root.exists() else "no such folder"
        raise FileNotFoundError(f"DIR: {root}: {what} (expected a dataset folder written by `camtask render`)")
    m = read_manifest(root)
    if m is None and root.resolve().name.startswith("episode_") and (root.resolve().parent / MANIFEST).is_file():
        raise FileNotFoundError(f"DIR: {root} is an episode of the dataset {root.resolve().parent}, whose "
                                f"{MANIFEST} lists it: verify the dataset (camtask verify {root.resolve().parent})")
    if m is None:
        raise FileNotFoundError(f"DIR: no {MANIFEST} in {root} (expected a folder written by `camtask render`)")
    algorithm = manifest_algorithm(m)
    entries = {int(e["index"]): e for e in m.get("episodes", [])}
    files = sum(len(e["files"]) for e in entries.values())
    bad = []
    with tqdm(total=files, desc="verify", unit="file", file=sys.stderr, dynamic_ncols=True) as bar:
        for entry in entries.values():
            problems = episode_problems(root, entry, algorithm)
            if any(problems.values()):
                bad.append(entry["name"])
                folder = root / entry["name"]
                text = problems_text(problems) if folder.is_dir() else f"{absent(folder)} ({file_count(entry)} listed)"
                if "meta.json" in problems["changed"]:
                    text += origin(root, entry)
                tqdm.write(f"{entry['name']}: {text}", file=sys.stdout)
            bar.update(len(entry["files"]))
    left = [p.name for p in unlisted(root, entries)]
    if left:
        print(f"not listed (left by a stopped run; `camtask render ... --resume` removes them): {names(left)}")
    planned = int(m.get("episodes_planned", len(entries)))
    if len(entries) < planned:
        print(f"{len(entries)} of {planned} planned episodes listed: an unfinished run (`--resume` finishes it)")
    if bad:
        print(f"{root}: {len(bad)} of {len(entries)} episodes differ from {MANIFEST} ({names(bad)})")
        return 1
    print(f"{root}: {len(entries)} episode{'' if len(entries) == 1 else 's'} intact ({files} files, {algorithm})")
    return 0


def absent(folder: Path) -> str:
    """Why an episode's ``folder`` holds none of its files: ``folder missing``, or what is
    there instead."""
    if folder.is_symlink() and not folder.exists():
        return "a link to nowhere, not a folder"
    if folder.exists():
        return f"a {'file' if folder.is_file() else 'special file'}, not a folder"
    return "folder missing"


def file_count(entry: dict) -> str:
    """``1 file`` or ``229 files``: how many files the manifest lists for ``entry``."""
    n = len(entry["files"])
    return f"{n} file{'' if n == 1 else 's'}"


def origin(root: Path, entry: dict) -> str:
    """``"; its meta.json is episode 1 of seed 2 (4 frames), not ..."`` when the changed
    meta.json of ``entry``'s folder describes another episode than the manifest lists (a
    folder copied from another dataset or episode), else ``""``."""
    import json

    try:
        meta = json.loads((root / entry["name"] / "meta.json").read_text())
        found = tuple(meta[k] for k in ("episode", "seed", "frames"))
    except (OSError, ValueError, TypeError, KeyError):
        return ""
    listed = (entry["index"], entry.get("seed"), entry["frames"])
    if found == listed:
        return ""
    say = lambda e, s, f: f"episode {e} of seed {s} ({f} frame{'' if f == 1 else 's'})"
    return (f"; its meta.json is {say(*found)}, not {say(*listed)} as listed: "
            "a folder of another dataset or episode")
