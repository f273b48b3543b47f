"""Export an episode in the WILDTRACK or MultiviewX layout read by multi-view detection code.

WILDTRACK (``layout="wildtrack"``)::

    OUT/Image_subsets/C<n>/NNNNNNNN.png      RGB frame of camera n (8-digit frame number)
    OUT/annotations_positions/NNNNNNNN.json  list, one entry per person:
        {"personID": i, "positionID": x_index + GRID_WIDTH * y_index,
         "views": [{"viewNum": v, "xmin": .., "ymin": .., "xmax": .., "ymax": ..}, ...]}
    OUT/calibrations/intrinsic_zero/intr_C<n>.xml   cv2.FileStorage: camera_matrix, distortion_coefficients
                                                    (zeros with ``undistort``)
    OUT/calibrations/extrinsic/extr_C<n>.xml        rvec, tvec (world -> camera, metres) as WILDTRACK
                                                    writes them: one line of numbers each, a
                                                    cv2.FileStorage sequence
    OUT/grid.json                                   the ground grid below, and view -> camera number

MultiviewX (``layout="multiviewx"``): the same, except ``Image_subsets/C<n>/NNNN.png``
(4 digits), ``annotations_positions/NNNNN.json`` (5 digits),
``calibrations/intrinsic/intr_Camera<n>.xml`` and ``calibrations/extrinsic/extr_Camera<n>.xml``
with ``rvec`` and ``tvec`` as cv2.FileStorage 3x1 matrices (MultiviewX readers call
``getNode('rvec').mat()``).

Ground grid: origin at the corner ``(min x, min y)`` of the room's bounds (the world
origin for the lab; ``origin_m`` in grid.json), cells of ``CELL`` = 0.025 m (WILDTRACK's
2.5 cm), ``x_index = floor((x - min x) / CELL)`` (0..268 along the lab's 22 ft wall),
``y_index = floor((y - min y) / CELL)`` (0..231 along its 19 ft wall), ``positionID =
x_index + grid_width * y_index`` (WILDTRACK's own convention, with its 480 replaced by
our grid width, 269 for the lab). Boxes are inclusive pixel bounds, in the image as
exported, of the person's *visible* label mask (``boxes="visible"``) or *unoccluded*
silhouette (``boxes="unoccluded"``: the whole body in view, as a box drawn around an
annotated position; its bottom is the feet even behind someone), all -1 when there are no
such pixels in that view; ``viewNum`` is 0-based over the episode's cameras in number order.

Images are the rendered, lens-distorted frames, and ``intrinsic_zero`` holds the true
distortion coefficients. With ``undistort`` (as WILDTRACK's own ``intrinsic_zero``
files, and what code that projects with ``K [R | t]`` alone expects) every frame is
remapped to the pinhole camera with the same camera matrix and no distortion (bilinear;
the label masks for the boxes by nearest neighbour), and the coefficients written are zeros.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from pipeline.files import temp_folder
from testbed.dataset import PEOPLE_DTYPE, read_meta, read_people
from testbed.output import made_folder
from testbed.png import write_png

#: Side of a ground-grid cell, metres (WILDTRACK: 2.5 cm).
CELL = 0.025


@dataclass(frozen=True)
class Layout:
    """Where a layout puts its files: calibration folders and names, digits of file numbers."""

    intrinsic: str          # folder under calibrations/
    camera: str             # calibration file stem after intr_ / extr_, {n} = camera number
    image_digits: int       # Image_subsets/C<n>/<frame, zero-padded>.png
    annotation_digits: int  # annotations_positions/<frame, zero-padded>.json
    extrinsic_matrices: bool  # rvec, tvec as FileStorage matrices (else WILDTRACK's lines of numbers)


LAYOUTS = {
    "wildtrack": Layout("intrinsic_zero", "C{n}", 8, 8, False),
    "multiviewx": Layout("intrinsic", "Camera{n}", 4, 5, True),
}
#: What the boxes bound: the visible label mask, or the unoccluded silhouette.
BOXES = ("visible", "unoccluded")


def ground_grid(room_bounds) -> tuple[tuple[float, float], int, int]:
    """The grid over the room's bounds ``(min x, min y, max x, max y)``, metres: its origin
    ``(min x, min y)``, metres (the world origin for the lab, whose corner it is), and
    ``(grid_width, grid_height)`` in cells.

    >>> ground_grid((-1.0, -1.0, 1.0, 1.0))
    ((-1.0, -1.0), 80, 80)
    """
    minx, miny, maxx, maxy = map(float, room_bounds)
    return (minx, miny), math.ceil((maxx - minx) / CELL - 1e-9), math.ceil((maxy - miny) / CELL - 1e-9)


def position_id(xy, grid_width: int, origin=(0.0, 0.0)) -> np.ndarray:
    """positionID of floor points ``xy`` (n, 2) metres, world frame, on the grid of ``origin`` (2,) metres.

    >>> position_id([[0.01, 0.0], [0.03, 0.06]], 269).tolist()
    [0, 539]
    """
    idx = np.floor((np.asarray(xy, float) - np.asarray(origin, float)) / CELL).astype(int)
    return idx[:, 0] + grid_width * idx[:, 1]


def boxes(labels: np.ndarray, people: int) -> np.ndarray:
    """Inclusive boxes (xmin, ymin, xmax, ymax) of each person's pixels, (n_cams, people, 4) int, -1 if absent.

    labels : (n_cams, H, W) int, 0 background, person + 1 (pixel indices (row, col); x = col, y = row)
    """
    return _boxes(labels, people, lambda lab, i: lab == i + 1)


def silhouette_boxes(bits: np.ndarray, people: int) -> np.ndarray:
    """:func:`boxes` of unoccluded silhouettes ``bits`` (n_cams, H, W) int, bit i = person i.

    >>> silhouette_boxes(np.array([[[0, 3], [2, 0]]]), 2).tolist()
    [[[1, 0, 1, 0], [0, 0, 1, 1]]]
    """
    return _boxes(bits, people, lambda sil, i: (sil >> i) & 1 == 1)


def _boxes(images: np.ndarray, people: int, mask: Callable[[np.ndarray, int], np.ndarray]) -> np.ndarray:
    out = np.full((len(images), people, 4), -1, int)
    for c, img in enumerate(images):
        for i in range(people):
            m = mask(img, i)
            rows = np.flatnonzero(m.any(axis=1))
            if rows.size:
                cols = np.flatnonzero(m[rows[0]:rows[-1] + 1].any(axis=0))
                out[c, i] = (cols[0], rows[0], cols[-1], rows[-1])
    return out


def _write_extrinsic(path: Path, rvec: np.ndarray, tvec: np.ndarray, matrices: bool = False) -> None:
    """WILDTRACK's extrinsic file: ``<rvec>a b c</rvec>`` and ``<tvec>..</tvec>`` in an
    ``opencv_storage`` root, each one line of numbers split by single spaces.

    cv2.FileStorage reads each as a sequence; MVDet's WILDTRACK reader parses the element's
    text with ElementTree and ``split(' ')``. (FileStorage itself would write matrices,
    which that reader cannot parse, and wraps long sequences over lines.) With ``matrices``,
    MultiviewX's: 3x1 FileStorage matrices.
    """
    if matrices:
        _write_fs(path, rvec=np.reshape(rvec, (3, 1)), tvec=np.reshape(tvec, (3, 1)))
        return
    line = lambda v: " ".join(repr(float(x)) for x in np.ravel(v))
    path.write_text(f'<?xml version="1.0"?>\n<opencv_storage>\n<rvec>{line(rvec)}</rvec>\n'
                    f"<tvec>{line(tvec)}</tvec>\n</opencv_storage>\n")


def _write_fs(path: Path, **mats) -> None:
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    try:
        for k, v in mats.items():
            fs.write(k, np.asarray(v, float))
    finally:
        fs.release()


def undistort_maps(K: np.ndarray, dist: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Float maps (h, w) float32 x and y into the distorted image for the pinhole image of
    the same camera matrix ``K`` (3, 3), pixels; ``dist`` (5,); ``size`` = (w, h) pixels."""
    return cv2.initUndistortRectifyMap(K, dist, None, K, size, cv2.CV_32FC1)


