"""Visual hull geometry: hand-computable cases, hypothesis properties, error cases."""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import GeometryCollection, LineString, Point, Polygon, box
from test_tasking_common import circle_room, random_discs, ring_cameras, scanlines_from_discs

from tasking import (
    camera_regions_from_discs,
    camera_regions_from_scanlines,
    empty_regions_from_discs,
    free_wedges_from_discs,
    free_wedges_from_scanlines,
    hull_from_wedges,
    polygon_centres,
    prune_small,
    visual_hull_of_discs,
    visual_hull_of_scanlines,
)

SQUARE = box(-1, -1, 1, 1)
R = 0.1
TAN = np.tan(np.arcsin(R / 1.0))  # half-angle asin(r / d) at d = 1


def sym_diff_area(a, b):
    return a.symmetric_difference(b).area


# --- hand-computable cases ------------------------------------------------------------


def test_one_disc_one_camera_is_the_tangent_wedge():
    # camera on the left wall looking +x at a disc 1 m away: a triangle of height 2 whose
    # half-angle is asin(r / d); area = 0.5 * 2 * (2 * 2 tan) = 4 tan.
    hull = visual_hull_of_discs([[-1, 0]], [0.0], np.pi, [[0, 0]], R, SQUARE)
    assert hull.area == pytest.approx(4 * TAN, rel=1e-12)
    expected = Polygon([(-1, 0), (1, 2 * TAN), (1, -2 * TAN)])
    assert sym_diff_area(hull, expected) < 1e-12
    # its edges are tangent to the disc
    assert hull.exterior.distance(Point(0, 0)) == pytest.approx(R, abs=1e-12)


def test_two_opposite_cameras_give_a_rhombus():
    hull = visual_hull_of_discs([[-1, 0], [1, 0]], [0.0, np.pi], np.pi, [[0, 0]], R, SQUARE)
    expected = Polygon([(-1, 0), (0, TAN), (1, 0), (0, -TAN)])
    assert hull.area == pytest.approx(2 * TAN, rel=1e-12)
    assert sym_diff_area(hull, expected) < 1e-12


def test_fov_missing_the_object_leaves_the_room_unconstrained_there():
    half = np.radians(49) / 2
    hull = visual_hull_of_discs([[0, -1]], [np.pi / 2], np.radians(49), [[0.8, 0.0]], R, SQUARE)
    sector = Polygon([(0, -1), (2 * np.tan(half), 1), (-2 * np.tan(half), 1)])
    assert hull.area == pytest.approx(4 - sector.area, rel=1e-12)
    assert sym_diff_area(hull, SQUARE.difference(sector)) < 1e-12
    assert hull.contains(Point(0.8, 0.0).buffer(R))


def test_180_degree_camera_on_the_boundary_sees_a_half_plane():
    # no objects at all: the camera proves its half of the room empty
    hull = visual_hull_of_discs([[0, -1]], [0.0], np.pi, np.empty((0, 2)), R, SQUARE)
    assert sym_diff_area(hull, box(-1, -1, 0, 1)) < 1e-12


def test_overlapping_cones_of_one_camera_merge():
    centres = np.array([[0.0, 0.0], [0.5, 0.03]])
    hull = visual_hull_of_discs([[-1, 0]], [0.0], np.pi, centres, R, SQUARE)
    far = 10.0

    def cone(c):
        d = np.hypot(c[0] + 1, c[1])
        b, h = np.arctan2(c[1], c[0] + 1), np.arcsin(R / d)
        return Polygon([(-1, 0), (-1 + far * np.cos(b - h), far * np.sin(b - h)),
                        (-1 + far * np.cos(b + h), far * np.sin(b + h))])

    expected = SQUARE.intersection(cone(centres[0]).union(cone(centres[1])))
    assert sym_diff_area(hull, expected) < 1e-12
    assert len(getattr(hull, "geoms", [hull])) == 1


def test_camera_regions_intersect_to_the_hull():
    room = circle_room()
    xy, yaw = ring_cameras(6)
    centres = random_discs(np.random.default_rng(1), 4)
    regions = camera_regions_from_discs(xy, yaw, np.pi, centres, R, room)
    hull = visual_hull_of_discs(xy, yaw, np.pi, centres, R, room)
    assert len(regions) == 6
    assert sym_diff_area(shapely.intersection_all([room, *regions]), hull) < 1e-10
    empties = empty_regions_from_discs(xy, yaw, np.pi, centres, R, room)
    assert sym_diff_area(room.difference(shapely.union_all(empties)), hull) < 1e-10


def test_prune_small_and_centres():
    geom = GeometryCollection(
        [box(0, 0, 1, 1), box(2, 2, 2.1, 2.1), LineString([(5, 5), (6, 6)]), Point(9, 9)]
    )
    kept = prune_small(geom, 0.5)
    assert [p.area for p in kept] == [1.0]
    assert polygon_centres(kept).tolist() == [[0.5, 0.5]]
    assert polygon_centres([]).shape == (0, 2)
    rows = polygon_centres([box(0, 0, 1, 1), Polygon(), box(2, 2, 3, 3)])   # rows stay aligned
    np.testing.assert_array_equal(rows, [[0.5, 0.5], [np.nan, np.nan], [2.5, 2.5]])
    assert len(prune_small(Polygon(), 0.0)) == 0


# --- hypothesis properties ------------------------------------------------------------

scenes = st.fixed_dictionaries(
    {
        "seed": st.integers(0, 2**32 - 1),
        "n": st.integers(1, 10),
        "m": st.integers(1, 6),
        "fov": st.floats(0.3, 2 * np.pi - 0.3),
        "inside": st.booleans(),
    }
)


