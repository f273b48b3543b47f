"""Study ``tracking``: the paper's tracking comparison (section 6, figure 14).

Six discs of radius 0.1 walk in the circular room of radius 1 (random waypoints,
right-hand avoidance). Two kinds of network watch the same walk:

- ``uniform``: k cameras evenly on the perimeter, all of them used every frame;
- ``incremental``: k of 16 evenly spaced cameras tasked by incremental greedy (m
  swapped every ``update_every`` frames) from the previous hull's polygon centres.

Each frame the hull is built from the true discs seen by the used cameras, polygons
smaller than one disc are removed and the tracker runs on the polygon centres. Tracks
are scored against the true positions: MSE of matched positions (room units squared),
MOTA and IDF1 (py-motmetrics). The paper compares incremental k=4 with uniform k=6,
and both at k=7 (MSE 0.009 tasked vs 0.014 uniform).
"""

from __future__ import annotations

import numpy as np

from scene.checks import used_or_refused
from scene.motion import random_waypoint
from tasking.track_metrics import tracking_metrics
from tasking.tracker import Tracker, TrackerParams
from testbed.memory import check_fits
from testbed.output import save_figure

from . import core

STUDY_ID = 4
DEFAULT_TRIALS = 20
CANDIDATES = 16
DT = 1 / 7.5
SPEED = 0.3          # room radii per second: 0.04 per frame at 7.5 Hz
#: Memory an episode holds until it is scored, per step: a fixed part and a part per object
#: (the walk, the tracks, and py-motmetrics' event table, which dominates). Measured (tracemalloc
#: peak of one episode; maxrss growth in brackets) 1.2 kB a step with 1 object, 5.0-5.9 (5.4)
#: with 6, 13.7-14.1 (18.6) with 30 and 44 with 100 (radius 0.05), 2 to 16 cameras; these err above.
STEP_BYTES, OBJECT_BYTES = 2000, 1000


def add_arguments(p) -> None:
    p.add_argument("--pairs", default="incremental:4,uniform:6,incremental:7,uniform:7",
                   help="networks to compare as TASKER:K (default: the paper's four)")
    core.add_objects(p, 6)
    core.add_steps(p, 150, "20 s")
    core.add_update(p, 1)
    core.add_radius(p)
    core.add_speed(p, SPEED)
    p.add_argument("--feedback", choices=("hull", "tracks"), default=None,
                   help="object estimates for tasking: previous hull centres (paper; default) or confirmed tracks "
                        "(not with uniform pairs alone, which never re-task)")


def parse(args) -> dict:
    pairs = []
    for part in str(args.pairs).split(","):
        name, _, k = part.strip().partition(":")
        if name not in ("uniform", "incremental", "greedy") or not k.isdigit() or int(k) < 1:
            raise ValueError(f"--pairs: expected TASKER:K items with TASKER uniform, greedy or "
                             f"incremental and K an integer >= 1, got {part!r}")
        if name != "uniform" and int(k) > CANDIDATES:
            raise ValueError(f"--pairs: k = {k} exceeds the {CANDIDATES} candidate cameras")
        core.check_cameras("pairs", int(k))
        pairs.append((name, int(k)))
    for name in ("objects", "steps"):
        core.check_count(name, getattr(args, name))
    update_every = core.check_period(args.update_every, 1, [name for name, _ in pairs])
    radius = core.check_discs(args.objects, args.radius)
    # before any trial: --steps 10**9 walked for hours, then filled the memory
    check_fits("--steps", args.steps, "steps", STEP_BYTES + OBJECT_BYTES * args.objects,
               "in each episode (the walk, its tracks and py-motmetrics' events of every step)")
    core.check_bounded("speed", args.speed, 0.0, core.MAX_SPEED, low_open=True)
    m = core.check_m(args.m, [k for name, k in pairs if name == "incremental"])
    used = used_or_refused("--feedback", args.feedback, update_every is not None,     # uniform alone: none
                           "the estimates the taskers re-task from", "uniform alone never re-tasks")
    feedback = (args.feedback or "hull") if used else None
    return {"pairs": pairs, "objects": args.objects, "steps": args.steps,
            "update_every": update_every, "m": m, "radius": radius, "speed": args.speed,
            "feedback": feedback}


def tracker_params(radius: float, speed: float) -> TrackerParams:
    return TrackerParams(dt=DT, gate=3 * radius, meas_std=0.5 * radius, accel_std=2 * speed)


def run_episode(tasker: str, k: int, opts: dict, seed: int, trial: int) -> dict:
    """One network on one walk: metrics plus the truth and tracks (for the figure).

    The walk depends only on (seed, trial), so every network sees the same walk.
    """
    r = opts["radius"]
    room = core.circle_room(1.0)
    radii = np.full(opts["objects"], r)
    with core.crowding(opts["objects"], r):
        truth = random_waypoint(room, radii, opts["steps"], DT, opts["speed"],
                                core.trial_rng(seed, STUDY_ID, trial))
    if tasker == "uniform":
        xy, yaw = core.circle_cameras(k)
        chosen = np.arange(k)
    else:
        xy, yaw = core.circle_cameras(CANDIDATES)
        chosen = core.choose_cameras("uniform", k, xy, yaw, core.FOV, np.zeros((0, 2)), r, room)
    params = tracker_params(r, opts["speed"])
    tracker = Tracker(params)
    track_ids, track_xy = [], []
    for t in range(opts["steps"]):
        _, _, polys = core.hull_residual(xy[chosen], yaw[chosen], truth[t], r, room)
        centres = core.polygon_centres(polys)
        ids, est = tracker.step(centres)
        track_ids.append(ids)
        track_xy.append(est)
        estimates = centres
        if opts.get("feedback") == "tracks" and len(tracker.estimates()):
            estimates = tracker.estimates()
        if tasker != "uniform" and (t + 1) % opts["update_every"] == 0 and len(estimates):
            current = chosen if tasker == "incremental" else None
            chosen = core.choose_cameras(tasker, k, xy, yaw, core.FOV, estimates, r, room,   # --m: incremental's
                                         current=current, m=opts["m"] if tasker == "incremental" else 1)
    gt_ids = [np.arange(opts["objects"])] * opts["steps"]
    metrics = tracking_metrics(gt_ids, list(truth), track_ids, track_xy, max_distance=params.gate)
    return {**metrics, "truth": truth, "track_ids": track_ids, "track_xy": track_xy}


