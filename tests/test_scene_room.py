"""The room: its floor polygon, what lies inside it, and its validation."""

import dataclasses

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
