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
lengths over a fine grid of rows (midpoint rule in y, exact in x) gives the limit area.
Connected pieces (for pruning the small ones) join segments of adjacent rows bounded by
the same two curves, or by one of them and two that cross (or touch, a disc and its
tangent) between the rows: between such rows they are one cell. Where the rows' pieces
differ (a piece starting or ending, two pieces meeting or parting), the strip is halved,
down to a 64th of the row spacing, and joined by x-overlap only there: joining by
overlap at the rows themselves merged pieces a fraction of a millimetre apart.

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
#: Halvings of a strip between rows whose pieces change (see :func:`limit_residual`).
REFINE_DEPTH = 6


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
    depth: int = REFINE_DEPTH,
) -> tuple[float, float]:
    """Area (m^2) of the infinite-camera visual hull outside the discs, raw and pruned.

    centers : (m, 2) float, metres, disc centres inside the circular room
    radii : float or (m,) float, metres
    room_radius : float, metres, the room is the disc of this radius at the origin
    h : float, metres, spacing of the integration rows (a fixed grid, midpoint rule)
    min_area : float, m^2; connected pieces of the hull containing no disc and smaller
        than this are removed in the pruned value (default: the smallest disc's area)
    depth : how many times a strip between rows whose pieces change is halved to find
        what connects across it (``h / 2**depth``: 0.03 mm for the default h)
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
    crosses = np.abs(ys[:, None] - centers[None, :, 1]) < radii[None, :]      # (rows, discs)
    near = crosses.any(axis=1)
    ys, krow = ys[near], ks[near]
    if len(ys) == 0:
        return 0.0, 0.0
    rows = _row_segments(ys, centers, radii, lines, room_radius, chunk)
    raw = float(sum(seg[3] for row in rows for seg in row) * h)
    if raw == 0.0:
        return raw, raw
    # Connected pieces (union-find over every row's segments, refined rows included):
    # segments of adjacent rows bounded by the same two curves, or turning a corner, are
    # one cell of the strip between them; a strip where the rows differ is halved until
    # they agree, or down to ``depth`` halvings, where segments that overlap in x are joined.
    segs = [seg for row in rows for seg in row]          # [x0, x1, ids, residual length, total, disc]
    curves = _Curves(centers, radii, lines, room_radius)
    parent = list(range(len(segs)))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    def union(a, b):
        parent[find(a)] = find(b)

    def add_row(row) -> list[int]:
        """Add a row that connects only (the rows hold the area); its segments' indices."""
        M = list(range(len(segs), len(segs) + len(row)))
        segs.extend([*seg[:3], 0.0, 0.0, seg[5]] for seg in row)
        parent.extend(M)
        return M

    first = np.cumsum([0] + [len(r) for r in rows])      # index of each row's first segment
    strips = [(ys[i], ys[i + 1], list(range(first[i], first[i + 1])), list(range(first[i + 1], first[i + 2])))
              for i in range(len(ys) - 1) if krow[i + 1] == krow[i] + 1]
    # A disc between two rows crossing neither (radius under h / 2) still marks its piece:
    # its strip is split by a row through its centre (connecting only, as refined rows do).
    for yc in sorted(float(y) for y in centers[~crosses.any(axis=0), 1]):
        k = next((k for k, s in enumerate(strips) if s[0] < yc < s[1]), None)
        if k is None:
            continue
        ya, yb, A, B = strips[k]
        M = add_row(_row_segments(np.array([yc]), centers, radii, lines, room_radius, chunk)[0])
        strips[k:k + 1] = [(ya, yc, A, M), (yc, yb, M, B)]
    for level in range(depth + 1):
        pending = []
        for ya, yb, A, B in strips:
            if _same_cells(segs, A, B, ya, yb, curves):
                for a, b in zip(A, B):
                    union(a, b)
            elif level == depth or not A or not B:
                for a in A:
                    for b in B:
                        if segs[a][0] < segs[b][1] and segs[b][0] < segs[a][1]:
                            union(a, b)
            else:
                pending.append((ya, yb, A, B))
        if not pending:
            break
        mids = np.array([0.5 * (ya + yb) for ya, yb, _, _ in pending])
        strips = []
        for (ya, yb, A, B), row in zip(pending, _row_segments(mids, centers, radii, lines, room_radius, chunk)):
            M = add_row(row)
            strips += [(ya, 0.5 * (ya + yb), A, M), (0.5 * (ya + yb), yb, M, B)]
    residual: dict[int, float] = {}
    total: dict[int, float] = {}
    disc: dict[int, bool] = {}
    for k, seg in enumerate(segs):
        root = find(k)
        residual[root] = residual.get(root, 0.0) + seg[3] * h
        total[root] = total.get(root, 0.0) + seg[4] * h
        disc[root] = disc.get(root, False) or seg[5]
    removed = sum(residual[k] for k in residual if not disc[k] and total[k] < min_area)
    return raw, raw - removed


