"""Taskers: hand cases, agreement between greedy variants, optimality, errors."""

from itertools import combinations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import box
from test_tasking_common import circle_room, random_discs, ring_cameras

from tasking import (
    TASKERS,
    IncrementalTasker,
    choose_cameras,
    free_wedges_from_discs,
    greedy_select,
    hull_from_wedges,
    lazy_greedy_select,
    naive_greedy_select,
    visual_hull_of_discs,
)
from tasking.clustering import axial_distance, cluster_axes, pair_axes
from tasking.coverage import coverage_cells, subset_areas

R = 0.1
ROOM = circle_room(quad_segs=32)


def area_of(sel, xy, yaw, centres, fov=np.pi):
    return visual_hull_of_discs(xy[sel], yaw[sel], fov, centres, R, ROOM).area


def drop(seed, n=10, m=4):
    rng = np.random.default_rng(seed)
    xy, yaw = ring_cameras(n)
    return xy, yaw, random_discs(rng, m)


# --- hand cases -----------------------------------------------------------------------


def test_uniform_spreads_indices_and_uses_supplied_sets():
    xy, yaw = ring_cameras(16)
    c = [[0.2, 0.0]]
    assert choose_cameras("uniform", 4, xy, yaw, np.pi, c, R, ROOM).tolist() == [0, 4, 8, 12]
    assert choose_cameras("uniform", 5, xy, yaw, np.pi, c, R, ROOM).tolist() == [0, 3, 6, 10, 13]
    odd = {8: list(range(0, 16, 2))}  # paper: the odd cameras 1, 3, ..., 15 (1-based)
    got = choose_cameras("uniform", 8, xy, yaw, np.pi, c, R, ROOM, uniform_sets=odd)
    assert got.tolist() == odd[8]
    # no entry for k: fall back to the even spread
    assert choose_cameras("uniform", 2, xy, yaw, np.pi, c, R, ROOM, uniform_sets=odd).tolist() == [0, 8]


def test_two_objects_two_cameras_pick_parallel_and_perpendicular():
    # Figure 7: objects on the x axis; cameras every 45 degrees. The best pair looks
    # along the pair vector and across it, leaving no phantom.
    xy, yaw = ring_cameras(8)
    c = np.array([[-0.3, 0.0], [0.3, 0.0]])
    for tasker in ("greedy", "lazy_greedy", "optimal"):
        sel = choose_cameras(tasker, 2, xy, yaw, np.pi, c, R, ROOM)
        axes = np.degrees(yaw[sel] % np.pi).round(6)
        assert sorted(axes.tolist()) == [0.0, 90.0], tasker
    sel = choose_cameras("clustering", 2, xy, yaw, np.pi, c, R, ROOM)
    assert sorted(np.degrees(yaw[sel] % np.pi).round(6).tolist()) == [0.0, 90.0]


def test_clustering_handles_the_wrap_at_pi():
    # axes near 0 and near pi are the same direction: one cluster, not two
    axes = np.array([0.01, np.pi - 0.01, 0.02, np.pi - 0.02, np.pi / 2, np.pi / 2 + 0.01])
    centres, sizes = cluster_axes(axes, 2, seed=0)
    assert sizes.tolist() == [4, 2]
    assert axial_distance(centres[0], 0.0) < 0.02
    assert axial_distance(centres[1], np.pi / 2) < 0.02
    assert pair_axes(np.array([[0.0, 0.0], [0.0, 0.0]])).size == 0


@pytest.mark.parametrize("seed", range(6))
def test_clustering_picks_the_same_of_two_twin_solutions_whatever_the_order(seed):
    """Each pair gives an axis and its perpendicular, so every k-means solution has a twin
    turned by pi / 2 of the same inertia; which one came out depended on rounding (the
    OpenMP thread count: `study static --workers 0` and `--workers 2` chose other cameras)
    and on the order of the axes."""
    est = np.random.default_rng(seed).uniform(-0.8, 0.8, (5, 2))
    axes = pair_axes(est)
    for k in (2, 3, 4):
        centres, sizes = cluster_axes(axes, k, seed=0)
        for other in (np.roll(axes, axes.size // 2), axes[::-1]):
            c2, s2 = cluster_axes(other, k, seed=0)
            np.testing.assert_allclose(c2, centres, atol=1e-9)
            np.testing.assert_array_equal(s2, sizes)


def test_clustering_ties_between_cameras_on_one_axis_go_to_the_lowest_index():
    """Opposite cameras of a ring share a viewing axis; ``yaw % pi`` leaves them ~1e-15 apart,
    which must not decide, and neither may the multiple of 2 pi a yaw is written with."""
    from tasking.clustering import clustering_select

    _, yaw = ring_cameras(16)                                  # the circle study's rig
    a = np.radians(30.0)
    est = np.array([[0.0, 0.0], [0.5 * np.cos(a), 0.5 * np.sin(a)]])   # axes 30 and 120 degrees
    assert clustering_select(yaw, est, 2, seed=0).tolist() == [1, 5]   # not 9 (1's twin), nor 13
    for turns in (-1, 1, 3):
        assert clustering_select(yaw + 2 * np.pi * turns, est, 2, seed=0).tolist() == [1, 5]


def test_clustering_ties_on_one_axis_go_to_the_camera_farthest_from_those_chosen():
    """With positions, of two cameras on one axis the one farther from the chosen cameras wins
    (the lowest index alone took every camera from one half of a ring)."""
    from tasking.clustering import clustering_select

    xy = np.array([[0.0, 0.0], [1.0, 0.0], [10.0, 0.0]])
    yaw = np.radians([0.0, 90.0, 270.0])                          # cameras 1 and 2 share the axis 90
    est = np.array([[0.0, 0.0], [1.0, 0.0]])                      # axes 0 (picked first) and 90
    assert clustering_select(yaw, est, 2, seed=0).tolist() == [0, 1]
    assert clustering_select(yaw, est, 2, seed=0, camera_xy=xy).tolist() == [0, 2]
    ring_xy, ring_yaw = ring_cameras(16)
    rng = np.random.default_rng(0)
    for _ in range(20):                                          # a ring: never all from one half
        c = rng.uniform(-0.6, 0.6, (5, 2))
        got = choose_cameras("clustering", 6, ring_xy, ring_yaw, np.pi, c, R, ROOM, rng=rng)
        assert not (np.all(got < 8) or np.all(got >= 8))


def test_clustering_falls_back_to_uniform_with_fewer_than_two_estimates():
    xy, yaw = ring_cameras(12)
    uni = choose_cameras("uniform", 4, xy, yaw, np.pi, [[0.1, 0.1]], R, ROOM)
    got = choose_cameras("clustering", 4, xy, yaw, np.pi, [[0.1, 0.1]], R, ROOM)
    assert got.tolist() == uni.tolist()
    got = choose_cameras("clustering", 4, xy, yaw, np.pi, np.empty((0, 2)), R, ROOM)
    assert got.tolist() == uni.tolist()


def test_clustering_is_seeded_and_distinct():
    xy, yaw, c = drop(5, n=16, m=5)
    a = choose_cameras("clustering", 6, xy, yaw, np.pi, c, R, ROOM, rng=np.random.default_rng(1))
    b = choose_cameras("clustering", 6, xy, yaw, np.pi, c, R, ROOM, rng=np.random.default_rng(1))
    assert a.tolist() == b.tolist() and np.unique(a).size == 6


estimate_sets = st.lists(st.tuples(st.integers(-40, 40), st.integers(-40, 40)), min_size=2, max_size=7,
                         unique=True).map(lambda p: np.array(p, float) / 40)     # 2.5 cm grid: no near-duplicates


def _turn(points, alpha, centre):
    c, s = np.cos(alpha), np.sin(alpha)
    return (np.asarray(points) - centre) @ np.array([[c, s], [-s, c]]) + centre


@settings(max_examples=100, deadline=None)
@given(estimate_sets, st.floats(-np.pi, np.pi), st.randoms(use_true_random=False))
def test_pair_axes_turn_with_the_estimates_and_ignore_their_order(est, alpha, rnd):
    axes = np.sort(pair_axes(est))
    order = list(range(len(est)))
    rnd.shuffle(order)
    np.testing.assert_allclose(np.sort(pair_axes(est[order])), axes, atol=1e-12)
    turned = np.sort(pair_axes(_turn(est, alpha, np.array([0.3, -0.2]))))
    assert np.all(axial_distance(np.sort((axes + alpha) % np.pi)[None], turned[:, None]).min(axis=1) < 1e-9)
    assert axes.size == len(est) * (len(est) - 1)


@settings(max_examples=150, deadline=None)
@given(estimate_sets, st.integers(2, 5), st.randoms(use_true_random=False))
def test_cluster_axes_do_not_depend_on_the_order_of_the_estimates(est, k, rnd):
    """The estimates' order (track ids, detection order) must not choose the clusters; k-means++
    seeds by index, so unsorted axes ended in other local optima (other cameras). (k = 1 has
    no direction at all: test_clustering_of_one_camera_is_uniform.)"""
    centres, sizes = cluster_axes(pair_axes(est), k, seed=0)
    order = list(range(len(est)))
    rnd.shuffle(order)
    c2, s2 = cluster_axes(pair_axes(est[order]), k, seed=0)
    np.testing.assert_array_equal(s2, sizes)
    assert np.all(axial_distance(c2, centres) < 1e-9)


@settings(max_examples=60, deadline=None)
@given(estimate_sets.filter(lambda e: len(e) <= 4), st.integers(0, 15), st.booleans())
def test_clustering_turns_with_the_room_when_every_axis_is_a_cluster(est, turns, reverse):
    """Estimates and a ring of cameras turned together about the room centre by a multiple of
    the ring's spacing: with k the number of distinct pair axes (each its own cluster, no
    k-means optimum to miss, no second round) and each nearest its own camera axis, the
    chosen viewing axes turn with them."""
    from tasking.clustering import clustering_select

    xy, yaw = ring_cameras(16)
    axes = pair_axes(est)
    feats = np.unique(np.round(np.c_[np.cos(2 * axes), np.sin(2 * axes)], 9), axis=0)
    k = feats.shape[0]
    ring = np.arange(8) * np.pi / 8                                 # the ring's 8 viewing axes
    d = axial_distance(np.arctan2(feats[:, 1], feats[:, 0])[:, None] / 2, ring[None])
    nearest = np.sort(d, axis=1)
    if k > 8 or np.unique(d.argmin(axis=1)).size < k or np.any(nearest[:, 1] - nearest[:, 0] < 1e-6):
        return          # centres contend for one camera axis: the order they pick in decides (by angle)
    alpha = 2 * np.pi * turns / 16
    est2 = _turn(est, alpha, np.zeros(2))
    got = clustering_select(yaw, est, k, seed=0, camera_xy=xy)
    got2 = clustering_select(yaw, est2[::-1] if reverse else est2, k, seed=0, camera_xy=xy)
    axis = lambda a: np.sort(np.round(np.asarray(a) % np.pi, 9) % np.round(np.pi, 9))
    np.testing.assert_allclose(axis(yaw[got2]), axis(yaw[got] + alpha), atol=1e-8)


@pytest.mark.parametrize("seed", range(6))                 # seeds 3-5: k-means' one centre is off camera 0's axis
def test_clustering_of_one_camera_is_uniform(seed):
    """k = 1: every pair axis comes with its perpendicular, so the doubled-angle points sum
    to zero and a single k-means centre's angle was rounding noise (reversing the estimates
    changed the camera); one camera has no cluster direction, so it is uniform's."""
    rng = np.random.default_rng(seed)
    est = rng.uniform(-0.8, 0.8, (3, 2))
    xy, yaw = ring_cameras(16)
    got = [choose_cameras("clustering", 1, xy, yaw, np.pi, e, R, ROOM).tolist() for e in (est, est[::-1])]
    assert got == [choose_cameras("uniform", 1, xy, yaw, np.pi, est, R, ROOM).tolist()] * 2


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 8), st.integers(0, 5), st.floats(0.3, 2 * np.pi - 0.3),
       st.booleans())
