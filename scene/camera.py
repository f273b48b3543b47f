"""Cameras: calibrated pinhole cameras (the lab) and floor-plane cameras (the circle).

Calibration (K, distortion, R, t) is the single source of truth: the renderer, the
image pipeline and the exported calibration files all read it from :class:`Camera`.
OpenCV convention: x right, y down, z forward; ``X_cam = R @ X_world + t``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import cv2
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


#: Newton steps at most that polish ``cv2.undistortPoints`` in :func:`undistort_points`
#: (each roughly squares the error; a step that does not lower a point's error is halved,
#: and tried again, up to this many times in all).
NEWTON_STEPS = 40
#: Pixels: a point whose ray projects nearer than this to it is left as OpenCV undistorted it.
POLISHED = 1e-9


def distort_normalised(xy: np.ndarray, dist) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's 5-coefficient lens model on ideal normalised coordinates, with its Jacobian.

    xy : (m, 2) float, ideal rays' (x / z, y / z); dist : (k1, k2, p1, p2, k3)
    Returns (m, 2) distorted normalised coordinates, as ``cv2.projectPoints`` computes them
    before the camera matrix, and (m, 2, 2) their derivatives d(x_d, y_d) / d(x, y).
    """
    k1, k2, p1, p2, k3 = np.asarray(dist, float).ravel()[:5]
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    slope = k1 + r2 * (2 * k2 + 3 * k3 * r2)                  # d radial / d r2
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    cross = 2 * x * y * slope + 2 * p1 * x + 2 * p2 * y
    J = np.empty((len(x), 2, 2))
    J[:, 0, 0] = radial + 2 * x * x * slope + 2 * p1 * y + 6 * p2 * x
    J[:, 0, 1] = J[:, 1, 0] = cross
    J[:, 1, 1] = radial + 2 * y * y * slope + 6 * p1 * y + 2 * p2 * x
    return np.stack([xd, yd], 1), J


def undistort_points(uv, K, dist, eps: float = 1e-12) -> np.ndarray:
    """Ideal normalised coordinates (m, 2) (x / z, y / z) of distorted pixels ``uv`` (m, 2).

    ``cv2.undistortPoints`` (fixed-point iterations, at most 100, until the ray projects
    within ``eps`` pixels of the pixel), then, for the points whose ray does not
    project back to within :data:`POLISHED` pixels of them, damped Newton steps on the
    distortion model (:func:`distort_normalised`), from OpenCV's ray and, where that does
    not reach a ray on which the lens keeps its orientation, from the inverse of the radial
    factor alone (:func:`_radial_start`). OpenCV's iterations stop short in the corners of
    strong lenses (0.015 px at a corner of the lab's image with k1 = -0.4476, up to 0.46 px
    in small images whose lenses ``pipeline.rectify.check_lens`` accepted), or wander off
    towards another ray; this takes every pixel that has a ray to within 1e-9 px of it
    (points OpenCV got there are returned as it gave them). Points OpenCV leaves NaN stay
    NaN. As OpenCV, this ignores the skew K[0, 1].
    """
    pts = np.asarray(uv, dtype=float).reshape(-1, 2)
    dist = np.asarray(dist, float).ravel()
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, eps)
    xy = cv2.undistortPoints(pts.reshape(-1, 1, 2), K, dist, None, None, None, criteria).reshape(-1, 2)
    if not np.any(dist) or not len(xy):
        return xy
    f = np.array([K[0, 0], K[1, 1]])
    target = (pts - [K[0, 2], K[1, 2]]) / f
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        todo = np.flatnonzero(_miss(xy, target, dist, f)[2] > POLISHED)     # NaN: left alone
        if not todo.size:
            return xy
        target = target[todo]
        sub, err, det = _newton(xy[todo], target, dist, f)
        retry = np.flatnonzero(~((err <= POLISHED) & (det > 0)))
        if retry.size:
            alt, err_alt, det_alt = _newton(_radial_start(target[retry], dist), target[retry], dist, f)
            good, good_alt = (err[retry] <= POLISHED) & (det[retry] > 0), (err_alt <= POLISHED) & (det_alt > 0)
            take = (good_alt & ~good) | ((good_alt == good) & (err_alt < err[retry]))
            sub[retry[take]] = alt[take]
    xy[todo] = sub
    return xy


