"""The fast production path equals the whole-image reference bit for bit; pooled noise statistics.

The production step draws only the people (over a copy of the room's colour and depth)
and reads back only their canvas boxes; the reference draws the whole scene and
remaps whole images. They must agree on every pixel and label.
"""

from statistics import NormalDist

import numpy as np
import pytest

pytestmark = pytest.mark.render


def _reference(r, positions, cameras=None):
    """Whole-canvas draw, whole-image remap of RGB and labels: the unoptimised path."""
    idx = r._indices(cameras)
    canvases = r.raster.draw(r.view_projs[idx], positions, bands=idx).copy()
    return r._distort(canvases, idx)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_clean_frames_equal_the_whole_image_reference(lab, lab_renderer, seed):
    rng = np.random.default_rng(seed)
    positions = rng.uniform(0.3, 5.7, (lab.people.count, 2))
    if seed == 1:
        positions[0] = np.nan                                 # a hidden person
    cameras = None if seed != 2 else [2, 5, 9, 16]            # a subset, drawn in its own bands
    f = lab_renderer.render(positions, cameras=cameras, clean=True)
    rgb, labels = _reference(lab_renderer, positions, cameras)
    assert np.array_equal(f.rgb, rgb)
    assert np.array_equal(f.labels, labels)


@pytest.mark.parametrize("cameras", [None, [2, 5, 9]])
def test_labels_only_equal_the_reference(lab, lab_renderer, cameras):
    """``Renderer.labels`` skips the colour work but gives the clean frames' labels exactly."""
    positions = np.random.default_rng(11).uniform(0.3, 5.7, (lab.people.count, 2))
    positions[1] = np.nan
    labels = lab_renderer.labels(positions, cameras=cameras)
    assert np.array_equal(labels, _reference(lab_renderer, positions, cameras)[1])
    assert np.array_equal(labels, lab_renderer.render(positions, cameras=cameras, clean=True).labels)


def _random_positions(lab, rng, margin):
    x0, y0, x1, y1 = lab.room.polygon.bounds
    return np.column_stack([rng.uniform(x0 + margin, x1 - margin, lab.people.count),
                            rng.uniform(y0 + margin, y1 - margin, lab.people.count)])


@pytest.mark.parametrize("seed", range(3, 9))
def test_many_layouts_equal_the_reference(lab, lab_renderer, seed):
    """People against the walls (radius + 1 cm), touching or hiding each other; the
    reference is drawn before the step too, so leftovers in the framebuffer must not leak."""
    rng = np.random.default_rng(seed)
    positions = _random_positions(lab, rng, lab.people.radius + 0.01)
    if seed % 3 == 0:                                          # two people touching
        positions[1] = positions[0] + [2 * lab.people.radius + 0.001, 0.0]
    rgb, labels = _reference(lab_renderer, positions)
    f = lab_renderer.render(positions, clean=True)
    assert np.array_equal(f.labels, labels)
    assert np.array_equal(f.rgb, rgb)
    assert np.array_equal(lab_renderer._work, lab_renderer._canvas)   # work canvases restored


def test_people_partly_inside_a_wall_are_occluded_like_the_reference(lab, lab_renderer):
    """The room's depth is copied under the people, so even a person half inside a wall
    is cut by it exactly as in the whole-scene draw (the room does occlude here)."""
    x0, _, x1, y1 = lab.room.polygon.bounds
    positions = np.array([[x0 + 0.05, 2.0], [3.0, y1 - 0.1], [x1 + 0.1, 3.0]])
    f = lab_renderer.render(positions, clean=True)
    rgb, labels = _reference(lab_renderer, positions)
    assert np.array_equal(f.rgb, rgb) and np.array_equal(f.labels, labels)


def test_each_person_alone_and_nobody(lab, lab_renderer, three_people):
    """The dataset generator hides the others with NaN rows; nobody shown is the background."""
    for p in range(lab.people.count):
        alone = np.full_like(three_people, np.nan)
        alone[p] = three_people[p]
        f = lab_renderer.render(alone, cameras=[3, 8, 11], clean=True)
        rgb, labels = _reference(lab_renderer, alone, [3, 8, 11])
        assert np.array_equal(f.rgb, rgb) and np.array_equal(f.labels, labels)
        assert set(np.unique(f.labels)) <= {0, p + 1}
    hidden = np.full_like(three_people, np.nan)
    f = lab_renderer.render(hidden, clean=True)
    bg = lab_renderer.background()
    assert np.array_equal(f.rgb, bg.rgb) and not f.labels.any()
    rgb, labels = _reference(lab_renderer, hidden)
    assert np.array_equal(f.rgb, rgb) and np.array_equal(f.labels, labels)


