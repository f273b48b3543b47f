"""A camera mounted among the people: a person that covers the lens fills its image.

Camera 3 of the lab is lowered to 1 m and levelled (below the people's heads); camera 1
is moved into the room, 1 m high, and camera 7 too, 0.3 m high, looking steeply down. The people's back faces are culled for speed, so a
camera inside a person, or with the person's surface nearer than the near plane, used
to see the empty room through them, and the hull carved the person out.
"""

import numpy as np
import pytest

from scene import Scene, scene_path

pytestmark = pytest.mark.render

LOW = [3.905, 0.05, 1.0]                # camera 3, lowered and levelled
INSIDE = [2.0, 2.0, 1.0]                # camera 1, in the room
FEET = [4.5, 3.0, 0.3]                  # camera 7, in the room, near the floor


def _scene(count=1):
    text = scene_path("lab").read_text()
    text = text.replace("{number: 3, position: [3.905, 0.05, 2.2], yaw_deg: 101.0, pitch_deg: 15.0}",
                        f"{{number: 3, position: {LOW}, yaw_deg: 101.0, pitch_deg: 0.0}}")
    text = text.replace("{number: 1, position: [0.781, 0.05, 2.2], yaw_deg: 47.9, pitch_deg: 15.0}",
                        f"{{number: 1, position: {INSIDE}, yaw_deg: 30.0, pitch_deg: 10.0}}")
    text = text.replace("{number: 7, position: [6.656, 3.448, 2.2], yaw_deg: -170.5, pitch_deg: 15.0}",
                        f"{{number: 7, position: {FEET}, yaw_deg: 0.0, pitch_deg: 60.0}}")
    text = text.replace("  count: 3\n", f"  count: {count}\n")
    return Scene.from_text(text)


@pytest.fixture(scope="module")
def low():
    from render import Renderer

    scene = _scene()
    with Renderer(scene, cameras=[1, 3, 7]) as r:
        yield scene, r


def _ahead(scene, number, distance):
    """Floor point ``distance`` metres ahead of camera ``number`` along its yaw, (1, 2)."""
    cam = scene.cameras[number - 1]
    return (cam.center_world[:2] + distance * np.array([np.cos(cam.yaw), np.sin(cam.yaw)]))[None]


@pytest.mark.parametrize("number,xy", [(3, [3.905, 0.27]),   # the repro
                                       (7, FEET[:2])])        # looking down at the person's feet
def test_a_camera_inside_a_person_sees_only_that_person(low, number, xy):
    _, r = low
    labels = r.labels(np.array([xy]), cameras=[number])
    assert (labels == 1).all()


@pytest.mark.parametrize("gap", [0.01, 0.02, 0.03])
def test_a_person_nearer_than_the_near_plane_fills_the_image(low, gap):
    """1-3 cm in front of the lens the person covers the whole view (cut by the near plane before)."""
    scene, r = low
    f = r.render(_ahead(scene, 3, scene.people.radius + gap), cameras=[3], clean=True)
    assert (f.labels == 1).all()
    assert (f.rgb != r.background(cameras=[3]).rgb).any(axis=-1).mean() > 0.99   # and shows


@pytest.mark.parametrize("number", [1, 3])
@pytest.mark.parametrize("gap", [0.005, 0.02, 0.1])
def test_inside_a_person_near_its_surface_looking_out(low, number, gap):
    """The surface the camera looks out through is nearer than the near plane. For the
    level camera 3 and a gap under 5 cm every vertex of the person is nearer than it too:
    its canvas box is the whole canvas all the same (``_rects`` finds it close by itself)."""
    scene, r = low
    pos = _ahead(scene, number, gap - scene.people.radius)
    labels = r.labels(pos, cameras=[number])
    assert (labels == 1).all()
    k = r.numbers.index(number)
    assert r._rects(np.array([k]), pos).tolist() == [[[-np.inf, -np.inf, np.inf, np.inf]]]


def test_fast_path_equals_the_whole_scene_draw_for_a_camera_inside(low):
    """The production step draws people over the stored room; the reference draws everything."""
    scene, r = low
    for pos in (np.array([[3.905, 0.27]]), _ahead(scene, 3, 0.27), _ahead(scene, 1, -0.2),
                np.array([[2.5, 2.5]]),
                np.array([[FEET[0] + 0.1, FEET[1] - 0.3]])):   # across camera 7's near plane, not close
        f = r.render(pos, clean=True)
        near = r._close(np.arange(3), pos).any(axis=1)
        canvases = r.raster.draw(r.view_projs, pos, bands=np.arange(3), near=near).copy()
        rgb, labels = r._distort(canvases, np.arange(3))
        assert np.array_equal(f.labels, labels) and np.array_equal(f.rgb, rgb)
        assert np.array_equal(r._work, r._canvas)


def test_the_hull_keeps_a_person_covering_a_low_camera():
    """`camtask run` on the repro: hull 0 and no estimate before."""
    import shapely

    from testbed.loop import LiveSource, LoopConfig, run_loop

    scene = _scene()
    truth = np.array([[[3.905, 0.27]]] * 2)
    source = LiveSource(scene, None, np.random.default_rng(0))
    try:
        results = list(run_loop(scene, LoopConfig("uniform", 6), truth, source))
    finally:
        source.close()
    assert 3 in results[0].tasked
    person = shapely.Point(3.905, 0.27).buffer(scene.people.radius)
    for res in results:
        assert res.hull_area > 0
        assert person.difference(shapely.union_all(res.polygons)).area < 0.05 * person.area


