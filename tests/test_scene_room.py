"""The room: its floor polygon, what lies inside it, and its validation."""

import dataclasses
import re

import numpy as np
import pytest

from scene import Room, load_scene


def test_the_circle_scenes_floor_is_the_studies_circle_room_vertex_for_vertex():
    """Scene runs and the studies share one room: a counter-clockwise regular 720-gon from
    (r, 0), each vertex once; a circle room's ceiling is 2.5 m when not given."""
    from testbed.studies.core import circle_room

    room = load_scene("circle").room
    np.testing.assert_array_equal(room.vertices, np.asarray(circle_room(1.0).exterior.coords)[:-1])
    assert room.kind == "circle" and room.height == 2.5
    assert Room.circle(3.0).height == 2.5
    step = np.diff(np.unwrap(np.arctan2(room.vertices[:, 1], room.vertices[:, 0])))
    np.testing.assert_allclose(step, 2 * np.pi / 720, rtol=1e-9)          # counter-clockwise, even
    assert room.area == pytest.approx(720 / 2 * np.sin(2 * np.pi / 720), rel=1e-12)


def test_a_disc_inside_is_inside_and_touching_or_outside_is_not():
    """contains_disc: 4 x 3 m room, disc of radius 0.5 m."""
    room = Room.rectangle(4.0, 3.0, 2.5)
    assert room.contains_disc([2.0, 1.5], 0.5)
    assert room.contains_disc([0.51, 1.5], 0.5)
    assert not room.contains_disc([0.5, 1.5], 0.5)          # touching the wall x = 0 counts as outside
    assert not room.contains_disc([3.5, 2.5], 0.5)          # touching two walls
    assert not room.contains_disc([10.0, 10.0], 0.5)        # far outside: far from every wall too
    assert not room.contains_disc([-0.6, 1.5], 0.5)         # outside, beyond the disc's reach of the wall


def test_a_room_is_frozen_and_its_vertices_checked():
    room = Room.rectangle(4.0, 3.0, 2.5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        room.height = 3.0
    with pytest.raises(ValueError, match="read-only"):
        room.vertices[0, 0] = 1.0
    with pytest.raises(ValueError, match=r"room.vertices: expected shape \(n, 2\), got \(4, 3\)"):
        Room(np.zeros((4, 3)), 2.5)
    with pytest.raises(ValueError, match="room.vertices: expected finite numbers"):
        Room(np.array([[0.0, 0.0], [1.0, np.nan], [0.0, 1.0]]), 2.5)


def test_a_foot_is_twelve_inches_of_two_and_a_half_centimetres():
    from scene import FOOT

    assert FOOT == pytest.approx(12 * 2.54 / 100, rel=1e-15)
    assert (22 * FOOT, 19 * FOOT) == (pytest.approx(6.7056), pytest.approx(5.7912))     # the lab, docs/conventions.md


def test_a_rectangle_is_counter_clockwise_from_the_origin_with_x_along_its_width():
    room = Room.rectangle(4.0, 3.0, 2.5)
    np.testing.assert_array_equal(room.vertices, [[0, 0], [4, 0], [4, 3], [0, 3]])
    assert room.kind == "rectangle" and room.area == 12.0
    x, y = room.vertices.T
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) == 12.0      # shoelace: positive, counter-clockwise


def test_a_room_from_its_vertices_is_not_a_circle_and_a_circle_room_is_read_only():
    assert Room(np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]]), 2.5).kind == "rectangle"
    circle = Room.circle(1.0, n_vertices=8)
    assert circle.kind == "circle" and circle.vertices.shape == (8, 2)
    with pytest.raises(ValueError, match="read-only"):
        circle.vertices[0, 0] = 2.0


@pytest.mark.parametrize("make, message", [
    (lambda: Room.rectangle(0.0, 3.0, 2.5), "room.width: expected a finite number > 0, got 0.0"),
    (lambda: Room.rectangle(4.0, -3.0, 2.5), "room.depth: expected a finite number > 0, got -3.0"),
    (lambda: Room.rectangle(4.0, 3.0, float("nan")), "room.height: expected a finite number > 0, got nan"),
    (lambda: Room.circle(-1.0), "room.radius: expected a finite number > 0, got -1.0"),
    (lambda: Room.circle(1.0, 0), "room.height: expected a finite number > 0, got 0"),
])
def test_a_room_of_no_size_is_refused_by_name(make, message):
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        make()


def test_a_point_on_the_wall_is_in_the_room_and_one_a_millimetre_beyond_is_not():
    room = Room.rectangle(4.0, 3.0, 2.5)
    for xy in ([0.0, 1.5], [4.0, 3.0], [2.0, 0.0], [2.0, 1.5]):
        assert room.contains_point(xy)
    for xy in ([-0.001, 1.5], [4.001, 3.0], [2.0, 3.001], [2.0, -0.001]):
        assert not room.contains_point(xy)


def test_a_room_is_hashable_compares_by_identity_and_builds_its_polygon_once():
    a, b = Room.rectangle(4.0, 3.0, 2.5), Room.rectangle(4.0, 3.0, 2.5)
    assert len({a, b}) == 2 and a != b             # equal arrays would make == ambiguous
    assert a.polygon is a.polygon
