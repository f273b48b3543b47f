"""OpenCV -> OpenGL camera conversion, checked against cv2.projectPoints and pyrender."""

import cv2
import numpy as np
import pytest

from render.pose import opencv_to_opengl_pose, project_opengl, projection_matrix, view_matrix


def _points_in_view(cam, rng, n=200):
    # points 1..6 m in front of the camera, spread over the image
    uv = rng.uniform([0, 0], [cam.width, cam.height], size=(n, 2))
    z = rng.uniform(1.0, 6.0, size=n)
    rays = np.linalg.solve(cam.K, np.column_stack([uv, np.ones(n)]).T).T
    points_cam = rays * z[:, None]
    return (cam.R.T @ (points_cam - cam.t).T).T


@pytest.mark.parametrize("number", [1, 6, 11, 16])
def test_opengl_projection_matches_projectpoints(lab, number):
    cam = lab.cameras[number - 1]
    pts = _points_in_view(cam, np.random.default_rng(number))
    rvec, _ = cv2.Rodrigues(cam.R)
    expected, _ = cv2.projectPoints(pts, rvec, cam.t, cam.K, np.zeros(5))
    got = project_opengl(pts, cam.R, cam.t, cam.K, cam.width, cam.height)
    np.testing.assert_allclose(got, expected.reshape(-1, 2), atol=1e-6)


def test_pose_is_inverse_of_view_and_matches_pyrender(lab):
    from render import gl

    pyrender = gl.pyrender()
    cam = lab.cameras[4]
    pose = opencv_to_opengl_pose(cam.R, cam.t)
    np.testing.assert_allclose(pose @ view_matrix(cam.R, cam.t), np.eye(4), atol=1e-12)
    np.testing.assert_allclose(pose[:3, 3], cam.center_world, atol=1e-12)
    # OpenGL looks down -z: the camera's -z axis is OpenCV's forward axis (row 2 of R)
    np.testing.assert_allclose(-pose[:3, 2], cam.R[2], atol=1e-12)
    K = cam.K
    ref = pyrender.IntrinsicsCamera(K[0, 0], K[1, 1], K[0, 2] + 0.5, K[1, 2] + 0.5, znear=0.05, zfar=50.0)
    np.testing.assert_allclose(projection_matrix(K, cam.width, cam.height, 0.05, 50.0),
                               ref.get_projection_matrix(cam.width, cam.height), atol=1e-12)


# --- hypothesis properties: random cameras -----------------------------------------------

from hypothesis import given, settings
from hypothesis import strategies as st


@st.composite
def pinhole_cameras(draw):
    """(K, rvec, R, t, width, height): any focal length, aspect, principal point (even
    off the image) and pose."""
    w, h = draw(st.integers(2, 1600)), draw(st.integers(2, 1200))
    fx = draw(st.floats(0.2, 3.0)) * w
    fy = fx * draw(st.floats(0.8, 1.25))
    cx, cy = draw(st.floats(-0.2, 1.2)) * w, draw(st.floats(-0.2, 1.2)) * h
    K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    rvec = np.array(draw(st.tuples(*[st.floats(-3.0, 3.0)] * 3)))
    t = np.array(draw(st.tuples(*[st.floats(-10.0, 10.0)] * 3)))
    return K, rvec, cv2.Rodrigues(rvec)[0], t, w, h


def _points_in_front(K, R, t, w, h, rng, n=50):
    """World points whose pixels spread over the image (outer edges included), 0.1..40 m deep."""
    uv = rng.uniform([-0.5, -0.5], [w - 0.5, h - 0.5], (n, 2))
    z = rng.uniform(0.1, 40.0, n)
    points_cam = np.linalg.solve(K, np.column_stack([uv, np.ones(n)]).T).T * z[:, None]
    return (R.T @ (points_cam - t).T).T, uv, z


