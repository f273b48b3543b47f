"""Lens distortion applied to ideal pinhole renders with ``cv2.remap``.

The renderer draws the ideal pinhole image on a slightly larger canvas (barrel
distortion pulls the corners of the real image from beyond the ideal frame), then
resamples it: for every pixel (u_d, v_d) of the distorted output image the map holds
the ideal pinhole pixel that shows the same ray,
``K_canvas @ undistort(K^-1 (u_d, v_d, 1))`` (without the skew ``K[0, 1]``, which
``cv2.projectPoints`` and the OpenGL projection leave out). That is
``cv2.undistortPoints`` applied to the output pixel grid (an iterative inverse of the
distortion model, polished by Newton steps where it stops short:
:func:`scene.camera.undistort_points`), *not*
``cv2.initUndistortRectifyMap``, whose map goes the other way (for each undistorted
pixel, where it lies in the distorted image). With this map a world point projected
by ``cv2.projectPoints(K, dist)`` lands on its rendered image.

>>> import numpy as np
>>> K = np.array([[500.0, 0, 319.5], [0, 500.0, 239.5], [0, 0, 1]])
>>> d = distortion_maps(K, np.zeros(5), 640, 480)
>>> d.canvas_size, d.offset
((640, 480), (0, 0))
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from scene.camera import undistort_points
from scene.checks import check_array


@dataclass(frozen=True, eq=False)
class DistortionMaps:
    """Per-camera resampling from the ideal canvas to the distorted image.

    canvas_size : (width, height) of the ideal pinhole canvas, pixels
    offset : (du, dv) pixels, where the output image's principal point moved on the
        canvas: ``K_canvas = K`` with ``cx + du``, ``cy + dv``
    map_xy : (H, W, 2) float32, canvas pixel (u, v) for each output pixel (row, col); the
        bilinear map (OpenCV rounds it to 1/32 px internally; measured ~30 % faster than
        its ``cv2.convertMaps`` fixed-point form, with 16 x 640 x 480 RGBA on this machine)
    nearest : the map rounded to whole pixels (CV_16SC2), for label images
    identity : True when there is no distortion (remapping is skipped)
    block_lo, block_hi : (ceil(H / BLOCK), ceil(W / BLOCK), 2) float32, the smallest and
        largest canvas (u, v) of each BLOCK x BLOCK tile of output pixels (for
        :func:`regions_of`)
    """

    canvas_size: tuple[int, int]
    offset: tuple[int, int]
    map_xy: np.ndarray
    nearest: np.ndarray | None
    identity: bool
    block_lo: np.ndarray = None
    block_hi: np.ndarray = None

    def canvas_K(self, K) -> np.ndarray:
        """The ideal canvas's camera matrix, (3, 3) pixels, without the skew ``K[0, 1]``
        (which ``cv2.projectPoints`` and the OpenGL projection leave out)."""
        Kc = np.array(K, float)
        Kc[0, 1] = 0.0
        Kc[0, 2] += self.offset[0]
        Kc[1, 2] += self.offset[1]
        return Kc


def ideal_pixels(K, dist, width: int, height: int) -> np.ndarray:
    """Ideal (undistorted) pixel (u, v) of every distorted pixel, (H, W, 2) float64."""
    K = check_array("K", K, (3, 3))
    dist = check_array("dist", dist, (5,))
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    xy = undistort_points(np.stack([u.ravel(), v.ravel()], axis=1), K, dist)
    # without the skew K[0, 1], which cv2.projectPoints and the OpenGL projection leave out
    # (cv2.undistortPoints(P=K) would add it)
    ideal = xy * [K[0, 0], K[1, 1]] + K[:2, 2]
    return ideal.reshape(height, width, 2)


#: Output tile size (pixels) of the coarse map bounds used to find affected regions.
BLOCK = 16


def _block_bounds(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rows = np.arange(0, xy.shape[0], BLOCK)
    cols = np.arange(0, xy.shape[1], BLOCK)
    lo = np.minimum.reduceat(np.minimum.reduceat(xy, rows, axis=0), cols, axis=1)
    hi = np.maximum.reduceat(np.maximum.reduceat(xy, rows, axis=0), cols, axis=1)
    return lo, hi


def distortion_maps(K, dist, width: int, height: int, margin: int = 2) -> DistortionMaps:
    """Maps that turn an ideal canvas render into the distorted ``width`` x ``height`` image."""
    dist = check_array("dist", dist, (5,))
    if not np.any(dist):
        v, u = np.mgrid[0:height, 0:width].astype(np.float32)
        xy = np.stack([u, v], axis=-1)
        return DistortionMaps((width, height), (0, 0), xy, None, True, *_block_bounds(xy))
    ideal = ideal_pixels(K, dist, width, height)
    lo = np.floor(ideal.reshape(-1, 2).min(axis=0)) - margin
    hi = np.ceil(ideal.reshape(-1, 2).max(axis=0)) + margin
    du = int(max(0, -lo[0]))
    dv = int(max(0, -lo[1]))
    canvas = (int(max(width, hi[0] + 1)) + du, int(max(height, hi[1] + 1)) + dv)
    xy = (ideal + np.array([du, dv])).astype(np.float32)
    nearest = cv2.convertMaps(xy[..., 0], xy[..., 1], cv2.CV_16SC2, nninterpolation=True)[0]
    return DistortionMaps(canvas, (du, dv), xy, nearest, False, *_block_bounds(xy))


def regions_of(block_lo: np.ndarray, block_hi: np.ndarray, rects: np.ndarray,
               size: tuple[int, int]) -> list[list[tuple[int, int, int, int]]]:
    """Output regions that can change when each camera's canvas changes inside its ``rects``.

    block_lo, block_hi : (n, nby, nbx, 2) each camera's map bounds per tile
        (:attr:`DistortionMaps.block_lo`, ``block_hi``)
    rects : (n, k, 4) float, canvas pixel bounds (x0, y0, x1, y1) per camera, inclusive;
        +-inf for "beyond the canvas edge", NaN rows: none
    size : (H, W) of the output images
    Returns per camera one ``(r0, r1, c0, c1)`` output slice per rect that touches the
    image (none for the others): every output pixel whose bilinear (or nearest) source
    pixels meet the rect lies inside. Conservative: whole BLOCK x BLOCK tiles.
    """
    H, W = size
    if not rects.shape[1]:
        return [[] for _ in range(len(rects))]
    # bilinear reads canvas pixels floor(m) and floor(m) + 1: affected iff x0 - 1 <= m < x1 + 1;
    # fixed-point maps are rounded to 1/32 px, so allow half a pixel more
    x0, y0, x1, y1 = (rects[:, :, i, None, None] for i in range(4))
    lo, hi = block_lo[:, None], block_hi[:, None]
    with np.errstate(invalid="ignore"):
        hit = ((hi[..., 0] >= x0 - 1.5) & (lo[..., 0] <= x1 + 1.5)
               & (hi[..., 1] >= y0 - 1.5) & (lo[..., 1] <= y1 + 1.5))
    rows, cols = hit.any(axis=3), hit.any(axis=2)               # (n, k, nby), (n, k, nbx)
    r_first, r_last = rows.argmax(axis=2), rows.shape[2] - 1 - rows[..., ::-1].argmax(axis=2)
    c_first, c_last = cols.argmax(axis=2), cols.shape[2] - 1 - cols[..., ::-1].argmax(axis=2)
    valid = rows.any(axis=2)
    out = [[] for _ in range(len(rects))]
    for k, j in zip(*np.nonzero(valid)):
        out[k].append((int(r_first[k, j]) * BLOCK, min(H, (int(r_last[k, j]) + 1) * BLOCK),
                       int(c_first[k, j]) * BLOCK, min(W, (int(c_last[k, j]) + 1) * BLOCK)))
    return out


def distort_region(canvas: np.ndarray, maps: DistortionMaps, region, out: np.ndarray,
                   nearest: bool = False) -> np.ndarray:
    """:func:`distort` of output pixels ``region = (r0, r1, c0, c1)`` only, into ``out``.

    Bit-identical to the same pixels of the whole-image :func:`distort` (each output
    pixel depends only on its own map entry).
    """
    r0, r1, c0, c1 = region
    if maps.identity:
        out[...] = canvas[r0:r1, c0:c1]
        return out
    if nearest:
        return cv2.remap(canvas, maps.nearest[r0:r1, c0:c1], None, cv2.INTER_NEAREST, dst=out,
                         borderMode=cv2.BORDER_REPLICATE)
    return cv2.remap(canvas, maps.map_xy[r0:r1, c0:c1], None, cv2.INTER_LINEAR, dst=out,
                     borderMode=cv2.BORDER_REPLICATE)


def distort(canvas: np.ndarray, maps: DistortionMaps, out: np.ndarray | None = None,
            nearest: bool = False) -> np.ndarray:
    """Resample one ideal ``canvas`` (Hc, Wc[, C]) to the distorted image (H, W[, C]).

    Bilinear for colour; ``nearest`` for label images (no blended labels).
    """
    H, W = maps.map_xy.shape[:2]
    if maps.identity:
        view = canvas[:H, :W]
        if out is None:
            return view.copy()
        out[...] = view
        return out
    if nearest:
        return cv2.remap(canvas, maps.nearest, None, cv2.INTER_NEAREST, dst=out,
                         borderMode=cv2.BORDER_REPLICATE)
    return cv2.remap(canvas, maps.map_xy, None, cv2.INTER_LINEAR, dst=out, borderMode=cv2.BORDER_REPLICATE)
