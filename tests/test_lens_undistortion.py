"""The camera model's numerics: undistortion that round-trips onto its pixels in the corners
of strong lenses, lens checks that find folds and nothing else, readable lens errors."""

import dataclasses
import re

import cv2
import numpy as np
import pytest

from scene import Camera, load_scene


def _project(rays, K, dist):
    """cv2.projectPoints of normalised rays (m, 2) -> pixels (m, 2)."""
    rays = np.asarray(rays, float).reshape(-1, 2)
    return cv2.projectPoints(np.column_stack([rays, np.ones(len(rays))]), np.zeros(3), np.zeros(3), K,
                             np.asarray(dist, float))[0].reshape(-1, 2)


def _pixel_grid(width, height):
    """Every pixel centre and the outer edges, (m, 2) (u, v)."""
    u = np.r_[-0.5, np.arange(width, dtype=float), width - 0.5]
    v = np.r_[-0.5, np.arange(height, dtype=float), height - 0.5]
    return np.stack(np.meshgrid(u, v), -1).reshape(-1, 2)


#: The lab's camera 1 with the strongest barrel distortion check_lens accepts on it (k1 alone).
STRONG = dataclasses.replace(load_scene("lab").cameras[0], dist=np.array([-0.447, 0.0, 0.0, 0.0, 0.0]))


def test_lens_model_is_opencvs_and_its_jacobian_its_derivative():
    from scene.camera import distort_normalised

    rng = np.random.default_rng(0)
    K = np.array([[500.0, 0, 320], [0, 480.0, 240], [0, 0, 1]])
    for _ in range(20):
        dist = rng.uniform([-0.5, -0.3, -0.05, -0.05, -0.2], [0.5, 0.3, 0.05, 0.05, 0.2])
        xy = rng.uniform(-1, 1, (50, 2))
        d, J = distort_normalised(xy, dist)
        np.testing.assert_allclose(d * [500, 480] + [320, 240], _project(xy, K, dist), atol=1e-9)
        h = 1e-6
        for axis in range(2):
            step = np.zeros(2)
            step[axis] = h
            numeric = (distort_normalised(xy + step, dist)[0] - distort_normalised(xy - step, dist)[0]) / (2 * h)
            np.testing.assert_allclose(J[:, :, axis], numeric, atol=1e-7)


def test_level_points_of_a_strong_lens_project_back_onto_their_pixels():
    """cv2.undistortPoints alone stopped 0.001 px short at a corner of this image."""
    from pipeline.rectify import check_lens, level_points, level_rotation

    check_lens(STRONG)
    w, h = STRONG.width, STRONG.height
    uv = np.r_[_pixel_grid(w, h)[::7], [[-0.5, -0.5], [w - 0.5, -0.5], [-0.5, h - 0.5], [w - 0.5, h - 0.5]]]
    x, y = level_points(STRONG, uv)
    rays = np.column_stack([x, y, np.ones_like(x)]) @ level_rotation(STRONG)     # back to the camera frame
    back = _project(rays[:, :2] / rays[:, 2:], STRONG.K, STRONG.dist)
    assert np.abs(back - uv).max() < 1e-6


@pytest.mark.parametrize("K, dist, width, height", [
    # cv2.undistortPoints alone: 1.1e-5 px short
    (STRONG.K, STRONG.dist, STRONG.width, STRONG.height),
    # 0.004 px short on a 42-pixel image
    (np.array([[21.0, 0, 20.5], [0, 21.0, 15.5], [0, 0, 1]]), np.array([-0.3, 0.1, 0.005, 0.005, 0.05]), 42, 32),
    # 0.35 px short on an 84-pixel image
    (np.array([[45.535, 0, 52.315], [0, 46.089, 27.085], [0, 0, 1]]),
     np.array([-0.21, -0.032, 0.003, -0.003, 0.019]), 84, 64),
])
def test_ideal_pixels_of_strong_lenses_project_back_onto_their_pixels(K, dist, width, height):
    """The renderer's distortion map: each output pixel's ideal pixel is the ray that
    cv2.projectPoints sends back onto it."""
    from pipeline.rectify import check_lens
    from render.distortion import ideal_pixels

    check_lens(Camera(1, K, dist, np.eye(3), np.zeros(3), width, height))
    ideal = ideal_pixels(K, dist, width, height).reshape(-1, 2)
    rays = np.column_stack([ideal, np.ones(len(ideal))]) @ np.linalg.inv(K).T
    v, u = np.mgrid[0:height, 0:width]
    assert np.abs(_project(rays[:, :2], K, dist) - np.column_stack([u.ravel(), v.ravel()])).max() < 1e-6


