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
constant times the measure of its parameter set. Per camera set this is a union of
intervals per edge or ray: pure numpy, no polygon overlay.
"""

from __future__ import annotations

import numpy as np
import shapely

__all__ = ["ring_edges", "cone_areas", "split_wide", "convex_ring", "UnionAreas"]

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
        v = np.asarray(room_xy, dtype=float)
        d = np.diff(v, axis=0)
        v, d = v[:-1][np.any(d != 0, axis=1)], d[np.any(d != 0, axis=1)]
        if np.sum(v[:, 0] * d[:, 1] - v[:, 1] * d[:, 0]) < 0:
            v = v[::-1]
            d = _next(v) - v
        E = v.shape[0]
        ln = np.hypot(d[:, 0], d[:, 1])
        delta = 1e-12 * float(np.ptp(v, axis=0).max())
        # the shrunk room: every edge moved delta inwards (inward normal nin)
        nin = np.stack((-d[:, 1], d[:, 0]), axis=-1) / ln[:, None]
        npr = _prev(nin)
        vs = v + delta * (npr + nin) / (1.0 + np.sum(npr * nin, axis=1))[:, None]
        ds = _next(vs) - vs
        # outward normal angle of every edge, increasing around the ring (by 2 pi)
        beta = np.maximum.accumulate(np.unwrap(np.arctan2(-d[:, 0], d[:, 1])))
        self._vs, self._ds, self._E = vs, ds, E
        self._beta2 = _cat(beta, beta + 2 * np.pi)
        q = camera.size
        # cameras: inside the shrunk room, or outside with a near chain of visible edges
        g = np.flatnonzero(_cat(True, camera[1:] != camera[:-1])) if q else np.empty(0, int)
        cap = apex[g]  # (nc, 2) one apex per camera with cones
        rel = cap[:, None, :] - vs[None, :, :]
        vis = ds[None, :, 0] * rel[:, :, 1] - ds[None, :, 1] * rel[:, :, 0] < 0  # (nc, E)
        out = vis.any(axis=1)
        first = np.argmax(vis & ~_prev(vis, axis=1), axis=1)  # near chain's first edge
        last = np.argmax(vis & ~_next(vis, axis=1), axis=1)  # and last edge
        s_max = first.astype(float)  # tangent vertex seen at the largest angle
        s_min = ((last + 1) % E).astype(float)  # ... at the smallest angle
        far = np.mod(s_max - s_min, E)  # far chain: [s_min, s_min + far]
        tmin, tmax = vs[(last + 1) % E] - cap, vs[first] - cap
        a_min = np.arctan2(tmin[:, 1], tmin[:, 0])
        width = np.mod(np.arctan2(tmax[:, 1], tmax[:, 0]) - a_min, 2 * np.pi)
        # per cone: clip outside cameras' cones to the directions that meet the room
        ci = np.repeat(np.arange(g.size), np.diff(_cat(g, q)))
        o = out[ci]
        lo = np.mod(t0 - a_min[ci], 2 * np.pi)
        hi = lo + (t1 - t0)
        wrap = (lo > width[ci]) & (hi >= 2 * np.pi)
        lo, hi = np.where(wrap, 0.0, lo), np.where(wrap, hi - 2 * np.pi, hi)
        hit = ~o | (lo < width[ci])
        clip0 = o & (lo <= 0.0)
        clip1 = o & (hi >= width[ci])
        hi = np.minimum(hi, width[ci])
        th0 = np.where(o, a_min[ci] + lo, t0)
        th1 = np.where(o, a_min[ci] + hi, t1)
        sel = hit & (~o | (hi > lo))
        camera, apex, ci, o = camera[sel], apex[sel], ci[sel], o[sel]
        th0, th1, clip0, clip1 = th0[sel], th1[sel], clip0[sel], clip1[sel]
        q = camera.size
        u0 = np.stack((np.cos(th0), np.sin(th0)), axis=-1)
        u1 = np.stack((np.cos(th1), np.sin(th1)), axis=-1)
        # where the two rays of every cone leave (and enter) the shrunk room
        pa, ua = _cat(apex, apex), _cat(u0, u1)
        lam_out, s_out = self._cross_chain(pa, ua, front=True)
        lam_in, s_in = self._cross_chain(pa, ua, front=False)
        oo = _cat(o, o)
        lam_in = np.where(oo, np.maximum(lam_in, 0.0), 0.0)
        # a ray clipped to a tangent direction only touches the room, at the tangent vertex
        tang = _cat(clip0, clip1)
        s_tan = _cat(s_min[ci], s_max[ci])
        s_out = np.where(tang, s_tan, s_out)
        s_in = np.where(tang, s_tan, s_in)
        lam_out = np.where(tang, lam_in, np.maximum(lam_out, lam_in))
        # boundary arcs: far side from exit(theta0) to exit(theta1), near side (cameras
        # outside) from entry(theta1) to entry(theta0), both counter-clockwise
        a0, a1 = s_out[:q], s_out[q:]
        span_in = np.mod(a1 - a0, E)
        same = (np.floor(a0) == np.floor(a1)) & (a1 < a0)
        span_in = np.where(same, 0.0, span_in)
        b_far = s_min[ci]
        f0 = self._chain_pos(a0 - b_far, far[ci])
        f1 = np.maximum(self._chain_pos(a1 - b_far, far[ci]), f0)
        n0 = self._chain_pos(s_in[q:] - s_max[ci], E - far[ci])
        n1 = np.maximum(self._chain_pos(s_in[:q] - s_max[ci], E - far[ci]), n0)
        arc_lo = _cat(np.where(o, b_far + f0, a0), (s_max[ci] + n0)[o])
        arc_hi = _cat(np.where(o, b_far + f1, a0 + span_in), (s_max[ci] + n1)[o])
        arc_cam = _cat(camera, camera[o])
        # rays as segments ra + t rd, t in [0, 1]: theta0 ray outwards, theta1 ray inwards
        ra = _cat(apex, apex + radius * u1)
        rd = _cat(radius * u0, -radius * u1)
        rcam = _cat(camera, camera)
        rlo = _cat(lam_in[:q], radius - lam_out[q:]) / radius
        rhi = _cat(lam_out[:q], radius - lam_in[q:]) / radius
        rhi = np.maximum(rhi, rlo)
        self._rays(camera, apex, u0, u1, ra, rd, rcam, rlo, rhi)
        self._pieces(v, d, arc_cam, arc_lo, arc_hi)

    def _chain_pos(self, x, length):
        """Offsets ``x`` (boundary positions minus a chain's start) wrapped onto a chain
        of ``length`` edges: [0, length]; a rounding error before the start counts as 0,
        after the end as ``length``."""
        x = np.mod(x, self._E)
        return np.where(x > length, np.where(x > 0.5 * (length + self._E), 0.0, length), x)

    def _cross_chain(self, p, u, front):
        """Where rays ``p + lam u`` cross the shrunk room's boundary.

        front=True: the exit, on the chain of edges facing u (outward normal . u > 0);
        False: the entry, on the other chain. Bisection on the side of the chain's
        vertices, which is monotone along the chain.

        Returns lam (r,) metres along unit u, and the boundary position s (r,).
        """
        vs, ds, E = self._vs, self._ds, self._E
        r = p.shape[0]
        if r == 0:
            return np.empty(0), np.empty(0)
        b0 = self._beta2[0]
        phi = np.arctan2(u[:, 1], u[:, 0])
        x = b0 + np.mod(phi - 0.5 * np.pi - b0, 2 * np.pi)
        start = np.searchsorted(self._beta2, x, side="right")
        end = np.searchsorted(self._beta2, x + np.pi, side="left")
        if front:
            base, length, sgn = start, end - start, 1.0
        else:
            base, length, sgn = end, start + E - end, -1.0
        lo = np.zeros(r, dtype=np.intp)
        hi = length.astype(np.intp)
        while True:
            wide = hi - lo > 1
            if not wide.any():
                break
            mid = (lo + hi) // 2
            vm = vs[(base + mid) % E]
            w = sgn * (u[:, 0] * (vm[:, 1] - p[:, 1]) - u[:, 1] * (vm[:, 0] - p[:, 0]))
            left = wide & (w <= 0)
            lo = np.where(left, mid, lo)
            hi = np.where(wide & ~left, mid, hi)
        e = (base + lo) % E
        a, de = vs[e], ds[e]
        den = u[:, 0] * de[:, 1] - u[:, 1] * de[:, 0]
        ax, ay = a[:, 0] - p[:, 0], a[:, 1] - p[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = (ax * de[:, 1] - ay * de[:, 0]) / den
            t = (ax * u[:, 1] - ay * u[:, 0]) / den
        ok = den != 0
        t = np.where(ok, np.clip(t, 0.0, 1.0), 0.0)
        return np.where(ok, lam, 0.0), e + t

    def _rays(self, camera, apex, u0, u1, ra, rd, rcam, rlo, rhi):
        """Cover of each in-room ray piece by the other cameras' open cones, as a dense
        (ray, cone) table of parameter intervals (the arithmetic of ``cone_areas``)."""
        nr, q = ra.shape[0], camera.size
        px = ra[:, None, 0] - apex[None, :, 0]
        py = ra[:, None, 1] - apex[None, :, 1]
        dx, dy = rd[:, None, 0], rd[:, None, 1]
        lo = np.zeros((nr, q))
        hi = np.ones((nr, q))
        for al, be in ((u0[None, :, 0] * py - u0[None, :, 1] * px,
                        u0[None, :, 0] * dy - u0[None, :, 1] * dx),
                       (px * u1[None, :, 1] - py * u1[None, :, 0],
                        dx * u1[None, :, 1] - dy * u1[None, :, 0])):
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -al / be
            lo = np.where(be > 0, np.maximum(lo, t), lo)
            hi = np.where(be < 0, np.minimum(hi, t), hi)
            hi = np.where((be == 0) & (al <= 0), -1.0, hi)
        lo = np.maximum(lo, rlo[:, None])
        hi = np.minimum(hi, rhi[:, None])
        use = (hi > lo) & (camera[None, :] != rcam[:, None]) & (rhi > rlo)[:, None]
        rj, cj = np.nonzero(use)
        self.ray_len = rhi - rlo
        self.ray_w = 0.5 * (ra[:, 0] * rd[:, 1] - ra[:, 1] * rd[:, 0])
        self.rcam = rcam
        self._ray_iv = (camera[cj], rj, lo[rj, cj], hi[rj, cj])

    def _pieces(self, v, d, arc_cam, arc_lo, arc_hi):
        """Cut the boundary (at the arcs' ends) and every ray (at its covering cones'
        ends) into pieces of constant cover: piece weights ``v`` (boundary integrand
        over the piece), covers (``bits`` or ``M`` (P, n)) and the ray camera of each
        piece (-1 on the room's boundary)."""
        n, E = self.n, self._E
        room_w = 0.5 * (v[:, 0] * d[:, 1] - v[:, 1] * d[:, 0])  # per unit of s on edge e
        cum = _cat(0.0, np.cumsum(room_w))
        shift = np.floor(arc_lo / E) * E
        lo, hi = arc_lo - shift, arc_hi - shift  # lo in [0, E), hi in [lo, lo + E]
        over = hi > E
        alo = _cat(lo, np.zeros(over.sum()))
        ahi = _cat(np.minimum(hi, E), hi[over] - E)
        acam = _cat(arc_cam, arc_cam[over])
        rcam_i, ritem, rlo, rhi = self._ray_iv
        na, nv = acam.size, ritem.size
        pos = np.concatenate([alo, ahi, [0.0, float(E)], rlo, rhi])
        item = np.concatenate([np.full(2 * na + 2, -1), ritem, ritem])
        cam = np.concatenate([acam, acam, [0, 0], rcam_i, rcam_i]).astype(np.intp)
        sgn = np.concatenate([np.ones(na), -np.ones(na), [0.0, 0.0],
                              np.ones(nv), -np.ones(nv)])
        key = np.where(item < 0, pos, E + 1.0 + 2.0 * item + pos)
        order = np.argsort(key, kind="stable")
        item, pos, cam, sgn = item[order], pos[order], cam[order], sgn[order]
        same = item[1:] == item[:-1]
        it = item[:-1]
        room = it < 0
        ir = np.maximum(it, 0)

        def boundary(s):  # boundary integral from s = 0 to s
            e = np.minimum(np.floor(s).astype(np.intp), E - 1)
            return cum[e] + (s - e) * room_w[e]

        length = np.where(same, pos[1:] - pos[:-1], 0.0)
        rw, rc = _cat(self.ray_w, 0.0), _cat(self.rcam, -1)  # padded: there may be no rays
        w = np.where(room, boundary(pos[1:]) - boundary(pos[:-1]), length * rw[ir])
        pc = np.where(room, -1, rc[ir])
        if n <= 62:
            # a camera's cones are disjoint, so the running sum of +-2**camera is the
            # bitmask of the cameras covering each piece (exact in int64)
            cover = np.cumsum(sgn.astype(np.int64) << cam)[:-1]
            sel = (length > 0) & (cover != 0)
            self.bits, self.M = cover[sel], None
        else:
            delta = np.zeros((n, item.size))
            delta[cam, np.arange(item.size)] = sgn
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
