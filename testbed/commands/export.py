"""``camtask export wildtrack|multiviewx DIR OUT [--episode N] [--undistort] [--boxes visible|unoccluded] [--overwrite]``.

An episode in the WILDTRACK or MultiviewX layout. See :mod:`testbed.wildtrack` and
docs/dataset.md for the layouts, the ground grid and positionID.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from testbed.commands import plain_help

#: testbed.wildtrack.LAYOUTS and BOXES (not imported here: it imports OpenCV, and the parser is built at start-up).
LAYOUTS = ("wildtrack", "multiviewx")
BOXES = ("visible", "unoccluded")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("export", help="export an episode for multi-view detection code (WILDTRACK or "
                                             "MultiviewX layout)",
                              description=plain_help(__doc__), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("layout", choices=LAYOUTS, help="output layout")
    p.add_argument("dir", metavar="DIR", help="dataset folder from `camtask render` (or one episode folder)")
    p.add_argument("out", metavar="OUT", help="output folder (must not exist or be empty)")
    p.add_argument("--episode", type=int, default=None,
                   help="episode index when DIR is a dataset (default 0); with an episode folder, its own")
    p.add_argument("--undistort", action="store_true",
                   help="pinhole images: frames undistorted to the same camera matrix, zero distortion "
                        "coefficients written (as WILDTRACK's intrinsic_zero; default: the rendered frames "
                        "and their true coefficients)")
    p.add_argument("--boxes", choices=BOXES, default="visible",
                   help="what a view's box bounds: the person's visible mask (default), or the unoccluded "
                        "silhouette, the whole body in view even behind someone (its bottom is the feet)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing non-empty OUT")
    p.set_defaults(func=run)


def run(args) -> int:
    from tqdm import tqdm

    from testbed.dataset import read_meta
    from testbed.episodes import episode_name
    from testbed.generate import MANIFEST
    from testbed.wildtrack import export_episode, people_table, read_calibrations

    root = Path(args.dir)
    index = 0 if args.episode is None else args.episode
    if index < 0:
        raise ValueError(f"--episode: expected an integer >= 0, got {index}")
    if not root.is_dir():
        what = "not a folder" if root.exists() else "no such folder"
        raise FileNotFoundError(f"DIR: {root}: {what} (expected a dataset or episode folder written by "
                                "`camtask render`)")
    episode = root if (root / "meta.json").is_file() else root / episode_name(index)
    if not (episode / "meta.json").is_file():
        raise FileNotFoundError(f"DIR: no episode {index} in {root} (expected {episode}/meta.json)")
    if episode == root and args.episode is not None:
        own = read_meta(episode, complete=False).get("episode")
        if own != args.episode:
            raise ValueError(f"--episode {args.episode}: DIR {root} is episode {own} itself; give the dataset "
                             f"folder {root.resolve().parent} to choose another")
    # DIR may be an episode of a dataset: keep out of that too; for an episode folder that is a
    # link, both the dataset beside the link (whose manifest lists it) and the one it leads into
    datasets = [d for d in dict.fromkeys((Path(os.path.abspath(episode)).parent, episode.resolve().parent))
                if (d / MANIFEST).is_file()]
    check_apart(args.out, root, episode, datasets=datasets)
    check_export_out(args.out, args.overwrite)
    check_intact(episode)
    meta = read_meta(episode)
    people = people_table(episode / "people.csv", meta["frames"], meta["people"])   # before the bar
    read_calibrations(episode, meta["cameras"])                                      # and these
    with tqdm(total=len(meta["cameras"]) * meta["frames"], desc="export", unit="image", file=sys.stderr,
              dynamic_ncols=True) as bar:
        export_episode(episode, args.out, args.layout, undistort=args.undistort, box=args.boxes,
                       progress=bar.update, people=people)
    name = {"wildtrack": "WILDTRACK", "multiviewx": "MultiviewX"}[args.layout]
    print(f"wrote {episode} as {name} layout{' (undistorted)' if args.undistort else ''} to {args.out}",
          file=sys.stderr)
    return 0


def check_apart(out: str, *sources: Path, datasets=()) -> None:
    """Refuse an OUT that is a source folder (or one of the ``datasets`` an episode DIR
    belongs to), lies inside one or holds one.

    Inside the dataset, the export's files would make an episode fail its checksums (and
    ``--resume`` delete it); holding it, ``--overwrite`` would delete the dataset.
    """
    o = Path(out).resolve()
    named = [(f"DIR {src}", src) for src in sources] + [(f"the dataset {d}", d) for d in datasets]
    for name, src in named:
        s = src.resolve()
        if o == s:
            raise ValueError(f"OUT: {out} is {name}; choose a folder outside the dataset")
        if s in o.parents:
            raise ValueError(f"OUT: {out} is inside {name}; choose a folder outside the dataset")
        if o in s.parents:
            raise ValueError(f"OUT: {out} holds {name}; choose a folder outside the dataset")


def check_export_out(out: str, overwrite: bool) -> None:
    """Refuse an OUT that is a file, the current folder or one holding it (replacing OUT
    removes it), inside an episode of a dataset, under a file or in a folder that cannot be
    written, or a non-empty folder unless ``overwrite`` and it is an earlier export (it holds
    grid.json): anything else in it is none of ours to delete."""
    from testbed.generate import refuse_foreign
    from testbed.output import check_outside_episodes, check_writable

    o = Path(out)
    if o.exists() and not o.is_dir():
        raise FileExistsError(f"OUT: {out} exists and is not a directory")
    here = Path.cwd().resolve()
    if o.resolve() == here or o.resolve() in here.parents:
        raise ValueError(f"OUT: {out or '.'} is the current folder or holds it, which the export would replace; "
                         "give a folder beside it")
    check_outside_episodes("OUT", o)
    parent = next(f for f in o.resolve().parents if f.exists())     # the nearest existing folder above OUT
    if not parent.is_dir():
        raise ValueError(f"OUT: cannot make {out} ({parent} is not a folder)")
    check_writable("OUT", parent)
    others = sorted(p.name for p in o.iterdir()) if o.is_dir() else []
    if others and not overwrite:
        raise FileExistsError(f"OUT: {out} exists and is not empty; choose another directory "
                              "or pass --overwrite to replace an earlier export")
    refuse_foreign(out, others, "grid.json", "an export of camtask", "--overwrite", read_grid)


def read_grid(path: Path) -> dict:
    """An export's grid.json; a ValueError unless it is one (the name alone proves nothing)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        doc = None
    if not (isinstance(doc, dict) and doc.get("layout") in LAYOUTS
            and {"cell_m", "position_id", "views"} <= doc.keys()):
        raise ValueError("its grid.json is not one")
    return doc


def check_intact(episode: Path) -> None:
    """Refuse an episode whose files differ from its dataset's manifest (one line); warn
    when no manifest lists it (a folder copied out of its dataset, or left by a stopped run)."""
    from testbed.generate import episode_problems, manifest_algorithm, problems_text, read_manifest

    # "." or "x/.." has no name to look up, nor the dataset as parent; made absolute, not resolved:
    # an episode folder that is a link is listed by the manifest beside the link, not its target's
    episode = Path(os.path.abspath(episode))
    m = read_manifest(episode.parent)
    entry = next((e for e in (m or {}).get("episodes", []) if e["name"] == episode.name), None)
    if entry is None:
        print(f"warning: DIR: no manifest lists {episode.name}; its files are exported unverified", file=sys.stderr)
        return
    problems = episode_problems(episode.parent, entry, manifest_algorithm(m))
    if any(problems.values()):
        raise ValueError(f"DIR: {episode.name} differs from its manifest ({problems_text(problems)}); "
                         "`camtask verify` names every such file")
