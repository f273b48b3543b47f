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
"""

from __future__ import annotations

import numpy as np
import shapely

__all__ = ["ring_edges", "cone_areas", "split_wide"]

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
