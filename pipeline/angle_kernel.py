"""The colour-angle test as one compiled pass per camera (numba), for :class:`pipeline.foreground.AngleTerms`.

Per pixel, in float32 exactly as the formulas of :mod:`pipeline.foreground` state them
(no fused multiply-add, no reassociation: ``fastmath`` is off), with the background
terms derived on the fly from the background (float32, or uint8 levels):

    dot = a0 b0 + a1 b1 + a2 b2,   aa = |a|^2,   bb = |b|^2          (float32, in this order)
    c2bb = float32(cos^2(theta) * bb in float64)
    foreground = (a . b)^2 < |a|^2 c2bb, or, where |a|^2 or bb < floor^2,
                 |a|^2 + bb - 2 a . b > delta^2

The loop has no branch, so LLVM vectorises it; it reads the frame and the background
once and writes the mask once (OpenCV needed eight passes over float32 temporaries:
lab, 16 cameras, ~9.5 -> 2.2-2.3 ms per frame with a uint8 background). Compiled on first use and cached on disk
(~0.5 s the first time on a machine, ~0.1 s per process after; see :func:`_compiled`).
"""

from __future__ import annotations

import numba
import numpy as np


def _compiled(fn):
    """``numba.njit`` with the compiled code cached on disk, or without a cache where numba
    finds no writable cache folder (next to this file, then ``NUMBA_CACHE_DIR`` or the
    user's cache folder): compiled once per process then."""
    options = dict(nogil=True, boundscheck=False, error_model="numpy")
    try:
        return numba.njit(cache=True, **options)(fn)
    except RuntimeError:                                  # "cannot cache function ...: no locator available"
        return numba.njit(**options)(fn)


@_compiled
def angle_mask(frames, background, c2, floor2, delta2, out):  # pragma: no cover - compiled
    """frames (n, H, W, 3) uint8 and background (n, H, W, 3) float32 or uint8, C-contiguous;
    c2 = cos^2(theta) float64; floor2, delta2 float32; out (n, rows, W) uint8,
    C-contiguous, rows >= H: out[:, :H] <- 255 where foreground, 0 elsewhere."""
    n, h, w = frames.shape[0], frames.shape[1], frames.shape[2]
    m = h * w
    two = np.float32(2.0)
    for i in range(n):
        f = frames[i].reshape(3 * m)
        b = background[i].reshape(3 * m)
        o = out[i].reshape(out.shape[1] * w)
        for x in range(m):
            a0 = np.float32(f[3 * x])
            a1 = np.float32(f[3 * x + 1])
            a2 = np.float32(f[3 * x + 2])
            b0 = np.float32(b[3 * x])
            b1 = np.float32(b[3 * x + 1])
            b2 = np.float32(b[3 * x + 2])
            dot = a0 * b0 + a1 * b1 + a2 * b2
            aa = a0 * a0 + a1 * a1 + a2 * a2
            bb = b0 * b0 + b1 * b1 + b2 * b2
            angle = dot * dot < aa * np.float32(c2 * bb)
            dark = (aa < floor2) | (bb < floor2)
            diff = (aa + bb) - two * dot > delta2
            o[x] = np.uint8(255) * np.uint8((angle & ~dark) | (diff & dark))
    return out
