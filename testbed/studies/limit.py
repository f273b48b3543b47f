"""The visual hull of discs seen by infinitely many 180-degree cameras on a circle.

With a camera at every point of the circular room's perimeter, each looking at the
centre with a 180-degree field of view, a point ``p`` of the room is in the visual hull
if and only if *every line through p meets an object*: the chord through ``p`` in any
direction has a camera at each end, and the camera at one end sees its whole chord.
A disc of radius ``r`` at distance ``d > r`` from ``p`` blocks the line directions within
``asin(r / d)`` of the direction to its centre (directions taken modulo pi), so ``p`` is
in the hull iff these intervals cover the circle of directions.

That test only changes value where two interval ends meet, i.e. on one of the four
common tangent lines of a pair of discs, or on a disc's boundary. Along a horizontal row
the hull is therefore a union of intervals between the row's crossings with those lines
and circles, each decided exactly by testing its midpoint. Integrating the covered row
lengths over a fine grid of rows (midpoint rule in y, exact in x) gives the limit area;
connected pieces are found by joining overlapping intervals of adjacent rows.

This is what ``camtask study cameras`` uses by default for the "infinite" case; the
paper approximated it with 2000 cameras (``--limit-cameras 2000`` still does that).

>>> import numpy as np
>>> raw, pruned = limit_residual(np.array([[0.0, 0.0]]), 0.1)
>>> raw, pruned
(0.0, 0.0)
"""

from __future__ import annotations

import numpy as np

__all__ = ["bitangent_lines", "covered", "limit_residual"]

_PREFILTER_ANGLES = np.pi * np.array([0.25, 0.75, 0.125, 0.375, 0.625, 0.875])