def build(scene):
    """A random circular-room scene: cameras on the rim (or inside), random yaws."""
    rng = np.random.default_rng(scene["seed"])
    room = circle_room()
    centres = random_discs(rng, scene["m"])
    xy, yaw = ring_cameras(scene["n"], phase=rng.uniform(0, 2 * np.pi))
    if scene["inside"]:  # cameras anywhere inside the room, clear of the objects
        pts = []
        while len(pts) < scene["n"]:
            p = rng.uniform(-1, 1, 2)
            if np.hypot(*p) < 1 and np.all(np.hypot(*(centres - p).T) > R + 0.01):
                pts.append(p)
        xy = np.array(pts)
    yaw = yaw + rng.normal(0, 0.3, scene["n"])
    return room, xy, yaw, scene["fov"], centres


def object_union(centres, room):
    return shapely.union_all([Point(c).buffer(R, quad_segs=32) for c in centres]).intersection(
        room
    )


@settings(max_examples=40, deadline=None)
@given(scenes)
def test_hull_contains_every_object_and_is_at_least_their_area(scene):
    room, xy, yaw, fov, centres = build(scene)
    hull = visual_hull_of_discs(xy, yaw, fov, centres, R, room)
    objects = object_union(centres, room)
    assert objects.difference(hull).area < 1e-9
    assert hull.area >= objects.area - 1e-9


@settings(max_examples=40, deadline=None)
@given(scenes)
def test_room_minus_each_wedge_set_is_the_room_minus_their_union(scene):
    """The two orders of hull_from_wedges (few cameras / many) give one region."""
    from tasking import hull as hull_module

    room, xy, yaw, fov, centres = build(scene)
    wedges = free_wedges_from_discs(xy, yaw, fov, centres, R, room)
    one_by_one = hull_from_wedges(wedges, room)
    limit = hull_module.SEQUENTIAL_MAX
    try:
        hull_module.SEQUENTIAL_MAX = 0
        united = hull_from_wedges(wedges, room)
    finally:
        hull_module.SEQUENTIAL_MAX = limit
    assert sym_diff_area(one_by_one, united) < 1e-12 * room.area
    assert abs(one_by_one.area - united.area) < 1e-12 * room.area


def test_dataset_hull_record_does_not_depend_on_the_overlay_order():
    """gt_hull.json holds polygons in normal form: rings that start elsewhere give the same record."""
    from testbed.episodes import hull_record

    square = Polygon([(0, 0), (2, 0), (2, 2), (0, 2)], [[(0.5, 0.5), (1, 0.5), (1, 1), (0.5, 1)]])
    turned = Polygon([(2, 2), (0, 2), (0, 0), (2, 0)], [[(1, 1), (0.5, 1), (0.5, 0.5), (1, 0.5)]])
    far = box(5, 5, 6, 6)
    assert hull_record(3, shapely.union_all([square, far])) == hull_record(3, shapely.MultiPolygon([far, turned]))
    rec = hull_record(3, square)
    assert rec["area"] == 3.75 and len(rec["polygons"]) == 1 and len(rec["polygons"][0]["holes"]) == 1
    assert hull_record(0, Polygon())["polygons"] == []


def test_dataset_hull_record_rounds_vertices_to_a_micrometre_and_area_to_1e9():
    """gt_hull.json: vertices in metres to 1e-6 m, the area in m^2 to 1e-9 m^2, of the unrounded polygon."""
    from testbed.episodes import hull_record

    tri = Polygon([(0, 0), (1 / 3, 0), (0, 2 / 3)])                 # area 1/9
    rec = hull_record(7, tri)
    assert rec["frame"] == 7 and rec["area"] == 0.111111111
    (poly,) = rec["polygons"]
    assert poly["holes"] == []
    assert sorted(map(tuple, poly["exterior"])) == [(0.0, 0.0), (0.0, 0.0), (0.0, 0.666667), (0.333333, 0.0)]


@settings(max_examples=30, deadline=None)
@given(scenes, st.integers(0, 9))
def test_adding_a_camera_never_grows_the_hull(scene, extra):
    room, xy, yaw, fov, centres = build(scene)
    n = xy.shape[0]
    if n < 2:
        return
    drop = extra % n
    keep = np.delete(np.arange(n), drop)
    small = visual_hull_of_discs(xy[keep], yaw[keep], fov, centres, R, room)
    full = visual_hull_of_discs(xy, yaw, fov, centres, R, room)
    assert full.area <= small.area + 1e-12
    assert full.difference(small).area < 1e-10


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 8), st.integers(1, 5))
def test_scanlines_agree_with_discs_at_fine_resolution(seed, n, m):
    # Columns are marked occupied when they meet a cone, so the scanline hull contains
    # the disc hull and every cone edge moves out by at most one column step (pi / W).
    # Cone half-angles are >= asin(0.1 / 2) = 0.05 rad, so W = 3000 widens each cone by
    # at most ~2 %; hull areas (intersections of such cones) agree within ~5 %.
    rng = np.random.default_rng(seed)
    room = circle_room()
    centres = random_discs(rng, m)
    xy, yaw = ring_cameras(n, phase=rng.uniform(0, 2 * np.pi))
    disc_hull = visual_hull_of_discs(xy, yaw, np.pi, centres, R, room)
    bearings, occ = scanlines_from_discs(xy, yaw, np.pi, centres, R, 3000)
    scan_hull = visual_hull_of_scanlines(xy, bearings, occ, room)
    assert disc_hull.difference(scan_hull).area < 1e-9
    assert scan_hull.area == pytest.approx(disc_hull.area, rel=0.05)
    # increasing bearings (columns reversed) and bearings wrapped to [-pi, pi) agree
    wrapped = (bearings[:, ::-1] + np.pi) % (2 * np.pi) - np.pi
    again = visual_hull_of_scanlines(xy, wrapped, occ[:, ::-1], room)
    assert sym_diff_area(again, scan_hull) < 1e-10


