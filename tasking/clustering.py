"""Clustering tasker (paper section 4.2): camera directions from object-pair directions.

For every pair of estimated object centres the direction of the connecting vector
``v_ij`` and of its perpendicular are collected, modulo pi (a camera looking along ``d``
and along ``d + pi`` is equally parallel to ``v_ij``). k-means on these axial angles
gives k directions; the camera whose viewing direction (modulo pi) is nearest each
cluster centre is tasked, without duplicates.

Axial angles wrap at pi, so k-means runs on the doubled-angle embedding
``(cos 2θ, sin 2θ)``, where 0 and pi coincide.

>>> yaw = np.radians([0.0, 45.0, 90.0, 135.0])
>>> clustering_select(yaw, np.array([[0.0, 0.0], [1.0, 0.0]]), 2, seed=0).tolist()
[0, 2]
"""

from __future__ import annotations

import warnings

import numpy as np

__all__ = ["axial_distance", "cluster_axes", "clustering_select", "pair_axes"]


def axial_distance(a, b):
    """Distance between axial angles (radians, modulo pi), in ``[0, pi/2]``."""
    d = (np.asarray(a, dtype=float) - np.asarray(b, dtype=float)) % np.pi
    return np.minimum(d, np.pi - d)


def pair_axes(estimates: np.ndarray) -> np.ndarray:
    """Axial angles of every pair vector and its perpendicular.

    Parameters
    ----------
    estimates : (p, 2) float, metres, world frame

    Returns
    -------
    (2 * q,) float, radians in ``[0, pi)``; q pairs with distinct centres.
    """
    i, j = np.triu_indices(estimates.shape[0], 1)
    v = estimates[j] - estimates[i]
    v = v[np.hypot(v[:, 0], v[:, 1]) > 1e-12]
    theta = np.arctan2(v[:, 1], v[:, 0]) % np.pi
    return np.concatenate([theta, (theta + np.pi / 2) % np.pi])


def cluster_axes(axes: np.ndarray, k: int, seed: int):
    """k-means of axial angles on the doubled-angle circle.

    Parameters
    ----------
    axes : (s,) float, radians modulo pi, s >= 1
    k : wanted number of clusters (fewer when there are fewer distinct angles, or angles
        ~1e-10 rad apart that k-means cannot tell apart: no cluster is returned empty)
    seed : int, k-means random_state

    Returns
    -------
    centres : (c,) float, radians in ``[0, pi)``, ordered by cluster size, largest first
    sizes : (c,) int
    """
    # imported here: scikit-learn's import is ~1 s of every command's start
    from sklearn.cluster import KMeans
    from sklearn.exceptions import ConvergenceWarning

    # k-means++ seeds by index: the same axes in another order (the estimates permuted)
    # could end in another local optimum; sorted (to 1e-12 rad) they are one input
    axes = np.sort(np.round(np.asarray(axes, dtype=float) % np.pi, 12) % np.pi)
    feats = np.c_[np.cos(2 * axes), np.sin(2 * axes)]
    distinct = np.unique(np.round(feats, 12), axis=0).shape[0]
    c = min(k, distinct)
    with _one_thread(), warnings.catch_warnings():  # the same sums whatever the machine's threads
        # axes ~1e-10 rad apart are distinct above but one point to k-means' distances: it
        # warns and leaves clusters empty, dropped below
        warnings.simplefilter("ignore", ConvergenceWarning)
        km = KMeans(n_clusters=c, n_init=10, random_state=seed).fit(feats)
    # twice: a tiny negative angle % pi rounds to pi itself
    centres = (np.arctan2(km.cluster_centers_[:, 1], km.cluster_centers_[:, 0]) / 2) % np.pi % np.pi
    sizes = np.bincount(km.labels_, minlength=c)
    centres, sizes = centres[sizes > 0], sizes[sizes > 0]
    order = np.lexsort((centres, _wrapped(centres), -sizes))
    centres, sizes = centres[order], sizes[order]
    if _closed_under_quarter_turn(feats):
        # every axis has its perpendicular: each solution has a twin turned by pi / 2, of
        # equal inertia, and rounding chose between them (with 1 or 2 OpenMP threads, other
        # cameras): take the one whose centres come first, largest cluster first
        twin = (centres + np.pi / 2) % np.pi
        order = np.lexsort((twin, _wrapped(twin), -sizes))
        if tuple(_wrapped(twin[order])) < tuple(_wrapped(centres)):
            centres, sizes = twin[order], sizes[order]
    return centres, sizes


