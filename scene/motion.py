"""The paper's random-waypoint walking model for disc-shaped people.

Each person is a disc of radius ``radii[i]`` (metres). A person picks a random
destination it can reach (a point of the room shrunk by its radius), walks there in a
straight line at constant speed and, on arrival, picks a new one. When two people would
collide, each circles around the other *to its right*: its velocity becomes the
tangent to the other person, rotated clockwise from the direction towards them.
The model is enforced, not hoped for: after every proposed step the new position is
checked (inside the room by at least the radius, no overlap with anyone) and the step is
shortened, down to standing still, until it is valid. People therefore never leave the
room and never overlap.

Positions are metres in the world frame, time in seconds, speeds in m/s.

>>> import numpy as np
>>> from shapely.geometry import box
>>> room = box(0.0, 0.0, 4.0, 3.0)
>>> pos = random_waypoint(room, [0.2, 0.2, 0.3], n_steps=50, dt=0.1, speed=1.0,
...                       rng=np.random.default_rng(7))
>>> pos.shape
(50, 3, 2)
>>> bool(np.all(np.linalg.norm(pos[1:] - pos[:-1], axis=-1) <= 0.1 + 1e-12))
True
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon

from .checks import check_positive

__all__ = ["circle_polygon", "random_drop", "random_waypoint"]

#: Tolerance (metres) on the no-overlap and inside-room constraints.
_EPS = 1e-9


def circle_polygon(radius: float = 1.0, n_vertices: int = 720, center=(0.0, 0.0)) -> Polygon:
    """A circle of ``radius`` metres as a regular ``n_vertices``-gon (counter-clockwise).

    >>> round(circle_polygon(1.0, 4).area, 6)
    2.0
    """
    r = check_positive("radius", radius)
    a = np.linspace(0.0, 2.0 * np.pi, int(n_vertices), endpoint=False)
    return Polygon(np.column_stack([center[0] + r * np.cos(a), center[1] + r * np.sin(a)]))


# ----------------------------------------------------------------------------- checks
def _check_radii(radii) -> np.ndarray:
    r = np.array(radii, dtype=float, ndmin=1)
    if r.ndim != 1:
        raise ValueError(f"radii: expected shape (m,), got {r.shape}")
    if not np.all(np.isfinite(r)) or np.any(r <= 0):
        raise ValueError("radii: expected finite numbers > 0")
    return r


def _check_room(room) -> Polygon:
    if not isinstance(room, Polygon) or room.is_empty or not room.is_valid:
        raise ValueError("room: expected a valid, non-empty shapely Polygon")
    return room


def _inner_regions(room: Polygon, radii: np.ndarray) -> list[Polygon]:
    """The room shrunk by each radius: where that person's centre may be."""
    cache: dict[float, Polygon] = {}
    out = []
    for r in radii:
        key = float(r)
        if key not in cache:
            inner = room.buffer(-key, quad_segs=32)
            shapely.prepare(inner)
            cache[key] = inner
        out.append(cache[key])
    return out