def test_scanline_hand_case_and_regions():
    # one camera, 4 columns spanning [-pi/2, pi/2] around yaw 0; column 2 occupied:
    # the occluded interval is [0, pi/4] -> the wedge between 0 and 45 degrees.
    step = np.pi / 4
    bearings = np.array([[-1.5, -0.5, 0.5, 1.5]]) * step
    occ = np.array([[False, False, True, False]])
    hull = visual_hull_of_scanlines([[-1, 0]], bearings, occ, SQUARE)
    assert sym_diff_area(hull, Polygon([(-1, 0), (1, 0), (1, 1), (0, 1)])) < 1e-12
    regions = camera_regions_from_scanlines([[-1, 0]], bearings, occ, SQUARE)
    assert sym_diff_area(regions[0], hull) < 1e-12


# --- errors ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(centers=[[0, 0], [0.1, 0]]), "overlap"),
        (dict(centers=[[3, 0]]), "outside the room"),
        (dict(camera_xy=[[0.05, 0]], camera_yaw=[0.0]), "camera 0 is inside object 0"),
        (dict(camera_xy=np.empty((0, 2)), camera_yaw=np.empty(0)), "camera_xy must not be empty"),
        (dict(camera_xy=[[np.nan, 0]]), "camera_xy must be finite"),
        (dict(centers=[[np.nan, 0]]), "centers must be finite"),
        (dict(fov=0.0), "fov must be in"),
        (dict(fov=-1.0), "fov must be in"),
        (dict(fov=2 * np.pi), "fov must be in"),
        (dict(fov=[1.0, 1.0]), r"fov must be a scalar or have shape \(1,\)"),
        (dict(camera_yaw=[0.0, 1.0]), r"camera_yaw must have shape \(1,\)"),
        (dict(camera_xy=[1.0, 0.0]), r"camera_xy must have shape \(n, 2\)"),
        (dict(radii=[0.1, 0.1]), r"radii must be a scalar or have shape \(1,\)"),
        (dict(radii=0.0), "radii must be finite and > 0"),
        (dict(room="square"), "room must be a shapely Polygon"),
    ],
)
def test_disc_errors(kwargs, match):
    args = dict(
        camera_xy=[[-1, 0]], camera_yaw=[0.0], fov=np.pi, centers=[[0, 0]], radii=R, room=SQUARE
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        visual_hull_of_discs(**args)


@pytest.mark.parametrize(
    "bearings, occ, match",
    [
        ([[0.0, 0.1, 0.2]], [[True, False]], "scanlines must have the shape"),
        ([[0.0, 0.1]], [[1, 0]], "scanlines must be a bool array"),
        ([[0.0, 0.2, 0.1]], [[True, False, True]], "strictly monotone"),
        ([[0.0]], [[True]], r"bearings must have shape \(1, W\) with W >= 2"),
        ([0.3], [True], r"bearings must have shape \(1, W\) with W >= 2"),         # 1-d, one per camera
        ([[0.0, 0.1], [0.0, 0.1]], [[True, False]] * 2, r"bearings must have shape \(1, W\)"),   # two rows, one camera
        ([[0.0, np.nan]], [[True, False]], "bearings must be finite"),
        ([[0.0, 3.0, 6.0]], [[True, False, True]], "span less than 2\\*pi"),
    ],
)
def test_scanline_errors(bearings, occ, match):
    with pytest.raises(ValueError, match=match):
        visual_hull_of_scanlines([[-1, 0]], np.array(bearings), np.array(occ), SQUARE)


@pytest.mark.parametrize("min_area", [-1.0, np.nan, np.inf])
def test_prune_small_rejects_negative_area(min_area):
    with pytest.raises(ValueError, match="min_area must be finite and >= 0"):
        prune_small(SQUARE, min_area)


@pytest.mark.parametrize("behind", [np.pi, np.pi - 0.05, -np.pi + 0.05])
def test_wide_camera_sees_an_object_straddling_the_direction_behind_it(behind):
    """A cone that wraps through +-pi (object behind a camera of fov > pi) is clipped on both
    ends of the field of view: without the 2*pi shifts of clip_to_fov half of it was free."""
    xy, yaw, fov = np.array([[0.0, 0.0]]), np.array([0.0]), 2 * np.pi - 0.2
    centre = 0.3 * np.array([np.cos(behind), np.sin(behind)])
    hull = visual_hull_of_discs(xy, yaw, fov, [centre], R, circle_room())
    disc = Point(centre).buffer(R, quad_segs=64)
    assert disc.difference(hull).area < 1e-9


def test_a_camera_inside_an_estimated_disc_proves_nothing_empty():
    """Docs: "a camera inside one is blind" (strict=False). asin(1) = pi/2 would leave it
    proving the half of its view away from the disc empty."""
    xy, yaw = ring_cameras(2)
    inside = xy[0] + [0.0, 0.05]                # 0.05 m beside camera 0 (disc radius 0.1)
    wedges = free_wedges_from_discs(xy, yaw, np.pi, [inside], R, circle_room(), strict=False)
    assert wedges[0].is_empty
    assert not wedges[1].is_empty


@pytest.mark.parametrize("near", [0.9, 0.995, 0.999, 0.9999])
def test_near_and_far_wedges_stay_between_the_two_circles_when_they_nearly_meet(near):
    """A camera proves empty only what lies between its blind radius and its sight radius,
    also when the two nearly meet (wedges whose inner chords would cross the outer ones are
    dropped, not drawn inside out)."""
    from shapely.geometry import box

    from tasking import visual_hull_of_scanlines

    room = box(-3, -3, 3, 3)
    bearings = np.linspace(0.4, -0.4, 64)[None]
    hull = visual_hull_of_scanlines([[0.0, 0.0]], bearings, np.zeros((1, 64), bool), room, near=near, far=1.0)
    empty = room.difference(hull)
    assert empty.intersection(Point(0, 0).buffer(near, quad_segs=256)).area < 1e-12
    assert empty.difference(Point(0, 0).buffer(1.0 + 1e-6, quad_segs=1024)).area < 1e-12   # polygon of the circle: outside it


@settings(max_examples=200, deadline=None)
@given(yaw=st.floats(-np.pi, np.pi), fov=st.floats(0.05, 2 * np.pi - 1e-3),
       rel=st.lists(st.tuples(st.floats(-np.pi, np.pi), st.floats(0.15, 1.5)), min_size=1, max_size=4))
def test_free_wedges_never_meet_an_object_whatever_its_bearing(yaw, fov, rel):
    """The core safety property, drawn in the camera's own frame so that objects behind it,
    straddling +-pi, and at the edges of fields of view up to 2*pi are all exercised."""
    from shapely.geometry import box

    room = box(-3, -3, 3, 3)
    centres = np.array([[d * np.cos(yaw + a), d * np.sin(yaw + a)] for a, d in rel])
    keep = [0]
    for i in range(1, len(centres)):                       # disjoint discs only
        if np.all(np.hypot(*(centres[keep] - centres[i]).T) > 2 * R):
            keep.append(i)
    centres = centres[keep]
    wedges = free_wedges_from_discs([[0.0, 0.0]], [yaw], fov, centres, R, room)
    for c in centres:
        disc = Point(c).buffer(R * (1 - 1e-9), quad_segs=32)    # inscribed polygon, just inside
        assert wedges[0].intersection(disc).area < 1e-12


def test_polygon_centres_refuses_what_is_not_a_polygon():
    """A multi-part polygon's centroid lies between its parts (two objects' hull gave one
    centre in neither); a single geometry is not a sequence of polygons."""
    from shapely.geometry import MultiPolygon

    two = MultiPolygon([box(0, 0, 1, 1), box(2, 0, 3, 1)])
    with pytest.raises(ValueError, match=r"polygons\[1\] is a MultiPolygon, not a Polygon.*prune_small"):
        polygon_centres([box(0, 0, 1, 1), two])
    with pytest.raises(ValueError, match=r"polygons\[0\] is a LineString"):
        polygon_centres([LineString([(0, 0), (1, 1)])])
    with pytest.raises(ValueError, match=r"polygons: expected a sequence of Polygons, got one MultiPolygon.*prune_small"):
        polygon_centres(two)
    with pytest.raises(ValueError, match="polygons: expected a sequence of Polygons, got one Polygon"):
        polygon_centres(box(0, 0, 1, 1))
    np.testing.assert_array_equal(polygon_centres(prune_small(two, 0.0)), [[0.5, 0.5], [2.5, 0.5]])


@pytest.mark.parametrize("offset, xy, yaw, fov", [
    # a georeferenced room (metres east, north) with two cameras in it
    ((5e5, 4e6), [[0.4, 1.8], [3.2, 1.8]], [1.3, -1.8], np.pi),
    # four cameras a kilometre away from a 4 x 3 m room and one on its wall
    ((0.0, 0.0), [[998.0, 91.0], [-199.0, -978.0], [-799.0, 600.0], [-998.0, 13.0], [4.9, 1.1]],
     [-1.8, 2.6, -1.8, 0.4, 0.6], 6.28),
])
def test_hull_overlays_hold_for_coordinates_large_against_the_room(offset, xy, yaw, fov):
    """The snap-rounding grid is 1e-13 of the room's size: below the rounding of
    coordinates millions of metres from the origin, or of wedges a kilometre long, GEOS's
    overlay stopped with 'TopologyException: side location conflict'."""
    from shapely import affinity

    room, centre = box(0, 0, 4, 3), np.array([[2.0, 1.5]])
    hull = visual_hull_of_discs(np.add(xy, offset), yaw, fov, centre + offset, 0.3, affinity.translate(room, *offset))
    hull = affinity.translate(hull, -offset[0], -offset[1])
    assert Point(2.0, 1.5).buffer(0.3 * (1 - 1e-9), quad_segs=32).difference(hull).area < 1e-9
    if any(offset):
        assert sym_diff_area(hull, visual_hull_of_discs(xy, yaw, fov, centre, 0.3, room)) < 1e-6


@pytest.mark.parametrize("reverse", [False, True])
def test_an_empty_scanline_proves_empty_its_field_of_view_and_nothing_beside_it(reverse):
    """A camera in the middle of the room: what lies outside its field of view (the span of
    its column edges) stays in the hull. Cameras on the wall with 180 degrees cannot show
    this: the room behind them is outside it anyway."""
    bearings = np.array([[-1.5, -0.5, 0.5, 1.5]]) * np.pi / 8     # column edges -pi/4 .. pi/4
    if reverse:
        bearings = bearings[:, ::-1]
    hull = visual_hull_of_scanlines([[0.0, 0.0]], bearings, np.zeros((1, 4), bool), SQUARE)
    seen = Polygon([(0, 0), (1, -1), (1, 1)])
    assert sym_diff_area(hull, SQUARE.difference(seen)) < 1e-12


@pytest.mark.parametrize("bad, match", [
    ([0.0, 0.1, 0.1, 0.2], r"strictly monotone along each row \(row 1\)"),    # a repeated bearing
    ([0.3, 0.2, 0.2, 0.1], r"strictly monotone along each row \(row 1\)"),
    ([0.0, 0.2, 0.1, 0.3], r"strictly monotone along each row \(row 1\)"),
    ([0.0, 2.0, 4.0, 6.0], r"span less than 2\*pi"),
])
def test_scanline_errors_of_a_camera_beside_a_good_one(bad, match):
    """Every camera's row is checked, not only as a whole: camera 0 is fine, camera 1 not."""
    bearings = np.array([[0.0, 0.1, 0.2, 0.3], bad])
    with pytest.raises(ValueError, match=match):
        visual_hull_of_scanlines([[-1, 0], [1, 0]], bearings, np.zeros((2, 4), bool), SQUARE)


@pytest.mark.parametrize("reverse", [False, True])
def test_occupied_columns_at_both_edges_of_the_image_stay_occluded(reverse):
    """The outer columns' edges extrapolate the first and last column steps: a camera on the
    left wall with its first and last of 4 columns occupied frees only [-pi/4, pi/4]."""
    bearings = np.array([[-1.5, -0.5, 0.5, 1.5]]) * np.pi / 4
    occ = np.array([[True, False, False, True]])
    if reverse:
        bearings, occ = bearings[:, ::-1], occ[:, ::-1]
    hull = visual_hull_of_scanlines([[-1.0, 0.0]], bearings, occ, SQUARE)
    corners = Polygon([(-1, 0), (-1, 1), (0, 1)]).union(Polygon([(-1, 0), (-1, -1), (0, -1)]))
    assert sym_diff_area(hull, corners) < 1e-12


def test_drop_slivers_drops_only_the_slivers_of_a_many_part_hull():
    """Docs: parts of area <= SLIVER * room.area are dropped; the other parts all stay,
    whatever their number, and the threshold grows with the room (100 x 100 m here)."""
    from tasking.hull import SLIVER, drop_slivers

    room = box(0, 0, 100, 100)
    a, b = box(1, 1, 2, 2), box(5, 5, 6, 7)
    sliver = box(50, 50, 50 + 1e-5, 50 + 1e-5)      # 1e-10 m^2 < SLIVER * room.area
    bigger = box(60, 60, 60 + 1e-3, 60 + 1e-3)      # 1e-6 m^2 > SLIVER * room.area
    assert sliver.area < SLIVER * room.area < bigger.area
    stray = [LineString([(0, 0), (3, 3)]), Point(9, 9)]
    for parts, want in [([a, sliver, b, *stray], [a, b]), ([sliver, a, bigger, b], [a, bigger, b]),
                        ([a, sliver], [a]), ([sliver, *stray], [])]:
        got = drop_slivers(GeometryCollection(parts), room)
        assert shapely.get_num_geometries(got) == len(want)
        assert sym_diff_area(got, shapely.union_all(want)) == 0.0


@pytest.mark.parametrize("scale", [0.05, 0.2, 30.0])
def test_the_hull_scales_with_the_scene(scale):
    """Metres are not special: the paper's scene shrunk to a 5 cm room (or grown to 30 m)
    has the paper-scale hull shrunk (grown) with it; the wedges reach across any room."""
    from shapely import affinity

    xy, yaw = ring_cameras(8)
    centres = np.array([[0.3, 0.2], [-0.4, -0.1], [0.1, -0.5]])
    hull = visual_hull_of_discs(xy, yaw, np.pi, centres, R, circle_room())
    small = visual_hull_of_discs(scale * xy, yaw, np.pi, scale * centres, scale * R,
                                 affinity.scale(circle_room(), scale, scale, origin=(0, 0)))
    expected = affinity.scale(hull, scale, scale, origin=(0, 0))
    assert sym_diff_area(small, expected) < 1e-12 * scale**2


@pytest.mark.parametrize("where", [(1000.0, 1.5), (2.0, -700.0), (-300.0, 400.0)])
def test_a_camera_far_outside_the_room_proves_all_of_it_empty(where):
    """Wedges reach the room from wherever the camera is: a camera hundreds of metres
    away whose narrow field of view holds the whole 4 x 3 m room, and no object, leaves
    no hull; beside a camera on the wall, too."""
    room = box(0, 0, 4, 3)
    xy = np.array([where])
    yaw = np.arctan2(1.5 - xy[:, 1], 2.0 - xy[:, 0])
    hull = visual_hull_of_discs(xy, yaw, 0.05, np.empty((0, 2)), R, room)
    assert hull.area < 1e-9
    both = visual_hull_of_discs([[0.0, 1.5], where], [0.0, yaw[0]], [0.05, 0.05], np.empty((0, 2)), R, room)
    assert both.area < 1e-9


# --- cones.py: hand values of its pieces ------------------------------------------------


def test_a_camera_on_a_discs_rim_is_occluded_by_a_half_plane():
    # at d = r the tangent lines are the rim's tangent: the disc hides a half-plane,
    # bearing +- pi/2; only a camera strictly inside is blind (+- pi)
    from tasking.cones import disc_intervals

    lo, hi = disc_intervals(np.array([[0.0, 0.0], [0.0, 0.1]]), np.array([0.0, 0.0]),
                            np.array([[0.0, 0.5]]), np.array([0.5]))
    np.testing.assert_allclose([lo[0, 0], hi[0, 0]], [0.0, np.pi], atol=1e-12)
    np.testing.assert_allclose(hi[1, 0] - lo[1, 0], 2 * np.pi, atol=1e-12)


def test_free_intervals_drop_gaps_of_min_gap_and_narrower():
    from tasking.cones import MIN_GAP, free_intervals

    # gaps between the occlusions and the FOV edge of 0.5 * MIN_GAP, exactly MIN_GAP
    # (0.0 to 1e-10) and 10 * MIN_GAP
    lo = np.array([[-1.0 + 0.5 * MIN_GAP, MIN_GAP, 0.5]])
    hi = np.array([[0.0, 0.5 - 10 * MIN_GAP, 0.9]])
    cam, a0, a1 = free_intervals(lo, hi, np.array([1.0]))
    assert cam.tolist() == [0, 0]
    np.testing.assert_allclose(a0, [0.5 - 10 * MIN_GAP, 0.9], rtol=0, atol=1e-15)
    np.testing.assert_allclose(a1, [0.5, 1.0], rtol=0, atol=1e-15)


def test_wedge_radius_is_twice_the_diagonal_of_the_box_with_the_cameras_plus_one():
    from tasking.cones import wedge_radius

    assert wedge_radius(box(0, 0, 3, 4), np.array([[0.0, 0.0], [3.0, 1.0]])) == 11.0
    # a camera outside widens the box to (-3, 0)-(3, 8): diagonal 10
    assert wedge_radius(box(0, 0, 3, 4), np.array([[-3.0, 8.0]])) == 21.0


def test_free_intervals_keep_a_gap_of_two_tenths_of_a_nanoradian_by_default():
    """The default min_gap is 1e-10 rad: a gap of 2e-10 rad at the FOV edge stays, one of
    5e-11 rad between two occlusions goes."""
    from tasking.cones import free_intervals

    lo = np.array([[-0.5, 0.2 + 5e-11]])
    hi = np.array([[0.2, 1.0 - 2e-10]])
    cam, a0, a1 = free_intervals(lo, hi, np.array([1.0]))
    assert cam.tolist() == [0, 0]
    np.testing.assert_allclose(a0, [-1.0, 1.0 - 2e-10], rtol=0, atol=1e-16)
    np.testing.assert_allclose(a1, [-0.5, 1.0], rtol=0, atol=1e-16)


def test_column_edges_extrapolate_each_ends_own_step():
    """Columns at 0, 1, 3 and 6 rad: the outer edges lie half the first step (1) before the
    first column and half the last step (3) after the last."""
    from tasking.cones import column_edges

    edges = column_edges(np.array([[0.0, 1.0, 3.0, 6.0], [6.0, 3.0, 1.0, 0.0]]))
    np.testing.assert_allclose(edges, [[-0.5, 0.5, 2.0, 4.5, 7.5], [7.5, 4.5, 2.0, 0.5, -0.5]],
                               rtol=0, atol=1e-15)


def test_scanline_intervals_by_hand():
    """Three cameras of four columns with uneven steps. Row 0 decreases through -pi: its
    columns, in increasing order, are at u = 2.6, 3.0, 3.2, 3.4 rad less 2*pi, with edges at
    2.4, 2.8, 3.1, 3.3, 3.5; the field of view is 1.1 rad about 2.95 rad (wrapped into
    [-pi, pi)), and its runs (u = 2.6-3.0 and 3.4) occlude -0.55..0.15 and 0.35..0.55.
    Row 1 (columns 0, 0.1, 0.3, 0.6; edges -0.05, 0.05, 0.2, 0.45, 0.75) has one run, of
    its middle columns, and row 2 none: their unused slots are (-fov/2, -fov/2)."""
    from tasking.cones import scanline_intervals, wrap_angle

    u = np.array([2.6, 3.0, 3.2, 3.4])
    bearings = np.array([wrap_angle(u)[::-1], [0.0, 0.1, 0.3, 0.6], [1.0, 1.1, 1.2, 1.3]])
    scanlines = np.array([[True, False, True, True], [False, True, True, False], [False] * 4])
    yaw, fov, lo, hi = scanline_intervals(bearings, scanlines)
    np.testing.assert_allclose(yaw, [2.95, 0.35, 1.15], rtol=0, atol=1e-12)
    np.testing.assert_allclose(fov, [1.1, 0.8, 0.4], rtol=0, atol=1e-12)
    np.testing.assert_allclose(lo, [[-0.55, 0.35], [-0.3, -0.4], [-0.2, -0.2]], rtol=0, atol=1e-12)
    np.testing.assert_allclose(hi, [[0.15, 0.55], [0.1, -0.4], [-0.2, -0.2]], rtol=0, atol=1e-12)


def test_clip_to_fov_by_hand():
    """Half FOV 1 rad. (0.5, 0.8) is kept as it is; (2, 2.5) lies beyond the FOV in every
    copy; (2, 5.8) reaches into it only shifted by -2*pi, as (-1, 5.8 - 2*pi). Every empty
    result is (-1, -1), including those clipped to the edge +1. Slots: the K intervals
    unshifted, then shifted by -2*pi, then by +2*pi."""
    from tasking.cones import clip_to_fov

    lo, hi = clip_to_fov(np.array([[0.5, 2.0, 2.0]]), np.array([[0.8, 2.5, 5.8]]), np.array([1.0]))
    e = -1.0
    np.testing.assert_allclose(lo, [[0.5, e, e, e, e, -1.0, e, e, e]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(hi, [[0.8, e, e, e, e, 5.8 - 2 * np.pi, e, e, e]], rtol=0, atol=1e-15)


def test_a_wedge_without_near_field_has_nine_points_on_its_far_arc():
    """A quarter wedge from (1, 1) of radius 2: the apex, nine points on the arc 2 m away,
    the apex again; its area is eight isosceles triangles of apex angle pi/16."""
    from tasking.cones import wedge_polygons

    (w,) = wedge_polygons(np.array([[1.0, 1.0]]), np.array([0.0]), np.array([np.pi / 2]), 2.0)
    ang = np.linspace(0.0, np.pi / 2, 9)
    want = np.r_[[[0.0, 0.0]], 2.0 * np.c_[np.cos(ang), np.sin(ang)], [[0.0, 0.0]]] + 1.0
    np.testing.assert_allclose(np.asarray(w.exterior.coords), want, rtol=0, atol=1e-12)
    assert abs(w.area - 0.5 * 8 * np.sin(np.pi / 16) * 2.0**2) < 1e-12


def test_wedge_polygons_with_near_and_far_radii_by_hand():
    # a quarter wedge from (1, 1), inner 0.5, sight radius 3 beyond the wedge length 2:
    # the far arc is at 2; ARC_POINTS on each arc, the inner arc at 0.5 / cos(step / 2)
    from tasking.cones import ARC_POINTS, wedge_polygons

    (w,) = wedge_polygons(np.array([[1.0, 1.0]]), np.array([0.0]), np.array([np.pi / 2]), 2.0,
                          inner=np.array([0.5]), outer=np.array([3.0]))
    xy = np.asarray(w.exterior.coords)
    assert xy.shape == (2 * ARC_POINTS + 1, 2)
    ang = np.linspace(0.0, np.pi / 2, ARC_POINTS)
    r_in = 0.5 / np.cos(np.pi / 4 / (ARC_POINTS - 1))
    want = np.r_[np.c_[np.cos(ang), np.sin(ang)] * 2.0, np.c_[np.cos(ang), np.sin(ang)][::-1] * r_in,
                 [[2.0, 0.0]]] + 1.0
    np.testing.assert_allclose(xy, want, atol=1e-12)
    # both arcs' chords: (n - 1) isosceles triangles of apex angle step, out minus in
    step = np.pi / 2 / (ARC_POINTS - 1)
    area = 0.5 * (ARC_POINTS - 1) * np.sin(step) * (2.0**2 - r_in**2)
    assert abs(w.area - area) < 1e-12


def test_prune_small_keeps_min_area_itself_and_drops_zero_area_and_finds_nested_parts():
    from shapely.geometry import MultiPolygon

    # a part of exactly min_area stays (>=); a zero-area polygon goes even at min_area 0
    kept = prune_small(MultiPolygon([box(0, 0, 1, 1), box(2, 0, 2.5, 1)]), 0.5)
    assert sorted(p.area for p in kept) == [0.5, 1.0]
    flat = Polygon([(0, 0), (1, 0), (2, 0)])
    assert [p.area for p in prune_small(GeometryCollection([box(0, 0, 1, 1), flat]), 0.0)] == [1.0]
    # a MultiPolygon two collections deep
    nested = GeometryCollection([GeometryCollection([MultiPolygon([box(0, 0, 1, 1), box(2, 0, 3, 2)])])])
    assert sorted(p.area for p in prune_small(nested, 0.1)) == [1.0, 2.0]


def test_scanline_columns_spanning_exactly_two_pi_are_refused():
    # four columns a quarter turn apart: their edges span exactly 2*pi
    bearings = np.array([[0.0, 0.5, 1.0, 1.5]]) * np.pi
    with pytest.raises(ValueError, match=r"span less than 2\*pi"):
        free_wedges_from_scanlines(np.zeros((1, 2)), bearings, np.zeros((1, 4), bool), box(-1, -1, 1, 1))


def test_non_monotone_bearings_name_the_first_bad_row():
    bearings = np.array([[0.0, 0.1, 0.2], [0.0, 0.2, 0.1], [0.3, 0.1, 0.2]])
    with pytest.raises(ValueError, match=r"strictly monotone along each row \(row 1\)"):
        free_wedges_from_scanlines(np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0]]), bearings,
                                   np.zeros((3, 3), bool), box(-1, -1, 1, 1))


