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


# -- more cameras than one framebuffer holds ------------------------------------------


def _frames(r, positions, subset, noisy):
    """Background, clean frames, labels, clean frames of cameras ``subset`` and camera
    ``noisy``'s noisy frame, of camera numbers in ``r.numbers`` order (subset: its own)."""
    out = {"background": r.background().rgb, "clean": r.render(positions, clean=True),
           "labels": r.labels(positions)}
    if subset:
        out["subset"] = r.render(positions, cameras=subset, clean=True)
    if noisy in r.numbers:
        out["noisy"] = r.render(positions, cameras=[noisy], rng=np.random.default_rng(4)).rgb
    return out


@pytest.mark.parametrize("per_page,groups", [(3, [[1, 2, 3], [4, 5, 6], [7]]),   # pages of three
                                             (1, [[4], [9]])])                  # camera by camera
def test_cameras_beyond_one_framebuffer_go_on_pages(lab, lab_renderer, three_people, monkeypatch,
                                                    per_page, groups):
    """With the framebuffer limit lowered to ``per_page`` canvases, the cameras are drawn
    on several framebuffers, and each camera's frames equal those of a renderer of just
    its page's cameras, bit for bit (a page's band b is where such a renderer draws it)."""
    from render import Renderer
    from render.raster import Rasteriser

    numbers = [n for g in groups for n in g]
    subset, noisy = numbers[1::2], numbers[-1]
    parts = []
    for g in groups:
        with Renderer(lab, cameras=g) as r:
            assert len(r.raster.pages) == 1
            parts.append(_frames(r, three_people, None, noisy))
    monkeypatch.setattr(Rasteriser, "max_page_height", per_page * lab_renderer.canvas_size[1])
    with Renderer(lab, cameras=numbers) as r:
        assert [p.tiles for p in r.raster.pages] == [len(g) for g in groups]
        paged = _frames(r, three_people, subset, noisy)
        idx = np.arange(len(numbers))[::-1]             # the whole-scene draw, across pages
        canvases = r.raster.draw(r.view_projs[idx], three_people, bands=idx).copy()
        rgb, labels = r._distort(canvases, idx)

    def joined(name):
        return np.concatenate([p[name] for p in parts])
    assert np.array_equal(paged["background"], joined("background"))
    assert np.array_equal(paged["labels"], joined("labels"))
    clean_rgb = np.concatenate([p["clean"].rgb for p in parts])
    clean_labels = np.concatenate([p["clean"].labels for p in parts])
    assert np.array_equal(paged["clean"].rgb, clean_rgb)
    assert np.array_equal(paged["clean"].labels, clean_labels)
    sub = [numbers.index(n) for n in subset]
    assert np.array_equal(paged["subset"].rgb, clean_rgb[sub])
    assert np.array_equal(paged["subset"].labels, clean_labels[sub])
    assert np.array_equal(paged["noisy"], parts[-1]["noisy"])
    assert np.array_equal(rgb, clean_rgb[idx]) and np.array_equal(labels, clean_labels[idx])


def test_more_cameras_than_the_opengl_limit_holds():
    """Two cameras whose canvases together are taller than the real framebuffer limit
    (`camtask run` refused 32 lab cameras or 16 of 1920x1080: no option to split)."""
    from render import Renderer, gl

    _, GL = gl.context("egl")
    limit = min(int(GL.glGetIntegerv(GL.GL_MAX_RENDERBUFFER_SIZE)), int(GL.glGetIntegerv(GL.GL_MAX_TEXTURE_SIZE)))
    scene = Scene.from_text(f"""
room: {{shape: rectangle, width: 6.0, depth: 4.0, height: 3.0}}
cameras:
  intrinsics: {{resolution: [48, {limit // 2 + 16}], hfov_deg: 5.0, distortion: [0, 0, 0, 0, 0]}}
  poses:
    - {{number: 1, position: [0.05, 2.0, 1.5], yaw_deg: 0.0, pitch_deg: 0.0}}
    - {{number: 2, position: [5.95, 1.9, 1.5], yaw_deg: 180.0, pitch_deg: 0.0}}
people: {{count: 1, radius: 0.25}}
render: {{noise_std: 0.0, gain_jitter: 0.0}}
""")
    pos = np.array([[3.0, 2.0]])
    parts = []
    for n in (1, 2):
        with Renderer(scene, cameras=[n]) as r:
            parts.append(r.render(pos, clean=True))
    with Renderer(scene) as r:
        assert len(r.raster.pages) == 2
        f = r.render(pos, clean=True)
    assert (f.labels == 1).sum(axis=(1, 2)).min() > 1000
    assert np.array_equal(f.rgb, np.concatenate([p.rgb for p in parts]))
    assert np.array_equal(f.labels, np.concatenate([p.labels for p in parts]))