def _same_cells(segs: list, A: list[int], B: list[int], ya: float, yb: float, curves: _Curves) -> bool:
    """Whether two rows' segments (rows ``ya`` and ``yb``), in x order, pair off one by one
    as one cell each: the same number, each overlapping in x its partner alone, and bounded
    by the same two curves, or at a corner of one piece: one side's curve the same, the
    other side's two curves crossing each other between the rows, neither crossing the
    shared one (else a piece may end and another begin between the rows on the same
    line; see :func:`_corner`)."""
    if len(A) != len(B):
        return False
    for i, (a, b) in enumerate(zip(A, B)):
        sa, sb = segs[a], segs[b]
        if not (sa[0] < sb[1] and sb[0] < sa[1]):
            return False
        if sa[2] != sb[2] and not _corner(sa[2], sb[2], ya, yb, curves):
            return False
        if i + 1 < len(A) and (sa[1] > segs[B[i + 1]][0] or sb[1] > segs[A[i + 1]][0]):
            return False                                  # overlaps its neighbour's partner too
    return True


def _corner(ca: tuple[int, int], cb: tuple[int, int], ya: float, yb: float, curves: _Curves) -> bool:
    """Whether segments bounded by curves ``ca`` on row ``ya`` and ``cb`` on row ``yb`` are
    one piece turning a corner between the rows: one curve shared and staying on the same
    side of the other two, which cross each other between the rows, or meet there as a
    disc and a common tangent of it at its point of contact."""
    if ca[0] == cb[0]:
        shared, u, v = ca[0], ca[1], cb[1]
    elif ca[1] == cb[1]:
        shared, u, v = ca[1], ca[0], cb[0]
    else:
        return False
    t, xu, xv = curves.x([shared, u, v], np.array([ya, yb]))       # x of each on both rows
    side = np.sign(xu[0] - t[0])                # u bounds row ya's segment, v row yb's
    if side == 0 or np.sign(xv[1] - t[1]) != side:
        return False
    for x in (xu, xv):                          # the shared curve crosses neither between the rows
        if np.all(np.isfinite(x)) and np.sign(x[1] - t[1]) != np.sign(x[0] - t[0]):
            return False
    if np.all(np.isfinite(xu)) and np.all(np.isfinite(xv)) and np.sign(xu[0] - xv[0]) * np.sign(xu[1] - xv[1]) < 0:
        return True
    touch = curves.contact_y(u, v)
    return touch is not None and min(ya, yb) <= touch <= max(ya, yb)


