"""Study ``cameras``: residual of the visual hull vs number of cameras (paper figs 5, 6).

Objects (discs of radius 0.1) are dropped at random without overlap in the unit circular
room; N cameras sit evenly on the perimeter facing the centre with a 180-degree field of
view. For each object count and each N the residual is the mean over trials of
(hull area - total object area) / one object's area, after removing hull polygons
smaller than one object (``residual``) and before (``residual_raw``). The same drops are
used for every N, so differences between N are paired.

The "infinite" case is, by default, computed *exactly* (up to a 1-D quadrature, see
:mod:`testbed.studies.limit`); ``--limit-cameras N`` instead uses N cameras, as the paper
did with 2000.
"""

from __future__ import annotations

import numpy as np

from scene.checks import used_or_refused
from testbed.output import count_axis, save_figure
from testbed.parallel import chunk

from . import core
from .limit import limit_residual

STUDY_ID = 0
#: Trials per Dask task.
CHUNK = 20
#: The exact limit's default row spacing is the radius over this: 2 mm for 0.1 m objects
#: (a fixed 2 mm left the limit of 0.01 m objects 25 % low).
QUADRATURE_PER_RADIUS = 50
#: The default of ``--fit-min``: slopes over N >= 8 (N <= 16 by default).
FIT_MIN = 8


def add_arguments(p) -> None:
    p.add_argument("--objects", default="1-10", help="object counts, e.g. 1,2,5 or 1-10 (default 1-10)")
    p.add_argument("--cameras", default="2-16", help="camera counts N (default 2-16)")
    p.add_argument("--limit-cameras", default="inf", metavar="N|inf",
                   help="the 'infinite' case: 'inf' = exact limit (default), or N cameras (paper: 2000)")
    core.add_radius(p)
    p.add_argument("--quadrature", type=float, default=None, metavar="H",
                   help="row spacing of the exact limit's quadrature, metres (default radius / 50: 0.002)")
    p.add_argument("--fit-min", type=int, default=None, metavar="N",
                   help=f"fit the log-log slope over cameras >= N, at least two of --cameras (default {FIT_MIN})")


def parse(args) -> dict:
    objects = core.parse_ints("objects", args.objects, minimum=1)
    cameras = core.parse_ints("cameras", args.cameras, minimum=2)
    core.check_cameras("cameras", max(cameras))
    lim = str(args.limit_cameras).strip().lower()
    if lim in ("inf", "exact", "infinite"):
        limit = None
    else:
        try:
            limit = int(lim)
        except ValueError:
            raise ValueError(f"--limit-cameras: expected an integer >= 2 or 'inf', got {args.limit_cameras!r}") from None
        if limit < 2:
            raise ValueError(f"--limit-cameras: expected an integer >= 2 or 'inf', got {limit}")
        core.check_cameras("limit-cameras", limit)
        if limit <= max(cameras):                 # the limit stands for infinitely many cameras
            raise ValueError(f"--limit-cameras: expected more cameras than the largest --cameras "
                             f"({max(cameras)}), got {limit}")
    core.check_discs(max(objects), args.radius)
    used_or_refused("--quadrature", args.quadrature, limit is None, "the row spacing of the exact limit "
                    "(--limit-cameras inf)", f"--limit-cameras {limit} takes none")
    quadrature = args.radius / QUADRATURE_PER_RADIUS if args.quadrature is None else args.quadrature
    if not args.radius / 1000 <= quadrature <= args.radius / 2:     # at least four rows across a disc
        raise ValueError(f"--quadrature: expected a number in [radius / 1000, radius / 2] = "
                         f"[{args.radius / 1000:g}, {args.radius / 2:g}], got {quadrature}")
    fit_min = FIT_MIN if args.fit_min is None else args.fit_min
    if args.fit_min is not None:                # a slope needs two camera counts: refused, not "n/a"
        if len(cameras) < 2:
            raise ValueError(f"--fit-min: the slope needs at least two --cameras, got {cameras[0]} alone")
        if not 2 <= fit_min <= cameras[-2]:
            raise ValueError(f"--fit-min: expected an integer in [2, {cameras[-2]}] (at least two --cameras "
                             f"from it on), got {fit_min}")
    return {"objects": objects, "cameras": cameras, "limit_cameras": limit,
            "radius": float(args.radius), "quadrature": float(quadrature) if limit is None else None,
            "fit_min": int(fit_min)}