def test_every_pixel_of_the_strongest_lab_lens_undistorts_to_within_1e_9_px():
    """OpenCV's iterations leave some of its pixels 1e-3 px short; polishing brings every one,
    edges included, to a ray that cv2.projectPoints sends back within 1e-9 px of it."""
    from scene.camera import undistort_points

    uv = _pixel_grid(STRONG.width, STRONG.height)
    rays = undistort_points(uv, STRONG.K, STRONG.dist)
    assert np.hypot(*(_project(rays, STRONG.K, STRONG.dist) - uv).T).max() < 1e-9


def test_undistortion_leaves_converged_points_and_nan_alone():
    from scene.camera import undistort_points

    lab = load_scene("lab").cameras[0]
    uv = _pixel_grid(lab.width, lab.height)[::5]
    plain = cv2.undistortPoints(uv.reshape(-1, 1, 2), lab.K, lab.dist, None, None, None,
                                (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)).reshape(-1, 2)
    np.testing.assert_array_equal(undistort_points(uv, lab.K, lab.dist), plain)   # the lab's maps stay as they were
    assert np.all(np.isnan(undistort_points(uv[:3], lab.K, [0, 0, 1e300, 0, 0])))


def test_a_lens_that_maps_two_rays_onto_one_pixel_is_refused():
    """Rays 3.7 degrees apart land on the same pixel, inside the image: OpenCV's iterations
    missed it (every one of the old samples came back within 0.5 px)."""
    from pipeline.rectify import check_lens

    K = np.array([[19.408483758668982, 0, 39.223358252269044], [0, 20.471025319242294, 17.231401674198526],
                  [0, 0, 1]])
    dist = np.array([-0.24624093887618126, -0.6204891598577895, 0.038227057285121394, 0.03985779886894347,
                     0.5429889194160566])
    a, b = _project([[-0.5425990224504708, -0.5195987110126055], [-0.59, -0.565]], K, dist)
    assert np.abs(a - b).max() < 1e-6 and 0 <= a[0] <= 65 and 0 <= a[1] <= 74
    with pytest.raises(ValueError, match=r"camera 1: its lens distortion \[-0\.2462, -0\.6205, .*\] folds over "
                                         r"inside its image \(it mirrors the rays near some of its pixels\)"):
        check_lens(Camera(1, K, dist, np.eye(3), np.zeros(3), 66, 75))


def test_a_lens_that_does_not_fold_is_accepted_where_opencv_stopped_short():
    """The lab's lens about a principal point an image width left of the image: OpenCV's
    iterations ended 35 px off in a far corner and the lens was refused as folding over."""
    from pipeline.rectify import check_lens
    from render.distortion import ideal_pixels

    cam = dataclasses.replace(STRONG, dist=load_scene("lab").cameras[0].dist,
                              K=np.array([[STRONG.K[0, 0], 0, -640.0], [0, STRONG.K[1, 1], 236.8], [0, 0, 1]]))
    check_lens(cam)
    ideal = ideal_pixels(cam.K, cam.dist, cam.width, cam.height)[::9, ::9].reshape(-1, 2)
    rays = np.column_stack([ideal, np.ones(len(ideal))]) @ np.linalg.inv(cam.K).T
    v, u = np.mgrid[0:cam.height:9, 0:cam.width:9]
    assert np.abs(_project(rays[:, :2], cam.K, cam.dist) - np.column_stack([u.ravel(), v.ravel()])).max() < 1e-6


