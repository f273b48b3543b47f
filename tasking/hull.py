"""Visual hulls on the floor plane, from object discs or from binary scanlines.

A camera proves *empty* every point of the room that lies inside its field of view and
outside all of its occluded cones: the union of its free wedges (:mod:`tasking.cones`).
The visual hull of a camera set ``S`` is the room minus the union of the empty regions
of the cameras in ``S``; equivalently the room intersected with each camera's "not
proven empty" region. A point outside a camera's field of view is not constrained by
that camera, so the hull always contains every object.

>>> from shapely.geometry import Point
>>> room = Point(0, 0).buffer(1.0, quad_segs=64)
>>> hull = visual_hull_of_discs([[-1, 0], [0, -1]], [0, np.pi / 2], np.pi,
...                             [[0, 0]], 0.1, room)
>>> round(hull.area, 4)  # two crossing tangent cones: a kite just larger than 0.2 x 0.2
0.0404
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.base import BaseGeometry

from . import cones
from .checks import (
    check_angles,
    check_camera_radii,
    check_cameras_outside_discs,
    check_discs_disjoint,
    check_discs_in_room,
    check_fov,
    check_points,
    check_radii,
    check_room,
)

#: Hull parts smaller than this fraction of the room's area are rounding noise.
SLIVER = 1e-12
#: Up to this many wedge sets, the room minus each in turn (largest first) beats one GEOS
#: cascaded union of them all: 16 cameras 2.6 -> 1.2 ms (3 discs), 5.1 -> 4.1 ms (10);
#: 32: 5.1 -> 2.3, 13.7 -> 8.4 ms; at 64 and 10 discs the union wins (docs/performance.md).
SEQUENTIAL_MAX = 32
#: Snap-rounding grid of the hull's overlays, relative to the room's size (:func:`overlay_grid`).
GRID = 1e-13
#: ... and at least this fraction of the largest coordinate of the overlaid geometries
#: (45 times a double's rounding, which a finer grid cannot snap to).
COORD_GRID = 1e-14

__all__ = [
    "SLIVER",
    "camera_regions_from_discs",
    "camera_regions_from_scanlines",
    "drop_slivers",
    "empty_regions_from_discs",
    "empty_regions_from_scanlines",
    "free_wedges_from_discs",
    "free_wedges_from_scanlines",
    "hull_from_wedges",
    "polygon_centres",
    "prune_small",
    "visual_hull_of_discs",
    "visual_hull_of_scanlines",
]


def free_wedges_from_discs(
    camera_xy, camera_yaw, fov, centers, radii, room, *, strict: bool = True,
    return_cones: bool = False, polygons: bool = True,
):
    """Per-camera union of free wedges (not clipped to the room), from object discs.

    Parameters
    ----------
    camera_xy : (n, 2) float, metres, world frame
    camera_yaw : (n,) float, radians, world frame viewing direction
    fov : float or (n,) float, radians, in (0, 2*pi)
    centers : (m, 2) float, metres, world frame (m may be 0)
    radii : float or (m,) float, metres
    room : shapely Polygon
    strict : bool
        Validate the objects as real ones (disjoint, inside the room, no camera inside).
        Estimated discs (``strict=False``) may overlap; a camera inside one is blind.
    return_cones : bool
        Also return the free wedges as a table ``(camera (q,) int, apex (q, 2),
        theta0 (q,), theta1 (q,))``, world-frame radians, grouped by camera.
    polygons : bool
        Build the wedge polygons (default); with ``polygons=False`` and ``return_cones``
        only the table is built and the wedges are returned as None.

    Returns
    -------
    (n,) object array of MultiPolygons, world frame: what each camera proves empty
    (intersect with ``room`` for the empty region proper); with ``return_cones`` a
    tuple ``(wedges, cones)``.
    """
    room = check_room(room)
    camera_xy = check_points("camera_xy", camera_xy)
    n = camera_xy.shape[0]
    camera_yaw = check_angles("camera_yaw", camera_yaw, n)
    fov = check_fov(fov, n)
    centers = check_points("centers", centers, allow_empty=True)
    radii = check_radii("radii", radii, centers.shape[0])
    if strict:
        check_discs_disjoint(centers, radii)
        check_discs_in_room(centers, room)
        check_cameras_outside_discs(camera_xy, centers, radii)
    half = 0.5 * fov
    lo, hi = cones.disc_intervals(camera_xy, camera_yaw, centers, radii)
    lo, hi = cones.clip_to_fov(lo, hi, half)
    wedges, table = _wedges(camera_xy, camera_yaw, half, lo, hi, room,
                            polygons or not return_cones)
    return (wedges, table) if return_cones else wedges


def free_wedges_from_scanlines(camera_xy, bearings, scanlines, room, near=None, far=None) -> np.ndarray:
    """Per-camera union of free wedges (not clipped to the room), from scanlines.

    Parameters
    ----------
    camera_xy : (n, 2) float, metres, world frame
    bearings : (n, W) float, radians, world-frame bearing of each column's vertical
        plane; strictly monotone along each row (either direction), W >= 2
    scanlines : (n, W) bool, True = occupied column
    room : shapely Polygon
    near : optional float or (n,) float, metres, >= 0 (``inf`` allowed): each camera's
        blind radius (:meth:`pipeline.Pipeline.sight_range`); its free wedges start
        that far from it, since an object closer may be below its image. None: from
        the camera centre, as for the paper's cameras.
    far : optional float or (n,) float, metres, > 0 (``inf`` allowed): each camera's sight
        radius; its free wedges end there, since an object farther may be outside its
        image or too small to be sent. None: they reach past the room.

    Returns
    -------
    (n,) object array of MultiPolygons, as :func:`free_wedges_from_discs`.
    """
    room = check_room(room)
    camera_xy = check_points("camera_xy", camera_xy)
    n = camera_xy.shape[0]
    bearings = np.asarray(bearings, dtype=float)
    scanlines = np.asarray(scanlines)
    if bearings.ndim != 2 or bearings.shape[0] != n or bearings.shape[1] < 2:
        raise ValueError(f"bearings must have shape ({n}, W) with W >= 2; got {bearings.shape}")
    if scanlines.shape != bearings.shape:
        raise ValueError(
            f"scanlines must have the shape of bearings {bearings.shape}; got {scanlines.shape}"
        )
    if scanlines.dtype != bool:
        raise ValueError(f"scanlines must be a bool array; got dtype {scanlines.dtype}")
    if not np.all(np.isfinite(bearings)):
        raise ValueError("bearings must be finite (no NaN or inf)")
    step = np.diff(np.unwrap(bearings, axis=1), axis=1)
    monotone = np.all(step > 0, axis=1) | np.all(step < 0, axis=1)
    if not np.all(monotone):
        bad = int(np.flatnonzero(~monotone)[0])
        raise ValueError(f"bearings must be strictly monotone along each row (row {bad})")
    if near is not None:
        near = check_camera_radii("near", near, n)
    if far is not None:
        far = check_camera_radii("far", far, n)
    yaw, fov, lo, hi = cones.scanline_intervals(bearings, scanlines)
    if np.any(fov >= 2 * np.pi):
        raise ValueError("bearings: the columns of a camera must span less than 2*pi")
    return _wedges(camera_xy, yaw, 0.5 * fov, lo, hi, room, near=near, far=far)[0]


def _wedges(camera_xy, yaw, half, lo, hi, room, polygons: bool = True, near=None, far=None):
    camera, a0, a1 = cones.free_intervals(lo, hi, half)
    theta0, theta1 = yaw[camera] + a0, yaw[camera] + a1
    table = (camera, camera_xy[camera], theta0, theta1)
    if not polygons:
        return None, table
    radius = cones.wedge_radius(room, camera_xy)
    inner = near[camera] if near is not None and np.any(near > 0) else None
    outer = far[camera] if far is not None and np.any(far < radius) else None
    if inner is not None or outer is not None:
        reach = radius if outer is None else np.minimum(outer, radius)
        start = 0.0 if inner is None else inner
        keep = start < reach * np.cos(0.5 * (theta1 - theta0) / (cones.ARC_POINTS - 1)) ** 2   # inside the chords
        camera, theta0, theta1 = camera[keep], theta0[keep], theta1[keep]
        inner = None if inner is None else inner[keep]
        outer = None if outer is None else outer[keep]
    polys = cones.wedge_polygons(camera_xy[camera], theta0, theta1, radius, inner, outer)
    return cones.group_by_camera(polys, camera, camera_xy.shape[0]), table


def hull_from_wedges(wedges, room: Polygon, subset=None) -> BaseGeometry:
    """Visual hull: the room minus the union of the chosen cameras' free wedges.

    The room minus each camera's wedges in turn, largest area first, up to
    ``SEQUENTIAL_MAX`` cameras; above, the room minus their union (the same region, to
    rounding: the cheaper order for few and for many cameras).

    Parameters
    ----------
    wedges : (n,) object array of MultiPolygons (from ``free_wedges_*``)
    room : shapely Polygon
    subset : optional sequence of 0-based camera indices; default all cameras

    Returns
    -------
    shapely geometry (Polygon, MultiPolygon or GeometryCollection), before pruning.
    """
    w = np.asarray(wedges, dtype=object)
    if subset is not None:
        w = w[np.asarray(subset, dtype=np.intp)]
    if w.size == 0:
        return room
    grid = overlay_grid(room, w)
    if w.size > SEQUENTIAL_MAX:
        return drop_slivers(shapely.difference(room, shapely.union_all(w, grid_size=grid), grid_size=grid), room)
    hull = room
    for g in w[np.argsort(-shapely.area(w), kind="stable")]:
        # without slivers and stray points or lines, which the next snap-rounded overlay refuses
        hull = drop_slivers(shapely.difference(hull, g, grid_size=grid), room)
    return hull


def overlay_grid(room: Polygon, geoms=()) -> float:
    """The precision grid (metres) of the hull's overlays: ``GRID`` times the room's size,
    at least ``COORD_GRID`` times the largest coordinate of ``room`` and ``geoms``.

    GEOS's floating overlays can misjudge a polygon edge that runs along a wedge's edge
    (wedges of cameras whose fields of view line up along a wall or a diagonal): three
    90-degree corner cameras of an empty square gave an empty hull in three of the six
    orders of the cameras, the right triangle in the others. Snap-rounding to a grid far
    below any length that matters (``grid_size``) makes these overlays robust, at about
    1.5-2 times the cost. The taskers' own overlays stay floating: their hulls only rank
    candidate cameras.

    A grid below the coordinates' own rounding snaps nothing: with a room millions of
    metres from the origin (georeferenced), or wedges a kilometre long from cameras far
    from a small room, GEOS stopped with 'TopologyException: side location conflict'.
    Hence the floor ``COORD_GRID`` times the largest coordinate (wedges included); for
    the lab and the circle the room's size decides.
    """
    x0, y0, x1, y1 = room.bounds
    bounds = shapely.bounds(np.asarray(geoms, dtype=object).ravel())
    reach = max(abs(x0), abs(y0), abs(x1), abs(y1), float(np.nanmax(np.abs(bounds), initial=0.0)))
    return max(GRID * max(x1 - x0, y1 - y0), COORD_GRID * reach)


def drop_slivers(geom: BaseGeometry, room: Polygon) -> BaseGeometry:
    """Drop numerical slivers: parts with area <= ``SLIVER * room.area``.

    A free wedge whose edge runs along a wall (a 180-degree camera on the boundary)
    leaves zero-area polygons of rounding noise along that wall. They are not objects,
    not phantoms, and far below any ``prune_small`` threshold.
    """
    eps = SLIVER * room.area
    if isinstance(geom, Polygon):
        return geom if geom.area > eps else Polygon()
    parts = shapely.get_parts(geom)
    keep = parts[shapely.area(parts) > eps]
    if keep.size == parts.size:
        return geom
    if keep.size == 1:
        return keep[0]
    return MultiPolygon(list(keep))


def empty_regions_from_discs(camera_xy, camera_yaw, fov, centers, radii, room) -> list:
    """Per-camera region proven empty (free wedges clipped to the room), from discs.

    Same parameters as :func:`visual_hull_of_discs`; returns a list of n geometries.
    """
    w = free_wedges_from_discs(camera_xy, camera_yaw, fov, centers, radii, room)
    return list(shapely.intersection(w, room))


def empty_regions_from_scanlines(camera_xy, bearings, scanlines, room, near=None, far=None) -> list:
    """Per-camera region proven empty, from scanlines (``near`` and ``far`` as in
    :func:`free_wedges_from_scanlines`); a list of n geometries."""
    w = free_wedges_from_scanlines(camera_xy, bearings, scanlines, room, near, far)
    return list(shapely.intersection(w, room))


def camera_regions_from_discs(camera_xy, camera_yaw, fov, centers, radii, room) -> list:
    """Per-camera "not proven empty" regions, from discs.

    ``hull(S) == room ∩ ⋂_{c in S} regions[c]``. Same parameters as
    :func:`visual_hull_of_discs`; returns a list of n geometries inside the room.
    """
    w = free_wedges_from_discs(camera_xy, camera_yaw, fov, centers, radii, room)
    return [drop_slivers(g, room) for g in shapely.difference(room, w)]


def camera_regions_from_scanlines(camera_xy, bearings, scanlines, room, near=None, far=None) -> list:
    """Per-camera "not proven empty" regions, from scanlines (``near`` and ``far`` as in
    :func:`free_wedges_from_scanlines`); a list of n geometries."""
    w = free_wedges_from_scanlines(camera_xy, bearings, scanlines, room, near, far)
    return [drop_slivers(g, room) for g in shapely.difference(room, w)]


def visual_hull_of_discs(camera_xy, camera_yaw, fov, centers, radii, room) -> BaseGeometry:
    """Visual hull of disc objects seen by cameras with a field of view.

    Parameters
    ----------
    camera_xy : (n, 2) float, metres, world frame
    camera_yaw : (n,) float, radians, world-frame viewing direction
    fov : float or (n,) float, radians, in (0, 2*pi)
    centers : (m, 2) float, metres, world frame; disjoint discs inside the room
    radii : float or (m,) float, metres
    room : shapely Polygon

    Returns
    -------
    shapely geometry, the hull before small-polygon removal (see :func:`prune_small`).
    """
    w = free_wedges_from_discs(camera_xy, camera_yaw, fov, centers, radii, room)
    return hull_from_wedges(w, room)


def visual_hull_of_scanlines(camera_xy, bearings, scanlines, room, near=None, far=None) -> BaseGeometry:
    """Visual hull from binary scanlines.

    Parameters
    ----------
    camera_xy : (n, 2) float, metres, world frame
    bearings : (n, W) float, radians, world-frame bearing of each column's vertical
        plane, strictly monotone along each row; a column covers half a column step
        either side, so the field of view is the span of the column edges
    scanlines : (n, W) bool, True = occupied column
    room : shapely Polygon
    near, far : optional float or (n,) float, metres: each camera's blind and sight
        radius; it proves empty only what lies between them
        (:func:`free_wedges_from_scanlines`)

    Returns
    -------
    shapely geometry, the hull before small-polygon removal.
    """
    w = free_wedges_from_scanlines(camera_xy, bearings, scanlines, room, near, far)
    return hull_from_wedges(w, room)


def prune_small(hull: BaseGeometry, min_area: float) -> list[Polygon]:
    """Polygons of ``hull`` with area >= ``min_area`` (m^2); lines and points dropped.

    >>> from shapely.geometry import box
    >>> [p.area for p in prune_small(box(0, 0, 1, 1).union(box(2, 0, 2.1, 0.1)), 0.5)]
    [1.0]
    """
    min_area = float(min_area)
    if not np.isfinite(min_area) or min_area < 0:
        raise ValueError(f"min_area must be finite and >= 0; got {min_area}")
    parts = shapely.get_parts(shapely.get_parts(np.array([hull], dtype=object)))
    polys = [p for p in parts if isinstance(p, Polygon) and not p.is_empty]
    polys.extend(q for p in parts if isinstance(p, MultiPolygon) for q in p.geoms)
    return [p for p in polys if p.area >= min_area and p.area > 0]


def polygon_centres(polygons) -> np.ndarray:
    """Centroids of polygons.

    Parameters
    ----------
    polygons : sequence of p shapely Polygons (:func:`prune_small`'s); a MultiPolygon,
        whose centroid can lie between its parts, or any other geometry is refused

    Returns
    -------
    (p, 2) float, metres, world frame; a row of NaN for an empty polygon (rows stay
    aligned with ``polygons``).

    >>> from shapely.geometry import Polygon, box
    >>> polygon_centres([box(0, 0, 2, 2), Polygon()]).tolist()
    [[1.0, 1.0], [nan, nan]]
    """
    if isinstance(polygons, BaseGeometry):
        raise ValueError(f"polygons: expected a sequence of Polygons, got one {polygons.geom_type} "
                         "(prune_small(hull, min_area) gives a hull's polygons)")
    polys = np.asarray(list(polygons), dtype=object)
    for i, p in enumerate(polys):
        if not isinstance(p, Polygon):
            raise ValueError(f"polygons[{i}] is a {getattr(p, 'geom_type', type(p).__name__)}, not a Polygon "
                             "(prune_small(hull, min_area) gives a hull's polygons)")
    if polys.size == 0:
        return np.empty((0, 2))
    centres = shapely.centroid(polys)
    out = np.full((polys.size, 2), np.nan)
    full = ~shapely.is_empty(centres)
    out[full] = shapely.get_coordinates(centres[full]).reshape(-1, 2)
    return out