def run_trials(m, start, stop, cameras, limit_cameras, radius, h, seed) -> np.ndarray:
    """Residuals for trials ``start..stop-1`` with ``m`` objects.

    returns (stop - start, len(cameras) + 1, 2) float: [raw, pruned] per camera count,
    the last column being the limit
    """
    room = core.circle_room(1.0)
    from scene.motion import random_drop

    out = np.empty((stop - start, len(cameras) + 1, 2))
    obj = np.pi * radius**2
    for t in range(start, stop):
        with core.crowding(m, radius):
            centers = random_drop(room, np.full(m, radius), core.trial_rng(seed, STUDY_ID, m, t))
        for j, n in enumerate(cameras):
            xy, yaw = core.circle_cameras(n)
            out[t - start, j] = core.hull_residual(xy, yaw, centers, radius, room)[:2]
        if limit_cameras is None:
            raw, pruned = limit_residual(centers, radius, h=h, min_area=obj)
            out[t - start, -1] = raw / obj, pruned / obj
        else:
            xy, yaw = core.circle_cameras(limit_cameras)
            out[t - start, -1] = core.hull_residual(xy, yaw, centers, radius, room)[:2]
    return out


def run(opts: dict, trials: int, seed: int, runner) -> dict:
    tasks, weights, keys = [], [], []
    for m in opts["objects"]:
        for a, b in chunk(trials, CHUNK):
            tasks.append((m, a, b, opts["cameras"], opts["limit_cameras"], opts["radius"],
                          opts["quadrature"], seed))
            weights.append(b - a)
            keys.append(m)
    results = runner(run_trials, tasks, weights, "cameras")
    per_m = {m: np.concatenate([r for r, k in zip(results, keys) if k == m]) for m in opts["objects"]}
    records, fits = [], []
    for m in opts["objects"]:
        res = per_m[m]
        lim_mean, lim_sem = core.mean_sem(res[:, -1, 1])
        for j, n in enumerate(opts["cameras"]):
            mean, sem = core.mean_sem(res[:, j, 1])
            records.append({
                "objects": m, "cameras": n, "limit": False,
                "residual": mean, "residual_sem": sem,
                "residual_raw": float(res[:, j, 0].mean()),
                "scaled": mean / lim_mean if lim_mean > 0 else None,
                "excess": mean - lim_mean,
                "trials": trials,
            })
        records.append({
            "objects": m, "cameras": opts["limit_cameras"], "limit": True,
            "method": "exact" if opts["limit_cameras"] is None else "cameras",
            "residual": lim_mean, "residual_sem": lim_sem,
            "residual_raw": float(res[:, -1, 0].mean()),
            "scaled": 1.0 if lim_mean > 0 else None, "excess": 0.0, "trials": trials,
        })
        fits.append(_fit(m, [r for r in records if r["objects"] == m and not r["limit"]], opts["fit_min"]))
    return {"records": records, "fits": fits}


def _fit(m, recs, fit_min) -> dict:
    """Least-squares slope of log(residual) and log(residual - limit) vs log(N)."""
    out = {"objects": m, "fit_cameras": None, "slope": None, "slope_excess": None}
    sel = [r for r in recs if r["cameras"] >= fit_min]
    if len(sel) < 2:
        return out
    n = np.log([r["cameras"] for r in sel])
    out["fit_cameras"] = [sel[0]["cameras"], sel[-1]["cameras"]]
    y = np.array([r["residual"] for r in sel])
    if np.all(y > 0):
        out["slope"] = float(np.polyfit(n, np.log(y), 1)[0])
    e = np.array([r["excess"] for r in sel])
    if np.all(e > 0):
        out["slope_excess"] = float(np.polyfit(n, np.log(e), 1)[0])
    return out


def format_table(result: dict) -> str:
    recs = result["records"]
    objects = sorted({r["objects"] for r in recs})
    cams = sorted({r["cameras"] for r in recs if not r["limit"]})
    lim = next(r for r in recs if r["limit"])
    lim_name = "inf" if lim["cameras"] is None else str(lim["cameras"])
    lines = ["Residual of the visual hull in object areas (after removing polygons < one object):",
             "N\\objects " + "".join(f"{m:>9d}" for m in objects)]
    table = {(r["objects"], r["cameras"] if not r["limit"] else "lim"): r for r in recs}
    for n in cams + ["lim"]:
        label = f"{n:>9}" if n != "lim" else f"{lim_name:>9}"
        lines.append(label + " " + "".join(f"{table[(m, n)]['residual']:9.4f}" for m in objects))
    lines.append("")
    lines.append("log-log slope of residual vs N (and of residual - limit), "
                 "paper: -2 for one object:")
    for f in result["fits"]:
        s = "n/a" if f["slope"] is None else f"{f['slope']:+.2f}"
        se = "n/a" if f["slope_excess"] is None else f"{f['slope_excess']:+.2f}"
        rng = f["fit_cameras"]
        where = f"N in {rng}" if rng is not None else "fewer than two N >= --fit-min"
        lines.append(f"  objects={f['objects']:>2d}  {where}: slope {s}   excess slope {se}")
    return "\n".join(lines)


