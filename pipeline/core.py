"""The node-side pipeline of a rig: per-camera precomputed maps, temporal state.

>>> from scene import Camera
>>> cam = Camera.from_pose(1, [0, 0, 1.5], 0.0, 0.0, 64, 48, np.radians(50), [0, 0, 0, 0, 0])
>>> bg = np.full((1, 48, 64, 3), 120, np.uint8)
>>> pipe = Pipeline([cam], PipelineParams(opening_kernel=1, spatial_kernel=1,
...                 median_kernel=1, column_threshold=0.5), background=bg)
>>> frame = bg.copy(); frame[0, 10:30, 30:34] = (200, 40, 40)
>>> np.flatnonzero(pipe.process(frame)[0]).tolist()
[30, 31, 32, 33]
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .foreground import AngleTerms, background_model, check_frames, check_lit, open_stacked
from .nearfield import raw_pixels_per_radian, sight_range
from .params import PipelineParams
from .rectify import Rectifier
from .scanline import median_threshold, spatial_smooth, temporal_smooth, true_scanlines


@dataclass(frozen=True, eq=False)
class StepOutput:
    """Intermediate results of one batch.

    foreground : (n_cams, H, W) bool, after the opening, raw (distorted) image
    rectified : (n_cams, out_height, width) bool
    smoothed : (n_cams, width) float, column counts after spatial and temporal smoothing
    scanlines : (n_cams, width) bool
    """

    foreground: np.ndarray
    rectified: np.ndarray
    smoothed: np.ndarray
    scanlines: np.ndarray


class Pipeline:
    """Frames to scanlines for a rig of calibrated cameras (all of one resolution).

    cameras : sequence of :class:`scene.Camera`
    params : :class:`PipelineParams` (defaults if None)
    background : empty-room frames, (n_cams, H, W, 3) or (n_frames, n_cams, H, W, 3) uint8
    rectifier : :class:`Rectifier` of these cameras, to share its maps between pipelines
        (default: built here, ~0.1 s for 16 cameras)
    """

    def __init__(self, cameras, params: PipelineParams | None = None, background=None,
                 rectifier: Rectifier | None = None):
        self.cameras = tuple(cameras)
        if not self.cameras:
            raise ValueError("cameras: expected at least one calibrated camera")
        self.params = PipelineParams() if params is None else params
        if not isinstance(self.params, PipelineParams):
            raise ValueError(f"params: expected PipelineParams, got {type(self.params).__name__}")
        self.height, self.width = self.cameras[0].height, self.cameras[0].width
        self.row_stride = self.height + self.params.opening_kernel // 2
        self.rectifier = Rectifier.build(self.cameras) if rectifier is None else rectifier
        self._buf = np.zeros((self.n_cams, self.row_stride, self.width), np.uint8)
        self._terms: AngleTerms | None = None
        self._state = None
        self._ranges: dict = {}                # sight_range's results, by its arguments
        self._pixels_per_radian = None         # the cameras' raw pixels per radian, for those
        if background is not None:
            self.set_background(background)

    @property
    def n_cams(self) -> int:
        return len(self.cameras)

    @property
    def bearings(self) -> np.ndarray:
        """(n_cams, width) float, radians, world-frame bearing of each scanline column."""
        return self.rectifier.bearings

    def sight_range(self, object_height: float, truth: bool = False,
                    object_width: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Per camera, the floor distances (metres) between which an upright object of
        ``object_height`` metres (and ``object_width`` metres across: a person's diameter;
        None for no width limit) is sent as occupied: ``(near, far)``, each (n_cams,)
        (:func:`pipeline.nearfield.sight_range`). A column is sent occupied when its
        smoothed count exceeds ``column_threshold``: a new object must show
        ``column_threshold / temporal_alpha`` rows, plus the opening's ``opening_kernel``;
        it must be wider than the opening's kernel in the raw image, and span ``spatial_kernel
        + median_kernel // 2 + 1`` columns, so that a run survives the box and median
        filters. With ``truth``, for the true scanlines (:meth:`ground_truth`): one row,
        one column and one raw pixel.
        """
        key = (float(object_height), bool(truth), None if object_width is None else float(object_width))
        if key not in self._ranges:         # ~5 ms a camera with a width: once per pipeline, not per episode
            p = self.params
            if truth:
                margin, columns, raw_columns = 1.0, 1.0, 1.0
            else:
                margin = p.column_threshold / p.temporal_alpha + p.opening_kernel
                columns, raw_columns = p.spatial_kernel + p.median_kernel // 2 + 1, p.opening_kernel + 1
            if object_width is not None and self._pixels_per_radian is None:
                self._pixels_per_radian = [raw_pixels_per_radian(c) for c in self.cameras]
            near, far = sight_range(self.cameras, object_height, margin, self.rectifier.width, object_width,
                                    columns, raw_columns, self._pixels_per_radian)
            near.setflags(write=False)
            far.setflags(write=False)
            self._ranges[key] = near, far
        return self._ranges[key]

    @property
    def frame_shape(self) -> tuple[int, int, int]:
        """(n_cams, H, W) expected of every batch."""
        return (self.n_cams, self.height, self.width)

    def set_background(self, frames) -> None:
        """Build the background model from empty-room frames (or a float32 model) and reset."""
        arr = np.asarray(frames)
        numbers = [c.number for c in self.cameras]
        if arr.dtype == np.float32 and arr.ndim == 4:
            bg = arr
            check_lit(bg, numbers)
        else:
            bg = background_model(arr, numbers)
        if bg.shape != self.frame_shape + (3,):
            n, h, w = self.frame_shape
            raise ValueError(f"background: expected shape ({n}, {h}, {w}, 3) to match the calibration, "
                             f"got {tuple(bg.shape)}")
        p = self.params
        self._terms = AngleTerms(bg, p.threshold_deg, p.brightness_floor, p.dark_delta)
        self.reset()

    def with_params(self, params: PipelineParams) -> Pipeline:
        """A pipeline of the same cameras, rectifier and background with other ``params``
        (fresh temporal state). Nothing per pixel is rebuilt: ~0.1 ms instead of ~80 ms
        for 16 cameras (tuning makes one per trial)."""
        self._need_background()
        pipe = Pipeline(self.cameras, params, rectifier=self.rectifier)
        pipe._terms = self._terms.with_thresholds(params.threshold_deg, params.brightness_floor,
                                                  params.dark_delta)
        return pipe

    @property
    def background(self) -> np.ndarray:
        """(n_cams, H, W, 3) float32 background model."""
        self._need_background()
        return self._terms.background

    def reset(self) -> None:
        """Forget the temporal state (start of a new sequence)."""
        self._state = None

    def _need_background(self):
        if self._terms is None:
            raise ValueError("background: not set; call set_background() with empty-room frames first")

    def step(self, frames) -> StepOutput:
        """Process one batch, returning the intermediate results too (see :class:`StepOutput`)."""
        opened = self._foreground_stacked(frames)
        rect = self.rectifier.remap_stacked(opened)
        p = self.params
        smoothed = temporal_smooth(spatial_smooth(_counts(rect), p.spatial_kernel), self._state,
                                   p.temporal_alpha)
        self._state = smoothed
        scan = median_threshold(smoothed, p.median_kernel, p.column_threshold)
        fg = opened.reshape(self._buf.shape)[:, :self.height] != 0
        return StepOutput(fg, rect != 0, smoothed, scan)

    def process(self, frames) -> np.ndarray:
        """(n_cams, H, W, 3) uint8 RGB -> (n_cams, W) bool scanlines; updates the temporal state."""
        opened = self._foreground_stacked(frames)
        return self._scanlines(_counts(self.rectifier.remap_stacked(opened)))

    def process_with_truth(self, frames, labels) -> tuple[np.ndarray, np.ndarray]:
        """``(process(frames), ground_truth(labels)[1])`` with one rectification pass for both.

        frames : (n_cams, H, W, 3) uint8 RGB; labels : (n_cams, H, W) int, 0 background
        Returns (scanlines, gt_scanlines), each (n_cams, W) bool; updates the temporal state.
        The opened foreground (bit 7) and the true mask (bit 0) share one image, so the
        rectification maps (~1.4 MB per camera, most of the remap's cost) are read once:
        per column, the ``F`` pixels with bit 7 are the foreground count and a pixel with
        bit 0 makes the true scanline occupied (:mod:`pipeline.truth_kernel`). Bit for bit
        what the two calls give (tests).
        """
        from .truth_kernel import count_columns, mark_truth  # numba: compiled on first use

        opened = self._foreground_stacked(frames)                 # 0/255, a fresh array
        lab = np.ascontiguousarray(self._check_labels(labels))
        mark_truth(opened, lab, self.row_stride)                  # bit 7 foreground, bit 0 truth
        rect = self.rectifier.remap_stacked(opened)                 # (n, Ho, W): 0, 1, 128, 129
        counts = np.empty((self.n_cams, rect.shape[2]), np.int32)  # F
        truth = np.empty(counts.shape, bool)
        count_columns(rect, counts, truth)
        return self._scanlines(counts.astype(np.float64)), truth

    def _scanlines(self, sums: np.ndarray) -> np.ndarray:
        """Column counts (n_cams, W) float64 -> scanlines (n_cams, W) bool; updates the temporal state."""
        p = self.params
        smoothed = temporal_smooth(spatial_smooth(sums, p.spatial_kernel), self._state, p.temporal_alpha)
        self._state = smoothed
        return median_threshold(smoothed, p.median_kernel, p.column_threshold)

    def _foreground_stacked(self, frames) -> np.ndarray:
        self._need_background()
        frames = check_frames("frames", frames, self.frame_shape)
        self._terms.mask(frames, self._buf)
        stacked = self._buf.reshape(-1, self.width)
        opened = open_stacked(stacked, self.params.opening_kernel, self.height)
        return opened.copy() if opened is stacked else opened

    def ground_truth(self, labels) -> tuple[np.ndarray, np.ndarray]:
        """True foreground and scanlines from label images.

        labels : (n_cams, H, W) int, 0 background, person id + 1 elsewhere (raw image)
        Returns (mask (n_cams, H, W) bool, scanlines (n_cams, width) bool): columns where
        any person is after the same undistortion and rectification (no opening, no smoothing).
        """
        mask = self._check_labels(labels) > 0
        return mask, true_scanlines(self.rectifier.rectify(mask))

    def _check_labels(self, labels) -> np.ndarray:
        lab = np.asarray(labels)
        if lab.shape != self.frame_shape:
            n, h, w = self.frame_shape
            raise ValueError(f"labels: expected shape ({n}, {h}, {w}), got {tuple(lab.shape)}")
        return lab


def _column_sums(rect: np.ndarray) -> np.ndarray:
    """Column sums of rectified uint8 images (n_cams, Ho, W) -> (n_cams, W) int32."""
    return np.stack([cv2.reduce(r, 0, cv2.REDUCE_SUM, dtype=cv2.CV_32S)[0] for r in rect])


def _counts(rect: np.ndarray) -> np.ndarray:
    """Column sums of rectified 0/255 masks (n_cams, Ho, W) -> (n_cams, W) float64 pixel counts."""
    return _column_sums(rect).astype(np.float64) / 255.0