def test_noisy_frames_are_the_reference_plus_gain_and_noise(lab, lab_renderer, three_people):
    from render.noise import degrade

    f = lab_renderer.render(three_people, cameras=[1, 6, 12], rng=np.random.default_rng(7))
    rgb, _ = _reference(lab_renderer, three_people, [1, 6, 12])
    s = lab.render
    expected = degrade(rgb, s.noise_std, s.gain_jitter, np.random.default_rng(7))
    assert np.array_equal(f.rgb, expected)


def test_person_near_a_camera_is_still_exact(lab, lab_renderer):
    cam = lab.cameras[0]
    centre = -cam.R.T @ cam.t                                   # camera 1's position, world frame
    positions = np.array([[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]])
    positions[0] = centre[:2] + 0.3 * (np.array([3.0, 3.0]) - centre[:2]) / np.linalg.norm(centre[:2] - 3.0)
    f = lab_renderer.render(positions, cameras=[1, 2], clean=True)
    rgb, labels = _reference(lab_renderer, positions, [1, 2])
    assert np.array_equal(f.rgb, rgb) and np.array_equal(f.labels, labels)


def _residual(noisy, clean):
    """Noise samples of one camera away from saturation, and the fitted gain."""
    clean, noisy = clean.astype(float), noisy.astype(float)
    inside = (clean > 20) & (clean < 230)
    c, x = clean[inside], noisy[inside]
    gain = (c * x).sum() / (c * c).sum()                       # least squares
    r = np.full(clean.shape, np.nan)
    r[inside] = x - np.rint(c * gain)
    return r, gain


def test_noise_is_gaussian_with_the_configured_std(lab, lab_renderer, three_people):
    clean = lab_renderer.render(three_people, cameras=[4], clean=True).rgb[0]
    noisy = lab_renderer.render(three_people, cameras=[4], rng=np.random.default_rng(11)).rgb[0]
    r, gain = _residual(noisy, clean)
    r = r[np.isfinite(r)]
    std = lab.render.noise_std
    assert abs(gain - 1) < 4 * lab.render.gain_jitter
    assert abs(r.std() - np.sqrt(std**2 + 1 / 12)) < 0.15      # rounded Gaussian
    assert abs(r.mean()) < 0.15
    within = 2 * NormalDist(0, std).cdf(2.5) - 1                # P(|round(z)| <= 2)
    assert abs(np.mean(np.abs(r) <= 2) - within) < 0.03


def test_noise_differs_between_frames_and_cameras(lab_renderer, three_people):
    rng = np.random.default_rng(3)
    clean = lab_renderer.render(three_people, cameras=[5, 6], clean=True).rgb
    f1 = lab_renderer.render(three_people, cameras=[5, 6], rng=rng).rgb
    f2 = lab_renderer.render(three_people, cameras=[5, 6], rng=rng).rgb
    a = [_residual(f1[k], clean[k])[0] for k in range(2)]
    b = [_residual(f2[k], clean[k])[0] for k in range(2)]
    for x, y in ((a[0], b[0]), (a[1], b[1]), (a[0], a[1])):   # frame to frame, camera to camera
        ok = np.isfinite(x) & np.isfinite(y)
        c = np.corrcoef(x[ok], y[ok])[0, 1]
        assert abs(c) < 0.02, c


def test_pool_offsets_and_gains_come_from_the_rng():
    from render.noise import POOL_EXTRA, draw_gains_offsets

    g1, o1 = draw_gains_offsets(16, 0.02, np.random.default_rng(0))
    g2, o2 = draw_gains_offsets(16, 0.02, np.random.default_rng(0))
    _, o3 = draw_gains_offsets(16, 0.02, np.random.default_rng(1))
    assert np.array_equal(g1, g2) and np.array_equal(o1, o2)
    assert not np.array_equal(o1, o3)
    assert o1.min() >= 0 and o1.max() <= POOL_EXTRA
    with pytest.raises(ValueError, match="rng"):
        draw_gains_offsets(2, 0.02, 5)


