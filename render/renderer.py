"""What the cameras see: shaded RGB frames, exact label images, lens distortion, noise.

Usage (not run as a doctest: it needs OpenGL)::

    with Renderer(load_scene("lab")) as r:
        frames = r.render(np.array([[2.0, 2.0], [4.0, 3.0], [3.0, 4.5]]),
                          rng=np.random.default_rng(0))
        frames.rgb.shape, frames.labels.shape   # (16, 480, 640, 3), (16, 480, 640)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Self

import cv2
import numpy as np

from scene.config import Scene

from .distortion import DistortionMaps, distort, distort_region, distortion_maps, regions_of
from .geometry import Lighting, Mesh, people_mesh, room_mesh, soles_mesh
from .noise import draw_gains_offsets, noise_pool, sense
from .pose import projection_matrix, view_matrix
from .raster import Rasteriser

#: The default lighting (frozen, shared).
DEFAULT_LIGHTING = Lighting()

#: Near clipping plane of the OpenGL cameras, metres (the far plane is :func:`far_plane`'s).
ZNEAR = 0.05

#: The far clipping plane is never nearer than this, metres: every scene whose far corner
#: is within 25 m of its cameras keeps exactly the depth values (and pixels) it always had.
ZFAR_MIN = 50.0


@dataclass(frozen=True, eq=False)
class Frames:
    """One time step seen by several cameras.

    rgb : (n_cams, H, W, 3) uint8, RGB, distorted like the real cameras
    labels : (n_cams, H, W) uint8, 0 = background, person index + 1 elsewhere; exact
        (nearest-neighbour resampled through the same lens distortion)
    cameras : the 1-based camera numbers, one per leading index
    """

    rgb: np.ndarray
    labels: np.ndarray
    cameras: tuple[int, ...]

    @property
    def masks(self) -> np.ndarray:
        """(n_cams, H, W) bool, True where any person is."""
        return self.labels > 0


def far_plane(scene: Scene) -> float:
    """The far clipping plane of every camera of ``scene``, metres.

    Twice the largest distance from any camera of the scene to any corner of the room's
    bounding box, from the floor to the ceiling or the people's heads (whichever is
    higher) and widened by the people's radius, and at least :data:`ZFAR_MIN`: nothing
    inside the room is ever clipped, whatever the scene's size or unit. It depends on
    all the scene's cameras, not on those a renderer prepares, so a camera's depth values
    do not depend on which others are rendered (its colours do a little, through its band
    in the framebuffer: docs/render.md). With the near plane fixed at :data:`ZNEAR`
    the depth step at distance d is about d**2 / (ZNEAR * 2**24) whatever the far plane
    (0.1 mm at 9 m, 4 mm at 60 m), so a generous far plane costs no depth precision.

    >>> from scene import load_scene
    >>> far_plane(load_scene("lab"))
    50.0
    """
    x0, y0, x1, y1 = scene.room.polygon.bounds
    r = scene.people.radius if scene.people.count else 0.0
    top = max(scene.room.height, scene.people.height if scene.people.count else 0.0)
    corners = np.array([[x, y, z] for x in (x0 - r, x1 + r) for y in (y0 - r, y1 + r) for z in (0.0, top)])
    centres = np.stack([np.asarray(c.center_world, float) for c in scene.cameras])
    farthest = float(np.linalg.norm(corners[None] - centres[:, None], axis=-1).max())
    return max(ZFAR_MIN, 2.0 * farthest)


def check_camera_numbers(name: str, numbers, available) -> tuple[int, ...]:
    """Return ``numbers`` as a tuple of camera numbers that exist in ``available``."""
    available = tuple(available)
    if numbers is None:
        return available
    try:
        numbers = tuple(_whole_number(n) for n in numbers)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name}: expected camera numbers, got {numbers!r}") from None
    bad = [n for n in numbers if n not in available]
    if bad or not numbers or len(set(numbers)) != len(numbers):
        run = available == tuple(range(available[0], available[-1] + 1))
        among = f"{available[0]}..{available[-1]}" if run else ", ".join(map(str, available))
        raise ValueError(f"{name}: expected distinct camera numbers among {among}, got {list(numbers)}")
    return numbers


def _whole_number(n) -> int:
    """``n`` as an int if it is a whole number (5, 5.0, np.int64(5)); ValueError for 5.5, True, "5"."""
    if isinstance(n, (bool, np.bool_, str, bytes)) or int(n) != n:
        raise ValueError(n)
    return int(n)


class Renderer:
    """Renders a calibrated scene for a set of cameras; reuse it across frames.

    scene : a :class:`scene.Scene` whose cameras are calibrated (``scene.is_calibrated``)
    cameras : 1-based camera numbers to prepare (default: all)
    lighting : the light baked into the vertex colours

    Every camera's ideal pinhole image (RGB and labels together) lives on a canvas
    slightly larger than the image (labels in the alpha channel). The empty room is drawn
    once and cached (canvases, distorted frames, and its colour + depth in GL); a step
    draws only the people's triangles, over the room's colour and depth copied into each
    person's canvas box, and reads back only those boxes (bit-identical to drawing the
    whole scene). ``cv2.remap`` applies each camera's lens distortion (bilinear for RGB, nearest for
    labels) only inside the regions the people can change, the rest of each frame being
    the cached distorted background (bit-identical to remapping everything); then the
    per-frame gain and the pooled sensor noise (:mod:`render.noise`). A camera that a
    person comes within the near plane of, or encloses, sees that person wherever it
    covers the lens (:meth:`_close`). docs/render.md. Use as a context manager, or call
    :meth:`close`.
    """

    def __init__(self, scene: Scene, cameras=None, lighting: Lighting = DEFAULT_LIGHTING):
        if not scene.is_calibrated:
            raise ValueError(f"scene: {scene.name!r} has floor-plane cameras only; rendering needs "
                             "calibrated cameras (K, distortion, R, t)")
        self.scene = scene
        by_number = {c.number: c for c in scene.cameras}
        self.numbers = check_camera_numbers("cameras", cameras, sorted(by_number))
        self.cameras = tuple(by_number[n] for n in self.numbers)
        sizes = {(c.width, c.height) for c in self.cameras}
        if len(sizes) != 1:
            raise ValueError(f"cameras: expected one image size for all rendered cameras, got {sorted(sizes)}")
        self.width, self.height = sizes.pop()
        self.maps, self.map_index = _maps(self.cameras)
        cw = max(m.canvas_size[0] for m in self.maps)
        ch = max(m.canvas_size[1] for m in self.maps)
        self.zfar = far_plane(scene)                # metres
        self.view_projs = np.stack([
            projection_matrix(m.canvas_K(c.K), cw, ch, ZNEAR, self.zfar, flip_rows=True) @ view_matrix(c.R, c.t)
            for c, m in zip(self.cameras, (self.maps[i] for i in self.map_index))])
        self.canvas_size = (cw, ch)
        people = scene.people
        people_m = people_mesh(people, lighting)
        soles = soles_mesh(people, lighting)                 # last: drawn only for cameras close to someone
        mesh = Mesh.concatenate([room_mesh(scene.room, lighting), people_m, soles])
        self.raster = Rasteriser(mesh, people.count, cw, ch, len(self.cameras), scene.render.backend,
                                 near_only=len(soles.positions))
        self.backend = self.raster.backend
        # for the regions people can touch: each person's vertices (at the origin) and
        # each camera's ideal canvas projection (OpenCV convention, pixel centres integer)
        pts = [np.unique(people_m.positions[people_m.person == p], axis=0).astype(float)
               for p in range(people.count)]
        m_max = max((len(p) for p in pts), default=1)
        self._people_pts = np.stack([np.concatenate([p, np.repeat(p[:1], m_max - len(p), 0)]) for p in pts]) \
            if pts else np.zeros((0, 1, 3))                            # (people, m, 3), padded
        cam_maps = [self.maps[i] for i in self.map_index]
        self._block_lo = np.stack([m.block_lo for m in cam_maps])
        self._block_hi = np.stack([m.block_hi for m in cam_maps])
        self._Kc = np.stack([m.canvas_K(c.K) for c, m in
                             zip(self.cameras, (self.maps[i] for i in self.map_index))])
        self._R = np.stack([np.asarray(c.R, float) for c in self.cameras])
        self._t = np.stack([np.asarray(c.t, float).reshape(3) for c in self.cameras])
        self._centre = np.stack([np.asarray(c.center_world, float) for c in self.cameras])
        # how far from the lens the near plane reaches inside the canvas frustum, metres
        corners = np.array([[-0.5, -0.5], [cw - 0.5, -0.5], [-0.5, ch - 0.5], [cw - 0.5, ch - 0.5]])
        rays = (corners[None] - self._Kc[:, None, :2, 2]) / self._Kc[:, None, [0, 1], [0, 1]]
        self._reach = ZNEAR * np.sqrt(1.0 + (rays**2).sum(axis=-1)).max(axis=1)      # (n_cams,)
        self._rgba = np.empty((self.height, self.width, 4), np.uint8)   # scratch
        self._alpha = np.zeros((ch, cw), np.uint8)                      # idem, kept all 0
        self._pool = None
        self._background = None
        self._canvas = self._work = None            # (n_cams, ch, cw, 4), with the background

    # -- context manager -------------------------------------------------------------
    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Free the GL objects (the process's shared GL context stays alive)."""
        self.raster.close()

    # -- rendering -------------------------------------------------------------------
    def _indices(self, cameras) -> np.ndarray:
        numbers = check_camera_numbers("cameras", cameras, self.numbers)
        return np.array([self.numbers.index(n) for n in numbers])

    def render(self, positions_xy, cameras=None, rng: np.random.Generator | None = None,
               clean: bool = False) -> Frames:
        """Frames of the people standing at ``positions_xy``.

        positions_xy : (count, 2) float, metres, world frame, one row per person of the
            scene (a row of NaN hides that person)
        cameras : 1-based camera numbers (default: all prepared cameras)
        rng : draws the per-camera gain and the sensor noise; required unless ``clean``
        clean : no gain and no noise (the ideal distorted image)
        """
        if not clean and rng is None:
            raise ValueError("rng: expected an np.random.Generator (or clean=True for noise-free frames)")
        idx = self._indices(cameras)
        rgb, labels = self._render(positions_xy, idx, rng, clean, colour=True)
        return Frames(rgb, labels, tuple(self.numbers[i] for i in idx))

    def labels(self, positions_xy, cameras=None) -> np.ndarray:
        """Label images only: ``render(positions_xy, cameras, clean=True).labels``, bit for bit,
        without the colour work (no RGB remap or copy).

        Returns (n_cams, H, W) uint8, 0 background, person index + 1 elsewhere.
        """
        return self._render(positions_xy, self._indices(cameras), None, True, colour=False)[1]

    def _render(self, positions_xy, idx: np.ndarray, rng, clean: bool, colour: bool):
        """(rgb (n, H, W, 3) uint8 or None without ``colour``, labels (n, H, W) uint8) of cameras ``idx``."""
        count = self.scene.people.count
        pos = np.asarray(positions_xy, float) if count else np.zeros((0, 2))
        if pos.shape != (count, 2):
            raise ValueError(f"positions_xy: expected shape ({count}, 2), got {np.shape(positions_xy)}")
        background = self._background_frames()
        n, H, W = len(idx), self.height, self.width
        s = self.scene.render
        gains = offsets = None
        pool = None
        if not clean:
            gains, offsets = draw_gains_offsets(n, s.gain_jitter, rng)
            if s.noise_std > 0:
                pool = self._noise_pool()
        close = self._close(idx, pos)
        rects = self._rects(idx, pos, close)
        regions = regions_of(self._block_lo[idx], self._block_hi[idx], rects, (H, W))
        rgb = np.empty((n, H, W, 3), np.uint8) if colour else None
        labels = np.zeros((n, H, W), np.uint8)

        boxes = [_boxes(r, self.canvas_size) for r in rects]
        work = self._work
        try:
            self._draw_people(idx, pos, boxes, close.any(axis=1))
            for k, i in enumerate(idx):
                noise = None if pool is None else pool[offsets[k]:offsets[k] + H * W * 3].reshape(H, W * 3)
                self._finish(int(i), work[i], boxes[k], regions[k], background.rgb[i],
                             None if rgb is None else rgb[k], labels[k], None if clean else gains[k], noise)
        finally:                                    # the work canvases are the room again
            for k, i in enumerate(idx):
                for x0, y0, x1, y1 in boxes[k]:
                    work[i, y0:y1, x0:x1] = self._canvas[i, y0:y1, x0:x1]
        return rgb, labels

    def _draw_people(self, idx: np.ndarray, pos: np.ndarray, boxes: list, near=None) -> None:
        """Draw the people over the room inside their canvas ``boxes``, into ``self._work``.

        boxes : per camera, the integer slice bounds (x0, y0, x1, y1), end exclusive, of
            each visible person's canvas box (:func:`_boxes` of :meth:`_rects`)
        Afterwards ``self._work[i]`` is camera ``i = idx[k]``'s whole-scene canvas: the
        cached room canvas outside ``boxes[k]``, inside the people drawn over the room's
        own colour and depth (:meth:`Rasteriser.draw_people`), bit for bit what a
        whole-scene draw gives. The caller restores the boxes from ``self._canvas``.
        near : (n,) bool, the cameras a person comes close to (:meth:`_close`): their
            people are drawn with back faces, unclipped by the near plane
        """
        self.raster.draw_people(self.view_projs[idx], pos, idx, boxes, self._work, near)

    def _finish(self, i: int, canvas: np.ndarray, boxes: list, regions: list, background: np.ndarray,
                rgb: np.ndarray | None, labels: np.ndarray, gain: float | None,
                noise: np.ndarray | None) -> None:
        """Camera ``i``'s distorted frame and labels from its canvas, into ``rgb`` and ``labels``.

        Outside the regions the people can reach the frame is the cached background, bit
        for bit (same draw, same band); inside, the canvas is remapped. Then the gain and
        the noise (``gain`` None: clean) over the whole frame, in one pass. ``rgb`` None:
        the labels only.
        """
        m = self.maps[self.map_index[i]]
        H, W = self.height, self.width
        if rgb is not None:
            np.copyto(rgb, background)
        if regions:
            scratch, alpha = self._rgba, self._alpha
            for x0, y0, x1, y1 in boxes:            # the labels; 0 outside the boxes
                cv2.extractChannel(canvas[y0:y1, x0:x1], 3, dst=alpha[y0:y1, x0:x1])
            for r0, r1, c0, c1 in regions:
                if rgb is not None:
                    rgba = scratch[:r1 - r0, :c1 - c0]
                    distort_region(canvas, m, (r0, r1, c0, c1), rgba)
                    cv2.cvtColor(rgba, cv2.COLOR_RGBA2RGB, dst=rgb[r0:r1, c0:c1])
                distort_region(alpha, m, (r0, r1, c0, c1), labels[r0:r1, c0:c1], nearest=True)
            for x0, y0, x1, y1 in boxes:
                alpha[y0:y1, x0:x1] = 0             # outside the boxes the canvas alpha is 0
        if gain is not None:
            flat = rgb.reshape(H, W * 3)
            sense(flat, flat, gain, noise)

    def _noise_pool(self) -> np.ndarray:
        if self._pool is None:
            self._pool = noise_pool(float(self.scene.render.noise_std), self.height * self.width * 3)
        return self._pool

    def _close(self, idx: np.ndarray, pos: np.ndarray) -> np.ndarray:
        """(n, people) bool: the person's cylinder comes within the near plane's reach of
        camera ``idx[k]``'s lens, or holds it.

        Only then can the near plane cut the person inside the view, or the camera face
        the person's back faces alone: such a camera's people are drawn with their back
        faces and clamped, not clipped, at the near plane (:meth:`Rasteriser._draw_range`).
        The reach is the distance from the lens to the near plane's farthest corner
        (~6 cm for the lab); the mesh lies inside the cylinder, so the test is safe.
        """
        people = self.scene.people
        c = self._centre[idx][:, None]                                  # (n, 1, 3)
        with np.errstate(invalid="ignore"):
            side = np.maximum(np.linalg.norm(c[..., :2] - pos[None], axis=-1) - people.radius, 0.0)
            up = np.maximum(np.maximum(-c[..., 2], c[..., 2] - people.height), 0.0)
            return np.hypot(side, up) < self._reach[idx][:, None]            # NaN (hidden): False

    def _rects(self, idx: np.ndarray, pos: np.ndarray, close: np.ndarray | None = None) -> np.ndarray:
        """(n, people, 4) canvas boxes (x0, y0, x1, y1) holding every pixel each person covers.

        Each person's vertices are projected on the ideal canvas (exact pinhole, the
        matrices the rasteriser uses, OpenCV pixel convention); the pixels a person
        covers lie inside the box of its projected vertices, widened by 2 px for
        rasterisation. A person straddling the near plane, or ``close`` to the camera
        (:meth:`_close`, computed when None), gets the whole canvas; hidden, wholly behind
        the near plane or off the canvas: a NaN row. A side on the canvas edge extends to
        infinity.
        """
        cw, ch = self.canvas_size
        n, P = len(idx), len(self._people_pts)
        rects = np.full((n, P, 4), np.nan)
        shown = np.isfinite(pos).all(axis=1)
        if not shown.any():
            return rects
        world = self._people_pts[shown] + np.column_stack([pos[shown], np.zeros(shown.sum())])[:, None, :]
        p, m = world.shape[:2]
        cam = self._R[idx] @ world.reshape(-1, 3).T + self._t[idx][:, :, None]     # (n, 3, p * m)
        uvw = (self._Kc[idx] @ cam).reshape(n, 3, p, m)
        z = cam[:, 2].reshape(n, p, m)
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = np.moveaxis(uvw[:, :2] / z[:, None], 1, -1)                      # (n, p, m, 2)
        lo = np.floor(uv.min(axis=2)) - 2
        hi = np.ceil(uv.max(axis=2)) + 2
        box = np.concatenate([lo, hi], axis=-1)                      # (n, shown, 4)
        box[..., :2] = np.where(box[..., :2] <= 0, -np.inf, box[..., :2])
        box[..., 2:] = np.where(box[..., 2:] >= np.array([cw - 1, ch - 1]), np.inf, box[..., 2:])
        off = (hi[..., 0] < 0) | (hi[..., 1] < 0) | (lo[..., 0] > cw - 1) | (lo[..., 1] > ch - 1)
        front = (z > 1.001 * ZNEAR).all(axis=2)
        behind = (z < 0.999 * ZNEAR).all(axis=2)
        box[~front] = [-np.inf, -np.inf, np.inf, np.inf]              # straddles the near plane
        box[behind | (front & off)] = np.nan
        close = self._close(idx, pos) if close is None else close
        box[close[:, shown]] = [-np.inf, -np.inf, np.inf, np.inf]   # drawn unclipped
        rects[:, shown] = box
        return rects

    def _background_frames(self) -> Frames:
        """The empty room for every prepared camera, clean; drawn and distorted once."""
        if self._background is None:
            hidden = np.full((self.scene.people.count, 2), np.nan)
            all_idx = np.arange(len(self.numbers))
            canvases = self.raster.draw(self.view_projs, hidden, bands=all_idx)
            self.raster.store_room()                # the room's colour and depth, in GL
            self._canvas = canvases.copy()          # the room's ideal canvases (read-only)
            self._canvas.flags.writeable = False
            self._work = canvases.copy()            # the canvases render() draws people into
            rgb, labels = self._distort(canvases, all_idx)
            self._background = Frames(rgb, labels, self.numbers)
        return self._background

    def background(self, cameras=None) -> Frames:
        """The empty room, clean (no gain, no noise), distorted; labels are all 0.

        This is what a background model converges to; add noise with
        :func:`render.noise.degrade` for a noisy empty frame.
        """
        bg = self._background_frames()
        idx = self._indices(cameras)
        return Frames(bg.rgb[idx].copy(), bg.labels[idx].copy(), tuple(self.numbers[i] for i in idx))

    def _distort(self, canvases: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distorted RGB (n, H, W, 3) and labels (n, H, W) from RGBA canvases (n, Hc, Wc, 4).

        The whole-image path: used for the cached background, and by the tests as the
        reference the per-region production path must match bit for bit.
        """
        n, H, W = len(idx), self.height, self.width
        rgb = np.empty((n, H, W, 3), np.uint8)
        labels = np.empty((n, H, W), np.uint8)
        rgba = np.empty((H, W, 4), np.uint8)
        alpha = np.empty(canvases.shape[1:3], np.uint8)
        for k, i in enumerate(idx):
            m = self.maps[self.map_index[i]]
            distort(canvases[k], m, out=rgba)
            cv2.cvtColor(rgba, cv2.COLOR_RGBA2RGB, dst=rgb[k])
            cv2.extractChannel(canvases[k], 3, dst=alpha)
            distort(alpha, m, out=labels[k], nearest=True)
        return rgb, labels


def _boxes(rects, canvas_size) -> list[tuple[int, int, int, int]]:
    """Integer canvas slice bounds (x0, y0, x1, y1), end exclusive, of each non-NaN rect.

    rects : (k, 4) float, inclusive bounds, +-inf beyond the canvas edges, NaN rows: none
    """
    cw, ch = canvas_size
    r = rects[~np.isnan(rects).any(axis=1)]
    lo = np.clip(r[:, :2], 0, [cw, ch])
    hi = np.clip(r[:, 2:] + 1, 0, [cw, ch])
    return [(int(a), int(b), int(c), int(d)) for (a, b), (c, d) in zip(lo, hi) if c > a and d > b]


def _maps(cameras) -> tuple[list[DistortionMaps], np.ndarray]:
    """Distortion maps, one per distinct intrinsics, and each camera's map index."""
    keys, maps, index = {}, [], []
    for c in cameras:
        key = (c.K.tobytes(), c.dist.tobytes(), c.width, c.height)
        if key not in keys:
            keys[key] = len(maps)
            maps.append(distortion_maps(c.K, c.dist, c.width, c.height))
        index.append(keys[key])
    return maps, np.array(index)
