"""Exact area of a polygon inside convex cones, by a triangle fan (pure numpy).

For a convex cone C with apex o (opening angle <= pi) and any polygon P with oriented
rings (exteriors counter-clockwise, holes clockwise), Green's theorem gives

    area(P ∩ C) = sum over the edges e of P of  1/2 cross(a_e - o, b_e - o),

where ``[a_e, b_e]`` is the part of edge e inside C: the boundary of P ∩ C also runs
along the cone's rays, but those pieces point at o and contribute nothing. This turns
greedy's gains, ``area(hull ∩ wedges[c])`` for every candidate c, into one vectorised
numpy expression instead of one polygon overlay per candidate.

>>> from shapely.geometry import box
>>> a, b = ring_edges(box(0, 0, 2, 2))
>>> cone_areas(a, b, np.array([[0.0, 0.0]]), np.array([0.0]), np.array([np.pi / 4])).round(12)
array([2.])

The same identity run the other way gives the area of a *convex* room covered by a union
of cones (:class:`UnionAreas`): the boundary of ``room ∩ ⋃ C`` is made of the parts of the
room's edges inside some cone and the parts of the cones' rays inside the room and outside
every other camera's cone; on a straight piece ``a + t d`` the integrand
``1/2 cross(p, dp)`` is the constant ``1/2 cross(a, d)``, so each piece contributes that
constant times the measure of its parameter set. A cone covers one arc of the room's
boundary (two for an apex outside the room), found from where its rays cross the
boundary; per camera set the area is a sum over pieces of constant cover: pure numpy, no
polygon overlay.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import shapely

__all__ = ["UnionAreas", "cone_areas", "convex_ring", "ring_edges", "split_wide"]

#: Pairs (cone, edge) evaluated per numpy block.
BLOCK = 1 << 20

def ring_edges(geom):
    """Edges of all rings of a (multi)polygon, exteriors CCW and holes CW.

    Returns
    -------
    a, b : (E, 2) float, metres; edge e runs from ``a[e]`` to ``b[e]``.
    """
    parts = shapely.get_parts(geom)
    parts = parts[~shapely.is_empty(parts)]
    if parts.size == 0:
        return np.empty((0, 2)), np.empty((0, 2))
    rings = shapely.get_rings(shapely.orient_polygons(parts))
    coords, idx = shapely.get_coordinates(rings, return_index=True)
    same = idx[1:] == idx[:-1]
    return coords[:-1][same], coords[1:][same]


def split_wide(camera, apex, theta0, theta1):
    """Split angular intervals wider than pi into two halves (cones must be convex).

    Parameters
    ----------
    camera : (q,) int; apex : (q, 2) float, metres
    theta0, theta1 : (q,) float, radians, theta0 < theta1

    Returns
    -------
    camera, apex, theta0, theta1 : (q',) arrays, still grouped by camera in order.
    """
    wide = theta1 - theta0 > np.pi
    if not wide.any():
        return camera, apex, theta0, theta1
    rep = np.where(wide, 2, 1)
    cam = np.repeat(camera, rep)
    apx = np.repeat(apex, rep, axis=0)
    t0 = np.repeat(theta0, rep)
    t1 = np.repeat(theta1, rep)
    first = np.concatenate([[0], np.cumsum(rep)[:-1]])
    mid = 0.5 * (theta0 + theta1)
    w = np.flatnonzero(wide)
    t1[first[w]] = mid[w]
    t0[first[w] + 1] = mid[w]
    return cam, apx, t0, t1


def cone_areas(a, b, apex, theta0, theta1) -> np.ndarray:
    """Area of the polygon with edges ``a -> b`` inside each convex cone.

    Parameters
    ----------
    a, b : (E, 2) float, metres, oriented ring edges (see :func:`ring_edges`)
    apex : (q, 2) float, metres, world frame
    theta0, theta1 : (q,) float, radians, world frame, ``0 < theta1 - theta0 <= pi``

    Returns
    -------
    (q,) float, m^2
    """
    q = apex.shape[0]
    out = np.zeros(q)
    if a.shape[0] == 0 or q == 0:
        return out
    u0 = np.c_[np.cos(theta0), np.sin(theta0)]
    u1 = np.c_[np.cos(theta1), np.sin(theta1)]
    d = b - a
    step = max(1, BLOCK // a.shape[0])
    for s in range(0, q, step):
        sl = slice(s, s + step)
        # inside C: f0 = cross(u0, p - o) >= 0 and f1 = cross(p - o, u1) >= 0, p = a + t d;
        # both are linear in t: f = al + t be
        o0 = u0[sl, 0] * apex[sl, 1] - u0[sl, 1] * apex[sl, 0]
        o1 = apex[sl, 0] * u1[sl, 1] - apex[sl, 1] * u1[sl, 0]
        al0 = np.outer(u0[sl, 0], a[:, 1]) - np.outer(u0[sl, 1], a[:, 0]) - o0[:, None]
        be0 = np.outer(u0[sl, 0], d[:, 1]) - np.outer(u0[sl, 1], d[:, 0])
        al1 = np.outer(u1[sl, 1], a[:, 0]) - np.outer(u1[sl, 0], a[:, 1]) - o1[:, None]
        be1 = np.outer(u1[sl, 1], d[:, 0]) - np.outer(u1[sl, 0], d[:, 1])
        # keep pairs whose edge is not wholly outside one of the two rays
        keep = ~(((al0 < 0) & (al0 + be0 < 0)) | ((al1 < 0) & (al1 + be1 < 0)))
        ci, ei = np.nonzero(keep)
        al0, be0, al1, be1 = al0[keep], be0[keep], al1[keep], be1[keep]
        lo = np.zeros(ci.size)
        hi = np.ones(ci.size)
        for al, be in ((al0, be0), (al1, be1)):
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -al / be
            lo = np.where(be > 0, np.maximum(lo, t), lo)
            hi = np.where(be < 0, np.minimum(hi, t), hi)
            hi = np.where((be == 0) & (al < 0), -1.0, hi)
        ok = hi > lo
        ao = a[ei] - apex[sl][ci]
        dd = d[ei]
        p = ao + lo[:, None] * dd
        r = ao + hi[:, None] * dd
        tri = np.where(ok, 0.5 * (p[:, 0] * r[:, 1] - p[:, 1] * r[:, 0]), 0.0)
        out[sl] = np.bincount(ci, weights=tri, minlength=apex[sl].shape[0])
    return out


def convex_ring(room):
    """The room's exterior ring as (V+1, 2) closed coordinates if it is a convex polygon
    without holes (collinear vertices allowed), else None."""
    if shapely.get_type_id(room) != 3 or shapely.get_num_interior_rings(room):
        return None
    v = shapely.get_coordinates(room)
    if v.shape[0] < 4:
        return None
    d = np.diff(v, axis=0)
    turn = d[:, 0] * np.roll(d[:, 1], -1) - d[:, 1] * np.roll(d[:, 0], -1)
    tol = 1e-12 * float(np.max(np.abs(turn)))
    if np.all(turn >= -tol) or np.all(turn <= tol):
        return v
    return None


def _cat(*parts):
    """``np.concatenate`` of arrays and scalars (``np.r_`` without its parsing cost)."""
    return np.concatenate([np.atleast_1d(p) for p in parts])


def _next(x, axis=0):
    """``np.roll(x, -1, axis)``: the next element along a closed ring."""
    return np.concatenate([x[(slice(None),) * axis + (slice(1, None),)],
                           x[(slice(None),) * axis + (slice(0, 1),)]], axis=axis)


def _prev(x, axis=0):
    """``np.roll(x, 1, axis)``: the previous element along a closed ring."""
    return np.concatenate([x[(slice(None),) * axis + (slice(-1, None),)],
                           x[(slice(None),) * axis + (slice(0, -1),)]], axis=axis)


class _Ring:
    """A convex room's ring (CCW, E edges) and the same ring shrunk by ``delta`` (1e-12
    of its size): ``vs``, ``ds`` (E, 2); outward normal angles ``beta2`` (2E,),
    increasing, twice around; boundary integrand ``room_w`` per unit of s on each edge
    and its running sum ``cum`` (E + 1,)."""

    def __init__(self, room_xy):
        v = room_xy
        d = np.diff(v, axis=0)
        real = np.any(d != 0, axis=1)
        v, d = v[:-1][real], d[real]
        if np.sum(v[:, 0] * d[:, 1] - v[:, 1] * d[:, 0]) < 0:
            v = v[::-1]
            d = _next(v) - v
        self.E = v.shape[0]
        ln = np.hypot(d[:, 0], d[:, 1])
        delta = 1e-12 * float(np.ptp(v, axis=0).max())
        nin = np.stack((-d[:, 1], d[:, 0]), axis=-1) / ln[:, None]  # inward normals
        npr = _prev(nin)
        self.vs = v + delta * (npr + nin) / (1.0 + np.sum(npr * nin, axis=1))[:, None]
        self.ds = _next(self.vs) - self.vs
        beta = np.maximum.accumulate(np.unwrap(np.arctan2(-d[:, 0], d[:, 1])))
        self.beta2 = _cat(beta, beta + 2 * np.pi)
        self.room_w = 0.5 * (v[:, 0] * d[:, 1] - v[:, 1] * d[:, 0])
        self.cum = _cat(0.0, np.cumsum(self.room_w))

    def chain_pos(self, x, length):
        """Offsets ``x`` (boundary positions minus a chain's start) wrapped onto a chain
        of ``length`` edges: [0, length]; a rounding error before the start counts as 0,
        after the end as ``length``."""
        x = np.mod(x, self.E)
        return np.where(x > length, np.where(x > 0.5 * (length + self.E), 0.0, length), x)

    def boundary(self, s):
        """Boundary integral ``1/2 cross(x, dx)`` from s = 0 to s (s in [0, E])."""
        e = np.minimum(s.astype(np.intp), self.E - 1)
        return self.cum[e] + (s - e) * self.room_w[e]

    def crossings(self, p, u):
        """Where rays ``p + lam u`` (u unit, (r, 2)) leave and enter the shrunk room.

        The exit is on the chain of edges facing u (outward normal . u > 0), the entry on
        the other chain; along each chain the side of the vertices w.r.t. the ray's line
        is monotone, so a bisection finds the crossed edge (O(log E) per ray).

        Returns lam_out, s_out, lam_in, s_in: (r,) each; lam in metres along u, s the
        boundary position ``edge + fraction``.
        """
        vs, ds, E = self.vs, self.ds, self.E
        r = p.shape[0]
        phi = np.arctan2(u[:, 1], u[:, 0])
        b0 = self.beta2[0]
        x = b0 + np.mod(phi - 0.5 * np.pi - b0, 2 * np.pi)
        start = np.searchsorted(self.beta2, x, side="right")
        end = np.searchsorted(self.beta2, x + np.pi, side="left")
        # rows [0, r): exits on the front chain; [r, 2r): entries on the back chain
        base = _cat(start, end)
        hi = _cat(end - start, start + E - end)
        sgn = _cat(np.ones(r), -np.ones(r))
        pp, uu = _cat(p, p), _cat(u, u)
        ux, uy, px, py = sgn * uu[:, 0], sgn * uu[:, 1], pp[:, 0], pp[:, 1]
        lo = np.zeros(2 * r, dtype=np.intp)
        for _ in range(max(1, int(E).bit_length())):
            mid = (lo + hi) >> 1
            vm = vs[(base + mid) % E]
            left = ux * (vm[:, 1] - py) <= uy * (vm[:, 0] - px)
            lo = np.where(left, mid, lo)
            hi = np.where(left, hi, mid)
        e = (base + lo) % E
        a, de = vs[e], ds[e]
        den = uu[:, 0] * de[:, 1] - uu[:, 1] * de[:, 0]
        ax, ay = a[:, 0] - px, a[:, 1] - py
        ok = den != 0
        den = np.where(ok, den, 1.0)
        lam = np.where(ok, (ax * de[:, 1] - ay * de[:, 0]) / den, 0.0)
        t = np.where(ok, np.clip((ax * uu[:, 1] - ay * uu[:, 0]) / den, 0.0, 1.0), 0.0)
        s = e + t
        return lam[:r], s[:r], lam[r:], s[r:]


@lru_cache(maxsize=8)
def _ring_cached(key: bytes, shape: tuple) -> _Ring:
    return _Ring(np.frombuffer(key).reshape(shape))


def _shrunk_ring(room_xy: np.ndarray) -> _Ring:
    """:class:`_Ring` of a closed (V+1, 2) ring, cached: rooms repeat frame after frame."""
    return _ring_cached(room_xy.tobytes(), room_xy.shape)


def _tangents(ring: _Ring, cap: np.ndarray):
    """Per apex (nc, 2): outside the shrunk room?, and if so the boundary positions of
    the tangent vertices seen at the smallest and largest angles ``s_min``, ``s_max``,
    the far chain's length ``far`` (edges from s_min to s_max), ``a_min`` and the
    angular width of the room seen from the apex, radians."""
    vs, ds, E = ring.vs, ring.ds, ring.E
    # edge e is visible from an apex outside its line
    vis = (ds[None, :, 0] * (cap[:, None, 1] - vs[None, :, 1])
           < ds[None, :, 1] * (cap[:, None, 0] - vs[None, :, 0]))  # (nc, E)
    out = vis.any(axis=1)
    first = np.argmax(vis & ~_prev(vis, axis=1), axis=1)  # near chain's first edge
    last = np.argmax(vis & ~_next(vis, axis=1), axis=1)  # and last edge
    s_max = first.astype(float)
    s_min = ((last + 1) % E).astype(float)
    far = np.mod(s_max - s_min, E)
    tmin, tmax = vs[(last + 1) % E] - cap, vs[first] - cap
    a_min = np.arctan2(tmin[:, 1], tmin[:, 0])
    width = np.mod(np.arctan2(tmax[:, 1], tmax[:, 0]) - a_min, 2 * np.pi)
    return out, s_min, s_max, far, a_min, width


#: Distance (relative to a ray's length) within which a ray lies on another cone's edge line.
COLLINEAR = 1e-12


class UnionAreas:
    """Exact areas ``area(room ∩ ⋃_{c in T} wedges[c])`` for many camera sets T at once.

    Parameters
    ----------
    room_xy : (V+1, 2) float, closed ring of a convex room (see :func:`convex_ring`)
    cones : ``split_wide`` wedge table (camera (q,), apex (q, 2), theta0, theta1)
    n : number of cameras
    radius : float, metres, a ray length that leaves the room from every apex

    The room's boundary is a closed line parametrised by ``s = e + t`` (edge e, fraction
    t); a cone covers one arc of it (two if its apex is outside the room: the far side and
    the near side), from where its rays leave (and enter) the room. Ray exits come from a
    bisection along the chain of edges facing the ray (O(log V) per ray), so nothing is
    evaluated per (ray, edge) pair. Rays are clipped to the room shrunk by ``1e-12`` of its
    size and the arcs are where they meet that shrunk room, so a ray along a wall is
    counted once, by the wall; an apex on the wall is outside the shrunk room. A ray is
    covered only by other cameras' open cones. Areas agree with GEOS overlays to ~1e-12
    of the room's area. Build once per frame: the boundary and every ray are cut once
    into pieces of constant cover (one sort of all end points; the cover of a piece is
    the running sum of ``+-2**camera``, a bitmask, for up to 62 cameras, else a (piece,
    camera) table), so a call is one vectorised pass over the pieces for all sets.

    >>> from shapely.geometry import box
    >>> sq = np.asarray(box(0, 0, 2, 2).exterior.coords)
    >>> cones = (np.array([0, 1]), np.array([[0.0, 0.0], [2.0, 0.0]]),
    ...          np.array([0.0, np.pi / 2]), np.array([np.pi / 4, np.pi]))
    >>> UnionAreas(sq, cones, 2, 10.0)([[True, False], [False, True], [True, True]]).round(9)
    array([2., 4., 4.])
    """

    def __init__(self, room_xy, cones, n, radius):
        camera, apex, t0, t1 = cones
        keep = t1 > t0
        camera, apex, t0, t1 = camera[keep], apex[keep], t0[keep], t1[keep]
        self.n = n
        # coordinates about the room's centre: Green's integrand x dy - y dx of coordinates
        # far from the origin (a georeferenced room) cancels, and the shrink drowns in them
        room_xy = np.asarray(room_xy, dtype=float)
        origin = 0.5 * (room_xy.min(axis=0) + room_xy.max(axis=0))
        apex = apex - origin
        ring = _shrunk_ring(np.ascontiguousarray(room_xy - origin))
        self._ring, E = ring, ring.E
        q = camera.size
        # cameras: inside the shrunk room, or outside with a near chain of visible edges
        g = np.flatnonzero(_cat(True, camera[1:] != camera[:-1])) if q else np.empty(0, int)
        out, s_min, s_max, far, a_min, width = _tangents(ring, apex[g])
        # per cone: clip outside cameras' cones to the directions that meet the room
        ci = np.repeat(np.arange(g.size), np.diff(_cat(g, q)))
        o, a_min, width = out[ci], a_min[ci], width[ci]
        lo = np.mod(t0 - a_min, 2 * np.pi)
        hi = lo + (t1 - t0)
        wrap = (lo > width) & (hi >= 2 * np.pi)
        lo, hi = np.where(wrap, 0.0, lo), np.where(wrap, hi - 2 * np.pi, hi)
        clip0 = o & (lo <= 0.0)
        clip1 = o & (hi >= width)
        hi = np.minimum(hi, width)
        sel = ~o | ((lo < width) & (hi > lo))
        th0 = np.where(o, a_min + lo, t0)[sel]
        th1 = np.where(o, a_min + hi, t1)[sel]
        camera, apex, o, clip0, clip1 = camera[sel], apex[sel], o[sel], clip0[sel], clip1[sel]
        s_min, s_max, far = s_min[ci[sel]], s_max[ci[sel]], far[ci[sel]]
        q = camera.size
        th = _cat(th0, th1)
        ua = np.stack((np.cos(th), np.sin(th)), axis=-1)
        u0, u1 = ua[:q], ua[q:]
        # where the two rays of every cone leave (and enter) the shrunk room
        lam_out, s_out, lam_in, s_in = ring.crossings(_cat(apex, apex), ua)
        oo = _cat(o, o)
        lam_in = np.where(oo, np.maximum(lam_in, 0.0), 0.0)
        # a ray clipped to a tangent direction only touches the room, at the tangent vertex
        tang = _cat(clip0, clip1)
        s_tan = _cat(s_min, s_max)
        s_out = np.where(tang, s_tan, s_out)
        s_in = np.where(tang, s_tan, s_in)
        lam_out = np.where(tang, lam_in, np.maximum(lam_out, lam_in))
        # boundary arcs: far side from exit(theta0) to exit(theta1), near side (cameras
        # outside) from entry(theta1) to entry(theta0), both counter-clockwise
        a0, a1 = s_out[:q], s_out[q:]
        span_in = np.mod(a1 - a0, E)
        span_in = np.where((np.floor(a0) == np.floor(a1)) & (a1 < a0), 0.0, span_in)
        f0 = ring.chain_pos(a0 - s_min, far)
        f1 = np.maximum(ring.chain_pos(a1 - s_min, far), f0)
        n0 = ring.chain_pos(s_in[q:] - s_max, E - far)
        n1 = np.maximum(ring.chain_pos(s_in[:q] - s_max, E - far), n0)
        arc_lo = _cat(np.where(o, s_min + f0, a0), (s_max + n0)[o])
        arc_hi = _cat(np.where(o, s_min + f1, a0 + span_in), (s_max + n1)[o])
        arc_cam = _cat(camera, camera[o])
        # rays as segments ra + t rd, t in [0, 1]: theta0 ray outwards, theta1 ray inwards
        ra = _cat(apex, apex + radius * u1)
        rd = _cat(radius * u0, -radius * u1)
        rcam = _cat(camera, camera)
        rlo = _cat(lam_in[:q], radius - lam_out[q:]) / radius
        rhi = _cat(lam_out[:q], radius - lam_in[q:]) / radius
        rhi = np.maximum(rhi, rlo)
        self._rays(camera, apex, u0, u1, ra, rd, rcam, rlo, rhi)
        self._pieces(arc_cam, arc_lo, arc_hi)

    def _rays(self, camera, apex, u0, u1, ra, rd, rcam, rlo, rhi):
        """Cover of each in-room ray piece by the other cameras' open cones, as a dense
        (ray, cone) table of parameter intervals (the arithmetic of ``cone_areas``).

        A ray on the edge line of another camera's cone (to ``COLLINEAR`` of the ray's
        length) is inside that cone when the cone lies on the same side of it as the ray's
        own cone and belongs to a lower-numbered camera: two cameras' rays along one
        segment, their cones on one side, are one edge of the union, counted once (the
        lower camera's ray); cones on opposite sides leave two opposite rays that cancel.
        """
        nr, q = ra.shape[0], camera.size
        px = ra[:, None, 0] - apex[None, :, 0]
        py = ra[:, None, 1] - apex[None, :, 1]
        dx, dy = rd[:, None, 0], rd[:, None, 1]
        lo = np.zeros((nr, q))
        hi = np.ones((nr, q))
        scale = np.hypot(rd[:, 0], rd[:, 1])[:, None] * COLLINEAR
        lower = camera[None, :] < rcam[:, None]
        # every ray's own cone is on its left: theta0 rays run outwards, theta1 rays inwards
        for al, be, edge, left in ((u0[None, :, 0] * py - u0[None, :, 1] * px,
                                    u0[None, :, 0] * dy - u0[None, :, 1] * dx, u0, 1.0),
                                   (px * u1[None, :, 1] - py * u1[None, :, 0],
                                    dx * u1[None, :, 1] - dy * u1[None, :, 0], u1, -1.0)):
            on = (np.abs(be) <= scale) & (np.abs(al) <= scale)
            same_side = left * (dx * edge[None, :, 0] + dy * edge[None, :, 1]) > 0
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -al / be
            inside = on & same_side & lower                 # the constraint holds all along
            lo = np.where((be > 0) & ~on, np.maximum(lo, t), lo)
            hi = np.where((be < 0) & ~on, np.minimum(hi, t), hi)
            hi = np.where(((be == 0) & (al <= 0) & ~on) | (on & ~inside), -1.0, hi)
        lo = np.maximum(lo, rlo[:, None])
        hi = np.minimum(hi, rhi[:, None])
        use = (hi > lo) & (camera[None, :] != rcam[:, None]) & (rhi > rlo)[:, None]
        rj, cj = np.nonzero(use)
        self.ray_len = rhi - rlo
        self.ray_w = 0.5 * (ra[:, 0] * rd[:, 1] - ra[:, 1] * rd[:, 0])
        self.rcam = rcam
        self._ray_iv = (camera[cj], rj, lo[rj, cj], hi[rj, cj])

    def _pieces(self, arc_cam, arc_lo, arc_hi):
        """Cut the boundary (at the arcs' ends) and every ray (at its covering cones'
        ends) into pieces of constant cover: piece weights ``v`` (boundary integrand
        over the piece), covers (``bits`` or ``M`` (P, n)) and the ray camera of each
        piece (-1 on the room's boundary). Ties in the sorts only order pieces of zero
        length, which are dropped."""
        n, ring = self.n, self._ring
        E = ring.E
        shift = np.floor(arc_lo / E) * E
        lo, hi = arc_lo - shift, arc_hi - shift  # lo in [0, E), hi in [lo, lo + E]
        over = hi > E
        na = arc_cam.size + int(over.sum())
        # boundary events (start, end of every arc; sentinels at 0 and E)
        bpos = np.concatenate([lo, np.zeros(na - lo.size), np.minimum(hi, E), hi[over] - E,
                               [0.0, float(E)]])
        bcam = np.concatenate([arc_cam, arc_cam[over], arc_cam, arc_cam[over], [0, 0]])
        bsgn = np.concatenate([np.ones(na), -np.ones(na), [0.0, 0.0]])
        order = np.argsort(bpos)
        bpos, bcam, bsgn = bpos[order], bcam[order], bsgn[order]
        bint = ring.boundary(bpos)
        # ray events, sorted by ray then position (ray item r at keys [2r, 2r + 1])
        rcam_i, ritem, rlo, rhi = self._ray_iv
        rpos = np.concatenate([rlo, rhi])
        rit = np.concatenate([ritem, ritem])
        order = np.argsort(2.0 * rit + rpos)
        rpos, rit = rpos[order], rit[order]
        rcam_e = np.concatenate([rcam_i, rcam_i])[order]
        rsgn = np.concatenate([np.ones(ritem.size), -np.ones(ritem.size)])[order]
        rlen = np.where(rit[1:] == rit[:-1], rpos[1:] - rpos[:-1], 0.0)
        blen = bpos[1:] - bpos[:-1]
        cam = np.concatenate([bcam, rcam_e]).astype(np.intp)
        npc = cam.size - 1  # pieces between consecutive events (boundary, then rays)
        length = np.concatenate([blen, [0.0], rlen])[:npc]
        w = np.concatenate([bint[1:] - bint[:-1], [0.0], rlen * self.ray_w[rit[:-1]]])[:npc]
        pc = np.concatenate([np.full(blen.size + 1, -1), self.rcam[rit[:-1]]])[:npc]
        sgn = np.concatenate([bsgn, rsgn])
        if n <= 62:
            # a camera's cones are disjoint, so the running sum of +-2**camera is the
            # bitmask of the cameras covering each piece (exact in int64)
            cover = np.cumsum(sgn.astype(np.int64) << cam)[:-1]
            sel = (length > 0) & (cover != 0)
            self.bits, self.M = cover[sel], None
        else:
            delta = np.zeros((n, cam.size))
            delta[cam, np.arange(cam.size)] = sgn
            cover = (np.cumsum(delta, axis=1)[:, :-1] > 0.5).T
            sel = (length > 0) & cover.any(axis=1)
            self.M, self.bits = cover[sel].astype(float), None
        self.v, self.pc = w[sel], pc[sel]
        self.W = self.ray_w * self.ray_len  # (nr,) a ray's whole integrand
        if self.bits is not None:
            # bit tables for the call: boundary pieces count if covered; ray pieces
            # (negative) if covered and the ray's camera is in the set
            ray = self.pc >= 0
            self._eb, self._ev = self.bits[~ray], self.v[~ray]
            self._rb, self._rv = self.bits[ray], self.v[ray]
            self._rcb = np.left_shift(1, self.pc[ray]).astype(np.int64)
            self._wcb = np.left_shift(1, self.rcam).astype(np.int64)

    def __call__(self, inset):
        """inset: (S, n) bool -> (S,) area of room ∩ union of the sets' wedges."""
        inset = np.atleast_2d(np.asarray(inset, dtype=bool))
        if self.bits is not None:
            sb = (inset.astype(np.int64) << np.arange(self.n)).sum(axis=1)[:, None]
            room = np.where((sb & self._eb) != 0, self._ev, 0.0).sum(axis=1)
            cut = np.where(((sb & self._rb) != 0) & ((sb & self._rcb) != 0), self._rv, 0.0)
            whole = np.where((sb & self._wcb) != 0, self.W, 0.0).sum(axis=1)
            return room - cut.sum(axis=1) + whole
        T = inset.astype(float)
        hit = (T @ self.M.T) > 0.5
        ray = self.pc >= 0
        sign = np.where(ray, -1.0, 1.0)
        inray = np.where(ray[None, :], T[:, np.maximum(self.pc, 0)] > 0.5, True)
        pieces = ((hit & inray) * (sign * self.v)).sum(axis=1)
        return pieces + (T[:, self.rcam] * self.W).sum(axis=1)
