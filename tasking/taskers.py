"""Taskers: choose k of N cameras to minimise the visual hull area of estimated discs.

Every tasker works on the cameras' free wedges (what each camera would prove empty,
:func:`tasking.hull.free_wedges_from_discs`) for discs of ``radius`` at the estimated
object centres. The hull of a set S is ``room - union(wedges[S])``, so

* adding camera c to a set with hull H gives ``H - wedges[c]``: one difference, and the
  area it removes, ``area(H ∩ wedges[c])``, is the *gain* of c;
* the removed area is a coverage function (monotone, submodular): gains only shrink as
  H shrinks, which is what lazy (CELF) greedy relies on.

Greedy and lazy greedy compute gains with the same operation on the same hull (the
triangle fan of :mod:`tasking.fan` when given the wedge table, else a GEOS overlay), so
they see identical floating-point numbers and make the identical choice: gains within
``LAZY_TOL`` of the room's area of the largest count as tied, and the lowest camera
index goes (as in removals and the fan-table path), so overlay rounding cannot decide.
Areas are of the raw hull, before small-polygon removal.

>>> from shapely.geometry import Point
>>> room = Point(0, 0).buffer(1.0, quad_segs=32)
>>> th = 2 * np.pi * np.arange(8) / 8
>>> xy, yaw = np.c_[np.cos(th), np.sin(th)], th + np.pi
>>> choose_cameras("uniform", 4, xy, yaw, np.pi, [[0.3, 0.0]], 0.1, room).tolist()
[0, 2, 4, 6]
>>> g = choose_cameras("greedy", 3, xy, yaw, np.pi, [[0.3, 0.0], [-0.4, 0.2]], 0.1, room)
>>> bool(np.all(g == choose_cameras("lazy_greedy", 3, xy, yaw, np.pi,
...                                  [[0.3, 0.0], [-0.4, 0.2]], 0.1, room)))
True
"""

from __future__ import annotations

import heapq
from collections.abc import Mapping
from math import comb

import numpy as np
import shapely
from shapely.geometry import Polygon

from .checks import check_choice, check_indices, check_int, check_points, check_radii, check_room
from .clustering import clustering_select, pair_axes
from .cones import wedge_radius
from .coverage import coverage_cells, optimal_subset
from .fan import UnionAreas, cone_areas, convex_ring, ring_edges, split_wide
from .hull import drop_slivers, free_wedges_from_discs, hull_from_wedges

__all__ = [
    "TASKERS",
    "IncrementalTasker",
    "choose_cameras",
    "greedy_remove",
    "greedy_remove_reference",
    "greedy_select",
    "incremental_select",
    "incremental_select_convex",
    "lazy_greedy_select",
    "naive_greedy_select",
    "optimal_select",
    "uniform_select",
]

TASKERS = ("uniform", "clustering", "optimal", "greedy", "lazy_greedy", "incremental")
#: The optimal tasker refuses to compare more subsets of cameras than this (C(16, 8) = 12870).
MAX_SUBSETS = 200_000

#: Gains within this fraction of the room's area count as possibly equal in lazy greedy's
#: staleness test (far above floating-point noise, far below any real gain difference).
LAZY_TOL = 1e-9


def _gains(hull, wedges: np.ndarray) -> np.ndarray:
    """Area each wedge set would remove from ``hull`` (polygon overlays): (c,) float, m^2."""
    return shapely.area(shapely.intersection(hull, wedges))


class Gains:
    """Gains ``area(hull ∩ wedges[c])`` of candidate cameras.

    With the wedge table (``cones``, from ``free_wedges_from_discs(...,
    return_cones=True)``) gains come from the exact triangle-fan formula of
    :mod:`tasking.fan` (pure numpy, one call for all candidates); without it, from one
    polygon overlay per candidate. A candidate's gain is the same float whether it is
    evaluated alone or with others, so greedy and lazy greedy agree exactly.
    """

    def __init__(self, wedges, cones=None):
        self.wedges = np.asarray(wedges, dtype=object)
        self.n = self.wedges.size
        self.cones = None if cones is None else split_wide(*cones)
        self._hull, self._edges = None, None

    def __call__(self, hull, cand) -> np.ndarray:
        cand = np.atleast_1d(np.asarray(cand, dtype=np.intp))
        if self.cones is None:
            return _gains(hull, self.wedges[cand])
        if hull is not self._hull:
            self._hull, self._edges = hull, ring_edges(hull)
        camera, apex, t0, t1 = self.cones
        rows = np.isin(camera, cand)
        areas = cone_areas(*self._edges, apex[rows], t0[rows], t1[rows])
        return np.bincount(camera[rows], weights=areas, minlength=self.n)[cand]


