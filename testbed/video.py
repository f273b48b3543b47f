"""MP4 output through imageio-ffmpeg's bundled ffmpeg, written atomically."""

from __future__ import annotations

import os

import numpy as np


class VideoWriter:
    """Collects RGB frames into ``path`` (H.264 MP4, a ``.mp4`` name whose folder exists or
    can be made); the file appears only when closed cleanly.

    Frames of a different size than the first are padded or cropped to it.
    """

    def __init__(self, path: str | os.PathLike, fps: float):
        import imageio_ffmpeg

        from testbed.lossless import ffmpeg_exe
        from testbed.output import check_output_file

        self.path = check_output_file("--video", path, ".mp4")
        ffmpeg_exe()                  # one line naming it now, not an errno at the first frame
        # a name of this run's own: two runs given one --video must not write into one file
        self.tmp = self.path.with_name(f".{self.path.stem}.partial-{os.getpid()}-{os.urandom(4).hex()}{self.path.suffix}")
        self.fps = fps
        self._ffmpeg = imageio_ffmpeg
        self._gen = None
        self._size = None

    def write(self, frame: np.ndarray) -> None:
        frame = np.ascontiguousarray(frame, np.uint8)
        if self._gen is None:
            h, w = frame.shape[:2]
            self._size = (w - w % 2, h - h % 2)
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._gen = self._ffmpeg.write_frames(
                str(self.tmp), self._size, fps=self.fps, codec="libx264", pix_fmt_in="rgb24",
                quality=7, macro_block_size=2, ffmpeg_log_level="error")
            self._gen.send(None)
        w, h = self._size
        canvas = np.full((h, w, 3), 255, np.uint8)
        hh, ww = min(h, frame.shape[0]), min(w, frame.shape[1])
        canvas[:hh, :ww] = frame[:hh, :ww]
        try:
            self._gen.send(canvas)
        except OSError as exc:        # imageio-ffmpeg's message holds ffmpeg's whole command line
            raise OSError(f"--video: ffmpeg stopped writing {self.path} ({type(exc).__name__})") from None

    def close(self, ok: bool = True) -> None:
        """Finish the file (``ok``) or remove it; an interrupt while ffmpeg finishes removes it too."""
        try:
            if self._gen is not None:
                self._gen.close()
            # imageio-ffmpeg does not report ffmpeg's exit status: an empty file is a failure
            wrote = self.tmp.exists() and self.tmp.stat().st_size > 0
            if ok and self._gen is not None and wrote:
                os.replace(self.tmp, self.path)
                return
            if ok and self._gen is not None:
                raise OSError(f"--video: ffmpeg wrote nothing to {self.path}")
        finally:
            self.tmp.unlink(missing_ok=True)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.close(ok=exc_type is None)
