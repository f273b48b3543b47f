"""Triangle-fan cone areas agree with polygon overlays."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import MultiPoint, Point, box

from tasking.cones import wedge_polygons
from tasking.fan import cone_areas, ring_edges, split_wide


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.booleans())
def test_cone_areas_match_shapely(seed, inside):
    rng = np.random.default_rng(seed)
    # a non-convex polygon with a hole, possibly in several parts
    poly = MultiPoint(rng.uniform(-1, 1, (6, 2))).buffer(0.3).difference(Point(0, 0).buffer(0.2))
    apex = rng.uniform(-0.5, 0.5, (5, 2)) if inside else rng.uniform(-3, 3, (5, 2))
    t0 = rng.uniform(-np.pi, np.pi, 5)
    t1 = t0 + rng.uniform(0.01, 2 * np.pi - 0.01, 5)
    cam, apx, s0, s1 = split_wide(np.arange(5), apex, t0, t1)
    got = np.bincount(cam, weights=cone_areas(*ring_edges(poly), apx, s0, s1))
    wedges = wedge_polygons(apex, t0, t1, 20.0)
    want = [poly.intersection(w).area for w in wedges]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)


def test_half_plane_cone_and_empty_polygon():
    a, b = ring_edges(box(-1, -1, 1, 1))
    area = cone_areas(a, b, np.array([[0.0, -1.0]]), np.array([0.0]), np.array([np.pi]))
    assert abs(area[0] - 4.0) < 1e-12
    e = ring_edges(box(0, 0, 1, 1).difference(box(-1, -1, 2, 2)))
    assert cone_areas(*e, np.zeros((1, 2)), np.zeros(1), np.ones(1)).tolist() == [0.0]