def test_subset_areas_are_the_shapely_hull_and_shrink_as_cameras_are_added(seed, n, m, fov, inside):
    rng = np.random.default_rng(seed)
    room = circle_room(quad_segs=16)
    c = random_discs(rng, m)
    xy, yaw = ring_cameras(n, phase=rng.uniform(0, 2 * np.pi))
    if inside:                                          # cameras anywhere inside, clear of the discs
        pts = []
        while len(pts) < n:
            p = rng.uniform(-1, 1, 2)
            if np.hypot(*p) < 1 and (m == 0 or np.all(np.hypot(*(c - p).T) > R + 0.01)):
                pts.append(p)
        xy = np.array(pts)
    yaw = yaw + rng.normal(0, 0.3, n)
    w = free_wedges_from_discs(xy, yaw, fov, c, R, room)
    cov = coverage_cells(w, room)
    assert cov.areas.sum() == pytest.approx(room.area, abs=1e-9)
    order = rng.permutation(n)
    chain = [order[:j] for j in range(1, n + 1)]                  # one camera added at a time
    table = np.array([subset_areas(cov, s[None])[0] for s in chain])
    direct = [shapely.difference(room, shapely.union_all(w[s])).area for s in chain]
    np.testing.assert_allclose(table, direct, rtol=1e-9, atol=1e-9)
    assert np.all(np.diff(np.r_[room.area, table]) <= 1e-12)


def _wall_rig():
    """Square room, 180-degree cameras on the walls (wedge edges run along the walls)."""
    room = box(-1, -1, 1, 1)
    xy = np.array([[0, -1], [1, 0], [0, 1], [-1, 0], [-0.5, -1], [1, 0.5], [0.5, 1], [-1, -0.5]])
    yaw = np.array([0.5, 1, 1.5, 0, 0.5, 1, 1.5, 0]) * np.pi
    return room, xy.astype(float), yaw


@pytest.mark.parametrize("rig", ["circle", "walls"])
def test_coverage_table_matches_geometry(rig):
    if rig == "circle":
        room, (xy, yaw, c) = ROOM, drop(2, n=8, m=3)
    else:
        room, xy, yaw = _wall_rig()
        c = np.array([[0.2, 0.3], [-0.4, -0.1], [0.5, -0.5]])
    w = free_wedges_from_discs(xy, yaw, np.pi, c, R, room)
    cov = coverage_cells(w, room)
    subsets = np.array(list(combinations(range(8), 3)))
    table = subset_areas(cov, subsets)
    direct = [hull_from_wedges(w, room, s).area for s in subsets]
    np.testing.assert_allclose(table, direct, rtol=1e-9, atol=1e-12)


def test_optimal_matches_brute_force_over_hulls():
    xy, yaw, c = drop(4, n=9, m=4)
    w = free_wedges_from_discs(xy, yaw, np.pi, c, R, ROOM)
    areas = {s: hull_from_wedges(w, ROOM, list(s)).area for s in combinations(range(9), 3)}
    got = choose_cameras("optimal", 3, xy, yaw, np.pi, c, R, ROOM)
    assert areas[tuple(got)] == pytest.approx(min(areas.values()), rel=1e-9)


@pytest.mark.parametrize(
    "n, fov, centres, k",
    [
        (16, np.pi, [[0.0, 0.0]], 1),  # one disc at the centre: all 16 cameras tie
        (16, np.pi, [[0.0, 0.0]], 3),
        (12, np.radians(49), np.zeros((0, 2)), 1),
        (16, np.radians(49), np.zeros((0, 2)), 2),
    ],
)
def test_optimal_ties_go_to_the_first_subset(n, fov, centres, k):
    """Symmetric rings tie up to ~1e-13 m^2 of summation noise; noise must not pick."""
    xy, yaw = ring_cameras(n)
    c = np.asarray(centres, dtype=float).reshape(-1, 2)
    w = free_wedges_from_discs(xy, yaw, fov, c, R, ROOM)
    areas = {s: hull_from_wedges(w, ROOM, list(s)).area for s in combinations(range(n), k)}
    best = min(areas.values())
    first = next(s for s in combinations(range(n), k) if areas[s] <= best + 1e-9 * ROOM.area)
    got = choose_cameras("optimal", k, xy, yaw, fov, c, R, ROOM)
    assert got.tolist() == list(first)


