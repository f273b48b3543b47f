"""The exact infinite-camera limit (testbed/studies/limit.py) against many cameras."""

import warnings

import numpy as np
import pytest
import shapely

from scene.motion import random_drop
from testbed.studies import core
from testbed.studies.limit import bitangent_lines, covered, limit_residual

OBJ = np.pi * 0.1**2


def test_single_disc_has_no_residual():
    assert limit_residual([[0.2, -0.3]], 0.1) == (0.0, 0.0)


def test_bitangents_touch_both_discs():
    c = np.array([[0.0, 0.0], [0.5, 0.2]])
    r = np.array([0.1, 0.15])
    lines = bitangent_lines(c, r)
    assert lines.shape == (4, 3)
    dist = np.abs(lines[:, :2] @ c.T - lines[:, 2:3])
    assert np.allclose(dist, r[None, :])


def test_covered_hand_case():
    # Three discs at 0.15 around a point, 120 degrees apart, each block +-41.8 degrees of
    # line directions around 0, 60 and 120 degrees (mod 180): every line is blocked.
    c = 0.15 * np.array([[1.0, 0.0], [-0.5, 0.75**0.5], [-0.5, -0.75**0.5]])
    assert covered(np.array([[0.0, 0.0], [0.0, 0.6]]), c, np.full(3, 0.1)).tolist() == [True, False]
    # Four discs at 0.15 on the axes leave a gap between 41.8 and 48.2 degrees.
    c4 = np.array([[0.15, 0.0], [-0.15, 0.0], [0.0, 0.15], [0.0, -0.15]])
    assert not covered(np.zeros((1, 2)), c4, np.full(4, 0.1))[0]


@pytest.mark.parametrize("seed, m", [(0, 3), (1, 6)])
def test_exact_limit_is_the_many_camera_limit(seed, m):
    room = core.circle_room()
    centers = random_drop(room, np.full(m, 0.1), np.random.default_rng(seed))
    raw, _ = limit_residual(centers, 0.1, h=0.002)
    prev = np.inf
    for n in (32, 128, 512):
        xy, yaw = core.circle_cameras(n)
        hull_raw = core.hull_residual(xy, yaw, centers, 0.1, room)[0] * OBJ
        # Every finite hull contains the limit hull, and they close in on it.
        assert hull_raw >= raw - 2e-4
        assert hull_raw <= prev + 1e-9
        prev = hull_raw
    assert prev - raw < 0.02 * OBJ + 0.02 * raw


def test_quadrature_converges():
    centers = random_drop(core.circle_room(), np.full(8, 0.1), np.random.default_rng(3))
    a = limit_residual(centers, 0.1, h=0.004)[0]
    b = limit_residual(centers, 0.1, h=0.001)[0]
    assert abs(a - b) < 0.01 * OBJ


def test_pruning_keeps_pieces_a_fraction_of_a_millimetre_apart_separate():
    """Drop 8 of `study cameras --objects 10` (seed 0): phantom pieces 0.16-0.30 mm from an
    object's piece were joined to it by row overlap, so the pruned limit depended on the
    row spacing (0.304 at 2 mm, 0.288 at 0.5 mm, 0.245 at 0.2 mm object areas). Now it does
    not, and it stays below the 4000-camera hull's (0.246)."""
    r = 0.1
    centers = random_drop(core.circle_room(1.0), np.full(10, r), core.trial_rng(0, 0, 10, 8))
    pruned = [limit_residual(centers, r, h=h, min_area=OBJ)[1] / OBJ for h in (0.002, 0.0005)]
    assert abs(pruned[0] - pruned[1]) < 0.01
    assert 0.24 < pruned[1] < 0.246


def test_no_disc_or_no_disc_inside_the_room_has_no_residual():
    assert limit_residual(np.zeros((0, 2)), 0.1) == (0.0, 0.0)
    # a disc outside the room crosses none of the room's rows
    assert limit_residual([[0.0, 1.5], [0.3, 1.5]], 0.1) == (0.0, 0.0)


