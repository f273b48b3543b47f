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

import cv2
import numpy as np

_ONES = np.ones((1, 3), np.float32)


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


def background_model(frames) -> np.ndarray:
    """Mean of empty-room frames.

    frames : (n_cams, H, W, 3) uint8, or (n_frames, n_cams, H, W, 3) uint8, RGB
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
    black = ~bg.reshape(bg.shape[0], -1).any(axis=1)
    if black.any():
        raise ValueError(f"background: camera index {int(np.flatnonzero(black)[0])} is all black; "
                         "expected an image of the lit, empty room")
    bg.setflags(write=False)
    return bg


class AngleTerms:
    """Per-pixel background terms of the colour-angle test, precomputed once.

    background : (n_cams, H, W, 3) float32
    """

    def __init__(self, background: np.ndarray, threshold_deg: float, brightness_floor: float,
                 dark_delta: float):
        self.background = np.ascontiguousarray(background, dtype=np.float32)
        self.bb = (self.background.astype(np.float64) ** 2).sum(-1).astype(np.float32)
        c = np.cos(np.radians(threshold_deg))
        self.c2bb = (c * c * self.bb).astype(np.float32)
        self.floor2 = np.float32(brightness_floor) ** 2
        self.delta2 = np.float32(dark_delta) ** 2
        self.dark_bg = (self.bb < self.floor2).astype(np.uint8) * 255
        self.cam_dark_bg = self.dark_bg.reshape(len(self.bb), -1).any(axis=1)

    def mask(self, frames: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Foreground of ``frames`` (n_cams, H, W, 3) uint8 into ``out`` (n_cams, H, W) uint8 0/255."""
        h, w = frames.shape[1:3]
        ff = np.empty((h, w, 3), np.float32)
        for i in range(frames.shape[0]):  # per camera: OpenCV kernels on cache-sized arrays
            ff[...] = frames[i]
            dot = cv2.transform(cv2.multiply(ff, self.background[i]), _ONES)
            aa = cv2.transform(cv2.multiply(ff, ff), _ONES)
            cv2.compare(cv2.multiply(dot, dot), cv2.multiply(aa, self.c2bb[i]), cv2.CMP_LT, dst=out[i])
            if self.floor2 > 0:
                dark = cv2.compare(aa, float(self.floor2), cv2.CMP_LT)
                if self.cam_dark_bg[i]:
                    cv2.bitwise_or(dark, self.dark_bg[i], dst=dark)
                if cv2.countNonZero(dark):
                    diff2 = cv2.scaleAdd(dot, -2.0, cv2.add(aa, self.bb[i]))
                    cv2.copyTo(cv2.compare(diff2, float(self.delta2), cv2.CMP_GT), dark, out[i])
        return out


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
    opened = open_stacked(buf.reshape(n * (h + pad), w), kernel)
    return opened.reshape(n, h + pad, w)[:, :h].astype(bool)


def open_stacked(stacked: np.ndarray, kernel: int) -> np.ndarray:
    """Opening of a stack of masks laid out with >= kernel // 2 zero rows between them.

    stacked : (rows, W) uint8, 0 or 255 (any one non-zero value). One OpenCV call for all cameras; the zero rows keep the
    cameras apart, and the constant-zero border makes edges behave like the separators.
    """
    if kernel == 1:
        return stacked
    k = cv2.getStructuringElement(cv2.MORPH_RECT, (kernel, kernel))
    return cv2.morphologyEx(stacked, cv2.MORPH_OPEN, k, borderType=cv2.BORDER_CONSTANT, borderValue=0)
