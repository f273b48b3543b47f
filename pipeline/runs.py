"""Whole runs: a render directory or a video through the pipeline, with metrics.

The scanline metrics compare every (frame, camera, column) with the ground truth from
the label images; the pixel metrics compare the foreground mask after the opening (raw,
distorted image) with ``labels > 0``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from .core import Pipeline
from .metrics import cdnet_metrics, confusion, evaluate
from .params import PipelineParams
from .rle import scanline_bits


@dataclass(frozen=True, eq=False)
class RunResult:
    """scanlines, gt_scanlines : (n_frames, n_cams, W) bool; bearings : (n_cams, W) float
    pixel_counts : (n_cams, 4) int TP, FP, FN, TN of the foreground mask (None without labels)
    """

    scanlines: np.ndarray
    gt_scanlines: np.ndarray | None
    bearings: np.ndarray
    pixel_counts: np.ndarray | None

    def metrics(self) -> dict:
        """JSON-ready metrics: scanline columns overall and per camera, pixels, bandwidth."""
        width = self.scanlines.shape[-1]
        bits = scanline_bits(self.scanlines)
        out = {"frames": int(self.scanlines.shape[0]), "cameras": int(self.scanlines.shape[1]),
               "width": int(width), "rle_bits_mean": float(bits.mean()),
               "rle_bits_max": int(bits.max()), "raw_bits": int(width)}
        if self.gt_scanlines is None:
            return out
        out |= evaluate(self.scanlines, self.gt_scanlines, camera_axis=1)
        c = self.pixel_counts
        tot = {k: int(v) for k, v in zip(("tp", "fp", "fn", "tn"), c.sum(0))}
        per = cdnet_metrics(*c.T)
        out["pixel"] = tot | cdnet_metrics(**tot) | {"per_camera": [
            {k: float(per[k][i]) for k in per} for i in range(len(c))]}
        return out


def run_sequence(pipeline: Pipeline, frames: Iterable[np.ndarray],
                 labels: Iterable[np.ndarray] | None = None,
                 progress: Callable[[], None] | None = None) -> RunResult:
    """Process batches (n_cams, H, W, 3) uint8 in order; labels (n_cams, H, W) int if known,
    one batch per frame batch.

    A run starts from its first frame: the pipeline's temporal state is reset first (a
    pipeline reused for a second sequence smoothed its first frames with the last ones of
    the first). Labels that end before the frames, or go on after them, are a ValueError:
    they would be compared with other frames than their own.
    """
    pipeline.reset()
    scans, gts, counts = [], [], np.zeros((pipeline.n_cams, 4), np.int64)
    labels = iter(labels) if labels is not None else None
    end = object()
    for batch in frames:
        step = pipeline.step(batch)
        scans.append(step.scanlines)
        if labels is not None:
            lab = next(labels, end)
            if lab is end:
                raise ValueError(f"labels: ended after {len(scans) - 1} batches, before the frames; expected one per frame")
            mask, gt = pipeline.ground_truth(lab)
            gts.append(gt)
            c = confusion(step.foreground, mask, axis=(1, 2))
            counts += np.stack([c["tp"], c["fp"], c["fn"], c["tn"]], 1)
        if progress is not None:
            progress()
    if not scans:
        raise ValueError("frames: expected at least one frame after the background")
    if labels is not None and next(labels, end) is not end:
        raise ValueError(f"labels: more batches than the {len(scans)} frames; expected one per frame")
    return RunResult(np.stack(scans), np.stack(gts) if gts else None, pipeline.bearings,
                     counts if labels is not None else None)


def scanline_f1(pipeline: Pipeline, frames, gt_scanlines, params: PipelineParams) -> float:
    """Scanline F1 of ``params`` on an in-memory sequence (for tuning).

    pipeline : a :class:`Pipeline` of the cameras with their background (its parameters
        are not used: :meth:`Pipeline.with_params` shares its maps and background)
    frames : (n_frames, n_cams, H, W, 3) uint8; gt_scanlines : (n_frames, n_cams, W) bool
    """
    pipe = pipeline.with_params(params)
    pred = np.stack([pipe.process(f) for f in frames])
    c = confusion(pred, gt_scanlines)
    return float(cdnet_metrics(**c)["f1"])
