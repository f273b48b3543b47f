"""A straightforward reference implementation of the same steps, for tests and benchmarks.

Per camera, per frame, in float64 with ``np.arccos`` per pixel, ``scipy.ndimage`` opening
and median filter, ``cv2.remap`` with float maps, ``np.convolve`` box filter. It shares
nothing with the production path but the background model and the calibration.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

from .params import PipelineParams
from .rectify import float_maps


class ReferencePipeline:
    """Same contract as :class:`pipeline.Pipeline`: ``process(frames) -> (n_cams, W) bool``."""

    def __init__(self, cameras, params: PipelineParams, background: np.ndarray):
        self.cameras = tuple(cameras)
        self.params = params
        self.background = np.asarray(background, np.float64)    # (n_cams, H, W, 3)
        self.maps = float_maps(self.cameras)                    # per camera (x, y) float32
        self.state = None

    def foreground(self, frame: np.ndarray, i: int) -> np.ndarray:
        """(H, W) bool colour-angle foreground of camera index ``i`` (before the opening)."""
        p = self.params
        a = frame.astype(np.float64)
        b = self.background[i]
        na = np.sqrt((a * a).sum(-1))
        nb = np.sqrt((b * b).sum(-1))
        with np.errstate(invalid="ignore", divide="ignore"):
            cos = (a * b).sum(-1) / (na * nb)
        angle = np.degrees(np.arccos(np.clip(np.nan_to_num(cos, nan=1.0), -1.0, 1.0)))
        fg = angle > p.threshold_deg
        dark = np.minimum(na, nb) < p.brightness_floor
        fg[dark] = np.sqrt(((a - b) ** 2).sum(-1))[dark] > p.dark_delta
        return fg

    def process(self, frames: np.ndarray) -> np.ndarray:
        p = self.params
        rows = []
        for i in range(len(self.cameras)):
            fg = self.foreground(frames[i], i)
            if p.opening_kernel > 1:
                fg = ndimage.binary_opening(fg, np.ones((p.opening_kernel,) * 2, bool), border_value=0)
            rect = cv2.remap(fg.astype(np.uint8), *self.maps[i], cv2.INTER_NEAREST,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=0)
            sums = rect.sum(axis=0).astype(np.float64)
            padded = np.pad(sums, p.spatial_kernel // 2, mode="edge")
            rows.append(np.convolve(padded, np.ones(p.spatial_kernel), mode="valid") / p.spatial_kernel)
        smooth = np.stack(rows)
        if self.state is not None and p.temporal_alpha != 1.0:
            smooth = p.temporal_alpha * smooth + (1.0 - p.temporal_alpha) * self.state
        self.state = smooth
        med = np.stack([ndimage.median_filter(s, size=p.median_kernel, mode="nearest")
                        for s in smooth])
        return med > p.column_threshold
