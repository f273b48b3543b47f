"""Run-length coding of scanlines (step 6) and the bandwidth it needs.

A scanline of width W is coded as the lengths of its alternating runs, starting with a
run of background (of length 0 when the scanline starts occupied). Each length takes
``ceil(log2(W + 1))`` bits (10 for W = 640); the receiver knows W, so no header is needed
and the lengths sum to W.

>>> s = np.array([0, 0, 1, 1, 1, 0, 1], bool)
>>> rle_encode(s)
array([2, 3, 1, 1])
>>> bool(np.array_equal(rle_decode(rle_encode(s), 7), s))
True
>>> rle_bits(rle_encode(s), 7)
12
"""

from __future__ import annotations

import math

import numpy as np


def rle_encode(scanline) -> np.ndarray:
    """Run lengths of a (W,) bool scanline, the first run being background (maybe 0 long)."""
    s = np.asarray(scanline, bool)
    if s.ndim != 1:
        raise ValueError(f"scanline: expected shape (W,), got {s.shape}")
    if s.size == 0:
        return np.zeros(0, np.int64)
    edges = np.flatnonzero(s[1:] != s[:-1]) + 1
    bounds = np.concatenate([[0], edges, [s.size]])
    runs = np.diff(bounds)
    return np.concatenate([[0], runs]) if s[0] else runs


def rle_decode(runs, width: int) -> np.ndarray:
    """Inverse of :func:`rle_encode`: run lengths -> (width,) bool."""
    runs = np.asarray(runs, np.int64)
    if runs.ndim != 1 or np.any(runs < 0) or runs.sum() != width:
        raise ValueError(f"runs: expected non-negative run lengths summing to width {width}")
    values = np.arange(runs.size) % 2 == 1
    return np.repeat(values, runs)


def bits_per_run(width: int) -> int:
    """Bits to code one run length of a scanline of ``width`` columns."""
    return max(1, math.ceil(math.log2(width + 1)))


def rle_bits(runs, width: int) -> int:
    """Bits of an encoded scanline."""
    return len(runs) * bits_per_run(width)


def scanline_bits(scanlines) -> np.ndarray:
    """RLE bits of each scanline without building the runs: (..., W) bool -> (...) int.

    >>> scanline_bits(np.array([[0, 0, 1, 1, 1, 0, 1], [1, 1, 1, 1, 1, 1, 1]], bool))
    array([12,  6])
    """
    s = np.asarray(scanlines, bool)
    width = s.shape[-1]
    n_runs = 1 + np.count_nonzero(s[..., 1:] != s[..., :-1], axis=-1) + s[..., 0]
    return n_runs * bits_per_run(width)
