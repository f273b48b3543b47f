"""The tasked camera network, closed in a loop over time (the paper's real system).

Each frame only the tasked cameras send scanlines; the central node builds the visual
hull from them through each camera's column -> bearing map, removes polygons smaller
than one person, takes the polygon centres as object estimates, feeds them to the
tracker, and the tasker chooses the next frame's cameras from them.

Scanlines come from a *source*: :class:`LiveSource` renders and processes only the
cameras asked for (nodes that are switched on); :class:`PrecomputedSource` serves
scanlines computed beforehand for all cameras, so that several taskers can be compared
on exactly the same data (the paper's figure 13).
"""

from __future__ import annotations

import time
from collections import defaultdict
from dataclasses import dataclass, field
from math import comb

import numpy as np

from pipeline import Pipeline, PipelineParams, scanline_bits
from scene import Scene
from scene.checks import check_int
from tasking import (
    TASKERS,
    check_choice,
    choose_cameras,
    polygon_centres,
    prune_small,
    visual_hull_of_scanlines,
)
from tasking.taskers import MAX_SUBSETS
from tasking.track_metrics import tracking_metrics
from tasking.tracker import Tracker, TrackerParams


@dataclass(frozen=True)
class LoopConfig:
    """How the network is tasked.

    tasker : one of :data:`tasking.TASKERS`
    k : cameras tasked per frame
    m : cameras swapped per incremental update
    update_every : re-task every this many frames (1 = every frame)
    feedback : "hull" (the paper: previous hull's polygon centres) or "tracks" (the
        tracker's confirmed, temporally supported estimates, falling back to the hull)
    near_field : each camera carves the hull only between its blind and sight radius
        (the source's ``near`` and ``far``, docs/pipeline.md), so that the hull keeps a
        person standing below (or beyond) its image; False: from the camera centre out,
        as the paper's cameras
    """

    tasker: str = "incremental"
    k: int = 6
    m: int = 1
    update_every: int = 1
    feedback: str = "hull"
    near_field: bool = True

    def check(self, n_cameras: int, *, as_options: bool = False) -> LoopConfig:
        """Raise a one-line ValueError naming the bad field (as its command-line option,
        ``--update-every``, with ``as_options``); return ``self``."""
        name = (lambda f: "--" + f.replace("_", "-")) if as_options else (lambda f: f)
        check_choice(name("tasker"), self.tasker, TASKERS)
        check_choice(name("feedback"), self.feedback, ("hull", "tracks"))
        k = check_int(name("k"), self.k, minimum=1)
        if k > n_cameras:
            raise ValueError(f"{name('k')}: expected at most {n_cameras} cameras (the scene has {n_cameras}), got {k}")
        m = check_int(name("m"), self.m, minimum=1)
        if m > k:
            raise ValueError(f"{name('m')}: expected at most k = {k}, got {m}")
        check_int(name("update_every"), self.update_every, minimum=1)
        if self.tasker == "optimal" and comb(n_cameras, k) > MAX_SUBSETS:
            raise ValueError(f"{name('tasker')}: optimal would compare C({n_cameras}, {k}) = {comb(n_cameras, k)} "
                             f"subsets of cameras each frame, more than {MAX_SUBSETS}; choose greedy or incremental")
        return self


@dataclass
class FrameResult:
    """What the central node saw and concluded in one frame.

    tasked : 1-based camera numbers that sent scanlines
    scanlines : (k, W) bool, in the order of ``tasked``
    polygons : hull polygons after small-polygon removal (shapely)
    hull_area : m^2, after small-polygon removal
    residual : hull_area / true occupied area - 1
    bits_sent : run-length coded bits sent by the tasked cameras
    switched_on, switched_off : camera numbers that changed state before this frame
    estimates : (p, 2) metres, polygon centres
    truth : (people, 2) metres, true positions
    track_ids, track_xy : confirmed tracks, (t,) int and (t, 2) metres
    """

    index: int
    tasked: tuple[int, ...]
    scanlines: np.ndarray
    polygons: list
    hull_area: float
    residual: float
    bits_sent: int
    switched_on: tuple[int, ...]
    switched_off: tuple[int, ...]
    estimates: np.ndarray
    truth: np.ndarray
    track_ids: np.ndarray
    track_xy: np.ndarray
    rgb: np.ndarray | None = field(default=None, repr=False)

    def to_json(self) -> dict:
        return {
            "frame": self.index,
            "tasked": list(self.tasked),
            "hull_area": self.hull_area,
            "residual": self.residual,
            "bits_sent": self.bits_sent,
            "switched_on": list(self.switched_on),
            "switched_off": list(self.switched_off),
            "estimates": np.round(self.estimates, 4).tolist(),
            "truth": np.round(self.truth, 4).tolist(),
            "tracks": [{"id": int(i), "xy": np.round(p, 4).tolist()}
                       for i, p in zip(self.track_ids, self.track_xy)],
        }


