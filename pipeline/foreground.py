"""Background model, colour-angle foreground and morphological opening (steps 1-3).

A pixel is foreground when the angle between its RGB vector ``a`` and the background's
``b`` exceeds the threshold ``theta``. No arccos is taken: since RGB vectors are
non-negative, ``a . b >= 0`` and, for ``theta < 90`` degrees,

    angle(a, b) > theta  <=>  (a . b)^2 < cos^2(theta) |a|^2 |b|^2.

**Brightness floor.** The angle of a dark vector is dominated by noise (and undefined at
black). Where ``min(|a|, |b|) < brightness_floor`` the pixel is instead foreground when the
RGB difference is large, ``|a - b| > dark_delta``, computed from the same terms as
``|a|^2 + |b|^2 - 2 a . b``. So a dark person in front of a bright wall, or a lit person
in front of a black wall, is still found; dark noise on dark background is not.

>>> bg = np.full((1, 4, 4, 3), 100, np.uint8)
>>> fr = bg.copy(); fr[0, 1:3, 1:3] = (200, 50, 50)          # a reddish square
>>> colour_angle_foreground(fr, background_model(bg), 5.0, 10.0, 20.0)[0].astype(int)
array([[0, 0, 0, 0],
       [0, 1, 1, 0],
       [0, 1, 1, 0],
       [0, 0, 0, 0]])
"""

from __future__ import annotations

import copy

import cv2
import numpy as np


def check_frames(name: str, frames, shape: tuple | None = None) -> np.ndarray:
    """Return ``frames`` as a (n, H, W, 3) uint8 array, checking ``shape`` = (n, H, W) if given."""
    arr = np.asarray(frames)
    if arr.dtype != np.uint8:
        raise ValueError(f"{name}: expected dtype uint8 (8-bit RGB), got {arr.dtype}")
    if arr.ndim != 4 or arr.shape[-1] != 3:
        raise ValueError(f"{name}: expected shape (n_cams, H, W, 3), got {tuple(arr.shape)}")
    if 0 in arr.shape:
        raise ValueError(f"{name}: expected non-empty images, got shape {tuple(arr.shape)}")
    if shape is not None and tuple(arr.shape[:3]) != tuple(shape):
        n, h, w = shape
        raise ValueError(f"{name}: expected shape ({n}, {h}, {w}, 3) to match the calibration "
                         f"(n_cams, height, width), got {tuple(arr.shape)}")
    return arr


def background_model(frames, numbers=None) -> np.ndarray:
    """Mean of empty-room frames.

    frames : (n_cams, H, W, 3) uint8, or (n_frames, n_cams, H, W, 3) uint8, RGB
    numbers : the cameras' numbers, for the error (default their indices)
    Returns background : (n_cams, H, W, 3) float32, RGB, read-only.
    Raises if a camera's background is all black (the colour angle is then undefined).
    """
    arr = np.asarray(frames)
    if arr.ndim == 4:
        arr = arr[None]
    if arr.ndim != 5 or arr.dtype != np.uint8 or arr.shape[-1] != 3 or 0 in arr.shape:
        raise ValueError("background: expected uint8 frames of shape (n_cams, H, W, 3) or "
                         f"(n_frames, n_cams, H, W, 3), got {arr.dtype} {tuple(arr.shape)}")
    bg = arr.mean(axis=0, dtype=np.float64).astype(np.float32)
    check_lit(bg, numbers)
    bg.setflags(write=False)
    return bg


def check_lit(background: np.ndarray, numbers=None) -> None:
    """Raise naming the first camera (its number from ``numbers``, else its index) whose
    ``background`` (n_cams, H, W, 3) is all black: the colour angle is then undefined (a
    camera facing a wall a few centimetres away, or looking out of the lit room)."""
    black = ~np.asarray(background).reshape(len(background), -1).any(axis=1)
    if black.any():
        i = int(np.flatnonzero(black)[0])
        which = f"camera {numbers[i]}" if numbers is not None else f"camera index {i}"
        raise ValueError(f"background: {which} sees all black; expected an image of the lit, empty room "
                         "(is it facing a wall from a few centimetres, or looking out of the room?)")


