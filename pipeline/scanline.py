"""From rectified masks to boolean scanlines (step 5).

Column sum -> spatial box smoothing -> temporal exponential smoothing -> median filter ->
threshold. The spatial and median filters extend the scanline by repeating its end
columns, so that a person cut by the image border keeps their run up to the border
(zero padding would erode it and wrongly clear columns that see the person).

Because thresholding is monotone, ``median(x) > t`` equals a majority vote of ``x > t``
over the same window; :func:`median_threshold` uses that (exactly equal to
``scipy.ndimage.median_filter(x, mode="nearest") > t``).

>>> x = np.array([[0, 9, 0, 9, 9, 0, 0, 9, 0]], float)
>>> median_threshold(x, 3, 5.0).astype(int)
array([[0, 0, 1, 1, 1, 0, 0, 0, 0]])
"""

from __future__ import annotations

import numpy as np


def _box_sum(x: np.ndarray, k: int) -> np.ndarray:
    """Edge-padded sliding sum of width ``k`` (odd) along the last axis, exact for integers."""
    pad = k // 2
    c = np.zeros(x.shape[:-1] + (x.shape[-1] + 2 * pad + 1,), x.dtype)
    np.cumsum(np.pad(x, [(0, 0)] * (x.ndim - 1) + [(pad, pad)], mode="edge"), axis=-1, out=c[..., 1:])
    return c[..., k:] - c[..., :-k]


def spatial_smooth(sums, k: int) -> np.ndarray:
    """Box mean of width ``k`` (odd) over columns, edge padded: (n, W) -> (n, W) float64.

    >>> spatial_smooth(np.array([[0., 3, 0, 0]]), 3)
    array([[1., 1., 1., 0.]])
    >>> spatial_smooth(np.array([[6., 0, 0, 0]]), 3)
    array([[4., 2., 0., 0.]])
    """
    x = np.asarray(sums, np.float64)
    return x.copy() if k == 1 else _box_sum(x, k) / k


def temporal_smooth(x, state, alpha: float) -> np.ndarray:
    """Exponential smoothing ``alpha * x + (1 - alpha) * state``; ``state`` None starts at ``x``."""
    x = np.asarray(x, np.float64)
    if state is None or alpha == 1.0:
        return x.copy()
    return alpha * x + (1.0 - alpha) * state


def median_threshold(x, k: int, threshold: float) -> np.ndarray:
    """``median_filter(x, k) > threshold`` along the last axis (edge padded, threshold >= 0).

    x : (n, W) float; Returns (n, W) bool.
    """
    above = np.asarray(x) > threshold
    if k == 1:
        return above
    return _box_sum(above.astype(np.int32), k) > k // 2


def true_scanlines(rectified_truth) -> np.ndarray:
    """Ground-truth scanline: columns with any foreground, (n, H, W) bool -> (n, W) bool."""
    return np.asarray(rectified_truth).any(axis=1)