@settings(max_examples=150, deadline=None)
@given(pinhole_cameras(), st.integers(0, 2**32 - 1))
def test_opengl_projection_matches_projectpoints_for_any_camera(camera, seed):
    K, rvec, R, t, w, h = camera
    pts, uv, z = _points_in_front(K, R, t, w, h, np.random.default_rng(seed))
    expected = cv2.projectPoints(pts, rvec, t, K, None)[0].reshape(-1, 2)
    got = project_opengl(pts, R, t, K, w, h)
    np.testing.assert_allclose(got, expected, atol=1e-6 * max(w, h))
    np.testing.assert_allclose(got, uv, atol=1e-6 * max(w, h))
    # flip_rows draws the image upside down: window y counts rows from the top
    clip = (projection_matrix(K, w, h, flip_rows=True) @ view_matrix(R, t) @ np.column_stack([pts, np.ones(len(pts))]).T).T
    assert np.all(clip[:, 3] > 0)                                 # in front of the OpenGL camera
    ndc = clip[:, :3] / clip[:, 3:]
    np.testing.assert_allclose((ndc[:, 1] + 1) / 2 * h - 0.5, uv[:, 1], atol=1e-6 * max(w, h))
    between = (z > 0.05) & (z < 50.0)                              # default near and far planes
    assert np.all(np.abs(ndc[between, 2]) <= 1 + 1e-9)


@settings(max_examples=150, deadline=None)
@given(pinhole_cameras(), st.floats(0.01, 1.0), st.floats(2.0, 500.0))
def test_pose_view_and_projection_follow_the_opengl_conventions(camera, znear, zfar):
    """The pose is camera-to-world with OpenGL axes (x right = R[0], y up = -R[1], z backward =
    -R[2]) at the camera centre, the view matrix its inverse, and the projection pyrender's
    IntrinsicsCamera with the principal point moved by half a pixel (docs of render.pose)."""
    import pyrender

    K, _, R, t, w, h = camera
    pose, view = opencv_to_opengl_pose(R, t), view_matrix(R, t)
    np.testing.assert_allclose(pose @ view, np.eye(4), atol=1e-9)
    np.testing.assert_allclose(pose[:3, :3], np.column_stack([R[0], -R[1], -R[2]]), atol=1e-12)
    np.testing.assert_allclose(pose[:3, 3], -R.T @ t, atol=1e-9)
    assert np.linalg.det(pose[:3, :3]) == pytest.approx(1.0)
    ref = pyrender.IntrinsicsCamera(K[0, 0], K[1, 1], K[0, 2] + 0.5, K[1, 2] + 0.5, znear=znear, zfar=zfar)
    np.testing.assert_allclose(projection_matrix(K, w, h, znear, zfar), ref.get_projection_matrix(w, h),
                               rtol=1e-12, atol=1e-12)


@st.composite
def small_lenses(draw):
    """(K, dist, width, height) of a small image with a lens that does not fold over."""
    from pipeline.rectify import check_lens
    from scene import Camera

    w, h = draw(st.integers(8, 96)), draw(st.integers(8, 96))
    f = w / 2 / np.tan(draw(st.floats(np.radians(20), np.radians(90))) / 2)
    cx = (w - 1) / 2 + draw(st.floats(-0.1, 0.1)) * w
    cy = (h - 1) / 2 + draw(st.floats(-0.1, 0.1)) * h
    K = np.array([[f, 0, cx], [0, f * draw(st.floats(0.9, 1.1)), cy], [0, 0, 1.0]])
    dist = np.array([draw(st.floats(-0.3, 0.3)), draw(st.floats(-0.1, 0.1)), draw(st.floats(-0.005, 0.005)),
                     draw(st.floats(-0.005, 0.005)), draw(st.floats(-0.05, 0.05))])
    try:
        check_lens(Camera(1, K, dist, np.eye(3), np.zeros(3), w, h))
    except ValueError:
        from hypothesis import reject
        reject()
    return K, dist, w, h


@settings(max_examples=100, deadline=None)
@given(small_lenses())
def test_distortion_map_sends_every_pixel_to_the_canvas_pixel_of_its_ray(lens):
    """Each output pixel reads, on the ideal canvas, the ray that cv2.projectPoints(K, dist)
    sends back to that very pixel; and it reads inside the canvas (no smeared border)."""
    from render.distortion import distortion_maps

    K, dist, w, h = lens
    maps = distortion_maps(K, dist, w, h)
    cw, ch = maps.canvas_size
    xy = maps.map_xy.reshape(-1, 2).astype(float)
    assert np.all(xy >= 0) and np.all(xy <= [cw - 1, ch - 1])
    rays = np.linalg.solve(maps.canvas_K(K), np.column_stack([xy, np.ones(len(xy))]).T).T
    back = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, dist)[0].reshape(-1, 2)
    v, u = np.mgrid[0:h, 0:w]
    # within 1e-4 px: the undistortion is exact to 1e-9 px (Newton steps after
    # cv2.undistortPoints, whose iterations alone stopped up to 0.2 px short in these lenses),
    # the float32 map's rounding is the rest (at most 4.5e-5 px in 3600 such lenses)
    np.testing.assert_allclose(back, np.column_stack([u.ravel(), v.ravel()]), atol=1e-4)