def test_naive_greedy_agrees_with_production_greedy():
    xy, yaw, c = drop(7, n=12, m=5)
    w = free_wedges_from_discs(xy, yaw, np.pi, c, R, ROOM)
    naive = naive_greedy_select(w, ROOM, 5)
    fast, hull = greedy_select(w, ROOM, 5)
    assert hull_from_wedges(w, ROOM, naive).area == pytest.approx(hull.area, rel=1e-9)
    assert sorted(naive) == sorted(fast)


def test_incremental_swaps_m_cameras_and_keeps_k():
    xy, yaw, c = drop(8, n=16, m=5)
    current = np.arange(8)
    new = choose_cameras("incremental", 8, xy, yaw, np.pi, c, R, ROOM, current=current, m=2)
    assert new.size == 8 and np.unique(new).size == 8
    assert np.setdiff1d(current, new).size <= 2
    assert area_of(new, xy, yaw, c) <= area_of(current, xy, yaw, c) + 1e-12
    # without a current set it is greedy
    g = choose_cameras("greedy", 8, xy, yaw, np.pi, c, R, ROOM)
    assert choose_cameras("incremental", 8, xy, yaw, np.pi, c, R, ROOM).tolist() == g.tolist()


def test_incremental_tasker_schedule():
    xy, yaw, c = drop(9, n=12, m=4)
    tasker = IncrementalTasker(k=4, m=1, update_every=3)
    first = tasker.step(0, xy, yaw, np.pi, c, R, ROOM)
    assert first.tolist() == choose_cameras("greedy", 4, xy, yaw, np.pi, c, R, ROOM).tolist()
    moved = c + 0.05
    kept = tasker.step(1, xy, yaw, np.pi, moved, R, ROOM)
    assert kept.tolist() == first.tolist()  # not an update frame
    upd = tasker.step(3, xy, yaw, np.pi, moved, R, ROOM)
    expect = choose_cameras("incremental", 4, xy, yaw, np.pi, moved, R, ROOM, current=first)
    assert upd.tolist() == expect.tolist()


def test_estimates_may_overlap_and_cover_a_camera():
    # estimates are polygon centres, not real objects: overlap is fine, and a camera
    # inside an estimated disc is simply blind
    xy, yaw = ring_cameras(8)
    est = np.array([[0.0, 0.0], [0.05, 0.0], [0.95, 0.0]])
    for tasker in TASKERS:
        sel = choose_cameras(tasker, 3, xy, yaw, np.pi, est, R, ROOM, current=[0, 1, 2])
        assert sel.size == 3


def test_lab_room_with_narrow_fov():
    room = box(0, 0, 6.7056, 5.7912)
    xs = np.linspace(0.5, 6.2, 4)
    xy = np.r_[np.c_[xs, np.zeros(4)], np.c_[xs, np.full(4, 5.7912)]]
    yaw = np.r_[np.full(4, np.pi / 2), np.full(4, -np.pi / 2)]
    est = np.array([[2.0, 2.0], [4.5, 3.5], [3.0, 4.0]])
    fov = np.radians(49)
    g = choose_cameras("greedy", 4, xy, yaw, fov, est, 0.25, room)
    lz = choose_cameras("lazy_greedy", 4, xy, yaw, fov, est, 0.25, room)
    opt = choose_cameras("optimal", 4, xy, yaw, fov, est, 0.25, room)
    assert g.tolist() == lz.tolist()
    w = free_wedges_from_discs(xy, yaw, fov, est, 0.25, room, strict=False)
    assert hull_from_wedges(w, room, opt).area <= hull_from_wedges(w, room, g).area + 1e-9


# --- properties -----------------------------------------------------------------------


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(6, 11), st.integers(1, 5), st.integers(1, 4))
def test_optimal_never_worse_than_greedy_and_lazy_equals_greedy(seed, n, m, k):
    rng = np.random.default_rng(seed)
    xy, yaw = ring_cameras(n, phase=rng.uniform(0, 2 * np.pi))
    c = random_discs(rng, m)
    fov = rng.choice([np.pi, np.radians(49), np.radians(120)])
    w = free_wedges_from_discs(xy, yaw, fov, c, R, ROOM)
    g, _ = greedy_select(w, ROOM, k)
    lz, _ = lazy_greedy_select(w, ROOM, k)
    assert g == lz  # same cameras in the same order
    opt = choose_cameras("optimal", k, xy, yaw, fov, c, R, ROOM)
    assert hull_from_wedges(w, ROOM, opt).area <= hull_from_wedges(w, ROOM, g).area + 1e-9


def test_greedy_beats_uniform_on_average():
    # not per instance: over seeded random drops of 5 objects, 16 cameras, k = 4 and 6
    diffs = []
    for seed in range(12):
        xy, yaw, c = drop(100 + seed, n=16, m=5)
        for k in (4, 6):
            g = choose_cameras("greedy", k, xy, yaw, np.pi, c, R, ROOM)
            u = choose_cameras("uniform", k, xy, yaw, np.pi, c, R, ROOM)
            diffs.append(area_of(u, xy, yaw, c) - area_of(g, xy, yaw, c))
    assert np.mean(diffs) > 0


# --- errors ---------------------------------------------------------------------------

XY, YAW = ring_cameras(6)
EST = np.array([[0.2, 0.0], [-0.3, 0.1]])


@pytest.mark.parametrize(
    "tasker, k, kwargs, match",
    [
        ("best", 2, {}, "tasker: unknown value 'best'; expected one of uniform, clustering, optimal"),
        ("greedy", 7, {}, "k must be >= 1 and <= 6"),
        ("greedy", 0, {}, "k must be >= 1"),
        ("incremental", 2, {"m": 3}, "m must be >= 1 and <= 2"),
        ("incremental", 2, {"m": 0}, "m must be >= 1"),
        ("incremental", 2, {"current": [0, 1, 2]}, "current must hold 2 indices"),
        ("incremental", 2, {"current": [0, 9]}, "current must be 0-based indices"),
        ("optimal", 3, {"max_subsets": 10}, r"max_subsets: optimal needs C\(6, 3\) = 20"),
        ("uniform", 2, {"uniform_sets": {2: [0, 0]}}, r"uniform_sets\[2\] must not repeat"),
        ("clustering", 2, {"rng": 3}, "rng must be a numpy Generator"),
        # docs/tasking.md lists max_subsets among the validated parameters: None or a string
        # ended in "TypeError: '>' not supported", 2.5 and True were compared as numbers
        ("optimal", 3, {"max_subsets": None}, "max_subsets must be an integer; got None"),
        ("optimal", 3, {"max_subsets": "100"}, "max_subsets must be an integer; got '100'"),
        ("optimal", 3, {"max_subsets": 2.5}, "max_subsets must be an integer; got 2.5"),
        ("optimal", 3, {"max_subsets": 0}, "max_subsets must be >= 1; got 0"),
        ("greedy", 3, {"max_subsets": None}, "max_subsets must be an integer; got None"),
        # a list of sets was never looked up (`k in` the list), so the default spread was used
        ("uniform", 2, {"uniform_sets": [(0, 3)]}, "uniform_sets must be a mapping k -> k camera indices; got list"),
    ],
)
def test_choose_errors(tasker, k, kwargs, match):
    with pytest.raises(ValueError, match=match):
        choose_cameras(tasker, k, XY, YAW, np.pi, EST, R, ROOM, **kwargs)