def _miss(xy, target, dist, f):
    """Residual (m, 2) normalised, Jacobian (m, 2, 2) and error (m,) pixels of rays ``xy``."""
    d, J = distort_normalised(xy, dist)
    r = d - target
    return r, J, np.hypot(*(r * f).T)


def _newton(xy, target, dist, f):
    """Damped Newton steps from rays ``xy`` (m, 2) towards the distorted ``target`` (m, 2):
    each step is kept for a point only where it lowers its error, else halved. Returns the
    rays, their errors (pixels) and Jacobian determinants, (m, 2), (m,), (m,)."""
    xy = xy.copy()
    r, J, err = _miss(xy, target, dist, f)
    scale = np.ones(len(xy))
    for _ in range(NEWTON_STEPS):
        live = err > POLISHED
        if not live.any():
            break
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        step = np.stack([J[:, 1, 1] * r[:, 0] - J[:, 0, 1] * r[:, 1],
                         J[:, 0, 0] * r[:, 1] - J[:, 1, 0] * r[:, 0]], 1) / det[:, None]
        trial = xy - scale[:, None] * step
        r_new, J_new, err_new = _miss(trial, target, dist, f)
        better = live & (err_new < err)                         # False for NaN
        xy[better], r[better], J[better], err[better] = trial[better], r_new[better], J_new[better], err_new[better]
        scale = np.where(better, np.minimum(1.0, 2 * scale), scale / 2)
    return xy, err, J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]


def _radial_start(target, dist) -> np.ndarray:
    """Rays (m, 2) along the distorted points ``target`` (m, 2), at the radius r that the
    radial factor alone sends to theirs, ``r (1 + k1 r^2 + k2 r^4 + k3 r^6) = |target|``,
    on its rising branch from the centre (bisection; its end where it never gets there)."""
    k1, k2, _, _, k3 = dist[:5]
    rd = np.hypot(*target.T)
    roots = np.roots([7 * k3, 5 * k2, 3 * k1, 1.0])               # slope in s = r^2, highest power first
    real = roots.real[np.abs(roots.imag) <= 1e-12 * np.maximum(1.0, np.abs(roots.real))]
    real = real[real > 0]
    hi = np.full(len(rd), np.sqrt(real.min()) if real.size else np.inf)
    grow = lambda r: r * (1 + r * r * (k1 + r * r * (k2 + r * r * k3)))
    if not real.size:                                              # rising for ever: bracket by doubling
        hi = np.maximum(rd, 1.0)
        for _ in range(64):
            short = grow(hi) < rd
            if not short.any():
                break
            hi = np.where(short, 2 * hi, hi)
    lo = np.zeros(len(rd))
    for _ in range(60):
        mid = (lo + hi) / 2
        below = grow(mid) < rd
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    scale = np.where(rd > 0, hi / np.where(rd > 0, rd, 1.0), 1.0)
    return target * scale[:, None]


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


#: The narrowest and widest field of view of a floor camera (a ring's), degrees. Floor cameras feed only the
#: tasking geometry, which drops free intervals narrower than 1e-10 radians as rounding noise
#: (tasking.cones.MIN_GAP, 5.7e-9 degrees): at 1e-9 degrees (and 1e-300) every camera silently
#: saw nothing, the hull was the whole room and the greedy tasker chose by ties. At 1e-6 a
#: camera's view is 175 times that: an interval it drops is under 0.6 % of its view.
FLOOR_FOV_RANGE = (1e-6, 180.0)


@dataclass(frozen=True, eq=False)
class FloorCamera:
    """A camera known only by its floor-plane pose (the paper's circular simulation).

    number : 1-based camera number
    xy : (2,) float, metres, world frame
    yaw : float, radians, viewing direction
    fov : float, radians, in [1e-6, 180] degrees (:data:`FLOOR_FOV_RANGE`)
    """

    number: int
    xy: np.ndarray
    yaw: float
    fov: float

    def __post_init__(self):
        check_int("camera.number", self.number, minimum=1)
        object.__setattr__(self, "xy", readonly(check_array("camera.xy", self.xy, (2,))))
        fov = np.degrees(check_positive("camera.fov", self.fov))
        low, high = FLOOR_FOV_RANGE
        if not low <= fov <= high + 1e-10:
            raise ValueError(f"camera.fov: expected a field of view in [{low:g}, {high:g}] degrees, got {fov:g}")

    @property
    def name(self) -> str:
        return f"cam{self.number:02d}"
