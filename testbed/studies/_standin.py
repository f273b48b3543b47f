"""Temporary stand-in for ``tasking.choose_cameras`` / ``tasking.TASKERS``.

Used only while the tasking package does not export them yet (see
``testbed/studies/core.py``); the study metadata records which one ran. Plain,
unoptimised versions of the paper's taskers over ``tasking.visual_hull_of_discs``.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

TASKERS = ("uniform", "clustering", "optimal", "greedy", "lazy_greedy", "incremental")


def _area(S, camera_xy, camera_yaw, fov, estimates, radius, room):
    from tasking import visual_hull_of_discs

    S = np.asarray(sorted(S))
    f = fov if np.ndim(fov) == 0 else np.asarray(fov)[S]
    if len(S) == 0:
        return room.area
    return visual_hull_of_discs(camera_xy[S], camera_yaw[S], f, estimates, radius, room).area


def choose_cameras(tasker, k, camera_xy, camera_yaw, fov, estimates, radius, room, *,
                   current=None, m=1, uniform_sets=None, max_subsets=200_000, rng=None):
    if tasker not in TASKERS:
        raise ValueError(f"tasker: unknown value {tasker!r}; expected one of {', '.join(TASKERS)}")
    camera_xy = np.asarray(camera_xy, float)
    camera_yaw = np.asarray(camera_yaw, float)
    n = len(camera_xy)
    estimates = np.asarray(estimates, float).reshape(-1, 2)
    if not 1 <= k <= n:
        raise ValueError(f"k: expected an integer in [1, {n}], got {k}")
    ang = np.arctan2(camera_xy[:, 1], camera_xy[:, 0])
    if tasker == "uniform":
        order = np.argsort(np.mod(ang - ang[0], 2 * np.pi))
        return np.sort(order[np.round(np.arange(k) * n / k).astype(int) % n])
    area = lambda S: _area(S, camera_xy, camera_yaw, fov, estimates, radius, room)  # noqa: E731
    if tasker == "optimal":
        best = min(combinations(range(n), k), key=area)
        return np.array(best)
    if tasker in ("greedy", "lazy_greedy"):
        S: list[int] = []
        for _ in range(k):
            S.append(min((c for c in range(n) if c not in S), key=lambda c: area(S + [c])))
        return np.sort(S)
    if tasker == "incremental":
        if current is None:
            raise ValueError("current: the incremental tasker needs the current camera set")
        S = [int(c) for c in current]
        for _ in range(m):
            worst = min(S, key=lambda c: area([x for x in S if x != c]))
            S.remove(worst)
        for _ in range(m):
            S.append(min((c for c in range(n) if c not in S), key=lambda c: area(S + [c])))
        return np.sort(S)
    # clustering: k-means on the angles of pair vectors and their normals (mod pi).
    from sklearn.cluster import KMeans

    i, j = np.triu_indices(len(estimates), 1)
    if len(i) == 0:
        return choose_cameras("uniform", k, camera_xy, camera_yaw, fov, estimates, radius, room)
    v = estimates[j] - estimates[i]
    a = np.mod(np.arctan2(v[:, 1], v[:, 0]), np.pi)
    a = np.concatenate([a, np.mod(a + np.pi / 2, np.pi)])
    pts = np.column_stack([np.cos(2 * a), np.sin(2 * a)])
    km = KMeans(n_clusters=min(k, len(pts)), n_init=4,
                random_state=None if rng is None else int(rng.integers(2**31))).fit(pts)
    dirs = np.mod(np.arctan2(km.cluster_centers_[:, 1], km.cluster_centers_[:, 0]) / 2, np.pi)
    view = np.mod(camera_yaw, np.pi)
    S: list[int] = []
    for d in dirs:
        diff = np.abs(np.angle(np.exp(2j * (view - d))))
        for c in np.argsort(diff):
            if c not in S:
                S.append(int(c))
                break
    for c in np.argsort(np.mod(ang - ang[0], 2 * np.pi)):
        if len(S) >= k:
            break
        if c not in S:
            S.append(int(c))
    return np.sort(S[:k])
