"""Coverage table: the room cut into cells by every camera's wedge edges.

Inside one cell of the arrangement of all wedge boundaries, every camera either proves
the whole cell empty or none of it. So a visual hull area is a table lookup:

    area(hull(S)) = sum of the areas of cells that no camera of S covers.

Building the table costs one noding of all wedge edges plus one point-in-polygon test
per (cell, camera); after that each subset costs a bitmask AND over the cells, which is
what makes the brute-force ``optimal`` tasker practical (C(16, 8) = 12,870 subsets in
well under a second instead of 12,870 polygon overlays).

Cells covered by at least ``N - k + 1`` cameras are covered by every k-subset and are
dropped by :func:`optimal_subset`; cells with the same coverage are merged.

>>> from shapely.geometry import box
>>> from tasking.cones import wedge_polygons
>>> w = wedge_polygons(np.array([[0.0, 0.0]]), np.array([0.0]), np.array([np.pi / 2]), 5.0)
>>> cov = coverage_cells(w, box(-1, -1, 1, 1))
>>> sorted(cov.areas.round(6).tolist()), cov.masks.ravel().tolist()
([1.0, 3.0], [False, True])
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon, box

from .hull import overlay_grid

__all__ = ["Coverage", "coverage_cells", "optimal_subset", "subset_areas"]

#: Subsets scored per vectorised block.
CHUNK = 4096


@dataclass(frozen=True)
class Coverage:
    """Cells of the wedge arrangement, merged by coverage.

    masks : (U, N) bool, read-only; masks[u, c] = camera c proves cell group u empty
    areas : (U,) float, m^2, read-only
    """

    masks: np.ndarray
    areas: np.ndarray


def coverage_cells(wedges, room: Polygon) -> Coverage:
    """Arrangement of the cameras' free wedges inside the room.

    Parameters
    ----------
    wedges : (N,) object array of (Multi)Polygons, free wedges per camera
    room : shapely Polygon

    Returns
    -------
    Coverage with one row per distinct coverage pattern.
    """
    wedges = np.asarray(wedges, dtype=object)
    # Clip edges to a box around the room rather than to the room itself: an edge
    # clipped at the wall ends a rounding error away from the wall's ring, is not noded
    # onto it and would be dropped by polygonize as a dangle. Faces between the box and
    # the wall are discarded below.
    x0, y0, x1, y1 = room.bounds
    pad = 0.01 * np.hypot(x1 - x0, y1 - y0)
    edges = shapely.intersection(shapely.boundary(wedges), box(x0 - pad, y0 - pad, x1 + pad, y1 + pad))
    rings = shapely.get_parts(shapely.boundary(room))
    noded = shapely.union_all(np.concatenate([edges, rings]), grid_size=overlay_grid(room))   # robust noding
    faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
    pts = shapely.point_on_surface(faces)
    inside = shapely.contains(room, pts)  # drops faces outside the walls or in holes
    faces, pts = faces[inside], pts[inside]
    masks = np.empty((faces.size, wedges.size), dtype=bool)
    for c, w in enumerate(wedges):
        shapely.prepare(w)
        masks[:, c] = shapely.contains(w, pts)
    uniq, inverse = np.unique(masks, axis=0, return_inverse=True)
    areas = np.bincount(inverse.ravel(), weights=shapely.area(faces), minlength=uniq.shape[0])
    uniq.setflags(write=False)
    areas.setflags(write=False)
    return Coverage(uniq, areas)


def subset_areas(cov: Coverage, subsets) -> np.ndarray:
    """Hull areas of camera subsets.

    Parameters
    ----------
    cov : Coverage
    subsets : (C, k) int, 0-based camera indices

    Returns
    -------
    (C,) float, m^2
    """
    subsets = np.asarray(subsets, dtype=np.intp)
    covered = cov.masks[:, subsets].any(axis=2)  # (U, C)
    return cov.areas @ ~covered


def optimal_subset(cov: Coverage, k: int, tol: float = 0.0) -> list:
    """The k-subset with the smallest hull area (ties: first in lexicographic order).

    Scores within ``tol`` (m^2) of the smallest count as tied, so summation noise
    (~1e-13 m^2 between symmetric subsets) does not pick the winner. Subsets are scored in
    blocks of ``CHUNK``; the smallest score is known only at the end, so the first block
    holding a subset within ``tol`` of it is scored again to find that subset.

    Returns
    -------
    list of k ints, sorted.
    """
    n = cov.masks.shape[1]
    # cells covered by >= n - k + 1 cameras are covered by every k-subset
    keep = cov.masks.sum(axis=1) < n - k + 1
    masks, areas = cov.masks[keep], cov.areas[keep]
    kept = Coverage(masks, areas)
    if n <= 63:
        bits = (masks.astype(np.uint64) << np.arange(n, dtype=np.uint64)).sum(axis=1)
        weights = np.left_shift(np.uint64(1), np.arange(n, dtype=np.uint64))
    chunk = CHUNK

    def block(combos):
        return np.array(list(itertools.islice(combos, chunk)), dtype=np.intp).reshape(-1, k)

    def scores(subsets):
        if n > 63:
            return subset_areas(kept, subsets)
        sub_bits = weights[subsets].sum(axis=1)
        return ((sub_bits[:, None] & bits[None, :]) == 0) @ areas       # (C, U) uncovered cells

    combos = itertools.combinations(range(n), k)
    mins = []
    while (subsets := block(combos)).shape[0]:
        mins.append(scores(subsets).min())
    best = min(mins) + tol
    first = next(b for b, s in enumerate(mins) if s <= best)
    subsets = block(itertools.islice(itertools.combinations(range(n), k), first * chunk, None))
    return subsets[int(np.flatnonzero(scores(subsets) <= best)[0])].tolist()
