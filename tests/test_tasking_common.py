"""Shared scene builders for the tasking tests (imported by the other test_tasking_* files).

pytest puts ``tests/`` on ``sys.path`` (rootdir-relative "prepend" import mode), so the
other tasking test modules import these helpers directly.
"""

import numpy as np
from shapely.geometry import Point, box


def circle_room(radius=1.0, quad_segs=64):
    """The paper's circular room, centred on the origin."""
    return Point(0.0, 0.0).buffer(radius, quad_segs=quad_segs)


def lab_room():
    """The 22 x 19 ft lab room, origin at a corner."""
    return box(0.0, 0.0, 6.7056, 5.7912)


def ring_cameras(n, radius=1.0, phase=0.0):
    """n cameras evenly on a circle, looking at its centre: (xy (n, 2), yaw (n,))."""
    theta = phase + 2 * np.pi * np.arange(n) / n
    xy = radius * np.c_[np.cos(theta), np.sin(theta)]
    return xy, theta + np.pi


def random_discs(rng, m, r=0.1, room_radius=1.0):
    """m disjoint discs of radius r dropped uniformly in the circular room (centres (m, 2))."""
    centres = []
    while len(centres) < m:
        p = rng.uniform(-1, 1, 2) * (room_radius - r)
        if np.hypot(*p) <= room_radius - r and all(
            np.hypot(*(p - q)) >= 2 * r for q in centres
        ):
            centres.append(p)
    return np.array(centres).reshape(-1, 2)


def scanlines_from_discs(xy, yaw, fov, centres, r, width):
    """Scanlines of disc objects: a column is occupied if its span meets a disc's cone.

    Returns bearings (n, W) decreasing along the row (image columns run clockwise) and
    scanlines (n, W) bool.
    """
    n = xy.shape[0]
    step = fov / width
    edges = yaw[:, None] + fov / 2 - step * np.arange(width + 1)[None, :]
    bearings = 0.5 * (edges[:, 1:] + edges[:, :-1])
    occ = np.zeros((n, width), dtype=bool)
    for c in range(n):
        for p in centres:
            d = p - xy[c]
            dist = np.hypot(*d)
            half = np.arcsin(min(1.0, r / dist))
            b = np.arctan2(d[1], d[0])
            # column j spans [edges[j+1], edges[j]]; overlap with [b - half, b + half]
            lo = edges[c, 1:]
            hi = edges[c, :-1]
            rel_lo = (lo - b + np.pi) % (2 * np.pi) - np.pi
            rel_hi = rel_lo + (hi - lo)
            occ[c] |= (rel_hi > -half) & (rel_lo < half)
    return bearings, occ


def test_ring_cameras_look_at_centre():
    xy, yaw = ring_cameras(4)
    direction = np.c_[np.cos(yaw), np.sin(yaw)]
    np.testing.assert_allclose(direction, -xy, atol=1e-12)


def test_random_discs_are_disjoint_and_inside():
    c = random_discs(np.random.default_rng(0), 6)
    d = np.hypot(*(c[:, None] - c[None]).transpose(2, 0, 1))
    assert np.all(d[np.triu_indices(6, 1)] >= 0.2)
    assert np.all(np.hypot(c[:, 0], c[:, 1]) <= 0.9)