@pytest.mark.parametrize(
    "args, match",
    [
        (dict(camera_xy=np.empty((0, 2))), "camera_xy must not be empty"),
        (dict(estimates=[[np.nan, 0.0]]), "estimates must be finite"),
        (dict(fov=0.0), "fov must be in"),
        (dict(camera_yaw=YAW[:3]), r"camera_yaw must have shape \(6,\)"),
        (dict(radius=-0.1), "radius must be finite and > 0"),
        # numpy's conversion errors named no parameter ("could not convert string to float: 'x'")
        (dict(camera_xy="x"), "^camera_xy must be numbers"),
        (dict(estimates=[[0.1, 0.2], [0.3]]), "^estimates must be an array of floats, its rows of one length"),
        (dict(camera_yaw=["a"] * 6), "^camera_yaw must be numbers"),
        (dict(fov="wide"), "^fov must be numbers"),
        (dict(radius="r"), "^radius must be numbers"),
    ],
)
def test_choose_input_errors(args, match):
    base = dict(camera_xy=XY, camera_yaw=YAW, fov=np.pi, estimates=EST, radius=R, room=ROOM)
    base.update(args)
    with pytest.raises(ValueError, match=match):
        choose_cameras("greedy", 2, **base)


@pytest.mark.parametrize("room", ["lab", 5, None])
def test_incremental_refuses_a_room_that_is_not_a_polygon_like_the_others(room):
    """With a current set the incremental tasker looked for a convex room before the room was
    checked: a string or a number ended in shapely's 'TypeError: One of the arguments is of
    incorrect type' where every other tasker says what room must be."""
    for tasker in TASKERS:
        with pytest.raises(ValueError, match="room must be a shapely Polygon"):
            choose_cameras(tasker, 2, XY, YAW, np.pi, EST, R, room, current=[0, 1])


def test_incremental_tasker_errors():
    with pytest.raises(ValueError, match="update_every must be >= 1"):
        IncrementalTasker(3, 1, 0)
    with pytest.raises(ValueError, match="m must be >= 1 and <= 3"):
        IncrementalTasker(3, 4)


def test_incremental_tasker_refuses_another_network():
    """Its tasked set indexes the network of its earlier steps: a step with fewer cameras
    named `current` (an argument the caller never passed), and on a frame between updates
    returned indices of the old network without a word."""
    xy, yaw, c = drop(9, n=12, m=4)
    for frame in (1, 3):                    # between updates, and an update frame
        tasker = IncrementalTasker(k=4, m=1, update_every=3)
        tasker.step(0, xy, yaw, np.pi, c, R, ROOM)
        with pytest.raises(ValueError, match="camera_xy has 8 cameras, but this IncrementalTasker tasks 4 of 12"):
            tasker.step(frame, xy[:8], yaw[:8], np.pi, c, R, ROOM)


# --- fast removal vs reference -----------------------------------------------------------


@pytest.mark.parametrize("fov", [np.pi, np.radians(49.0)])
@pytest.mark.parametrize("seed", range(6))
def test_greedy_remove_matches_reference(fov, seed):
    from tasking.taskers import greedy_remove, greedy_remove_reference

    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(6, 17))
    xy, yaw = ring_cameras(n)
    c = random_discs(rng, int(rng.integers(1, 6)))
    w = free_wedges_from_discs(xy, yaw, fov, c, R, ROOM, strict=False)
    k = int(rng.integers(2, n + 1))
    current = np.sort(rng.choice(n, k, replace=False))
    for m in range(1, min(k, 3) + 1):
        kept, removed, h = greedy_remove(w, ROOM, current, m)
        kept_r, removed_r, h_r = greedy_remove_reference(w, ROOM, current, m)
        assert (kept, removed) == (kept_r, removed_r)
        assert abs(h.area - h_r.area) <= 1e-9 * max(h_r.area, 1e-12)
        exact = hull_from_wedges(w, ROOM, kept).area
        assert abs(h.area - exact) <= 1e-9 * ROOM.area


def test_greedy_remove_down_to_one_camera():
    from tasking.taskers import greedy_remove, greedy_remove_reference

    xy, yaw, c = drop(3, n=6, m=3)
    w = free_wedges_from_discs(xy, yaw, np.pi, c, R, ROOM)
    for m in (2, 3):
        got = greedy_remove(w, ROOM, [1, 3, 4], m)
        ref = greedy_remove_reference(w, ROOM, [1, 3, 4], m)
        assert got[:2] == ref[:2]
        assert abs(got[2].area - ref[2].area) <= 1e-9 * ROOM.area


# --- overlay-free incremental step (convex rooms) vs the polygon reference --------------


def _reference_incremental(w, room, current, m):
    """Reference removal, then plain greedy adds by full hull areas (lowest index on ties)."""
    from tasking.taskers import LAZY_TOL, greedy_remove_reference

    kept, _, _ = greedy_remove_reference(w, room, current, m)
    tol = LAZY_TOL * room.area
    for _ in range(len(current) - len(kept)):
        cand = [c for c in range(len(w)) if c not in kept]
        areas = np.array([hull_from_wedges(w, room, kept + [c]).area for c in cand])
        kept = kept + [cand[int(np.flatnonzero(areas <= areas.min() + tol)[0])]]
    return sorted(kept)


def _check_convex_step(xy, yaw, fov, c, room, current, m):
    from tasking.cones import wedge_radius
    from tasking.fan import UnionAreas, convex_ring, split_wide
    from tasking.taskers import incremental_select_convex

    w, cones = free_wedges_from_discs(xy, yaw, fov, c, R, room, strict=False,
                                      return_cones=True)
    ring = convex_ring(room)
    assert ring is not None
    got = incremental_select_convex(xy, cones, room, ring, current, m)
    assert got == _reference_incremental(w, room, list(current), m)
    assert choose_cameras("incremental", len(current), xy, yaw, fov, c, R, room,
                          current=current, m=m).tolist() == got
    # the covered areas themselves agree with GEOS
    ua = UnionAreas(ring, split_wide(*cones), len(xy), wedge_radius(room, xy))
    rng = np.random.default_rng(len(xy) + m)
    sets = rng.random((6, len(xy))) < 0.5
    ref = [room.area - hull_from_wedges(w, room, np.flatnonzero(s)).area for s in sets]
    assert np.allclose(ua(sets), ref, rtol=0, atol=1e-10 * room.area)


@pytest.mark.parametrize("fov", [np.pi, np.radians(49.0)])
@pytest.mark.parametrize("seed", range(6))
def test_incremental_convex_matches_polygon_reference(fov, seed):
    rng = np.random.default_rng(300 + seed)
    n = int(rng.integers(6, 17))
    xy, yaw = ring_cameras(n)
    c = random_discs(rng, int(rng.integers(1, 6)))
    k = int(rng.integers(2, n + 1))
    current = np.sort(rng.choice(n, k, replace=False))
    for m in range(1, min(k, 3) + 1):
        _check_convex_step(xy, yaw, fov, c, ROOM, current, m)


@pytest.mark.parametrize("fov", [np.pi, np.radians(49.0), np.radians(120.0)])
def test_incremental_convex_lab_room_with_rays_along_walls(fov):
    # 180-degree cameras on the walls: their field-of-view edges run along the walls
    room = box(0, 0, 6.7056, 5.7912)
    xs = np.linspace(0.5, 6.2, 4)
    xy = np.r_[np.c_[xs, np.zeros(4)], np.c_[xs, np.full(4, 5.7912)],
               [[0.0, 2.0], [6.7056, 3.5]]]
    yaw = np.r_[np.full(4, np.pi / 2), np.full(4, -np.pi / 2), [0.0, np.pi]]
    est = np.array([[2.0, 2.0], [4.5, 3.5], [3.0, 4.0]])
    for m in (1, 2):
        _check_convex_step(xy, yaw, fov, est, room, [0, 2, 5, 7, 8], m)
    # no estimates, and a camera inside an estimate (blind)
    _check_convex_step(xy, yaw, fov, np.empty((0, 2)), room, [1, 4, 9], 1)
    _check_convex_step(xy, yaw, fov, np.array([[0.5, 0.05]]), room, [0, 3, 6], 2)


