"""What the cameras see: shaded RGB frames, exact label images, lens distortion, noise.

Usage (not run as a doctest: it needs OpenGL)::

    with Renderer(load_scene("lab")) as r:
        frames = r.render(np.array([[2.0, 2.0], [4.0, 3.0], [3.0, 4.5]]),
                          rng=np.random.default_rng(0))
        frames.rgb.shape, frames.labels.shape   # (16, 480, 640, 3), (16, 480, 640)
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from scene.config import Scene

from .distortion import DistortionMaps, distort, distortion_maps
from .geometry import Lighting, Mesh, people_mesh, room_mesh
from .noise import degrade, noise_table
from .pose import projection_matrix, view_matrix
from .raster import Rasteriser

#: Clipping planes of the OpenGL cameras, metres.
ZNEAR, ZFAR = 0.05, 50.0


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


def check_camera_numbers(name: str, numbers, available) -> tuple[int, ...]:
    """Return ``numbers`` as a tuple of camera numbers that exist in ``available``."""
    available = tuple(available)
    if numbers is None:
        return available
    try:
        numbers = tuple(int(n) for n in numbers)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected camera numbers, got {numbers!r}") from None
    bad = [n for n in numbers if n not in available]
    if bad or not numbers or len(set(numbers)) != len(numbers):
        raise ValueError(f"{name}: expected distinct camera numbers among {available[0]}..{available[-1]}, "
                         f"got {list(numbers)}")
    return numbers


class Renderer:
    """Renders a calibrated scene for a set of cameras; reuse it across frames.

    scene : a :class:`scene.Scene` whose cameras are calibrated (``scene.is_calibrated``)
    cameras : 1-based camera numbers to prepare (default: all)
    lighting : the light baked into the vertex colours

    One OpenGL pass draws every camera's ideal pinhole image (RGB and labels together)
    on a canvas slightly larger than the image (labels in the alpha channel);
    ``cv2.remap`` applies each camera's lens distortion (bilinear for RGB, nearest for
    labels); :func:`render.noise.degrade` adds the per-frame gain and the sensor noise.
    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, scene: Scene, cameras=None, lighting: Lighting = Lighting()):
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
        self.view_projs = np.stack([
            projection_matrix(m.canvas_K(c.K), cw, ch, ZNEAR, ZFAR, flip_rows=True) @ view_matrix(c.R, c.t)
            for c, m in zip(self.cameras, (self.maps[i] for i in self.map_index))])
        people = scene.people
        mesh = Mesh.concatenate([room_mesh(scene.room, lighting), people_mesh(people, lighting)])
        self.raster = Rasteriser(mesh, people.count, cw, ch, len(self.cameras), scene.render.backend)
        self.backend = self.raster.backend
        self._table = noise_table(scene.render.noise_std)
        self._background = None

    # -- context manager -------------------------------------------------------------
    def __enter__(self) -> Renderer:
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
        count = self.scene.people.count
        pos = np.asarray(positions_xy, float).reshape(-1, 2) if count else np.zeros((0, 2))
        if pos.shape != (count, 2):
            raise ValueError(f"positions_xy: expected shape ({count}, 2), got {np.shape(positions_xy)}")
        if not clean and rng is None:
            raise ValueError("rng: expected an np.random.Generator (or clean=True for noise-free frames)")
        idx = self._indices(cameras)
        canvases = self.raster.draw(self.view_projs[idx], pos)
        rgb, labels = self._distort(canvases, idx)
        if not clean:
            s = self.scene.render
            degrade(rgb, s.noise_std, s.gain_jitter, rng, self._table)
        return Frames(rgb, labels, tuple(self.numbers[i] for i in idx))

    def background(self, cameras=None) -> Frames:
        """The empty room, clean (no gain, no noise), distorted; labels are all 0.

        This is what a background model converges to; add noise with
        :func:`render.noise.degrade` for a noisy empty frame.
        """
        if self._background is None:
            hidden = np.full((self.scene.people.count, 2), np.nan)
            self._background = self.render(hidden, clean=True)
        idx = self._indices(cameras)
        return Frames(self._background.rgb[idx].copy(), self._background.labels[idx].copy(),
                      tuple(self.numbers[i] for i in idx))

    def _distort(self, canvases: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distorted RGB (n, H, W, 3) and labels (n, H, W) from RGBA canvases (n, Hc, Wc, 4)."""
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