def test_a_lens_whose_image_reaches_past_its_widest_ray_says_so():
    """k1 = -0.6 on the lab's 49-degree lens: r (1 - 0.6 r^2) peaks inside the image, so its
    corners have no ray at all; the error says that a pixel does not come back (the fold
    itself lies beyond the rays that the image's pixels have)."""
    from pipeline.rectify import check_lens

    cam = dataclasses.replace(load_scene("lab").cameras[0], dist=np.array([-0.6, 0.0, 0.0, 0.0, 0.0]))
    r = np.linspace(0, 2, 20001)
    peak = (r * (1 - 0.6 * r**2)).max() * cam.K[0, 0]                  # pixels from the principal point
    assert np.hypot(cam.K[0, 2] + 0.5, cam.K[1, 2] + 0.5) > peak        # the corner lies beyond it
    with pytest.raises(ValueError, match=r"folds over inside its image \(a pixel undistorted and distorted "
                                         r"again lands [\d.]+ pixels away\)"):
        check_lens(cam)


def test_lens_errors_show_readable_numbers():
    from pipeline.rectify import check_rectifiable

    for dist in ([1e300, 0.06, 0, 0, 0], [-0.18, 0.06, 0, 0, -1e300]):
        cam = dataclasses.replace(load_scene("lab").cameras[0], dist=np.array(dist))
        with pytest.raises(ValueError, match=r"camera 1: its lens distortion \[.*1e\+300.*\] folds over") as info:
            check_rectifiable([cam])
        assert not re.search(r"\d{12}", str(info.value)) and len(str(info.value)) < 250, str(info.value)


def test_every_pixel_of_a_lens_that_folds_beyond_them_gets_its_ray_before_the_fold():
    """An 8 x 59 camera with k2 = 0.0625, k3 = -1/256: OpenCV's iterations leave 20 of its
    pixels up to 17 px off, some towards a second ray beyond the lens's fold that projects
    onto the same pixel. Every pixel's ray projects back onto it (cv2.projectPoints, 1e-9 px)
    and the projection keeps its orientation there (a positive determinant of its
    derivative, by central differences): the ray before the fold, the one the camera sees."""
    from scene.camera import undistort_points

    K = np.array([[7.32195089, 0.0, 3.5], [0.0, 7.32195089, 29.0], [0.0, 0.0, 1.0]])
    dist = np.array([0.0, 0.0625, 0.0, 0.0, -0.00390625])
    uv = _pixel_grid(8, 59)
    rays = undistort_points(uv, K, dist, eps=1e-10)
    assert np.abs(_project(rays, K, dist) - uv).max() < 1e-9
    h = 1e-6
    du = (_project(rays + [h, 0], K, dist) - _project(rays - [h, 0], K, dist)) / (2 * h)
    dv = (_project(rays + [0, h], K, dist) - _project(rays - [0, h], K, dist)) / (2 * h)
    assert (du[:, 0] * dv[:, 1] - du[:, 1] * dv[:, 0]).min() > 0


@pytest.mark.parametrize("K, dist, width, height", [
    # polished from OpenCV's ray, some pixels reach a ray past the fold first: the radial start's is taken
    (np.array([[4.36, 0.0, 1.13], [0.0, 4.36, 12.63], [0.0, 0.0, 1.0]]), [0.119, 0.113, 0.01, -0.001, -0.023], 8, 15),
    # strong barrel distortion and tangential terms: Newton's steps need the whole determinant
    (np.array([[11.43, 0.0, 9.63], [0.0, 11.43, 4.3], [0.0, 0.0, 1.0]]), [-0.404, -0.128, 0.021, -0.011, 0.146], 20, 45),
    # pincushion distortion: a damped step that succeeds grows back to at most a whole Newton step
    (np.array([[10.83, 0.0, 17.2], [0.0, 10.83, 24.76], [0.0, 0.0, 1.0]]), [0.177, 0.234, 0.017, 0.008, -0.064], 23, 45),
])
def test_every_pixel_of_a_wide_small_lens_gets_the_ray_before_its_fold(K, dist, width, height):
    """Every pixel, edges included, gets a ray that cv2.projectPoints sends back within 1e-9 px
    of it, where the projection keeps its orientation (a positive determinant of its
    derivative, by central differences)."""
    from scene.camera import undistort_points

    dist = np.array(dist)
    uv = _pixel_grid(width, height)
    rays = undistort_points(uv, K, dist)
    assert np.hypot(*(_project(rays, K, dist) - uv).T).max() < 1e-9
    h = 1e-6
    du = (_project(rays + [h, 0], K, dist) - _project(rays - [h, 0], K, dist)) / (2 * h)
    dv = (_project(rays + [0, h], K, dist) - _project(rays - [0, h], K, dist)) / (2 * h)
    assert (du[:, 0] * dv[:, 1] - du[:, 1] * dv[:, 0]).min() > 0