def test_chunks_of_points_do_not_change_the_limit():
    """The midpoints are tested in chunks; a chunk of one point holds chunks of points inside a
    disc alone (nothing left to test for coverage)."""
    centers = random_drop(core.circle_room(), np.full(4, 0.1), np.random.default_rng(5))
    whole = limit_residual(centers, 0.1, h=0.01)
    assert whole[0] > 0
    assert limit_residual(centers, 0.1, h=0.01, chunk=1) == whole
    assert limit_residual(centers, 0.1, h=0.01, chunk=7) == whole


def test_three_discs_around_a_point_leave_a_piece_between_them_that_is_pruned():
    """Three discs at 0.15 from the origin, 120 degrees apart, cover every line through the
    origin (covered() above): the limit hull holds a piece between them, apart from the discs
    and smaller than one disc, so pruning removes it with the other small pieces; both values
    lie under a 1000-camera hull's and close to them."""
    c = 0.15 * np.array([[1.0, 0.0], [-0.5, 0.75**0.5], [-0.5, -0.75**0.5]])
    raw, pruned = limit_residual(c, 0.1, h=0.002)
    room = core.circle_room()
    xy, yaw = core.circle_cameras(1000)
    hull = core.visual_hull_of_discs(xy, yaw, np.pi, c, 0.1, room)
    pieces = [g.area for g in hull.geoms]
    centre = next(g for g in hull.geoms if g.contains(shapely.Point(0, 0)))
    assert 0.05 * OBJ < centre.area < OBJ                  # the piece between the discs
    kept = sum(a for a in pieces if a >= OBJ) - 3 * OBJ
    assert raw <= hull.area - 3 * OBJ + 1e-9 and pruned <= kept + 1e-9
    assert hull.area - 3 * OBJ - raw < 0.01 * OBJ and kept - pruned < 0.01 * OBJ
    assert raw - pruned > centre.area - 0.01 * OBJ         # the centre piece went with the pruning


def test_pruning_threshold_defaults_to_the_smallest_discs_area():
    """The three discs' centre piece (about 0.1 areas of a 0.1 m disc) is larger than a 0.02 m
    disc: with one such disc far away the default threshold keeps it, a 0.1 m disc's drops it."""
    c = np.vstack([0.15 * np.array([[1.0, 0.0], [-0.5, 0.75**0.5], [-0.5, -0.75**0.5]]), [[-0.7, 0.0]]])
    r = np.array([0.1, 0.1, 0.1, 0.02])
    default = limit_residual(c, r, h=0.002)
    assert default == limit_residual(c, r, h=0.002, min_area=np.pi * 0.02**2)
    big = limit_residual(c, r, h=0.002, min_area=OBJ)
    assert big[0] == default[0] and big[1] < default[1] - 0.05 * OBJ


def test_a_point_inside_a_lone_disc_is_covered():
    # one disc: no pair of arcs covers the directions, only being inside it does
    got = covered(np.array([[0.07, 0.0], [0.0, 0.099], [0.0, 0.101], [0.5, 0.5]]), np.zeros((1, 2)), np.array([0.1]))
    assert got.tolist() == [True, True, False, False]


def cluster(centre, d, r, turn=0.0):
    """Three discs of radius r at distance d from centre, 120 degrees apart, the first at angle turn."""
    a = turn + np.radians([0.0, 120.0, 240.0])
    return np.asarray(centre) + d * np.column_stack([np.cos(a), np.sin(a)])


@pytest.mark.parametrize("c, r, h", [
    # rows y = -0.875, -0.625, ..., 0.875: the first 0.125 above the room's bottom, through the discs
    (cluster([0.0, -0.875], 0.09, 0.06, np.pi / 2), 0.06, 0.25),
    # a piece's edge on a common tangent 3 degrees from the rows' direction, crossed by the row y = -0.11
    (np.array([[0.198, 0.002], [-0.094, 0.085], [-0.019, -0.209]]), 0.1, 0.02),
])
def test_raw_residual_is_h_times_the_hulls_chords_on_rows_midway_in_strips_of_height_h(c, r, h):
    """The rows are the midpoints y = (k + 1/2) h of the strips of height h from the room's
    bottom, each measured exactly: the raw residual is h times the sum of the rows' chords
    through the hull outside the discs, here measured on a 2000-camera hull (which contains the
    limit hull and is close to it)."""
    hull = core.visual_hull_of_discs(*core.circle_cameras(2000), np.pi, c, r, core.circle_room())
    outside = hull.difference(shapely.union_all([shapely.Point(p).buffer(r, 256) for p in c]))
    ys = (np.arange(-round(1 / h), round(1 / h)) + 0.5) * h
    chords = h * sum(outside.intersection(shapely.LineString([(-1, y), (1, y)])).length for y in ys)
    assert chords > 0.01 * OBJ
    raw, _ = limit_residual(c, r, h=h)
    assert chords - 1e-4 < raw <= chords + 1e-9


