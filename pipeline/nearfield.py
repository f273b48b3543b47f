"""Where a camera can see an object at all: the blind radius and the sight radius.

A camera pitched down does not see the floor at its feet, and one pitched steeply down
(or up) does not see far away. An upright object of height ``h`` standing on the floor at
distance ``d`` from a camera at height ``H`` spans, in the scanline column of its
bearing (a column at ``x`` on the level virtual camera of :mod:`pipeline.rectify`,
``s = sqrt(1 + x^2)``), the virtual image heights ``y`` from ``(H - h) s / d`` (its top)
to ``H s / d`` (its foot); the raw image covers ``y`` from its upper edge ``Yt`` to its
lower edge ``Yb`` in that column (undistorted into the level frame). With ``u = 1 / d``
the rows the object shows there,

    f (min(H s u, Yb) - max((H - h) s u, Yt)) = f min((h s) u, H s u - Yt, Yb - (H - h) s u, Yb - Yt),

are a concave function of ``u``, so the distances at which it shows at least ``margin``
rows form one interval ``[near, far]``, in closed form:

* ``(h s) u >= m``: ``d <= h s / m`` (far away the object is too small),
* ``H s u - Yt >= m``: ``d <= H s / (Yt + m)`` when ``Yt + m > 0`` (its foot above the image),
* ``Yb - (H - h) s u >= m``: ``d >= (H - h) s / (Yb - m)`` for a camera above the object's
  top (its top below the image: the near field); ``d <= (h - H) s / (m - Yb)`` for one
  below it whose lower edge is above the horizon,
* ``Yb - Yt >= m``: a column fewer than ``margin`` rows tall never shows that many (the
  three above can all hold there for a camera pitched down: its upper edge below the horizon),

with ``m = margin / f``. Closer than the **blind radius** (the largest ``near`` over the
columns) or farther than the **sight radius** (the smallest ``far``) the camera can send
"empty" although an object stands there; tasking carves its free wedges only between
the two (:func:`tasking.visual_hull_of_scanlines` with ``near`` and ``far``), so that the
hull keeps every object. A camera that sees no such distance has ``near = inf``.

The object's top is what is seen first from above (the lab's people are cylinders with
a flat top, whose top disc is drawn), and any floor point of it has its own vertical
segment inside it: the rows counted are a lower bound of what its column shows.

**Width.** Far away an object also becomes too narrow: the opening removes a blob
narrower than its kernel, and the spatial and median filters a run of too few columns.
An object ``w`` metres wide (a person's diameter) at floor distance ``d`` spans bearings
``2 asin(w / 2d) >= w / d`` radians; a level virtual camera has at least ``f`` columns
per radian (``1 / (f (1 + x^2))`` radians per column), and the raw image at least
:func:`raw_pixels_per_radian` pixels per radian in any row. So the object shows at least
``columns`` rectified columns and ``raw_columns`` raw pixels per row out to
``d = w f / columns`` and ``d = w g / raw_columns``: the sight radius is the smaller of
these and the one of the rows.
"""

from __future__ import annotations

import numpy as np

from scene.checks import check_positive

from .rectify import level_cameras, level_points

__all__ = ["image_edge", "raw_pixels_per_radian", "sight_range"]

#: Points sampled along the raw image's upper and lower edges.
EDGE_POINTS = 129


def image_edge(camera, K_virtual: np.ndarray, width: int, lower: bool = True) -> np.ndarray:
    """The raw image's lower (or upper) edge on the level virtual camera, per output column.

    Returns (width,) float: the virtual image y (z = 1 plane, y down) of the outer edge of
    the raw image's last (first) row of pixels, at each output column's x. Columns are
    those of :func:`pipeline.rectify.virtual_camera_matrix`, all of which the raw image
    covers from top to bottom.
    """
    us = np.linspace(-0.5, camera.width - 0.5, EDGE_POINTS)
    v = camera.height - 0.5 if lower else -0.5
    x, y = level_points(camera, np.stack([us, np.full_like(us, v)], 1))
    order = np.argsort(x)
    columns = (np.arange(width) - K_virtual[0, 2]) / K_virtual[0, 0]
    return np.interp(columns, x[order], y[order])