@pytest.mark.parametrize("target, want", [
    ([0.4375 * 0.6, 0.4375 * 0.8], [0.3, 0.4]),             # r = 0.5: 0.5 - 0.5 * 0.5**3 = 0.4375
    ([0.0, -(0.25 - 0.5 * 0.25**3)], [0.0, -0.25]),
    ([0.6, 0.0], [np.sqrt(2 / 3), 0.0]),                    # past the top, 0.544 at r**2 = 2/3: its end
    ([0.0, 0.0], [0.0, 0.0]),
])
def test_the_radial_start_inverts_the_radial_factor_on_its_rising_branch(target, want):
    """k1 = -0.5 alone: r (1 - 0.5 r**2) rises to r = sqrt(2/3) (slope 1 - 1.5 r**2 = 0), then falls."""
    from scene.camera import _radial_start

    got = _radial_start(np.array([target]), np.array([-0.5, 0.0, 0.0, 0.0, 0.0]))
    np.testing.assert_allclose(got[0], want, rtol=0, atol=1e-12)


def test_the_radial_start_of_a_lens_that_rises_for_ever():
    """k1 = 0.5, k3 = 0.25: r + 0.5 r**3 + 0.25 r**7 is 1.75 at r = 1 and 2 + 4 + 32 = 38 at r = 2."""
    from scene.camera import _radial_start

    got = _radial_start(np.array([[0.0, 1.75], [38.0 * 0.6, 38.0 * 0.8]]), np.array([0.5, 0.0, 0.0, 0.0, 0.25]))
    np.testing.assert_allclose(got, [[0.0, 1.0], [1.2, 1.6]], rtol=0, atol=1e-12)


def _radial(r, k1, k2, k3):
    """r (1 + k1 r^2 + k2 r^4 + k3 r^6), the radial factor's image of the radius r."""
    return r * (1 + k1 * r**2 + k2 * r**4 + k3 * r**6)


def test_the_radial_start_of_a_lens_whose_slope_nearly_vanishes_rises_for_ever():
    """The slope 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3 (s = r^2) is (s + 1)((s - 1)^2 + 0.005^2) / 1.000025:
    its roots are -1 and the complex pair 1 +- 0.005i, so it stays above 0 (5e-5 at s = 1) and
    the radial factor rises for ever; r = 1.2 comes back as itself, not as the turn at r = 1
    that the pair's real part would be."""
    from scene.camera import _radial_start

    c = 1.000025
    k1, k2, k3 = -0.999975 / c / 3, -1 / c / 5, 1 / c / 7
    rd = _radial(1.2, k1, k2, k3)
    got = _radial_start(np.array([[0.6 * rd, 0.8 * rd]]), np.array([k1, k2, 0.0, 0.0, k3]))
    np.testing.assert_allclose(got, [[0.72, 0.96]], rtol=0, atol=1e-12)


@pytest.mark.parametrize("r, rd", [(0.7, None), (1.0, 0.8)])
def test_the_radial_start_of_a_lens_that_turns_twice_stops_at_its_first_turn(r, rd):
    """k1 = -1/6, k2 = -1/5, k3 = 1/14: the slope 1 - s/2 - s^2 + s^3/2 = (s - 1)(s - 2)(s + 1) / 2
    falls to 0 at r = 1 (the image 0.705 there), then rises again past r = sqrt(2). A point
    within reach gets its ray on the first rising branch; one beyond (0.8) the first turn, r = 1."""
    from scene.camera import _radial_start

    k1, k2, k3 = -1 / 6, -1 / 5, 1 / 14
    rd = _radial(r, k1, k2, k3) if rd is None else rd
    got = _radial_start(np.array([[0.0, -rd]]), np.array([k1, k2, 0.0, 0.0, k3]))
    np.testing.assert_allclose(got, [[0.0, -r]], rtol=0, atol=1e-12)