def export_episode(episode: str | os.PathLike, out: str | os.PathLike, layout: str = "wildtrack",
                   undistort: bool = False, box: str = "visible",
                   progress: Callable[[int], None] | None = None, people: np.ndarray | None = None) -> Path:
    """Write episode folder ``episode`` to ``out`` in ``layout`` (atomically); return ``out``.

    layout : a key of ``LAYOUTS``
    undistort : export pinhole images (and boxes) with zero distortion coefficients
    box : what the boxes bound, one of ``BOXES``
    progress : called with 1 for every image written (from several threads)
    people : the episode's :func:`people_table`, when the caller has read it already
    Cameras are exported on a thread per core (OpenCV and the PNG encoder release the GIL).
    ``out`` may be a link to a folder (the folder is replaced). Folders made for ``out`` are
    removed again when the export fails.
    """
    from scene import Scene
    from testbed.parallel import default_workers

    if layout not in LAYOUTS:
        raise ValueError(f"layout: expected one of {', '.join(LAYOUTS)}, got {layout!r}")
    lay = LAYOUTS[layout]
    if box not in BOXES:
        raise ValueError(f"box: expected one of {', '.join(BOXES)}, got {box!r}")
    episode, out = Path(episode), Path(out).resolve()   # resolved: "." has no name to replace
    meta = read_meta(episode)
    numbers = meta["cameras"]
    frames = meta["frames"]
    room = Scene.from_text(meta["scene_yaml"], source=str(episode / "meta.json")).room
    origin, gw, gh = ground_grid(room.polygon.bounds)
    P = meta["people"]
    table = people_table(episode / "people.csv", frames, P) if people is None else people
    calib = read_calibrations(episode, numbers)         # before any folder is made
    tmp = None
    with made_folder("OUT", out.parent):        # removed again when the export fails
        try:
            tmp = temp_folder(out.parent, f".{out.name}.")
            maps = _write_calibrations(tmp, lay, calib, undistort)
            # Ctrl-C stops the cameras being exported at their next frame: the pool's shutdown
            # otherwise waited for each running camera's every frame (~9 s for 300 frames)
            stop = threading.Event()
            with ThreadPoolExecutor(max_workers=min(default_workers(), len(numbers))) as pool:
                try:
                    b = np.stack(list(pool.map(
                        lambda n: _export_camera(episode, meta, n, P, tmp / "Image_subsets" / f"C{n}", maps.get(n),
                                                 lay.image_digits, box, progress, stop),
                        numbers)), axis=1)                                 # (frames, n_cams, P, 4)
                except BaseException:
                    stop.set()
                    raise
            _write_annotations(tmp / "annotations_positions", lay, table, b, gw, origin)
            (tmp / "grid.json").write_text(json.dumps({
                "layout": layout, "cell_m": CELL, "origin_m": list(origin), "grid_width": gw, "grid_height": gh,
                "position_id": "x_index + grid_width * y_index, x_index = floor((x - origin_m[0]) / cell_m), "
                               "y_index = floor((y - origin_m[1]) / cell_m)",
                "views": {str(v): n for v, n in enumerate(numbers)}, "units": "metres, world frame",
                "undistorted": bool(undistort), "boxes": box, "source": os.path.abspath(episode)}, indent=1) + "\n")
            _replace_folder(tmp, out)
        except BaseException:
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)
            raise
    return out


