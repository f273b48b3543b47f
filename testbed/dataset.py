"""Render datasets on disk: the layout, written atomically (see docs/dataset.md).

::

    DIR/calibration/camNN.yaml   cv2.FileStorage: camera_matrix (3x3, pixels),
                                 distortion_coefficients (1x5: k1 k2 p1 p2 k3),
                                 rvec, tvec (3x1, world -> camera, radians / metres),
                                 image_width, image_height (pixels)
    DIR/frames/camNN/NNNNNN.png  RGB frames as rendered (distorted, noisy); BGR on disk
    DIR/masks/camNN/NNNNNN.png   uint8 labels: 0 background, person id + 1 elsewhere
    DIR/background/camNN.png     the empty room, clean (no noise, no gain)
    DIR/people.csv               frame, person_id, x, y, radius, height (metres, world)
    DIR/meta.json                seed, scene, frame count, dt, package versions

Camera numbers NN count from 01; frame numbers NNNNNN from 000000. A
:class:`DatasetWriter` writes into a temporary folder next to DIR and renames it into
place on success, so a half-written DIR never exists.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
from pathlib import Path
from typing import Self

import cv2
import numpy as np

from pipeline.files import temp_folder
from scene.camera import Camera
from testbed.png import write_png


def frame_name(index: int) -> str:
    """``NNNNNN.png`` for the 0-based frame ``index``."""
    return f"{index:06d}.png"


def write_calibration(path: str | os.PathLike, camera: Camera) -> None:
    """Write ``camera``'s calibration as an OpenCV FileStorage YAML file."""
    rvec, _ = cv2.Rodrigues(np.asarray(camera.R, float))
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    try:
        fs.write("camera_number", int(camera.number))
        fs.write("image_width", int(camera.width))
        fs.write("image_height", int(camera.height))
        fs.write("camera_matrix", np.asarray(camera.K, float))
        fs.write("distortion_coefficients", np.asarray(camera.dist, float).reshape(1, 5))
        fs.write("rvec", rvec.reshape(3, 1))
        fs.write("tvec", np.asarray(camera.t, float).reshape(3, 1))
    finally:
        fs.release()


def read_calibration(path: str | os.PathLike) -> dict:
    """The arrays of a calibration file: K (3, 3), dist (5,), rvec (3,), tvec (3,), width, height."""
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    try:
        return {
            "K": fs.getNode("camera_matrix").mat(),
            "dist": fs.getNode("distortion_coefficients").mat().ravel(),
            "rvec": fs.getNode("rvec").mat().ravel(),
            "tvec": fs.getNode("tvec").mat().ravel(),
            "width": int(fs.getNode("image_width").real()),
            "height": int(fs.getNode("image_height").real()),
        }
    finally:
        fs.release()


def check_output_dir(out: str | os.PathLike, overwrite: bool) -> Path:
    """``out`` as a Path; refuse an existing non-empty directory unless ``overwrite``."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"--out: {out} exists and is not a directory")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise FileExistsError(f"--out: {out} exists and is not empty; choose another directory "
                              "or pass --overwrite to replace it")
    return out


class DatasetWriter:
    """Writes one render dataset into a temporary sibling of ``out``, then renames it.

    Use as a context manager: on success the temporary folder replaces ``out``; on an
    exception it is removed and ``out`` is left as it was.
    """

    def __init__(self, out: str | os.PathLike, cameras, overwrite: bool = False):
        self.out = check_output_dir(out, overwrite)
        self.cameras = tuple(cameras)
        self.out.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = temp_folder(self.out.parent, f".{self.out.name}.")
        for sub in ("calibration", "background"):
            (self.tmp / sub).mkdir()
        for c in self.cameras:
            (self.tmp / "frames" / c.name).mkdir(parents=True)
            (self.tmp / "masks" / c.name).mkdir(parents=True)
            write_calibration(self.tmp / "calibration" / f"{c.name}.yaml", c)
        self._people = []

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return
        self._finish()

    def write_background(self, rgb: np.ndarray) -> None:
        """rgb : (n_cams, H, W, 3) uint8, one image per camera of the writer."""
        for c, img in zip(self.cameras, rgb, strict=True):
            write_png(self.tmp / "background" / f"{c.name}.png", img)

    def write_frame(self, index: int, rgb: np.ndarray, labels: np.ndarray, positions_xy: np.ndarray,
                    radius: float, height: float) -> None:
        """Frame ``index``: rgb (n_cams, H, W, 3) uint8, labels (n_cams, H, W) uint8,
        positions_xy (m, 2) metres world frame."""
        name = frame_name(index)
        for c, img, lab in zip(self.cameras, rgb, labels, strict=True):
            write_png(self.tmp / "frames" / c.name / name, img)
            write_png(self.tmp / "masks" / c.name / name, lab)
        for pid, (x, y) in enumerate(np.asarray(positions_xy, float)):
            self._people.append((index, pid, repr(float(x)), repr(float(y)), radius, height))

    def write_meta(self, meta: dict) -> None:
        (self.tmp / "meta.json").write_text(json.dumps(meta, indent=2, sort_keys=True) + "\n")

    def _finish(self) -> None:
        with open(self.tmp / "people.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["frame", "person_id", "x", "y", "radius", "height"])
            w.writerows(self._people)
        if self.out.exists():
            old = self.out.with_name(f".{self.out.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            self.out.rename(old)
            self.tmp.rename(self.out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            self.tmp.rename(self.out)


def read_people(path: str | os.PathLike) -> np.ndarray:
    """people.csv as a structured array (frame, person_id, x, y, radius, height)."""
    return np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