def test_pieces_holding_a_disc_are_never_pruned():
    """With a threshold above every piece's area only the pieces without a disc go: the three
    discs' pieces stay, the piece between them (and the slivers) are removed, as measured on a
    1000-camera hull's pieces that hold a disc."""
    c = 0.15 * np.array([[1.0, 0.0], [-0.5, 0.75**0.5], [-0.5, -0.75**0.5]])
    hull = core.visual_hull_of_discs(*core.circle_cameras(1000), np.pi, c, 0.1, core.circle_room())
    discs = [shapely.Point(p).buffer(0.05) for p in c]
    with_disc = sum(g.area for g in hull.geoms if any(g.contains(d) for d in discs)) - 3 * OBJ
    assert with_disc > 0.05 * OBJ
    raw, pruned = limit_residual(c, 0.1, h=0.002, min_area=1.0)
    assert pruned <= with_disc + 1e-9 and with_disc - pruned < 0.01 * OBJ
    assert raw - pruned > 0.05 * OBJ


def test_a_piece_around_a_small_disc_keeps_it_though_the_rows_cross_the_disc_inside_the_piece():
    """A 1 cm disc at the centre of the three discs lies inside their centre piece: every row
    crosses the piece, then the disc, then the piece again, as one segment, and the piece holds
    a disc (a segment's flag is any of its intervals', not its last one's). Pruning pieces below
    one 0.1 m disc's area keeps it, as on a 1000-camera hull."""
    c = np.vstack([0.15 * np.array([[1.0, 0.0], [-0.5, 0.75**0.5], [-0.5, -0.75**0.5]]), [[0.0, 0.0]]])
    r = np.array([0.1, 0.1, 0.1, 0.01])
    hull = core.visual_hull_of_discs(*core.circle_cameras(1000), np.pi, c, r, core.circle_room())
    discs = [shapely.Point(p).buffer(0.5 * s) for p, s in zip(c, r)]
    centre = next(g for g in hull.geoms if g.contains(discs[3]))
    assert not any(centre.contains(d) for d in discs[:3]) and centre.area < OBJ
    with_disc = sum(g.area for g in hull.geoms if any(g.contains(d) for d in discs)) - 3 * OBJ - np.pi * 0.01**2
    pruned = limit_residual(c, r, h=0.002, min_area=OBJ)[1]
    assert pruned <= with_disc + 1e-9 and with_disc - pruned < 0.01 * OBJ
    assert centre.area - np.pi * 0.01**2 > 0.05 * OBJ


@pytest.mark.parametrize("r, y", [(0.0009, 0.0), (0.0009, 0.0004), (0.0002, 0.0004)])
def test_a_disc_no_row_crosses_keeps_its_piece(r, y):
    """A disc of radius under h / 2 = 1 mm in the three discs' centre piece, between the rows
    y = -0.001 and 0.001: the piece holds a disc and stays when pieces below one 0.1 m disc's
    area are pruned (the centre piece alone, about 0.1 object areas, goes)."""
    c3 = 0.15 * np.array([[1.0, 0.0], [-0.5, 0.75**0.5], [-0.5, -0.75**0.5]])
    alone = limit_residual(c3, 0.1, h=0.002, min_area=OBJ)[1]
    pruned = limit_residual(np.vstack([c3, [[0.0, y]]]), np.array([0.1, 0.1, 0.1, r]), h=0.002, min_area=OBJ)[1]
    assert pruned - alone > 0.05 * OBJ


