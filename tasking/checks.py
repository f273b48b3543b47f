"""Boundary validation for the tasking core.

Every public function of :mod:`tasking` converts and checks its inputs with these
helpers, which raise a one-line ``ValueError`` naming the parameter and what was
expected. Nothing here uses ``assert``.

String choices go through the project's one helper, :func:`scene.checks.check_choice`:

>>> check_choice("tasker", "best", ("uniform", "greedy"))
Traceback (most recent call last):
    ...
ValueError: tasker: unknown value 'best'; expected one of uniform, greedy
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from scene.checks import check_choice

__all__ = [
    "check_angles",
    "check_camera_radii",
    "check_cameras_outside_discs",
    "check_choice",
    "check_discs_disjoint",
    "check_discs_in_room",
    "check_fov",
    "check_indices",
    "check_int",
    "check_points",
    "check_radii",
    "check_room",
]


def _floats(name: str, value) -> np.ndarray:
    """``np.asarray(value, dtype=float)``, its conversion errors naming ``name``.

    >>> _floats("fov", "wide")
    Traceback (most recent call last):
        ...
    ValueError: fov must be numbers (an array of floats); got str
    >>> _floats("centers", [[0, 0], [1]])
    Traceback (most recent call last):
        ...
    ValueError: centers must be an array of floats, its rows of one length; got rows of different lengths
    """
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        if "inhomogeneous" in str(e):
            raise ValueError(f"{name} must be an array of floats, its rows of one length; got rows of different "
                             "lengths") from None
        raise ValueError(f"{name} must be numbers (an array of floats); got {type(value).__name__}") from None


def check_points(name: str, points, *, allow_empty: bool = False) -> np.ndarray:
    """Convert to a ``(n, 2)`` float array of finite coordinates.

    >>> check_points("centers", [[0, 0], [1, 2]]).shape
    (2, 2)
    >>> check_points("centers", [0, 1, 2])
    Traceback (most recent call last):
        ...
    ValueError: centers must have shape (n, 2); got shape (3,)
    """
    arr = _floats(name, points)
    if arr.ndim == 1 and arr.size == 0 and allow_empty:
        return arr.reshape(0, 2)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"{name} must have shape (n, 2); got shape {arr.shape}")
    if arr.shape[0] == 0 and not allow_empty:
        raise ValueError(f"{name} must not be empty")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf coordinates)")
    return arr


def check_angles(name: str, angles, n: int) -> np.ndarray:
    """Convert to a finite ``(n,)`` float array of angles, radians."""
    arr = _floats(name, angles)
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},); got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return arr


def check_fov(fov, n: int) -> np.ndarray:
    """Broadcast ``fov`` (scalar or ``(n,)``, radians) to ``(n,)`` within (0, 2*pi)."""
    arr = _floats("fov", fov)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"fov must be a scalar or have shape ({n},); got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("fov must be finite (no NaN or inf)")
    if np.any(arr <= 0) or np.any(arr >= 2 * np.pi):
        raise ValueError(f"fov must be in (0, 2*pi) radians; got {arr.min():g}..{arr.max():g}")
    return arr


def check_radii(name: str, radii, m: int) -> np.ndarray:
    """Broadcast ``radii`` (scalar or ``(m,)``, metres) to ``(m,)``, all > 0."""
    arr = _floats(name, radii)
    if arr.ndim == 0:
        arr = np.full(m, float(arr))
    if arr.shape != (m,):
        raise ValueError(f"{name} must be a scalar or have shape ({m},); got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"{name} must be finite and > 0")
    return arr


def check_camera_radii(name: str, radii, n: int) -> np.ndarray:
    """Broadcast a camera's blind or sight radii ``radii`` (scalar or ``(n,)``, metres) to
    ``(n,)``, all >= 0 (``inf`` allowed)."""
    arr = _floats(name, radii)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have shape ({n},); got shape {arr.shape}")
    if np.any(np.isnan(arr)) or np.any(arr < 0):
        raise ValueError(f"{name} must be >= 0 metres (inf allowed), not NaN")
    return arr


def check_room(room) -> Polygon:
    """Check that ``room`` is a valid, non-empty shapely Polygon."""
    if not isinstance(room, Polygon):
        raise ValueError(f"room must be a shapely Polygon; got {type(room).__name__}")
    if room.is_empty or room.area <= 0 or not room.is_valid:
        raise ValueError("room must be a valid Polygon with positive area")
    return room


def check_int(name: str, value, lo: int, hi: int | None = None) -> int:
    """Return ``value`` as int, checking ``lo <= value (<= hi)``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer; got {value!r}")
    value = int(value)
    if value < lo or (hi is not None and value > hi):
        upper = "" if hi is None else f" and <= {hi}"
        raise ValueError(f"{name} must be >= {lo}{upper}; got {value}")
    return value


def check_indices(name: str, indices, n: int, size: int | None = None) -> np.ndarray:
    """Convert to a sorted ``(size,)`` int array of distinct 0-based indices below ``n``."""
    arr = np.asarray(indices)
    if arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
        raise ValueError(f"{name} must be a 1-D sequence of integer indices")
    arr = arr.astype(np.intp)
    if size is not None and arr.size != size:
        raise ValueError(f"{name} must hold {size} indices; got {arr.size}")
    if arr.size and (arr.min() < 0 or arr.max() >= n):
        raise ValueError(f"{name} must be 0-based indices in [0, {n - 1}]")
    if np.unique(arr).size != arr.size:
        raise ValueError(f"{name} must not repeat an index")
    return np.sort(arr)


def check_discs_disjoint(centers: np.ndarray, radii: np.ndarray, name: str = "centers") -> None:
    """Raise if two discs overlap (touching is allowed, up to 1e-12 m)."""
    if centers.shape[0] < 2:
        return
    diff = centers[:, None, :] - centers[None, :, :]
    dist = np.hypot(diff[..., 0], diff[..., 1])
    overlap = dist < radii[:, None] + radii[None, :] - 1e-12
    np.fill_diagonal(overlap, False)
    if overlap.any():
        i, j = np.argwhere(overlap)[0]
        raise ValueError(f"{name}: objects {i} and {j} overlap (distance {dist[i, j]:.6g} m)")


def check_discs_in_room(centers: np.ndarray, room: BaseGeometry, name: str = "centers") -> None:
    """Raise if a disc centre lies outside the room (its boundary counts as inside)."""
    inside = shapely.covers(room, shapely.points(centers))
    if not np.all(inside):
        i = int(np.flatnonzero(~inside)[0])
        raise ValueError(f"{name}: object {i} at {centers[i].tolist()} is outside the room")


def check_cameras_outside_discs(
    camera_xy: np.ndarray, centers: np.ndarray, radii: np.ndarray
) -> None:
    """Raise if a camera centre lies strictly inside an object disc."""
    if centers.shape[0] == 0:
        return
    diff = camera_xy[:, None, :] - centers[None, :, :]
    dist = np.hypot(diff[..., 0], diff[..., 1])
    inside = dist < radii[None, :] - 1e-12
    if inside.any():
        c, j = np.argwhere(inside)[0]
        raise ValueError(f"camera_xy: camera {c} is inside object {j}")
