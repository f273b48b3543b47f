"""Study ``moving``: taskers on walking objects (paper figs 9, 10).

Objects walk by the random-waypoint model with right-hand avoidance
(:func:`scene.motion.random_waypoint`). Frame 0 is seen by the uniform set of k
cameras. At every later frame the tasker chooses its cameras from *estimates*: the
centres of the previous frame's hull polygons (after removing polygons smaller than
one object), never the true positions; the hull of the true discs seen by the chosen
cameras gives that frame's residual. ``residual`` is the time average over frames
1..steps-1, then the mean over trials.

- ``uniform``: the uniform set, never changed;
- ``greedy``: full greedy choice every frame;
- ``incremental``: starts from the uniform set; every ``u`` frames (``--update-every``)
  greedily removes then adds ``--m`` cameras. Each ``u`` gives a record.
"""

from __future__ import annotations

import numpy as np

from scene.checks import used_or_refused
from testbed.output import count_axis, save_figure
from testbed.parallel import chunk

from . import core

STUDY_ID = 2
CHUNK = 2


#: The taskers this study can compare.
TASKERS = ("uniform", "greedy", "lazy_greedy", "incremental")
#: The default of ``--update-every``: the periods of the paper's figure 10.
UPDATE_EVERY = "1,3,5,7"


def add_arguments(p) -> None:
    core.add_objects(p, 5)
    core.add_k(p, "2-8")
    core.add_candidates(p)
    core.add_taskers(p, "uniform,greedy,incremental", TASKERS)
    core.add_update(p, UPDATE_EVERY)
    core.add_steps(p, 40)
    p.add_argument("--dt", type=float, default=0.1, help="seconds per frame (default 0.1)")
    core.add_speed(p, 0.5)
    core.add_radius(p)


def parse(args) -> dict:
    core.check_count("objects", args.objects)
    core.check_count("candidates", args.candidates, 2)
    core.check_cameras("candidates", args.candidates)
    ks = core.parse_k(args.k, args.candidates, f"the {args.candidates} candidates")
    taskers = core.parse_names("taskers", args.taskers, TASKERS)
    us = core.parse_ints("update-every", UPDATE_EVERY if args.update_every is None else args.update_every, minimum=1)
    if not used_or_refused("--update-every", args.update_every, "incremental" in taskers,
                           "incremental's re-tasking periods", f"--taskers {','.join(taskers)} runs no incremental"):
        us = None
    m = core.check_m(args.m, ks if "incremental" in taskers else [])
    core.check_count("steps", args.steps, 2)
    core.check_bounded("dt", args.dt, 0.0, core.MAX_DT, low_open=True)
    core.check_bounded("speed", args.speed, 0.0, core.MAX_SPEED)
    radius = core.check_discs(args.objects, args.radius)
    return {"objects": int(args.objects), "k": ks, "candidates": int(args.candidates),
            "taskers": taskers, "update_every": us, "m": m, "steps": int(args.steps),
            "dt": float(args.dt), "speed": float(args.speed), "radius": radius}


def settings(opts) -> list[tuple[str, int, int]]:
    """(tasker, k, update_every) in record order."""
    out = []
    for tasker in opts["taskers"]:
        for u in (opts["update_every"] if tasker == "incremental" else [1]):
            for k in opts["k"]:
                out.append((tasker, k, u))
    return out