def raw_pixels_per_radian(camera, rows: int = 33) -> float:
    """The fewest raw-image pixels per radian of bearing along any row of ``camera``'s
    image (lens distortion squeezes the periphery), from the level virtual camera's
    bearing ``atan(x)`` at pixel edges on ``rows`` rows from top to bottom."""
    us = np.arange(camera.width + 1) - 0.5
    vs = np.linspace(0.0, camera.height - 1.0, rows)
    uu, vv = np.meshgrid(us, vs)
    x, _ = level_points(camera, np.stack([uu.ravel(), vv.ravel()], 1))
    per_pixel = np.abs(np.diff(np.arctan(x).reshape(rows, -1), axis=1))     # radians per raw pixel
    return float(1.0 / per_pixel.max())


def sight_range(cameras, object_height: float, margin: float = 1.0,
                width: int | None = None, object_width: float | None = None,
                columns: float = 1.0, raw_columns: float = 1.0,
                pixels_per_radian=None) -> tuple[np.ndarray, np.ndarray]:
    """Per camera, the floor distances (metres) between which an upright object of
    ``object_height`` metres shows at least ``margin`` rows of the rectified image in
    every column (and, given ``object_width``, at least ``columns`` rectified columns and
    ``raw_columns`` raw pixels across): ``(near, far)``, the blind and the sight radius.

    cameras : sequence of :class:`scene.Camera` (world frame: floor at z = 0)
    object_height : metres, > 0
    margin : rows (pixels of the level virtual camera, :class:`pipeline.Rectifier`'s
        output) the object must show to be sent: 1 for true masks, more for the
        pipeline's threshold (:meth:`pipeline.Pipeline.sight_range`)
    width : output width of the rectification (default the cameras')
    object_width : metres (a person's diameter), or None for no width limit
    columns, raw_columns : how many rectified columns and raw pixels across it must span
    pixels_per_radian : (n_cams,) :func:`raw_pixels_per_radian` of the cameras, when known

    Returns two (n_cams,) float arrays, metres: ``near`` (0 for a camera no higher than
    the object that sees the horizon; ``inf`` where the object is never seen) and
    ``far`` (``inf`` where no limit applies).

    >>> from scene import load_scene
    >>> near, far = sight_range(load_scene("lab").cameras[:1], 1.75)   # 2.2 m high, 15 deg down
    >>> near.round(2).tolist(), far.round().tolist()   # far: where a person is one row tall
    ([0.71], [1224.0])
    """
    object_height = check_positive("object_height", object_height)
    if object_width is not None:
        object_width = check_positive("object_width", object_width)
        if not (columns > 0 and raw_columns > 0):
            raise ValueError(f"columns, raw_columns: expected numbers > 0, got {columns}, {raw_columns}")
    margin = float(margin)
    if not (np.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin: expected a number of rows >= 0, got {margin}")
    cameras = tuple(cameras)
    Ks, _, width = level_cameras(cameras, width)
    near, far = np.zeros(len(cameras)), np.full(len(cameras), np.inf)
    for i, (camera, K) in enumerate(zip(cameras, Ks)):
        H = float(camera.center_world[2])
        if H <= 0:                                      # at or below the floor: sees no object on it
            near[i] = np.inf
            continue
        s = np.sqrt(1.0 + ((np.arange(width) - K[0, 2]) / K[0, 0]) ** 2)
        m = margin / K[1, 1]
        Yb, Yt = image_edge(camera, K, width), image_edge(camera, K, width, lower=False)
        top = (H - object_height) * s                  # the top's y times d
        lo = np.zeros(width)
        hi = np.full(width, np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            if m > 0:
                hi = np.minimum(hi, object_height * s / m)
            hi = np.where(Yt + m > 0, np.minimum(hi, H * s / (Yt + m)), hi)
            room = Yb - m                               # how far below the horizon `margin` rows end
            above = top > 0
            lo = np.where(above & (room > 0), top / room, lo)
            lo = np.where(above & (room <= 0), np.inf, lo)
            hi = np.where(~above & (room < 0), np.minimum(hi, top / room), hi)   # both <= 0
            lo = np.where(Yb - Yt < m, np.inf, lo)     # a column fewer than `margin` rows tall
        near[i], far[i] = float(np.max(lo)), float(np.min(hi))
        if object_width is not None:                    # too narrow beyond these
            g = raw_pixels_per_radian(camera) if pixels_per_radian is None else pixels_per_radian[i]
            far[i] = min(far[i], object_width * K[0, 0] / columns, object_width * g / raw_columns)
        if near[i] >= far[i]:
            near[i], far[i] = np.inf, np.inf
    return near, far

