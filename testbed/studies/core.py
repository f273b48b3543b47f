"""What every study shares: the paper's circular rig, seeding, residuals, parsing.

The occupancy core comes from :mod:`tasking` (``visual_hull_of_discs``,
``prune_small``, ``polygon_centres``, ``choose_cameras``, ``TASKERS``).

>>> cam_xy, yaw = circle_cameras(4)
>>> np.round(cam_xy, 6).tolist()
[[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [-0.0, -1.0]]
>>> parse_ints("k", "2-4,8")
[2, 3, 4, 8]
"""

from __future__ import annotations

from contextlib import contextmanager
from functools import lru_cache

import numpy as np
from shapely.geometry import Polygon

from scene.checks import used_or_refused
from scene.motion import circle_polygon
from tasking import TASKERS, choose_cameras, polygon_centres, prune_small, visual_hull_of_discs
from testbed.output import count_axis, save_figure

#: Where the taskers come from (recorded in every study's metadata).
TASKING_BACKEND = "tasking"

__all__ = [
    "FOV",
    "TASKERS",
    "TASKING_BACKEND",
    "choose_cameras",
    "circle_cameras",
    "circle_room",
    "hull_residual",
    "parse_ints",
    "parse_names",
    "polygon_centres",
    "trial_rng",
    "visual_hull_of_discs",
]

#: The paper's cameras see 180 degrees.
FOV = np.pi
#: Vertices of the polygon standing in for the circular room.
ROOM_VERTICES = 720


@lru_cache(maxsize=8)
def circle_room(radius: float = 1.0) -> Polygon:
    """The paper's circular room (a regular 720-gon) of ``radius`` metres at the origin."""
    return circle_polygon(radius, ROOM_VERTICES)