def run_trials(start, stop, opts, seed) -> np.ndarray:
    """returns (stop - start, len(settings)) float: time-averaged residual."""
    from scene.motion import random_waypoint

    room = core.circle_room(1.0)
    xy, yaw = core.circle_cameras(opts["candidates"])
    r = opts["radius"]
    sets = settings(opts)
    out = np.empty((stop - start, len(sets)))
    for t in range(start, stop):
        with core.crowding(opts["objects"], r):
            traj = random_waypoint(room, np.full(opts["objects"], r), opts["steps"], opts["dt"],
                                   opts["speed"], core.trial_rng(seed, STUDY_ID, 0, t))
        for s, (tasker, k, u) in enumerate(sets):
            S = core.choose_cameras("uniform", k, xy, yaw, core.FOV, traj[0], r, room)
            polys = core.hull_residual(xy[S], yaw[S], traj[0], r, room)[2]
            est = core.polygon_centres(polys)
            total = 0.0
            for f in range(1, opts["steps"]):
                if tasker != "uniform" and (f - 1) % u == 0 and len(est):
                    S = core.choose_cameras(tasker, k, xy, yaw, core.FOV, est, r, room,   # --m: incremental's
                                            current=S, m=opts["m"] if tasker == "incremental" else 1)
                _, res, polys = core.hull_residual(xy[S], yaw[S], traj[f], r, room)
                total += res
                if polys:
                    est = core.polygon_centres(polys)
            out[t - start, s] = total / (opts["steps"] - 1)
    return out


def run(opts: dict, trials: int, seed: int, runner) -> dict:
    chunks = chunk(trials, CHUNK)
    res = np.concatenate(runner(run_trials, [(a, b, opts, seed) for a, b in chunks],
                                [b - a for a, b in chunks], "moving"))
    records = []
    for s, (tasker, k, u) in enumerate(settings(opts)):
        mean, sem = core.mean_sem(res[:, s])
        records.append({"tasker": tasker, "k": k, "update_every": u, "residual": mean,
                        "residual_sem": sem, "trials": trials, "steps": opts["steps"]})
    return {"records": records}


def _label(tasker, u):
    return tasker if tasker != "incremental" else f"incremental/{u}"


def format_table(result: dict) -> str:
    recs = result["records"]
    cols = list(dict.fromkeys((r["tasker"], r["update_every"]) for r in recs))
    ks = sorted({r["k"] for r in recs})
    t = {(r["tasker"], r["update_every"], r["k"]): r for r in recs}
    lines = [("Time-averaged residual (object areas) with moving objects "
              "(incremental/u: re-tasked every u frames):"),
             f"{'k':>3} " + "".join(f"{_label(*c):>15}" for c in cols)]
    for k in ks:
        lines.append(f"{k:>3} " + "".join(f"{t[(c[0], c[1], k)]['residual']:15.4f}" for c in cols))
    return "\n".join(lines)


def plot(result: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    recs = result["records"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    cols = list(dict.fromkeys((r["tasker"], r["update_every"]) for r in recs))

    colours = {c: f"C{i % 10}" for i, c in enumerate(cols)}   # one colour per series in both panels

    def draw(ax, tasker, u, **kw):
        rs = [r for r in recs if r["tasker"] == tasker and r["update_every"] == u]
        ax.errorbar([r["k"] for r in rs], [r["residual"] for r in rs],
                    yerr=[r["residual_sem"] for r in rs], marker="o", capsize=3,
                    label=_label(tasker, u), color=colours[(tasker, u)], **kw)

    for tasker, u in cols:
        if tasker != "incremental" or u == min(c[1] for c in cols if c[0] == "incremental"):
            draw(axes[0], tasker, u)
        if tasker == "incremental" or tasker == "uniform":
            draw(axes[1], tasker, u)
    axes[0].set(title="Fig. 9: taskers with moving objects", xlabel="number of cameras tasked k",
                ylabel="time-averaged residual / object area")
    axes[1].set(title="Fig. 10: incremental greedy, update every u frames",
                xlabel="number of cameras tasked k")
    for ax in axes:
        ax.set_yscale("log")
        count_axis(ax.xaxis)                                                  # k is a count
        if ax.has_data():
            ax.legend()
        else:                                   # fig. 10 needs incremental or uniform among --taskers
            ax.text(0.5, 0.5, "no incremental or uniform\nin --taskers", ha="center", va="center",
                    transform=ax.transAxes, color="grey")
    fig.tight_layout()
    save_figure(fig, path)
