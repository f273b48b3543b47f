"""Meshes of the room and the people, with Lambert shading baked into vertex colours.

Every mesh is a triangle soup of plain arrays (:class:`Mesh`), so the rasteriser draws
it flat, without lighting: the shading is computed once here, per vertex, from a fixed
directional light, an ambient term and (for the static room only) a lamp under the
ceiling. People are upright cylinders built at the origin; they only ever translate, so
their directional-light shading stays exact when they move.

>>> m = cylinder(0.25, 1.75, np.array([200, 30, 30]), person=0)
>>> m.positions.shape[1], float(m.positions[:, 2].max()), int(m.person.max())
(3, 1.75, 0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from scene.room import FOOT, Room


@dataclass(frozen=True)
class Lighting:
    """The fixed light baked into vertex colours.

    direction : (3,) world frame, the direction the light travels (points down)
    ambient, diffuse : weights of the ambient and directional terms
    lamp : lamp strength (room only); the lamp hangs ``lamp_drop`` metres under the
        ceiling at the centre of the floor
    """

    direction: tuple = (0.35, 0.25, -1.0)
    ambient: float = 0.45
    diffuse: float = 0.45
    lamp: float = 0.35
    lamp_drop: float = 0.3


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle soup.

    positions : (3k, 3) float32, metres, world frame (people: relative to their feet)
    colours : (3k, 3) float32 in [0, 1], RGB with shading baked in
    person : (3k,) float32, person index, -1 for the room
    """

    positions: np.ndarray
    colours: np.ndarray
    person: np.ndarray

    @staticmethod
    def concatenate(meshes) -> Mesh:
        meshes = list(meshes)
        return Mesh(*(np.concatenate([getattr(m, f) for m in meshes]).astype(np.float32)
                      for f in ("positions", "colours", "person")))


def lambert(normals, lighting: Lighting) -> np.ndarray:
    """Directional Lambert factor, (n,) float, for unit ``normals`` (n, 3)."""
    to_light = -np.asarray(lighting.direction, float)
    to_light /= np.linalg.norm(to_light)
    return lighting.ambient + lighting.diffuse * np.clip(normals @ to_light, 0.0, None)


def lamp(points, normals, lamp_world, strength: float) -> np.ndarray:
    """Lambert factor of a point lamp at ``lamp_world`` (3,), with soft 1/d^2 falloff."""
    d = lamp_world - points
    dist = np.linalg.norm(d, axis=1)
    cos = np.clip(np.einsum("ij,ij->i", normals, d) / dist, 0.0, None)
    return strength * cos * 4.0 / (1.0 + dist**2)


def _shade(colours_u8, points, normals, lighting, lamp_world=None) -> np.ndarray:
    f = lambert(normals, lighting)
    if lamp_world is not None:
        f = f + lamp(points, normals, lamp_world, lighting.lamp)
    return np.clip(np.asarray(colours_u8, float) / 255.0 * f[:, None], 0.0, 1.0)


def _quads_to_triangles(quads: np.ndarray) -> np.ndarray:
    """(q, 4, d) quads (corners in order) -> (6q, d) triangle soup."""
    return quads[:, [0, 1, 2, 0, 2, 3]].reshape(-1, quads.shape[-1])


FLOOR_COLOUR = (150, 142, 128)
CEILING_COLOUR = (228, 228, 224)
WALL_COLOURS = ((196, 190, 172), (178, 186, 192), (200, 194, 184), (184, 192, 178))
BASEBOARD = (0.10, (92, 84, 76))  # height (m), colour


def _piece_triangles(piece) -> np.ndarray:
    """A tile clipped to the room, as (3t, 2) float triangle corners, metres.

    A convex polygon is fanned from its first corner (every tile of a rectangle or circle
    room); the parts of any other piece (a concave room's corner makes one, a slot can
    cut a tile in two) go through a constrained Delaunay triangulation, which keeps to
    their outline.
    """
    out = []
    for part in shapely.get_parts(piece):
        if not isinstance(part, shapely.Polygon) or part.area < 1e-12:
            continue                            # a point or segment the clip touched
        if part.interiors or part.convex_hull.area - part.area > 1e-12 * max(part.area, 1.0):
            tris = shapely.get_parts(shapely.constrained_delaunay_triangles(part))
            out.extend(np.asarray(t.exterior.coords)[:3] for t in tris)
            continue
        ring = np.asarray(part.exterior.coords)[:-1]
        out.append(np.stack([np.repeat(ring[:1], len(ring) - 2, 0), ring[1:-1], ring[2:]], 1).reshape(-1, 2))
    return np.concatenate(out) if out else np.empty((0, 2))