def plot(result: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    recs = result["records"]
    objects = sorted({r["objects"] for r in recs})
    lim = {r["objects"]: r for r in recs if r["limit"]}
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    ax = axes[0]
    ax.errorbar(objects, [lim[m]["residual"] for m in objects],
                yerr=[lim[m]["residual_sem"] for m in objects], marker="o", capsize=3,
                label="after pruning")
    ax.plot(objects, [lim[m]["residual_raw"] for m in objects], "s--", alpha=0.7, label="raw")
    name = "exact limit" if lim[objects[0]]["cameras"] is None else f"{lim[objects[0]]['cameras']} cameras"
    ax.set(xlabel="number of objects", ylabel="residual / object area",
           title=f"Fig. 5: residual with 'infinite' cameras ({name})")
    count_axis(ax.xaxis)                                                 # a count of objects
    ax.legend()
    cmap = plt.get_cmap("viridis")
    for i, m in enumerate(objects):
        rs = sorted((r for r in recs if r["objects"] == m and not r["limit"]), key=lambda r: r["cameras"])
        n = [r["cameras"] for r in rs]
        color = cmap(i / max(1, len(objects) - 1))
        if lim[m]["residual"] > 0:
            axes[1].loglog(n, [r["scaled"] for r in rs], "o-", ms=3, color=color, label=f"{m}")
        e = [r["excess"] for r in rs]
        ok = [k for k, v in enumerate(e) if v > 0]
        axes[2].loglog([n[k] for k in ok], [e[k] for k in ok], "o-", ms=3, color=color, label=f"{m}")
    axes[1].set(xlabel="number of cameras N", ylabel="residual / limit residual",
                title="Fig. 6: residual scaled by the limit (objects >= 2)")
    if axes[1].has_data():
        axes[1].legend(title="objects", fontsize=7, ncol=2)
    else:                                       # no curve when every limit residual is 0 (one object)
        axes[1].text(0.5, 0.5, "no object count\nwith a nonzero limit", ha="center", va="center",
                     transform=axes[1].transAxes, color="grey")
    nn = np.array([min(r["cameras"] for r in recs if not r["limit"]),
                   max(r["cameras"] for r in recs if not r["limit"])], float)
    one = [r for r in recs if r["objects"] == objects[0] and not r["limit"]]
    if one:
        y0 = max(r["excess"] for r in one)
        axes[2].loglog(nn, y0 * (nn / nn[0]) ** -2.0, "k:", label="N^-2")
    axes[2].set(xlabel="number of cameras N", ylabel="residual - limit (object areas)",
                title="excess over the limit")
    axes[2].legend(title="objects", fontsize=7, ncol=2)
    # N is a count: plain numbers (log's own labels, 2x10^0, 3x10^0, 4x10^0, ran together)
    for ax in (a for a in axes[1:] if a.has_data()):
        ax.xaxis.set_major_locator(matplotlib.ticker.FixedLocator(count_ticks(nn[0], nn[1])))
        ax.xaxis.set_major_formatter(matplotlib.ticker.StrMethodFormatter("{x:.0f}"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    fig.tight_layout()
    save_figure(fig, path)


def count_ticks(lo: float, hi: float) -> list[float]:
    """Ticks of a log axis of counts from ``lo`` to ``hi``: both ends, and between them 1, 2,
    5, 10, 20, ... (1, 10, 100, ... over more than 300x) at least 1.5x from either end.

    >>> count_ticks(2, 16), count_ticks(4, 256), count_ticks(2, 10000), count_ticks(8, 8)
    ([2, 5, 10, 16], [4, 10, 20, 50, 100, 256], [2, 10, 100, 1000, 10000], [8])
    """
    steps = (1,) if hi / lo > 300 else (1, 2, 5)
    between = [m * 10**e for e in range(int(np.log10(hi)) + 1) for m in steps if lo * 1.5 <= m * 10**e <= hi / 1.5]
    return list(dict.fromkeys([lo, *between, hi]))
