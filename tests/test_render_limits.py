"""Scenes beyond the lab's size: far rooms, other units."""

import numpy as np
import pytest

from scene import Scene

pytestmark = pytest.mark.render

CORRIDOR = """
name: corridor
room: {shape: rectangle, width: 80.0, depth: 4.0, height: 3.0}
cameras:
  intrinsics: {resolution: [160, 120], hfov_deg: 10.0, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 1, position: [0.05, 1.5, 2.2], yaw_deg: 0.0, pitch_deg: 1.0}
    - {number: 2, position: [0.05, 2.5, 2.2], yaw_deg: 0.0, pitch_deg: 1.0}
people: {count: 1, radius: 0.25, height: 1.75}
render: {noise_std: 0.0, gain_jitter: 0.0}
"""

CENTIMETRES = """
name: box_cm
room: {shape: rectangle, width: 90.0, depth: 60.0, height: 60.0}
cameras:
  intrinsics: {resolution: [160, 120], hfov_deg: 60.0, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 1, position: [1.0, 30.0, 50.0], yaw_deg: 0.0, pitch_deg: 20.0}
people: {count: 1, radius: 5.0, height: 35.0}
render: {noise_std: 0.0, gain_jitter: 0.0}
"""


def test_far_plane_reaches_the_far_corner_of_the_room(lab):
    from render.renderer import ZFAR_MIN, far_plane

    assert far_plane(lab) == ZFAR_MIN                    # the lab keeps its depth values
    assert far_plane(Scene.from_text(CORRIDOR)) > 2 * 80.0
    assert far_plane(Scene.from_text(CENTIMETRES)) > 2 * 90.0


def test_a_person_60_m_away_is_drawn():
    """An 80 m corridor: the person at 60 m was beyond a constant 50 m far plane."""
    from pipeline.nearfield import sight_range
    from render import Renderer

    corridor = Scene.from_text(CORRIDOR)
    _, far = sight_range(corridor.cameras, corridor.people.height)
    assert (far > 60.0).all()                              # the hull trusts them out there
    with Renderer(corridor) as r:
        labels = r.labels(np.array([[60.0, 2.0]]))
    # 1.75 m x 0.5 m at 60 m with f = 914 px: ~27 x 8 px
    assert (labels == 1).sum(axis=(1, 2)).min() > 150


def test_a_scene_in_centimetres_is_drawn():
    """A 90 x 60 x 60 cm box seen from 50 cm up: beyond a constant far plane of 50 (metres,
    but here centimetres) the whole image was black, and the person missing."""
    from render import Renderer

    with Renderer(Scene.from_text(CENTIMETRES)) as r:
        assert r.background().rgb.any(axis=-1).all()       # every pixel sees the room
        assert (r.labels(np.array([[80.0, 30.0]])) == 1).sum() > 500