def run_trial(trial: int, opts: dict, seed: int) -> list[dict]:
    """Every network on the walk of one trial: one metrics dict per pair."""
    out = []
    for tasker, k in opts["pairs"]:
        ep = run_episode(tasker, k, opts, seed, trial)
        out.append({f: ep[f] for f in ("mse", "mota", "idf1", "switches")})
    return out


def run(opts: dict, trials: int, seed: int, runner) -> dict:
    per_trial = runner(run_trial, [(t, opts, seed) for t in range(trials)], [1] * trials, "tracking")
    records = []
    for i, (tasker, k) in enumerate(opts["pairs"]):
        rows = [trial[i] for trial in per_trial]
        rec = {"tasker": tasker, "k": k, "trials": trials}
        for f in ("mota", "idf1"):
            rec[f], rec[f + "_sem"] = core.mean_sem([r[f] for r in rows])
        # a trial whose tracks never came near a true object has no matched position
        mse = [r["mse"] for r in rows if np.isfinite(r["mse"])]
        rec["mse"], rec["mse_sem"] = core.mean_sem(mse) if mse else (None, None)
        rec["mse_trials"] = len(mse)
        records.append(rec)
    return {"records": records, "figure_trial": 0}


def format_table(result: dict) -> str:
    objects = result["meta"]["arguments"]["objects"]
    lines = [f"Tracking on hull polygon centres, {objects} walking disc{'s' * (objects != 1)} (mean over trials):",
             f"{'tasker':>12} {'k':>3} {'MSE':>9} {'MOTA':>7} {'IDF1':>7}"]
    for r in result["records"]:
        mse = "-" if r["mse"] is None else f"{r['mse']:.4f}"
        lines.append(f"{r['tasker']:>12} {r['k']:>3} {mse:>9} {r['mota']:7.3f} {r['idf1']:7.3f}"
                     + (f"  (MSE over the {r['mse_trials']} of {r['trials']} trials with a matched position)"
                        if r["mse_trials"] < r["trials"] else ""))
    return "\n".join(lines)


def plot(result: dict, path: str) -> None:
    """Figure 14: one object's true and estimated tracks, for each network, on trial 0."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    opts, seed = result["meta"]["arguments"], result["meta"]["seed"]
    pairs = opts["pairs"]
    fig, axes = plt.subplots(1, len(pairs), figsize=(4 * len(pairs), 4.2), squeeze=False)
    for ax, (tasker, k) in zip(axes[0], pairs):
        ep = run_episode(tasker, k, opts, seed, result["figure_trial"])
        truth = ep["truth"][:, 0]
        ax.add_patch(plt.Circle((0, 0), 1.0, fill=False, color="0.5"))
        ax.plot(truth[:, 0], truth[:, 1], "k-", lw=2, label="true track")
        est = follow(truth, ep["track_ids"], ep["track_xy"], 3 * opts["radius"])
        ax.plot(est[:, 0], est[:, 1], "r.-", ms=3, lw=0.8, label="estimated track")
        seen = ~np.isnan(est[:, 0])
        err = f"{np.mean(np.sum((est[seen] - truth[seen]) ** 2, axis=1)):.4f}" if seen.any() else "-"
        every = f"{ep['mse']:.4f}" if np.isfinite(ep["mse"]) else "-"     # no matched position: as the table
        ax.set_title(f"{tasker} k={k}: this track's MSE {err}\n(all objects {every})", fontsize=9)
        ax.set_aspect("equal")
        ax.set(xlim=(-1.05, 1.05), ylim=(-1.05, 1.05), xlabel="x (room radii)", ylabel="y (room radii)")
        ax.legend(loc="lower right", fontsize=7)
    n = opts["objects"]
    fig.suptitle(f"Fig. 14: {'the object' if n == 1 else f'one of {n} objects'}, true and estimated tracks")
    fig.tight_layout()
    save_figure(fig, path)


def follow(truth: np.ndarray, track_ids, track_xy, gate: float) -> np.ndarray:
    """Per frame, the position of the track most often nearest to this object (NaN when absent).

    truth : (T, 2) one object's true positions; returns (T, 2).
    """
    votes: dict[int, int] = {}
    for p, ids, xy in zip(truth, track_ids, track_xy):
        if len(ids):
            d = np.linalg.norm(xy - p, axis=1)
            if d.min() < gate:
                i = int(ids[d.argmin()])
                votes[i] = votes.get(i, 0) + 1
    best = max(votes, key=votes.get) if votes else -1
    out = np.full_like(truth, np.nan)
    for t, (ids, xy) in enumerate(zip(track_ids, track_xy)):
        hit = np.flatnonzero(ids == best)
        if hit.size:
            out[t] = xy[hit[0]]
    return out