def uniform_select(n: int, k: int) -> np.ndarray:
    """Evenly spread indices ``floor(i * n / k + 1/2)``, i = 0..k-1.

    >>> uniform_select(16, 5).tolist()
    [0, 3, 6, 10, 13]
    """
    return np.floor(np.arange(k) * n / k + 0.5).astype(np.intp)


def greedy_select(wedges, room: Polygon, k: int, start=(), hull=None, cones=None):
    """Paper algorithm 4.4: add k cameras one at a time, each minimising the hull area.

    Parameters
    ----------
    wedges : (N,) object array of MultiPolygons, free wedges per camera
    room : shapely Polygon
    k : number of cameras to add
    start : sequence of camera indices already tasked (not candidates)
    hull : hull of ``start`` if known (default: recomputed)
    cones : optional wedge table for fast gains (see :class:`Gains`)

    Returns
    -------
    chosen : list of k ints, in the order added
    hull : shapely geometry, the hull of ``start`` plus ``chosen``
    """
    wedges = np.asarray(wedges, dtype=object)
    gains = Gains(wedges, cones)
    avail = np.ones(wedges.size, dtype=bool)
    avail[list(start)] = False
    h = hull_from_wedges(wedges, room, list(start)) if hull is None else hull
    tol = LAZY_TOL * room.area
    chosen = []
    for _ in range(k):
        cand = np.flatnonzero(avail)
        g = gains(h, cand)
        best = int(cand[np.flatnonzero(g >= g.max() - tol)[0]])   # ties within tol: lowest index
        h = drop_slivers(h.difference(wedges[best]), room)
        avail[best] = False
        chosen.append(best)
    return chosen, h


def lazy_greedy_select(wedges, room: Polygon, k: int, start=(), hull=None, cones=None,
                       final_hull: bool = True):
    """Lazy (CELF) greedy: the same choice as :func:`greedy_select`, fewer evaluations.

    Stale gains are upper bounds (submodularity). A freshly evaluated camera is taken
    only when every stale bound is below its gain by more than ``LAZY_TOL * room.area``;
    stale cameras within that margin are re-evaluated first, so floating-point noise
    cannot change the choice. Same parameters and returns as :func:`greedy_select`;
    with ``final_hull=False`` the last round's difference is skipped and the returned
    hull is None (the incremental step only needs the choice).
    """
    wedges = np.asarray(wedges, dtype=object)
    gain = Gains(wedges, cones)
    h = hull_from_wedges(wedges, room, list(start)) if hull is None else hull
    taken = {int(s) for s in start}
    cand = np.array([c for c in range(wedges.size) if c not in taken], dtype=np.intp)
    if k == 0:
        return [], h
    tol = LAZY_TOL * room.area
    gains = gain(h, cand)
    heap = [(-float(g), int(c), 0) for g, c in zip(gains, cand)]
    heapq.heapify(heap)
    chosen = []
    for rnd in range(k):
        while True:
            neg, c, stamp = heapq.heappop(heap)
            if stamp != rnd:
                g = float(gain(h, c)[0])
                heapq.heappush(heap, (-g, c, rnd))
                continue
            # c is fresh and on top; every entry within tol of its gain must be fresh too
            near = []
            while heap and -heap[0][0] >= -neg - tol:
                near.append(heapq.heappop(heap))
            if all(e[2] == rnd for e in near):
                # c and the entries within tol of its gain are tied: the lowest index wins
                tied = [(neg, c, stamp), *near]
                best = min(tied, key=lambda e: e[1])
                for e in tied:
                    if e is not best:
                        heapq.heappush(heap, e)
                c = best[1]
                break
            for e in near:
                if e[2] == rnd:
                    heapq.heappush(heap, e)
                else:
                    g = float(gain(h, e[1])[0])
                    heapq.heappush(heap, (-g, e[1], rnd))
            heapq.heappush(heap, (neg, c, stamp))
        chosen.append(c)
        h = drop_slivers(h.difference(wedges[c]), room) if final_hull or rnd < k - 1 else None
    return chosen, h


