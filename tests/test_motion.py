"""Properties of the random-waypoint walking model (scene/motion.py)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, box

from scene.motion import circle_polygon, random_drop, random_waypoint

CIRCLE = circle_polygon(1.0, 360)
LAB = box(0.0, 0.0, 6.7056, 5.7912)


def _check_valid(room, pos, radii):
    for frame in pos:
        for i, p in enumerate(frame):
            assert room.contains(Point(p))
            assert room.exterior.distance(Point(p)) >= radii[i] - 1e-7
        d = np.linalg.norm(frame[:, None] - frame[None], axis=2)
        need = radii[:, None] + radii[None, :]
        np.fill_diagonal(d, np.inf)
        assert np.all(d >= need - 1e-7)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 7))
def test_never_overlap_never_leave_circle(seed, m):
    radii = np.full(m, 0.1)
    pos = random_waypoint(CIRCLE, radii, 40, 0.1, 0.8, np.random.default_rng(seed))
    assert pos.shape == (40, m, 2)
    _check_valid(CIRCLE, pos, radii)
    steps = np.linalg.norm(np.diff(pos, axis=0), axis=2)
    assert np.all(steps <= 0.08 + 1e-12)


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_never_overlap_never_leave_lab_mixed_radii_and_speeds(seed):
    rng = np.random.default_rng(seed)
    radii = rng.uniform(0.2, 0.35, size=6)
    speed = rng.uniform(0.5, 1.5, size=6)
    pos = random_waypoint(LAB, radii, 40, 0.2, speed, rng)
    _check_valid(LAB, pos, radii)


def test_crowded_room_stays_valid():
    radii = np.full(10, 0.15)
    pos = random_waypoint(CIRCLE, radii, 60, 0.1, 1.0, np.random.default_rng(3))
    _check_valid(CIRCLE, pos, radii)


def test_deterministic():
    a = random_waypoint(CIRCLE, [0.1] * 5, 30, 0.1, 0.5, np.random.default_rng(42))
    b = random_waypoint(CIRCLE, [0.1] * 5, 30, 0.1, 0.5, np.random.default_rng(42))
    c = random_waypoint(CIRCLE, [0.1] * 5, 30, 0.1, 0.5, np.random.default_rng(43))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_people_move_and_reach_far():
    pos = random_waypoint(CIRCLE, [0.1] * 3, 300, 0.1, 0.5, np.random.default_rng(1))
    span = pos.max(axis=0) - pos.min(axis=0)
    assert np.all(span > 0.5)


def test_head_on_pair_turns_right(monkeypatch):
    # Two people walking straight at each other along the x axis each turn clockwise.
    from scene import motion

    initial = np.array([[-0.5, 0.0], [0.5, 0.0]])
    dests = iter([np.array([0.7, 0.0]), np.array([-0.7, 0.0])])
    monkeypatch.setattr(motion, "_sample_in", lambda region, rng, n: next(dests, np.zeros(2)))
    pos = random_waypoint(CIRCLE, [0.1, 0.1], 12, 0.1, 1.0, np.random.default_rng(0), initial=initial)
    _check_valid(CIRCLE, pos, np.array([0.1, 0.1]))
    # Person 1 heads +x: its right is -y. Person 2 heads -x: its right is +y.
    assert pos[:, 0, 1].min() < -0.05
    assert pos[:, 1, 1].max() > 0.05
    assert np.all(pos[:, 0, 1] <= 1e-12) and np.all(pos[:, 1, 1] >= -1e-12)
    # They got past each other.
    assert pos[-1, 0, 0] > pos[-1, 1, 0]


def test_random_drop_errors():
    with pytest.raises(ValueError, match="cannot fit"):
        random_drop(CIRCLE, [0.6] * 4, np.random.default_rng(0))
    with pytest.raises(ValueError, match="too crowded"):
        random_drop(CIRCLE, [0.3] * 8, np.random.default_rng(0), max_tries=50)
    with pytest.raises(ValueError, match="radii"):
        random_drop(CIRCLE, [0.1, -1.0], np.random.default_rng(0))


def test_random_drop_inside_and_disjoint():
    radii = np.full(10, 0.1)
    c = random_drop(CIRCLE, radii, np.random.default_rng(5))
    _check_valid(CIRCLE, c[None], radii)


def test_initial_validated():
    with pytest.raises(ValueError, match="initial"):
        random_waypoint(CIRCLE, [0.1, 0.1], 5, 0.1, 1.0, np.random.default_rng(0),
                        initial=[[0.0, 0.0], [0.05, 0.0]])


@settings(max_examples=20, deadline=None)
@given(theta=st.floats(0, 2 * np.pi), offset=st.floats(-0.05, 0.05))
def test_any_head_on_pair_turns_right(theta, offset):
    from unittest import mock

    from scene import motion

    u = np.array([np.cos(theta), np.sin(theta)])
    n = np.array([-u[1], u[0]])  # left of u
    initial = np.array([-0.45 * u, 0.45 * u + offset * n])
    goals = [0.7 * u, -0.7 * u + offset * n]
    dests = iter(goals)
    with mock.patch.object(motion, "_sample_in", lambda region, rng, k: next(dests, np.zeros(2))):
        pos = random_waypoint(CIRCLE, [0.1, 0.1], 10, 0.1, 1.0, np.random.default_rng(0),
                              initial=initial)
    _check_valid(CIRCLE, pos, np.array([0.1, 0.1]))
    # Each leaves its straight line only to its right (cross(heading, offset) < 0).
    for i, heading in ((0, u), (1, -u)):
        rel = pos[:, i] - pos[0, i]
        lateral = heading[0] * rel[:, 1] - heading[1] * rel[:, 0]
        assert np.all(lateral <= 1e-9)
        assert lateral.min() < -0.03
