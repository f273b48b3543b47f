"""Lens-distortion correction and rectification to a level virtual camera (step 4).

The lab cameras are pitched down, so columns of the raw image are not vertical planes.
Each mask is remapped, in one pass with precomputed maps, to a *level* virtual camera at
the same centre and yaw (``cv2.initUndistortRectifyMap`` with the rotation from the real
camera frame to the virtual one). The virtual camera's y axis is the world's down, so
every output column is a vertical plane through the camera centre with an exact
world-frame bearing (:func:`column_bearings`).

Its horizontal field of view is the band of columns that the real image covers *from
its top edge to its bottom edge*: the raw image's side edges are curved and slanted in
the level view (lens distortion and pitch), and a column that the raw image covers only
at some heights must not be sent as empty where it saw nothing; it is left out of the
field of view instead, where tasking treats the room as unconstrained. For the lab
cameras this band is 49.1 degrees wide. Pixels are square, and the output height covers
the real image vertically.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from scene.camera import Camera, distort_normalised, rotation_from_yaw_pitch, undistort_points


def level_rotation(camera: Camera) -> np.ndarray:
    """Rotation (3, 3) from the real camera frame to the level virtual camera frame.

    ``X_virtual = R_rect @ X_camera``; the virtual camera looks along ``camera.yaw`` with
    no pitch or roll (OpenCV axes: x right, y down = world -z, z forward, horizontal).
    """
    return rotation_from_yaw_pitch(camera.yaw, 0.0) @ camera.R.T


def _border_points(width: int, height: int, per_side: int = 64) -> np.ndarray:
    """(m, 2) float (u, v) points along the outer edges of the image's pixels."""
    us = np.linspace(-0.5, width - 0.5, per_side)
    vs = np.linspace(-0.5, height - 0.5, per_side)
    return np.concatenate([
        np.stack([us, np.full_like(us, -0.5)], 1), np.stack([us, np.full_like(us, height - 0.5)], 1),
        np.stack([np.full_like(vs, -0.5), vs], 1), np.stack([np.full_like(vs, width - 0.5), vs], 1),
    ])


def virtual_extent(camera: Camera) -> tuple[float, float, float, float]:
    """Extent of the real image on the virtual camera's z = 1 plane: (xmin, xmax, ymin, ymax).

    x: the columns covered over the whole height of the raw image (between its left and
    right edges at every row); y: the full vertical extent of the raw image.
    """
    per_side = 1024                 # 64 missed an extreme mid-edge by 0.1 px under strong distortion
    x, y = level_points(camera, _border_points(camera.width, camera.height, per_side))
    left, right = x[2 * per_side:3 * per_side], x[3 * per_side:]
    if right.min() <= left.max():
        u, v = camera.K[0, 2], camera.K[1, 2]
        cu, cv = (camera.width - 1) / 2, (camera.height - 1) / 2
        if abs(u - cu) > camera.width / 4 or abs(v - cv) > camera.height / 4:
            why = f"its principal point {u:g}, {v:g} is far from the image's centre {cu:g}, {cv:g}"
        else:                       # a centred lens: its distortion bends the side edges across
            why = f"its lens distortion {np.round(camera.dist, 4).tolist()} bends the image's sides too far"
        raise ValueError(f"camera {camera.number}: once turned level, no column of its image spans the image's whole "
                         f"height ({why}); it cannot be rectified to a level camera")
    return float(left.max()), float(right.min()), float(y.min()), float(y.max())


