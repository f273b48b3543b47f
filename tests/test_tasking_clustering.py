"""The clustering tasker (paper section 4.2): pair axes, k-means on axial angles, camera picks.

Hand cases pin the documented tolerances and tie rules; property tests check what holds for
any drop of estimates: k distinct cameras, k-means clusters that are a fixed point of
Lloyd's iteration on the doubled-angle plane, and the angle between two axes.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_tasking_common import ring_cameras

from tasking.clustering import (
    _one_thread,
    axial_distance,
    cluster_axes,
    clustering_select,
    pair_axes,
)

ALONG_X = np.array([[0.0, 0.0], [1.0, 0.0]])          # pair axes 0 and 90 degrees


def test_pair_axes_keep_estimates_a_tenth_of_a_millimetre_apart():
    """Two estimates 0.1 mm apart are distinct centres (only coinciding ones, within
    1e-12 m, give no axis, 1e-12 m included): their diagonal and its perpendicular, 45 and
    135 degrees."""
    got = pair_axes(np.array([[0.2, 0.3], [0.2001, 0.3001]]))
    np.testing.assert_allclose(got, np.radians([45.0, 135.0]), atol=1e-9)
    got = pair_axes(np.array([[0.2, 0.3], [0.2, 0.3001]]))
    np.testing.assert_allclose(got, np.radians([90.0, 0.0]), atol=1e-9)
    assert pair_axes(np.array([[0.0, 0.0], [1e-12, 0.0]])).size == 0


def test_cluster_axes_of_axes_without_their_perpendiculars_are_not_turned():
    """Two axes a milliradian (or a microradian) short of a quarter turn apart are not closed
    under a quarter turn, so there is no twin solution: each axis is its own cluster, centres
    exactly on them, in increasing order (equal sizes). A twin taken for them would be off by
    that much."""
    for short in (1e-3, 1e-6):
        axes = np.array([0.3, 0.3 + np.pi / 2 - short])
        centres, sizes = cluster_axes(axes, 2, seed=0)
        np.testing.assert_allclose(centres, axes, atol=1e-12)
        assert sizes.tolist() == [1, 1]
    axes = np.array([2.0, 2.0, 2.0, 2.0 - np.pi / 2 + 1e-3])   # twin would be [0.43, 0.43 + pi / 2]
    centres, sizes = cluster_axes(axes, 2, seed=0)
    np.testing.assert_allclose(centres, [2.0, 2.0 - np.pi / 2 + 1e-3], atol=1e-9)
    assert sizes.tolist() == [3, 1]


def test_cluster_axes_a_microradian_apart_are_two_clusters():
    """Only axes ~1e-10 rad apart are one to k-means (docs): two a microradian apart, k = 2,
    are a cluster each, centred on them."""
    centres, sizes = cluster_axes(np.array([0.3, 0.3 + 1e-6]), 2, seed=0)
    np.testing.assert_allclose(centres, [0.3, 0.3 + 1e-6], atol=1e-12)
    assert sizes.tolist() == [1, 1]


def test_a_camera_a_microradian_off_the_axis_loses_to_one_on_it():
    """Only axes within AXIS_TOL (1e-9 rad) tie: camera 1, 1e-6 rad off the pair axis 0,
    loses to camera 2 on it although its index is lower, with or without positions."""
    yaw = np.array([np.pi / 2, 1e-6, 0.0])
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    assert clustering_select(yaw, ALONG_X, 2, seed=0).tolist() == [0, 2]
    assert clustering_select(yaw, ALONG_X, 2, seed=0, camera_xy=xy).tolist() == [0, 2]


def test_a_millimetre_farther_from_the_chosen_camera_wins_a_tie():
    """Cameras 1 and 2 share the axis 90 degrees; camera 0 (axis 0) is chosen first, at the
    origin. Camera 2 is 1.001 m from it, camera 1 1 m: a millimetre is far beyond
    SPREAD_TOL (1e-9 m), so camera 2 wins."""
    yaw = np.radians([0.0, 90.0, 270.0])
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [-1.001, 0.0]])
    assert clustering_select(yaw, ALONG_X, 2, seed=0, camera_xy=xy).tolist() == [0, 2]


def test_cameras_equally_far_from_the_chosen_one_tie_to_the_lowest_index():
    """Ring of 16: camera 0 (axis 0) is chosen first; cameras 4 and 12 both look along 90
    degrees and are both sqrt(2) from camera 0 (12 by one rounding farther): a tie, so the
    lowest index, 4."""
    xy, yaw = ring_cameras(16)
    gap = np.linalg.norm(xy[[4, 12]] - xy[0], axis=1)
    np.testing.assert_allclose(gap, np.sqrt(2), rtol=1e-15)
    assert clustering_select(yaw, ALONG_X, 2, seed=0, camera_xy=xy).tolist() == [0, 4]


def test_a_second_round_without_positions_takes_an_unused_camera():
    """Two pair axes (0 and 90 degrees) for k = 3: axis 0 picks again, and camera 0, on it
    but already tasked, is not taken twice: camera 2 (10 degrees off) is."""
    yaw = np.radians([0.0, 90.0, 10.0])
    assert clustering_select(yaw, ALONG_X, 3, seed=0).tolist() == [0, 1, 2]


def test_clustering_pins_blas_and_openmp_to_one_thread():
    """k-means' sums must not depend on the machine's thread count (docs): inside the
    context every thread pool that threadpoolctl sees (numpy's BLAS, scikit-learn's
    OpenMP) runs one thread."""
    import sklearn.cluster  # noqa: F401  (loads the OpenMP runtime)
    from threadpoolctl import threadpool_info

    with _one_thread():
        pools = threadpool_info()
        assert pools and all(p["num_threads"] == 1 for p in pools)


def test_cluster_axes_fit_k_means_on_one_thread(monkeypatch):
    """cluster_axes fits k-means inside that context: each pool has one thread during the fit."""
    from sklearn.cluster import KMeans
    from threadpoolctl import threadpool_info

    fit, seen = KMeans.fit, []

    def recording_fit(self, *args, **kwargs):
        seen.append([p["num_threads"] for p in threadpool_info()])
        return fit(self, *args, **kwargs)

    monkeypatch.setattr(KMeans, "fit", recording_fit)
    cluster_axes(pair_axes(ALONG_X), 2, seed=0)
    assert len(seen) == 1 and seen[0] and set(seen[0]) == {1}


def test_the_kmeans_seed_reaches_kmeans():
    """k-means is a heuristic: on this drop of six estimates (30 axes, 3 clusters) k-means'
    ten starts end in other local optima for other seeds. Each seed gives its own result,
    the same every time."""
    axes = pair_axes(np.random.default_rng(2).uniform(-0.8, 0.8, (6, 2)))
    runs = {s: cluster_axes(axes, 3, seed=s) for s in (0, 1)}
    for s, (centres, sizes) in runs.items():
        again, again_sizes = cluster_axes(axes, 3, seed=s)
        np.testing.assert_array_equal(again, centres)
        np.testing.assert_array_equal(again_sizes, sizes)
    assert runs[0][1].tolist() != runs[1][1].tolist() or not np.allclose(runs[0][0], runs[1][0], atol=1e-6)


# --- properties ---------------------------------------------------------------------------

angles = st.floats(-20.0, 20.0, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(angles, angles, st.integers(-3, 3))
def test_axial_distance_is_the_angle_between_two_lines(a, b, turns):
    """The angle between lines of directions a and b: atan2(|sin(a - b)|, |cos(a - b)|),
    whatever multiple of pi either is written with, and symmetric."""
    want = np.arctan2(abs(np.sin(a - b)), abs(np.cos(a - b)))
    assert 0.0 <= axial_distance(a, b) <= np.pi / 2
    assert axial_distance(a, b) == pytest.approx(want, abs=1e-9)
    assert axial_distance(b, a) == pytest.approx(want, abs=1e-9)
    assert axial_distance(a + turns * np.pi, b) == pytest.approx(want, abs=1e-9)


estimate_sets = st.lists(st.tuples(st.integers(-40, 40), st.integers(-40, 40)), min_size=2, max_size=6,
                         unique=True).map(lambda p: np.array(p, float) / 40)


def _lloyd_labels(axes, centres, sizes, starts=10):
    """Labels of ``axes`` that make ``centres`` and ``sizes`` a fixed point of Lloyd's iteration
    on the doubled-angle plane, or None. k-means' means lie inside the unit circle, each on its
    centre's direction at its own length r (the mean projection of its axes), and an axis is
    nearest the mean, not the unit point, of its cluster: the lengths are searched by the
    iteration r -> mean projection, from r = 1 and from seeded random lengths (one start can
    end in another fixed point)."""
    feats = np.c_[np.cos(2 * axes), np.sin(2 * axes)]
    proj = feats @ np.c_[np.cos(2 * centres), np.sin(2 * centres)].T
    rng = np.random.default_rng(0)
    for r in [np.ones(centres.size), *rng.uniform(0.2, 1.0, (starts, centres.size))]:
        for _ in range(50):
            label = (r ** 2 - 2 * r * proj).argmin(axis=1)        # |x - r u|^2 less |x|^2
            count = np.bincount(label, minlength=centres.size)
            if count.min() == 0:
                break
            r, last = np.array([proj[label == j, j].mean() for j in range(centres.size)]), r
            if np.allclose(r, last, rtol=0, atol=1e-13):
                break
        if not np.array_equal(count, sizes):
            continue
        mean = np.array([feats[label == j].mean(axis=0) for j in range(centres.size)])
        found = np.hypot(mean[:, 0], mean[:, 1]) > 1e-6      # the mean of an axis and its perpendicular is 0
        if np.all(axial_distance(np.arctan2(mean[found, 1], mean[found, 0]) / 2, centres[found]) < 1e-7):
            return label
    return None


@settings(max_examples=60, deadline=None)
@given(estimate_sets, st.integers(1, 6), st.integers(0, 3))
def test_clusters_are_a_fixed_point_of_lloyds_iteration(est, k, seed):
    """Some labelling of the axes has the sizes returned, each centre the mean direction of its
    cluster, and every axis nearest (on the doubled-angle plane) its own cluster's mean."""
    axes = pair_axes(est)
    centres, sizes = cluster_axes(axes, k, seed=seed)
    assert 1 <= centres.size <= k and sizes.sum() == axes.size and sizes.min() >= 1
    assert np.all((centres >= 0) & (centres < np.pi)) and np.all(np.diff(sizes) <= 0)
    assert _lloyd_labels(axes, centres, sizes) is not None