class LiveSource:
    """Renders and processes only the cameras asked for, as switched-on nodes would.

    A node that is switched on starts with a fresh temporal filter state.
    scene : calibrated scene; params : pipeline parameters; rng : sensor noise
    """

    def __init__(self, scene: Scene, params: PipelineParams | None, rng: np.random.Generator,
                 keep_frames: bool = False):
        from render import Renderer

        self.renderer = Renderer(scene)
        background = self.renderer.background().rgb
        self.pipes = {cam.number: Pipeline([cam], params, background=background[i:i + 1])
                      for i, cam in enumerate(scene.cameras)}
        self.bearings = {n: p.bearings[0] for n, p in self.pipes.items()}
        ranges = {n: p.sight_range(scene.people.height, object_width=2 * scene.people.radius)
                  for n, p in self.pipes.items()}
        self.near = {n: float(r[0][0]) for n, r in ranges.items()}   # blind radius, metres
        self.far = {n: float(r[1][0]) for n, r in ranges.items()}    # sight radius, metres
        self.rng = rng
        self.keep_frames = keep_frames
        self._on: set[int] = set()
        self.seconds: dict[str, float] = defaultdict(float)   # time spent per stage

    def scanlines(self, index: int, positions_xy: np.ndarray, numbers: tuple[int, ...]):
        """(k, W) bool scanlines of cameras ``numbers`` and, if kept, their RGB frames."""
        t0 = time.perf_counter()
        frames = self.renderer.render(positions_xy, cameras=numbers, rng=self.rng)
        t1 = time.perf_counter()
        out = []
        for i, n in enumerate(numbers):
            if n not in self._on:
                self.pipes[n].reset()
            out.append(self.pipes[n].process(frames.rgb[i:i + 1])[0])
        self._on = set(numbers)
        self.seconds["render"] += t1 - t0
        self.seconds["pipeline"] += time.perf_counter() - t1
        return np.array(out), (frames.rgb if self.keep_frames else None)

    def close(self) -> None:
        self.renderer.close()


class PrecomputedSource:
    """Scanlines computed beforehand for every camera: (frames, n_cams, W) bool.

    bearings : (n_cams, W) float, radians; near, far : optional (n_cams,) float, metres,
    each camera's blind and sight radius (:meth:`pipeline.Pipeline.sight_range`), default
    0 and inf
    """

    def __init__(self, scanlines: np.ndarray, bearings: np.ndarray, near=None, far=None):
        self.all = np.asarray(scanlines, bool)
        self.bearings = {i + 1: b for i, b in enumerate(np.asarray(bearings, float))}
        n = len(self.bearings)
        self.near = dict(enumerate(np.zeros(n) if near is None else np.asarray(near, float).tolist(), 1))
        self.far = dict(enumerate(np.full(n, np.inf) if far is None else np.asarray(far, float).tolist(), 1))

    def scanlines(self, index: int, positions_xy, numbers: tuple[int, ...]):
        return self.all[index, np.asarray(numbers) - 1], None

    def close(self) -> None:
        pass


def tracker_params(scene: Scene) -> TrackerParams:
    """Tracker settings scaled to the people's size: gate 3 radii, noise half a radius."""
    r = scene.people.radius
    return TrackerParams(dt=scene.dt, gate=3 * r, meas_std=0.5 * r, accel_std=2.0 * scene.people.speed)


def scanline_views(bearings) -> tuple[np.ndarray, np.ndarray]:
    """Each camera's floor-plane view as its scanline sees it, for tasking: yaw (n,) radians,
    the direction halfway between the outer edges of its first and last columns, and fov
    (n,) radians, the angle between those edges.

    bearings : n sequences of (W,) float, radians, each camera's column bearings, left to
        right (decreasing, as the pipeline's; increasing ones, of a hand-made source, are
        read right to left). Not the optical axis and the pinhole's field of view: an
        off-centre principal point turns the view from the axis, a barrel lens widens it,
        and the pitch and the rectification narrow it (lab: 49.15 degrees, 0.21 off the
        axis).

    The same view as :func:`tasking.cones.scanline_intervals` gives, but for the yaw's last
    bit (that one wraps by a modulo, this one through ``np.angle``): the recorded tasking
    results were made with this one.

    >>> yaw, fov = scanline_views([np.radians([10.0, 0.0, -10.0])])
    >>> np.degrees(yaw).round(6).tolist(), np.degrees(fov).round(6).tolist()
    ([0.0], [30.0])
    """
    yaw, fov = [], []
    for b in bearings:
        b = np.unwrap(np.asarray(b, float))
        if b[-1] > b[0]:                                     # increasing: the same view, read from the right
            b = b[::-1]
        left = b[0] + (b[0] - b[1]) / 2                     # columns are pixel centres: half one out
        right = b[-1] - (b[-2] - b[-1]) / 2
        yaw.append(float(np.angle(np.exp(0.5j * (left + right)))))
        fov.append(float(left - right))
    return np.array(yaw), np.array(fov)


