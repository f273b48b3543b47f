"""From OpenCV calibration to OpenGL camera matrices (pure numpy).

OpenCV cameras: x right, y down, z forward; ``X_cam = R @ X_world + t``; pixel centres
at integer (u, v). OpenGL / pyrender cameras: x right, y up, z backward; pixel centres
at half-integer window coordinates. :data:`CV_TO_GL` is the one axis flip, applied by
:func:`opencv_to_opengl_pose` and by its inverse :func:`view_matrix` (what the renderer
uses); :func:`projection_matrix` equals pyrender's ``IntrinsicsCamera``
projection with the principal point moved by half a pixel, so that a world point lands
on the pixel ``cv2.projectPoints`` (without distortion) gives it.

>>> import numpy as np
>>> pose = opencv_to_opengl_pose(np.eye(3), np.zeros(3))
>>> pose[:3, :3].astype(int).tolist()
[[1, 0, 0], [0, -1, 0], [0, 0, -1]]
"""

from __future__ import annotations

import numpy as np

from scene.checks import check_array

#: Diagonal that turns OpenCV camera axes into OpenGL camera axes (and back).
CV_TO_GL = np.diag([1.0, -1.0, -1.0])


def opencv_to_opengl_pose(R, t) -> np.ndarray:
    """pyrender camera pose (camera-to-world, OpenGL axes) from OpenCV extrinsics.

    R : (3, 3) float, rotation world -> camera (OpenCV axes)
    t : (3,) float, metres, translation world -> camera
    Returns (4, 4) float: columns 0-2 are the OpenGL camera's x (right), y (up) and
    z (backward) axes in world coordinates, column 3 the camera centre, metres.
    """
    R = check_array("R", R, (3, 3))
    t = check_array("t", t, (3,))
    pose = np.eye(4)
    pose[:3, :3] = R.T @ CV_TO_GL
    pose[:3, 3] = -R.T @ t
    return pose


def view_matrix(R, t) -> np.ndarray:
    """World -> OpenGL camera transform, (4, 4) float: the inverse of the pose."""
    R = check_array("R", R, (3, 3))
    t = check_array("t", t, (3,))
    view = np.eye(4)
    view[:3, :3] = CV_TO_GL @ R
    view[:3, 3] = CV_TO_GL @ t
    return view


def projection_matrix(K, width: int, height: int, znear: float = 0.05, zfar: float = 50.0,
                      flip_rows: bool = False) -> np.ndarray:
    """OpenGL projection (4, 4) for OpenCV intrinsics ``K`` on a ``width`` x ``height`` viewport.

    Equal to ``pyrender.IntrinsicsCamera(fx, fy, cx + 0.5, cy + 0.5, znear, zfar)
    .get_projection_matrix(width, height)``. With ``flip_rows`` the image is drawn upside
    down, so that ``glReadPixels`` returns rows top first (row 0 = v in [0, 1)).
    """
    K = check_array("K", K, (3, 3))
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2] + 0.5, K[1, 2] + 0.5
    P = np.zeros((4, 4))
    P[0, 0] = 2.0 * fx / width
    P[1, 1] = 2.0 * fy / height
    P[0, 2] = 1.0 - 2.0 * cx / width
    P[1, 2] = 2.0 * cy / height - 1.0
    P[2, 2] = (zfar + znear) / (znear - zfar)
    P[2, 3] = 2.0 * zfar * znear / (znear - zfar)
    P[3, 2] = -1.0
    if flip_rows:
        P[1] *= -1.0
    return P


def project_opengl(points_world, R, t, K, width: int, height: int) -> np.ndarray:
    """Pixel coordinates (u, v) of ``points_world`` (n, 3) through the OpenGL matrices.

    Returns (n, 2) float, OpenCV pixel coordinates (u = col, v = row, pixel centres at
    integers). Used to check the conversion against ``cv2.projectPoints``.
    """
    pts = check_array("points_world", points_world, (None, 3))
    clip = (projection_matrix(K, width, height) @ view_matrix(R, t)
            @ np.column_stack([pts, np.ones(len(pts))]).T).T
    ndc = clip[:, :3] / clip[:, 3:4]
    window_x = (ndc[:, 0] + 1.0) / 2.0 * width       # pixel centres at i + 0.5
    window_y = (ndc[:, 1] + 1.0) / 2.0 * height      # counted from the bottom
    return np.column_stack([window_x - 0.5, (height - window_y) - 0.5])
