"""Lossless video per camera: FFV1 in Matroska through imageio-ffmpeg's bundled ffmpeg.

Frames go in as (H, W, 3) uint8 RGB and come back bit for bit (FFV1 is lossless; the
pixel format on disk is ``bgr0``, 8 bits per channel, no chroma subsampling). The
encoder runs single-threaded with ``+bitexact`` flags and no metadata, so the same
frames give the same bytes (no muxer dates or version strings).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from scene.checks import check_input_file

#: Codec options that make the output depend only on the frames.
BITEXACT = ["-threads", "1", "-slices", "4", "-level", "3", "-fflags", "+bitexact", "-flags", "+bitexact",
            "-map_metadata", "-1"]


class VideoWriter:
    """Append (H, W, 3) uint8 RGB frames to a lossless ``.mkv``; :meth:`close` finishes it."""

    def __init__(self, path: str | os.PathLike, width: int, height: int, fps: float):
        import imageio_ffmpeg

        self.path = Path(path)
        self.shape = (int(height), int(width), 3)
        self._gen = imageio_ffmpeg.write_frames(
            str(self.path), (int(width), int(height)), fps=float(fps), codec="ffv1", pix_fmt_in="rgb24",
            pix_fmt_out="bgr0", quality=None, macro_block_size=1, ffmpeg_log_level="error",
            output_params=BITEXACT)
        self._gen.send(None)

    def write(self, rgb: np.ndarray) -> None:
        rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
        if rgb.shape != self.shape:
            raise ValueError(f"frame: expected shape {self.shape}, got {rgb.shape}")
        self._gen.send(rgb)

    def close(self) -> None:
        if self._gen is not None:
            self._gen.close()
            self._gen = None


def read_video(path: str | os.PathLike) -> Iterator[np.ndarray]:
    """Yield the (H, W, 3) uint8 RGB frames of a video written by :class:`VideoWriter`."""
    import imageio_ffmpeg

    path = check_input_file("video", path)
    gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24", bits_per_pixel=24)
    meta = next(gen)
    w, h = meta["size"]
    for raw in gen:
        yield np.frombuffer(raw, np.uint8).reshape(h, w, 3)