def room_mesh(room: Room, lighting: Lighting = Lighting(), tile: float = FOOT,
              cell: float = 1.0) -> Mesh:
    """Floor (tiles with a subtle checker and per-tile variation), walls, ceiling.

    tile : floor tile size, metres; cell : wall and ceiling subdivision, metres (for
    smooth lamp shading).
    """
    lamp_world = np.array([*room.polygon.centroid.coords[0], room.height - lighting.lamp_drop])
    rng = np.random.default_rng(0)  # fixed texture: part of the room, not of a run
    parts = []

    # floor: tiles clipped to the room, each piece cut into triangles
    x0, y0, x1, y1 = room.polygon.bounds
    tris, cols = [], []
    for i, x in enumerate(np.arange(x0, x1, tile)):
        for j, y in enumerate(np.arange(y0, y1, tile)):
            piece = shapely.box(x, y, x + tile, y + tile).intersection(room.polygon)
            if piece.is_empty or piece.area < 1e-9:
                continue
            tint = (1.0 + 0.05 * ((i + j) % 2)) * (1.0 + 0.025 * rng.standard_normal())
            fan = _piece_triangles(piece)
            tris.append(np.column_stack([fan, np.zeros(len(fan))]))
            cols.append(np.tile(np.asarray(FLOOR_COLOUR) * tint, (len(fan), 1)))
    pts = np.concatenate(tris)
    normals = np.tile([0.0, 0.0, 1.0], (len(pts), 1))
    parts.append((pts, _shade(np.concatenate(cols), pts, normals, lighting, lamp_world)))

    # walls: one per polygon edge, subdivided into cells, with a dark baseboard
    verts = np.asarray(room.vertices, float)
    edges = zip(verts, np.roll(verts, -1, axis=0))
    for k, (a, b) in enumerate(edges):
        length = np.linalg.norm(b - a)
        inward = np.array([-(b - a)[1], (b - a)[0], 0.0]) / length
        s = np.linspace(0.0, 1.0, max(2, int(np.ceil(length / cell)) + 1))
        z = np.unique(np.concatenate([[0.0, BASEBOARD[0]], np.linspace(BASEBOARD[0], room.height,
                                      max(2, int(np.ceil(room.height / cell)) + 1))]))
        S0, Z0 = np.meshgrid(s[:-1], z[:-1], indexing="ij")
        S1, Z1 = np.meshgrid(s[1:], z[1:], indexing="ij")
        quads = np.stack([np.stack(c, -1) for c in ((S0, Z0), (S1, Z0), (S1, Z1), (S0, Z1))],
                         axis=2).reshape(-1, 4, 2)  # (s, z) corners in order
        xy = a + quads[..., :1] * (b - a)
        quad_pts = np.concatenate([xy, quads[..., 1:]], axis=-1)
        pts = _quads_to_triangles(quad_pts)
        low = np.repeat(quads[:, :, 1].mean(axis=1) < BASEBOARD[0], 6)
        base = np.where(low[:, None], BASEBOARD[1], WALL_COLOURS[k % len(WALL_COLOURS)])
        normals = np.tile(inward, (len(pts), 1))
        parts.append((pts, _shade(base, pts, normals, lighting, lamp_world)))

    # ceiling: floor outline at the ceiling height, subdivided by the tile grid
    ceiling = []
    for x in np.arange(x0, x1, cell):
        for y in np.arange(y0, y1, cell):
            piece = shapely.box(x, y, x + cell, y + cell).intersection(room.polygon)
            if piece.is_empty or piece.area < 1e-9:
                continue
            ceiling.append(_piece_triangles(piece))
    fan = np.concatenate(ceiling)
    pts = np.column_stack([fan, np.full(len(fan), room.height)])
    normals = np.tile([0.0, 0.0, -1.0], (len(pts), 1))
    parts.append((pts, _shade(np.tile(CEILING_COLOUR, (len(pts), 1)), pts, normals, lighting, lamp_world)))

    positions = np.concatenate([p for p, _ in parts])
    colours = np.concatenate([c for _, c in parts])
    return Mesh(positions.astype(np.float32), colours.astype(np.float32),
                np.full(len(positions), -1.0, np.float32))


