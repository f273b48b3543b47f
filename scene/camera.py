"""Cameras: calibrated pinhole cameras (the lab) and floor-plane cameras (the circle).

Calibration (K, distortion, R, t) is the single source of truth: the renderer, the
image pipeline and the exported calibration files all read it from :class:`Camera`.
OpenCV convention: x right, y down, z forward; ``X_cam = R @ X_world + t``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .checks import check_array, check_int, check_positive, readonly


def rotation_from_yaw_pitch(yaw: float, pitch: float) -> np.ndarray:
    """World-to-camera rotation of a level camera turned by ``yaw`` and tilted down by ``pitch``.

    yaw : radians, world-frame direction of the optical axis on the floor (atan2(dy, dx))
    pitch : radians, positive looks down
    Returns R : (3, 3) float, rows are the camera x (right), y (down), z (forward) axes in
    world coordinates.

    >>> R = rotation_from_yaw_pitch(0.0, 0.0)
    >>> R @ np.array([1.0, 0.0, 0.0])   # world +x is straight ahead
    array([0., 0., 1.])
    """
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    forward = np.array([cp * cy, cp * sy, -sp])
    right = np.array([sy, -cy, 0.0])
    down = np.cross(forward, right)
    return np.stack([right, down, forward])


def intrinsics_from_fov(width: int, height: int, hfov: float, principal=None) -> np.ndarray:
    """Camera matrix K (3, 3), pixels, for square pixels and horizontal field of view ``hfov``.

    >>> K = intrinsics_from_fov(640, 480, np.radians(90))
    >>> round(float(K[0, 0]), 6)
    320.0
    """
    f = (width / 2.0) / np.tan(hfov / 2.0)
    cx, cy = principal if principal is not None else ((width - 1) / 2.0, (height - 1) / 2.0)
    return np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])


@dataclass(frozen=True, eq=False)
class Camera:
    """A calibrated pinhole camera.

    number : 1-based camera number
    K : (3, 3) float, pixels, intrinsic matrix
    dist : (5,) float, OpenCV distortion (k1, k2, p1, p2, k3)
    R : (3, 3) float, rotation world -> camera
    t : (3,) float, metres, translation world -> camera
    width, height : int, pixels
    """

    number: int
    K: np.ndarray
    dist: np.ndarray
    R: np.ndarray
    t: np.ndarray
    width: int
    height: int

    def __post_init__(self):
        check_int("camera.number", self.number, minimum=1)
        check_int("camera.resolution", self.width, minimum=1)
        check_int("camera.resolution", self.height, minimum=1)
        for name, shape in (("K", (3, 3)), ("dist", (5,)), ("R", (3, 3)), ("t", (3,))):
            object.__setattr__(self, name, readonly(check_array(f"camera.{name}", getattr(self, name), shape)))
        if not np.allclose(self.R @ self.R.T, np.eye(3), atol=1e-6) or np.linalg.det(self.R) < 0:
            raise ValueError("camera.R: expected a rotation matrix")
        K = self.K
        if not (K[0, 0] > 0 and K[1, 1] > 0 and K[1, 0] == 0 and np.array_equal(K[2], [0.0, 0.0, 1.0])):
            raise ValueError("camera.K: expected [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0")

    @staticmethod
    def from_pose(number, position_world, yaw, pitch, width, height, hfov, dist, principal=None) -> Camera:
        """A camera at ``position_world`` (3,) metres looking along ``yaw`` tilted down by ``pitch``."""
        R = rotation_from_yaw_pitch(yaw, pitch)
        c = check_array("camera.position", position_world, (3,))
        return Camera(number, intrinsics_from_fov(width, height, hfov, principal), np.asarray(dist, float),
                      R, -R @ c, width, height)

    @cached_property
    def center_world(self) -> np.ndarray:
        """Camera centre, (3,) float, metres, world frame."""
        return readonly(-self.R.T @ self.t)

    @property
    def xy(self) -> np.ndarray:
        """Floor-plane position, (2,) float, metres."""
        return self.center_world[:2]

    @property
    def yaw(self) -> float:
        """World-frame bearing (radians) of the optical axis projected on the floor."""
        forward = self.R[2]
        return float(np.arctan2(forward[1], forward[0]))

    @property
    def pitch(self) -> float:
        """Downward tilt of the optical axis, radians."""
        return float(-np.arcsin(np.clip(self.R[2, 2], -1, 1)))

    @property
    def hfov(self) -> float:
        """Horizontal field of view of the ideal pinhole, radians."""
        fx, cx = self.K[0, 0], self.K[0, 2]
        return float(np.arctan((cx + 0.5) / fx) + np.arctan((self.width - 0.5 - cx) / fx))

    @property
    def fov(self) -> float:
        """Alias of :attr:`hfov`: the floor-plane field of view used by tasking."""
        return self.hfov

    @property
    def name(self) -> str:
        """File-system name, ``camNN`` with NN counting from 01."""
        return f"cam{self.number:02d}"


@dataclass(frozen=True, eq=False)
class FloorCamera:
    """A camera known only by its floor-plane pose (the paper's circular simulation).

    number : 1-based camera number
    xy : (2,) float, metres, world frame
    yaw : float, radians, viewing direction
    fov : float, radians, in (0, pi]
    """

    number: int
    xy: np.ndarray
    yaw: float
    fov: float

    def __post_init__(self):
        check_int("camera.number", self.number, minimum=1)
        object.__setattr__(self, "xy", readonly(check_array("camera.xy", self.xy, (2,))))
        fov = check_positive("camera.fov", self.fov)
        if fov > np.pi + 1e-12:
            raise ValueError(f"camera.fov: expected a field of view in (0, 180] degrees, got {np.degrees(fov):g}")

    @property
    def name(self) -> str:
        return f"cam{self.number:02d}"