def test_non_convex_room_uses_the_polygon_path():
    from tasking.fan import convex_ring

    room = box(0, 0, 2, 2).difference(box(1, 1, 2, 2))
    assert convex_ring(room) is None
    assert convex_ring(box(0, 0, 2, 2).difference(box(0.5, 0.5, 1, 1))) is None
    xy = np.array([[0.0, 0.5], [0.5, 0.0], [2.0, 0.5], [0.5, 2.0]])
    yaw = np.array([0.0, np.pi / 2, np.pi, -np.pi / 2])
    got = choose_cameras("incremental", 2, xy, yaw, np.pi, [[0.5, 0.5]], R, room,
                         current=[0, 1], m=1)
    assert got.size == 2


def test_union_areas_many_cameras_uses_the_cover_table():
    # more than 62 cameras: no int64 bitmasks, the (piece, camera) table instead
    from tasking.cones import wedge_radius
    from tasking.fan import UnionAreas, convex_ring, split_wide

    xy, yaw = ring_cameras(70)
    c = random_discs(np.random.default_rng(7), 4)
    w, cones = free_wedges_from_discs(xy, yaw, np.pi, c, R, ROOM, strict=False,
                                      return_cones=True)
    ua = UnionAreas(convex_ring(ROOM), split_wide(*cones), 70, wedge_radius(ROOM, xy))
    assert ua.bits is None
    sets = np.zeros((3, 70), dtype=bool)
    sets[0, [0, 30, 65]] = True
    sets[1, ::9] = True
    sets[2, [5]] = True
    ref = [ROOM.area - hull_from_wedges(w, ROOM, np.flatnonzero(s)).area for s in sets]
    assert np.allclose(ua(sets), ref, rtol=0, atol=1e-10 * ROOM.area)


def test_greedy_ties_go_to_the_lowest_index_whatever_the_rounding():
    # no estimates: every camera removes as much as the next, up to overlay rounding
    from testbed.studies import core

    room = core.circle_room(1.0)
    xy, yaw = core.circle_cameras(8)
    for tasker in ("greedy", "lazy_greedy", "optimal"):
        assert choose_cameras(tasker, 3, xy, yaw, core.FOV, np.zeros((0, 2)), 0.1, room).tolist() == [0, 1, 2]


def test_optimal_ties_go_to_the_first_subset_across_scoring_blocks(monkeypatch):
    """Ties are broken in lexicographic order over all C(n, k) subsets, not only inside one
    block of CHUNK subsets (the lab's C(16, 8) = 12870 spans four blocks)."""
    from tasking import choose_cameras, coverage

    monkeypatch.setattr(coverage, "CHUNK", 7)
    xy, yaw = ring_cameras(12)
    got = choose_cameras("optimal", 2, xy, yaw, np.radians(49), np.zeros((0, 2)), R, ROOM)
    monkeypatch.setattr(coverage, "CHUNK", 4096)
    assert got.tolist() == choose_cameras("optimal", 2, xy, yaw, np.radians(49), np.zeros((0, 2)), R,
                                          ROOM).tolist()


def test_incremental_tasker_updates_exactly_on_multiples_of_update_every(monkeypatch):
    from tasking import taskers

    frames = []
    real = taskers.choose_cameras

    def spy(*a, **kw):
        frames.append(current_frame[0])
        return real(*a, **kw)

    monkeypatch.setattr(taskers, "choose_cameras", spy)
    xy, yaw = ring_cameras(12)
    est = np.array([[0.2, 0.1], [-0.3, 0.2]])
    tasker = IncrementalTasker(k=4, m=1, update_every=3)
    current_frame = [None]
    for f in range(8):
        current_frame[0] = f
        tasker.step(f, xy, yaw, np.pi, est, R, ROOM)
    assert frames == [0, 3, 6]


def test_non_convex_room_incremental_swaps_to_a_smaller_hull():
    """The polygon path (a room that is not convex) must actually swap: returning ``current``
    unchanged passed test_non_convex_room_uses_the_polygon_path, which checks only the size."""
    from shapely.geometry import box

    from tasking import choose_cameras, hull_from_wedges

    room = box(0, 0, 2, 2).difference(box(1, 1, 2, 2))
    xy = np.array([[0.0, 0.5], [0.5, 0.0], [2.0, 0.5], [0.5, 2.0]])
    yaw = np.array([0.0, np.pi / 2, np.pi, -np.pi / 2])
    w = free_wedges_from_discs(xy, yaw, np.pi, [[0.5, 0.5]], R, room, strict=False)
    for current in ([0, 2], [1, 3]):
        got = choose_cameras("incremental", 2, xy, yaw, np.pi, [[0.5, 0.5]], R, room, current=current, m=1)
        assert got.tolist() == [2, 3]
        assert hull_from_wedges(w, room, got).area < 0.25 * hull_from_wedges(w, room, current).area


def test_optimal_subset_beyond_63_cameras_is_the_smallest_table_area():
    """More than 63 cameras do not fit uint64 bit masks: the other branch scores by the table."""
    from tasking.coverage import optimal_subset

    xy, yaw = ring_cameras(65)
    c = np.array([[0.3, 0.1], [-0.4, 0.2]])
    cov = coverage_cells(free_wedges_from_discs(xy, yaw, np.radians(60), c, R, ROOM), ROOM)
    subsets = np.array(list(combinations(range(65), 2)))
    scores = subset_areas(cov, subsets)
    got = optimal_subset(cov, 2)
    assert subset_areas(cov, [got])[0] == pytest.approx(scores.min(), abs=1e-12)


@pytest.mark.parametrize("chunk", [1, 2, 4096])
def test_optimal_subset_is_the_first_within_tol_of_the_smallest_whatever_the_blocks(monkeypatch, chunk):
    """Single-camera subsets scoring 1 + 5 tol, 1, 1 - 0.8 tol and 1 - 1.5 tol: the smallest is
    the last, the first within tol of it the third. Ties were judged against the best of the
    blocks scored so far, so the answer hung on CHUNK: 1 gave the last, 2 the second (1.5 tol
    above the smallest, outside the documented tie), one block the third."""
    from tasking import coverage
    from tasking.coverage import Coverage, optimal_subset

    monkeypatch.setattr(coverage, "CHUNK", chunk)
    tol = 1e-9
    masks = ~np.eye(4, dtype=bool)                 # cell c is left uncovered by camera c alone
    cov = Coverage(masks, np.array([1.0 + 5 * tol, 1.0, 1.0 - 0.8 * tol, 1.0 - 1.5 * tol]))
    assert optimal_subset(cov, 1, tol=tol) == [2]


# --- the polygon path against the paper's algorithm ---------------------------------------

L_ROOM = box(0, 0, 4, 4).difference(box(2, 2, 4, 4))       # not convex: the overlay path
L_XY = np.array([[0.0, 1.0], [0.0, 3.0], [1.0, 0.0], [3.0, 0.0], [4.0, 1.0], [2.0, 3.0],
                 [1.0, 4.0], [3.0, 2.0], [0.0, 0.2], [3.8, 0.0]])
L_YAW = np.array([0.0, -0.3, np.pi / 2, 1.9, np.pi, -np.pi / 2 - 0.2, -np.pi / 2, np.pi + 0.4,
                  0.7, 2.4])
L_EST = np.array([[0.7, 0.8], [1.5, 2.9], [3.1, 1.2], [1.4, 1.6]])


def paper_incremental(wedges, room, current, m):
    """Section 4.5 by brute force: m times remove the camera whose removal leaves the
    smallest hull, then m times add the one that gives the smallest hull."""
    s = sorted(current)
    for _ in range(m):
        s.pop(int(np.argmin([hull_from_wedges(wedges, room, [c for c in s if c != r]).area for r in s])))
    for _ in range(m):
        cand = [c for c in range(len(wedges)) if c not in s]
        s.append(cand[int(np.argmin([hull_from_wedges(wedges, room, s + [c]).area for c in cand]))])
    return sorted(s)