@pytest.mark.parametrize("c, h", [
    # the pieces between the discs are bounded by common tangents that also bound the discs' pieces
    ([[0.272, -0.154], [0.15, -0.352], [0.383, -0.359]], 0.002),
    # no disc reaches the row y = -0.445, between the bottom disc's top and the others' bottoms
    ([[-0.296, -0.548], [-0.177, -0.337], [-0.419, -0.339]], 0.01),
])
def test_pruned_limit_keeps_the_pieces_a_many_camera_hull_keeps(c, h):
    """Three discs 0.134-0.14 m apart: the limit hull has pieces without a disc of 0.1-0.18
    object areas, pruned; joining one to a disc's piece across rows (sharing a bounding line,
    or across rows with no disc between them) would keep it. The pruned value is a 2000-camera
    hull's pieces holding a disc or larger than one, less the discs."""
    c = np.array(c)
    hull = core.visual_hull_of_discs(*core.circle_cameras(2000), np.pi, c, 0.1, core.circle_room())
    discs = [shapely.Point(p).buffer(0.05) for p in c]
    small = [g.area for g in hull.geoms if g.area < OBJ and not any(g.contains(d) for d in discs)]
    assert max(small) > 0.09 * OBJ
    kept = hull.area - sum(small) - 3 * OBJ
    assert abs(limit_residual(c, 0.1, h=h)[1] - kept) < 0.01 * OBJ     # within the quadrature's error


@pytest.mark.parametrize("c, h", [
    # a piece without a disc ends and a disc's piece begins between two rows 2-5 cm apart,
    # both bounded on one side by the same common tangent
    ([[-0.363, 0.606], [-0.446, 0.382], [-0.21, 0.422]], 0.05),
    ([[-0.363, 0.606], [-0.446, 0.382], [-0.21, 0.422]], 0.02),
    (random_drop(core.circle_room(), np.full(10, 0.1), np.random.default_rng(1175)), 0.01),
])
def test_pruning_on_coarse_rows_adds_no_error_of_its_own(c, h):
    """On rows h apart the raw residual is off by its quadrature error; the pruned value is
    off by no more than that (and 0.01 object areas), against a 2000-camera hull's pieces
    holding a disc or larger than one. Joining a segment to the next row's where they share
    one bounding curve, as a corner of one piece, kept a piece of 0.14 object areas at
    h = 0.02 here (0.31 instead of 0.17)."""
    c = np.array(c)
    hull = core.visual_hull_of_discs(*core.circle_cameras(2000), np.pi, c, 0.1, core.circle_room())
    discs = [shapely.Point(p).buffer(0.05) for p in c]
    small = sum(g.area for g in hull.geoms if g.area < OBJ and not any(g.contains(d) for d in discs))
    assert small > 0.05 * OBJ
    raw, pruned = limit_residual(c, 0.1, h=h)
    raw_error = abs(raw - (hull.area - len(c) * OBJ))
    assert abs(pruned - (hull.area - small - len(c) * OBJ)) < raw_error + 0.01 * OBJ


def test_the_curves_numbers_are_the_row_segments_ends():
    """Every segment's ends on every row are its two bounding curves' x there, and a common
    tangent touches its discs where contact_y says: on the line and on the circle."""
    from testbed.studies.limit import _Curves, _row_segments

    c = random_drop(core.circle_room(), np.full(6, 0.1), np.random.default_rng(3))
    r = np.full(6, 0.1)
    lines = bitangent_lines(c, r)
    ys = (np.arange(-50, 50) + 0.5) * 0.02
    curves = _Curves(c, r, lines, 1.0)
    ends = [(seg[:2], curves.x(list(seg[2]), np.array([y]))[:, 0])
            for y, row in zip(ys, _row_segments(ys, c, r, lines, 1.0, 20000)) for seg in row]
    assert len(ends) > 50 and all(np.array_equal(a, b) for a, b in ends)
    m = len(c)
    touched = 0
    for k in range(4 * m + 2, 4 * m + 2 + len(curves.lines)):
        for disc in range(2 * m):
            y = curves.contact_y(disc, k)
            if y is None:
                continue
            touched += 1
            assert y == curves.contact_y(k, disc)
            nx, ny, d = curves.lines[k - 4 * m - 2]
            x = (d - ny * y) / nx
            assert abs(np.hypot(x - c[disc % m, 0], y - c[disc % m, 1]) - 0.1) < 1e-9
            assert (x > c[disc % m, 0]) == (disc >= m)          # on that half: left (< m) or right
    assert touched == 2 * len(curves.lines)          # each line touches two discs, each on one half
    assert curves.contact_y(0, 1) is None and curves.contact_y(4 * m, 4 * m + 2) is None
    # a disc's half touches no curve but a line: not its other half, its extents nor the room
    assert all(curves.contact_y(disc, k) is None for disc in range(2 * m) for k in range(4 * m + 2))


