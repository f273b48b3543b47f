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
    DIR/meta.json                seed, scene and its text, people, cameras, frames, dt

and silhouettes, scanlines.npz, pipeline.yaml, gt_hull.json: every file, with units,
is in docs/dataset.md.

Camera numbers NN count from 01; frame numbers NNNNNN from 000000. Episodes are written
by :func:`testbed.episodes.render_episode` into a temporary folder and renamed into place
when complete, so a half-written episode never exists.
"""

from __future__ import annotations

import json
import os
import warnings
from pathlib import Path

import cv2
import numpy as np

from scene.camera import Camera


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
    """The arrays of a calibration file: K (3, 3), dist (5,), rvec (3,), tvec (3,), width, height.

    A file missing or malformed is a one-line ValueError naming it and the key
    (checked by :func:`pipeline.io.load_calibration`).
    """
    from pipeline.io import load_calibration

    load_calibration(path)                  # the arrays read below are there, of their sizes
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


def read_meta(episode: str | os.PathLike, complete: bool = True) -> dict:
    """An episode's meta.json, refused in one line naming the file and the key unless it
    is a JSON object with (when ``complete``) ``cameras`` (distinct integers >= 1),
    ``frames`` (>= 1), ``people`` (>= 0) and ``scene_yaml`` (text), as ``camtask render``
    writes it."""
    from scene.checks import read_input_text

    path = Path(episode) / "meta.json"
    try:
        meta = json.loads(read_input_text("meta.json", path))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise ValueError(f"{path}: expected a JSON object, got {type(meta).__name__}")
    if not complete:
        return meta
    count = lambda v, low: isinstance(v, int) and not isinstance(v, bool) and v >= low
    for key, ok, what in (
            ("cameras", lambda v: isinstance(v, list) and v and all(count(n, 1) for n in v) and len(set(v)) == len(v),
             "a non-empty list of distinct camera numbers >= 1"),
            ("frames", lambda v: count(v, 1), "an integer >= 1"),
            ("people", lambda v: count(v, 0), "an integer >= 0"),
            ("scene_yaml", lambda v: isinstance(v, str), "the scene file's text")):
        if key not in meta:
            raise ValueError(f"{path}: no {key!r} (expected {what})")
        if not ok(meta[key]):
            raise ValueError(f"{path}: {key}: expected {what}, got {json.dumps(meta[key])[:60]}")
    return meta


#: people.csv's columns and their types: frame and person id, then metres (world frame).
PEOPLE_DTYPE = np.dtype([("frame", int), ("person_id", int), ("x", float), ("y", float),
                         ("radius", float), ("height", float)])


def read_people(path: str | os.PathLike) -> np.ndarray:
    """people.csv as a 1-D structured array of :data:`PEOPLE_DTYPE` (frame, person_id, x, y,
    radius, height), one row per person and frame: also for a single row or none. A file
    that cannot be parsed or lacks a column is a one-line ValueError naming it."""
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", "genfromtxt: Empty input file")
            table = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8", ndmin=1,
                                  usemask=True)          # masked: an empty field
    except ValueError as exc:               # "Some errors were detected !\n    Line #2 (got 4 columns ...)"
        raise ValueError(f"{path}: cannot read ({' '.join(str(exc).split())})") from None
    except IndexError:                      # no line at all: genfromtxt looked for a header in vain
        raise ValueError(f"{path}: no header line (expected {','.join(PEOPLE_DTYPE.names)})") from None
    found = table.dtype.names or ()
    for name in PEOPLE_DTYPE.names:
        if name not in found:
            raise ValueError(f"{path}: no column {name!r} (expected the header {','.join(PEOPLE_DTYPE.names)})")
    people = np.empty(len(table), PEOPLE_DTYPE)
    for name in PEOPLE_DTYPE.names:
        column = table[name]
        empty = np.ma.getmaskarray(column)
        try:
            values = np.asarray(column.data, dtype=float)
        except (ValueError, TypeError):     # a word among the numbers
            raise ValueError(f"{path}: column {name!r}: expected numbers, got text") from None
        whole = PEOPLE_DTYPE[name].kind == "i"
        bad = empty | ~np.isfinite(values) | ((values != np.round(values)) if whole else False)
        if bad.any():                       # 1.5 would be cut to 1, an empty field read as -1
            row = int(np.argmax(bad))
            got = "an empty field" if empty[row] else f"{values[row]:g}"
            raise ValueError(f"{path}: column {name!r}, row {row + 1}: expected "
                             f"{'a whole number' if whole else 'a finite number'}, got {got}")
        people[name] = values
    return people