def test_a_surface_through_a_lens_stays_in_that_cameras_image():
    """A person's surface exactly through camera 3's lens (axis-aligned camera, prism corner
    ahead): drawn with depth clamping, its fragments once landed in the next camera's band,
    and camera 4 showed 41,647 pixels of a person it cannot see."""
    from render import Renderer

    text = scene_path("lab").read_text()
    text = text.replace("{number: 3, position: [3.905, 0.05, 2.2], yaw_deg: 101.0, pitch_deg: 15.0}",
                        "{number: 3, position: [3.905, 0.05, 1.0], yaw_deg: 90.0, pitch_deg: 0.0}")
    text = text.replace("{number: 4, position: [5.467, 0.05, 2.2], yaw_deg: 126.6, pitch_deg: 15.0}",
                        "{number: 4, position: [5.0, 0.05, 1.5], yaw_deg: 90.0, pitch_deg: 0.0}")
    text = text.replace("  count: 3\n", "  count: 2\n").replace("height: 1.75 ", "height: 2.18 ")
    scene = Scene.from_text(text)
    assert scene.cameras[3].center_world[2] == 1.5 and scene.people.height == 2.18
    people = np.array([[3.905, 0.30], [5.6, 0.30]])      # person 1 stands beside camera 4
    with Renderer(scene, cameras=[3, 4]) as r:
        both = r.render(people, clean=True).labels
        alone = r.render(people, cameras=[4], clean=True).labels
    np.testing.assert_array_equal(both[1], alone[0])
    assert not (both[1] == 1).any()                       # camera 4 cannot see person 0


def _near_plane_reach(r, k):
    """Distance from camera k's lens to the farthest corner of its near plane on the canvas, metres."""
    from render.renderer import ZNEAR

    cw, ch = r.canvas_size
    Kc = r.maps[r.map_index[k]].canvas_K(r.cameras[k].K)
    corners = np.array([[-0.5, -0.5, 1.0], [cw - 0.5, -0.5, 1.0], [-0.5, ch - 0.5, 1.0], [cw - 0.5, ch - 0.5, 1.0]])
    return max(np.linalg.norm(ZNEAR * np.linalg.solve(Kc, c)) for c in corners)


def test_close_means_the_cylinder_within_the_near_planes_reach_of_the_lens(low, lab, lab_renderer):
    scene, r = low
    reach = _near_plane_reach(r, 1)          # camera 3, 1 m high, below the heads; its canvas corner (-0.5, ch - 0.5)
    assert 0.055 < reach < 0.07
    lens = np.array(LOW[:2])
    away = np.array([np.cos(0.3), np.sin(0.3)])                  # any side: the cylinder is round
    for gap, close in [(0.9998 * reach, True), (1.0002 * reach, False), (-0.1, True)]:
        pos = (lens + (scene.people.radius + gap) * away)[None]
        assert r._close(np.array([1]), pos).tolist() == [[close]], gap
    assert r._close(np.arange(3), np.array([INSIDE[:2]])).tolist() == [[True], [False], [False]]
    assert r._close(np.arange(3), np.array([[np.nan, np.nan]])).tolist() == [[False]] * 3
    # a lab camera, 2.2 m high, right above a person 1.75 m tall: 45 cm over the head
    above = lab.cameras[0].center_world[:2][None]
    three = np.vstack([above, [[3.0, 3.0], [4.0, 4.0]]])
    assert not lab_renderer._close(np.arange(16), three).any()


def test_one_person_covering_the_lens_is_drawn_unclipped_beside_others():
    """The camera inside person 0 sees only person 0, also when person 1 stands elsewhere."""
    from render import Renderer

    with Renderer(_scene(count=2), cameras=[3]) as r:
        labels = r.labels(np.array([[3.905, 0.27], [2.0, 4.0]]))
    assert (labels == 1).all()


def _other_lenses(lab, **people):
    """The lab with camera 2's principal point moved and fy 15 % above fx, and camera 3's
    distortion stronger; ``people`` replaces fields of the people."""
    import dataclasses

    c = lab.cameras
    K = c[1].K.copy()
    K[1, 1] *= 1.15
    K[:2, 2] += [-150.0, 90.0]
    dist = np.array([-0.3, 0.12, 0.0, 0.0, 0.0])
    cameras = (c[0], dataclasses.replace(c[1], K=K), dataclasses.replace(c[2], dist=dist), *c[3:])
    return dataclasses.replace(lab, cameras=cameras, people=dataclasses.replace(lab.people, **people))


def test_close_takes_each_cameras_own_reach_and_the_distance_over_the_heads(lab):
    """Cameras of three lenses (their farthest near-plane corners differ, one with fy != fx),
    2.2 m high over people 2.17 m tall: close when the lens is within its own camera's reach
    of the cylinder, measured straight to its top rim (3 cm up, the rest sideways)."""
    from render import Renderer

    scene = _other_lenses(lab, height=2.17)
    with Renderer(scene, cameras=[1, 2, 3]) as r:
        reach = [_near_plane_reach(r, k) for k in range(3)]
        assert max(reach) - min(reach) > 0.005
        for k in range(3):
            cam = r.cameras[k]
            up = cam.center_world[2] - scene.people.height
            ahead = np.array([np.cos(cam.yaw), np.sin(cam.yaw)])
            for f, close in [(0.999, True), (1.001, False)]:
                side = np.sqrt((f * reach[k]) ** 2 - up**2)
                pos = (cam.center_world[:2] + (scene.people.radius + side) * ahead)[None]
                assert r._close(np.array([k]), pos).tolist() == [[close]], (k, f)
