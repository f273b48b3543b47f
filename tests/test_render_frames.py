"""Rendered frames: labels agree with cv2.projectPoints silhouettes, seeded noise, backgrounds."""

import cv2
import numpy as np
import pytest

from testbed.dataset import read_calibration, write_calibration

pytestmark = pytest.mark.render


def _cylinder_points(xy, radius, height, n_around=180, n_up=60):
    a = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    z = np.linspace(0, height, n_up)
    A, Z = np.meshgrid(a, z)
    side = np.column_stack([xy[0] + radius * np.cos(A.ravel()), xy[1] + radius * np.sin(A.ravel()), Z.ravel()])
    r = np.linspace(0, radius, 20)
    Rr, Aa = np.meshgrid(r, a)
    top = np.column_stack([xy[0] + Rr.ravel() * np.cos(Aa.ravel()), xy[1] + Rr.ravel() * np.sin(Aa.ravel()),
                           np.full(Rr.size, height)])
    return np.concatenate([side, top])


@pytest.mark.parametrize("number,xy", [(1, (2.5, 2.5)), (6, (3.5, 2.0)), (11, (3.0, 2.5)), (15, (2.0, 3.5))])
def test_label_mask_matches_projected_silhouette(lab, lab_renderer, tmp_path, number, xy):
    cam = lab.cameras[number - 1]
    write_calibration(tmp_path / "cam.yaml", cam)
    calib = read_calibration(tmp_path / "cam.yaml")
    positions = np.full((lab.people.count, 2), np.nan)
    positions[1] = xy                                     # person 1 alone in the room
    frames = lab_renderer.render(positions, cameras=[number], clean=True)
    mask = frames.labels[0] == 2
    assert set(np.unique(frames.labels[0])) <= {0, 2}
    pts = _cylinder_points(np.array(xy), lab.people.radius, lab.people.height)
    uv, _ = cv2.projectPoints(pts, calib["rvec"], calib["tvec"], calib["K"], calib["dist"])
    expected = np.zeros_like(mask, np.uint8)
    cv2.fillConvexPoly(expected, np.round(cv2.convexHull(uv.astype(np.float32))[:, 0]).astype(np.int32), 1)
    expected = expected.astype(bool)
    iou = (mask & expected).sum() / (mask | expected).sum()
    assert mask.sum() > 2000
    assert iou > 0.95, iou


def test_same_seed_same_frames_different_seed_different_noise(lab, lab_renderer, three_people):
    a = lab_renderer.render(three_people, cameras=[3, 9], rng=np.random.default_rng(5))
    b = lab_renderer.render(three_people, cameras=[3, 9], rng=np.random.default_rng(5))
    c = lab_renderer.render(three_people, cameras=[3, 9], rng=np.random.default_rng(6))
    clean = lab_renderer.render(three_people, cameras=[3, 9], clean=True)
    assert np.array_equal(a.rgb, b.rgb) and np.array_equal(a.labels, b.labels)
    assert not np.array_equal(a.rgb, c.rgb)
    assert np.array_equal(a.labels, c.labels)             # labels are exact, never noisy
    noise = a.rgb.astype(float) - clean.rgb
    assert 1.0 < noise.std() < 6.0                          # noise_std 2 plus a 2 % gain


def test_frames_are_shaded_not_flat(lab, lab_renderer, three_people):
    f = lab_renderer.render(three_people, cameras=[1], clean=True)
    person = f.rgb[0][f.labels[0] == 1]
    assert len(np.unique(person, axis=0)) > 20              # shading varies across the body
    assert f.rgb.shape == (1, 480, 640, 3) and f.rgb.dtype == np.uint8


def test_every_default_colour_stands_out_from_the_room_by_colour_angle(lab_renderer):
    """The pipeline is blind to brightness: a grey person (the palette's tenth, once) was
    invisible against the grey room, and the hull lost them."""
    from scene.config import default_colours

    bg = lab_renderer.background().rgb.reshape(-1, 3).astype(float)
    bg = bg[np.linalg.norm(bg, axis=1) > 25]                 # above the brightness floor
    bg /= np.linalg.norm(bg, axis=1, keepdims=True)
    colours = default_colours(10).astype(float)
    colours /= np.linalg.norm(colours, axis=1, keepdims=True)
    angles = np.degrees(np.arccos(np.clip(bg @ colours.T, -1, 1)))     # (pixels, 10)
    assert angles.min(axis=0).min() > 20


def test_background_has_no_people(lab, lab_renderer):
    bg = lab_renderer.background()
    assert bg.rgb.shape == (16, 480, 640, 3)
    assert not bg.labels.any()
    hidden = np.full((lab.people.count, 2), np.nan)
    assert np.array_equal(bg.rgb, lab_renderer.render(hidden, clean=True).rgb)


def test_render_checks_its_input(lab, lab_renderer, three_people):
    with pytest.raises(ValueError, match="positions_xy"):
        lab_renderer.render(three_people[:2], clean=True)
    with pytest.raises(ValueError, match="rng"):
        lab_renderer.render(three_people)
    with pytest.raises(ValueError, match="cameras"):
        lab_renderer.render(three_people, cameras=[17], clean=True)


@pytest.mark.parametrize("people", [[[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]],
                                    [[3.0, 3.0], [3.45, 3.05], [3.2, 3.5]]])   # apart, and occluding each other
def test_culling_back_faces_keeps_every_label(lab, lab_renderer, people):
    """The people's back faces are culled: same labels as drawing both faces, colour only on outlines."""
    pos = np.array(people)
    culled = lab_renderer.render(pos, clean=True)
    lab_renderer.raster.cull_back_faces = False
    try:
        both = lab_renderer.render(pos, clean=True)
    finally:
        lab_renderer.raster.cull_back_faces = True
    assert np.array_equal(culled.labels, both.labels)
    changed = (culled.rgb != both.rgb).any(-1)
    assert changed.sum() <= 1e-4 * changed.size, changed.sum()
    outline = np.zeros_like(changed)
    for k in range(len(culled.labels)):             # a changed pixel lies on a person's outline
        lab_k = culled.labels[k]
        edge = cv2.morphologyEx(lab_k, cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0
        outline[k] = cv2.dilate(edge.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    assert not (changed & ~outline).any()
