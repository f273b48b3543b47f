"""Properties of the random-waypoint walking model (scene/motion.py)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely import affinity
from shapely.geometry import MultiPolygon, Point, Polygon, box

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


def test_circle_polygon_is_a_counter_clockwise_circle_about_its_centre():
    c = circle_polygon(0.5, 12, center=(2.0, -1.0))
    xy = np.asarray(c.exterior.coords)[:-1]
    np.testing.assert_allclose(np.hypot(xy[:, 0] - 2.0, xy[:, 1] + 1.0), 0.5)
    np.testing.assert_allclose(xy[0], [2.5, -1.0])                 # the first vertex at angle 0
    assert c.exterior.is_ccw
    np.testing.assert_allclose([c.centroid.x, c.centroid.y], [2.0, -1.0], atol=1e-12)


@pytest.mark.parametrize("radii", [[0.1, 0.0], [0.1, np.nan], [np.inf], [[0.1, 0.1]]])
def test_radii_must_be_finite_and_positive(radii):
    with pytest.raises(ValueError, match="radii: expected"):
        random_drop(CIRCLE, radii, np.random.default_rng(0))
    with pytest.raises(ValueError, match="radii: expected"):
        random_waypoint(CIRCLE, radii, 5, 0.1, 1.0, np.random.default_rng(0))


@pytest.mark.parametrize("room", [Polygon(), Polygon([(0, 0), (1, 1), (1, 0), (0, 1)]), CIRCLE.exterior,
                                  MultiPolygon([box(0, 0, 1, 1), box(2, 0, 3, 1)])])
def test_the_room_must_be_one_valid_polygon(room):
    """Empty, self-crossing (a bow tie), a ring or two rooms are refused before any drawing."""
    with pytest.raises(ValueError, match="room: expected a valid, non-empty shapely Polygon"):
        random_drop(room, [0.1], np.random.default_rng(0))


def _walk_past_standing(monkeypatch, initial, goal, n_steps):
    """Person 1 (0.1 m, 1 m/s, 0.1 s steps) walks from initial[0] to ``goal``; the others stand still."""
    from scene import motion

    dests = iter([np.asarray(goal, float)])
    standing = {i: np.asarray(p, float) for i, p in enumerate(initial[1:], 1)}
    calls = {"n": 0}

    def sample(region, rng, tries):          # first the walker's goal, then the standing people's places
        calls["n"] += 1
        return next(dests, None) if calls["n"] == 1 else standing[(calls["n"] - 2) % len(standing) + 1]

    monkeypatch.setattr(motion, "_sample_in", sample)
    m = len(initial)
    return random_waypoint(CIRCLE, [0.1] * m, n_steps, 0.1, [1.0] + [0.0] * (m - 1), np.random.default_rng(0),
                           initial=np.asarray(initial, float))


def test_a_walker_keeps_its_line_until_within_two_steps_of_touching_then_turns_right(monkeypatch):
    """Gaps 0.55, 0.45, 0.35, 0.25 m to the person standing in the way: straight on; at
    0.15 m (under 2 steps of 0.1 m) the next step is the tangent, turned clockwise."""
    pos = _walk_past_standing(monkeypatch, [[-0.75, 0.0], [0.0, 0.0]], [0.75, 0.0], 7)
    np.testing.assert_allclose(pos[:5, 0], np.column_stack([-0.75 + 0.1 * np.arange(5), np.zeros(5)]), atol=1e-12)
    np.testing.assert_allclose(pos[5, 0], [-0.35, -0.1], atol=1e-12)
    np.testing.assert_array_equal(pos[:, 1], 0.0)


def test_a_walker_steps_around_the_nearest_of_two_people_in_its_way(monkeypatch):
    """Both are within two steps of touching it and ahead; it turns clockwise from the direction
    towards the nearer one (gap 0.116 m against 0.19 m)."""
    a, near, far = np.array([-0.5, 0.0]), np.array([-0.2, 0.1]), np.array([-0.2, -0.25])
    pos = _walk_past_standing(monkeypatch, [a, near, far], [0.8, 0.0], 2)
    u = (near - a) / np.linalg.norm(near - a)
    np.testing.assert_allclose(pos[1, 0], a + 0.1 * np.array([u[1], -u[0]]), atol=1e-12)


def test_the_first_position_is_the_initial_one_and_progress_counts_steps():
    initial = np.array([[0.0, 0.0], [0.5, 0.0]])
    ticks = []
    pos = random_waypoint(CIRCLE, [0.1, 0.1], 6, 0.1, 1.0, np.random.default_rng(0), initial=initial,
                          progress=ticks.append)
    np.testing.assert_array_equal(pos[0], initial)
    assert ticks == [1] * 5
    one = random_waypoint(CIRCLE, [0.1, 0.1], 1, 0.1, 1.0, np.random.default_rng(0), initial=initial)
    np.testing.assert_array_equal(one, initial[None])
    still = random_waypoint(CIRCLE, [0.1, 0.1], 4, 0.1, 0.0, np.random.default_rng(0), initial=initial)
    np.testing.assert_array_equal(still, np.broadcast_to(initial, (4, 2, 2)))


@pytest.mark.parametrize("kwargs, match", [
    ({"n_steps": 0}, "n_steps: expected an integer >= 1, got 0"),
    ({"speed": -0.1}, "speed: expected finite numbers >= 0"),
    ({"speed": [1.0, np.nan]}, "speed: expected finite numbers >= 0"),
    ({"initial": [[0.0, 0.0]]}, r"initial: expected finite numbers of shape \(2, 2\)"),
    ({"initial": [[0.0, 0.0], [0.5, np.nan]]}, r"initial: expected finite numbers of shape \(2, 2\)"),
])
def test_bad_walk_arguments(kwargs, match):
    args = {"n_steps": 5, "speed": 1.0, "initial": None} | kwargs
    with pytest.raises(ValueError, match=match):
        random_waypoint(CIRCLE, [0.1, 0.1], args["n_steps"], 0.1, args["speed"], np.random.default_rng(0),
                        initial=args["initial"])


def test_max_tries_must_be_at_least_one():
    assert random_drop(CIRCLE, [0.1], np.random.default_rng(0), max_tries=1).shape == (1, 2)
    with pytest.raises(ValueError, match="max_tries: expected an integer >= 1, got 0"):
        random_drop(CIRCLE, [0.1], np.random.default_rng(0), max_tries=0)


@pytest.mark.parametrize("patience", [3, 20])
def test_a_boxed_in_walker_picks_a_new_destination_after_patience_blocked_steps(monkeypatch, patience):
    """Four people stand 0.01 m from it on all sides: its steps are cut to nothing, and every
    ``patience`` steps it gives up its destination and draws a new one (the standing people,
    at speed 0, never count as blocked nor draw one)."""
    from scene import motion

    steps, drawn = [], []
    monkeypatch.setattr(motion, "_sample_in", lambda region, rng, tries: (drawn.append(len(steps)),
                                                                           np.array([0.8, 0.0]))[1])
    ring = 0.21 * np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    initial = np.vstack([[0.0, 0.0], ring])
    pos = random_waypoint(CIRCLE, [0.1] * 5, 2 * patience + 2, 0.1, [1.0, 0, 0, 0, 0], np.random.default_rng(0),
                          initial=initial, patience=patience, progress=steps.append)
    assert drawn == [0] * 5 + [patience - 1, 2 * patience - 1]     # the walker's draws, in steps patience, 2 patience
    np.testing.assert_array_equal(pos[:, 1:], np.broadcast_to(ring, (len(pos), 4, 2)))
    assert np.abs(pos[:, 0]).max() < 0.01


def test_a_free_walker_keeps_its_destination_until_it_arrives(monkeypatch):
    """Alone, with patience 3, it walks 1.5 m in 12 steps of 0.125 m and draws its next
    destination only on arriving (walking is never being blocked)."""
    from scene import motion

    steps, drawn = [], []
    goals = iter([np.array([0.75, 0.0]), np.array([0.75, 0.5])])
    monkeypatch.setattr(motion, "_sample_in", lambda region, rng, tries: (drawn.append(len(steps)), next(goals))[1])
    pos = random_waypoint(CIRCLE, [0.1], 14, 0.125, 1.0, np.random.default_rng(0), initial=[[-0.75, 0.0]],
                          patience=3, progress=steps.append)
    assert drawn == [0, 11]                                        # at the start, then in step 12
    np.testing.assert_array_equal(pos[:13, 0], np.column_stack([-0.75 + 0.125 * np.arange(13), np.zeros(13)]))
    np.testing.assert_array_equal(pos[13, 0], [0.75, 0.125])


#: A corridor 10 m long at 45 degrees, 1e-5 m wider than a disc of 0.1 m: where a centre may
#: be is a sliver of 1e-4 m^2 in a bounding box of 49 m^2, which rejection sampling misses.
SLIVER = affinity.rotate(box(0.0, 0.0, 10.0, 0.2 + 1e-5), 45, origin=(0, 0))


def test_random_drop_refuses_a_disc_wider_than_the_room_though_its_area_fits():
    with pytest.raises(ValueError, match=r"^radii: a disc of radius 0.2 does not fit in the room$"):
        random_drop(box(0.0, 0.0, 10.0, 0.3), [0.1, 0.2], np.random.default_rng(0))


def test_random_drop_says_when_it_cannot_draw_a_place_for_a_disc():
    with pytest.raises(ValueError, match=r"^radii: could not place a disc of radius 0.1 in the room$"):
        random_drop(SLIVER, [0.1], np.random.default_rng(0))


class _Counting:
    """A generator that counts the points drawn through ``uniform``."""

    def __init__(self, seed):
        self.rng, self.points = np.random.default_rng(seed), 0

    def uniform(self, low, high, size):
        self.points += size[0]
        return self.rng.uniform(low, high, size)


@pytest.mark.parametrize("tries, points", [(1, 64), (64, 64), (127, 64), (128, 128), (4096, 4096)])
def test_sampling_gives_up_after_its_tries_in_batches_of_64_at_least_one(tries, points):
    from scene.motion import _inner_regions, _sample_in

    inner = _inner_regions(SLIVER, np.array([0.1]))[0]
    rng = _Counting(0)
    assert _sample_in(inner, rng, tries) is None and rng.points == points


def test_sampling_returns_the_first_point_drawn_inside_the_region():
    from scene.motion import _sample_in

    region = box(0.0, 0.0, 0.5, 1.0).union(box(0.5, 0.0, 2.0, 0.01))   # bounding box 2 x 1, a quarter inside
    pts = np.random.default_rng(4).uniform((0.0, 0.0), (2.0, 1.0), size=(64, 2))
    inside = np.flatnonzero((pts[:, 0] <= 0.5) | (pts[:, 1] <= 0.01))
    assert inside[0] > 0                                               # not the first point drawn
    np.testing.assert_array_equal(_sample_in(region, np.random.default_rng(4), 64), pts[inside[0]])


def test_a_walk_with_no_destination_to_draw_is_refused_in_one_line():
    """A walk placed in a room where no destination could be drawn failed with
    'TypeError: unsupported operand type(s) for -: 'NoneType' and 'float''."""
    from scene.motion import _inner_regions

    start = np.array(_inner_regions(SLIVER, np.array([0.1]))[0].centroid.coords)
    with pytest.raises(ValueError, match=r"^radii: could not draw a destination for person 1 \(radius 0.1\) "
                                         r"in the room$"):
        random_waypoint(SLIVER, [0.1], 3, 0.1, 1.0, np.random.default_rng(0), initial=start)


def test_a_walk_of_nobody_is_an_empty_walk():
    """No disc failed with 'operands could not be broadcast together with shapes (0,) (0,2)'
    (its destinations were an array of shape (0,)); random_drop gives (0, 2)."""
    assert random_drop(CIRCLE, [], np.random.default_rng(0)).shape == (0, 2)
    assert random_waypoint(CIRCLE, [], 3, 0.1, 1.0, np.random.default_rng(0)).shape == (3, 0, 2)


def test_without_initial_positions_the_walk_starts_where_random_drop_puts_the_discs():
    for seed in (42, 43):
        walked = random_waypoint(CIRCLE, [0.1] * 5, 2, 0.1, 0.5, np.random.default_rng(seed))
        np.testing.assert_array_equal(walked[0], random_drop(CIRCLE, [0.1] * 5, np.random.default_rng(seed)))


def test_a_walker_whose_destination_is_short_of_a_person_walks_straight_to_it(monkeypatch):
    """Within two steps of touching the person standing at the origin, but its destination
    (-0.2, 0), touching them, is not beyond them: no turn."""
    pos = _walk_past_standing(monkeypatch, [[-0.75, 0.0], [0.0, 0.0]], [-0.2, 0.0], 7)
    expected = np.column_stack([[-0.75, -0.65, -0.55, -0.45, -0.35, -0.25, -0.2], np.zeros(7)])
    np.testing.assert_allclose(pos[:, 0], expected, atol=1e-12)


def test_steps_are_halved_down_to_a_sixteenth_and_a_sixteenth_is_standing_still(monkeypatch):
    """A destination 0.2 m ahead, 0.13 m from a person standing beside it: a full step, then
    a quarter (0.025 m), then a sixteenth (0.0047 m, under a tenth of a step: blocked), then
    nothing (blocked); with patience 2 a new destination is drawn in step 4, not before."""
    from scene import motion

    steps, drawn = [], []
    goals = iter([np.array([0.2, 0.0]), np.array([-0.5, 0.0]), np.array([0.0, 0.5])])   # the stander's is never reached
    monkeypatch.setattr(motion, "_sample_in", lambda region, rng, tries: (drawn.append(len(steps)), next(goals))[1])
    pos = random_waypoint(CIRCLE, [0.1, 0.1], 5, 0.1, [1.0, 0.0], np.random.default_rng(0),
                          initial=[[0.0, 0.0], [0.33, 0.0]], patience=2, progress=steps.append)
    # each valid position: the first fraction of the step that keeps 0.2 m from the person at 0.33
    np.testing.assert_allclose(pos[:4, 0, 0], [0.0, 0.1, 0.1 + 0.1 / 4, 0.125 + 0.075 / 16], atol=1e-12)
    np.testing.assert_allclose(pos[:, 0, 1], 0.0, atol=1e-12)
    assert drawn == [0, 0, 3]                       # walker and stander at the start, then the walker in step 4


def test_a_walker_within_a_step_of_a_destination_beyond_someone_steps_around_them(monkeypatch):
    """A destination 0.08 m ahead, under a big person (radius 0.3) 0.01 m from the small
    walker (radius 0.05): it walks the tangent, turned clockwise, not towards the destination."""
    from scene import motion

    goals = iter([np.array([0.08, 0.0]), np.array([0.0, 0.5])])      # the stander's is never reached
    monkeypatch.setattr(motion, "_sample_in", lambda region, rng, tries: next(goals))
    pos = random_waypoint(CIRCLE, [0.05, 0.3], 2, 0.1, [1.0, 0.0], np.random.default_rng(0),
                          initial=[[0.0, 0.0], [0.36, 0.0]])
    np.testing.assert_allclose(pos[1, 0], [0.0, -0.1], atol=1e-12)


def test_an_eighth_of_a_step_is_still_walking_a_sixteenth_is_not(monkeypatch):
    """Blocked means moving less than a tenth of a step: beside a person at 0.32 m the walker
    makes a full step, an eighth (0.0125 m: walking), then a sixteenth (0.0055 m: blocked),
    and with patience 1 draws a new destination in step 3."""
    from scene import motion

    steps, drawn = [], []
    goals = iter([np.array([0.2, 0.0]), np.array([-0.5, 0.0]), np.array([0.0, 0.5])])
    monkeypatch.setattr(motion, "_sample_in", lambda region, rng, tries: (drawn.append(len(steps)), next(goals))[1])
    pos = random_waypoint(CIRCLE, [0.1, 0.1], 4, 0.1, [1.0, 0.0], np.random.default_rng(0),
                          initial=[[0.0, 0.0], [0.32, 0.0]], patience=1, progress=steps.append)
    np.testing.assert_allclose(pos[:4, 0, 0], [0.0, 0.1, 0.1125, 0.1125 + 0.0875 / 16], atol=1e-12)
    assert drawn == [0, 0, 2]


def test_arriving_clears_the_steps_a_walker_was_blocked(monkeypatch):
    """A walker touching a person who walks off ahead of it is blocked in step 1 and arrives
    in step 2; its next destination is under a person standing beside it: blocked in steps 3
    and 4. With patience 2 it draws a new one in step 4: the block before its arrival does
    not count towards the ones after."""
    from scene import motion

    steps, drawn = [], []
    goals = iter([np.array([0.1, 0.0]), np.array([0.8, 0.0]), np.array([-0.5, 0.0]), np.array([0.1, -0.1])])
    monkeypatch.setattr(motion, "_sample_in",
                        lambda region, rng, tries: (drawn.append(len(steps)), next(goals, np.array([-0.5, 0.5])))[1])
    pos = random_waypoint(CIRCLE, [0.1] * 3, 5, 0.1, [1.0, 1.0, 0.0], np.random.default_rng(0),
                          initial=[[0.0, 0.0], [0.2, 0.0], [0.1, -0.2]], patience=2, progress=steps.append)
    np.testing.assert_allclose(pos[:, 0], [[0.0, 0.0], [0.0, 0.0], [0.1, 0.0], [0.1, 0.0], [0.1, 0.0]], atol=1e-12)
    np.testing.assert_allclose(pos[:, 1, 0], [0.2, 0.3, 0.4, 0.5, 0.6], atol=1e-12)
    assert drawn == [0, 0, 0, 1, 3]                # the three at the start; the walker in steps 2 and 4


@pytest.mark.parametrize("radius", [0.0, -1.0, np.nan])
def test_a_circle_needs_a_positive_radius(radius):
    with pytest.raises(ValueError, match=r"^radius: expected a finite number > 0, got "):
        circle_polygon(radius)


def test_random_drop_draws_1024_points_for_a_place_before_giving_up():
    rng = _Counting(0)
    with pytest.raises(ValueError, match=r"^radii: could not place a disc of radius 0.1 in the room$"):
        random_drop(SLIVER, [0.1], rng)
    assert rng.points == 64 * 16


def test_a_walk_draws_4096_points_for_a_destination_before_giving_up():
    from scene.motion import _inner_regions

    start = np.array(_inner_regions(SLIVER, np.array([0.1]))[0].centroid.coords)
    rng = _Counting(0)
    with pytest.raises(ValueError, match=r"^radii: could not draw a destination for person 1"):
        random_waypoint(SLIVER, [0.1], 3, 0.1, 1.0, rng, initial=start)
    assert rng.points == 4096


def test_random_drop_keeps_discs_that_just_touch(monkeypatch):
    """The second disc's centre 0.2 m from the first's, the sum of their radii: no overlap."""
    from scene import motion

    places = iter([np.array([0.0, 0.0]), np.array([0.2, 0.0])])
    monkeypatch.setattr(motion, "_sample_in", lambda region, rng, tries: next(places, None))
    np.testing.assert_array_equal(random_drop(CIRCLE, [0.1, 0.1], np.random.default_rng(0)), [[0.0, 0.0], [0.2, 0.0]])


def test_discs_as_large_as_the_room_pass_the_area_check():
    """One disc of area pi in a room of area pi: not refused for its area (only more than the
    room's is), but because it does not fit across the room's 1 m."""
    room = box(0.0, 0.0, np.pi, 1.0)
    assert np.pi * 1.0**2 == room.area
    with pytest.raises(ValueError, match=r"^radii: a disc of radius 1.0 does not fit in the room$"):
        random_drop(room, [1.0], np.random.default_rng(0))


def test_a_walker_passing_someone_right_beside_it_walks_straight_on(monkeypatch):
    """A person 0.25 m to its right (gap 0.05 m, under two steps) but exactly abeam, not ahead:
    it is not approaching them, so it keeps its line (steering would turn it back, (-1, 0))."""
    pos = _walk_past_standing(monkeypatch, [[0.0, 0.0], [0.0, -0.25]], [0.8, 0.0], 2)
    np.testing.assert_allclose(pos[1, 0], [0.1, 0.0], atol=1e-12)


def test_walking_clears_the_steps_a_walker_was_blocked(monkeypatch):
    """Walker (0.05 m steps) towards (0.1, 0): in step 1 a person at (0.1, 0.175), walking off
    up, lets it make only a sixteenth of its step (0.003 m: blocked); in step 2 a full step
    (walking); in steps 3 and 4 a person standing at (0.2532, 0) keeps it from its destination
    (blocked, blocked). With patience 2 it draws a new one in step 4, not in step 3: walking
    in step 2 cleared the block of step 1."""
    from scene import motion

    steps, drawn = [], []
    goals = iter([np.array([0.1, 0.0]), np.array([0.1, 0.8]), np.array([0.5, 0.0])])
    monkeypatch.setattr(motion, "_sample_in",
                        lambda region, rng, tries: (drawn.append(len(steps)), next(goals, np.array([-0.5, 0.5])))[1])
    pos = random_waypoint(CIRCLE, [0.1] * 3, 5, 0.1, [0.5, 1.0, 0.0], np.random.default_rng(0),
                          initial=[[0.0, 0.0], [0.1, 0.175], [0.2532, 0.0]], patience=2, progress=steps.append)
    np.testing.assert_allclose(pos[:, 0, 0], [0.0, 0.05 / 16, 0.05 / 16 + 0.05, 0.053125, 0.053125], atol=1e-12)
    np.testing.assert_allclose(pos[:, 0, 1], 0.0, atol=1e-12)
    assert drawn == [0, 0, 0, 3]                   # the three at the start; the walker in step 4


def test_a_walker_exactly_two_steps_from_touching_someone_turns(monkeypatch):
    """A gap of 0.2 m (0.4 - 0.1 - 0.1 rounds to 1 ulp over it) is two steps of 0.1 m: within
    them, so the first step is already the tangent, turned clockwise."""
    pos = _walk_past_standing(monkeypatch, [[-0.4, 0.0], [0.0, 0.0]], [0.75, 0.0], 2)
    np.testing.assert_allclose(pos[1, 0], [-0.4, -0.1], atol=1e-12)


def test_a_walker_stopped_a_millimetre_short_of_its_destination_has_not_arrived(monkeypatch):
    """Its destination 2 mm ahead is under a person standing at 0.2015 m: it gets half way
    (1 mm, under a tenth of a step: blocked) and keeps that destination: it draws no new one."""
    from scene import motion

    steps, drawn = [], []
    goals = iter([np.array([0.002, 0.0]), np.array([0.5, 0.5])])
    monkeypatch.setattr(motion, "_sample_in",
                        lambda region, rng, tries: (drawn.append(len(steps)), next(goals, np.array([-0.5, 0.0])))[1])
    pos = random_waypoint(CIRCLE, [0.1, 0.1], 2, 0.1, [1.0, 0.0], np.random.default_rng(0),
                          initial=[[0.0, 0.0], [0.2015, 0.0]], progress=steps.append)
    np.testing.assert_allclose(pos[1, 0], [0.001, 0.0], atol=1e-12)
    assert drawn == [0, 0]


def test_destinations_are_drawn_where_each_persons_centre_may_be(monkeypatch):
    """Radii 0.1 and 0.3 m in the 360-gon of circumradius 1: each destination comes from the
    room shrunk by that person's radius, a 360-gon of apothem cos(pi / 360) - r and area
    360 (cos(pi / 360) - r)^2 tan(pi / 360), at the start and after arriving."""
    from scene import motion

    areas = []
    goals = iter([np.array([-0.5, 0.5]), np.array([0.35, 0.0]), np.array([0.35, 0.05])])
    monkeypatch.setattr(motion, "_sample_in",
                        lambda region, rng, tries: (areas.append(region.area), next(goals, np.array([0.3, 0.0])))[1])
    random_waypoint(CIRCLE, [0.1, 0.3], 3, 0.1, [0.0, 1.0], np.random.default_rng(0),
                    initial=[[-0.5, 0.0], [0.3, 0.0]])
    want = [360 * (np.cos(np.pi / 360) - r) ** 2 * np.tan(np.pi / 360) for r in (0.1, 0.3, 0.3, 0.3)]
    np.testing.assert_allclose(areas, want, rtol=1e-9)


def test_the_region_of_a_centre_rounds_a_rooms_inner_corner():
    """An L of two 2 x 1 m arms shrunk by 0.1 m: arms 1.8 x 0.8 m overlapping in 0.8 x 0.8 m,
    and at the inner corner a 0.1 m square less a quarter disc of radius 0.1 m."""
    from scene.motion import _inner_regions

    room = box(0.0, 0.0, 2.0, 1.0).union(box(0.0, 0.0, 1.0, 2.0))
    want = 2 * 1.8 * 0.8 - 0.8 * 0.8 + 0.1**2 * (1 - np.pi / 4)
    assert abs(_inner_regions(room, np.array([0.1]))[0].area - want) < 1e-5


def test_a_boxed_in_walker_draws_its_new_destination_where_its_centre_may_be(monkeypatch):
    """Person 1 (radius 0.1 m) boxed in by four others, person 0 (radius 0.2 m) standing far
    off: after two blocked steps its new destination comes from the room shrunk by 0.1 m
    (the area of a 360-gon of apothem cos(pi / 360) - 0.1), not by person 0's 0.2 m."""
    from scene import motion

    areas = []
    monkeypatch.setattr(motion, "_sample_in",
                        lambda region, rng, tries: (areas.append(region.area), np.array([0.8, 0.0]))[1])
    ring = 0.21 * np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    random_waypoint(CIRCLE, [0.2] + [0.1] * 5, 3, 0.1, [0.0, 1.0, 0, 0, 0, 0], np.random.default_rng(0),
                    initial=np.vstack([[-0.6, 0.5], [0.0, 0.0], ring]), patience=2)
    area = [360 * (np.cos(np.pi / 360) - r) ** 2 * np.tan(np.pi / 360) for r in (0.2, 0.1)]
    np.testing.assert_allclose(areas, [area[0]] + [area[1]] * 6, rtol=1e-9)