def test_an_axis_is_nearest_its_clusters_mean_not_the_unit_point_of_its_centre():
    """Six estimates, k = 3: the axis 0.88 rad is nearer the unit point of the centre 1.44 rad
    than of 0.30, but nearer the mean of 0.30's cluster (of length 0.76, the other's 0.94):
    the sizes 11, 10, 9 are those of the means' cells, 10, 11, 9 those of the unit points."""
    est = np.array([(0, 0), (0, 1), (0, 2), (0, 6), (-10, -6), (-27, 12)], float) / 40
    axes = pair_axes(est)
    centres, sizes = cluster_axes(axes, 3, seed=0)
    assert sizes.tolist() == [11, 10, 9]
    unit = np.c_[np.cos(2 * centres), np.sin(2 * centres)]
    feats = np.c_[np.cos(2 * axes), np.sin(2 * axes)]
    nearest_unit = np.linalg.norm(feats[:, None] - unit[None], axis=2).argmin(axis=1)
    assert np.bincount(nearest_unit).tolist() == [10, 11, 9]
    assert _lloyd_labels(axes, centres, sizes) is not None
    assert _lloyd_labels(axes, centres, np.array([10, 11, 9])) is None


@settings(max_examples=30, deadline=None)
@given(estimate_sets, st.lists(st.integers(0, 15), min_size=1, max_size=10), st.data(), st.booleans())
def test_clustering_tasks_k_distinct_cameras_in_order(est, yaw_steps, data, with_xy):
    """Any drop and any rig (cameras may share axes, or sit on one spot): k distinct
    indices, sorted, each a camera; the first centre's camera is one nearest its axis."""
    n = len(yaw_steps)
    yaw = np.array(yaw_steps) * np.pi / 8                # on 8 axes: shared axes are common
    k = data.draw(st.integers(1, n))
    xy = np.column_stack([np.cos(yaw), np.sin(yaw)]) if with_xy else None
    got = clustering_select(yaw, est, k, seed=0, camera_xy=xy)
    assert got.dtype.kind == "i" and got.shape == (k,)
    assert np.all(np.diff(got) > 0) and got[0] >= 0 and got[-1] < n
    centres, _ = cluster_axes(pair_axes(est), k, seed=0)
    dist = axial_distance(yaw, centres[0])
    assert dist[got].min() <= dist.min() + 1e-9