class _Curves:
    """The curves of :func:`_row_segments`, by its numbers: discs' left and right halves,
    their x-extents, the room's halves and the common tangents not parallel to the rows."""

    def __init__(self, centers: np.ndarray, radii: np.ndarray, lines: np.ndarray, room_radius: float):
        self.centers, self.radii, self.room_radius = centers, radii, room_radius
        self.lines = lines[np.abs(lines[:, 0]) > 1e-12] if len(lines) else np.zeros((0, 3))

    def all_x(self, ys: np.ndarray) -> np.ndarray:
        """(len(ys), number of curves) float: x (metres) of every curve on each row y, the
        column being the curve's number; NaN where a disc does not cross the row."""
        c, r = self.centers, self.radii
        dy = ys[:, None] - c[None, :, 1]
        half = np.sqrt(np.maximum(r[None, :] ** 2 - dy**2, 0.0))
        circ = np.where(np.abs(dy) < r[None, :], 1.0, np.nan)
        xr = np.sqrt(np.maximum(self.room_radius**2 - ys**2, 0.0))
        nx, ny, d = self.lines.T
        return np.concatenate([
            c[None, :, 0] - half * circ,                    # discs' left halves
            c[None, :, 0] + half * circ,                    # and right halves
            np.broadcast_to(c[None, :, 0] - r, dy.shape),   # their x-extents
            np.broadcast_to(c[None, :, 0] + r, dy.shape),
            -xr[:, None],                                   # the room's halves
            xr[:, None],
            (d[None] - ny[None] * ys[:, None]) / nx[None],  # the common tangents
        ], axis=1)

    def x(self, curves: list[int], ys: np.ndarray) -> np.ndarray:
        """(len(curves), len(ys)) float: x (metres) of the given curves on each row y."""
        return self.all_x(ys)[:, curves].T

    def contact_y(self, a: int, b: int) -> float | None:
        """y (metres) where a disc's half and a line tangent to that half, curves ``a`` and
        ``b`` in either order, touch; None for other pairs."""
        m = len(self.centers)
        disc, line = (a, b) if a < 2 * m else (b, a)
        if not (disc < 2 * m and line >= 4 * m + 2):
            return None
        nx, ny, d = self.lines[line - 4 * m - 2]
        j = disc % m
        off = nx * self.centers[j, 0] + ny * self.centers[j, 1] - d       # signed distance of the centre
        if abs(abs(off) - self.radii[j]) > 1e-9 or (-off * nx > 0) != (disc >= m):   # its x side of the centre
            return None
        return float(self.centers[j, 1] - off * ny)


def _row_segments(ys: np.ndarray, centers: np.ndarray, radii: np.ndarray, lines: np.ndarray,
                  room_radius: float, chunk: int) -> list[list]:
    """The hull's segments on each row ``y`` of ``ys``: per row, in x order, a list of
    ``[x0, x1, (left curve, right curve), residual length, length, holds a disc]`` (metres):
    runs of touching intervals of the hull (the discs included), each interval between
    consecutive crossings of the row with the discs, the pairs' common tangents and the
    room, decided by its midpoint. Curves are numbered the same on every row (:class:`_Curves`)."""
    m = len(centers)
    R = len(ys)
    xr = np.sqrt(np.maximum(room_radius**2 - ys**2, 0.0))
    bx = _Curves(centers, radii, lines, room_radius).all_x(ys)
    bx = np.where((bx >= -xr[:, None]) & (bx <= xr[:, None]), bx, np.nan)
    order = np.argsort(bx, axis=1)  # NaNs last; the column is the curve's number
    bx = np.take_along_axis(bx, order, axis=1)
    lo, hi = bx[:, :-1], bx[:, 1:]
    valid = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
    mid_x = 0.5 * (lo + hi)
    # Necessary condition: the vertical line through p meets a disc.
    in_xrange = np.zeros_like(valid)
    for j in range(m):
        in_xrange |= np.abs(mid_x - centers[j, 0]) < radii[j]
    rr, cc = np.nonzero(valid & in_xrange)
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
    rows: list[list] = [[] for _ in range(R)]
    keep = status > 0
    for r_, c_, s_ in zip(rr[keep].tolist(), cc[keep].tolist(), status[keep].tolist()):
        a, b = float(lo[r_, c_]), float(hi[r_, c_])
        row = rows[r_]
        if row and abs(row[-1][1] - a) <= 1e-12:           # touches the previous interval
            seg = row[-1]
            seg[1] = b
            seg[2] = (seg[2][0], int(order[r_, c_ + 1]))
        else:
            seg = [a, b, (int(order[r_, c_]), int(order[r_, c_ + 1])), 0.0, 0.0, False]
            row.append(seg)
        seg[3] += (b - a) if s_ == 1 else 0.0
        seg[4] += b - a
        seg[5] |= s_ == 2
    return rows
