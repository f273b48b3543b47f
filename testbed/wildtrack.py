"""Export an episode in the WILDTRACK / MultiviewX layout read by multi-view detection code.

::

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

Ground grid: origin at the corner ``(min x, min y)`` of the room's bounds (the world
origin for the lab; ``origin_m`` in grid.json), cells of ``CELL`` = 0.025 m (WILDTRACK's
2.5 cm), ``x_index = floor((x - min x) / CELL)`` (0..268 along the lab's 22 ft wall),
``y_index = floor((y - min y) / CELL)`` (0..231 along its 19 ft wall), ``positionID =
x_index + grid_width * y_index`` (WILDTRACK's own convention, with its 480 replaced by
our grid width, 269 for the lab). Boxes are inclusive pixel bounds of the person's *visible*
label mask in the image as exported, all -1 when the person is not visible in that view;
``viewNum`` is 0-based over the episode's cameras in number order.

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
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np

from pipeline.files import temp_folder
from testbed.dataset import read_people
from testbed.png import write_png

#: Side of a ground-grid cell, metres (WILDTRACK: 2.5 cm).
CELL = 0.025


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
    out = np.full((len(labels), people, 4), -1, int)
    for c, lab in enumerate(labels):
        for i in range(people):
            rows = np.flatnonzero((lab == i + 1).any(axis=1))
            if rows.size:
                cols = np.flatnonzero((lab[rows[0]:rows[-1] + 1] == i + 1).any(axis=0))
                out[c, i] = (cols[0], rows[0], cols[-1], rows[-1])
    return out


def _write_extrinsic(path: Path, rvec: np.ndarray, tvec: np.ndarray) -> None:
    """WILDTRACK's extrinsic file: ``<rvec>a b c</rvec>`` and ``<tvec>..</tvec>`` in an
    ``opencv_storage`` root, each one line of numbers split by single spaces.

    cv2.FileStorage reads each as a sequence; MVDet's WILDTRACK reader parses the element's
    text with ElementTree and ``split(' ')``. (FileStorage itself would write matrices,
    which that reader cannot parse, and wraps long sequences over lines.)
    """
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


def export_wildtrack(episode: str | os.PathLike, out: str | os.PathLike, undistort: bool = False,
                     progress: Callable[[int], None] | None = None) -> Path:
    """Write episode folder ``episode`` to ``out`` in the WILDTRACK layout (atomically); return ``out``.

    undistort : export pinhole images (and boxes) with zero distortion coefficients
    progress : called with 1 for every image written (from several threads)
    Cameras are exported on a thread per core (OpenCV and the PNG encoder release the GIL).
    """
    from scene import Scene
    from testbed.dataset import read_calibration
    from testbed.parallel import default_workers

    episode, out = Path(episode), Path(out)
    meta = json.loads((episode / "meta.json").read_text())
    numbers = list(meta["cameras"])
    frames = int(meta["frames"])
    room = Scene.from_text(meta["scene_yaml"], source=str(episode / "meta.json")).room
    origin, gw, gh = ground_grid(room.polygon.bounds)
    table = read_people(episode / "people.csv")
    P = int(meta["people"])
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = temp_folder(out.parent, f".{out.name}.")
    try:
        for sub in ("annotations_positions", "calibrations/intrinsic_zero", "calibrations/extrinsic"):
            (tmp / sub).mkdir(parents=True)
        maps = {}                              # camera number -> undistortion maps (undistort only)
        for n in numbers:
            (tmp / "Image_subsets" / f"C{n}").mkdir(parents=True)
            c = read_calibration(episode / "calibration" / f"cam{n:02d}.yaml")
            dist = c["dist"].reshape(1, 5)
            if undistort:
                maps[n] = undistort_maps(c["K"], c["dist"], (c["width"], c["height"]))
                dist = np.zeros_like(dist)
            _write_fs(tmp / "calibrations" / "intrinsic_zero" / f"intr_C{n}.xml",
                      camera_matrix=c["K"], distortion_coefficients=dist)
            _write_extrinsic(tmp / "calibrations" / "extrinsic" / f"extr_C{n}.xml", c["rvec"], c["tvec"])
        with ThreadPoolExecutor(max_workers=min(default_workers(), len(numbers))) as pool:
            b = np.stack(list(pool.map(
                lambda n: _export_camera(episode, meta, n, P, tmp / "Image_subsets" / f"C{n}", maps.get(n), progress),
                numbers)), axis=1)                                     # (frames, n_cams, P, 4)
        for f in range(frames):
            rows = table[table["frame"] == f]
            xy = np.column_stack([rows["x"], rows["y"]]).astype(float)
            pids = position_id(xy, gw, origin)
            ann = [{"personID": int(rows["person_id"][k]), "positionID": int(pids[k]),
                    "views": [{"viewNum": v, "xmin": int(b[f, v, k, 0]), "ymin": int(b[f, v, k, 1]),
                               "xmax": int(b[f, v, k, 2]), "ymax": int(b[f, v, k, 3])} for v in range(len(numbers))]}
                   for k in range(len(rows))]
            (tmp / "annotations_positions" / f"{f:08d}.json").write_text(json.dumps(ann))
        (tmp / "grid.json").write_text(json.dumps({
            "cell_m": CELL, "origin_m": list(origin), "grid_width": gw, "grid_height": gh,
            "position_id": "x_index + grid_width * y_index, x_index = floor((x - origin_m[0]) / cell_m), "
                           "y_index = floor((y - origin_m[1]) / cell_m)",
            "views": {str(v): n for v, n in enumerate(numbers)}, "units": "metres, world frame",
            "undistorted": bool(undistort), "source": str(episode)}, indent=1) + "\n")
        if out.exists():
            shutil.rmtree(out)
        os.rename(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def _remapped(image: np.ndarray, maps, interpolation: int) -> np.ndarray:
    """``image`` through the undistortion ``maps`` (or unchanged when ``maps`` is None)."""
    if maps is None:
        return image
    return cv2.remap(image, maps[0], maps[1], interpolation, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def _export_camera(episode: Path, meta: dict, number: int, people: int, dest: Path, maps,
                   progress: Callable[[int], None] | None) -> np.ndarray:
    """Camera ``number``'s RGB frames to ``dest/NNNNNNNN.png`` (copied PNGs, decoded video, or
    undistorted); returns its boxes (frames, people, 4) int from its label masks (see :func:`boxes`)."""
    from pipeline.io import read_labels

    frames = int(meta["frames"])
    if meta.get("format") == "video":
        from testbed.lossless import read_video
        images = read_video(episode / "frames" / f"cam{number:02d}.mkv")
    else:
        images = (episode / "frames" / f"cam{number:02d}" / f"{f:06d}.png" for f in range(frames))
    out = np.empty((frames, people, 4), int)
    for f, image in zip(range(frames), images, strict=True):
        if isinstance(image, Path) and maps is None:
            shutil.copyfile(image, dest / f"{f:08d}.png")
        else:
            if isinstance(image, Path):
                image = cv2.cvtColor(cv2.imread(str(image), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
            write_png(dest / f"{f:08d}.png", _remapped(image, maps, cv2.INTER_LINEAR))
        labels = read_labels(episode / "masks" / f"cam{number:02d}" / f"{f:06d}.png").astype(np.uint16)
        out[f] = boxes(_remapped(labels, maps, cv2.INTER_NEAREST)[None], people)[0]
        if progress is not None:
            progress(1)
    return out
