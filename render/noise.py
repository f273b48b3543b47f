"""Sensor degradation: per-frame illumination gain and Gaussian sensor noise.

Both are drawn from an ``np.random.Generator`` in a fixed order (one gain per camera,
then one pool offset per camera), so the same seed gives the same bytes.

The noise is Gaussian rounded to whole grey levels, but it is not drawn afresh per
frame: each camera's frame takes a contiguous window of one fixed **noise pool**, a
few megabytes of independent rounded N(0, noise_std) samples (clipped to -128..127)
drawn once from a constant seed, starting at an offset drawn from ``rng``. Drawing
one offset instead of H x W x 3 random numbers makes the noise nearly free (one
saturating ``cv2.addWeighted`` pass that also applies the gain). What this
approximates, honestly:

- within one frame every sample is an independent rounded Gaussian (exact);
- at a fixed pixel the samples of successive frames are independent unless two
  windows start at the same offset (probability ``1 / (POOL_EXTRA + 1)`` per pair);
- two windows that overlap share samples, shifted: one camera's noise can be a
  translated copy of part of another frame's. Per-pixel statistics cannot tell;
  cross-correlating two frames at exactly that lag could;
- the pool is the same for every seed; seeds change the offsets (and the gains).

>>> pool = noise_pool(2.0, 1000)          # rounding adds 1/12 to the variance
>>> pool.dtype, len(pool) == 1000 + POOL_EXTRA, round(float(pool[:10**6].std()), 2)
(dtype('uint8'), True, 2.02)
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

#: Offset added to the signed noise so that it fits in uint8.
BIAS = 128

#: The pool's length beyond one frame: window offsets run over 0..POOL_EXTRA, both ends included.
POOL_EXTRA = 1 << 23

#: The pool's fixed seed: the pool is part of the renderer, like the room's texture.
POOL_SEED = 20240611


@lru_cache(maxsize=4)
def noise_pool(noise_std: float, frame_size: int) -> np.ndarray:
    """(frame_size + POOL_EXTRA,) uint8: rounded N(0, noise_std) + :data:`BIAS`, clipped, read-only."""
    rng = np.random.default_rng(POOL_SEED)
    pool = np.empty(frame_size + POOL_EXTRA, np.uint8)
    chunk = 1 << 21
    for start in range(0, len(pool), chunk):
        z = rng.standard_normal(min(chunk, len(pool) - start), dtype=np.float32)
        pool[start:start + len(z)] = np.clip(np.rint(z * np.float32(noise_std)) + BIAS, 0, 255)
    pool.flags.writeable = False
    return pool


def draw_gains_offsets(n: int, gain_jitter: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Per-camera gains ``max(0, 1 + N(0, gain_jitter))`` and pool offsets, drawn in that order."""
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected an np.random.Generator, got {type(rng).__name__}")
    gains = np.clip(1.0 + gain_jitter * rng.standard_normal(n), 0.0, None)
    offsets = rng.integers(0, POOL_EXTRA, n, endpoint=True)
    return gains, offsets


def sense(dst: np.ndarray, src: np.ndarray, gain: float, noise: np.ndarray | None) -> None:
    """``dst = saturate(round(src * gain) + noise - BIAS)``, one pass, on 2-D uint8 views.

    dst, src, noise : (rows, cols) uint8 of one shape (``src`` may be ``dst``); noise is
    biased by :data:`BIAS` (a pool window), or None for no noise
    """
    if noise is not None:
        cv2.addWeighted(src, float(gain), noise, 1.0, -BIAS, dst=dst)
    elif gain != 1.0:
        cv2.convertScaleAbs(src, dst=dst, alpha=float(gain))
    elif dst is not src:
        np.copyto(dst, src)


def degrade(rgb: np.ndarray, noise_std: float, gain_jitter: float, rng: np.random.Generator,
            pool: np.ndarray | None = None) -> np.ndarray:
    """Multiply each camera by a random gain ``1 + N(0, gain_jitter)`` and add noise, in place.

    rgb : (n_cams, H, W, 3) uint8, modified in place and returned
    noise_std : grey levels; gain_jitter : relative std of the per-camera gain
    pool : :func:`noise_pool` ``(noise_std, H * W * 3)`` (built and cached when None)
    """
    n, H = rgb.shape[:2]
    gains, offsets = draw_gains_offsets(n, gain_jitter, rng)
    size = rgb[0].size
    if noise_std > 0 and pool is None:
        pool = noise_pool(float(noise_std), size)
    for i in range(n):
        flat = rgb[i].reshape(H, -1)                # a copy if a row's bytes are not contiguous
        noise = pool[offsets[i]:offsets[i] + size].reshape(flat.shape) if noise_std > 0 else None
        sense(flat, flat, gains[i], noise)
        if not np.may_share_memory(flat, rgb):
            rgb[i] = flat.reshape(rgb[i].shape)
    return rgb