def _sample_in(region: Polygon, rng: np.random.Generator, max_tries: int) -> np.ndarray | None:
    """A uniform random point of ``region`` by rejection from its bounding box."""
    x0, y0, x1, y1 = region.bounds
    for _ in range(max(1, max_tries // 64)):
        pts = rng.uniform((x0, y0), (x1, y1), size=(64, 2))
        inside = shapely.contains_xy(region, pts[:, 0], pts[:, 1])
        if inside.any():
            return pts[np.argmax(inside)]
    return None


# ----------------------------------------------------------------------------- drop
def random_drop(room: Polygon, radii, rng: np.random.Generator, max_tries: int = 2000) -> np.ndarray:
    """Drop discs at random, without overlap, each inside the room by at least its radius.

    Discs are placed one after the other, each uniformly in the room shrunk by its
    radius; a candidate overlapping an earlier disc is removed and dropped again (at most
    ``max_tries`` times per disc).

    room : shapely Polygon, metres
    radii : (m,) float, metres
    rng : np.random.Generator
    returns centres : (m, 2) float, metres

    Raises ``ValueError`` when the room cannot hold the discs.

    >>> c = random_drop(circle_polygon(1.0), [0.1] * 5, np.random.default_rng(0))
    >>> c.shape
    (5, 2)
    """
    room = _check_room(room)
    radii = _check_radii(radii)
    max_tries = int(max_tries)
    if max_tries < 1:
        raise ValueError(f"max_tries: expected an integer >= 1, got {max_tries}")
    if np.sum(np.pi * radii**2) > room.area:
        raise ValueError(
            f"radii: {len(radii)} discs of total area {np.sum(np.pi * radii**2):.3g} m^2 "
            f"cannot fit in a room of area {room.area:.3g} m^2"
        )
    inner = _inner_regions(room, radii)
    centres = np.zeros((len(radii), 2))
    for i, r in enumerate(radii):
        if inner[i].is_empty:
            raise ValueError(f"radii: a disc of radius {r} does not fit in the room")
        for _ in range(max_tries):
            p = _sample_in(inner[i], rng, 64 * 16)
            if p is None:
                raise ValueError(f"radii: could not place a disc of radius {r} in the room")
            d = np.linalg.norm(centres[:i] - p, axis=1)
            if np.all(d >= radii[:i] + r):
                centres[i] = p
                break
        else:
            raise ValueError(
                f"radii: could not drop {len(radii)} non-overlapping discs in the room "
                f"(gave up on disc {i + 1} after {max_tries} tries); the room is too crowded"
            )
    return centres


# ----------------------------------------------------------------------------- walk
def _destination(i: int, region: Polygon, radius: float, rng: np.random.Generator) -> np.ndarray:
    """A random destination for person ``i`` (0-based) in ``region``, or a one-line ValueError."""
    p = _sample_in(region, rng, 4096)
    if p is None:
        raise ValueError(f"radii: could not draw a destination for person {i + 1} (radius {radius}) in the room")
    return p


def _valid_position(i, p, positions, radii, inner) -> bool:
    if not shapely.contains_xy(inner[i], p[0], p[1]):
        return False
    d = np.linalg.norm(positions - p, axis=1)
    d[i] = np.inf
    return bool(np.all(d >= radii + radii[i] - _EPS))


def _proposals(pos: np.ndarray, dest: np.ndarray, radii: np.ndarray, step_len: np.ndarray):
    """Everyone's next position before the room and the others are checked.

    pos, dest : (m, 2) float, metres; radii, step_len : (m,) float, metres
    Returns (proposal (m, 2) float, metres; arrive (m,) bool: the proposal is the
    destination). A person heads for its destination, or, with someone within
    ``2 * step_len`` of touching it, between it and its destination and approached, walks
    along the tangent around the nearest such person, turned clockwise.
    """
    m = len(radii)
    if m == 0:                                   # nobody: no pair to steer around
        return pos.copy(), np.zeros(0, bool)
    to_dest = dest - pos
    dist = np.linalg.norm(to_dest, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        heading = np.where(dist[:, None] > 0, to_dest / dist[:, None], 0.0)
    # Right-hand avoidance: vectorised over pairs.
    diff = pos[None, :, :] - pos[:, None, :]  # (m, m, 2) from i to j
    centre_dist = np.linalg.norm(diff, axis=2)
    gap = centre_dist - radii[:, None] - radii[None, :]
    np.fill_diagonal(gap, np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        towards = diff / centre_dist[:, :, None]
    approaching = np.einsum("ik,ijk->ij", heading, np.nan_to_num(towards)) > 0
    threat = (gap < 2.0 * step_len[:, None] + _EPS) & approaching
    # Only steer around someone standing between us and our destination.
    threat &= centre_dist < dist[:, None] + radii[None, :]
    gap_masked = np.where(threat, gap, np.inf)
    nearest = np.argmin(gap_masked, axis=1)
    avoid = np.isfinite(gap_masked[np.arange(m), nearest])
    u = towards[np.arange(m), nearest]
    right = np.column_stack([u[:, 1], -u[:, 0]])  # u rotated by -90 deg (clockwise)
    velocity = np.where(avoid[:, None], right, heading)
    arrive = (~avoid) & (dist <= step_len)
    return np.where(arrive[:, None], dest, pos + velocity * step_len[:, None]), arrive


def random_waypoint(
    room: Polygon,
    radii,
    n_steps: int,
    dt: float,
    speed,
    rng: np.random.Generator,
    initial=None,
    *,
    patience: int = 20,
    progress=None,
) -> np.ndarray:
    """Walk discs by the random-waypoint model with right-hand collision avoidance.

    room : shapely Polygon, metres (the circular room as a fine polygon, or the lab)
    radii : (m,) float, metres
    n_steps : int, number of time steps returned (the first is ``initial``)
    dt : float, seconds per step
    speed : float or (m,) float, m/s
    rng : np.random.Generator (same generator state, same trajectory)
    initial : (m, 2) float, metres, or None to :func:`random_drop` the discs
    patience : steps a person may stay blocked before choosing a new destination
    progress : optional callable, called with 1 after each step drawn (a progress bar's
        ``update``: a long walk takes ~0.2 ms a step for 3 people, ~4 ms for 49)
    returns positions : (n_steps, m, 2) float, metres

    A person within one step of its destination stops there and picks a new one. A
    person whose straight step would bring it within ``2 * speed * dt`` of touching
    another (while approaching) instead walks along the tangent around that person,
    turned clockwise (to its right). Every step is then shortened by halving, down to
    not moving, until the new position is inside the room by the radius and overlaps
    nobody.

    Raises ``ValueError`` when the room cannot hold the discs or no destination can be
    drawn for one of them (a room whose shrunk region is a sliver of its bounding box).
    """
    room = _check_room(room)
    radii = _check_radii(radii)
    m = len(radii)
    n_steps = int(n_steps)
    if n_steps < 1:
        raise ValueError(f"n_steps: expected an integer >= 1, got {n_steps}")
    dt = check_positive("dt", dt)
    speeds = np.broadcast_to(np.asarray(speed, dtype=float), (m,)).copy()
    if not np.all(np.isfinite(speeds)) or np.any(speeds < 0):
        raise ValueError("speed: expected finite numbers >= 0")
    inner = _inner_regions(room, radii)
    if initial is None:
        pos = random_drop(room, radii, rng)
    else:
        pos = np.array(initial, dtype=float)
        if pos.shape != (m, 2) or not np.all(np.isfinite(pos)):
            raise ValueError(f"initial: expected finite numbers of shape ({m}, 2), got {pos.shape}")
        for i in range(m):
            if not _valid_position(i, pos[i], pos, radii, inner):
                raise ValueError(
                    f"initial: person {i + 1} overlaps another or is not inside the room by its radius"
                )

    dest = np.array([_destination(i, inner[i], radii[i], rng) for i in range(m)]).reshape(m, 2)
    blocked = np.zeros(m, dtype=int)
    out = np.empty((n_steps, m, 2))
    out[0] = pos
    for t in range(1, n_steps):
        step_len = speeds * dt
        proposal, arrive = _proposals(pos, dest, radii, step_len)

        # Enforce the constraints person by person against everyone's latest position.
        for i in range(m):
            delta = proposal[i] - pos[i]
            moved = False
            for frac in (1.0, 0.5, 0.25, 0.125, 0.0625):
                p = pos[i] + frac * delta
                if _valid_position(i, p, pos, radii, inner):
                    moved = frac == 1.0 or np.linalg.norm(frac * delta) > 0.1 * step_len[i]
                    pos[i] = p
                    break
            if arrive[i] and np.allclose(pos[i], dest[i]):
                dest[i] = _destination(i, inner[i], radii[i], rng)
                blocked[i] = 0
            elif not moved and speeds[i] > 0:
                blocked[i] += 1
                if blocked[i] >= patience:
                    dest[i] = _destination(i, inner[i], radii[i], rng)
                    blocked[i] = 0
            else:
                blocked[i] = 0
        out[t] = pos
        if progress is not None:
            progress(1)
    return out