@pytest.mark.parametrize("current, m", [([0, 1, 2, 3], 1), ([0, 1, 2, 3], 2), ([5, 6, 8, 9], 2)])
def test_incremental_in_a_non_convex_room_is_the_papers_remove_then_add(current, m):
    """In an L-shaped room the incremental tasker swaps m cameras as section 4.5 says (not a
    fresh greedy choice, which is another set here)."""
    w = free_wedges_from_discs(L_XY, L_YAW, np.pi, L_EST, R, L_ROOM, strict=False)
    got = choose_cameras("incremental", 4, L_XY, L_YAW, np.pi, L_EST, R, L_ROOM, current=current, m=m)
    assert got.tolist() == paper_incremental(w, L_ROOM, current, m)
    greedy = choose_cameras("greedy", 4, L_XY, L_YAW, np.pi, L_EST, R, L_ROOM)
    assert greedy.tolist() != got.tolist()


def test_a_radius_per_estimate_is_accepted():
    """radius may be a (p,) array (docs), for any p: equal radii choose as the scalar does."""
    xy, yaw, c = drop(3, n=10, m=3)
    for tasker in ("optimal", "greedy", "incremental"):
        one = choose_cameras(tasker, 3, xy, yaw, np.pi, c, R, ROOM, current=[0, 1, 2])
        each = choose_cameras(tasker, 3, xy, yaw, np.pi, c, np.full(3, R), ROOM, current=[0, 1, 2])
        assert each.tolist() == one.tolist(), tasker
    with pytest.raises(ValueError, match="radius"):
        choose_cameras("greedy", 3, xy, yaw, np.pi, c, np.full(2, R), ROOM)


def test_incremental_tasker_defaults_are_the_papers_one_swap_every_frame():
    """IncrementalTasker(k): m = 1 and an update on every frame (the paper's setting);
    k = 1 is a valid size and a negative frame index is refused."""
    xy, yaw, c = drop(9, n=12, m=4)
    tasker = IncrementalTasker(4)
    first = tasker.step(0, xy, yaw, np.pi, c, R, ROOM)
    moved = -c[:, ::-1]
    expect = choose_cameras("incremental", 4, xy, yaw, np.pi, moved, R, ROOM, current=first, m=1)
    assert expect.tolist() != first.tolist()
    assert tasker.step(1, xy, yaw, np.pi, moved, R, ROOM).tolist() == expect.tolist()
    one = IncrementalTasker(1).step(0, xy, yaw, np.pi, c, R, ROOM)
    assert one.tolist() == choose_cameras("greedy", 1, xy, yaw, np.pi, c, R, ROOM).tolist()
    with pytest.raises(ValueError, match="frame_index"):
        tasker.step(-1, xy, yaw, np.pi, c, R, ROOM)


def test_cluster_axes_return_the_first_of_two_twin_solutions_whatever_the_kmeans_seed():
    """Of a solution and its twin turned by pi / 2 (equal inertia), the one whose centres
    (largest cluster first) come first is returned, whichever k-means found: k-means seeds
    stand in for the rounding of other thread counts."""
    for s in (3, 4, 5):
        axes = pair_axes(np.random.default_rng(s).uniform(-0.8, 0.8, (5, 2)))
        for k in (3, 4):
            for seed in range(3):
                centres, sizes = cluster_axes(axes, k, seed=seed)
                twin = (centres + np.pi / 2) % np.pi
                order = np.lexsort((twin, -sizes))
                assert tuple(np.round(centres, 9)) <= tuple(np.round(twin[order], 9))


def test_clustering_of_people_in_a_row_takes_each_of_the_two_axes_twice():
    """Three people on a line give two pair axes (along it and across it), fewer than k = 4:
    the two centres pick again in the same order, each its second camera on that axis
    (docs), here the opposite camera of the ring: 0 and 8 look along x, 4 and 12 across."""
    from tasking.clustering import clustering_select

    xy, yaw = ring_cameras(16)
    row = np.array([[-0.6, 0.1], [0.0, 0.1], [0.5, 0.1]])
    centres, sizes = cluster_axes(pair_axes(row), 4, seed=0)
    assert sizes.tolist() == [3, 3]
    np.testing.assert_allclose(np.sort(axial_distance(centres, 0.0)), [0.0, np.pi / 2], atol=1e-9)
    assert clustering_select(yaw, row, 4, seed=0, camera_xy=xy).tolist() == [0, 4, 8, 12]


@pytest.mark.parametrize("eps", [1e-10, 3e-10])
def test_cluster_axes_of_axes_k_means_cannot_tell_apart_are_nonempty_and_below_pi(eps):
    """Axes 1e-10 rad apart count as distinct to 1e-12 but not to k-means' distances: it
    found 3 clusters of 5, returned the 2 empty ones (size 0) with a ConvergenceWarning,
    and one centre at exactly pi (a tiny negative angle % pi)."""
    import warnings

    axes = np.array([0.0, eps, np.pi / 2, np.pi / 2 + eps, 0.3])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        centres, sizes = cluster_axes(axes, 5, seed=0)
    assert sizes.min() >= 1 and sizes.sum() == axes.size
    assert np.all((centres >= 0) & (centres < np.pi))
    for c in centres:                                   # each centre on one of the three axes
        assert axial_distance(c, np.array([0.0, np.pi / 2, 0.3])).min() < 1e-8


def test_axial_distance_is_the_angle_between_two_axes_in_0_to_a_right_angle():
    """Hand values: axes a quarter turn apart are pi / 2 apart whichever way round, axes pi or
    2 pi apart coincide, and 170 degrees from 10 degrees is 20 degrees."""
    d = axial_distance(np.radians([0.0, 90.0, 0.0, 30.0, 10.0, 0.0]),
                       np.radians([90.0, 0.0, 180.0, 390.0, 170.0, 135.0]))
    np.testing.assert_allclose(d, np.radians([90.0, 90.0, 0.0, 0.0, 20.0, 45.0]), atol=1e-12)


def test_pair_axes_by_hand_lie_in_0_to_pi():
    """Pairs (0, 0)-(1, 1) and (0, 0)-(-1, 1): axes 45 and 135 degrees, each with its
    perpendicular, which wraps into [0, pi): 135 and 45; and (-1, 1)-(1, 1): 0 and 90."""
    got = pair_axes(np.array([[0.0, 0.0], [1.0, 1.0], [-1.0, 1.0]]))
    # pairs in order (0, 1), (0, 2), (1, 2): axes first, then their perpendiculars
    np.testing.assert_allclose(got, np.radians([45.0, 135.0, 0.0, 135.0, 45.0, 90.0]), atol=1e-12)


def _optimal_partitions(axes, k):
    """Every k-partition of the doubled-angle points of ``axes`` with the least k-means
    inertia (brute force over all labelings), as (sorted centre angles, sorted sizes)."""
    from itertools import product

    feats = np.c_[np.cos(2 * axes), np.sin(2 * axes)]
    found = []
    for lab in product(range(k), repeat=len(axes)):
        lab = np.array(lab)
        if np.unique(lab).size < k or lab[0] != 0:
            continue
        means = np.array([feats[lab == j].mean(axis=0) for j in range(k)])
        inertia = sum(((feats[lab == j] - means[j]) ** 2).sum() for j in range(k))
        found.append((inertia, np.arctan2(means[:, 1], means[:, 0]) / 2 % np.pi, np.bincount(lab)))
    best = min(f[0] for f in found)
    return [(np.sort(c), np.sort(s)) for i, c, s in found if i <= best + 1e-9]


