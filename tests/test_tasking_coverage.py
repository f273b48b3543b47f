"""The coverage table: cells merged by coverage pattern, and the exhaustive k-subset search."""

from itertools import combinations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import box

from tasking import coverage
from tasking.coverage import Coverage, coverage_cells, optimal_subset, subset_areas
from tasking.hull import free_wedges_from_discs


def test_cells_with_one_coverage_pattern_are_one_row():
    """Two 90-degree cameras back to back at the centre of a 2 m square, no objects: the right
    quarter (1 m^2) is proven empty by camera 0, the left by camera 1, and the top and bottom
    quarters, two separate cells seen by neither, are one row of 2 m^2."""
    room = box(-1, -1, 1, 1)
    w = free_wedges_from_discs(np.zeros((2, 2)), np.array([0.0, np.pi]), np.pi / 2, np.zeros((0, 2)), 0.1,
                               room, strict=False)
    cov = coverage_cells(w, room)
    rows = {tuple(m): a for m, a in zip(cov.masks.tolist(), cov.areas.tolist(), strict=True)}
    assert len(rows) == cov.masks.shape[0] == 3
    assert rows == pytest.approx({(False, False): 2.0, (True, False): 1.0, (False, True): 1.0}, abs=1e-9)


def _first_best_by_hand(masks, areas, k, tol):
    """Every k-subset in lexicographic order, scored by a loop over the cells: the first
    within tol of the smallest score."""
    scores = {}
    for s in combinations(range(masks.shape[1]), k):
        scores[s] = sum(a for m, a in zip(masks, areas, strict=True) if not any(m[c] for c in s))
    best = min(scores.values())
    return next(list(s) for s, v in scores.items() if v <= best + tol)


@settings(max_examples=150, deadline=None)
@given(st.integers(1, 7), st.integers(1, 10), st.data(), st.sampled_from([1, 2, 5, 4096]),
       st.sampled_from([0.0, 0.5, 1.5]))
def test_optimal_subset_is_the_first_best_subset_by_hand(n, cells, data, chunk, tol):
    """Random tables with whole-number areas (exact sums: ties are real ties): the subset is
    the first in lexicographic order within tol of the smallest hull, whatever the block
    size, and subset_areas are the hand scores."""
    k = data.draw(st.integers(1, n))
    masks = np.array(data.draw(st.lists(st.lists(st.booleans(), min_size=n, max_size=n), min_size=cells,
                                        max_size=cells)), dtype=bool)
    areas = np.array(data.draw(st.lists(st.integers(0, 4), min_size=cells, max_size=cells)), dtype=float)
    cov = Coverage(masks, areas)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(coverage, "CHUNK", chunk)
        got = optimal_subset(cov, k, tol=tol)
    assert got == _first_best_by_hand(masks, areas, k, tol)
    subsets = np.array(list(combinations(range(n), k)))
    hand = [sum(a for m, a in zip(masks, areas, strict=True) if not m[s].any()) for s in subsets]
    np.testing.assert_array_equal(subset_areas(cov, subsets), hand)


def test_subset_areas_take_camera_indices_held_as_floats():
    """NumPy's default dtype is float: np.zeros((0, 2)) is no subset, and [[0.0, 2.0]] is
    cameras 0 and 2."""
    masks = np.array([[True, False, False], [False, True, False], [False, False, True]])
    cov = Coverage(masks, np.array([1.0, 2.0, 4.0]))
    np.testing.assert_array_equal(subset_areas(cov, np.array([[0.0, 2.0], [1.0, 2.0]])), [2.0, 1.0])
    assert subset_areas(cov, np.zeros((0, 2))).shape == (0,)


def test_optimal_subset_without_a_tolerance_takes_the_strictly_smallest_hull():
    """Camera 1's hull is 1e-12 m^2 smaller than camera 0's: no tolerance, no tie."""
    cov = Coverage(np.array([[True, False], [False, True]]), np.array([1.0, 1.0 + 1e-12]))
    assert optimal_subset(cov, 1) == [1]
    assert optimal_subset(cov, 1, tol=1e-9) == [0]