def test_camera_numbers_name_the_cameras_that_exist():
    from render.renderer import check_camera_numbers

    with pytest.raises(ValueError, match=r"^x: expected distinct camera numbers among 1\.\.16, got \[17\]$"):
        check_camera_numbers("x", [17], range(1, 17))
    with pytest.raises(ValueError, match=r"among 1, 5, 9, got \[2\]$"):       # a renderer for 1, 5 and 9
        check_camera_numbers("cameras", [2], (1, 5, 9))


def _one_camera_room(position, yaw_deg, count=1):
    return Scene.from_text(f"""
name: long_room
room: {{shape: rectangle, width: 40.0, depth: 4.0, height: 3.0}}
cameras:
  intrinsics: {{resolution: [160, 120], hfov_deg: 30.0, distortion: [0, 0, 0, 0, 0]}}
  poses:
    - {{number: 1, position: {list(position)}, yaw_deg: {yaw_deg}, pitch_deg: 0.0}}
people: {{count: {count}, radius: 0.5, height: 1.8}}
""")


@pytest.mark.parametrize("position, yaw, count, corner", [
    ([39.95, 0.5, 2.9], 180.0, 1, [-0.5, 4.5, 0.0]),      # the room widened by the people's radius
    ([0.05, 3.5, 0.1], 0.0, 1, [40.5, -0.5, 3.0]),        # the other way round, up to the ceiling
    ([39.95, 0.5, 2.9], 180.0, 0, [0.0, 4.0, 0.0]),       # nobody: the room's own corner
])
def test_far_plane_is_twice_the_distance_to_the_farthest_corner_by_hand(position, yaw, count, corner):
    from render.renderer import far_plane

    expected = 2.0 * np.linalg.norm(np.subtract(corner, position))
    assert expected > 50.0
    assert far_plane(_one_camera_room(position, yaw, count)) == pytest.approx(expected, rel=1e-12)


def test_camera_numbers_are_checked_and_returned_as_ints():
    from render.renderer import check_camera_numbers

    assert check_camera_numbers("cameras", None, (1, 5, 9)) == (1, 5, 9)
    got = check_camera_numbers("cameras", np.array([9, 1]), (1, 5, 9))
    assert got == (9, 1) and all(type(n) is int for n in got)
    assert check_camera_numbers("cameras", [5.0], (1, 5, 9)) == (5,)
    with pytest.raises(ValueError, match=r"^cameras: expected distinct camera numbers among 1, 5, 9, got \[5, 5\]$"):
        check_camera_numbers("cameras", [5, 5], (1, 5, 9))
    with pytest.raises(ValueError, match=r"^cameras: expected distinct camera numbers among 1\.\.3, got \[\]$"):
        check_camera_numbers("cameras", [], range(1, 4))
    with pytest.raises(ValueError, match=r"^cameras: expected camera numbers, got 'x'$"):
        check_camera_numbers("cameras", "x", range(1, 4))
    with pytest.raises(ValueError, match=r"^cameras: expected camera numbers, got 3$"):
        check_camera_numbers("cameras", 3, range(1, 4))


@pytest.mark.parametrize("numbers, shown", [([2.5], r"\[2\.5\]"), ([True], r"\[True\]"), (["3"], r"\['3'\]"),
                                            ([1, np.float64(1.5)], r"1\.5"), ([np.inf], r"\[inf\]"),
                                            ([np.nan], r"\[nan\]")])
def test_camera_numbers_that_are_not_whole_numbers_are_refused(numbers, shown):
    """Camera 2.5, True or "3" used to become camera 2, 1 or 3 without a word."""
    from render.renderer import check_camera_numbers

    with pytest.raises(ValueError, match=rf"^cameras: expected camera numbers, got .*{shown}"):
        check_camera_numbers("cameras", numbers, range(1, 17))