@pytest.mark.parametrize("seed, k", [(0, 3), (0, 4), (14, 2), (14, 3)])
def test_cluster_axes_find_the_least_inertia_partition(seed, k):
    """Three estimates give six axes; the clusters are the k-partition of least inertia, found
    by brute force over every labeling (here a single k-means start ends in a worse one)."""
    axes = pair_axes(np.random.default_rng(seed).uniform(-0.8, 0.8, (3, 2)))
    centres, sizes = cluster_axes(axes, k, seed=0)
    assert any(np.allclose(np.sort(centres), c, atol=1e-9) and np.array_equal(np.sort(sizes), s)
               for c, s in _optimal_partitions(axes, k))


def test_clustering_ties_in_a_second_round_go_to_the_camera_farthest_from_its_nearest_chosen():
    """Two estimates along x: axes 0 and 90, fewer than k = 3, so axis 0 picks twice (docs).
    First camera 1 (the lowest index of the axis-0 cameras 1, 2, 3), then camera 0 for axis 90;
    in the second round cameras 2 and 3 tie on axis 0, and the one whose nearest chosen
    camera is farther wins: 3 (5 m from both) over 2 (4.7 m from camera 1, though 11 m from
    camera 0), by 0.3 m. The result is sorted, not in picking order."""
    from tasking.clustering import clustering_select

    xy = np.array([[10.0, 0.0], [0.0, 0.0], [0.0, 4.7], [5.0, 0.0]])
    yaw = np.radians([90.0, 0.0, 0.0, 180.0])
    est = np.array([[0.0, 0.0], [1.0, 0.0]])
    assert clustering_select(yaw, est, 3, seed=0, camera_xy=xy).tolist() == [0, 1, 3]


def test_coverage_of_a_room_with_a_hole_leaves_the_hole_out():
    """A pillar (a hole) is a closed ring of the arrangement, but no cell: the cells sum to the
    room's area (15 m^2), and subset areas are the hulls'."""
    room = box(0, 0, 4, 4).difference(box(1.5, 1.5, 2.5, 2.5))
    xy = np.array([[0.0, 1.0], [1.0, 0.0], [4.0, 3.0], [3.0, 4.0]])
    yaw = np.array([0.3, np.pi / 2 + 0.2, np.pi - 0.1, -np.pi / 2])
    w = free_wedges_from_discs(xy, yaw, np.radians(100), [[0.8, 3.0]], R, room, strict=False)
    cov = coverage_cells(w, room)
    assert cov.areas.sum() == pytest.approx(15.0, abs=1e-9)
    subsets = [list(s) for j in range(1, 5) for s in combinations(range(4), j)]
    np.testing.assert_allclose([subset_areas(cov, [s])[0] for s in subsets],
                               [hull_from_wedges(w, room, s).area for s in subsets], rtol=0, atol=1e-9)


def test_coverage_table_is_read_only():
    w = free_wedges_from_discs(*ring_cameras(4), np.pi, [[0.2, 0.1]], R, ROOM)
    cov = coverage_cells(w, ROOM)
    for arr in (cov.masks, cov.areas):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = arr[0]


@pytest.mark.parametrize("n", [63, 64])
def test_optimal_subset_of_63_and_64_cameras_by_hand(n):
    """Cell u, of area 1 + |u - 40|, is covered by every camera but u: one camera leaves
    only its own cell in the hull, smallest for camera 40; any two cover everything (all
    tie: the first pair). 63 cameras are the most that fit the uint64 bit masks, 64 the
    first scored by the table."""
    from tasking.coverage import Coverage, optimal_subset

    cov = Coverage(~np.eye(n, dtype=bool), 1.0 + np.abs(np.arange(n) - 40))
    assert optimal_subset(cov, 1) == [40]
    assert optimal_subset(cov, 2) == [0, 1]


def _greedy_by_hulls(w, room, k, start=()):
    """Greedy by full hull areas (ties within LAZY_TOL of the room: lowest index)."""
    from tasking.taskers import LAZY_TOL

    chosen = []
    for _ in range(k):
        cand = [c for c in range(len(w)) if c not in chosen and c not in start]
        areas = np.array([hull_from_wedges(w, room, [*start, *chosen, c]).area for c in cand])
        chosen.append(cand[int(np.flatnonzero(areas <= areas.min() + LAZY_TOL * room.area)[0])])
    return chosen


def test_greedy_with_the_last_camera_blind():
    """The last camera stands inside an estimate, so it proves nothing empty (no wedge at all):
    the fast gains still cover every candidate, and greedy is greedy by full hulls."""
    xy, yaw = ring_cameras(8)
    est = np.array([[0.3, 0.1], [-0.2, -0.4], xy[7] * 0.95])
    w = free_wedges_from_discs(xy, yaw, np.pi, est, R, ROOM, strict=False)
    assert w[7].is_empty
    for tasker in ("greedy", "lazy_greedy"):
        got = choose_cameras(tasker, 7, xy, yaw, np.pi, est, R, ROOM)
        assert got.tolist() == sorted(_greedy_by_hulls(w, ROOM, 7)), tasker


def test_greedy_from_a_start_never_adds_a_camera_of_the_start():
    """Four 180-degree cameras on a ring, no objects: each sees the whole room, so camera 0
    alone empties it; every gain is then zero and the ties go to the lowest cameras not
    tasked, 1 and 2 (not 0 again)."""
    xy, yaw = ring_cameras(4)
    w, cones = free_wedges_from_discs(xy, yaw, np.pi, np.zeros((0, 2)), R, ROOM, return_cones=True)
    for c in (None, cones):
        for select in (greedy_select, lazy_greedy_select):
            chosen, hull = select(w, ROOM, 2, start=[0], cones=c)
            assert chosen == [1, 2] and hull.area < 1e-9 * ROOM.area


def test_greedy_returns_the_hull_of_its_choice():
    xy, yaw, c = drop(11, n=10, m=4)
    w = free_wedges_from_discs(xy, yaw, np.pi, c, R, ROOM)
    for select in (greedy_select, lazy_greedy_select):
        chosen, hull = select(w, ROOM, 4)
        assert hull.area == pytest.approx(hull_from_wedges(w, ROOM, chosen).area, rel=0, abs=1e-9)
    chosen, hull = lazy_greedy_select(w, ROOM, 4, final_hull=False)
    assert hull is None and len(chosen) == 4


def test_incremental_ties_go_to_the_lowest_index_whatever_the_rounding():
    """No objects and 180-degree cameras on a ring, each seeing the whole room: every hull is
    empty, up to rounding. Removals take the lowest kept index (3, then 5), adds the lowest
    free one (0, then 1)."""
    xy, yaw = ring_cameras(12)
    got = choose_cameras("incremental", 3, xy, yaw, np.pi, np.zeros((0, 2)), R, ROOM, current=[3, 5, 6], m=2)
    assert got.tolist() == [0, 1, 6]


def test_optimal_accepts_exactly_max_subsets():
    """C(6, 3) = 20 subsets with max_subsets = 20 is within the limit (19 is refused)."""
    got = choose_cameras("optimal", 3, XY, YAW, np.pi, EST, R, ROOM, max_subsets=20)
    assert got.size == 3
    with pytest.raises(ValueError, match="max_subsets"):
        choose_cameras("optimal", 3, XY, YAW, np.pi, EST, R, ROOM, max_subsets=19)


def test_incremental_tasker_first_step_off_the_schedule_is_greedy():
    """The first step tasks greedy's cameras even on a frame that is not an update frame."""
    xy, yaw, c = drop(9, n=12, m=4)
    got = IncrementalTasker(k=4, m=1, update_every=3).step(1, xy, yaw, np.pi, c, R, ROOM)
    assert got.tolist() == choose_cameras("greedy", 4, xy, yaw, np.pi, c, R, ROOM).tolist()


def test_incremental_tasker_swaps_its_m_and_hands_out_copies():
    xy, yaw, c = drop(9, n=12, m=4)
    tasker = IncrementalTasker(k=4, m=2)
    first = tasker.step(0, xy, yaw, np.pi, c, R, ROOM)
    kept = first.copy()
    first[:] = [8, 9, 10, 11]                           # the caller's array, not the tasker's state
    moved = -c                                          # m = 1 and m = 2 end in other sets here
    two = choose_cameras("incremental", 4, xy, yaw, np.pi, moved, R, ROOM, current=kept, m=2)
    one = choose_cameras("incremental", 4, xy, yaw, np.pi, moved, R, ROOM, current=kept, m=1)
    assert two.tolist() != one.tolist()
    assert tasker.step(1, xy, yaw, np.pi, moved, R, ROOM).tolist() == two.tolist()


