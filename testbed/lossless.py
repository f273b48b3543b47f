"""Lossless video per camera: FFV1 in Matroska through imageio-ffmpeg's bundled ffmpeg.

Frames go in as (H, W, 3) uint8 RGB and come back bit for bit (FFV1 is lossless; the
pixel format on disk is ``bgr0``, 8 bits per channel, no chroma subsampling). The
encoder runs single-threaded with ``+bitexact`` flags and no metadata, so the same
frames give the same bytes (no muxer dates or version strings).
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from scene.checks import check_input_file

#: Codec options that make the output depend only on the frames.
BITEXACT = ["-threads", "1", "-slices", "4", "-level", "3", "-fflags", "+bitexact", "-flags", "+bitexact",
            "-map_metadata", "-1"]


#: Matroska stores timestamps in milliseconds: above this rate two frames share one and ffmpeg drops one.
MAX_FPS = 1000.0


def check_frame_rate(name: str, fps: float) -> float:
    """``fps`` (Hz) if a Matroska video can hold it, else a one-line ValueError naming ``name``."""
    if not 0 < float(fps) <= MAX_FPS:
        raise ValueError(f"{name}: Matroska stores milliseconds, so at most {MAX_FPS:g} frames per second; "
                         f"got a frame rate of {fps:g} Hz (use --format png)")
    return float(fps)


def ffmpeg_exe() -> str:
    """The ffmpeg that imageio-ffmpeg names, else a one-line OSError: ``camtask render
    --format video`` checks it before any work. imageio-ffmpeg returns IMAGEIO_FFMPEG_EXE
    untested, so a name there that is no program is refused here, naming the variable."""
    import imageio_ffmpeg

    try:
        exe = imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError as exc:
        raise OSError(f"ffmpeg: not found ({' '.join(str(exc).split())})") from None
    if shutil.which(exe) is None:
        given = " (IMAGEIO_FFMPEG_EXE)" if exe == os.environ.get("IMAGEIO_FFMPEG_EXE") else ""
        raise OSError(f"ffmpeg: {exe!r}{given} is not an executable file; install imageio-ffmpeg's "
                      "binaries or point IMAGEIO_FFMPEG_EXE at an ffmpeg")
    return exe


#: The ``[component @ 0x55d0c4a8b740] `` context ffmpeg puts before a message: pointer addresses, noise to a user.
_CONTEXT = re.compile(r"^(\[[^\]]* @ 0x[0-9a-fA-F]+\] *)+")


def _message(log) -> str:
    """ffmpeg's reason in the stderr ``log`` (a binary file), without its context prefixes: its
    summary of a file it could not open (the last line, ``Error opening input files: ...``),
    else its first message (``File ended prematurely``, ``slice CRC mismatch``), not the
    consequences it prints after it (``Nothing was written into output file``)."""
    log.seek(0)
    lines = [_CONTEXT.sub("", ln.strip()) for ln in log.read().decode("utf-8", "replace").splitlines()]
    lines = [ln for ln in lines if ln]
    if not lines:
        return "no message"
    return lines[-1] if lines[-1].startswith("Error opening") else lines[0]


class VideoWriter:
    """Append (H, W, 3) uint8 RGB frames to a lossless ``.mkv``; :meth:`close` finishes it.

    Any failure of ffmpeg (it died, could not write the file: a full disk, a file size
    limit) is an OSError naming the file, from :meth:`write` or :meth:`close`: the file is
    complete when :meth:`close` returns. Frames less than 2 pixels wide or high are a
    ValueError before ffmpeg starts (FFV1 cannot cut them into its slices).
    """

    def __init__(self, path: str | os.PathLike, width: int, height: int, fps: float):
        from fractions import Fraction

        self.path = Path(path)
        self.shape = (int(height), int(width), 3)
        if min(self.shape[:2]) < 2:                     # FFV1's 4 slices need 2 x 2 pixels; ffmpeg fails at frame 1
            raise ValueError(f"cannot write {self.path}: a lossless video needs frames at least 2 pixels wide and "
                             f"high; got {int(width)} x {int(height)}")
        rate = str(Fraction(check_frame_rate("video", fps)).limit_denominator())
        # the command imageio_ffmpeg.write_frames ran (same bytes), with ffmpeg's exit status checked
        cmd = [ffmpeg_exe(), "-y", "-f", "rawvideo", "-vcodec", "rawvideo", "-s", f"{int(width)}x{int(height)}",
               "-pix_fmt", "rgb24", "-r", rate, "-i", "-", "-an", "-vcodec", "ffv1", "-pix_fmt", "bgr0",
               "-v", "error"] + BITEXACT + [str(self.path)]
        self._log = tempfile.TemporaryFile()  # noqa: SIM115 (closed by close())
        self._proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=self._log,
                                      start_new_session=True)      # Ctrl-C reaches this process only
        self.frames = 0

    def _failed(self, proc: subprocess.Popen, what: str) -> OSError:
        proc.kill()
        code = proc.wait()
        status = f"killed by signal {-code}" if code < 0 else f"exit status {code}"
        return OSError(f"cannot write {self.path}: ffmpeg {what} ({status}: {_message(self._log)})")

    def write(self, rgb: np.ndarray) -> None:
        rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
        if rgb.shape != self.shape:
            raise ValueError(f"frame: expected shape {self.shape}, got {rgb.shape}")
        try:
            self._proc.stdin.write(memoryview(rgb).cast("B"))
        except OSError:
            raise self._failed(self._proc, f"stopped at frame {self.frames}") from None
        self.frames += 1

    def close(self) -> None:
        if self._proc is None:
            return
        proc, self._proc = self._proc, None
        try:
            with contextlib.suppress(OSError):          # ffmpeg gone: its status says why
                proc.stdin.close()
            code = proc.wait()
        except BaseException:
            proc.kill()
            proc.wait()
            self._log.close()
            raise
        try:
            if code != 0:
                raise self._failed(proc, f"failed after {self.frames} frame{'s' * (self.frames != 1)}")
            if self.frames == 0:                        # ffmpeg exits 0 on it; no reader takes the file
                raise OSError(f"cannot write {self.path}: closed before any frame was written (a video holds "
                              "at least one)")
        finally:
            self._log.close()


def read_video(path: str | os.PathLike, frames: int | None = None, name: str = "video") -> Iterator[np.ndarray]:
    """Yield the (H, W, 3) uint8 RGB frames of a video (by :class:`VideoWriter`, or any ffmpeg decodes).

    A file ffmpeg cannot open, a slice whose CRC fails, a truncated file (and, given
    ``frames``, another number of frames) is a one-line ValueError naming the file (after
    ``name``, what the messages start with: the file's role or the option that gave it), raised
    once the frames before it are yielded: a frame is yielded only while ffmpeg has
    reported no error (ffmpeg conceals a corrupt slice and goes on decoding; its message
    comes before the frame's bytes), so a corrupt frame never is, not even the first one
    that ``next(read_video(path))`` takes. An ffmpeg that fails without a message (killed,
    or no ffmpeg at all) is an OSError naming it, not the video.

    One ffmpeg decodes the file to PPM images (a header ``P6\\n<w> <h>\\n255\\n``, then the
    RGB bytes): each frame says its own size, so the file is not opened a second time to
    read it (that cost as much as decoding a few frames).
    """
    path = check_input_file(name, path)
    exe = ffmpeg_exe()
    log = tempfile.TemporaryFile()  # noqa: SIM115 (closed in finally)
    proc = subprocess.Popen([exe, "-v", "error", "-nostdin", "-i", str(path), "-map", "0:v:0",
                             "-f", "image2pipe", "-c:v", "ppm", "-pix_fmt", "rgb24", "-"],
                            stdout=subprocess.PIPE, stderr=log, start_new_session=True)
    n, short, held = 0, False, False           # frames yielded; a frame read but not yielded
    try:
        while True:
            head = proc.stdout.readline()
            if not head:
                break
            head += proc.stdout.readline() + proc.stdout.readline()
            magic, size, depth = (head.split(b"\n") + [b"", b""])[:3]
            try:
                w, h = map(int, size.split())
            except ValueError:
                w = h = 0
            raw = proc.stdout.read(w * h * 3) if (magic, depth) == (b"P6", b"255") and w > 0 and h > 0 else b""
            if not raw or len(raw) < w * h * 3:
                short = True                    # ffmpeg's message, when it failed, says more
                break
            if os.fstat(log.fileno()).st_size:  # an error decoding this frame (or one after it)
                held = True
                break
            yield np.frombuffer(raw, np.uint8).reshape(h, w, 3)
            n += 1
        if short:
            proc.stdout.read()                  # at its end already (a short read is the end of output)
        elif held:
            proc.kill()                         # its error is in the log: the frames after it are not wanted
        code = proc.wait()
        log.seek(0)
        said = log.read().strip()
        if code != 0 and not said:              # killed (out of memory?) or broken: not the file's fault
            status = f"was killed by signal {-code}" if code < 0 else f"failed with exit status {code}"
            raise OSError(f"{name}: cannot read {str(path)!r}: ffmpeg ({exe}) {status} without a message")
        if said:
            if n == 0 and not held:
                raise ValueError(f"{name}: cannot read {str(path)!r}: {_message(log)} "
                                 "(not a video ffmpeg can open, or corrupt)")
            raise ValueError(f"{name}: cannot read {str(path)!r} after {n} frame{'' if n == 1 else 's'}: {_message(log)} "
                             "(truncated or corrupt)")
        if short:
            raise ValueError(f"{name}: {str(path)!r}: frame {n} ends early")
        if frames is not None and n != frames:
            raise ValueError(f"{name}: {str(path)!r} holds {n} frame{'' if n == 1 else 's'}; expected {frames}")
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        proc.stdout.close()
        log.close()
