"""Pictures of the network: a top view of the room and a mosaic of tasked frames.

Drawn with OpenCV on uint8 RGB canvases (fast enough for every video frame).
"""

from __future__ import annotations

import cv2
import numpy as np

from scene import Scene
from tasking.cones import column_edges

BACKGROUND = (250, 250, 250)
WALL = (60, 60, 60)
HULL = (240, 150, 40)
CONE = (120, 160, 230)
TRUTH = (20, 140, 20)
TRACK = (200, 30, 30)
CAMERA_ON = (200, 30, 30)
CAMERA_OFF = (150, 150, 150)
#: Positions of a track drawn behind it (and kept: no more).
TAIL = 40


class TopView:
    """Maps floor coordinates (metres) to pixels of a ``width``-pixel-wide canvas.

    The room fills the width less the margins; a room deeper than it is wide fills the
    height of a square canvas instead, centred across (a 1 x 100 m corridor drawn 720
    pixels wide was 66254 pixels tall, more than a video encoder takes).
    """

    def __init__(self, scene: Scene, width: int = 640, margin: int = 30):
        self.scene = scene
        lo = scene.room.vertices.min(axis=0)
        hi = scene.room.vertices.max(axis=0)
        self.scale = (width - 2 * margin) / float(np.max(hi - lo))
        self.lo, self.margin = lo, margin
        self.left = (width - (hi[0] - lo[0]) * self.scale) / 2      # pixels left of the room: the margin, or more
        self.width = width
        self.height = round((hi[1] - lo[1]) * self.scale + 2 * margin)
        self.tails: dict[int, list] = {}
        self.inside = np.zeros((self.height, self.width), np.uint8)
        cv2.fillPoly(self.inside, [self.px(scene.room.vertices)], 1)

    def px(self, xy) -> np.ndarray:
        """Floor points (..., 2) metres -> pixel points (..., 2) int32 (u right, v down; y up)."""
        xy = np.asarray(xy, float)
        u = self.left + (xy[..., 0] - self.lo[0]) * self.scale
        v = self.height - self.margin - (xy[..., 1] - self.lo[1]) * self.scale
        return np.stack([u, v], axis=-1).round().astype(np.int32)

    def draw(self, result, bearings: dict[int, np.ndarray], title: str = "") -> np.ndarray:
        """(height, width, 3) uint8 RGB top view of one :class:`testbed.loop.FrameResult`."""
        img = np.full((self.height, self.width, 3), BACKGROUND, np.uint8)
        reach = 2 * float(np.ptp(self.scene.room.vertices, axis=0).max())
        xy, _, _ = self.scene.floor_poses()
        # Each tasked camera's occluded cones, shaded so that overlaps darken: the hull
        # is where every tasked camera's cones (or its blind side) meet.
        shade = np.zeros((self.height, self.width), np.float32)
        # each tasked camera's column edges; a field of view may cross +-pi (lab cameras 6, 7)
        edges_of = {n: column_edges(np.unwrap(bearings[n])[None])[0] for n in result.tasked}
        for n, scan in zip(result.tasked, result.scanlines):
            c, edges = xy[n - 1], edges_of[n]
            mask = np.zeros((self.height, self.width), np.uint8)
            for lo, hi in _runs(scan):          # from the run's outer column edges, as the hull carves
                fan = np.linspace(edges[lo], edges[hi], 8)
                pts = np.vstack([c, c + reach * np.column_stack([np.cos(fan), np.sin(fan)])])
                cv2.fillPoly(mask, [self.px(pts)], 1)
            shade += mask
        alpha = (0.5 * shade / max(len(result.tasked), 1) * self.inside)[..., None]
        img = (img * (1 - alpha) + np.array(CONE, np.float32) * alpha).astype(np.uint8)
        for n in result.tasked:                          # field-of-view edges
            c, edges = xy[n - 1], edges_of[n]
            for a in (edges[0], edges[-1]):
                cv2.line(img, tuple(self.px(c)), tuple(self.px(c + reach * np.array([np.cos(a), np.sin(a)]))),
                         CAMERA_OFF, 1, cv2.LINE_AA)
        img[self.inside == 0] = BACKGROUND              # cones and edges end at the walls
        for p in result.polygons:                        # holes too: free space carved inside a polygon
            rings = [p.exterior, *p.interiors]
            cv2.fillPoly(img, [self.px(np.asarray(r.coords)) for r in rings], HULL)
        cv2.polylines(img, [self.px(self.scene.room.vertices)], True, WALL, 2, cv2.LINE_AA)
        r = max(2, int(self.scene.people.radius * self.scale))
        for p in result.truth:
            cv2.circle(img, tuple(self.px(p)), r, TRUTH, 2, cv2.LINE_AA)
        for i, p in zip(result.track_ids, result.track_xy):
            tail = self.tails.setdefault(int(i), [])
            tail.append(p)
            del tail[:-TAIL]
            cv2.polylines(img, [self.px(np.array(tail))], False, TRACK, 1, cv2.LINE_AA)
            _track_mark(img, tuple(self.px(p)))
            cv2.putText(img, str(int(i)), tuple(self.px(p) + 6), cv2.FONT_HERSHEY_SIMPLEX, 0.4, TRACK, 1)
        for n in range(1, len(xy) + 1):
            on = n in result.tasked
            q = tuple(self.px(xy[n - 1]))
            _camera_mark(img, q, on)
            cv2.putText(img, str(n), (q[0] + 6, q[1] - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.4, WALL, 1)
        text = title or f"frame {result.index}  hull {result.hull_area:.2f} m2  residual {result.residual:.2f}"
        cv2.putText(img, text, (8, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, WALL, 1, cv2.LINE_AA)
        self._legend(img)
        return img

    def _legend(self, img: np.ndarray) -> None:
        """What the marks mean, each drawn as in the picture, along the bottom margin (as
        squares of colour, tracks and tasked cameras were the same red square)."""
        y, x = self.height - 9, 8
        square = lambda colour: lambda im, c: cv2.rectangle(im, (c[0] - 5, c[1] - 5), (c[0] + 4, c[1] + 4), colour, -1)
        for what, mark in (("person", lambda im, c: cv2.circle(im, c, 5, TRUTH, 2, cv2.LINE_AA)),
                           ("track", _track_mark), ("hull", square(HULL)), ("occluded", square(CONE)),
                           ("tasked camera", lambda im, c: _camera_mark(im, c, True)),
                           ("other camera", lambda im, c: _camera_mark(im, c, False))):
            mark(img, (x + 6, y - 3))
            cv2.putText(img, what, (x + 16, y + 2), cv2.FONT_HERSHEY_SIMPLEX, 0.38, WALL, 1, cv2.LINE_AA)
            x += 16 + cv2.getTextSize(what, cv2.FONT_HERSHEY_SIMPLEX, 0.38, 1)[0][0] + 14


def _track_mark(img: np.ndarray, q) -> None:
    cv2.drawMarker(img, q, TRACK, cv2.MARKER_CROSS, 10, 2)


def _camera_mark(img: np.ndarray, q, tasked: bool) -> None:
    cv2.circle(img, q, 6 if tasked else 4, CAMERA_ON if tasked else CAMERA_OFF, -1, cv2.LINE_AA)


def level_view(rgb: np.ndarray, rectifier, height: int) -> np.ndarray:
    """A camera's frame (H, W, 3) as its level virtual camera sees it, (height, width, 3),
    black where the raw image does not reach and below its ``rectifier.out_height`` rows:
    column j is the vertical plane of column j of the camera's scanline. Raw columns are not
    (pitch and lens bend them): in a lab camera a person at raw columns 560-599 (rows
    200-479) has the run of columns 569-639.

    rectifier : the camera's :class:`pipeline.rectify.Rectifier` (of one camera)
    height : at least ``rectifier.out_height`` (cameras pitched otherwise have other heights)
    """
    out = np.zeros((height, rectifier.width, 3), np.uint8)
    cv2.remap(rgb, rectifier.fixed_map[0], None, cv2.INTER_NEAREST, dst=out[:rectifier.out_height],
              borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    return out


def mosaic(rgb: np.ndarray, scanlines: np.ndarray, numbers, width: int, columns: int = 3) -> np.ndarray:
    """Tasked frames (k, H, W, 3) with their scanlines (k, W) drawn under them, tiled.

    Returns (rows * tile_h, width, 3) uint8 RGB.
    """
    k, h, w, _ = rgb.shape
    tw = width // columns
    th = round(h * tw / w)
    strip = 10
    rows = -(-k // columns)
    out = np.full((rows * (th + strip + 4), width, 3), 255, np.uint8)
    for i in range(k):
        r, c = divmod(i, columns)
        y, x = r * (th + strip + 4), c * tw
        out[y:y + th, x:x + tw] = cv2.resize(rgb[i], (tw, th), interpolation=cv2.INTER_AREA)
        line = cv2.resize(scanlines[i].astype(np.uint8)[None] * 255, (tw, strip), interpolation=cv2.INTER_NEAREST)
        out[y + th:y + th + strip, x:x + tw] = np.where(line[..., None] > 0, (0, 0, 0), (220, 220, 220))
        cv2.putText(out, f"cam {numbers[i]}", (x + 4, y + 14), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 0), 1)
    return out


def _runs(scan: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) column ranges of the True runs of a (W,) bool scanline."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], scan.astype(np.int8), [0]])))
    return list(zip(edges[::2], edges[1::2]))