def test_twin_solutions_with_an_axis_at_the_wrap_are_one_whatever_the_kmeans_seed():
    """Seven estimates mirrored about the x axis: the largest cluster (11 axes) is centred on
    the axis 0, which k-means puts at 1e-14 or at pi - 1e-14 rad, the same axis. Of a solution
    and its quarter-turned twin the one whose centres come first is returned, the largest
    cluster on 0 here, not on pi / 2: compared without the wrap, pi - 1e-14 came after
    pi / 2, and k-means seeds 2 and 3 returned the twin (other cameras on a ring)."""
    est = np.array([[-0.53, -0.67], [0.53, -0.67], [0.0, -0.56], [-0.42, 0.46], [0.42, 0.46],
                    [-0.71, 0.6], [0.71, 0.6]])
    axes = pair_axes(est)
    for seed in (0, 2, 3):
        centres, sizes = cluster_axes(axes, 5, seed=seed)
        assert sizes[0] == 11 and axial_distance(centres[0], 0.0) < 1e-9


def test_axes_that_round_apart_still_have_their_twin_solution_taken_first():
    """Six estimates mirrored about the x axis: two doubled-angle points at -0.0783109405
    round (to 1e-9) to -0.078310941 and -0.07831094, so sorting the rounded points paired
    each with the wrong partner, the axes (closed under a quarter turn by construction)
    were taken as not closed, and k-means seeds 1 and 3 returned the twin of seeds 0 and 2
    (largest cluster on 1.21 rad or 2.78). The twin whose centres come first is returned
    for every seed."""
    est = np.array([[0.22, -0.07], [0.22, 0.07], [0.73, -0.32], [0.73, 0.32], [0.75, -0.56], [0.75, 0.56]])
    axes = pair_axes(est)
    first, first_sizes = cluster_axes(axes, 3, seed=0)
    assert first_sizes.tolist() == [14, 8, 8] and first[0] < np.pi / 2
    for seed in (1, 2, 3):
        centres, sizes = cluster_axes(axes, 3, seed=seed)
        np.testing.assert_array_equal(sizes, first_sizes)
        assert np.all(axial_distance(centres, first) < 1e-9)