def test_uniform_rounds_halves_up():
    """floor(i * 6 / 4 + 1/2) for i = 0..3: 0, 1.5 -> 2, 3, 4.5 -> 5 (halves up, not to even)."""
    from tasking.taskers import uniform_select

    assert uniform_select(6, 4).tolist() == [0, 2, 3, 5]
    assert uniform_select(3, 2).tolist() == [0, 2]


def test_lazy_greedy_re_evaluates_a_stale_bound_within_tol_before_taking_the_lower_index():
    """Rectangles in a 10 x 10 room (exact areas). Camera 0 removes 40 and goes first; camera 1
    (gain 20, stale) is within tol of camera 2 (20 + 2**-24, still 20 after camera 0) but overlaps
    camera 0, so its real gain is 10: greedy takes 2, and lazy greedy must not take the lower
    index on a stale bound."""
    room = box(0, 0, 10, 10)
    w = np.array([box(0, 0, 4, 10), box(3, 0, 5, 10),
                  box(6, 0, 8, 10).union(box(8, 0, 8 + 2.0**-20, 2.0**-4))], dtype=object)
    assert shapely.area(w).tolist() == [40.0, 20.0, 20.0 + 2.0**-24]
    for select in (greedy_select, lazy_greedy_select):
        chosen, hull = select(w, room, 2)
        assert chosen == [0, 2], select.__name__
        assert hull.area == pytest.approx(100 - 40 - (20 + 2.0**-24), abs=1e-12)


def test_greedy_remove_drops_the_line_where_two_hulls_touch():
    """Camera 0 leaves the left half, camera 2 the right half, camera 1 proves nothing: without
    camera 1 the hull is the line x = 2 where the halves touch, of area 0, so camera 1 goes and
    the hull of cameras 0 and 2 is empty, not that line."""
    from tasking.taskers import greedy_remove, greedy_remove_reference

    room = box(0, 0, 4, 4)
    w = np.array([box(2, 0, 4, 4), shapely.Polygon(), box(0, 0, 2, 4)], dtype=object)
    assert room.difference(w[0]).intersection(room.difference(w[2])).length == 4.0
    for remove in (greedy_remove, greedy_remove_reference):
        kept, removed, hull = remove(w, room, [0, 1, 2], 1)
        assert (kept, removed) == ([0, 2], [1]), remove.__name__
        assert hull.is_empty, remove.__name__


def test_clustering_without_a_generator_seeds_k_means_with_0():
    """rng=None is seed 0 (docs); these estimates end in other cameras with seed 1."""
    from tasking.clustering import clustering_select

    xy, yaw = ring_cameras(16)
    est = np.random.default_rng(2).uniform(-0.8, 0.8, (6, 2))
    got = choose_cameras("clustering", 3, xy, yaw, np.pi, est, R, ROOM)
    assert got.tolist() == clustering_select(yaw, est, 3, 0, camera_xy=xy).tolist()
    assert got.tolist() != clustering_select(yaw, est, 3, 1, camera_xy=xy).tolist()


def test_incremental_tasker_refuses_k_0():
    with pytest.raises(ValueError, match="k must be >= 1"):
        IncrementalTasker(0)


def test_convex_room_takes_the_overlay_free_incremental_path(monkeypatch):
    """In the circle the incremental step never builds polygons: the polygon path would fail."""
    from tasking import taskers

    def no_overlays(*args, **kwargs):
        raise AssertionError("polygon path taken in a convex room")

    monkeypatch.setattr(taskers, "incremental_select", no_overlays)
    xy, yaw, c = drop(9, n=12, m=4)
    got = choose_cameras("incremental", 4, xy, yaw, np.pi, c, R, ROOM, current=[0, 3, 6, 9], m=1)
    assert got.size == 4 and len(set(got.tolist()) & {0, 3, 6, 9}) >= 3


def test_greedy_hull_holds_no_slivers_along_the_walls():
    """180-degree cameras on the walls of a square: their wedge edges run along the walls, and
    the plain differences leave parts of zero area (rounding noise) that the hull must drop."""
    room, xy, yaw = _wall_rig()
    c = np.array([[0.2, 0.3], [-0.4, -0.1], [0.5, -0.5]])
    w = free_wedges_from_discs(xy, yaw, np.pi, c, R, room)
    for select in (greedy_select, lazy_greedy_select):
        for k in (1, 2):
            chosen, hull = select(w, room, k)
            raw = room
            for j in chosen:
                raw = raw.difference(w[j])
            assert shapely.area(shapely.get_parts(raw)).min() <= 1e-12 * room.area   # slivers were there
            assert shapely.area(shapely.get_parts(hull)).min() > 1e-12 * room.area, (select.__name__, k)
            assert hull.area == pytest.approx(raw.area, rel=0, abs=1e-12)


def test_incremental_convex_with_free_cones_wider_than_pi():
    """270-degree cameras inside the room: a camera's free interval can span more than pi, a
    cone that is not convex; the overlay-free step splits it and still agrees with the polygon
    reference."""
    xy, yaw = ring_cameras(8)
    xy, c = 0.5 * xy, np.array([[0.7, 0.0]])
    _, (_, _, t0, t1) = free_wedges_from_discs(xy, yaw, 1.5 * np.pi, c, R, ROOM, strict=False,
                                               return_cones=True)
    assert np.any(t1 - t0 > np.pi)
    for m in (1, 2):
        _check_convex_step(xy, yaw, 1.5 * np.pi, c, ROOM, [0, 3, 5], m)


def test_naive_greedy_ties_go_to_the_lowest_index_never_a_chosen_camera():
    """No objects and 180-degree cameras on a ring: each empties the room alone, so every
    later hull is empty and the ties go to the lowest cameras not chosen yet."""
    xy, yaw = ring_cameras(4)
    w = free_wedges_from_discs(xy, yaw, np.pi, np.zeros((0, 2)), R, ROOM)
    assert naive_greedy_select(w, ROOM, 3) == [0, 1, 2]


def test_greedy_remove_ties_within_tol_go_to_the_lowest_index():
    """Rectangles in a 4 x 4 room (exact areas): camera 0 proves 4 + 2**-30 m^2 empty, camera 1
    4 m^2. Without camera 1 the hull is 2**-30 smaller, far within 1e-9 of the room's area:
    a tie, so camera 0, the lower index, goes."""
    from tasking.taskers import greedy_remove, greedy_remove_reference

    room = box(0, 0, 4, 4)
    w = np.array([box(0, 0, 1, 4).union(box(1, 0, 1 + 2.0**-28, 2.0**-2)), box(3, 0, 4, 4)], dtype=object)
    assert shapely.area(w).tolist() == [4 + 2.0**-30, 4.0]
    for remove in (greedy_remove, greedy_remove_reference):
        kept, removed, hull = remove(w, room, [0, 1], 1)
        assert (kept, removed) == ([1], [0]), remove.__name__
        assert hull.area == 12.0


def test_incremental_convex_removal_ties_go_to_the_lowest_index_whatever_the_rounding():
    """Objects on the x axis and cameras 1 and 7 mirror images across it: dropping either leaves
    the same hull area, up to rounding (here the rounding favours dropping 7), so camera 1, the
    lower index, goes, as in the polygon reference."""
    xy, yaw = ring_cameras(8)
    c = np.array([[0.4, 0.0], [-0.3, 0.0]])
    _check_convex_step(xy, yaw, np.pi, c, ROOM, [1, 7], 1)
    got = choose_cameras("incremental", 2, xy, yaw, np.pi, c, R, ROOM, current=[1, 7], m=1)
    assert 7 in got.tolist()