def _write_calibrations(tmp: Path, lay: Layout, calib: dict[int, dict], undistort: bool) -> dict:
    """Make the export's folders in ``tmp`` and write each camera's intrinsic and extrinsic
    FileStorage XML (zero distortion when ``undistort``); return camera number -> its
    undistortion maps (empty without ``undistort``)."""
    calibrations = tmp / "calibrations"
    for sub in ("annotations_positions", f"calibrations/{lay.intrinsic}", "calibrations/extrinsic"):
        (tmp / sub).mkdir(parents=True)
    maps = {}
    for n, c in calib.items():
        (tmp / "Image_subsets" / f"C{n}").mkdir(parents=True)
        dist = c["dist"].reshape(1, 5)
        if undistort:
            maps[n] = undistort_maps(c["K"], c["dist"], (c["width"], c["height"]))
            dist = np.zeros_like(dist)
        stem = lay.camera.format(n=n)
        _write_fs(calibrations / lay.intrinsic / f"intr_{stem}.xml", camera_matrix=c["K"],
                  distortion_coefficients=dist)
        _write_extrinsic(calibrations / "extrinsic" / f"extr_{stem}.xml", c["rvec"], c["tvec"],
                         lay.extrinsic_matrices)
    return maps


def _write_annotations(folder: Path, lay: Layout, table: np.ndarray, boxes: np.ndarray, gw: int,
                       origin) -> None:
    """One JSON file of people per frame: personID, positionID on the ground grid (``gw``
    cells wide from ``origin``, metres) and a box per view.

    boxes : (frames, n_cams, P, 4) int pixels, xmin ymin xmax ymax (-1: not seen)
    """
    for f in range(len(boxes)):
        rows = table[table["frame"] == f]
        pids = position_id(np.column_stack([rows["x"], rows["y"]]).astype(float), gw, origin)
        ann = [{"personID": int(i), "positionID": int(pid),
                "views": [{"viewNum": v, "xmin": int(b[0]), "ymin": int(b[1]), "xmax": int(b[2]), "ymax": int(b[3])}
                          for v, b in enumerate(boxes[f, :, i])]}
               for i, pid in zip(rows["person_id"], pids, strict=True)]
        (folder / f"{f:0{lay.annotation_digits}d}.json").write_text(json.dumps(ann))