def run_loop(scene: Scene, config: LoopConfig, truth: np.ndarray, source, *, on_frame=None,
             progress: bool = False, seconds: dict | None = None):
    """Run the tasked network over ``truth`` (frames, people, 2) metres; yield :class:`FrameResult`.

    source : :class:`LiveSource` or :class:`PrecomputedSource`
    on_frame : optional callback called with each result
    seconds : optional dict; the central node's time per stage ("hull", "tracker",
        "tasker", seconds) is added to it
    """
    seconds = defaultdict(float) if seconds is None else seconds
    from tqdm import tqdm

    config.check(len(scene.cameras))
    xy, _, _ = scene.floor_poses()
    yaw, fov = scanline_views([source.bearings[i + 1] for i in range(len(scene.cameras))])
    radius = scene.people.radius
    object_area = np.pi * radius**2
    occupied = max(len(truth[0]) if len(truth) else 0, 1) * object_area
    uniform = scene.uniform_indices()
    tasked = choose_cameras("uniform", config.k, xy, yaw, fov, np.zeros((0, 2)), radius,
                            scene.room.polygon, uniform_sets=uniform)
    tracker = Tracker(tracker_params(scene))
    previous: tuple[int, ...] = ()
    for t in tqdm(range(len(truth)), desc=f"{config.tasker} k={config.k}", unit="frame",
                  disable=not progress):
        numbers = tuple(int(i) + 1 for i in tasked)
        scan, rgb = source.scanlines(t, truth[t], numbers)
        t0 = time.perf_counter()
        bearings = np.array([source.bearings[n] for n in numbers])
        near = np.array([source.near[n] for n in numbers]) if config.near_field else None
        far = np.array([source.far[n] for n in numbers]) if config.near_field else None
        hull = visual_hull_of_scanlines(xy[tasked], bearings, scan, scene.room.polygon, near, far)
        polygons = prune_small(hull, object_area)
        centres = polygon_centres(polygons)
        t1 = time.perf_counter()
        ids, est = tracker.step(centres)
        seconds["hull"] = seconds.get("hull", 0.0) + t1 - t0
        seconds["tracker"] = seconds.get("tracker", 0.0) + time.perf_counter() - t1
        area = float(sum(p.area for p in polygons))
        result = FrameResult(
            index=t, tasked=numbers, scanlines=scan, polygons=polygons, hull_area=area,
            residual=area / occupied - 1, bits_sent=int(scanline_bits(scan).sum()),
            switched_on=tuple(sorted(set(numbers) - set(previous))) if previous else (),
            switched_off=tuple(sorted(set(previous) - set(numbers))),
            estimates=centres, truth=np.asarray(truth[t]), track_ids=ids, track_xy=est, rgb=rgb)
        if on_frame is not None:
            on_frame(result)
        yield result
        previous = numbers
        last = t + 1 == len(truth)  # no next frame to choose cameras for
        if (t + 1) % config.update_every == 0 and config.tasker != "uniform" and not last:
            t0 = time.perf_counter()
            estimates = centres
            if config.feedback == "tracks" and len(tracker.estimates()):
                estimates = tracker.estimates()
            current = tasked if config.tasker == "incremental" else None
            tasked = choose_cameras(config.tasker, config.k, xy, yaw, fov, estimates, radius,
                                    scene.room.polygon, current=current, m=config.m,
                                    uniform_sets=uniform, rng=np.random.default_rng(t))
            seconds["tasker"] = seconds.get("tasker", 0.0) + time.perf_counter() - t0


def summarise(results: list[FrameResult], scene: Scene) -> dict:
    """Means over the run and tracking metrics against the true positions (``mse`` and
    ``motp`` None when no track was ever matched to a person)."""
    n = len(results)
    switches = sum(len(r.switched_on) + len(r.switched_off) for r in results)
    people = len(results[0].truth) if n else 0
    tracking = tracking_metrics(
        [np.arange(people)] * n, [r.truth for r in results],
        [r.track_ids for r in results], [r.track_xy for r in results],
        max_distance=tracker_params(scene).gate) if n and people else {}
    # no matched position, no mean error: null in JSON, which has no NaN
    tracking = {k: None if isinstance(v, float) and not np.isfinite(v) else v for k, v in tracking.items()}
    if tracking:
        tracking["max_distance"] = tracker_params(scene).gate     # metres, the metric's matching distance
    return {
        "frames": n,
        "hull_area": float(np.mean([r.hull_area for r in results])) if n else float("nan"),
        "residual": float(np.mean([r.residual for r in results])) if n else float("nan"),
        "bits_per_frame": float(np.mean([r.bits_sent for r in results])) if n else 0.0,
        "camera_switches": switches,
        "tracking": tracking,
    }
