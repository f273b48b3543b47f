"""Geometry that lines up exactly: fields of view along walls and diagonals, cameras on corners.

Such rigs are what people draw first (90-degree cameras in the corners of a square room),
and they put wedge edges exactly on walls and on each other, where floating-point
overlays can misjudge a whole polygon.
"""

import itertools

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon, box

from tasking import choose_cameras, incremental_select, visual_hull_of_discs
from tasking.coverage import coverage_cells, subset_areas
from tasking.hull import free_wedges_from_discs, hull_from_wedges

NO_OBJECTS = np.empty((0, 2))


def seen_by_none(points, xy, yaw, fov):
    """(p,) bool: no camera has the point inside its field of view (no objects: the hull)."""
    d = points[:, None, :] - xy[None]
    rel = (np.arctan2(d[..., 1], d[..., 0]) - yaw[None] + np.pi) % (2 * np.pi) - np.pi
    return ~np.any(np.abs(rel) < fov / 2, axis=1)


@pytest.mark.parametrize("order", list(itertools.permutations(range(3))))
def test_three_corner_cameras_leave_the_triangle_nobody_sees_in_any_order(order):
    """Cameras in three corners of an empty 4 m square, 90 degrees, edges along the walls and
    the diagonal: the triangle (4, 0), (4, 4), (2, 2) is seen by none. Three of the six
    orders of the cameras used to give an empty hull."""
    room = box(0, 0, 4, 4)
    xy = np.array([[4.0, 4.0], [0.0, 4.0], [4.0, 0.0]])[list(order)]
    yaw = np.radians([180.0, -90.0, 180.0])[list(order)]
    hull = visual_hull_of_discs(xy, yaw, np.pi / 2, NO_OBJECTS, 0.3, room)
    assert hull.area == pytest.approx(4.0, abs=1e-9)
    assert shapely.equals_exact(shapely.normalize(hull), shapely.normalize(Polygon([(4, 0), (4, 4), (2, 2)])),
                                1e-9)
    probe = np.random.default_rng(0).uniform(0, 4, (2000, 2))
    np.testing.assert_array_equal(shapely.contains_xy(hull, probe[:, 0], probe[:, 1]),
                                  seen_by_none(probe, xy, yaw, np.pi / 2))


def test_the_optimal_tasker_keeps_every_cell_of_an_l_shaped_room():
    """A 180-degree camera on the L's outer corner proves only x < 2 empty (hull 4 m^2); a
    camera on the wall x = 4 sees the whole room (hull 0). The coverage table used to lose
    the 4 m^2 cell (a sliver from an edge passing 1e-16 off the inner corner)."""
    room = Polygon([(0, 0), (4, 0), (4, 2), (2, 2), (2, 4), (0, 4)])
    xy = np.array([[2.0, 4.0], [4.0, 1.0]])
    yaw = np.array([np.pi, np.pi])
    wedges = free_wedges_from_discs(xy, yaw, np.pi, NO_OBJECTS, 0.3, room, strict=False)
    cov = coverage_cells(wedges, room)
    assert cov.areas.sum() == pytest.approx(room.area, abs=1e-9)
    np.testing.assert_allclose(subset_areas(cov, [[0], [1]]), [4.0, 0.0], atol=1e-9)
    assert hull_from_wedges(wedges, room, [0]).area == pytest.approx(4.0, abs=1e-9)
    for tasker in ("optimal", "greedy", "lazy_greedy"):
        assert choose_cameras(tasker, 1, xy, yaw, np.pi, NO_OBJECTS, 0.3, room).tolist() == [1]


def test_incremental_select_survives_a_hull_with_a_stray_point():
    """12 wall cameras of 90 degrees in a square, 9 tasked, 6 swapped, polygon gains: the
    hull of the kept cameras came out of an intersection with a stray point in it, and the
    next overlay raised GEOSException."""
    room = box(0, 0, 4, 4)
    xy = np.array([[2, 0], [4, 2], [2, 4], [0, 2], [1, 0], [3, 0], [4, 1], [4, 3], [3, 4], [1, 4], [0, 3],
                   [0, 1]], float)
    yaw = np.round(np.arctan2(2 - xy[:, 1], 2 - xy[:, 0]) / (np.pi / 2)) * (np.pi / 2)
    est = np.array([[2.117, 0.38], [2.536, 0.585], [1.371, 2.19], [0.081, 0.921], [2.144, 2.479]])
    wedges = free_wedges_from_discs(xy, yaw, np.pi / 2, est, 0.3, room, strict=False)
    chosen = incremental_select(wedges, room, [0, 1, 2, 3, 4, 7, 9, 10, 11], 6)
    assert len(chosen) == 9 and len(set(chosen)) == 9 and all(0 <= c < 12 for c in chosen)


@pytest.mark.parametrize("fov_deg", [90.0, 180.0, 270.0])
def test_union_areas_count_a_segment_two_cameras_share_once(fov_deg):
    """Rays of two cameras along one segment with both cones on one side are one edge of
    the union: the fast path (incremental greedy on a convex room) must agree with the
    hull's overlays. It counted the segment twice: a hull area of -1 m^2 for 0.5."""
    from tasking.cones import wedge_radius
    from tasking.fan import UnionAreas, convex_ring, split_wide

    room = box(0, 0, 4, 4)
    xy = np.array([[0.0, 2.0], [3.0, 0.0], [4.0, 1.0], [1.0, 4.0]])
    yaw = np.array([0.0, np.pi / 2, np.pi, -np.pi / 2])
    fov = np.radians(fov_deg)
    wedges, cones = free_wedges_from_discs(xy, yaw, fov, NO_OBJECTS, 0.3, room, strict=False, return_cones=True)
    union = UnionAreas(convex_ring(room), split_wide(*cones), 4, wedge_radius(room, xy))
    sets = np.array(list(itertools.product([False, True], repeat=4)))
    hulls = [hull_from_wedges(wedges, room, np.flatnonzero(s)).area for s in sets]
    np.testing.assert_allclose(room.area - union(sets), hulls, atol=1e-9)


def test_incremental_greedy_fast_path_chooses_as_the_overlays_do():
    room = box(0, 0, 4, 4)
    xy = np.array([[0.0, 2.0], [3.0, 0.0], [4.0, 1.0]])
    yaw = np.array([0.0, np.pi / 2, np.pi])
    wedges, cones = free_wedges_from_discs(xy, yaw, np.pi / 2, NO_OBJECTS, 0.3, room, strict=False,
                                           return_cones=True)
    fast = choose_cameras("incremental", 2, xy, yaw, np.pi / 2, NO_OBJECTS, 0.3, room, current=[1, 2], m=1)
    assert fast.tolist() == incremental_select(wedges, room, [1, 2], 1, cones) == [0, 2]