SKIN = (214, 164, 132)
HAIR = (60, 44, 34)


def cylinder(radius: float, height: float, colour, person: int, lighting: Lighting = Lighting(),
             segments: int = 32) -> Mesh:
    """An upright person-cylinder standing on the origin, ``colour`` (3,) uint8 clothing.

    Bands from the floor: legs (clothing, darker), torso (clothing), head (skin), and a
    hair-coloured top cap. Side normals are radial, so the shading varies smoothly
    around the body. Open at the bottom: :func:`sole` closes it.
    """
    colour = np.asarray(colour, float)
    head = min(0.25, 0.2 * height)
    bands = [(0.0, 0.47 * height, 0.7 * colour), (0.47 * height, height - head, colour),
             (height - head, height, np.asarray(SKIN, float))]
    a = np.linspace(0.0, 2 * np.pi, segments + 1)
    ring = np.column_stack([np.cos(a), np.sin(a)])
    pts, normals, cols = [], [], []
    for z0, z1, c in bands:
        quads = np.stack([np.column_stack([ring[:-1], np.full(segments, z0)]),
                          np.column_stack([ring[1:], np.full(segments, z0)]),
                          np.column_stack([ring[1:], np.full(segments, z1)]),
                          np.column_stack([ring[:-1], np.full(segments, z1)])], axis=1)
        tri = _quads_to_triangles(quads)
        normals.append(np.column_stack([tri[:, :2], np.zeros(len(tri))]))
        pts.append(tri * [radius, radius, 1.0])
        cols.append(np.tile(c, (len(tri), 1)))
    cap = np.stack([np.zeros((segments, 2)), ring[:-1], ring[1:]], axis=1).reshape(-1, 2) * radius
    pts.append(np.column_stack([cap, np.full(len(cap), height)]))
    normals.append(np.tile([0.0, 0.0, 1.0], (len(cap), 1)))
    cols.append(np.tile(HAIR, (len(cap), 1)))
    pts, normals, cols = np.concatenate(pts), np.concatenate(normals), np.concatenate(cols)
    return Mesh(pts.astype(np.float32), _shade(cols, pts, normals, lighting).astype(np.float32),
                np.full(len(pts), float(person), np.float32))


def sole(radius: float, height: float, colour, person: int, lighting: Lighting = Lighting(),
         segments: int = 32) -> Mesh:
    """The bottom cap of :func:`cylinder` (its legs' colour), facing the floor.

    It closes the person for a camera inside it, which would otherwise see the floor at
    its feet (docs/render.md); from outside, no camera above the floor ever sees it (it
    faces away and lies within the closed body). It floats a thousandth of the height
    above the floor, so that it does not tie with the floor in depth.

    >>> m = sole(0.25, 1.75, np.array([200, 30, 30]), person=0)
    >>> len(m.positions), round(float(m.positions[:, 2].max()), 6)
    (96, 0.00175)
    """
    a = np.linspace(0.0, 2 * np.pi, segments + 1)
    ring = np.column_stack([np.cos(a), np.sin(a)])
    disc = np.stack([np.zeros((segments, 2)), ring[1:], ring[:-1]], axis=1).reshape(-1, 2) * radius
    pts = np.column_stack([disc, np.full(len(disc), 1e-3 * height)])
    normals = np.tile([0.0, 0.0, -1.0], (len(pts), 1))
    cols = np.tile(0.7 * np.asarray(colour, float), (len(pts), 1))
    return Mesh(pts.astype(np.float32), _shade(cols, pts, normals, lighting).astype(np.float32),
                np.full(len(pts), float(person), np.float32))


def soles_mesh(people, lighting: Lighting = Lighting()) -> Mesh:
    """One :func:`sole` per person of ``people``, at the origin."""
    return Mesh.concatenate(sole(people.radius, people.height, people.colours[i], i, lighting)
                            for i in range(people.count)) if people.count else \
        Mesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.float32), np.zeros(0, np.float32))


def people_mesh(people, lighting: Lighting = Lighting()) -> Mesh:
    """One cylinder per person of ``people`` (a :class:`scene.People`), at the origin."""
    return Mesh.concatenate(cylinder(people.radius, people.height, people.colours[i], i, lighting)
                            for i in range(people.count)) if people.count else \
        Mesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.float32), np.zeros(0, np.float32))