def test_a_corner_is_two_curves_crossing_between_the_rows_beside_the_shared_one():
    """No disc; lines x = 0.5 + y (2), x = 0.5 - y (3) crossing at y = 0, x = -0.5 (4) and
    x = 0.3 + 2 y (5), which crosses both near y = 0.067-0.2. A segment bounded on the right
    by 2 on the row y = -0.1 and by 3 on y = 0.1 turns a corner if its left curve is 4, not if
    it is 5, nor if the rows do not hold the crossing."""
    from testbed.studies.limit import _corner, _Curves

    lines = np.array([[1.0, -1.0, 0.5], [1.0, 1.0, 0.5], [1.0, 0.0, -0.5], [1.0, -2.0, 0.3]])
    curves = _Curves(np.zeros((0, 2)), np.zeros(0), lines, 1.0)
    assert np.allclose(curves.x([2, 3, 4, 5], np.array([-0.1, 0.1])), [[0.4, 0.6], [0.6, 0.4], [-0.5, -0.5], [0.1, 0.5]])
    assert _corner((4, 2), (4, 3), -0.1, 0.1, curves)
    assert not _corner((4, 2), (4, 3), -0.1, -0.05, curves)       # 2 and 3 cross above both rows
    assert not _corner((5, 2), (5, 3), -0.1, 0.1, curves)         # the shared curve crosses them
    assert not _corner((4, 2), (5, 3), -0.1, 0.1, curves)         # no curve shared


def test_a_point_on_a_lone_discs_circle_is_covered_and_its_centre_warns_nothing():
    # every line through a point of the circle meets the (closed) disc; at the centre the
    # angular radius is a quarter turn without a division by zero
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = covered(np.array([[0.1, 0.0], [0.0, -0.1], [0.0, 0.0]]), np.zeros((1, 2)), np.array([0.1]))
    assert got.tolist() == [True, True, True]


def test_two_discs_cover_every_line_through_a_point_in_the_pocket_beside_their_gap():
    """Discs at (-0.105, 0) and (0.105, 0), 1 cm apart: from (-0.05, 0.09) the first blocks the
    line directions -12.8 to 130 degrees, the second 116 to 183.8 degrees, all of them; from
    (0, 0.09) both are seen around 30 and 150 degrees, leaving 80-100 degrees open."""
    c = np.array([[-0.105, 0.0], [0.105, 0.0]])
    got = covered(np.array([[-0.05, 0.09], [0.05, -0.09], [0.0, 0.09], [0.0, 0.0]]), c, np.full(2, 0.1))
    assert got.tolist() == [True, True, False, False]


@pytest.mark.parametrize("c, r, h", [
    (cluster([0.0, -0.875], 0.09, 0.06, np.pi / 2), 0.06, 0.25),
    (random_drop(core.circle_room(), np.full(10, 0.1), np.random.default_rng(132)), 0.1, 0.02),
])
def test_the_limit_of_a_scene_mirrored_is_the_same(c, r, h):
    """The rows are symmetric about y = 0 and pieces are joined the same going up or down: the
    scene mirrored top to bottom or left to right has the same raw and pruned residuals. (In
    the drop a piece parts in two going up, one arm without a disc: joining only the first
    arm to it, or dropping the top row, changed one side's values.)"""
    raw, pruned = limit_residual(c, r, h=h)
    assert raw > 0.01 * OBJ
    for flip in ([1.0, -1.0], [-1.0, 1.0]):
        assert limit_residual(c * flip, r, h=h) == pytest.approx((raw, pruned), rel=1e-9, abs=1e-15)