def _expected_rects(lab, r, positions):
    """Per camera and person, the box of the person's mesh vertices projected by cv2.projectPoints
    on the ideal canvas, floor/ceil + 2 px, sides on the canvas edge at infinity; NaN hidden,
    behind the near plane or off the canvas; the whole canvas straddling the near plane."""
    import cv2

    from render.geometry import people_mesh
    from render.renderer import ZNEAR

    cw, ch = r.canvas_size
    mesh = people_mesh(lab.people)
    out = np.full((len(r.numbers), lab.people.count, 4), np.nan)
    for k, cam in enumerate(r.cameras):
        Kc = r.maps[r.map_index[k]].canvas_K(cam.K)
        for p, xy in enumerate(positions):
            if np.isnan(xy).any():
                continue
            world = mesh.positions[mesh.person == p].astype(float) + [xy[0], xy[1], 0.0]
            z = (cam.R @ world.T + cam.t.reshape(3, 1))[2]
            if np.all(z < 0.999 * ZNEAR):
                continue
            if not np.all(z > 1.001 * ZNEAR):
                out[k, p] = [-np.inf, -np.inf, np.inf, np.inf]
                continue
            uv = cv2.projectPoints(world, cv2.Rodrigues(cam.R)[0], cam.t, Kc, None)[0].reshape(-1, 2)
            lo, hi = np.floor(uv.min(axis=0)) - 2, np.ceil(uv.max(axis=0)) + 2
            if hi[0] < 0 or hi[1] < 0 or lo[0] > cw - 1 or lo[1] > ch - 1:
                continue
            out[k, p] = [-np.inf if lo[0] <= 0 else lo[0], -np.inf if lo[1] <= 0 else lo[1],
                         np.inf if hi[0] >= cw - 1 else hi[0], np.inf if hi[1] >= ch - 1 else hi[1]]
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_people_boxes_are_the_projected_vertices_plus_two_pixels_and_hold_every_label(lab, lab_renderer, seed):
    """The canvas boxes of ``_rects`` against cv2.projectPoints of the mesh, and every pixel a
    person covers in the whole-scene draw inside that person's box."""
    from render.renderer import _boxes

    r = lab_renderer
    cam = lab.cameras[0]
    centre = cam.center_world
    side = cam.R[0, :2] / np.linalg.norm(cam.R[0, :2])           # camera 1's right, on the floor
    ahead = cam.R[2, :2] / np.linalg.norm(cam.R[2, :2])
    rng = np.random.default_rng(seed)
    positions = _random_positions(lab, rng, lab.people.radius + 0.01)
    if seed == 1:
        positions[0] = centre[:2] + 0.6 * side                   # beside camera 1: across its near plane
        positions[1] = centre[:2] - 1.0 * ahead                  # behind camera 1
    else:
        positions[2, 0] = np.nan                                 # half a NaN row hides the person too
    idx = np.arange(len(r.numbers))
    assert not r._close(idx, positions).any()
    rects = r._rects(idx, positions)
    expected = _expected_rects(lab, r, positions)
    np.testing.assert_array_equal(np.isnan(rects), np.isnan(expected))
    np.testing.assert_allclose(rects[~np.isnan(rects)], expected[~np.isnan(expected)], atol=0)
    assert np.isnan(rects).any() and np.isinf(rects).any() and np.isfinite(rects).any()
    if seed == 1:
        assert rects[0, 0].tolist() == [-np.inf, -np.inf, np.inf, np.inf] and np.isnan(rects[0, 1]).all()
    labels = r.raster.draw(r.view_projs, positions, bands=idx)[..., 3]
    for k in idx:
        for p in range(lab.people.count):
            inside = np.zeros(labels.shape[1:], bool)
            for x0, y0, x1, y1 in _boxes(rects[k, p:p + 1], r.canvas_size):
                inside[y0:y1, x0:x1] = True
            assert not np.any((labels[k] == p + 1) & ~inside), (k, p)


def test_boxes_are_the_end_exclusive_slices_of_the_rects_on_the_canvas():
    """Inclusive float bounds to integer slices on an 8x6 canvas, by hand: infinite sides at the
    edges, NaN rows and rects off the canvas (or empty on it) left out."""
    from render.renderer import _boxes

    inf, nan = np.inf, np.nan
    rects = np.array([[2.0, 3.0, 5.0, 7.0],          # rows 3..7 -> 3..5 on the canvas
                      [-inf, -inf, inf, inf],        # the whole canvas
                      [nan, nan, nan, nan],          # hidden
                      [10.0, 1.0, 12.0, 2.0],        # right of the canvas
                      [1.0, 7.0, 3.0, 9.0],          # below it
                      [-3.0, -5.0, -1.0, 2.0],       # left of it
                      [0.0, 5.0, 7.0, 5.0]])         # its last row, whole width
    assert _boxes(rects, (8, 6)) == [(2, 3, 6, 6), (0, 0, 8, 6), (0, 5, 8, 6)]
    assert _boxes(rects[2:4], (8, 6)) == []


