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

#: Room edges per chain in :class:`UnionAreas` (coarse side-of-line tests).
CHAIN = 16


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


def _clip_pairs(a, d, apex, u0, u1, strict):
    """Parameter interval [lo, hi] of segments a + t d, t in [0, 1], inside cones (pairwise)."""
    p = a - apex
    lo = np.zeros(a.shape[0])
    hi = np.ones(a.shape[0])
    # f0 = cross(u0, p + t d) >= 0, f1 = cross(p + t d, u1) >= 0
    for al, be in ((u0[:, 0] * p[:, 1] - u0[:, 1] * p[:, 0], u0[:, 0] * d[:, 1] - u0[:, 1] * d[:, 0]),
                   (p[:, 0] * u1[:, 1] - p[:, 1] * u1[:, 0], d[:, 0] * u1[:, 1] - d[:, 1] * u1[:, 0])):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -al / be
        lo = np.where(be > 0, np.maximum(lo, t), lo)
        hi = np.where(be < 0, np.minimum(hi, t), hi)
        bad = (al <= 0) if strict else (al < 0)
        hi = np.where((be == 0) & bad, -1.0, hi)
    return lo, hi


class UnionAreas:
    """Exact areas ``area(room ∩ ⋃_{c in T} wedges[c])`` for many camera sets T at once.

    Parameters
    ----------
    room_xy : (V+1, 2) float, closed ring of a convex room (see :func:`convex_ring`)
    cones : ``split_wide`` wedge table (camera (q,), apex (q, 2), theta0, theta1)
    n : number of cameras
    radius : float, metres, a ray length that leaves the room from every apex

    Rays are clipped to the room shrunk by ``1e-12`` of its size and the room's edges are
    tested ``1e-12`` inside, so a ray along a wall is counted once, by the wall; a ray is
    covered only by other cameras' open cones. Areas agree with GEOS overlays to ~1e-12 of
    the room's area. Build once per frame: every room edge and ray is cut once into pieces
    of constant cover (one sort of all interval end points; the cover of a piece is the
    running sum of ``+-2**camera``, a bitmask, for up to 62 cameras, else a (piece,
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
        self.n = n
        v = room_xy
        a, d = v[:-1], v[1:] - v[:-1]
        if np.sum(a[:, 0] * d[:, 1] - a[:, 1] * d[:, 0]) < 0:
            v = v[::-1]
            a, d = v[:-1], v[1:] - v[:-1]
        E = a.shape[0]
        ln = np.hypot(d[:, 0], d[:, 1])
        span = float(np.ptp(v, axis=0).max())
        delta = 1e-12 * span
        eps = 1e-9 * span
        u0 = np.c_[np.cos(t0), np.sin(t0)]
        u1 = np.c_[np.cos(t1), np.sin(t1)]
        q = camera.size
        # rays: theta0 ray outwards, theta1 ray inwards (the cone's boundary, CCW)
        ra = np.r_[apex, apex + radius * u1]
        rd = np.r_[radius * u0, -radius * u1]
        rcam = np.r_[camera, camera]
        # sv = cross(rd_r, v - ra_r): the side of room vertex v of ray r's line; for the
        # cones sv[:q] = radius * cross(u0, v - apex), sv[q:] = radius * cross(v - apex, u1),
        # both >= 0 inside the cone. The ring is cut into chains of CHAIN edges; a chain
        # whose bounding circle is clear of a line lies on one side of it, and only the
        # other (ray, chain) pairs are evaluated vertex by vertex.
        eps_r = eps * radius
        nr = ra.shape[0]
        K = -(-E // CHAIN)
        vk = np.concatenate([v, np.repeat(v[-1:], K * CHAIN + 1 - v.shape[0], axis=0)])
        chain = np.lib.stride_tricks.sliding_window_view(vk, CHAIN + 1, axis=0)[::CHAIN]
        chain = np.moveaxis(chain, -1, 1)  # (K, CHAIN + 1, 2)
        ctr = chain.mean(axis=1)
        rad = np.sqrt(((chain - ctr[:, None, :]) ** 2).sum(axis=2)).max(axis=1)
        rc = rd[:, 0] * ra[:, 1] - rd[:, 1] * ra[:, 0]
        sc = np.outer(rd[:, 0], ctr[:, 1]) - np.outer(rd[:, 1], ctr[:, 0]) - rc[:, None]
        clear = np.abs(sc) > rad[None, :] * radius + 2 * eps_r
        st = np.repeat(np.where(clear, np.sign(sc), 0).astype(np.int8), CHAIN, axis=1)[:, :E]
        pr, pk = np.nonzero(~clear)
        cv = chain[pk]  # (P, CHAIN + 1, 2)
        sv = rd[pr, None, 0] * cv[:, :, 1] - rd[pr, None, 1] * cv[:, :, 0] - rc[pr, None]
        mn = np.minimum(sv[:, :-1], sv[:, 1:])
        mx = np.maximum(sv[:, :-1], sv[:, 1:])
        pe = pk[:, None] * CHAIN + np.arange(CHAIN)[None, :]  # (P, CHAIN) edge index
        ok = pe < E
        pst = np.where(mn > eps_r, 1, np.where(mx < -eps_r, -1, 0)).astype(np.int8)
        prr = np.broadcast_to(pr[:, None], pe.shape)
        st[prr[ok], pe[ok]] = pst[ok]
        # room edges: classified by their vertices; clipped exactly only near a ray
        full = (st[:q] == 1) & (st[q:] == 1)
        part = ~(full | (st[:q] == -1) | (st[q:] == -1))
        # (n, E) count of cones fully covering each edge (cones are grouped by camera;
        # no matmul: a threaded BLAS would cost more CPU than it saves)
        self.fullcam = np.zeros((n, E))
        if q:
            g = np.flatnonzero(np.r_[True, camera[1:] != camera[:-1]])
            self.fullcam[camera[g]] = np.add.reduceat(full.astype(float), g, axis=0)
        ci, ei = np.nonzero(part)
        nin = np.c_[-d[:, 1], d[:, 0]] / ln[:, None]
        elo, ehi = _clip_pairs(a[ei] + delta * nin[ei], d[ei], apex[ci], u0[ci], u1[ci], False)
        fullc = self.fullcam
        room_iv = (camera[ci], ei, elo, ehi)
        # the part of each ray inside the room shrunk by delta; only the edges its line
        # crosses (a vertex sign change) bind
        cross = (mn <= 0) & (mx >= 0) & ok
        ri, ei = prr[cross], pe[cross]
        order = np.argsort(ri, kind="stable")
        ri, ei = ri[order], ei[order]
        g0 = (d[ei, 0] * (ra[ri, 1] - a[ei, 1]) - d[ei, 1] * (ra[ri, 0] - a[ei, 0])
              - delta * ln[ei])
        g1 = d[ei, 0] * rd[ri, 1] - d[ei, 1] * rd[ri, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -g0 / g1
        tlo = np.where(g1 > 0, t, 0.0)
        thi = np.where(g1 < 0, t, 1.0)
        thi = np.where((g1 == 0) & (g0 < 0), -1.0, thi)
        rlo = np.zeros(nr)
        rhi = np.zeros(nr)
        if ri.size:
            start = np.flatnonzero(np.r_[True, ri[1:] != ri[:-1]])
            rows = ri[start]
            rlo[rows] = np.maximum(np.maximum.reduceat(tlo, start), 0.0)
            rhi[rows] = np.minimum(np.minimum.reduceat(thi, start), 1.0)
        rhi = np.maximum(rhi, rlo)
        inside = rhi > rlo
        # cover of each in-room ray by the other cameras' cones (open cones), as a dense
        # (ray, cone) table: the same arithmetic as _clip_pairs, without fancy indexing
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
        use = (hi > lo) & (camera[None, :] != rcam[:, None]) & inside[:, None]
        rj, cj = np.nonzero(use)
        self.ray_len = rhi - rlo
        self.ray_w = 0.5 * (ra[:, 0] * rd[:, 1] - ra[:, 1] * rd[:, 0])
        self.rcam = rcam
        self.room_w = 0.5 * (a[:, 0] * d[:, 1] - a[:, 1] * d[:, 0])
        self.E = E
        self._pieces(camera, E, fullc, room_iv,
                     (camera[cj], rj, lo[rj, cj], hi[rj, cj]))

    def _pieces(self, camera, E, fullc, room, rays):
        """Cut every room edge and ray into pieces of constant cover: piece weights
        ``v`` (boundary integrand times length), cover table ``M`` (P, n) and the ray
        camera of each piece (-1 for room edges)."""
        n = self.n
        ecam, eitem, elo, ehi = room
        rcam_i, ritem, rlo, rhi = rays
        keep = ehi > elo
        ecam, eitem, elo, ehi = ecam[keep], eitem[keep], elo[keep], ehi[keep]
        pe = np.unique(eitem)  # room edges cut by a cone's ray: sentinels at 0 and 1
        item = np.concatenate([eitem, eitem, pe, pe, ritem + E, ritem + E])
        pos = np.concatenate([elo, ehi, np.zeros(pe.size), np.ones(pe.size), rlo, rhi])
        cam = np.concatenate([ecam, ecam, np.zeros(2 * pe.size, np.intp), rcam_i, rcam_i])
        sgn = np.concatenate([np.ones(eitem.size), -np.ones(eitem.size),
                              np.zeros(2 * pe.size), np.ones(ritem.size),
                              -np.ones(ritem.size)])
        order = np.argsort(2.0 * item + pos, kind="stable")
        item, pos, cam, sgn = item[order], pos[order], cam[order], sgn[order]
        same = item[1:] == item[:-1]
        length = np.where(same, pos[1:] - pos[:-1], 0.0)
        it = item[:-1]
        edge = it < E
        ie = np.minimum(it, E - 1)
        ir = np.maximum(it - E, 0)
        v = length * np.where(edge, self.room_w[ie], self.ray_w[ir])
        pc = np.where(edge, -1, self.rcam[ir])
        # whole room edges without cuts: one piece each, covered by fullc
        whole = np.ones(E, bool)
        whole[pe] = False
        whole &= fullc.any(axis=0)
        we = np.flatnonzero(whole)
        if n <= 62:
            # a camera's cones are disjoint, so the running sum of +-2**camera is the
            # bitmask of the cameras covering each piece (exact in int64)
            fb = ((fullc > 0).T.astype(np.int64) << np.arange(n)).sum(axis=1)
            cover = np.cumsum(sgn.astype(np.int64) << cam)[:-1]
            cover |= np.where(edge, fb[ie], 0)
            sel = (length > 0) & (cover != 0)
            self.bits = np.concatenate([cover[sel], fb[we]])
            self.M = None
        else:
            delta = np.zeros((n, item.size))
            delta[cam, np.arange(item.size)] = sgn
            cover = (np.cumsum(delta, axis=1)[:, :-1] > 0.5).T
            cover |= edge[:, None] & (fullc[:, ie].T > 0)
            sel = (length > 0) & cover.any(axis=1)
            self.M = np.concatenate([cover[sel], fullc[:, we].T > 0]).astype(float)
            self.bits = None
        self.v = np.concatenate([v[sel], self.room_w[we]])
        self.pc = np.concatenate([pc[sel], np.full(we.size, -1)])
        self.W = self.ray_w * self.ray_len  # (nr,) a ray's whole integrand
        if self.bits is not None:
            # bit tables for the call: room-edge pieces count if covered; ray pieces
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