def _wrapped(angles: np.ndarray) -> np.ndarray:
    """Axial angles in ``[0, pi)`` rounded to 1e-9 rad, those within it of pi as 0: the key
    that orders centres (k-means puts a centre on the axis 0 at 1e-14 or at pi - 1e-14)."""
    return np.round(angles, 9) % np.round(np.pi, 9)


def _closed_under_quarter_turn(feats: np.ndarray) -> bool:
    """Whether axial angles, as doubled-angle points ``feats`` (s, 2), turned by pi / 2 (the
    points negated) are the same multiset (points within 1e-8 count as one, without a wrap
    at pi): every point has as many points of ``feats`` as of ``-feats`` that near it.
    (Sorting the points rounded to 1e-9 paired wrong partners when two equal coordinates
    rounded apart.)"""
    from scipy.spatial import cKDTree

    tree = cKDTree(feats)
    near = tree.query_ball_point(feats, r=1e-8, return_length=True)
    return bool(np.array_equal(near, tree.query_ball_point(-feats, r=1e-8, return_length=True)))


_CONTROLLER = None

#: Axial distances (radians) within this of the nearest count as tied: cameras on one
#: viewing axis (yaws pi or 2 pi apart) differ by ~1e-15 after ``% pi``.
AXIS_TOL = 1e-9
#: Distances (metres) to the chosen cameras within this of the largest count as tied.
SPREAD_TOL = 1e-9


def _one_thread():
    """A context that holds the BLAS and OpenMP pools to one thread (threadpoolctl's
    controller, made once: making it looks up the loaded libraries, ~1 ms a call)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        from threadpoolctl import ThreadpoolController
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER.limit(limits=1)


def clustering_select(camera_yaw, estimates, k: int, seed: int, camera_xy=None) -> np.ndarray:
    """Cameras whose viewing axes best match the k-means pair directions.

    Cluster centres take turns, largest cluster first, each picking its nearest unused
    camera by viewing axis, until k cameras are chosen; with fewer distinct pair
    directions than k, centres pick again in the same order. Cameras within
    ``AXIS_TOL`` radians of the nearest axis tie (on a ring, the two cameras facing each
    other share an axis): with ``camera_xy`` the one farthest from the cameras already
    chosen wins (within ``SPREAD_TOL`` metres), then the lowest index. Always the lowest
    index would take every camera from one half of a ring.

    Parameters
    ----------
    camera_yaw : (N,) float, radians, world frame
    estimates : (p, 2) float, metres, world frame, p >= 2
    k : number of cameras, 1 <= k <= N (with k = 1 the one centre of axes that all come
        with their perpendiculars is the zero vector: its angle is noise, and
        :func:`tasking.choose_cameras` tasks uniform's camera instead)
    seed : int, k-means random_state
    camera_xy : (N, 2) float, metres, world frame, or None (ties: lowest index)

    Returns
    -------
    (k,) int, sorted 0-based camera indices.
    """
    centres, _ = cluster_axes(pair_axes(estimates), k, seed)
    axis = np.asarray(camera_yaw, dtype=float) % np.pi
    xy = None if camera_xy is None else np.asarray(camera_xy, dtype=float).reshape(-1, 2)
    used = np.zeros(axis.size, dtype=bool)
    chosen: list[int] = []
    while len(chosen) < k:
        for phi in centres:
            if len(chosen) == k:
                break
            dist = np.where(used, np.inf, axial_distance(axis, phi))
            tied = np.flatnonzero(dist <= dist.min() + AXIS_TOL)
            if xy is not None and chosen and tied.size > 1:
                gap = np.linalg.norm(xy[tied, None] - xy[None, chosen], axis=-1).min(axis=1)
                tied = tied[gap >= gap.max() - SPREAD_TOL]
            best = int(tied[0])
            used[best] = True
            chosen.append(best)
    return np.sort(np.array(chosen, dtype=np.intp))