def test_of_equal_clusters_the_one_on_the_axis_0_comes_first_even_just_below_pi():
    """Axes 0.1 and pi - 0.1 - 4e-12 average to a centre 2e-12 rad below pi, the axis 0:
    of two clusters of two it comes before the one at 1.05 rad (and picks first). A centre
    1e-7 rad below pi is not within 1e-9 of it: it comes after 1.05."""
    centres, sizes = cluster_axes(np.array([0.1, np.pi - 0.1 - 4e-12, 1.0, 1.1]), 2, seed=0)
    assert sizes.tolist() == [2, 2]
    assert axial_distance(centres[0], 0.0) < 1e-9 and centres[1] == pytest.approx(1.05, abs=1e-9)
    centres, sizes = cluster_axes(np.array([0.1, np.pi - 0.1 - 2e-7, 1.0, 1.1]), 2, seed=0)
    np.testing.assert_allclose(centres, [1.05, np.pi - 1e-7], atol=1e-9)


def test_cluster_axes_of_mirrored_estimates_do_not_depend_on_their_order_or_turns_of_pi():
    """Four estimates mirrored about the x axis: pair vectors of mirrored pairs differ in the
    last bit of their angle by the estimates' order, and the axes sorted as they came ended in
    other clusters for some orders. Every order gives the same clusters, and so does every
    multiple of pi the axes are written with."""
    from itertools import permutations

    est = np.array([[-0.14, 0.38], [0.34, 0.69], [-0.14, -0.38], [0.34, -0.69]])
    centres, sizes = cluster_axes(pair_axes(est), 4, seed=0)
    for order in permutations(range(4)):
        c2, s2 = cluster_axes(pair_axes(est[list(order)]), 4, seed=0)
        np.testing.assert_array_equal(s2, sizes)
        assert np.all(axial_distance(c2, centres) < 1e-9), order
    est = np.array([[-0.19, 0.8], [0.77, 0.3], [-0.19, -0.8], [0.77, -0.3]])
    axes = pair_axes(est)
    centres, sizes = cluster_axes(axes, 3, seed=0)
    for turns in (-2, -1, 1, 3):
        c2, s2 = cluster_axes(axes + turns * np.pi, 3, seed=0)
        np.testing.assert_array_equal(s2, sizes)
        assert np.all(axial_distance(c2, centres) < 1e-9), turns


def test_twin_solutions_of_axes_under_a_milliradian_apart_are_one_whatever_the_kmeans_seed():
    """Three pairs of estimates mirrored about the x axis and a seventh: some of their axes are
    0.9 mrad apart (only points within 1e-8 count as one: the quarter-turn test still finds
    every axis's perpendicular). k = 3: every seed returns the twin whose centres come first.
    k = 5: of three clusters of nine, the one on the axis 0 (at 1e-14 or at pi - 1e-14 rad)
    comes first in the twin too."""
    est = np.array([[-0.23, 0.11], [-0.29, 0.15], [-0.26, -0.17], [0.62, -0.44], [-0.23, -0.11],
                    [-0.29, -0.15], [-0.26, 0.17]])
    axes = pair_axes(est)
    for seed in range(4):
        centres, sizes = cluster_axes(axes, 3, seed=seed)
        assert sizes.tolist() == [18, 13, 11]
        np.testing.assert_allclose(centres, [1.327281, 2.559959, 0.161939], atol=1e-6)
    for seed in (0, 4):
        centres, sizes = cluster_axes(axes, 5, seed=seed)
        assert sizes.tolist() == [11, 9, 9, 9, 4]
        assert np.all(axial_distance(centres, [1.46213, 0.0, 0.857453, 2.655192, 2.039162]) < 1e-6)
