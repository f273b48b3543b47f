"""How close to a camera an object can stand and not be sent: the near field.

A camera pitched down does not see the floor at its feet. An upright object of height
``h`` standing at floor distance ``d`` from a camera at height ``H > h`` shows, in the
scanline column of its bearing, the rows from its top (on the level virtual camera of
:mod:`pipeline.rectify`, ``y = (H - h) / (d cos a)`` for a column at angle ``a`` off the
optical axis) down to the raw image's lower edge. Closer than some distance it shows
fewer rows than the scanline needs, or none: the camera sends "empty" there although an
object may stand in it. The **blind radius** is the largest such distance over the
camera's columns; tasking carves a camera's free wedges only beyond it
(:func:`tasking.visual_hull_of_scanlines` with ``near``), so that the hull keeps every
object near a camera too.

The object stands on the floor (z = 0, world frame) and its top is what is seen first
from above (the lab's people are cylinders with a flat top, whose top disc is drawn): a
floor point of the object at distance ``d`` beyond the blind radius has the object's
top above it in view, with at least ``margin`` rows of the object below it in that
column. A camera no higher than the object sees the object at its own height, on the
horizon: radius 0. A camera whose lower image edge is above the horizon in some column
never sees a low object there: radius ``inf`` (it proves nothing empty).
"""

from __future__ import annotations

import numpy as np

from .rectify import level_cameras, level_points

__all__ = ["blind_radius", "lower_edge"]

#: Points sampled along the raw image's lower edge.
EDGE_POINTS = 129


def lower_edge(camera, K_virtual: np.ndarray, width: int) -> np.ndarray:
    """The raw image's lower edge on the level virtual camera, per output column.

    Returns (width,) float: the virtual image y (z = 1 plane, y down) of the outer edge of
    the raw image's last row of pixels, at each output column's x. Columns are those of
    :func:`pipeline.rectify.virtual_camera_matrix`, all of which the raw image covers
    from top to bottom.
    """
    us = np.linspace(-0.5, camera.width - 0.5, EDGE_POINTS)
    x, y = level_points(camera, np.stack([us, np.full_like(us, camera.height - 0.5)], 1))
    order = np.argsort(x)
    columns = (np.arange(width) - K_virtual[0, 2]) / K_virtual[0, 0]
    return np.interp(columns, x[order], y[order])


def blind_radius(cameras, object_height: float, margin: float = 1.0, width: int | None = None) -> np.ndarray:
    """Per camera, the floor distance (metres) within which an upright object of
    ``object_height`` metres can show fewer than ``margin`` rows of the rectified image in
    its column.

    cameras : sequence of :class:`scene.Camera` (world frame: floor at z = 0)
    object_height : metres, > 0
    margin : rows (pixels of the level virtual camera, :class:`pipeline.Rectifier`'s
        output) the object must show below its top to be sent: 1 for true masks,
        more for the pipeline's threshold (:meth:`pipeline.Pipeline.blind_radius`)
    width : output width of the rectification (default the cameras')

    Returns (n_cams,) float, metres; 0 for a camera no higher than the object, ``inf``
    where the object is never seen.

    >>> from scene import load_scene
    >>> cams = load_scene("lab").cameras[:1]          # 2.2 m high, pitched 15 degrees down
    >>> blind_radius(cams, 1.75).round(2).tolist()     # the top of a 1.75 m person
    [0.71]
    """
    if not (np.isfinite(object_height) and object_height > 0):
        raise ValueError(f"object_height: expected a positive number of metres, got {object_height}")
    if not (np.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin: expected a number of rows >= 0, got {margin}")
    cameras = tuple(cameras)
    Ks, _, width = level_cameras(cameras, width)
    out = np.zeros(len(cameras))
    for i, (camera, K) in enumerate(zip(cameras, Ks)):
        drop = float(camera.center_world[2]) - object_height         # camera above the object's top
        if drop <= 0:
            continue
        columns = (np.arange(width) - K[0, 2]) / K[0, 0]
        lowest = lower_edge(camera, K, width) - margin / K[1, 1]       # lowest y with `margin` rows below
        if np.any(lowest <= 0):
            out[i] = np.inf
            continue
        # the top at floor distance d along a column at x: depth d / sqrt(1 + x^2), y = drop / depth
        out[i] = float(np.max(drop * np.sqrt(1.0 + columns**2) / lowest))
    return out