class AngleTerms:
    """The colour-angle test of one rig's background, in one compiled pass per frame.

    background : (n_cams, H, W, 3) float32; threshold_deg : degrees; brightness_floor,
    dark_delta : RGB norms, 8-bit levels. The per-pixel terms |b|^2 and cos^2 |b|^2 are
    taken on the fly (:mod:`pipeline.angle_kernel`): nothing is precomputed per pixel.
    A background of whole levels (one clean frame, as datasets record it) is kept as
    uint8, a quarter of the bytes to read per frame, with the same results (the float32
    terms of whole levels are exact). Any other is kept as float32: a read-only array
    (``background_model``'s) as it is, a writeable one copied.
    """

    def __init__(self, background: np.ndarray, threshold_deg: float, brightness_floor: float,
                 dark_delta: float):
        from .angle_kernel import angle_mask  # numba: imported (and compiled) on first use

        self._kernel = angle_mask
        bg = np.ascontiguousarray(background, dtype=np.float32)
        whole = bg.min() >= 0 and bg.max() <= 255 and np.array_equal(np.rint(bg), bg)
        if not whole and bg.flags.writeable and np.may_share_memory(bg, background):
            bg = bg.copy()      # the caller's own array: its writes must not change the model
        self._levels = bg.astype(np.uint8) if whole else bg       # what the compiled pass reads
        self._set_thresholds(threshold_deg, brightness_floor, dark_delta)

    def _set_thresholds(self, threshold_deg: float, brightness_floor: float, dark_delta: float) -> None:
        c = np.cos(np.radians(threshold_deg))
        self.c2 = float(c * c)
        self.floor2 = np.float32(brightness_floor) ** 2
        self.delta2 = np.float32(dark_delta) ** 2

    def with_thresholds(self, threshold_deg: float, brightness_floor: float, dark_delta: float) -> AngleTerms:
        """The same background (shared, not copied) with other thresholds."""
        terms = copy.copy(self)
        terms._set_thresholds(threshold_deg, brightness_floor, dark_delta)
        return terms

    @property
    def background(self) -> np.ndarray:
        """(n_cams, H, W, 3) float32, read-only."""
        bg = self._levels.astype(np.float32, copy=self._levels.dtype != np.float32)
        bg.setflags(write=False)
        return bg

    def mask(self, frames: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Foreground of ``frames`` (n_cams, H, W, 3) uint8 into ``out[:, :H]`` (255 or 0).

        out : (n_cams, rows, W) uint8, C-contiguous, rows >= H (rows past H are left as they are)
        """
        n, h, w = self._levels.shape[:3]
        if frames.shape != (n, h, w, 3) or frames.dtype != np.uint8:
            raise ValueError(f"frames: expected ({n}, {h}, {w}, 3) uint8, got {frames.shape} {frames.dtype}")
        if (out.ndim != 3 or out.shape[0] != n or out.shape[1] < h or out.shape[2] != w
                or out.dtype != np.uint8 or not out.flags.c_contiguous):
            raise ValueError(f"out: expected C-contiguous ({n}, >= {h}, {w}) uint8, got {out.shape} {out.dtype}")
        return self._kernel(np.ascontiguousarray(frames), self._levels, self.c2, self.floor2,
                            self.delta2, out)


def colour_angle_foreground(frames, background, threshold_deg: float, brightness_floor: float,
                            dark_delta: float) -> np.ndarray:
    """Colour-angle foreground mask.

    frames : (n_cams, H, W, 3) uint8, RGB
    background : (n_cams, H, W, 3) float32, RGB (from :func:`background_model`)
    threshold_deg : degrees; brightness_floor, dark_delta : RGB norms, 8-bit levels
    Returns (n_cams, H, W) bool.
    """
    background = np.asarray(background, np.float32)
    frames = check_frames("frames", frames, background.shape[:3])
    out = np.empty(frames.shape[:3], np.uint8)
    AngleTerms(background, threshold_deg, brightness_floor, dark_delta).mask(frames, out)
    return out != 0


def open_masks(masks, kernel: int) -> np.ndarray:
    """Morphological opening of each mask with a ``kernel`` x ``kernel`` square, zero outside.

    masks : (n_cams, H, W) bool
    Returns (n_cams, H, W) bool. Pixels beyond the image count as background (the same in
    every implementation here).

    >>> m = np.zeros((1, 5, 6), bool); m[0, 1:4, 1:4] = True; m[0, 0, 5] = True
    >>> open_masks(m, 3)[0].astype(int)
    array([[0, 0, 0, 0, 0, 0],
           [0, 1, 1, 1, 0, 0],
           [0, 1, 1, 1, 0, 0],
           [0, 1, 1, 1, 0, 0],
           [0, 0, 0, 0, 0, 0]])
    """
    masks = np.asarray(masks, bool)
    if kernel == 1:
        return masks.copy()
    pad = kernel // 2
    n, h, w = masks.shape
    buf = np.zeros((n, h + pad, w), np.uint8)
    buf[:, :h] = masks
    opened = open_stacked(buf.reshape(n * (h + pad), w), kernel, h)
    return opened.reshape(n, h + pad, w)[:, :h].astype(bool)


def open_stacked(stacked: np.ndarray, kernel: int, height: int) -> np.ndarray:
    """Opening of a stack of masks of ``height`` rows laid out with >= kernel // 2 zero rows between them.

    stacked : (rows, W) uint8, 0 or 255 (any one non-zero value). One OpenCV call for all cameras; the zero rows keep the
    cameras apart, and the constant-zero border makes edges behave like the separators. A
    kernel taller than a mask or wider than it always meets a zero: the opening is empty
    (at once, where OpenCV would take seconds per frame for a kernel in the thousands).
    """
    if kernel == 1:
        return stacked
    if kernel > min(height, stacked.shape[1]):
        return np.zeros_like(stacked)
    k = cv2.getStructuringElement(cv2.MORPH_RECT, (kernel, kernel))
    return cv2.morphologyEx(stacked, cv2.MORPH_OPEN, k, borderType=cv2.BORDER_CONSTANT, borderValue=0)