def test_free_wedges_skip_the_polygons_only_when_the_table_alone_is_asked_for():
    """polygons=False builds no wedges only with return_cones: the table of free wedges of a
    camera on the left wall, around a disc 1 m ahead, is its two sides of the FOV."""
    args = ([[-1, 0]], [0.0], np.pi, [[0, 0]], R, SQUARE)
    plain = free_wedges_from_discs(*args)
    assert shapely.equals(free_wedges_from_discs(*args, polygons=False)[0], plain[0])
    wedges, (camera, apex, theta0, theta1) = free_wedges_from_discs(*args, return_cones=True, polygons=False)
    assert wedges is None
    assert camera.tolist() == [0, 0]
    np.testing.assert_array_equal(apex, [[-1, 0], [-1, 0]])
    half = np.arcsin(R)
    np.testing.assert_allclose(theta0, [-np.pi / 2, half], rtol=0, atol=1e-12)
    np.testing.assert_allclose(theta1, [-half, np.pi / 2], rtol=0, atol=1e-12)
    built, _ = free_wedges_from_discs(*args, return_cones=True)
    assert shapely.equals(built[0], plain[0])


@pytest.mark.parametrize("near, kept", [(0.99, True), (0.9901, False)])
def test_a_wedge_is_kept_while_its_blind_radius_is_under_far_cos_squared_of_half_an_arc_step(near, kept):
    """Two columns at -0.4 and 0.4 rad: one free wedge of 1.6 rad, nine arc points 0.2 rad
    apart; with far 1 it is kept for near < cos(0.1)^2 = 0.990033 (the inner arc at
    near / cos(0.1), eight chord triangles out minus in), dropped above."""
    room = box(-3, -3, 3, 3)
    (w,) = free_wedges_from_scanlines([[0.0, 0.0]], [[-0.4, 0.4]], np.zeros((1, 2), bool), room,
                                      near=near, far=1.0)
    if not kept:
        assert w.is_empty
        return
    r_in = near / np.cos(0.1)
    assert w.area == pytest.approx(0.5 * 8 * np.sin(0.2) * (1.0 - r_in**2), rel=1e-9)


