"""The room: a floor polygon and a ceiling height."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely

from .checks import check_array, check_positive, readonly

FOOT = 0.3048
"""One foot in metres."""

@dataclass(frozen=True, eq=False)
class Room:
    """A room with a polygonal floor.

    vertices : (k, 2) float, metres, world frame, counter-clockwise floor outline
    height : float, metres, ceiling height
    kind : "rectangle" or "circle" (a circle is a fine regular polygon)
    """

    vertices: np.ndarray
    height: float
    kind: str = "rectangle"

    @staticmethod
    def rectangle(width: float, depth: float, height: float) -> Room:
        """A ``width`` (x) by ``depth`` (y) room with a corner at the origin."""
        w = check_positive("room.width", width)
        d = check_positive("room.depth", depth)
        v = np.array([[0.0, 0.0], [w, 0.0], [w, d], [0.0, d]])
        return Room(readonly(v), check_positive("room.height", height), "rectangle")

    @staticmethod
    def circle(radius: float, height: float = 2.5, n_vertices: int = 720) -> Room:
        """A circular room of ``radius`` centred on the origin, as a regular polygon."""
        r = check_positive("room.radius", radius)
        a = np.linspace(0.0, 2 * np.pi, n_vertices, endpoint=False)
        v = r * np.column_stack([np.cos(a), np.sin(a)])
        return Room(readonly(v), check_positive("room.height", height), "circle")

    def __post_init__(self):
        check_array("room.vertices", self.vertices, (None, 2))

    @cached_property
    def polygon(self) -> shapely.Polygon:
        """The floor as a shapely Polygon (metres, world frame)."""
        return shapely.Polygon(self.vertices)

    @property
    def area(self) -> float:
        """Floor area, square metres."""
        return float(self.polygon.area)

    def contains_disc(self, center_xy, radius: float) -> bool:
        """True if the disc lies inside the floor (touching the wall counts as outside)."""
        p = shapely.Point(center_xy)
        return bool(self.polygon.contains(p) and self.polygon.exterior.distance(p) > radius)

    def contains_point(self, xy) -> bool:
        """True if the floor point ``xy`` (metres) is inside the room or on its wall."""
        return bool(self.polygon.covers(shapely.Point(xy)))