def test_a_disc_and_its_tangent_turn_a_corner_where_they_touch():
    """A disc of 0.1 m at the origin and lines touching its right half at 30 and 80 degrees
    (y = 0.05, 0.0985): a segment between the disc's right half (1) and the room's right half
    (5) on one row and between the line and the room on the next is one piece turning round
    the point of contact if the rows hold it, even where the disc does not reach the upper row."""
    from testbed.studies.limit import _corner, _Curves

    a = np.radians([30.0, 80.0])
    lines = np.column_stack([np.cos(a), np.sin(a), np.full(2, 0.1)])
    curves = _Curves(np.zeros((1, 2)), np.array([0.1]), lines, 1.0)
    assert curves.contact_y(1, 6) == pytest.approx(0.05) and curves.contact_y(7, 1) == pytest.approx(0.1 * np.sin(a[1]))
    assert _corner((1, 5), (6, 5), 0.04, 0.06, curves)
    assert _corner((6, 5), (1, 5), 0.06, 0.04, curves)
    assert not _corner((1, 5), (6, 5), 0.06, 0.08, curves)        # touching below both rows
    assert _corner((1, 5), (7, 5), 0.09, 0.105, curves)           # the disc ends below 0.105
    assert not _corner((1, 5), (7, 5), 0.08, 0.09, curves)


def test_no_corner_where_the_shared_curve_crosses_one_of_the_others():
    """Lines x = 0.4 (2), 0.6 - y (3), 0.5 + 2 y (4), 0.5 - 2 y (5) and 0.6 + y (6); on the rows
    y = -0.1 and 0.1 segments bounded on the left by 2. 3 and 6 cross at y = 0 right of 2: a
    corner. 3 and 4 cross, but 4 crosses 2 too (y = -0.05), as 5 does (y = 0.05) with 6."""
    from testbed.studies.limit import _corner, _Curves

    lines = np.array([[1.0, 0.0, 0.4], [1.0, 1.0, 0.6], [1.0, -2.0, 0.5], [1.0, 2.0, 0.5], [1.0, -1.0, 0.6]])
    curves = _Curves(np.zeros((0, 2)), np.zeros(0), lines, 1.0)
    assert _corner((2, 3), (2, 6), -0.1, 0.1, curves)
    assert not _corner((2, 3), (2, 4), -0.1, 0.1, curves)
    assert not _corner((2, 5), (2, 6), -0.1, 0.1, curves)


def test_rows_pair_off_only_segment_by_segment_each_overlapping_its_partner_alone():
    """_same_cells on hand-made segments ``[x0, x1, curves]`` of the rows y = -0.1 and 0.1 (the
    curves of the test above): partners must overlap in x, may turn a corner (2, 3 then 2, 6),
    and neither may overlap its neighbour's partner as well."""
    from testbed.studies.limit import _Curves, _same_cells

    lines = np.array([[1.0, 0.0, 0.4], [1.0, 1.0, 0.6], [1.0, -2.0, 0.5], [1.0, 2.0, 0.5], [1.0, -1.0, 0.6]])
    curves = _Curves(np.zeros((0, 2)), np.zeros(0), lines, 1.0)

    def same(a_row, b_row):
        segs = a_row + b_row
        return _same_cells(segs, list(range(len(a_row))), list(range(len(a_row), len(segs))), -0.1, 0.1, curves)

    assert same([[0.4, 0.7, (2, 3)]], [[0.4, 0.5, (2, 3)]])
    assert not same([[0.1, 0.2, (2, 3)]], [[0.3, 0.4, (2, 3)]])       # no overlap
    assert same([[0.4, 0.7, (2, 3)]], [[0.4, 0.7, (2, 6)]])           # a corner
    assert not same([[0.4, 0.7, (2, 3)]], [[0.4, 0.7, (2, 4)]])       # not a corner
    pair = [(2, 3), (4, 5)]
    assert same([[0.0, 0.1, pair[0]], [0.5, 0.6, pair[1]]], [[0.0, 0.3, pair[0]], [0.4, 0.6, pair[1]]])
    assert not same([[0.0, 0.3, pair[0]], [0.5, 0.6, pair[1]]], [[0.0, 0.1, pair[0]], [0.2, 0.6, pair[1]]])
    assert not same([[0.0, 0.1, pair[0]], [0.2, 0.6, pair[1]]], [[0.0, 0.3, pair[0]], [0.5, 0.6, pair[1]]])
