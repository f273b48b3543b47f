"""One episode of a synthetic dataset, rendered and processed into its own folder.

:func:`render_episode` is the unit of work that ``camtask render`` spreads over Dask
workers: it renders the walk of episode ``index``, writes every file of the episode into
a temporary folder ``DIR/.episode_NNNN.<random>.tmp``, computes the checksum (BLAKE3) of each file
and renames the folder to ``DIR/episode_NNNN`` only when everything is written. Its
random streams come from ``np.random.SeedSequence(seed, spawn_key=(index,))`` (the
``index``-th child of ``SeedSequence(seed).spawn``), never from the worker, so the bytes do
not depend on which worker renders the episode or how many there are.

Each process keeps its last :data:`KEEP` :class:`render.Renderer` s, one per (scene text,
people, cameras), in a module cache (one GL context per process; renderers are not
created and destroyed per episode), and closes older ones: a worker of a long-lived
cluster renders run after run. The caches are keyed by the scene file's text, so a file
edited between two runs is rendered as it is now; the parsed scenes by its path as well,
since a scene without a ``name`` is named after its file. The layout is in docs/dataset.md.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import os
import shutil
import sys
import time
import weakref
import zipfile
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.files import temp_folder
from scene.checks import check_choice
from testbed.checksum import ALGORITHM, digest, file_digest
from testbed.dataset import frame_name, write_calibration
from testbed.png import encode_png, write_file, write_png

#: Formats of the RGB frames: PNG per frame, or one lossless FFV1 video per camera.
FORMATS = ("png", "video")

#: Renderers kept per process (a lab renderer holds ~150 MB: canvases, frames, framebuffers);
#: as many rigs' rectification maps, and twice as many pipelines (one per parameter set).
KEEP = 2

_SCENES: OrderedDict = OrderedDict()      # (scene text, file) -> Scene, parsed once
_RENDERERS: OrderedDict = OrderedDict()   # (scene text, people, cameras) -> Renderer
_RECTIFIERS: OrderedDict = OrderedDict()  # (scene text, cameras) -> Rectifier, shared by that rig's pipelines
_PIPELINES: OrderedDict = OrderedDict()   # (renderer key, parameters) -> Pipeline on its background, reset per episode
_BACKGROUNDS: OrderedDict = OrderedDict()  # renderer key -> (weak ref to that Renderer, its background PNGs)


def _cached(cache: OrderedDict, key, make, keep: int = KEEP):
    """``cache[key]``, made by ``make()`` when missing; the ``keep`` most recently used stay,
    older values are dropped (and closed, if they can be)."""
    if key in cache:
        cache.move_to_end(key)
        return cache[key]
    value = cache[key] = make()
    while len(cache) > keep:
        _, old = cache.popitem(last=False)
        if hasattr(old, "close"):
            old.close()
    return value


@dataclass(frozen=True)
class EpisodeConfig:
    """What every episode of a run shares (picklable; sent to the workers).

    scene : built-in scene name or scene file path
    people : number of people, None for the scene's own
    cameras : 1-based camera numbers, None for all; kept in number order, so the same
        cameras given in another order are the same run (same config, same bytes)
    frames : frames per episode (>= 1)
    seed : the run's seed S
    fmt : "png" or "video"
    params : pipeline parameters as a plain dict (PipelineParams.to_dict())
    scene_yaml : the scene file's text, read once when the run starts (:func:`with_scene_text`),
        so that every episode renders the same scene even if the file is edited during the
        run, and workers need not see the file; "" to read ``scene`` when needed. Not in
        :meth:`to_dict` (each episode's meta.json holds it)
    """

    scene: str
    people: int | None
    cameras: tuple[int, ...] | None
    frames: int
    seed: int
    fmt: str = "png"
    params: dict = field(default_factory=dict)
    scene_yaml: str = field(default="", repr=False)

    def __post_init__(self):
        check_choice("fmt", self.fmt, FORMATS)
        if self.cameras is not None:
            object.__setattr__(self, "cameras", tuple(sorted(self.cameras)))

    def to_dict(self) -> dict:
        return {"scene": self.scene, "people": self.people,
                "cameras": None if self.cameras is None else list(self.cameras),
                "frames": self.frames, "seed": self.seed, "format": self.fmt, "params": dict(self.params)}


def episode_name(index: int) -> str:
    """``episode_NNNN`` for the 0-based episode ``index``."""
    return f"episode_{index:04d}"


def episode_seed(seed: int, index: int) -> np.random.SeedSequence:
    """The seed of episode ``index`` of a run with seed ``seed``: ``SeedSequence(seed).spawn(...)[index]``.

    >>> int(episode_seed(7, 2).generate_state(1)[0]) == int(np.random.SeedSequence(7).spawn(3)[2].generate_state(1)[0])
    True
    """
    return np.random.SeedSequence(int(seed), spawn_key=(int(index),))


def scene_text(config: EpisodeConfig) -> str:
    """The text of the run's scene: ``config.scene_yaml``, else the scene file's text now."""
    from scene.config import read_scene_text, scene_file

    return config.scene_yaml or read_scene_text(scene_file(config.scene))


def with_scene_text(config: EpisodeConfig) -> EpisodeConfig:
    """``config`` with its scene file's text read (:attr:`EpisodeConfig.scene_yaml`), once."""
    return config if config.scene_yaml else dataclasses.replace(config, scene_yaml=scene_text(config))


def load_episode_scene(config: EpisodeConfig):
    """The scene of a run (parsed from :func:`scene_text`), with ``config.people`` people."""
    from scene import Scene
    from scene.config import scene_file
    from testbed.episode import with_people

    text, source = scene_text(config), str(scene_file(config.scene))
    # keyed by the file too: a scene without ``name`` is named after its file (meta.json's "scene")
    scene = _cached(_SCENES, (text, source), lambda: Scene.from_text(text, source), 2 * KEEP)
    return with_people(scene, config.people)


def without_scene_own(values: dict, config: EpisodeConfig) -> dict:
    """``values`` (in the form of :meth:`EpisodeConfig.to_dict`) with ``people`` and
    ``cameras`` None where they name the scene of ``config`` itself: its number of people,
    every camera in the file's order. Other keys as they are."""
    own = load_episode_scene(dataclasses.replace(config, people=None))
    owns = {"people": own.people.count, "cameras": [c.number for c in own.cameras]}
    return {k: None if k in owns and v == owns[k] else v for k, v in values.items()}


def canonical(config: EpisodeConfig) -> EpisodeConfig:
    """``config`` with ``people`` and ``cameras`` None where they name the scene's own: ``--people
    3`` on a scene of 3 people, or every camera in the scene file's order, renders the same
    episodes as leaving them out, so it is the same run (the same manifest, and ``--resume``
    takes either; :func:`without_scene_own`)."""
    values = without_scene_own(config.to_dict(), config)
    return dataclasses.replace(config, people=values["people"],
                               cameras=None if values["cameras"] is None else config.cameras)


def _renderer(config: EpisodeConfig, scene):
    """This process's renderer of ``scene`` (:func:`load_episode_scene` of ``config``)."""
    from render import Renderer

    key = (scene_text(config), scene.people.count, config.cameras)
    return _cached(_RENDERERS, key, lambda: Renderer(scene, config.cameras))


def _background_pngs(key, renderer) -> list[tuple[bytes, str]]:
    """Each camera's background PNG (bytes, checksum), in ``renderer.numbers`` order: encoded
    once per renderer, not per episode (16 lab frames: ~15 ms of fpng and checksums an
    episode; ~8 MB kept per renderer, which is not kept alive by it)."""
    if key in _BACKGROUNDS and _BACKGROUNDS[key][0]() is not renderer:
        del _BACKGROUNDS[key]                   # a renderer made anew: its own background
    pngs = lambda: [(data, digest(data)) for data in map(encode_png, renderer.background().rgb)]
    return _cached(_BACKGROUNDS, key, lambda: (weakref.ref(renderer), pngs()))[1]


def checksums(root: Path, known: dict[str, str] | None = None, algorithm: str = ALGORITHM,
              others: list[str] | None = None) -> dict[str, str]:
    """Checksum of every file under ``root``, keyed by the POSIX path relative to it, sorted.

    known : digests already computed while writing (relative path -> hex); those files
        are not read again
    algorithm : see :mod:`testbed.checksum`
    others : if given, the entries that are neither files nor folders are appended (see
        :func:`files_under`)
    """
    known = known or {}
    root = Path(root)
    return {rel: known[rel] if rel in known else file_digest(root / rel, algorithm)
            for rel in files_under(root, others)}


def files_under(root: str | os.PathLike, others: list[str] | None = None) -> list[str]:
    """Every file under ``root`` (symbolic links to files included, not followed into
    folders), as POSIX paths relative to it, sorted as ``sorted(root.rglob("*"))`` sorts
    them: by path components. (``os.scandir`` strings: ~0.6 ms for the ~1200 files of a
    24-frame lab episode, ~11 ms with ``pathlib``.)

    others : if given, every other entry is appended to it, sorted likewise: FIFOs,
        sockets, devices, links to nowhere or to themselves (none is read)
    """
    found, other, todo = [], [], [(os.fspath(root), "")]
    while todo:
        folder, prefix = todo.pop()
        with os.scandir(folder) as entries:
            for e in entries:
                if e.is_dir(follow_symlinks=False):
                    todo.append((e.path, f"{prefix}{e.name}/"))
                elif _is_file(e):
                    found.append(prefix + e.name)
                else:
                    other.append(prefix + e.name)
    if others is not None:
        others.extend(sorted(other, key=lambda rel: rel.split("/")))
    return sorted(found, key=lambda rel: rel.split("/"))


def _is_file(entry: os.DirEntry) -> bool:
    """A regular file, or a link to one; False for a link loop (ELOOP) rather than an error."""
    try:
        return entry.is_file()
    except OSError:
        return False


def save_npz_exact(path: Path, **arrays) -> None:
    """Like ``np.savez_compressed``, but the bytes depend only on the arrays (fixed zip dates)."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for key, val in arrays.items():
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.asanyarray(val), allow_pickle=False)
            info = zipfile.ZipInfo(f"{key}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            zf.writestr(info, buf.getvalue())


def silhouette_dtype(people: int, option: str = "--people"):
    """uint8 up to 8 people, uint16 up to 16 (PNG stores at most 16 bits); ``option`` names the count in errors."""
    if people > 16:
        raise ValueError(f"{option}: silhouettes store one bit per person in a 16-bit PNG; expected at most 16, "
                         f"got {people}")
    return np.uint8 if people <= 8 else np.uint16


#: Gap between two people's discs (metres) beyond which the nearer one's label is exact.
APART = 0.02


def silhouettes(renderer, positions_xy: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Unoccluded silhouette of every person as a bitmask, exactly as if rendered alone.

    positions_xy : (P, 2) float, metres, world frame (NaN rows: hidden)
    labels : (n_cams, H, W) uint8, the visible labels of the same frame, all cameras of
        ``renderer`` (0 background, person + 1)
    Returns (n_cams, H, W) uint8 (uint16 above 8 people), bit ``i`` set where person ``i``
    covers the pixel when the others are hidden.

    Person i's silhouette in a camera is ``labels == i + 1`` when nobody can occlude
    them there: when every person whose canvas box (the renderer's conservative box of
    every pixel a person covers) meets i's stands behind i. Person j is behind i when
    their discs are more than ``2 radius + APART`` apart and the camera is no farther
    from i's centre than from j's: the people are translated copies of one convex prism
    inside their discs, so the vertical bisector plane separates them, every ray from
    the camera meets i before j, and with APART the depths along a ray differ by far more
    than the 24-bit depth buffer resolves. One look-up table per camera maps every such
    label to its bit; the other people are re-rendered with the others hidden
    (:meth:`render.Renderer.labels`, no colour work). Both are bit-identical to rendering
    each person alone (tests/test_dataset_render.py).
    """
    from testbed.label_kernel import or_lookup  # numba: imported (and compiled) on first use

    pos = np.asarray(positions_xy, float)
    P, n = len(pos), len(renderer.numbers)
    dtype = silhouette_dtype(P)
    out = np.zeros(labels.shape, dtype)
    if P == 0:
        return out
    rects = renderer._rects(np.arange(n), pos)                          # (n, P, 4) canvas boxes, NaN: unseen
    x0, y0, x1, y1 = (rects[..., k] for k in range(4))
    with np.errstate(invalid="ignore"):
        meet = ((x0[:, :, None] <= x1[:, None, :]) & (x0[:, None, :] <= x1[:, :, None])
                & (y0[:, :, None] <= y1[:, None, :]) & (y0[:, None, :] <= y1[:, :, None]))  # (n, P, P)
    meet &= ~np.eye(P, dtype=bool)[None]
    centres = np.stack([c.center_world[:2] for c in renderer.cameras])  # (n, 2) metres
    to_cam = np.linalg.norm(centres[:, None, :] - pos[None], axis=2)    # (n, P)
    apart = np.linalg.norm(pos[:, None] - pos[None], axis=2) > 2 * renderer.scene.people.radius + APART
    behind = apart[None] & (to_cam[:, :, None] <= to_cam[:, None, :])  # (n, P, P): j behind i
    overlap = (meet & ~behind).any(axis=2)                              # (n, P): i may be occluded
    bits = (1 << np.arange(P)).astype(dtype)
    lut = np.zeros((n, 256), dtype)                                     # label -> bit, direct people only
    lut[:, 1:P + 1] = np.where(overlap, 0, bits)
    labels = np.ascontiguousarray(labels)
    for c in np.flatnonzero(lut.any(axis=1)):
        or_lookup(labels[c], lut[c], out[c])                            # label 0 stays 0
    for i in range(P):
        cams = np.flatnonzero(overlap[:, i])
        if cams.size:
            alone = np.full_like(pos, np.nan)
            alone[i] = pos[i]
            seen = renderer.labels(alone, cameras=[renderer.numbers[c] for c in cams])
            table = np.full(256, bits[i], dtype)                        # any label: person i
            for k, c in enumerate(cams):
                or_lookup(seen[k], table, out[c])
    return out


def hull_record(frame: int, hull) -> dict:
    """One frame's hull as JSON: area (m^2) and polygons (exterior + holes, metres, 1e-6 m).

    The polygons are in GEOS's normal form (``shapely.normalize``: parts and rings in a
    fixed order, each ring from a fixed vertex), so the bytes depend on the region, not on
    the order in which the overlays built it.
    """
    import shapely
    from shapely.geometry import MultiPolygon

    from tasking.hull import prune_small

    polys = list(shapely.normalize(MultiPolygon(prune_small(hull, 0.0))).geoms)
    ring = lambda r: [[round(x, 6), round(y, 6)] for x, y in r.coords]
    return {"frame": frame, "area": round(float(sum(p.area for p in polys)), 9),
            "polygons": [{"exterior": ring(p.exterior), "holes": [ring(h) for h in p.interiors]}
                         for p in polys]}


def _episode_pipeline(config: EpisodeConfig, scene, renderer, params):
    """The node pipeline of ``config``'s rig on ``renderer``'s background, reset to its first
    frame: its background levels (~15 MB for 16 cameras) and rectification maps are made once
    per process and rig."""
    from pipeline import Pipeline, Rectifier

    text, cameras, numbers = config.scene_yaml, renderer.cameras, tuple(renderer.numbers)

    def make():
        rectifier = _cached(_RECTIFIERS, (text, numbers), lambda: Rectifier.build(cameras))
        return Pipeline(cameras, params, renderer.background().rgb, rectifier)

    key = (text, scene.people.count, config.cameras, json.dumps(config.params, sort_keys=True))
    pipe = _cached(_PIPELINES, key, make, 2 * KEEP)
    pipe.reset()
    return pipe


class _Frames:
    """What one episode keeps of its frames, consumed in order: the images written into
    ``tmp`` (their checksums in ``digests``), the node pipeline's and the true scanlines,
    the ground-truth hull and the people's rows for people.csv.

    spent : callable(stage, seconds) that adds up the wall-clock time per stage
    """

    def __init__(self, tmp: Path, config: EpisodeConfig, scene, renderer, pipe, track, spent):
        from tasking.hull import visual_hull_of_scanlines

        self.tmp, self.pipe, self.track, self.spent = tmp, pipe, track, spent
        self.people = scene.people
        self.digests: dict[str, str] = {}       # checksums of the images, from the bytes written
        self.rows, self.scans, self.gts, self.hulls = [], [], [], []
        self.cameras = renderer.cameras
        self.images = ("masks", "silhouettes") if config.fmt == "video" else ("frames", "masks", "silhouettes")
        self.folders = {(sub, k): f"{sub}/{c.name}/" for sub in self.images
                        for k, c in enumerate(self.cameras)}                    # relative to tmp
        xy_all, _, _ = scene.floor_poses()
        by_number = {c.number: k for k, c in enumerate(scene.cameras)}
        camera_xy = xy_all[[by_number[n] for n in renderer.numbers]]
        size = {"object_width": 2 * self.people.radius}
        self.near, self.far = pipe.sight_range(self.people.height, **size)     # metres: the pipeline's scanlines
        self.gt_near, self.gt_far = pipe.sight_range(self.people.height, truth=True, **size)  # the true ones
        room = scene.room.polygon
        self.hull = lambda gt: visual_hull_of_scanlines(camera_xy, pipe.bearings, gt, room,
                                                        self.gt_near, self.gt_far)
        self.videos = []

    def start(self, renderer, backgrounds, frame_rate: float) -> None:
        """Write the calibration and backgrounds, make the image folders, open the videos."""
        tmp = self.tmp
        for sub in ("calibration", "background"):
            (tmp / sub).mkdir()
        for k, c in enumerate(self.cameras):
            write_calibration(tmp / "calibration" / f"{c.name}.yaml", c)
            data, self.digests[f"background/{c.name}.png"] = backgrounds[k]
            write_file(tmp / "background" / f"{c.name}.png", data)
            for sub in self.images:
                (tmp / self.folders[sub, k]).mkdir(parents=True)
        if "frames" not in self.images:
            from testbed.lossless import VideoWriter
            (tmp / "frames").mkdir()
            for c in self.cameras:                # one by one: those started are closed if a later one fails
                self.videos.append(VideoWriter(tmp / "frames" / f"{c.name}.mkv", renderer.width, renderer.height,
                                               frame_rate))

    def consume(self, f: int, fr, sil) -> None:
        """Write frame f's images, then run the node pipeline, ground truth and hull."""
        t2 = time.perf_counter()
        fname = frame_name(f)
        for k in range(len(self.cameras)):
            if self.videos:
                self.videos[k].write(fr.rgb[k])
            for sub, img in ((("frames", fr.rgb[k]),) if not self.videos else ()) + (
                    ("masks", fr.labels[k]), ("silhouettes", sil[k])):
                rel = self.folders[sub, k] + fname
                self.digests[rel] = write_png(f"{self.tmp}/{rel}", img)
        t3 = time.perf_counter()
        scan, gt = self.pipe.process_with_truth(fr.rgb, fr.labels)
        self.scans.append(scan)
        self.gts.append(gt)
        t4 = time.perf_counter()
        self.hulls.append(hull_record(f, self.hull(gt)))
        for pid, (x, y) in enumerate(np.asarray(self.track[f], float)):
            self.rows.append((f, pid, repr(float(x)), repr(float(y)), self.people.radius, self.people.height))
        for key, dt in (("write", t3 - t2), ("pipeline", t4 - t3), ("hull", time.perf_counter() - t4)):
            self.spent(key, dt)

    def close_videos(self) -> None:
        """Close every video writer; raise the first failure unless an exception is under way."""
        closing = None
        for v in self.videos:
            try:
                v.close()
            except OSError as exc:
                closing = closing or exc
        if closing is not None and sys.exc_info()[1] is None:
            raise closing

    def finish(self, params, meta: dict) -> None:
        """Write the files made from every frame: people.csv, scanlines.npz, pipeline.yaml,
        gt_hull.json and meta.json."""
        tmp, pipe = self.tmp, self.pipe
        with open(tmp / "people.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["frame", "person_id", "x", "y", "radius", "height"])
            w.writerows(self.rows)
        save_npz_exact(tmp / "scanlines.npz", scanlines=np.stack(self.scans), gt_scanlines=np.stack(self.gts),
                       bearings=pipe.bearings, camera_numbers=np.array(meta["cameras"]),
                       blind_radius=self.near, sight_radius=self.far,
                       gt_blind_radius=self.gt_near, gt_sight_radius=self.gt_far)
        params.to_yaml(tmp / "pipeline.yaml")
        (tmp / "gt_hull.json").write_text(json.dumps(
            {"units": "metres, world frame", "source": "ground-truth scanlines of all cameras of the episode, between their blind and sight radii",
             "cameras": meta["cameras"], "frames": self.hulls}, separators=(",", ":")) + "\n")
        (tmp / "meta.json").write_text(json.dumps(meta, indent=2, sort_keys=True) + "\n")


def _render_frames(renderer, track, sensor_rng, frames: _Frames, count: int, spent, progress=None,
                   overlap: bool = False) -> None:
    """Render frames 0 .. count - 1 of ``track`` with their silhouettes and hand each to
    ``frames.consume`` in order; with ``overlap`` a second thread consumes frame f while this
    one renders frame f + 1 (one frame in flight at most: bounded memory)."""
    pool = ThreadPoolExecutor(1, thread_name_prefix="episode-consume") if overlap else None
    pending = None
    try:
        for f in range(count):
            t0 = time.perf_counter()
            fr = renderer.render(track[f], rng=sensor_rng)
            t1 = time.perf_counter()
            sil = silhouettes(renderer, track[f], fr.labels)
            for key, dt in (("render", t1 - t0), ("silhouettes", time.perf_counter() - t1)):
                spent(key, dt)
            if pool is None:
                frames.consume(f, fr, sil)
            else:
                if pending is not None:
                    pending.result()            # frame f - 1 is done
                pending = pool.submit(frames.consume, f, fr, sil)
            if progress is not None and (pool is None or f > 0):
                progress(1)
        if pending is not None:
            pending.result()
            if progress is not None:
                progress(1)
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
        frames.close_videos()


def render_episode(config: EpisodeConfig, index: int, out: str, progress=None,
                   seconds: dict | None = None, overlap: bool = False) -> dict:
    """Render, process and write episode ``index`` into ``out/episode_NNNN``; return its manifest entry.

    progress : optional callable(frames_done_since_last_call) for in-process progress bars
    seconds : optional dict; the wall-clock seconds spent per stage (render, silhouettes,
        write, pipeline, hull, finish) and in all (total) are added to it, so one dict can
        sum several episodes - for run_info.json, never the manifest
    overlap : write and process frame f on a second thread while frame f + 1 renders (for a
        process that has a core to spare; the files are the same bytes either way)
    """
    seconds = {} if seconds is None else seconds

    def spent(stage: str, dt: float) -> None:
        seconds[stage] = seconds.get(stage, 0.0) + dt

    start = time.perf_counter()
    from pipeline import PipelineParams
    from testbed.episode import walk

    out = Path(out)
    config = with_scene_text(config)             # one text for the whole episode
    scene = load_episode_scene(config)
    renderer = _renderer(config, scene)
    params = PipelineParams.from_mapping(config.params)
    pipe = _episode_pipeline(config, scene, renderer, params)
    motion_rng, sensor_rng = np.random.default_rng(episode_seed(config.seed, index)).spawn(2)
    track = walk(scene, config.frames, motion_rng)
    backgrounds = _background_pngs((config.scene_yaml, scene.people.count, config.cameras), renderer)
    name = episode_name(index)
    tmp = temp_folder(out, f".{name}.")
    try:
        frames = _Frames(tmp, config, scene, renderer, pipe, track, spent)
        try:
            frames.start(renderer, backgrounds, scene.frame_rate)
        except BaseException:
            frames.close_videos()                # the videos started before the failure
            raise
        loop_start = time.perf_counter()
        _render_frames(renderer, track, sensor_rng, frames, config.frames, spent, progress, overlap)
        loop_end = time.perf_counter()
        frames.finish(params, {
            "episode": index, "seed": config.seed, "spawn_key": [index],
            "scene": scene.name, "scene_file": config.scene, "scene_yaml": config.scene_yaml,
            "people": scene.people.count, "cameras": list(renderer.numbers), "frames": config.frames,
            "dt": scene.dt, "format": config.fmt, "backend": renderer.backend,
            "background": "clean: no sensor noise, no gain jitter",
            "silhouettes": f"bit i = person i, {np.dtype(silhouette_dtype(scene.people.count)).name} PNG",
        })
        files = checksums(tmp, frames.digests)
        end = time.perf_counter()
        spent("total", end - start)
        spent("finish", (loop_start - start) + (end - loop_end))    # set-up and the files after the frames
        final = out / name
        if final.exists():                       # a retried task whose first run got this far
            shutil.rmtree(final)
        os.rename(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return {"index": index, "name": name, "seed": config.seed, "spawn_key": [index],
            "frames": config.frames, "files": files}