def test_a_blind_radius_beyond_the_wedges_reach_frees_nothing_beside_a_camera_that_sees():
    """Camera 0 blind out to 50 m in a 2 x 2 m room (its sight radius 1 km): it proves nothing
    empty, however far it sees; camera 1 beside it keeps its own near and far radii."""
    bearings = np.array([[-0.4, 0.4], [np.pi - 0.4, np.pi + 0.4]])
    xy = [[-0.9, 0.0], [0.9, 0.0]]
    free = np.zeros((2, 2), bool)
    w = free_wedges_from_scanlines(xy, bearings, free, SQUARE, near=[50.0, 0.1], far=[1000.0, 1.0])
    assert w[0].is_empty
    alone = free_wedges_from_scanlines(xy[1:], bearings[1:], free[1:], SQUARE, near=0.1, far=1.0)
    assert not alone[0].is_empty and sym_diff_area(w[1], alone[0]) < 1e-12
    hull = hull_from_wedges(w, SQUARE, [0])
    assert sym_diff_area(hull, SQUARE) < 1e-12


def test_hulls_drop_the_slivers_their_overlays_leave_on_either_path():
    """A wedge that frees all of a 1 m square but a strip 5e-13 m high (area 5e-13 m^2, under
    SLIVER times the room's area) leaves an empty hull, alone and as 33 copies (the union path)."""
    room = box(0, 0, 1, 1)
    w = np.array([box(-1, 5e-13, 2, 2)], dtype=object)
    assert not shapely.difference(room, w[0]).is_empty          # the strip is there
    assert hull_from_wedges(w, room).is_empty
    assert hull_from_wedges(np.repeat(w, 33), room).is_empty