def test_the_default_clipping_planes_are_5_cm_and_50_m():
    """Depth 0.05 m in front of the lens maps to NDC z = -1 (the near plane), 50 m to +1 (far)."""
    K = np.array([[500.0, 0, 319.5], [0, 500.0, 239.5], [0, 0, 1]])
    points = np.array([[0.0, 0.0, 0.05, 1.0], [0.0, 0.0, 50.0, 1.0], [0.01, -0.02, 1.0, 1.0]])  # OpenCV camera
    clip = (projection_matrix(K, 640, 480) @ view_matrix(np.eye(3), np.zeros(3)) @ points.T).T
    ndc_z = clip[:, 2] / clip[:, 3]
    np.testing.assert_allclose(ndc_z[:2], [-1.0, 1.0], atol=1e-12)
    assert -1.0 < ndc_z[2] < 1.0


def test_a_skew_in_K_is_left_out_as_projectpoints_leaves_it_out():
    """A skew K[0, 1] changes neither the projection matrix nor where project_opengl puts a
    point: both agree with cv2.projectPoints, which leaves the skew out (docs/conventions.md)."""
    K = np.array([[500.0, 0.0, 300.0], [0.0, 480.0, 200.0], [0.0, 0.0, 1.0]])
    skewed = K.copy()
    skewed[0, 1] = 40.0
    np.testing.assert_array_equal(projection_matrix(skewed, 640, 480), projection_matrix(K, 640, 480))
    R, _ = cv2.Rodrigues(np.array([0.1, -0.2, 0.3]))
    t = np.array([0.2, -0.1, 3.0])
    pts = np.random.default_rng(0).uniform(-1.0, 1.0, (20, 3))
    expected = cv2.projectPoints(pts, cv2.Rodrigues(R)[0], t, skewed, None)[0].reshape(-1, 2)
    np.testing.assert_allclose(expected, cv2.projectPoints(pts, cv2.Rodrigues(R)[0], t, K, None)[0].reshape(-1, 2))
    np.testing.assert_allclose(project_opengl(pts, R, t, skewed, 640, 480), expected, atol=1e-6)


@pytest.mark.parametrize("call, message", [
    (lambda: opencv_to_opengl_pose(np.eye(3)[:2], np.zeros(3)), r"R: expected shape \(3, 3\), got \(2, 3\)"),
    (lambda: opencv_to_opengl_pose(np.eye(3), [0.0, np.nan, 0.0]), "t: expected finite numbers"),
    (lambda: view_matrix(np.eye(4), np.zeros(3)), r"R: expected shape \(3, 3\), got \(4, 4\)"),
    (lambda: view_matrix(np.eye(3), np.zeros(4)), r"t: expected shape \(3,\), got \(4,\)"),
    (lambda: projection_matrix([[500, 0, "320"], [0, 500, 240], [0, 0, 1]], 640, 480), "K: expected numbers"),
    (lambda: projection_matrix(np.eye(3)[:, :2], 640, 480), r"K: expected shape \(3, 3\)"),
    (lambda: project_opengl(np.zeros((4, 2)), np.eye(3), np.zeros(3), np.eye(3), 8, 8),
     r"points_world: expected shape \(n, 3\), got \(4, 2\)"),
    (lambda: project_opengl([[0.0, 0.0, np.inf]], np.eye(3), np.zeros(3), np.eye(3), 8, 8),
     "points_world: expected finite numbers"),
    (lambda: project_opengl(np.ones((1, 3)), np.eye(3), [0.0, 0.0, np.nan], np.eye(3), 8, 8), "t: expected finite"),
])
def test_bad_matrices_are_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()
