"""Sensor degradation: per-frame illumination gain and Gaussian sensor noise.

Both are drawn from an ``np.random.Generator`` in a fixed order (one gain per camera,
then the noise), so the same seed gives the same bytes. The noise is Gaussian rounded
to whole grey levels, drawn by inverse-CDF lookup from one random byte per sample: the
byte k selects the quantile ``(k + 0.5) / 256`` of N(0, noise_std), rounded. That is
the rounded Gaussian up to the 1/256 quantisation of its tails (|z| <= 2.9 sigma), at
the cost of one random byte and one table lookup per sample.

>>> lut = noise_table(2.0)
>>> int(lut[128]) - BIAS, int(lut.min()) - BIAS, int(lut.max()) - BIAS
(0, -6, 6)
"""

from __future__ import annotations

from statistics import NormalDist

import cv2
import numpy as np

#: Offset added to the signed noise so that it fits a uint8 lookup table.
BIAS = 128


def noise_table(noise_std: float) -> np.ndarray:
    """(256,) uint8 table: random byte -> rounded Gaussian noise + :data:`BIAS`."""
    q = (np.arange(256) + 0.5) / 256.0
    z = np.array([NormalDist().inv_cdf(x) for x in q])
    return np.clip(np.rint(noise_std * z) + BIAS, 0, 255).astype(np.uint8)


def degrade(rgb: np.ndarray, noise_std: float, gain_jitter: float, rng: np.random.Generator,
            table: np.ndarray | None = None) -> np.ndarray:
    """Multiply each camera by a random gain ``1 + N(0, gain_jitter)`` and add noise, in place.

    rgb : (n_cams, H, W, 3) uint8, modified in place and returned
    noise_std : grey levels; gain_jitter : relative std of the per-camera gain
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected an np.random.Generator, got {type(rng).__name__}")
    n = rgb.shape[0]
    gains = np.clip(1.0 + gain_jitter * rng.standard_normal(n), 0.0, None)
    if noise_std > 0:
        table = noise_table(noise_std) if table is None else table
        codes = np.frombuffer(rng.bytes(rgb.size), np.uint8).reshape(n, -1)
        noise = cv2.LUT(codes, table)
    for i in range(n):
        flat = rgb[i].reshape(rgb.shape[1], -1)
        if noise_std > 0:
            cv2.addWeighted(flat, float(gains[i]), noise[i].reshape(flat.shape), 1.0, -BIAS, dst=flat)
        elif gains[i] != 1.0:
            cv2.convertScaleAbs(flat, dst=flat, alpha=float(gains[i]))
    return rgb