def _replace_folder(new: Path, out: Path) -> None:
    """Rename folder ``new`` to ``out``, replacing an earlier ``out`` whole.

    The earlier one is moved aside and deleted once the new one is in place: deleted first,
    a Ctrl-C meanwhile left part of it without its grid.json (refused by --overwrite) and
    neither export. Signals wait until the renames are done.
    """
    from render.gl import signals_held

    aside = None
    try:
        with signals_held():
            if out.exists():
                aside = temp_folder(out.parent, f".{out.name}.replaced-")
                os.replace(out, aside)
                try:
                    os.rename(new, out)
                except BaseException:
                    os.rename(aside, out)
                    aside = None
                    raise
            else:
                os.rename(new, out)
        if aside is not None:
            shutil.rmtree(aside)
    except BaseException:
        if aside is not None:
            shutil.rmtree(aside, ignore_errors=True)
        raise


def read_calibrations(episode: Path, numbers) -> dict[int, dict]:
    """Camera number -> :func:`testbed.dataset.read_calibration` of the episode's
    ``calibration/camNN.yaml``; a file missing or malformed is a one-line error naming it."""
    from testbed.dataset import read_calibration

    return {n: read_calibration(episode / "calibration" / f"cam{n:02d}.yaml") for n in numbers}


def people_table(path: Path, frames: int, people: int) -> np.ndarray:
    """people.csv (:func:`testbed.dataset.read_people`), refused in one line unless it lists
    each of the ``people`` persons once in each of the ``frames`` frames."""
    if people == 0:
        return np.zeros(0, PEOPLE_DTYPE)
    table = read_people(path)
    listed = sorted(zip(table["frame"].tolist(), table["person_id"].tolist()))
    if listed != [(f, i) for f in range(frames) for i in range(people)]:
        raise ValueError(f"{path}: expected one row per person (0..{people - 1}) and frame (0..{frames - 1}), "
                         f"as meta.json says; its {len(table)} rows do not")
    return table


def _remapped(image: np.ndarray, maps, interpolation: int) -> np.ndarray:
    """``image`` through the undistortion ``maps`` (or unchanged when ``maps`` is None)."""
    if maps is None:
        return image
    return cv2.remap(image, maps[0], maps[1], interpolation, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def _export_camera(episode: Path, meta: dict, number: int, people: int, dest: Path, maps, digits: int,
                   box: str, progress: Callable[[int], None] | None,
                   stop: threading.Event | None = None) -> np.ndarray:
    """Camera ``number``'s RGB frames to ``dest/<frame, zero-padded to digits>.png`` (copied
    PNGs, decoded video, or undistorted); returns its boxes (frames, people, 4) int from its
    label masks or silhouettes (``box``; see :func:`boxes`). Returns early, at the next frame,
    once ``stop`` is set (the export is abandoned)."""
    from pipeline.io import read_labels, read_rgb

    frames = int(meta["frames"])
    video = None
    if meta.get("format") == "video":
        from testbed.lossless import read_video
        video = episode / "frames" / f"cam{number:02d}.mkv"
        images = read_video(video, frames)
    else:
        images = (episode / "frames" / f"cam{number:02d}" / f"{f:06d}.png" for f in range(frames))
    folder, find = ("masks", boxes) if box == "visible" else ("silhouettes", silhouette_boxes)
    out = np.empty((frames, people, 4), int)
    done = 0
    for f, image in zip(range(frames), images):
        if stop is not None and stop.is_set():
            if video is not None:
                images.close()                  # its ffmpeg stopped now, not when collected
            return out
        name = dest / f"{f:0{digits}d}.png"
        if isinstance(image, Path) and maps is None:
            if not image.is_file():
                raise ValueError(f"image: cannot read {str(image)!r}")
            shutil.copyfile(image, name)
        else:
            if isinstance(image, Path):
                image = read_rgb(image)
            write_png(name, _remapped(image, maps, cv2.INTER_LINEAR))
        labels = read_labels(episode / folder / f"cam{number:02d}" / f"{f:06d}.png").astype(np.uint16)
        out[f] = find(_remapped(labels, maps, cv2.INTER_NEAREST)[None], people)[0]
        done += 1
        if progress is not None:
            progress(1)
    if video is not None and (done < frames or next(images, None) is not None):
        raise ValueError(f"video: {video} holds {'more than ' if done == frames else ''}{done} frames; "
                         f"meta.json says {frames}")
    return out