def naive_greedy_select(wedges, room: Polygon, k: int) -> list:
    """Reference greedy that recomputes every candidate hull from scratch (benchmarks)."""
    chosen: list[int] = []
    for _ in range(k):
        best, best_area = -1, np.inf
        for c in range(len(wedges)):
            if c in chosen:
                continue
            area = hull_from_wedges(wedges, room, chosen + [c]).area
            if area < best_area:
                best, best_area = c, area
        chosen.append(best)
    return chosen


def optimal_select(wedges, room: Polygon, k: int) -> list:
    """Paper section 4.3: the k-subset with the smallest hull, by exhaustive search.

    Every one of the C(N, k) subsets is scored, but through the coverage table of
    :mod:`tasking.coverage` (a bitmask AND per subset) rather than a polygon overlay.
    Areas within ``LAZY_TOL * room.area`` of the smallest count as tied and the first
    subset in lexicographic order wins.

    Returns
    -------
    list of k ints, sorted.
    """
    return optimal_subset(coverage_cells(wedges, room), k, tol=LAZY_TOL * room.area)


def _first_min(areas, tol: float) -> int:
    """Lowest index whose value is within ``tol`` of the minimum (ties: lowest index)."""
    areas = np.asarray(areas, dtype=float)
    return int(np.flatnonzero(areas <= areas.min() + tol)[0])


def greedy_remove(wedges, room: Polygon, current, m: int):
    """Remove m cameras one at a time, each time the one whose removal grows the hull least.

    Hulls without each camera come from prefix and suffix hulls of the current set,
    ``hull(S - s_i) = P_{i-1} ∩ Q_{i+1}``, built only as far as needed: the prefix
    ``P_{k-1}`` and suffix ``Q_1`` are already the hulls without the last and the first
    camera, so a removal costs ``3|S| - 4`` overlays (the reference builds ``3|S|``).
    Areas within ``LAZY_TOL * room.area`` of the smallest count as tied and the lowest
    index wins, so overlay rounding cannot change the choice.

    Returns
    -------
    kept : list of ints (ascending), removed : list of m ints, hull : hull of ``kept``
    """
    wedges = np.asarray(wedges, dtype=object)
    tol = LAZY_TOL * room.area
    kept = sorted(int(c) for c in current)
    removed = []
    h = None
    for _ in range(m):
        s = len(kept)
        if s == 1:
            removed.append(kept.pop())
            h = room
            break
        prefix = [room]  # prefix[i] = hull of kept[:i], i = 0 .. s-1
        for c in kept[:-1]:
            prefix.append(prefix[-1].difference(wedges[c]))
        suffix = [room]  # reversed below: suffix[i] = hull of kept[i+1:], i = 0 .. s-1
        for c in reversed(kept[1:]):
            suffix.append(suffix[-1].difference(wedges[c]))
        suffix = suffix[::-1]
        without = np.empty(s, dtype=object)
        without[0], without[-1] = suffix[0], prefix[-1]
        if s > 2:
            without[1:-1] = shapely.intersection(np.array(prefix[1:-1], dtype=object),
                                                 np.array(suffix[1:-1], dtype=object))
        i = _first_min(shapely.area(without), tol)
        removed.append(kept.pop(i))
        h = drop_slivers(without[i], room)     # an intersection may hold a stray point or line
    return kept, removed, h


def greedy_remove_reference(wedges, room: Polygon, current, m: int):
    """Reference for :func:`greedy_remove` (tests): full prefix/suffix hulls, 3|S| overlays.

    Same tie rule (within ``LAZY_TOL * room.area``: lowest index) and returns.
    """
    wedges = np.asarray(wedges, dtype=object)
    tol = LAZY_TOL * room.area
    kept = sorted(int(c) for c in current)
    removed = []
    h = None
    for _ in range(m):
        s = len(kept)
        prefix = [room]
        for c in kept:
            prefix.append(prefix[-1].difference(wedges[c]))
        suffix = [room]
        for c in reversed(kept):
            suffix.append(suffix[-1].difference(wedges[c]))
        suffix = suffix[::-1]  # suffix[i] = hull of kept[i:]
        without = shapely.intersection(np.array(prefix[:s], dtype=object),
                                       np.array(suffix[1:], dtype=object))
        i = _first_min(shapely.area(without), tol)
        removed.append(kept.pop(i))
        h = drop_slivers(without[i], room)     # an intersection may hold a stray point or line
    return kept, removed, h