def test_drop_slivers_of_one_polygon_and_at_the_threshold_itself():
    """A lone polygon of area SLIVER * room.area (1e-12 m^2 in a 1 m square) or less is dropped,
    one twice as large stays; so in a collection."""
    from tasking.hull import drop_slivers

    room = box(0, 0, 1, 1)
    at, above, big = box(0, 0, 1, 1e-12), box(0, 0.5, 1, 0.5 + 2e-12), box(0, 0.7, 1, 1)
    assert drop_slivers(at, room).is_empty
    assert drop_slivers(above, room).equals(above)
    got = drop_slivers(GeometryCollection([at, big]), room)
    assert shapely.get_num_geometries(got) == 1 and sym_diff_area(got, big) == 0.0


def test_regions_from_discs_lie_in_the_room_and_hold_no_slivers():
    """180-degree cameras on the walls of a 4 x 3 m room: the empty regions are clipped to
    the room, and the "not proven empty" regions, room minus wedges, hold one polygon each (the
    plain differences leave zero-area parts along the walls)."""
    room = box(0, 0, 4, 3)
    xy = np.array([[1.3, 0.0], [4.0, 1.1], [2.7, 3.0], [0.0, 1.9]])
    yaw = np.array([0.5, 1.0, -0.5, 0.0]) * np.pi
    centre = np.array([[2.0, 1.5]])
    empties = empty_regions_from_discs(xy, yaw, np.pi, centre, 0.3, room)
    regions = camera_regions_from_discs(xy, yaw, np.pi, centre, 0.3, room)
    raw = shapely.difference(room, free_wedges_from_discs(xy, yaw, np.pi, centre, 0.3, room))
    assert max(shapely.get_num_geometries(raw)) > 1                 # slivers were there
    for empty, region in zip(empties, regions):
        assert empty.difference(room).area == 0.0
        assert shapely.get_num_geometries(region) == 1
        assert region.area == pytest.approx(room.area - empty.area, rel=0, abs=1e-12)


