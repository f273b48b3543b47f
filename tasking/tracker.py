"""A multi-object tracker on visual-hull polygon centres (the paper's section 6).

Detections are the centres of the hull polygons that survive small-polygon removal.
Tracks follow them with a constant-velocity Kalman filter; detections are assigned
to predicted tracks by gated minimum-cost matching (``scipy.optimize.linear_sum_assignment``).
Tracks are born tentative and confirmed after ``confirm_hits`` consecutive matches,
and end after ``max_missed`` consecutive misses (hysteresis). Phantom polygons that
appear and vanish from frame to frame never earn the hits that confirm a track: this
is the paper's future-work idea of pruning hull polygons with no temporal support, and
:meth:`Tracker.estimates` feeds the supported positions back to tasking. Phantoms are
intersections of real people's cones, though, so they move smoothly with the people and
often persist: with 6 of the lab's 16 cameras over half of them last 3 frames or more and
are confirmed (false positives dominate MOTA there, docs/network.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene.checks import check_array, check_int, check_positive


@dataclass(frozen=True)
class TrackerParams:
    """Tracker settings.

    dt : seconds between frames
    gate : metres; a detection farther than this from a track's prediction cannot match it
    confirm_hits : consecutive matches that confirm a tentative track
    max_missed : consecutive misses that end a track
    accel_std : metres / s^2, process noise of the constant-velocity model
    meas_std : metres, noise of a polygon centre as a position measurement
    """

    dt: float = 1 / 7.5
    gate: float = 0.5
    confirm_hits: int = 3
    max_missed: int = 3
    accel_std: float = 2.0
    meas_std: float = 0.08

    def __post_init__(self):
        for name in ("dt", "gate", "accel_std", "meas_std"):
            check_positive(f"tracker.{name}", getattr(self, name))
        check_int("tracker.confirm_hits", self.confirm_hits, minimum=1)
        check_int("tracker.max_missed", self.max_missed, minimum=1)


class Tracker:
    """Constant-velocity Kalman tracks over 2-D detections, batched over tracks.

    >>> tr = Tracker(TrackerParams(dt=1.0, confirm_hits=2))
    >>> for t in range(4):
    ...     ids, xy = tr.step(np.array([[0.1 * t, 0.0]]))
    >>> ids.tolist(), np.round(xy, 2).tolist()
    ([0], [[0.3, 0.0]])
    """

    def __init__(self, params: TrackerParams | None = None):
        self.params = params or TrackerParams()
        dt = self.params.dt
        self._F = np.array([[1, 0, dt, 0], [0, 1, 0, dt], [0, 0, 1, 0], [0, 0, 0, 1]], float)
        self._H = np.array([[1, 0, 0, 0], [0, 1, 0, 0]], float)
        g = np.array([[dt**2 / 2, 0], [0, dt**2 / 2], [dt, 0], [0, dt]])
        self._Q = self.params.accel_std**2 * g @ g.T
        self._R = self.params.meas_std**2 * np.eye(2)
        self.x = np.zeros((0, 4))          # (n, 4) state: x, y, vx, vy (metres, m/s)
        self.P = np.zeros((0, 4, 4))       # (n, 4, 4) covariances
        self.ids = np.zeros(0, int)        # (n,) track ids, never reused
        self.hits = np.zeros(0, int)       # (n,) consecutive matches
        self.missed = np.zeros(0, int)     # (n,) consecutive misses
        self.confirmed = np.zeros(0, bool) # (n,)
        self._next_id = 0

    def step(self, detections) -> tuple[np.ndarray, np.ndarray]:
        """Advance one frame with ``detections`` (p, 2) metres; return confirmed (ids, xy)."""
        z = np.asarray(detections, float)
        z = check_array("detections", z.reshape(0, 2) if z.size == 0 else z, (None, 2))
        self._predict()
        rows, cols = self._assign(z)
        self._update(rows, z[cols])
        matched = np.zeros(len(self.x), bool)
        matched[rows] = True
        self.hits = np.where(matched, self.hits + 1, 0)
        self.missed = np.where(matched, 0, self.missed + 1)
        self.confirmed |= self.hits >= self.params.confirm_hits
        alive = self.missed < self.params.max_missed
        # A tentative track that misses once is a phantom: drop it at once.
        alive &= self.confirmed | matched
        self._keep(alive)
        unmatched = np.setdiff1d(np.arange(len(z)), cols)
        self._birth(z[unmatched])
        return self.tracks()

    def tracks(self) -> tuple[np.ndarray, np.ndarray]:
        """Confirmed tracks that were seen this frame: ids (n,), positions (n, 2) metres."""
        keep = self.confirmed & (self.missed == 0)
        return self.ids[keep].copy(), self.x[keep, :2].copy()

    def estimates(self) -> np.ndarray:
        """Object estimates for tasking, (n, 2) metres: next-frame predictions of confirmed tracks."""
        return (self.x[self.confirmed] @ self._F.T)[:, :2]

    def _predict(self) -> None:
        self.x = self.x @ self._F.T
        self.P = self._F @ self.P @ self._F.T + self._Q

    def _assign(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # imported here: scipy.optimize takes ~0.5 s to import
        from scipy.optimize import linear_sum_assignment

        if len(self.x) == 0 or len(z) == 0:
            return np.zeros(0, int), np.zeros(0, int)
        cost = np.linalg.norm(self.x[:, None, :2] - z[None], axis=-1)
        # Confirmed tracks get first pick: a tiny bias breaks ties in their favour.
        biased = np.where(cost <= self.params.gate, cost - 1e-6 * self.confirmed[:, None], 1e6)
        rows, cols = linear_sum_assignment(biased)
        ok = cost[rows, cols] <= self.params.gate
        return rows[ok], cols[ok]

    def _update(self, rows: np.ndarray, z: np.ndarray) -> None:
        if len(rows) == 0:
            return
        H, P, x = self._H, self.P[rows], self.x[rows]
        S = H @ P @ H.T + self._R                          # (r, 2, 2)
        K = P @ H.T @ np.linalg.inv(S)                     # (r, 4, 2)
        innovation = z - x @ H.T                           # (r, 2)
        self.x[rows] = x + np.einsum("rij,rj->ri", K, innovation)
        self.P[rows] = (np.eye(4) - K @ H) @ P

    def _keep(self, mask: np.ndarray) -> None:
        for name in ("x", "P", "ids", "hits", "missed", "confirmed"):
            setattr(self, name, getattr(self, name)[mask])

    def _birth(self, z: np.ndarray) -> None:
        n = len(z)
        if n == 0:
            return
        x = np.zeros((n, 4))
        x[:, :2] = z
        P = np.tile(np.diag([self.params.meas_std**2] * 2 + [1.0, 1.0]), (n, 1, 1))
        self.x = np.concatenate([self.x, x])
        self.P = np.concatenate([self.P, P])
        self.ids = np.concatenate([self.ids, self._next_id + np.arange(n)])
        self._next_id += n
        self.hits = np.concatenate([self.hits, np.ones(n, int)])
        self.missed = np.concatenate([self.missed, np.zeros(n, int)])
        self.confirmed = np.concatenate([self.confirmed, np.full(n, self.params.confirm_hits <= 1)])
