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