def test_the_polishing_error_is_in_pixels_of_each_axis():
    """A ray 1e-3 off in x and 2e-3 off in y (normalised) misses by 0.5 px and 1.6 px with fx = 500,
    fy = 800: 1.66 px, not 2.2e-3."""
    from scene.camera import _miss

    r, _, err = _miss(np.array([[0.101, 0.202]]), np.array([[0.1, 0.2]]), np.zeros(5), np.array([500.0, 800.0]))
    np.testing.assert_allclose(r, [[1e-3, 2e-3]], atol=1e-15)
    assert err[0] == pytest.approx(np.sqrt(0.5**2 + 1.6**2), rel=1e-9)


@pytest.mark.parametrize("rd", [0.55, 0.6, 1.5])
def test_a_pixel_past_a_lens_reach_gets_the_ray_that_lands_nearest_it(rd):
    """k1 = -0.5 sends no ray farther than 0.544 (normalised) from the centre, at r = sqrt(2/3):
    a pixel beyond gets that ray, in its own direction (0.6, 0.8), not where Newton's steps stalled."""
    from scene.camera import undistort_points

    K = np.array([[100.0, 0.0, 50.0], [0.0, 100.0, 50.0], [0.0, 0.0, 1.0]])
    uv = np.array([[50 + 100 * rd * 0.6, 50 + 100 * rd * 0.8]])
    ray = undistort_points(uv, K, [-0.5, 0.0, 0.0, 0.0, 0.0])[0]
    np.testing.assert_allclose(ray, np.sqrt(2 / 3) * np.array([0.6, 0.8]), atol=1e-12)


@pytest.mark.parametrize("dist, turn", [
    ([-0.5, 0.0, 0.0, 0.0, 0.0], np.sqrt(1 / 1.5)),         # d/dr r (1 - 0.5 r^2) = 1 - 1.5 r^2
    ([0.0, -0.2, 0.0, 0.0, 0.0], 1.0),                      # 1 - 5 * 0.2 r^4
    ([0.0, 0.0, 0.0, 0.0, -0.1], (1 / 0.7) ** (1 / 6)),     # 1 - 7 * 0.1 r^6
])
def test_a_lens_whose_radial_factor_turns_just_past_its_corners_is_refused(dist, turn):
    """A 101 x 101 image whose corner pixels' rays lie at 0.985 or 0.995 of the radius where the
    radial factor r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops growing (by hand): within 1% of its
    farthest ray the lens folds, which check_lens refuses; at 1.5% it accepts it."""
    from pipeline.rectify import check_lens

    k1, k2, _, _, k3 = dist
    for share, refused in ((0.985, False), (0.995, True)):
        r = share * turn
        f = 50.5 * np.sqrt(2) / (r * (1 + k1 * r**2 + k2 * r**4 + k3 * r**6))   # the corner is 50.5 px per axis out
        cam = Camera(1, np.array([[f, 0, 50.0], [0, f, 50.0], [0, 0, 1]]), np.array(dist), np.eye(3), np.zeros(3),
                     101, 101)
        if refused:
            with pytest.raises(ValueError, match=r"folds over inside its image \(rays farther out come back nearer "
                                                 r"the centre\); use smaller distortion coefficients$"):
                check_lens(cam)
        else:
            check_lens(cam)


@pytest.mark.parametrize("cx, hint", [(-0.25, False), (-0.5, False), (-0.75, True), (640.0, True), (639.5, False)])
def test_a_folding_lens_is_told_to_move_its_principal_point_only_when_it_is_off_the_image(cx, hint):
    """The image's pixels reach from -0.5 to W - 0.5: a principal point on them gets no such hint."""
    from pipeline.rectify import check_lens

    lab = load_scene("lab").cameras[0]
    K = lab.K.copy()
    K[0, 2] = cx
    cam = dataclasses.replace(lab, K=K, dist=np.array([-0.6, 0.0, 0.0, 0.0, 0.0]))
    with pytest.raises(ValueError, match="folds over inside its image") as info:
        check_lens(cam)
    assert ("or a principal point nearer the image than" in str(info.value)) == hint, str(info.value)
