"""The circle scene's ring cameras: a field of view the tasking geometry can honour."""

import numpy as np
import pytest
import shapely

from scene import Scene
from scene.config import scene_path
from tasking.cones import MIN_GAP
from tasking.hull import free_wedges_from_discs

CIRCLE = scene_path("circle").read_text()


def ring(fov_deg: str) -> Scene:
    assert "fov_deg: 180" in CIRCLE
    return Scene.from_text(CIRCLE.replace("fov_deg: 180", f"fov_deg: {fov_deg}"), "s.yaml")


@pytest.mark.parametrize("value, shown", [
    ("1e-300", "1e-300"),            # every camera saw nothing, silently
    ("1e-9", "1e-09"),               # below tasking.cones.MIN_GAP: the same
    ("9e-7", "9e-07"),
    ("0", "0"),
    ("1" + "0" * 400, "1e+400"),     # a 400-digit integer prints short
    ("-" + "9" * 400, "-1e+400"),
])
def test_a_ring_narrower_than_the_geometry_sees_is_refused_in_one_line(value, shown):
    with pytest.raises(ValueError) as info:
        ring(value)
    message = str(info.value)
    assert message == f"cameras.ring.fov_deg: expected a field of view in [1e-06, 180] degrees, got {shown}"


@pytest.mark.parametrize("fov_deg", ["1e-6", "0.5", "180"])
def test_every_ring_camera_at_the_bounds_proves_its_view_empty(fov_deg):
    scene = ring(fov_deg)
    xy, yaw, fov = scene.floor_poses()
    np.testing.assert_allclose(fov, np.radians(float(fov_deg)))
    room = scene.room.polygon
    wedges = free_wedges_from_discs(xy, yaw, fov, np.zeros((0, 2)), 0.1, room)
    inside = np.array([shapely.intersection(w, room).area for w in wedges])
    # a camera on the wall looking at the centre: a thin wedge through the room is
    # half its angle times the 2 m chord squared
    expect = 2 * fov if float(fov_deg) < 1 else inside
    np.testing.assert_allclose(inside, expect, rtol=1e-4)
    assert np.all(inside > 0)


def test_the_narrowest_ring_sees_well_above_the_dropped_intervals():
    from scene.camera import FLOOR_FOV_RANGE

    assert np.radians(FLOOR_FOV_RANGE[0]) > 100 * MIN_GAP


def test_a_floor_camera_made_in_python_is_held_to_the_same_range():
    """Only scene files were: FloorCamera(fov=1e-12) saw nothing, silently."""
    import pytest

    from scene.camera import FloorCamera

    FloorCamera(1, [1.0, 0.0], np.pi, np.radians(1e-6))
    FloorCamera(1, [1.0, 0.0], np.pi, np.pi)
    for fov in (1e-12, np.radians(1e-7), np.pi + 1e-6):
        with pytest.raises(ValueError, match=r"^camera.fov: expected a field of view in \[1e-06, 180\] degrees"):
            FloorCamera(1, [1.0, 0.0], np.pi, fov)