def bitangent_lines(centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """The common tangent lines of every pair of disjoint discs.

    centers : (m, 2) float, metres; radii : (m,) float, metres
    returns lines : (L, 3) float, rows ``(nx, ny, c)`` of lines ``nx x + ny y = c`` with
        ``(nx, ny)`` a unit normal; four lines per pair (two outer, two inner)
    """
    m = len(centers)
    i, j = np.triu_indices(m, 1)
    if len(i) == 0:
        return np.zeros((0, 3))
    D = centers[i] - centers[j]
    dd = np.hypot(D[:, 0], D[:, 1])
    phi = np.arctan2(D[:, 1], D[:, 0])
    lines = []
    for s1, s2 in ((radii[i], radii[j]), (radii[i], -radii[j])):
        q = np.clip((s1 - s2) / dd, -1.0, 1.0)
        for sign in (1.0, -1.0):
            theta = phi + sign * np.arccos(q)
            n = np.column_stack([np.cos(theta), np.sin(theta)])
            c = np.einsum("pk,pk->p", n, centers[i]) - s1
            lines.append(np.column_stack([n, c]))
    return np.concatenate(lines)


def covered(points: np.ndarray, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Whether every line through each point meets a disc (points inside a disc: True).

    points : (P, 2) float, metres; centers : (m, 2); radii : (m,)
    returns (P,) bool

    >>> covered(np.array([[0.0, 0.0], [0.0, 0.5]]),
    ...         0.15 * np.array([[1.0, 0.0], [-0.5, 0.75**0.5], [-0.5, -0.75**0.5]]),
    ...         np.full(3, 0.1)).tolist()
    [True, False]
    """
    d = centers[None, :, :] - points[:, None, :]  # (P, m, 2)
    dist = np.hypot(d[..., 0], d[..., 1])
    inside = np.any(dist <= radii[None, :], axis=1)
    w = np.arcsin(np.clip(radii[None, :] / np.maximum(dist, 1e-300), 0.0, 1.0))  # (P, m)
    alpha = np.mod(np.arctan2(d[..., 1], d[..., 0]), np.pi)
    start = alpha - w
    end = alpha + w
    # The union of arcs covers the circle iff every arc's end lies inside another arc.
    off = np.mod(end[:, :, None] - start[:, None, :], np.pi)  # (P, i, j)
    inside_other = off < 2.0 * w[:, None, :]
    m = centers.shape[0]
    inside_other &= ~np.eye(m, dtype=bool)[None]
    cov = np.all(np.any(inside_other, axis=2), axis=1) if m > 1 else np.zeros(len(points), bool)
    return inside | cov


def limit_residual(
    centers,
    radii,
    *,
    room_radius: float = 1.0,
    h: float = 0.002,
    min_area: float | None = None,
    chunk: int = 20000,
) -> tuple[float, float]:
    """Area (m^2) of the infinite-camera visual hull outside the discs, raw and pruned.

    centers : (m, 2) float, metres, disc centres inside the circular room
    radii : float or (m,) float, metres
    room_radius : float, metres, the room is the disc of this radius at the origin
    h : float, metres, spacing of the integration rows (a fixed grid, midpoint rule)
    min_area : float, m^2; connected pieces of the hull containing no disc and smaller
        than this are removed in the pruned value (default: the smallest disc's area)
    returns (raw, pruned) : residual areas in m^2 (hull area minus the discs' area)
    """
    centers = np.asarray(centers, dtype=float).reshape(-1, 2)
    m = len(centers)
    radii = np.broadcast_to(np.asarray(radii, dtype=float), (m,)).astype(float)
    if m == 0:
        return 0.0, 0.0
    if min_area is None:
        min_area = float(np.pi * radii.min() ** 2)
    lines = bitangent_lines(centers, radii)
    # Rows: a horizontal line through p must meet a disc, so only rows within a disc's
    # y-range can hold hull points.
    ks = np.arange(int(np.floor((-room_radius) / h)), int(np.ceil(room_radius / h)))
    ys = (ks + 0.5) * h
    near = np.any(np.abs(ys[:, None] - centers[None, :, 1]) < radii[None, :], axis=1)
    ys = ys[near]
    krow = ks[near]
    if len(ys) == 0:
        return 0.0, 0.0
    R = len(ys)
    xr = np.sqrt(np.maximum(room_radius**2 - ys**2, 0.0))
    dy = ys[:, None] - centers[None, :, 1]
    half = np.sqrt(np.maximum(radii[None, :] ** 2 - dy**2, 0.0))
    circ = np.where(np.abs(dy) < radii[None, :], 1.0, np.nan)
    bx = [
        centers[None, :, 0] - half * circ,
        centers[None, :, 0] + half * circ,
        np.broadcast_to(centers[None, :, 0] - radii, (R, m)),
        np.broadcast_to(centers[None, :, 0] + radii, (R, m)),
        -xr[:, None],
        xr[:, None],
    ]
    if len(lines):
        nx, ny, c = lines.T
        ok = np.abs(nx) > 1e-12
        bx.append((c[None, ok] - ny[None, ok] * ys[:, None]) / nx[None, ok])
    bx = np.concatenate(bx, axis=1)
    bx = np.where((bx >= -xr[:, None]) & (bx <= xr[:, None]), bx, np.nan)
    bx = np.sort(bx, axis=1)  # NaNs last
    lo, hi = bx[:, :-1], bx[:, 1:]
    valid = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
    mid_x = 0.5 * (lo + hi)
    # Necessary condition: the vertical line through p meets a disc.
    in_xrange = np.zeros_like(valid)
    for j in range(m):
        in_xrange |= np.abs(mid_x - centers[j, 0]) < radii[j]
    test = valid & in_xrange
    rr, cc = np.nonzero(test)
    pts = np.column_stack([mid_x[rr, cc], ys[rr]])
    status = np.zeros(len(pts), dtype=np.int8)  # 0 out, 1 residual, 2 inside a disc
    for s in range(0, len(pts), chunk):
        p = pts[s : s + chunk]
        d2 = np.sum((p[:, None, :] - centers[None]) ** 2, axis=2)
        inside = np.any(d2 <= radii[None] ** 2, axis=1)
        cov = np.zeros(len(p), dtype=bool)
        # Cheap necessary condition first: lines in a few fixed directions meet a disc.
        cand = ~inside
        rel = centers[None] - p[:, None, :]  # (P, m, 2)
        for a in _PREFILTER_ANGLES:
            cross = np.abs(np.cos(a) * rel[..., 1] - np.sin(a) * rel[..., 0])
            cand &= np.any(cross < radii[None], axis=1)
        if np.any(cand):
            cov[cand] = covered(p[cand], centers, radii)
        status[s : s + chunk] = np.where(inside, 2, np.where(cov, 1, 0))
    lengths = (hi - lo)[rr, cc]
    raw = float(np.sum(lengths[status == 1]) * h)

    # Connected pieces: merge adjacent hull intervals within a row into segments, then
    # join segments of adjacent rows whose x-ranges overlap.
    keep = status > 0
    if not np.any(keep & (status == 1)):
        return raw, raw
    rr, lo_k, hi_k, st = rr[keep], lo[rr, cc][keep], hi[rr, cc][keep], status[keep]
    segs: list[list] = []  # [row, x0, x1, area, has_disc]
    for r_, a, b, s_ in zip(krow[rr].tolist(), lo_k.tolist(), hi_k.tolist(), st.tolist()):
        if segs and segs[-1][0] == r_ and abs(segs[-1][2] - a) <= 1e-12:
            seg = segs[-1]
            seg[2] = b
            seg[3] += (b - a) * h if s_ == 1 else 0.0
            seg[4] |= s_ == 2
            seg[5] += (b - a) * h
        else:
            segs.append([r_, a, b, (b - a) * h if s_ == 1 else 0.0, s_ == 2, (b - a) * h])
    parent = list(range(len(segs)))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    by_row: dict[int, list[int]] = {}
    for k, seg in enumerate(segs):
        by_row.setdefault(seg[0], []).append(k)
    for r_ in sorted(by_row):
        nxt = r_ + 1
        if nxt not in by_row:
            continue
        for a in by_row[r_]:
            for b in by_row[nxt]:
                if segs[a][1] < segs[b][2] and segs[b][1] < segs[a][2]:
                    parent[find(a)] = find(b)
    comp_res: dict[int, float] = {}
    comp_tot: dict[int, float] = {}
    comp_disc: dict[int, bool] = {}
    for k, seg in enumerate(segs):
        root = find(k)
        comp_res[root] = comp_res.get(root, 0.0) + seg[3]
        comp_tot[root] = comp_tot.get(root, 0.0) + seg[5]
        comp_disc[root] = comp_disc.get(root, False) or seg[4]
    removed = sum(comp_res[k] for k in comp_res if not comp_disc[k] and comp_tot[k] < min_area)
    return raw, raw - removed