def level_points(camera: Camera, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Raw image points (m, 2) float (u, v) pixels -> their (x, y) on the level virtual
    camera's z = 1 plane (lens distortion removed, pitch turned level); (m,) each."""
    norm = undistort_points(uv, camera.K, camera.dist, eps=1e-10)
    rays = np.concatenate([norm, np.ones((len(norm), 1))], 1) @ level_rotation(camera).T
    if not np.all(rays[:, 2] > 0.05):               # NaN (undistortion failed) too
        raise ValueError(f"camera {camera.number}: field of view too wide, or pitch too steep, to rectify to a level "
                         "camera (every pixel must look less than 87 degrees from the level forward direction: "
                         "check its pitch_deg, hfov_deg and distortion)")
    return rays[:, 0] / rays[:, 2], rays[:, 1] / rays[:, 2]


#: How far (pixels) a pixel may land from itself when undistorted and distorted again
#: (:func:`scene.camera.undistort_points` takes every pixel that has a ray to within 1e-9 px).
ROUND_TRIP = 1e-3


def check_lens(camera: Camera, samples: int = 65) -> None:
    """Raise a one-line ValueError unless ``camera``'s lens distortion maps the rays it
    sees one to one onto its image: every pixel (a grid of ``samples`` x ``samples``, the
    edges included) undistorts to a ray that distorts back to it (within ``ROUND_TRIP``
    pixels), the distortion keeps its orientation (a positive Jacobian determinant) at those
    rays and at every ray of a fine grid out to the farthest of them that lands on the
    image, and the radial factor ``r (1 + k1 r^2 + k2 r^4 + k3 r^6)`` grows out to that
    farthest ray. Coefficients that fold over inside the image (``k1 = -0.6`` on the lab's
    49-degree lens) would render rays twice (a "glass ball") and rectify nonsense."""
    u = np.linspace(-0.5, camera.width - 0.5, samples)
    v = np.linspace(-0.5, camera.height - 0.5, samples)
    pts = np.stack(np.meshgrid(u, v), -1).reshape(-1, 2)
    norm = undistort_points(pts, camera.K, camera.dist, eps=1e-10)
    how = None
    if not np.all(np.isfinite(norm)):
        how = "some of its pixels cannot be undistorted"
    else:
        back = cv2.projectPoints(np.column_stack([norm, np.ones(len(norm))]), np.zeros(3), np.zeros(3), camera.K,
                                 camera.dist)[0].reshape(-1, 2)
        with np.errstate(over="ignore", invalid="ignore"):
            miss = float(np.abs(back - pts).max())
            reach = 1.01 * float(np.hypot(norm[:, 0], norm[:, 1]).max())
            turned = _mirrored(norm, camera.dist) or _mirrored(_ray_grid(reach), camera.dist, camera)
            k1, k2, _, _, k3 = np.asarray(camera.dist, float).ravel()[:5]
            r = np.linspace(0.0, reach, 2001)
            slope = 1 + 3 * k1 * r**2 + 5 * k2 * r**4 + 7 * k3 * r**6          # d/dr of the radial factor
        if not miss <= ROUND_TRIP:
            how = f"a pixel undistorted and distorted again lands {miss:.3g} pixels away"
        elif turned:
            how = "it mirrors the rays near some of its pixels"
        elif not slope.min() > 0:
            how = "rays farther out come back nearer the centre"
    if how is not None:
        cx, cy = camera.K[0, 2], camera.K[1, 2]
        off = not (-0.5 <= cx <= camera.width - 0.5 and -0.5 <= cy <= camera.height - 0.5)
        raise ValueError(f"camera {camera.number}: its lens distortion {np.round(camera.dist, 4).tolist()} folds over "
                         f"inside its image ({how}); use smaller distortion coefficients"
                         + (f", or a principal point nearer the image than ({cx:g}, {cy:g})" if off else ""))


def _ray_grid(reach: float, n: int = 257) -> np.ndarray:
    """Rays (m, 2), normalised, of an n x n grid over the disc of radius ``reach``."""
    g = np.linspace(-reach, reach, n)
    xy = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    return xy[np.hypot(xy[:, 0], xy[:, 1]) <= reach]


def _mirrored(rays: np.ndarray, dist, camera: Camera | None = None) -> bool:
    """True if the lens model turns over (Jacobian determinant <= 0) at any of ``rays`` (m, 2)
    (of those that land on ``camera``'s image, when it is given)."""
    d, J = distort_normalised(rays, dist)
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    if camera is not None:
        u = camera.K[0, 0] * d[:, 0] + camera.K[0, 2]
        v = camera.K[1, 1] * d[:, 1] + camera.K[1, 2]
        det = det[(u >= -0.5) & (u <= camera.width - 0.5) & (v >= -0.5) & (v <= camera.height - 0.5)]
    return not np.all(det > 0)


def check_column_threshold(column_threshold: float, cameras, option: str) -> None:
    """Raise a one-line ValueError naming ``option`` when ``column_threshold`` (pixels) is
    not below the rows of the cameras' rectified columns: a column is occupied when its
    count exceeds the threshold, so every scanline would be empty (the :class:`Pipeline`
    itself allows it; ``render`` and ``run`` check it before any work).

    >>> from scene import load_scene
    >>> check_column_threshold(600, load_scene("lab").cameras, "--params")
    Traceback (most recent call last):
    ...
    ValueError: --params: column_threshold 600 is not below the 552 pixels of a rectified column; every scanline would be empty
    """
    rows = level_cameras(cameras)[1]
    if column_threshold >= rows:
        raise ValueError(f"{option}: column_threshold {column_threshold:g} is not below the {rows} pixels of a "
                         "rectified column; every scanline would be empty")


def check_rectifiable(cameras, names=None) -> None:
    """Raise the one-line error of :func:`check_lens` or :func:`virtual_extent` for the first
    camera whose lens folds over or that cannot be rectified to a level camera (before any
    work starts, rather than at the first frame). A lens is checked once for all the cameras
    that share it (the lab's 16: 0.06 -> 0.03 s; one call per camera took 0.24 s).

    names : optional, one per camera: what its error starts with (``"DIR: calibration/cam03.yaml"``)
    """
    lenses = set()
    for i, camera in enumerate(cameras):
        try:
            lens = (camera.K.tobytes(), camera.dist.tobytes(), camera.width, camera.height)
            if lens not in lenses:
                check_lens(camera)
                lenses.add(lens)
            virtual_extent(camera)
        except ValueError as exc:
            if names is None:
                raise
            raise ValueError(f"{names[i]}: {exc}") from None


def virtual_camera_matrix(camera: Camera, width: int | None = None) -> tuple[np.ndarray, int]:
    """Camera matrix (3, 3) of the level virtual camera and the output height it needs.

    width : output width, pixels (default the camera's). Columns 0 and width - 1 are the
    left and right limits of the band covered over the raw image's whole height (see
    :func:`virtual_extent`); pixels are square.
    """
    width = camera.width if width is None else int(width)
    xmin, xmax, ymin, ymax = virtual_extent(camera)
    f = (width - 1) / (xmax - xmin)
    K = np.array([[f, 0.0, -xmin * f], [0.0, f, -ymin * f], [0.0, 0.0, 1.0]])
    return K, int(np.ceil((ymax - ymin) * f)) + 1


def column_bearings(camera: Camera, K_virtual: np.ndarray, width: int) -> np.ndarray:
    """World-frame bearing of each output column's vertical plane through the camera centre.

    Returns (width,) float, radians in (-pi, pi], ``atan2(dy, dx)`` of the floor-plane
    direction; it decreases from left to right (x is to the camera's right).
    """
    x = (np.arange(width) - K_virtual[0, 2]) / K_virtual[0, 0]
    rays_virtual = np.stack([x, np.zeros_like(x), np.ones_like(x)], 1)
    d_world = rays_virtual @ rotation_from_yaw_pitch(camera.yaw, 0.0)   # R_v.T @ ray, batched
    return np.arctan2(d_world[:, 1], d_world[:, 0])


def rectify_maps(camera: Camera, K_virtual: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Float maps (out_h, out_w) float32 x (col) and y (row) into the raw image, size = (w, h)
    of the output; entries on the raw image's outer edge on its edge pixels (:func:`onto_edge_pixels`)."""
    x, y = cv2.initUndistortRectifyMap(camera.K, camera.dist, level_rotation(camera), K_virtual,
                                       size, cv2.CV_32FC1)
    return onto_edge_pixels(x, y, (camera.width, camera.height))


def level_cameras(cameras, width: int | None = None) -> tuple[np.ndarray, int, int]:
    """The level virtual cameras of a rig: (K_virtual (n_cams, 3, 3), out_height, width).

    width : output width, pixels (default the cameras'); out_height covers every camera's
    raw image (:func:`virtual_camera_matrix`). The cameras must share one resolution.
    """
    cameras = tuple(cameras)
    if not cameras:
        raise ValueError("cameras: expected at least one calibrated camera")
    h, w = cameras[0].height, cameras[0].width
    if any((c.height, c.width) != (h, w) for c in cameras):
        raise ValueError("cameras: expected every camera to have the same resolution")
    width = w if width is None else int(width)
    Ks, heights = zip(*(virtual_camera_matrix(c, width) for c in cameras))
    return np.stack(Ks), max(heights), width


def float_maps(cameras, width: int | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per camera the float maps (x, y), each (out_height, width) float32, of its remap to
    the level virtual camera: what :attr:`Rectifier.fixed_map` rounds, for references
    (``cv2.remap`` with float maps). 2 x 1.4 MB per lab camera, which production never keeps.
    """
    cameras = tuple(cameras)
    Ks, out_h, width = level_cameras(cameras, width)
    return [rectify_maps(c, K, (width, out_h)) for c, K in zip(cameras, Ks)]


@dataclass(frozen=True, eq=False)
class Rectifier:
    """Precomputed rectification of a rig: nearest-neighbour remaps with integer maps.

    Input masks are (n_cams, rows, W) uint8, or stacked as (n_cams * rows, W) with camera
    i's rows at ``i * rows`` (rows >= height: any rows past ``height`` are never read);
    output (n_cams, out_height, width) uint8. The maps do not depend on ``rows``, so one
    rectifier serves every stacking (every opening kernel).

    K_virtual : (n_cams, 3, 3) float; bearings : (n_cams, width) float, radians, world frame
    fixed_map : (n_cams, out_height, width, 2) int16, source (column, row) of every output
        pixel in its camera's raw image, (-1, -1) where it falls outside (:func:`nearest_map`)
    height : raw image rows per camera
    column_x : (n_cams, 2, width) int32, min and max source column over each output column
    row_y : (n_cams, 2, out_height) int32, min and max source row (0..height-1) over each
        output row (empty columns and rows: min > max)
    """

    width: int
    out_height: int
    K_virtual: np.ndarray
    bearings: np.ndarray
    fixed_map: np.ndarray
    height: int
    column_x: np.ndarray
    row_y: np.ndarray

    @classmethod
    def build(cls, cameras, width: int | None = None) -> Rectifier:
        cameras = tuple(cameras)
        Ks, out_h, width = level_cameras(cameras, width)
        h, w = cameras[0].height, cameras[0].width
        fixed = np.stack([nearest_map(*rectify_maps(cam, K, (width, out_h)), (w, h))   # float maps dropped
                          for cam, K in zip(cameras, Ks)])
        column_x, row_y = _envelopes(fixed)
        bearings = np.stack([column_bearings(c, K, width) for c, K in zip(cameras, Ks)])
        ro = lambda a: (a.setflags(write=False), a)[1]
        return cls(width, out_h, ro(Ks), ro(bearings), ro(fixed), h, ro(column_x), ro(row_y))

    def remap_stacked(self, stacked: np.ndarray) -> np.ndarray:
        """Remap masks (n_cams, rows, W) or (n_cams * rows, W) uint8 -> (n_cams, out_height, width) uint8.

        Camera i's output is ``cv2.remap`` of its own ``height`` rows with its maps
        (``INTER_NEAREST``, zero outside the raw image), as :class:`pipeline.reference`
        remaps it, bit for bit (tests). Only the output rectangles that can see the
        camera's non-zero pixels are remapped: for each box of :func:`nonzero_boxes`, the
        output columns whose source columns meet it, times the rows whose source rows do
        (``column_x``, ``row_y``); every other output pixel reads a zero or falls outside
        the raw image. Lab, 3 people, 16 cameras: 5.9 ms for whole images, 3.1 ms for
        one box of all non-zero pixels per camera; one box per group of people (about half
        that area) is faster still (docs/performance.md).
        """
        n, ho, w = self.n_cams, self.out_height, self.width
        src = stacked.reshape(n, -1, stacked.shape[-1])
        if src.shape[1] < self.height:
            raise ValueError(f"masks: expected at least {self.height} rows per camera, got {src.shape[1]}")
        out = np.zeros((n, ho, w), np.uint8)
        for i in range(n):
            image = src[i, :self.height]
            for x, y, bw, bh in nonzero_boxes(image):
                cols = np.flatnonzero((self.column_x[i, 1] >= x) & (self.column_x[i, 0] < x + bw))
                rows = np.flatnonzero((self.row_y[i, 1] >= y) & (self.row_y[i, 0] < y + bh))
                if cols.size and rows.size:       # boxes' rectangles may overlap: the same values twice
                    r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
                    cv2.remap(image, self.fixed_map[i, r0:r1, c0:c1], None, cv2.INTER_NEAREST,
                              dst=out[i, r0:r1, c0:c1], borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        return out

    def rectify(self, masks) -> np.ndarray:
        """Rectify masks (n_cams, H, W) bool/uint8 -> (n_cams, out_height, width) bool."""
        m = np.asarray(masks)
        if m.ndim != 3 or m.shape[0] != self.n_cams:
            raise ValueError(f"masks: expected {self.n_cams} cameras of (H, W), got shape {m.shape}")
        return self.remap_stacked((m != 0).view(np.uint8)).astype(bool)

    @property
    def n_cams(self) -> int:
        return self.bearings.shape[0]


#: Zero columns (pixels) that :func:`nonzero_boxes` needs between two groups of non-zero
#: pixels to give them separate boxes (2 to 64 remap about as fast: docs/performance.md).
GAP = 32


def nonzero_boxes(image: np.ndarray, gap: int = GAP) -> list[tuple[int, int, int, int]]:
    """Boxes (x, y, width, height), pixels, that together hold every non-zero pixel of ``image``.

    image : (H, W) uint8; gap : >= 1. One box per run of columns that hold non-zero pixels
    (runs fewer than ``gap`` zero columns apart are one run), as tall as the rows of its
    non-zero pixels; none for an all-zero image. People apart in the image get a box each:
    together far less area than the bounding box of them all.
    """
    occupied = np.flatnonzero(image.max(axis=0))                # numpy's max: ~14x cv2.reduce's here
    if not occupied.size:
        return []
    cuts = np.flatnonzero(np.diff(occupied) > gap)
    starts = [int(occupied[0])] + occupied[cuts + 1].tolist()
    ends = occupied[cuts].tolist() + [int(occupied[-1])]               # inclusive
    boxes = []
    for c0, c1 in zip(starts, ends):
        _, y, _, h = cv2.boundingRect(image[:, c0:c1 + 1])
        boxes.append((c0, y, c1 + 1 - c0, h))
    return boxes


def nearest_map(x: np.ndarray, y: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Integer map (out_h, out_w, 2) int16 of the source pixel nearest each float map entry.

    x, y : (out_h, out_w) float32 source column and row; size = (w, h) of the source.
    Rounded half to even, as ``cv2.remap`` rounds float maps for ``INTER_NEAREST``;
    (-1, -1) where the rounded pixel is outside the source (or not finite).
    """
    w, h = size
    xi, yi = np.rint(x), np.rint(y)
    inside = (xi >= 0) & (xi <= w - 1) & (yi >= 0) & (yi <= h - 1)
    return np.where(inside[..., None], np.stack([xi, yi], -1), -1).astype(np.int16)


def onto_edge_pixels(x: np.ndarray, y: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Map entries on the image's outer edge (within the edge pixels' half pixel, e.g.
    x = w - 0.5) moved onto those pixels' centres: rounding half to even sent x = w - 0.5
    out of the image for an even w, so a level, undistorted camera's last column never
    saw anything. Others unchanged. x, y : float source column and row; size = (w, h)."""
    w, h = size
    x = np.where((x >= -0.5) & (x <= w - 0.5), np.clip(x, 0, w - 1), x).astype(np.float32)
    y = np.where((y >= -0.5) & (y <= h - 0.5), np.clip(y, 0, h - 1), y).astype(np.float32)
    return x, y


def _envelopes(fixed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Source column range of every output column and source row range of every output row.

    fixed : (n_cams, out_height, width, 2) int16 maps of :func:`nearest_map`, -1 outside
    Returns column_x (n_cams, 2, width) and row_y (n_cams, 2, out_height) int32: min, max
    over the output pixels inside the raw image; min > max where there are none.
    """
    x, y = fixed[..., 0].astype(np.int32), fixed[..., 1].astype(np.int32)
    inside = x >= 0
    big = np.int32(1 << 30)
    lo_x, hi_x = np.where(inside, x, big).min(axis=1), np.where(inside, x, -big).max(axis=1)
    lo_y, hi_y = np.where(inside, y, big).min(axis=2), np.where(inside, y, -big).max(axis=2)
    return np.stack([lo_x, hi_x], 1), np.stack([lo_y, hi_y], 1)
