"""Occluded cones and free wedges on the floor plane.

A camera at ``camera_xy`` looking along ``camera_yaw`` with field of view ``fov`` sees
the angular interval ``[-fov/2, fov/2]`` in its *local* frame (angles relative to
``camera_yaw``). Each object, or each run of occupied scanline columns, occludes an
angular interval; the complement of the merged occluded intervals inside the field of
view is a set of *free* intervals. Every free interval becomes a forward wedge from the
camera centre out to ``radius`` (chosen longer than any camera-room distance): the
region this camera proves empty, before clipping to the room.

All functions vectorise over cameras: intervals are stored padded as ``(n, K)`` arrays,
with unused slots set to the empty interval ``(-fov/2, -fov/2)``.

>>> lo, hi = disc_intervals(np.array([[0.0, 0.0]]), np.array([0.0]),
...                         np.array([[2.0, 0.0]]), np.array([1.0]))
>>> np.degrees([lo[0, 0], hi[0, 0]]).round(6).tolist()
[-30.0, 30.0]
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

__all__ = [
    "ARC_POINTS",
    "MIN_GAP",
    "clip_to_fov",
    "disc_intervals",
    "free_intervals",
    "group_by_camera",
    "scanline_intervals",
    "wedge_polygons",
    "wedge_radius",
    "wrap_angle",
]

#: Points on the far arc of every wedge polygon. The arc step is at most (2*pi)/8, so
#: the polygon's far edge stays beyond ``cos(pi/8) * radius`` from the apex.
ARC_POINTS = 9
#: Free intervals narrower than this (radians) are dropped: the hull grows by a sliver
#: at most ``MIN_GAP * radius`` wide, and GEOS is spared needle-thin polygons.
MIN_GAP = 1e-10


def wrap_angle(a):
    """Wrap angles (radians) to ``[-pi, pi)``.

    >>> float(wrap_angle(3 * np.pi / 2))
    -1.5707963267948966
    """
    return (np.asarray(a, dtype=float) + np.pi) % (2 * np.pi) - np.pi


def disc_intervals(camera_xy, camera_yaw, centers, radii):
    """Occluded angular interval of every disc as seen from every camera.

    Exact tangent lines: a disc of radius ``r`` whose centre is at distance ``d`` and
    bearing ``b`` occludes ``b +- asin(r / d)``. A camera inside a disc (``d < r``,
    possible only for estimated discs) is blinded: the interval is the whole circle.

    Parameters
    ----------
    camera_xy : (n, 2) float, metres, world frame
    camera_yaw : (n,) float, radians, world frame
    centers : (m, 2) float, metres, world frame
    radii : (m,) float, metres

    Returns
    -------
    lo, hi : (n, m) float, radians, camera-local frame (relative to ``camera_yaw``);
        ``lo`` lies in ``[-3*pi/2, pi)`` (``[-2*pi, 0)`` for a camera inside a disc),
        ``hi - lo <= 2*pi``.
    """
    diff = centers[None, :, :] - camera_xy[:, None, :]
    dist = np.hypot(diff[..., 0], diff[..., 1])
    bearing = wrap_angle(np.arctan2(diff[..., 1], diff[..., 0]) - camera_yaw[:, None])
    with np.errstate(divide="ignore", invalid="ignore"):
        half = np.where(
            dist >= radii[None, :], np.arcsin(np.clip(radii[None, :] / dist, 0.0, 1.0)), np.pi
        )
    return bearing - half, bearing + half


def column_edges(bearings) -> np.ndarray:
    """Edges of each column's angle: half a column step either side of its bearing, the
    outer edges extrapolating the first and last steps (what :func:`scanline_intervals`
    gives each column).

    bearings : (n, W) float, radians, unwrapped (no jump of 2*pi along a row), W >= 2
    Returns (n, W + 1) float, radians, in the order of the columns: column ``j`` spans
    ``edges[:, j]`` to ``edges[:, j + 1]``.
    """
    b = np.asarray(bearings, dtype=float)
    mid = 0.5 * (b[:, 1:] + b[:, :-1])
    first = b[:, :1] - 0.5 * (b[:, 1:2] - b[:, :1])
    last = b[:, -1:] + 0.5 * (b[:, -1:] - b[:, -2:-1])
    return np.concatenate([first, mid, last], axis=1)


def scanline_intervals(bearings, scanlines):
    """Field of view and occluded intervals of binary scanlines.

    Each column ``j`` covers half a column step either side of ``bearings[:, j]``;
    the outer edges extrapolate the first and last steps. Bearings may increase or
    decrease along a row and may wrap through +-pi (they are unwrapped first).

    Parameters
    ----------
    bearings : (n, W) float, radians, world frame; strictly monotone along each row
    scanlines : (n, W) bool, True = occupied column

    Returns
    -------
    camera_yaw : (n,) float, radians, world frame, centre of the field of view
    fov : (n,) float, radians, span of the column edges
    lo, hi : (n, K) float, radians, camera-local frame; one slot per run of True
        columns, unused slots ``(-fov/2, -fov/2)``.
    """
    b = np.unwrap(bearings, axis=1)
    step = np.diff(b, axis=1)
    decreasing = step[:, 0] < 0
    b = np.where(decreasing[:, None], b[:, ::-1], b)
    occ = np.where(decreasing[:, None], scanlines[:, ::-1], scanlines)
    edges = column_edges(b)  # (n, W + 1), increasing
    yaw = 0.5 * (edges[:, 0] + edges[:, -1])
    fov = edges[:, -1] - edges[:, 0]
    n = b.shape[0]
    padded = np.zeros((n, occ.shape[1] + 2), dtype=np.int8)
    padded[:, 1:-1] = occ
    d = np.diff(padded, axis=1)
    rows, starts = np.nonzero(d == 1)  # run begins at column `starts` -> edge starts
    _, ends = np.nonzero(d == -1)  # run ended at column ends - 1 -> edge ends
    counts = np.bincount(rows, minlength=n)
    k = max(int(counts.max()) if n else 0, 1)
    lo = np.repeat((-0.5 * fov)[:, None], k, axis=1)
    hi = lo.copy()
    if rows.size:
        rank = np.arange(rows.size) - np.concatenate([[0], np.cumsum(counts)[:-1]])[rows]
        lo[rows, rank] = edges[rows, starts] - yaw[rows]
        hi[rows, rank] = edges[rows, ends] - yaw[rows]
    return wrap_angle(yaw), fov, lo, hi


def clip_to_fov(lo, hi, half_fov):
    """Clip intervals (and their copies shifted by +-2*pi) to ``[-half_fov, half_fov]``.

    Parameters
    ----------
    lo, hi : (n, K) float, radians, camera-local frame
    half_fov : (n,) float, radians

    Returns
    -------
    lo, hi : (n, 3K) float; empty results become ``(-half_fov, -half_fov)``.
    """
    shifts = np.array([0.0, -2 * np.pi, 2 * np.pi])
    h = half_fov[:, None, None]
    lo3 = np.clip(lo[:, None, :] + shifts[None, :, None], -h, h)
    hi3 = np.clip(hi[:, None, :] + shifts[None, :, None], -h, h)
    empty = hi3 <= lo3
    lo3 = np.where(empty, -h, lo3)
    hi3 = np.where(empty, -h, hi3)
    n = lo.shape[0]
    return lo3.reshape(n, -1), hi3.reshape(n, -1)


def free_intervals(lo, hi, half_fov, min_gap: float = MIN_GAP):
    """Gaps between merged occluded intervals inside the field of view.

    Overlapping occluded intervals of one camera merge; gaps narrower than
    ``min_gap`` radians are dropped.

    Parameters
    ----------
    lo, hi : (n, K) float, radians, camera-local frame, already within the FOV
    half_fov : (n,) float, radians

    Returns
    -------
    camera : (q,) int, index of the camera owning each free interval
    a0, a1 : (q,) float, radians, camera-local frame, ``a0 < a1``

    >>> cam, a0, a1 = free_intervals(np.array([[-0.1, 0.2]]), np.array([[0.1, 0.3]]),
    ...                              np.array([1.0]))
    >>> cam.tolist(), a0.tolist(), a1.tolist()
    ([0, 0, 0], [-1.0, 0.1, 0.3], [-0.1, 0.2, 1.0])
    """
    order = np.argsort(lo, axis=1, kind="stable")
    lo_s = np.take_along_axis(lo, order, axis=1)
    hi_s = np.maximum.accumulate(np.take_along_axis(hi, order, axis=1), axis=1)
    h = half_fov[:, None]
    gap_lo = np.concatenate([-h, hi_s], axis=1)
    gap_hi = np.concatenate([lo_s, h], axis=1)
    keep = gap_hi - gap_lo > min_gap
    camera, _ = np.nonzero(keep)
    return camera, gap_lo[keep], gap_hi[keep]


def wedge_radius(room: BaseGeometry, camera_xy: np.ndarray) -> float:
    """Wedge length (metres): twice the diagonal of the box holding room and cameras, plus 1 m
    (a room of one point still gets wedges of length)."""
    x0, y0, x1, y1 = room.bounds
    x0, y0 = min(x0, camera_xy[:, 0].min()), min(y0, camera_xy[:, 1].min())
    x1, y1 = max(x1, camera_xy[:, 0].max()), max(y1, camera_xy[:, 1].max())
    return 2.0 * float(np.hypot(x1 - x0, y1 - y0)) + 1.0


def wedge_polygons(apex, theta0, theta1, radius: float, inner=None, outer=None) -> np.ndarray:
    """Forward wedges from ``apex`` between world-frame angles ``theta0 < theta1``.

    Parameters
    ----------
    apex : (q, 2) float, metres, world frame
    theta0, theta1 : (q,) float, radians, world frame, ``0 < theta1 - theta0 < 2*pi``
    radius : float, metres
    inner : optional (q,) float, metres, ``0 <= inner < outer cos(s/2)^2`` for the arc
        step ``s = (theta1 - theta0) / (ARC_POINTS - 1)``: cut every wedge to the part
        beyond ``inner`` from the apex (a camera's blind radius,
        :mod:`pipeline.nearfield`). The inner arc's chords pass outside the circle of
        radius ``inner``, so the whole disc stays outside the wedge.
    outer : optional (q,) float, metres: end every wedge at ``min(outer, radius)`` (a
        camera's sight radius); the far arc's chords pass inside that circle.

    Returns
    -------
    (q,) object array of shapely Polygons with ``ARC_POINTS + 2`` vertices each
    (``2 * ARC_POINTS + 1`` with ``inner``).
    """
    t = np.linspace(0.0, 1.0, ARC_POINTS)
    ang = theta0[:, None] + (theta1 - theta0)[:, None] * t[None, :]
    q = apex.shape[0]
    if q == 0:
        return np.empty(0, dtype=object)
    far = np.full(q, float(radius)) if outer is None else np.minimum(np.asarray(outer, float), radius)
    if inner is None:
        coords = np.empty((q, ARC_POINTS + 2, 2))
        coords[:, 0] = apex
        coords[:, -1] = apex
        arc = coords[:, 1:-1]
    else:
        coords = np.empty((q, 2 * ARC_POINTS + 1, 2))
        half_step = 0.5 * (theta1 - theta0) / (ARC_POINTS - 1)
        r = np.asarray(inner, float) / np.cos(half_step)           # chords tangent to the circle
        back = ang[:, ::-1]
        coords[:, ARC_POINTS:-1, 0] = apex[:, :1] + r[:, None] * np.cos(back)
        coords[:, ARC_POINTS:-1, 1] = apex[:, 1:] + r[:, None] * np.sin(back)
        arc = coords[:, :ARC_POINTS]
    arc[..., 0] = apex[:, :1] + far[:, None] * np.cos(ang)
    arc[..., 1] = apex[:, 1:] + far[:, None] * np.sin(ang)
    if inner is not None:
        coords[:, -1] = coords[:, 0]                                # closed on the far arc's start
    return np.atleast_1d(shapely.polygons(coords))


def group_by_camera(polygons: np.ndarray, camera: np.ndarray, n: int) -> np.ndarray:
    """Collect polygons into one MultiPolygon per camera.

    Parameters
    ----------
    polygons : (q,) object array of Polygons
    camera : (q,) int, non-decreasing camera index of each polygon
    n : number of cameras

    Returns
    -------
    (n,) object array of MultiPolygons (empty for a camera without polygons).
    """
    out = np.array([shapely.MultiPolygon() for _ in range(n)], dtype=object)
    if polygons.size:
        shapely.multipolygons(polygons, indices=camera, out=out)
    return out
