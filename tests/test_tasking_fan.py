"""Triangle-fan cone areas agree with polygon overlays."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import MultiPoint, Point, Polygon, box

from tasking.cones import wedge_polygons
from tasking.fan import cone_areas, ring_edges, split_wide


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.booleans())
def test_cone_areas_match_shapely(seed, inside):
    rng = np.random.default_rng(seed)
    # a non-convex polygon with a hole, possibly in several parts
    poly = MultiPoint(rng.uniform(-1, 1, (6, 2))).buffer(0.3).difference(Point(0, 0).buffer(0.2))
    apex = rng.uniform(-0.5, 0.5, (5, 2)) if inside else rng.uniform(-3, 3, (5, 2))
    t0 = rng.uniform(-np.pi, np.pi, 5)
    t1 = t0 + rng.uniform(0.01, 2 * np.pi - 0.01, 5)
    cam, apx, s0, s1 = split_wide(np.arange(5), apex, t0, t1)
    got = np.bincount(cam, weights=cone_areas(*ring_edges(poly), apx, s0, s1))
    wedges = wedge_polygons(apex, t0, t1, 20.0)
    want = [poly.intersection(w).area for w in wedges]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)


def test_half_plane_cone_and_empty_polygon():
    a, b = ring_edges(box(-1, -1, 1, 1))
    area = cone_areas(a, b, np.array([[0.0, -1.0]]), np.array([0.0]), np.array([np.pi]))
    assert abs(area[0] - 4.0) < 1e-12
    e = ring_edges(box(0, 0, 1, 1).difference(box(-1, -1, 2, 2)))
    assert cone_areas(*e, np.zeros((1, 2)), np.zeros(1), np.ones(1)).tolist() == [0.0]


def _cones_of(rng, n, apex):
    """Up to three disjoint angular intervals per camera (split at pi like the taskers)."""
    cam, apx, t0, t1 = [], [], [], []
    for c in range(n):
        m = int(rng.integers(1, 4))
        a = np.sort(rng.uniform(0, 2 * np.pi, 2 * m)) + rng.uniform(-np.pi, np.pi)
        cam += [c] * m
        apx += [apex[c]] * m
        t0 += list(a[0::2])
        t1 += list(a[1::2])
    return split_wide(np.array(cam), np.array(apx), np.array(t0), np.array(t1))


def _union_reference(room, cones, sets, radius):
    import shapely

    cam, apx, t0, t1 = cones
    wedges = wedge_polygons(apx, t0, t1, radius)
    # snapped to a 1e-12 grid: GEOS's floating overlay of many thin wedges sharing an
    # apex can drop a piece (seen: 1.6 % of the area, against a Monte Carlo estimate)
    return np.array([room.intersection(shapely.union_all(wedges[s[cam]], grid_size=1e-12)).area
                     if s[cam].any() else 0.0 for s in sets])


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["inside", "boundary", "outside", "mixed"]))
def test_union_areas_match_shapely(seed, where):
    from tasking.fan import UnionAreas, convex_ring

    rng = np.random.default_rng(seed)
    room = MultiPoint(rng.uniform(-1, 1, (int(rng.integers(3, 30)), 2))).convex_hull
    if room.area < 0.05:
        room = box(-1, -0.7, 1, 0.7)
    ring = convex_ring(room)
    v = ring[:-1]
    n = int(rng.integers(1, 9))
    e = rng.integers(0, v.shape[0], n)
    t = rng.choice([0.0, 0.5, rng.uniform()], n)  # vertices, mid-edges, anywhere
    on = v[e] + t[:, None] * (np.roll(v, -1, axis=0)[e] - v[e])
    inner = np.asarray(room.centroid.coords)[0] + 0.5 * (on - room.centroid.coords[0])
    outer = on + rng.uniform(0.01, 1.0, (n, 1)) * (on - room.centroid.coords[0])
    pick = {"inside": 0, "boundary": 1, "outside": 2}.get(where)
    kind = rng.integers(0, 3, n) if pick is None else np.full(n, pick)
    apex = np.choose(kind[:, None], [inner, on, outer])
    cones = _cones_of(rng, n, apex)
    radius = 20.0
    sets = rng.random((5, n)) < 0.6
    got = UnionAreas(ring, cones, n, radius)(sets)
    want = _union_reference(room, cones, sets, radius)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * room.area)


def test_union_areas_rays_along_the_walls_count_once():
    # cameras on the walls of a box looking in with 180 degrees: their cone edges run
    # along the walls, several collinear; and cameras in the corners with 90 degrees
    from tasking.fan import UnionAreas, convex_ring

    room = box(0, 0, 3, 2)
    apex = np.array([[1.0, 0.0], [2.0, 0.0], [3.0, 1.0], [0.0, 0.0], [3.0, 2.0], [1.5, 2.0]])
    t0 = np.array([0.0, 0.0, np.pi / 2, 0.0, np.pi, np.pi])
    t1 = np.array([np.pi, np.pi, 1.5 * np.pi, np.pi / 2, 1.5 * np.pi, 2 * np.pi])
    cones = (np.arange(6), apex, t0, t1)
    sets = np.array([[1, 1, 0, 0, 0, 0], [1, 1, 1, 1, 1, 1], [0, 0, 0, 1, 1, 0],
                     [0, 0, 1, 0, 0, 1], [1, 0, 0, 1, 0, 0]], dtype=bool)
    got = UnionAreas(convex_ring(room), cones, 6, 20.0)(sets)
    np.testing.assert_allclose(got, [6.0] * 5, rtol=0, atol=1e-9)
    # narrow cones from those wall points, one of them grazing its wall
    t1n = t0 + np.array([0.3, 1e-7, 0.4, 0.2, 0.25, 0.1])
    cones = (np.arange(6), apex, t0, t1n)
    got = UnionAreas(convex_ring(room), cones, 6, 20.0)(sets)
    want = _union_reference(room, cones, sets, 20.0)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)


@pytest.mark.parametrize("offset", [(-3e3, 2e3), (5e5, 4e6)])
def test_union_areas_do_not_depend_on_where_the_origin_is(offset):
    # a room in georeferenced coordinates (metres east and north, UTM-like): Green's
    # integrand x dy - y dx of such coordinates cancels to ~1e-3 m^2, and a shrink of
    # 1e-12 of the room's size is below their rounding
    from shapely import affinity

    from tasking.fan import UnionAreas, convex_ring

    rng = np.random.default_rng(7)
    room = box(0, 0, 6.7056, 5.7912)
    apex = np.r_[[[1.0, 0.0], [3.0, 5.7912], [0.0, 2.0], [6.7056, 0.0]], rng.uniform(-1, 7, (5, 2))]
    t0 = np.r_[0.0, np.pi, -np.pi / 2, np.pi / 2, rng.uniform(-np.pi, np.pi, 5)]
    t1 = t0 + np.r_[0.5, np.pi, 0.3, np.pi / 2, rng.uniform(0.1, 0.6, 5)]
    cones = (np.arange(9), apex, t0, t1)
    sets = rng.random((12, 9)) < 0.3
    want = UnionAreas(convex_ring(room), cones, 9, 40.0)(sets)
    moved = (np.arange(9), apex + offset, t0, t1)
    got = UnionAreas(convex_ring(affinity.translate(room, *offset)), moved, 9, 40.0)(sets)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * room.area)


def test_union_areas_of_a_room_whose_ring_repeats_a_vertex():
    """A ring may repeat a vertex (a zero-length edge, as drawn rooms can have): the areas
    are the room's all the same (the zero-length edge's normal would be 0 / 0)."""
    from shapely.geometry import Polygon

    from tasking.fan import UnionAreas, convex_ring

    room = Polygon([(0, 0), (3, 0), (3, 0), (3, 2), (0, 2), (0, 2)])
    rng = np.random.default_rng(11)
    apex = np.r_[[[1.0, 0.0], [3.0, 0.0], [0.0, 1.0]], rng.uniform(0.2, 1.8, (3, 2))]
    t0 = np.r_[0.0, np.pi / 2, -np.pi / 2, rng.uniform(-np.pi, np.pi, 3)]
    cones = (np.arange(6), apex, t0, t0 + np.r_[1.0, 0.8, 2.0, rng.uniform(0.2, 1.5, 3)])
    sets = rng.random((8, 6)) < 0.5
    got = UnionAreas(convex_ring(room), cones, 6, 20.0)(sets)
    np.testing.assert_allclose(got, _union_reference(room, cones, sets, 20.0), rtol=0, atol=1e-9)


def test_cone_areas_of_edges_passing_behind_the_apex_are_zero():
    # the cone is the first quadrant; the triangle lies wholly in x + y <= -1, and its edge
    # from (1, -2) to (-2, 1) crosses both rays' lines behind the apex (first the y = 0
    # line's back half, then the x = 0 one's): inside neither ray's half-plane at once
    tri = Polygon([(1, -2), (-2, 1), (-3, -3)])
    got = cone_areas(*ring_edges(tri), np.zeros((1, 2)), np.zeros(1), np.array([np.pi / 2]))
    assert got.tolist() == [0.0]
    # the same edge as part of a square around the apex: only the quadrant's unit square
    sq = Polygon([(1, -2), (1, 1), (-2, 1)])
    got = cone_areas(*ring_edges(sq), np.zeros((1, 2)), np.zeros(1), np.array([np.pi / 2]))
    assert abs(got[0] - 1.0) < 1e-12


def test_cone_areas_in_blocks_match_shapely(monkeypatch):
    # more cones than one block holds (BLOCK pairs of cone and edge): every block's cones
    # must meet their own apexes
    from tasking import fan

    rng = np.random.default_rng(3)
    poly = Point(0.2, -0.1).buffer(1.0, quad_segs=4)  # 16 edges
    apex = rng.uniform(-1.5, 1.5, (23, 2))
    t0 = rng.uniform(-np.pi, np.pi, 23)
    t1 = t0 + rng.uniform(0.1, np.pi, 23)
    monkeypatch.setattr(fan, "BLOCK", 5 * 16)  # 5 cones per block, the last block 3
    got = cone_areas(*ring_edges(poly), apex, t0, t1)
    want = [poly.intersection(w).area for w in wedge_polygons(apex, t0, t1, 20.0)]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)


def test_convex_ring_accepts_collinear_vertices_and_refuses_dents_and_holes():
    from tasking.fan import convex_ring

    # a vertex on an edge (its turn 0), in either orientation
    ccw = Polygon([(0, 0), (1, 0), (2, 0), (2, 2), (0, 2)])
    cw = Polygon([(0, 0), (0, 2), (2, 2), (2, 0), (1, 0)])
    for room in (ccw, cw):
        assert np.array_equal(convex_ring(room), np.asarray(room.exterior.coords))
    # a vertex at 0.3 of an edge whose rounding makes its turn -9e-17 of the largest
    a, m = (0.5159020047128562, 0.025517446524156107), (0.6826345592247665, -0.8666199824657972)
    b, c = (0.8582084415940123, -0.8678350065518505), (0.618593935777203, -0.24248828939864586)
    assert convex_ring(Polygon([a, m, b, c])) is not None
    # a dent of 1e-3 m in a 1 m square; a hole whose ring would turn the same way throughout
    assert convex_ring(Polygon([(0, 0), (1, 0), (1, 1), (0.5, 0.999), (0, 1)])) is None
    hole = [(3.3506488814064777, 3.324870928249579), (3.3829327123116366, 3.3760437365656712),
            (3.3859556977471463, 3.3914704625655396)]
    assert convex_ring(Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], [hole])) is None


def test_union_areas_ray_along_the_wall_of_a_sharp_corner():
    """A ray along the wall of a 0.0077-rad corner, from outside the room, through a camera
    on that wall: the shrunk ring's corner must move in along its bisector far enough
    (delta / sin(half the angle)) that the ray stays outside it; a shrink of delta along
    the bisector left it within rounding of the walls and counted 12 % of the room twice."""
    from tasking.fan import UnionAreas, convex_ring

    room = Polygon([(0, 0), (3, 0), (1.3054262745459861, 0.01)])
    apex = np.array([[-0.6527131372729931, -0.005], [0.5399832442704986, 0.00413645147795343]])
    cones = (np.arange(2), apex, np.array([-2.425335105150533, -3.133932470399422]),
             np.array([0.00766018319037132, -1.7466250777501744]))  # camera 0 covers it all
    sets = np.array([[1, 0], [0, 1], [1, 1]], dtype=bool)
    got = UnionAreas(convex_ring(room), cones, 2, 20.0)(sets)
    np.testing.assert_allclose(got[[0, 2]], [0.015, 0.015], rtol=0, atol=1e-9 * room.area)
    np.testing.assert_allclose(got[1], _union_reference(room, cones, sets[1:2], 20.0)[0],
                               rtol=0, atol=1e-9 * room.area)


def _aimed_cones(rng, v, centre, n):
    """Cameras on wall lines (at vertices, on walls, beyond them), outside or inside the
    room, their cone edges aimed at vertices or along walls (70 %) or anywhere."""
    V = v.shape[0]
    cam, apx, t0, t1 = [], [], [], []
    for c in range(n):
        e = int(rng.integers(V))
        w = v[(e + 1) % V] - v[e]
        a = [v[e] + rng.choice([-0.5, 0.0, 0.5, 1.0, 1.5]) * w,
             v[e] + rng.uniform(0.05, 1.0) * (v[e] - centre),
             v[e] + rng.uniform(0.1, 0.9) * w,
             centre + 0.5 * (v[e] - centre)][int(rng.integers(4))]
        d = v - a
        aims = [np.arctan2(y, x) for x, y in d[np.hypot(d[:, 0], d[:, 1]) > 1e-9]]
        aims += [np.arctan2(w[1], w[0]), np.arctan2(-w[1], -w[0])]
        ang = [rng.choice(aims) if rng.random() < 0.7 else rng.uniform(-np.pi, np.pi)
               for _ in range(2)]
        width = np.mod(ang[1] - ang[0], 2 * np.pi)
        cam.append(c)
        apx.append(a)
        t0.append(ang[0])
        t1.append(ang[0] + (width if width > 1e-6 else rng.uniform(0.1, 3.0)))
    return split_wide(np.array(cam), np.array(apx), np.array(t0), np.array(t1))


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["box", "hull", "sliver"]))
def test_union_areas_cone_edges_through_vertices_and_along_walls(seed, shape):
    from tasking.fan import UnionAreas, convex_ring

    rng = np.random.default_rng(seed)
    if shape == "box":
        room = box(0, 0, 3, 2)
    elif shape == "hull":
        room = MultiPoint(rng.uniform(-1, 1, (int(rng.integers(3, 12)), 2))).convex_hull
        room = room if room.area >= 0.05 else box(-1, -0.7, 1, 0.7)
    else:  # a thin triangle: sharp corners
        room = Polygon([(0, 0), (3, 0), (rng.uniform(0.2, 2.2), rng.choice([0.01, 0.1, 1.0]))])
    ring = convex_ring(room)
    n = int(rng.integers(1, 7))
    cones = _aimed_cones(rng, ring[:-1], np.asarray(room.centroid.coords[0]), n)
    sets = rng.random((4, n)) < 0.6
    got = UnionAreas(ring, cones, n, 20.0)(sets)
    want = _union_reference(room, cones, sets, 20.0)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * room.area)


def test_union_areas_from_outside_a_triangle_seeing_two_walls():
    # from (1, 3) above the apex of the triangle the near chain (two walls) is longer than
    # the far one (the base): a cone entering only the second near wall, the left one
    from tasking.fan import UnionAreas, convex_ring

    room = Polygon([(0, 0), (2, 0), (1, 2)])
    apex = np.array([[1.0, 3.0], [1.0, 3.0], [1.0, -1.0], [3.0, 3.0], [1.0, 3.0]])
    t0 = np.array([-np.pi / 2 - 1.0, -np.pi / 2 - 0.2, np.pi / 2 - 1.0, -2.4, -1.85])
    t1 = np.array([-np.pi / 2 + 1.0, -np.pi / 2 + 0.3, np.pi / 2 + 1.0, -1.8, -1.65])
    got = UnionAreas(convex_ring(room), (np.arange(5), apex, t0, t1), 5, 20.0)(np.eye(5, dtype=bool))
    want = [room.intersection(w).area for w in wedge_polygons(apex, t0, t1, 20.0)]
    np.testing.assert_allclose(want[0], 2.0, rtol=1e-12)  # cameras 0 and 2 see it all
    np.testing.assert_allclose(want[2], 2.0, rtol=1e-12)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)


def test_union_areas_of_cones_an_ulp_or_two_wide_are_zero():
    # both rays of such a cone leave the room at one point up to rounding (exit theta1
    # can come out just before exit theta0 on the same wall): its arc must be empty, not
    # the whole boundary
    from tasking.fan import UnionAreas, convex_ring

    rng = np.random.default_rng(0)
    for room in (box(0, 0, 3, 2), MultiPoint(rng.uniform(-1, 1, (8, 2))).convex_hull):
        ring, centre = convex_ring(room), np.asarray(room.centroid.coords[0])
        for _ in range(10):
            n = 60
            apex = centre + rng.uniform(-2, 2, (n, 2)) * rng.choice([0.1, 0.3, 3.0], (n, 1))
            t0 = rng.uniform(-np.pi, np.pi, n)
            t1 = t0 + rng.integers(1, 3, n) * np.spacing(np.abs(t0))
            got = UnionAreas(ring, (np.arange(n), apex, t0, t1), n, 20.0)(np.eye(n, dtype=bool))
            assert np.abs(got).max() < 1e-9 * room.area


def test_split_wide_halves_intervals_wider_than_pi():
    # camera 1's 4.5-rad interval becomes two 2.25-rad halves, both on its apex; a
    # half-plane (pi) and narrower intervals are left as they are
    apex = np.array([[0.0, 0.0], [1.0, 2.0], [1.0, 2.0], [3.0, 0.0]])
    cam, apx, t0, t1 = split_wide(np.array([0, 1, 1, 2]), apex, np.array([0.0, 0.0, 4.6, 1.0]),
                                  np.array([3.0, 4.5, 5.0, 1.0 + np.pi]))
    assert cam.tolist() == [0, 1, 1, 1, 2]
    np.testing.assert_array_equal(apx, apex[[0, 1, 1, 2, 3]])
    np.testing.assert_allclose(t0, [0.0, 0.0, 2.25, 4.6, 1.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(t1, [3.0, 2.25, 4.5, 5.0, 1.0 + np.pi], rtol=0, atol=1e-15)


def test_cone_areas_of_a_polygon_with_more_edges_than_a_block(monkeypatch):
    # a block holds fewer (cone, edge) pairs than the polygon has edges: one cone per block
    from tasking import fan

    poly = Point(0.2, -0.1).buffer(1.0, quad_segs=4)  # 16 edges
    apex = np.array([[0.0, 0.0], [1.5, 0.0], [-0.5, -1.5]])
    t0 = np.array([0.3, 2.0, 0.5])
    t1 = t0 + np.array([2.0, 2.5, 1.5])
    monkeypatch.setattr(fan, "BLOCK", 8)
    got = cone_areas(*ring_edges(poly), apex, t0, t1)
    want = [poly.intersection(w).area for w in wedge_polygons(apex, t0, t1, 20.0)]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)


def test_convex_ring_refuses_what_is_not_one_convex_polygon():
    from shapely.geometry import MultiPolygon

    from tasking.fan import convex_ring

    assert convex_ring(Polygon()) is None
    # two boxes side by side: their rings, one after the other, turn one way throughout
    assert convex_ring(MultiPolygon([box(0, 0, 1, 1), box(2, 0, 3, 1)])) is None
    assert convex_ring(box(0, 0, 1, 1).exterior) is None
    # a dent at the ring's first vertex (the turn between its last and first edges)
    assert convex_ring(Polygon([(0.5, 0.1), (1, 0), (1, 1), (0, 1), (0, 0)])) is None
    # a dent of 1e-7 m in a 1 m square: 5e-8 m^2, 50 times the areas' accuracy (1e-9 of
    # the room's area)
    assert convex_ring(Polygon([(0, 0), (1, 0), (1, 1), (0.5, 1 - 1e-7), (0, 1)])) is None


@pytest.mark.parametrize("rot", [0.0, 0.0730470885143677, 0.5, 1.3, 2.9, 4.4])
@pytest.mark.parametrize("order", [(0, 1), (1, 0)])
def test_union_areas_count_a_theta0_and_a_theta1_ray_along_one_segment_once(rot, order):
    # camera A at (0, 0) sees [0, pi/2], B at (1, 0) sees [pi/2, pi] (box and cameras
    # turned by rot): A's theta0 ray and B's theta1 ray share the segment from A to B, both
    # cones above it; the union is the room's upper part, 5 x 2, whichever camera is lower
    from shapely import affinity

    from tasking.fan import UnionAreas, convex_ring

    c, s = np.cos(rot), np.sin(rot)
    room = affinity.rotate(box(-2, -1, 3, 2), rot, origin=(0, 0), use_radians=True)
    apex = np.array([[0.0, 0.0], [c, s]])
    cones = (np.array(order), apex, np.array([0.0, np.pi / 2]) + rot,
             np.array([np.pi / 2, np.pi]) + rot)
    got = UnionAreas(convex_ring(room), cones, 2, 20.0)(np.array([[1, 0], [0, 1], [1, 1]], bool))
    np.testing.assert_allclose(got, [6.0, 6.0, 10.0], rtol=0, atol=1e-9)


def test_union_areas_of_one_set_given_as_a_flat_row():
    from tasking.fan import UnionAreas, convex_ring

    cones = (np.array([0, 1]), np.array([[0.0, 0.0], [2.0, 0.0]]),
             np.array([0.0, np.pi / 2]), np.array([np.pi / 4, np.pi]))
    ua = UnionAreas(convex_ring(box(0, 0, 2, 2)), cones, 2, 10.0)
    np.testing.assert_allclose(ua([True, False]), [2.0], rtol=0, atol=1e-9)