def test_frames_without_noise_still_take_the_gain(three_people):
    """noise_std 0, gain_jitter 0.2: each camera's clean frame times its gain, no noise."""
    from render import Renderer
    from scene import Scene, scene_path

    text = scene_path("lab").read_text().replace("noise_std: 2.0 ", "noise_std: 0.0 ").replace(
        "gain_jitter: 0.02 ", "gain_jitter: 0.2 ")
    scene = Scene.from_text(text)
    assert scene.render.noise_std == 0.0 and scene.render.gain_jitter == 0.2
    with Renderer(scene, cameras=[1, 6]) as r:
        f = r.render(three_people, rng=np.random.default_rng(5))
        clean = r.render(three_people, clean=True).rgb
    gains = 1.0 + 0.2 * np.random.default_rng(5).standard_normal(2)
    assert np.abs(gains - 1).min() > 0.01
    expected = np.clip(np.rint(clean * gains[:, None, None, None]), 0, 255)
    np.testing.assert_allclose(f.rgb, expected, atol=1)              # round(x.5) either way
    assert np.mean(f.rgb == expected) > 0.99


def test_a_gain_clipped_to_zero_gives_a_black_frame(three_people):
    """gain_jitter 1.0 draws gains below 0, clipped to 0 (seed 5: 0.198 and 0 for cameras
    1 and 6): no light, a black frame, not the clean one (a 160x120 lab)."""
    from render import Renderer
    from scene import Scene, scene_path

    text = scene_path("lab").read_text().replace("noise_std: 2.0 ", "noise_std: 0.0 ").replace(
        "gain_jitter: 0.02 ", "gain_jitter: 1.0 ").replace("resolution: [640, 480]", "resolution: [160, 120]")
    with Renderer(Scene.from_text(text.replace("[322.4, 236.8]", "[80.6, 59.2]")), cameras=[1, 6]) as r:
        f = r.render(three_people, rng=np.random.default_rng(5))
        clean = r.render(three_people, clean=True).rgb
    assert np.clip(1.0 + np.random.default_rng(5).standard_normal(2), 0.0, None)[1] == 0.0
    assert clean[1].mean() > 50 and not f.rgb[1].any()
    assert 0 < f.rgb[0].mean() < 0.25 * clean[0].mean()


def test_a_skewed_camera_equals_the_reference(lab):
    """OpenCV and the OpenGL projection leave out the skew K[0, 1], so the people's canvas
    boxes must too: shifted by the skew (up to 14 px here), they left out pixels of people
    near the top and bottom of the image, which the fast path then did not draw."""
    import dataclasses

    from render import Renderer

    K = lab.cameras[0].K.copy()
    K[0, 1] = 40.0
    cameras = (dataclasses.replace(lab.cameras[0], K=K), *lab.cameras[1:])
    scene = dataclasses.replace(lab, cameras=cameras)
    rng = np.random.default_rng(12)
    with Renderer(scene, cameras=[1]) as r:
        for _ in range(4):
            positions = _random_positions(lab, rng, lab.people.radius + 0.01)
            rgb, labels = _reference(r, positions)
            f = r.render(positions, clean=True)
            assert (labels > 0).any()
            assert np.array_equal(f.labels, labels)
            assert np.array_equal(f.rgb, rgb)


def test_cameras_of_other_lenses_render_as_each_alone():
    """A 160x120 lab whose camera 2 has its principal point moved and fy 15 % above fx, and
    camera 3 a stronger distortion (the largest canvas): rendered together, each camera
    gives its frames alone (each with its own map, on a canvas that holds the largest),
    but for a pixel or two on the people's edges (a larger canvas rasterises a hair apart)."""
    import dataclasses

    from render import Renderer
    from scene import Scene, scene_path

    text = scene_path("lab").read_text().replace("resolution: [640, 480]", "resolution: [160, 120]")
    lab = Scene.from_text(text.replace("principal: [322.4, 236.8]", "principal: [80.6, 59.2]"))
    c = lab.cameras
    K = c[1].K.copy()
    K[1, 1] *= 1.15
    K[:2, 2] += [-40.0, 20.0]
    dist = np.array([-0.3, 0.12, 0.0, 0.0, 0.0])
    scene = dataclasses.replace(lab, cameras=(c[0], dataclasses.replace(c[1], K=K),
                                              dataclasses.replace(c[2], dist=dist), *c[3:]))
    positions = np.array([[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]])
    with Renderer(scene, cameras=[1, 2, 3]) as r:
        together = r.render(positions, clean=True)
        rgb, labels = _reference(r, positions)
    assert np.array_equal(together.rgb, rgb) and np.array_equal(together.labels, labels)
    for k, n in enumerate([1, 2, 3]):
        with Renderer(scene, cameras=[n]) as r:
            alone = r.render(positions, clean=True)
        assert (alone.labels[0] > 0).sum() > 500
        assert (together.labels[k] != alone.labels[0]).sum() <= 3, n
        assert (np.abs(together.rgb[k].astype(int) - alone.rgb[0]) > 1).any(axis=-1).sum() <= 3, n