def test_regions_from_scanlines_keep_near_and_far_and_hold_no_slivers():
    """A camera in the middle of the square, blind to 0.3 m and seeing to 0.8 m, with nothing
    in view: its empty region is a ring sector between the two circles, its other region the
    rest of the room. 180-degree wall cameras' regions are one polygon each."""
    from tasking import empty_regions_from_scanlines

    bearings = np.array([[-1.5, -0.5, 0.5, 1.5]]) * np.pi / 8           # edges -pi/4 .. pi/4
    args = ([[0.0, 0.0]], bearings, np.zeros((1, 4), bool), SQUARE)
    (empty,) = empty_regions_from_scanlines(*args, near=0.3, far=0.8)
    (region,) = camera_regions_from_scanlines(*args, near=0.3, far=0.8)
    sector = 0.5 * (np.pi / 2) * (0.8**2 - 0.3**2)
    assert empty.area == pytest.approx(sector, rel=0.02) and empty.area < sector
    assert empty.intersection(Point(0, 0).buffer(0.3, quad_segs=256)).area < 1e-12
    assert empty.difference(Point(0, 0).buffer(0.8 + 1e-9, quad_segs=256)).area < 1e-12
    assert region.area == pytest.approx(SQUARE.area - empty.area, rel=0, abs=1e-12)
    room = box(0, 0, 4, 3)
    xy = np.array([[1.3, 0.0], [4.0, 1.1], [2.7, 3.0], [0.0, 1.9]])
    bearings, occ = scanlines_from_discs(xy, np.array([0.5, 1.0, -0.5, 0.0]) * np.pi, np.pi,
                                         np.array([[2.0, 1.5]]), 0.3, 64)
    empties = empty_regions_from_scanlines(xy, bearings, occ, room)
    for empty, region in zip(empties, camera_regions_from_scanlines(xy, bearings, occ, room)):
        assert empty.difference(room).area == 0.0
        assert shapely.get_num_geometries(region) == 1