def circle_cameras(n: int, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` cameras evenly on the room's perimeter, camera 1 at angle 0, facing the centre.

    returns camera_xy : (n, 2) float, metres; camera_yaw : (n,) float, radians
    """
    a = 2.0 * np.pi * np.arange(n) / n
    xy = radius * np.column_stack([np.cos(a), np.sin(a)])
    return xy, np.mod(a + np.pi, 2.0 * np.pi)


def trial_rng(seed: int, study: int, *key: int) -> np.random.Generator:
    """The generator of one trial: a function of (seed, study, setting..., trial) only.

    Workers never influence it, so results are identical for any worker count.
    """
    ss = np.random.SeedSequence(int(seed), spawn_key=(int(study), *map(int, key)))
    return np.random.default_rng(ss)


def hull_residual(camera_xy, camera_yaw, centers, radius, room) -> tuple[float, float, list]:
    """Residual of the visual hull, in units of one object's area, raw and pruned.

    Residual = (hull area - total object area) / (pi radius^2); "pruned" after removing
    polygons smaller than one object's area (the paper's rule).
    returns (raw, pruned, polygons) where polygons is the pruned list
    """
    hull = visual_hull_of_discs(camera_xy, camera_yaw, FOV, centers, radius, room)
    obj = np.pi * radius**2
    polys = prune_small(hull, obj)
    total = len(centers) * obj
    return (hull.area - total) / obj, (sum(p.area for p in polys) - total) / obj, polys


#: The most values one range of a list option may hold (a typo like ``2-200000000`` is an
#: error, not gigabytes of settings).
MAX_RANGE = 100_000


def parse_ints(name: str, text, *, minimum: int = 1) -> list[int]:
    """Parse ``"1,2,5-8"`` into a sorted list of distinct ints >= ``minimum``."""
    if isinstance(text, (list, tuple)):
        text = ",".join(map(str, text))
    out: set[int] = set()
    for part in str(text).split(","):
        part = part.strip()
        try:
            if "-" in part[1:]:
                a, b = part.split("-", 1) if not part.startswith("-") else (part, "")
                lo, hi = int(a), int(b)
                if hi < lo:
                    raise ValueError
                if hi - lo >= MAX_RANGE:
                    raise OverflowError
                out.update(range(lo, hi + 1))
            else:
                out.add(int(part))
        except ValueError:
            raise ValueError(
                f"--{name}: expected integers like '2,3,4' or '2-8', got {text!r}"
            ) from None
        except OverflowError:
            raise ValueError(f"--{name}: a range of at most {MAX_RANGE} values, got {part!r}") from None
    bad = [v for v in out if v < minimum]
    if bad:
        raise ValueError(f"--{name}: expected integers >= {minimum}, got {min(bad)}")
    return sorted(out)


#: The most cameras a study may put on the circle (--cameras, --limit-cameras, --candidates, a
#: uniform k of --pairs): five times the paper's 2000-camera "infinite" case. 10**9 asked for
#: gigabytes per array and the machine killed the run; 10**5 took over 5 minutes a trial, deaf to
#: SIGTERM inside the hull; 10**4 takes 6 s (cameras) to 26 s (tracking, 2 frames).
MAX_CAMERAS = 10_000
#: The fastest walk, room radii per second, and the longest frame, seconds (--speed, --dt):
#: at 1e300 the tracker's process noise overflowed, and the walks were teleports long before.
MAX_SPEED = 100.0
MAX_DT = 1000.0


def check_cameras(name: str, n: int) -> int:
    """``n`` cameras on the circle, at most :data:`MAX_CAMERAS`, else a one-line error naming ``--name``."""
    if n > MAX_CAMERAS:
        raise ValueError(f"--{name}: expected at most {MAX_CAMERAS} cameras, got {n}")
    return n


def check_objects(name: str, objects: int, radius: float) -> int:
    """``objects`` discs of ``radius`` must fit in the circular room by area (what
    :func:`scene.motion.random_drop` asks), checked before any array of them is made."""
    most = int(circle_room().area // (np.pi * radius**2))
    if objects > most:
        raise ValueError(f"--{name}: {objects} discs of radius {radius:g} do not fit in the room of radius 1; "
                         f"expected at most {most}")
    return objects


def check_bounded(name: str, value: float, low: float, high: float, *, low_open: bool = False) -> float:
    """``value`` finite, >= ``low`` (> with ``low_open``) and at most ``high``, else a one-line error."""
    if not (np.isfinite(value) and low <= value <= high) or (low_open and value == low):
        raise ValueError(f"--{name}: expected a finite number {'>' if low_open else '>='} {low:g} and at most "
                         f"{high:g}, got {value}")
    return float(value)


def check_count(name: str, value: int, minimum: int = 1) -> int:
    """An integer option ``--name`` >= ``minimum``, else a one-line error."""
    if value < minimum:
        raise ValueError(f"--{name}: expected an integer >= {minimum}, got {value}")
    return int(value)


# Options that several studies share: each is declared and checked here once, so that its
# name, help and one-line errors are the same in every study that takes it.

#: The default of ``--radius``: the paper's discs (the room's radius is 1).
RADIUS = 0.1


def add_objects(p, default: int) -> None:
    """``--objects N``: how many discs (static, moving, tracking; cameras takes a list)."""
    p.add_argument("--objects", type=int, default=default, help=f"number of objects (default {default})")


def add_k(p, default: str) -> None:
    """``--k LIST``: the numbers of tasked cameras, parsed by :func:`parse_k`."""
    p.add_argument("--k", default=default, help=f"numbers of tasked cameras (default {default})")


def add_candidates(p, default: int = 16) -> None:
    """``--candidates N``: cameras evenly on the perimeter to choose from."""
    p.add_argument("--candidates", type=int, default=default, help=f"cameras to choose from (default {default})")


def add_taskers(p, default: str, valid) -> None:
    """``--taskers LIST``: taskers among ``valid``, parsed by :func:`parse_names`."""
    p.add_argument("--taskers", default=default,
                   help=f"comma-separated taskers of {', '.join(valid)} (default {default})")


def add_update(p, update_every) -> None:
    """``--update-every`` and ``--m``. A string ``update_every``: a list of incremental greedy's
    periods, one record each (moving); an integer: the one period of every tasker but uniform
    (lab, tracking, checked by :func:`check_period`). Either is parsed as None when not given,
    so that a study can tell a value given to no tasker that uses it from its default."""
    if isinstance(update_every, str):
        p.add_argument("--update-every", default=None,
                       help=f"incremental re-tasking periods in frames (default {update_every})")
    else:
        p.add_argument("--update-every", type=int, default=None,
                       help=f"re-tasking period in frames, of every tasker but uniform (default {update_every})")
    p.add_argument("--m", type=int, default=None, help="cameras swapped per incremental update (default 1)")


def add_steps(p, default: int, note: str = "") -> None:
    """``--steps N``: frames per trial (``note``: what the default comes to, e.g. ``20 s``)."""
    p.add_argument("--steps", type=int, default=default,
                   help=f"frames per trial (default {default}{', ' + note if note else ''})")


def add_speed(p, default: float) -> None:
    """``--speed V``: walking speed, metres (room radii) per second."""
    p.add_argument("--speed", type=float, default=default, help=f"walking speed, m/s (default {default:g})")


def add_radius(p) -> None:
    """``--radius R``: the discs' radius, checked by :func:`check_discs`."""
    p.add_argument("--radius", type=float, default=RADIUS,
                   help=f"object radius, metres; the room's radius is 1 (default {RADIUS:g})")


def check_discs(objects: int, radius: float) -> float:
    """``--radius`` in (0, 0.5) and ``objects`` discs of it fitting in the room; returns the radius."""
    if not 0 < radius < 0.5:
        raise ValueError(f"--radius: expected a number in (0, 0.5), got {radius}")
    check_objects("objects", objects, radius)
    return float(radius)


@contextmanager
def crowding(objects: int, radius: float):
    """Re-raise :mod:`scene.motion`'s ``radii: ...`` errors (a room that passed
    :func:`check_objects` by area but too crowded for a random drop) naming the options:
    ``--objects 60 with --radius 0.1: could not drop ...``."""
    try:
        yield
    except ValueError as exc:
        text = str(exc)
        if not text.startswith("radii: "):
            raise
        raise ValueError(f"--objects {objects} with --radius {radius:g}: {text.removeprefix('radii: ')}") from None


def parse_k(text, most: int, of: str) -> list[int]:
    """``--k``: sorted distinct counts >= 1 and at most ``most``, the cameras ``of`` names
    (e.g. ``"the 16 candidates"``) in the error."""
    ks = parse_ints("k", text, minimum=1)
    if max(ks) > most:
        raise ValueError(f"--k: {max(ks)} cameras exceed {of}")
    return ks


def check_period(value: int | None, default: int, taskers) -> int | None:
    """lab's and tracking's ``--update-every`` (``value``; None when not given: ``default``),
    at least 1. Uniform never re-tasks: with no other tasker among ``taskers`` a given value
    is refused, and the period is None (recorded so, not as a period nothing used)."""
    period = default if value is None else check_count("update-every", value)
    if not used_or_refused("--update-every", value, any(t != "uniform" for t in taskers),
                           "the re-tasking period of every tasker but uniform",
                           f"{', '.join(dict.fromkeys(taskers))} alone never re-tasks"):
        return None
    return period


def check_m(m: int | None, ks) -> int | None:
    """``--m`` (None when not given: 1), at least 1 and at most the smallest of ``ks``, the k
    that incremental greedy runs with. Empty ``ks``: no incremental tasker uses ``--m``, so a
    given value is refused and the result is None (recorded so, not as swaps nobody made)."""
    if not used_or_refused("--m", m, bool(len(ks)), "the cameras incremental greedy swaps per update",
                           f"no incremental tasker runs (got --m {m})"):
        return None
    m = 1 if m is None else check_count("m", m)
    if m > min(ks):
        raise ValueError(f"--m: expected at most the smallest incremental k = {min(ks)}, got {m}")
    return int(m)


def parse_names(name: str, text: str, valid) -> list[str]:
    """Parse ``"a,b"`` into names, each one of ``valid`` (order kept, duplicates dropped)."""
    names = [s.strip() for s in str(text).split(",") if s.strip()]
    if not names:
        raise ValueError(f"--{name}: expected a comma-separated list, got {text!r}")
    for s in names:
        if s not in valid:
            raise ValueError(f"--{name}: unknown value {s!r}; expected one of {', '.join(valid)}")
    return list(dict.fromkeys(names))


def mean_sem(x) -> tuple[float, float]:
    """Mean and standard error of the mean (0 for a single value)."""
    x = np.asarray(x, dtype=float)
    if len(x) < 2:
        return float(x.mean()), 0.0
    return float(x.mean()), float(x.std(ddof=1) / np.sqrt(len(x)))


def tasker_table(records: list[dict], title: str, digits: int = 4) -> str:
    """A k-by-tasker table of ``residual`` from records with ``tasker``, ``k``, ``residual``."""
    taskers = list(dict.fromkeys(r["tasker"] for r in records))
    t = {(r["tasker"], r["k"]): r for r in records}
    lines = [title, f"{'k':>3} " + "".join(f"{n:>13}" for n in taskers)]
    for k in sorted({r["k"] for r in records}):
        lines.append(f"{k:>3} " + "".join(f"{t[(n, k)]['residual']:13.{digits}f}" for n in taskers))
    return "\n".join(lines)


def plot_taskers(records: list[dict], path: str, title: str, ylabel: str, *, log: bool = False,
                 reference: tuple[float, str] | None = None) -> None:
    """Residual vs k, one line with standard-error bars per tasker, to a PNG at ``path``.

    reference : optional (value, label) drawn as a dashed horizontal line
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.5))
    for tasker in dict.fromkeys(r["tasker"] for r in records):
        rs = [r for r in records if r["tasker"] == tasker]
        ax.errorbar([r["k"] for r in rs], [r["residual"] for r in rs],
                    yerr=[r["residual_sem"] for r in rs], marker="o", capsize=3, label=tasker)
    if reference is not None:
        ax.axhline(reference[0], color="0.5", ls="--", label=reference[1])
    if log:
        ax.set_yscale("log")
    ax.set(xlabel="number of cameras tasked k", ylabel=ylabel, title=title)
    count_axis(ax.xaxis)                                                      # k is a count
    ax.legend()
    fig.tight_layout()
    save_figure(fig, path)