def incremental_select(wedges, room: Polygon, current, m: int, cones=None) -> list:
    """Paper section 4.5: greedily remove m of the current cameras, then add m greedily.

    Returns
    -------
    list of ints, sorted, the same size as ``current``.
    """
    kept, _, h = greedy_remove(wedges, room, current, m)
    added, _ = lazy_greedy_select(wedges, room, m, start=kept, hull=h, cones=cones,
                                  final_hull=False)
    return sorted(kept + added)


def incremental_select_convex(camera_xy, cones, room: Polygon, room_xy, current,
                              m: int) -> list:
    """:func:`incremental_select` for a convex room, without polygon overlays.

    Every hull area comes from :class:`tasking.fan.UnionAreas` (``area(hull(T)) =
    area(room) - area(room ∩ ⋃ wedges[T])``, exact to ~1e-12 of the room's area), all
    candidate sets of a round in one numpy call. Removal: the same rule as
    :func:`greedy_remove` (smallest hull; within ``LAZY_TOL * room.area`` the lowest
    index). Adding: the largest gain, within ``LAZY_TOL * room.area`` the lowest index,
    as lazy greedy in :func:`incremental_select`.

    Parameters
    ----------
    camera_xy : (N, 2) float; cones : wedge table from ``free_wedges_from_discs(...,
    return_cones=True)``; room_xy : ``convex_ring(room)``; current : (k,) int; m : int

    Returns
    -------
    list of ints, sorted, the same size as ``current``.
    """
    n = camera_xy.shape[0]
    ua = UnionAreas(room_xy, split_wide(*cones), n, wedge_radius(room, camera_xy))
    tol = LAZY_TOL * room.area
    kept = sorted(int(c) for c in current)
    for _ in range(m):
        if len(kept) == 1:
            kept = []
            break
        sets = np.zeros((len(kept), n), dtype=bool)
        sets[:, kept] = True
        sets[np.arange(len(kept)), kept] = False
        # hull area = room area - covered area: the smallest hull is the largest cover
        i = _first_min(-ua(sets), tol)
        kept.pop(i)
    start = len(kept)
    for _ in range(len(current) - start):
        cand = np.setdiff1d(np.arange(n), kept)
        sets = np.zeros((cand.size, n), dtype=bool)
        sets[:, kept] = True
        sets[np.arange(cand.size), cand] = True
        kept.append(int(cand[_first_min(-ua(sets), tol)]))
    return sorted(kept)


