"""Study ``static``: taskers on static objects (paper fig 8).

``--objects`` discs are dropped at random (as in ``cameras``); ``--candidates`` cameras
sit evenly on the perimeter. Each tasker chooses k of them from the *true* object
positions; the residual (object areas, after removing polygons smaller than one
object) is averaged over trials. All taskers and k see the same drops.
"""

from __future__ import annotations

from math import comb

import numpy as np

from scene.checks import used_or_refused
from testbed.parallel import chunk

from . import core

STUDY_ID = 1
CHUNK = 10
#: The default of ``--max-subsets``: C(16, 8) = 12870 subsets at the paper's largest k, with room.
MAX_SUBSETS = 200_000


#: The taskers this study can compare (incremental needs a previous frame).
TASKERS = tuple(t for t in core.TASKERS if t != "incremental")


def add_arguments(p) -> None:
    core.add_objects(p, 5)
    core.add_k(p, "2-8")
    core.add_candidates(p)
    core.add_taskers(p, "uniform,clustering,optimal,greedy", TASKERS)
    core.add_radius(p)
    p.add_argument("--max-subsets", type=int, default=None,
                   help=f"refuse 'optimal' beyond this many subsets (default {MAX_SUBSETS})")


def parse(args) -> dict:
    core.check_count("objects", args.objects)
    core.check_count("candidates", args.candidates, 2)
    core.check_cameras("candidates", args.candidates)
    ks = core.parse_k(args.k, args.candidates, f"the {args.candidates} candidates")
    taskers = core.parse_names("taskers", args.taskers, TASKERS)
    max_subsets = MAX_SUBSETS if args.max_subsets is None else core.check_count("max-subsets", args.max_subsets)
    if not used_or_refused("--max-subsets", args.max_subsets, "optimal" in taskers,
                           "the limit of optimal's subsets", f"--taskers {','.join(taskers)} runs no optimal"):
        max_subsets = None
    worst = max(ks, key=lambda k: comb(args.candidates, k))
    if max_subsets is not None and comb(args.candidates, worst) > max_subsets:
        raise ValueError(f"--taskers: optimal would compare C({args.candidates}, {worst}) = "
                         f"{comb(args.candidates, worst)} subsets of cameras per trial, more than --max-subsets "
                         f"{max_subsets}")
    radius = core.check_discs(args.objects, args.radius)
    return {"objects": int(args.objects), "k": ks, "candidates": int(args.candidates),
            "taskers": taskers, "radius": radius, "max_subsets": max_subsets}


def run_trials(start, stop, opts, seed) -> np.ndarray:
    """returns (stop - start, len(taskers), len(k)) float: residual after pruning."""
    from scene.motion import random_drop

    room = core.circle_room(1.0)
    xy, yaw = core.circle_cameras(opts["candidates"])
    r = opts["radius"]
    out = np.empty((stop - start, len(opts["taskers"]), len(opts["k"])))
    for t in range(start, stop):
        with core.crowding(opts["objects"], r):
            centers = random_drop(room, np.full(opts["objects"], r), core.trial_rng(seed, STUDY_ID, 0, t))
        for i, tasker in enumerate(opts["taskers"]):
            for j, k in enumerate(opts["k"]):
                limit = {"max_subsets": opts["max_subsets"]} if tasker == "optimal" else {}
                S = core.choose_cameras(tasker, k, xy, yaw, core.FOV, centers, r, room, **limit,
                                        # keyed by the tasker's name, not its place in --taskers
                                        rng=core.trial_rng(seed, STUDY_ID, 1 + core.TASKERS.index(tasker), k, t))
                out[t - start, i, j] = core.hull_residual(xy[S], yaw[S], centers, r, room)[1]
    return out


def run(opts: dict, trials: int, seed: int, runner) -> dict:
    chunks = chunk(trials, CHUNK)
    res = np.concatenate(runner(run_trials, [(a, b, opts, seed) for a, b in chunks],
                                [b - a for a, b in chunks], "static"))
    records = []
    for i, tasker in enumerate(opts["taskers"]):
        for j, k in enumerate(opts["k"]):
            mean, sem = core.mean_sem(res[:, i, j])
            records.append({"tasker": tasker, "k": k, "residual": mean, "residual_sem": sem,
                            "trials": trials})
    return {"records": records}


def format_table(result: dict) -> str:
    return core.tasker_table(result["records"], "Residual (object areas) with static objects, by tasker and k:")


def plot(result: dict, path: str) -> None:
    core.plot_taskers(result["records"], path, "Fig. 8: taskers with static objects",
                      "residual / object area", log=True)