def choose_cameras(
    tasker: str,
    k: int,
    camera_xy,
    camera_yaw,
    fov,
    estimates,
    radius,
    room,
    *,
    current=None,
    m: int = 1,
    uniform_sets: Mapping | None = None,
    max_subsets: int = MAX_SUBSETS,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Choose k of N cameras with one of :data:`TASKERS`.

    Parameters
    ----------
    tasker : one of ``TASKERS``
    k : number of cameras, 1 <= k <= N
    camera_xy : (N, 2) float, metres, world frame
    camera_yaw : (N,) float, radians, world-frame viewing direction
    fov : float or (N,) float, radians, in (0, 2*pi)
    estimates : (p, 2) float, metres, world frame, estimated object centres (p may be 0);
        modelled as discs of ``radius`` that may overlap
    radius : float or (p,) float, metres
    room : shapely Polygon
    current : (k,) int, 0-based indices tasked now (incremental; None -> lazy greedy, the
        same choice as greedy)
    m : cameras swapped per incremental update, 1 <= m <= k
    uniform_sets : mapping k -> k 0-based indices for the uniform tasker (e.g. the lab's
        paper lists); without an entry, ``uniform_select(N, k)``
    max_subsets : int >= 1; the optimal tasker refuses when C(N, k) exceeds this
    rng : numpy Generator seeding k-means (clustering); None -> seed 0

    Returns
    -------
    (k,) int, sorted ascending 0-based camera indices.
    """
    check_choice("tasker", tasker, TASKERS)
    camera_xy = check_points("camera_xy", camera_xy)
    n = camera_xy.shape[0]
    k = check_int("k", k, 1, n)
    m = check_int("m", m, 1, k)
    max_subsets = check_int("max_subsets", max_subsets, 1)
    if uniform_sets is not None and not isinstance(uniform_sets, Mapping):   # `k in` a list: never, silently
        raise ValueError(f"uniform_sets must be a mapping k -> k camera indices; got {type(uniform_sets).__name__}")
    estimates = check_points("estimates", estimates, allow_empty=True)
    check_radii("radius", radius, estimates.shape[0])
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy Generator or None; got {type(rng).__name__}")
    if current is not None:
        current = check_indices("current", current, n, size=k)
    room = check_room(room)
    room_xy = convex_ring(room) if tasker == "incremental" and current is not None else None
    # the rest of the geometry validation (yaw, fov, finite values) happens here
    wedges, cones = free_wedges_from_discs(camera_xy, camera_yaw, fov, estimates, radius,
                                           room, strict=False, return_cones=True,
                                           polygons=room_xy is None)
    if room_xy is not None:
        return np.array(incremental_select_convex(camera_xy, cones, room, room_xy, current,
                                                  m), dtype=np.intp)
    if tasker == "clustering" and k >= 2 and pair_axes(estimates).size:   # k = 1: no direction (docs)
        seed = 0 if rng is None else int(rng.integers(2**31 - 1))
        return clustering_select(camera_yaw, estimates, k, seed, camera_xy=camera_xy)
    if tasker in ("uniform", "clustering"):
        if uniform_sets is not None and k in uniform_sets:
            return check_indices(f"uniform_sets[{k}]", uniform_sets[k], n, size=k)
        return uniform_select(n, k)
    if tasker == "optimal":
        count = comb(n, k)
        if count > max_subsets:
            raise ValueError(
                f"max_subsets: optimal needs C({n}, {k}) = {count} hulls; limit {max_subsets}"
            )
        return np.array(optimal_select(wedges, room, k), dtype=np.intp)
    if tasker == "incremental" and current is not None:
        return np.array(incremental_select(wedges, room, current, m, cones), dtype=np.intp)
    if tasker == "greedy":
        chosen, _ = greedy_select(wedges, room, k, cones=cones)
    else:  # lazy_greedy, or incremental without a current set
        chosen, _ = lazy_greedy_select(wedges, room, k, cones=cones)
    return np.sort(np.array(chosen, dtype=np.intp))


class IncrementalTasker:
    """Incremental greedy on a schedule: greedy at first, then swap m every u frames.

    Holds configuration and the last selection only; the geometry is in the functions.

    Parameters
    ----------
    k : cameras tasked
    m : cameras swapped per update, 1 <= m <= k
    update_every : update on frames whose index is a multiple of this (>= 1)
    """

    def __init__(self, k: int, m: int = 1, update_every: int = 1):
        self.k = check_int("k", k, 1)
        self.m = check_int("m", m, 1, self.k)
        self.update_every = check_int("update_every", update_every, 1)
        self.current: np.ndarray | None = None
        self.n_cameras: int | None = None   # the network of the tasked set

    def step(self, frame_index: int, camera_xy, camera_yaw, fov, estimates, radius, room):
        """Cameras to task for this frame: (k,) int, sorted 0-based indices.

        Every step must pass the same network (``camera_xy`` of the same length): the
        tasked set is indices into it.
        """
        frame_index = check_int("frame_index", frame_index, 0)
        n = len(check_points("camera_xy", camera_xy))
        if self.n_cameras is not None and n != self.n_cameras:
            raise ValueError(f"camera_xy has {n} cameras, but this IncrementalTasker tasks {self.k} of "
                             f"{self.n_cameras} (its earlier steps); make a new IncrementalTasker for another network")
        if self.current is None or frame_index % self.update_every == 0:
            self.current = choose_cameras(
                "incremental", self.k, camera_xy, camera_yaw, fov, estimates, radius, room,
                current=self.current, m=self.m,
            )
            self.n_cameras = n
        return self.current.copy()
