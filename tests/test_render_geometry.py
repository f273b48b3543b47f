"""The meshes without OpenGL: Lambert and lamp shading by hand, the room's floor, walls and
ceiling, the people's cylinders and soles (bands, colours, winding)."""

import numpy as np
import pytest
import shapely

from render.geometry import (
    BASEBOARD,
    CEILING_COLOUR,
    FLOOR_COLOUR,
    HAIR,
    SKIN,
    WALL_COLOURS,
    Lighting,
    Mesh,
    cylinder,
    lambert,
    lamp,
    people_mesh,
    room_mesh,
    sole,
    soles_mesh,
)
from scene import People, Room

#: |(-0.35, -0.25, 1)|: the default light travels along (0.35, 0.25, -1).
NORM = np.sqrt(0.35**2 + 0.25**2 + 1.0)


def _triangles(positions):
    """(k, 3, 3) triangles and their (k, 3) normals cross(b - a, c - a) (length: twice the area)."""
    tri = np.asarray(positions, float).reshape(-1, 3, 3)
    return tri, np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])


def _check_colours_at(mesh, point, expected):
    """Every vertex of ``mesh`` at ``point`` (3,) has the colour ``expected`` (3,)."""
    at = np.all(np.abs(mesh.positions - np.asarray(point)) < 1e-6, axis=1)
    assert at.sum() >= 2, point
    np.testing.assert_allclose(mesh.colours[at], np.broadcast_to(expected, (at.sum(), 3)), rtol=1e-5)


def test_lambert_and_lamp_by_hand():
    normals = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    np.testing.assert_allclose(lambert(normals, Lighting()),
                               [0.45 + 0.45 / NORM, 0.45, 0.45 + 0.45 * 0.35 / NORM, 0.45])
    np.testing.assert_allclose(lambert(normals, Lighting(direction=(0, 0, -2), ambient=0.1, diffuse=0.5)),
                               [0.6, 0.1, 0.1, 0.1])
    # a lamp 2 m above: straight up, 4 / (1 + 4); 2 m aside, cos 45 degrees and 4 / (1 + 8); behind: 0
    points = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    up = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    np.testing.assert_allclose(lamp(points, up, np.array([0.0, 0.0, 2.0]), 0.5),
                               [0.5 * 4 / 5, 0.5 * np.sqrt(0.5) * 4 / 9, 0.0])


#: An L: its inner corner (1.5, 1.5) lies inside a floor tile and a ceiling cell, which
#: it makes concave (fanned from a corner, their triangles crossed the notch).
L_ROOM = Room(np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1.5], [1.5, 1.5], [1.5, 3.0], [0.0, 3.0]]), 2.5)
#: A U whose 0.1 m slot (x 1.0 .. 1.1, y from 1 m up) cuts floor tiles and ceiling cells
#: in two (each piece a polygon of its own: a MultiPolygon has no exterior).
U_ROOM = Room(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [1.1, 3.0], [1.1, 1.0], [1.0, 1.0], [1.0, 3.0],
                        [0.0, 3.0]]), 2.5)


@pytest.mark.parametrize("room", [Room.rectangle(4.0, 3.0, 2.5), Room.circle(2.0, 2.4, n_vertices=60), L_ROOM,
                                  U_ROOM], ids=["rectangle", "circle", "L", "U"])
def test_room_mesh_is_the_floor_the_walls_and_the_ceiling(room):
    mesh = room_mesh(room)
    assert mesh.positions.dtype == mesh.colours.dtype == mesh.person.dtype == np.float32
    assert np.all(mesh.person == -1)
    assert mesh.colours.min() >= 0 and mesh.colours.max() <= 1
    tri, cross = _triangles(mesh.positions)
    area = np.linalg.norm(cross, axis=1) / 2
    z = tri[:, :, 2]
    floor, ceiling = np.all(z == 0, axis=1), np.all(np.abs(z - room.height) < 1e-6, axis=1)
    walls = ~floor & ~ceiling
    assert area[floor].sum() == pytest.approx(room.polygon.area, rel=1e-6)
    assert area[ceiling].sum() == pytest.approx(room.polygon.area, rel=1e-6)
    assert area[walls].sum() == pytest.approx(room.polygon.length * room.height, rel=1e-6)
    assert np.all(np.abs(cross[walls, 2]) < 1e-6)                        # vertical
    inside = shapely.contains_xy(room.polygon.buffer(1e-5), tri[floor | ceiling, :, 0].ravel(),
                                 tri[floor | ceiling, :, 1].ravel())
    on_edge = shapely.contains_xy(room.polygon.exterior.buffer(1e-5), tri[walls, :, 0].ravel(),
                                  tri[walls, :, 1].ravel())
    assert inside.all() and on_edge.all()
    centres = tri[floor | ceiling].mean(axis=1)                         # no triangle spills out of the room
    assert shapely.contains_xy(room.polygon.buffer(1e-9), centres[:, 0], centres[:, 1]).all()
    # the floor is tinted by tile, grey: each floor vertex's colour is FLOOR_COLOUR's hue
    c = mesh.colours.reshape(-1, 3, 3)[floor].reshape(-1, 3).astype(float)
    np.testing.assert_allclose(c / c[:, :1], np.tile(np.array(FLOOR_COLOUR) / FLOOR_COLOUR[0], (len(c), 1)),
                               rtol=1e-5)


def test_room_shading_by_hand():
    """The 4 x 3 x 2.5 m room; lamp at (2, 1.5, 2.2). Wall 0 runs from (0, 0) to (4, 0),
    facing +y (the light, travelling along +y, does not reach it: ambient 0.45 only)."""
    mesh = room_mesh(Room.rectangle(4.0, 3.0, 2.5))
    lamp_at = np.array([2.0, 1.5, 2.2])

    def lit(point, normal):
        d = lamp_at - point
        return 0.35 * max(0.0, d @ normal / np.linalg.norm(d)) * 4 / (1 + d @ d)

    # wall 0 at 1.7 m: sqrt(2.5) m from the lamp, cos = 1.5 / sqrt(2.5)
    p = np.array([2.0, 0.0, 1.7])
    assert lit(p, np.array([0.0, 1.0, 0.0])) == pytest.approx(0.35 * 1.5 / np.sqrt(2.5) * 4 / 3.5)
    _check_colours_at(mesh, p, np.array(WALL_COLOURS[0]) / 255 * (0.45 + lit(p, np.array([0.0, 1.0, 0.0]))))
    # the baseboard under it (the bottom 0.1 m), wall 1 (x = 4, facing -x: lit by the light)
    p = np.array([2.0, 0.0, 0.0])
    _check_colours_at(mesh, p, np.array(BASEBOARD[1]) / 255 * (0.45 + lit(p, np.array([0.0, 1.0, 0.0]))))
    p = np.array([4.0, 1.0, 0.9])
    f = 0.45 + 0.45 * 0.35 / NORM + lit(p, np.array([-1.0, 0.0, 0.0]))
    _check_colours_at(mesh, p, np.array(WALL_COLOURS[1]) / 255 * f)
    # wall 3 runs from (0, 3) to (0, 0), facing +x (away from the light)
    p = np.array([0.0, 1.0, 0.9])
    _check_colours_at(mesh, p, np.array(WALL_COLOURS[3]) / 255 * (0.45 + lit(p, np.array([1.0, 0.0, 0.0]))))
    # the ceiling (facing down, away from the light) 1 m from two walls
    p = np.array([1.0, 1.0, 2.5])
    _check_colours_at(mesh, p, np.array(CEILING_COLOUR) / 255 * (0.45 + lit(p, np.array([0.0, 0.0, -1.0]))))


def test_cylinder_bands_colours_and_shading_by_hand():
    """Legs 0.47 h (0.7 x clothing), torso, head min(0.25, 0.2 h) of skin, hair on top; side
    normals radial: at angle pi (facing -x, towards the light) 0.45 + 0.45 * 0.35 / |L|,
    at angle 0 the ambient 0.45 alone."""
    colour = np.array([200, 30, 30])
    for height, head in ((1.75, 0.25), (1.0, 0.2)):
        m = cylinder(0.25, height, colour, person=3)
        assert len(m.positions) == 3 * 32 * 6 + 32 * 3
        assert np.all(m.person == 3)
        np.testing.assert_allclose(np.unique(m.positions[:, 2]), [0, 0.47 * height, height - head, height],
                                   atol=1e-6)
    m = cylinder(0.25, 1.75, colour, person=0)
    tri, cross = _triangles(m.positions)
    side = np.ptp(tri[:, :, 2], axis=1) > 0
    np.testing.assert_allclose(np.hypot(tri[side, :, 0], tri[side, :, 1]), 0.25, rtol=1e-6)
    assert np.all(np.hypot(tri[~side, :, 0], tri[~side, :, 1]) <= 0.25 + 1e-6)
    np.testing.assert_allclose(tri[~side, :, 2], 1.75)                    # the cap, no bottom
    side_area = np.linalg.norm(cross[side], axis=1).sum() / 2             # the bands do not overlap
    assert side_area == pytest.approx(32 * 2 * 0.25 * np.sin(np.pi / 32) * 1.75)
    # counter-clockwise seen from outside: the side's normals point away from the axis, the cap's up
    centre = tri[side].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", cross[side][:, :2], centre[:, :2]) > 0)
    assert np.all(cross[~side, 2] > 0)
    c = m.colours.reshape(-1, 3, 3)
    zmid = tri[:, :, 2].mean(axis=1)
    back = 0.45 + 0.45 * 0.35 / NORM
    for lo, hi, base in ((0, 0.8225, 0.7 * colour), (0.8225, 1.5, colour), (1.5, 1.75, np.array(SKIN))):
        band = side & (zmid > lo) & (zmid < hi)
        assert band.sum() == 32 * 2
        at_pi = np.abs(tri[:, :, 0] + 0.25) < 1e-6                       # vertices at angle pi
        at_0 = np.abs(tri[:, :, 0] - 0.25) < 1e-6
        assert at_pi[band].sum() == at_0[band].sum() == 6                 # in two quads each
        np.testing.assert_allclose(c[band][at_pi[band]], np.tile(base / 255 * back, (6, 1)), rtol=1e-5)
        np.testing.assert_allclose(c[band][at_0[band]], np.tile(base / 255 * 0.45, (6, 1)), rtol=1e-5)
    np.testing.assert_allclose(c[~side].reshape(-1, 3), np.tile(np.array(HAIR) / 255 * (0.45 + 0.45 / NORM),
                                                                 (32 * 3, 1)), rtol=1e-5)


def test_sole_faces_the_floor_in_the_legs_colour():
    m = sole(0.25, 2.0, np.array([200, 100, 50]), person=2)
    tri, cross = _triangles(m.positions)
    assert len(tri) == 32 and np.all(cross[:, 2] < 0)                    # seen from below: counter-clockwise
    np.testing.assert_allclose(m.positions[:, 2], 2e-3)
    assert np.all(np.hypot(m.positions[:, 0], m.positions[:, 1]) <= 0.25 + 1e-6)
    assert np.sum(np.linalg.norm(cross, axis=1)) / 2 == pytest.approx(32 / 2 * 0.25**2 * np.sin(2 * np.pi / 32))
    np.testing.assert_allclose(m.colours, np.tile(0.7 * np.array([200, 100, 50]) / 255 * 0.45, (96, 1)), rtol=1e-5)
    assert np.all(m.person == 2)


def test_people_meshes_are_one_cylinder_and_one_sole_per_person():
    colours = np.array([[200, 30, 30], [30, 200, 30]], np.uint8)
    people = People(2, 0.3, 1.6, 1.0, colours)
    bodies, soles = people_mesh(people), soles_mesh(people)
    for mesh, one in ((bodies, cylinder), (soles, sole)):
        parts = [one(0.3, 1.6, colours[i], i) for i in range(2)]
        ref = Mesh.concatenate(parts)
        for f in ("positions", "colours", "person"):
            assert getattr(mesh, f).dtype == np.float32
            assert np.array_equal(getattr(mesh, f), getattr(ref, f))
        assert np.array_equal(np.unique(mesh.person), [0, 1])
        assert len(mesh.positions) == 2 * len(parts[0].positions)
    nobody = People(0, 0.3, 1.6, 1.0, np.zeros((0, 3), np.uint8))
    for mesh in (people_mesh(nobody), soles_mesh(nobody)):
        assert mesh.positions.shape == (0, 3) and mesh.colours.shape == (0, 3) and mesh.person.shape == (0,)


def test_walls_are_covered_without_gaps_or_overlaps():
    """Each wall of the 4 x 3 x 2.5 m room, unrolled to (distance along it, height): its
    triangles tile the rectangle (their union's area is the sum of their areas)."""
    room = Room.rectangle(4.0, 3.0, 2.5)
    tri = room_mesh(room).positions.astype(float).reshape(-1, 3, 3)
    z = tri[:, :, 2]
    walls = tri[~np.all(z == 0, axis=1) & ~np.all(z == 2.5, axis=1)]
    for a, b in zip(room.vertices, np.roll(room.vertices, -1, axis=0)):
        along = (b - a) / np.linalg.norm(b - a)
        off = (walls[:, :, 0] - a[0]) * along[1] - (walls[:, :, 1] - a[1]) * along[0]     # metres
        on = np.all(np.abs(off) < 1e-6, axis=1)
        flat = [shapely.Polygon(np.column_stack([(t[:, :2] - a) @ along, t[:, 2]])) for t in walls[on]]
        union = shapely.union_all(flat)
        length = np.linalg.norm(b - a)
        assert union.area == pytest.approx(length * 2.5, rel=1e-6)
        assert sum(f.area for f in flat) == pytest.approx(length * 2.5, rel=1e-6)
        assert union.symmetric_difference(shapely.box(0, 0, length, 2.5)).area < 1e-9


def test_cell_and_tile_set_the_subdivisions():
    """Walls and ceiling are cut every ``cell`` metres (the baseboard line at 0.1 m too), the
    floor into ``tile`` squares."""
    room = Room.rectangle(4.0, 3.0, 2.5)
    tri = room_mesh(room, tile=0.75, cell=0.5).positions.astype(float).reshape(-1, 3, 3)
    z = tri[:, :, 2]
    floor, ceiling = np.all(z == 0, axis=1), np.all(z == 2.5, axis=1)
    wall0 = tri[~floor & ~ceiling & np.all(np.abs(tri[:, :, 1]) < 1e-6, axis=1)].reshape(-1, 3)
    np.testing.assert_allclose(np.unique(wall0[:, 0]), np.arange(0, 4.01, 0.5), atol=1e-6)
    np.testing.assert_allclose(np.unique(wall0[:, 2]), [0, 0.1, 0.58, 1.06, 1.54, 2.02, 2.5], atol=1e-6)
    np.testing.assert_allclose(np.unique(tri[ceiling][:, :, 0]), np.arange(0, 4.01, 0.5), atol=1e-6)
    np.testing.assert_allclose(np.unique(tri[ceiling][:, :, 1]), np.arange(0, 3.01, 0.5), atol=1e-6)
    np.testing.assert_allclose(np.unique(tri[floor][:, :, 0]), [0, 0.75, 1.5, 2.25, 3, 3.75, 4], atol=1e-6)
    np.testing.assert_allclose(np.unique(tri[floor][:, :, 1]), [0, 0.75, 1.5, 2.25, 3], atol=1e-6)


def test_floor_tiles_are_a_subtle_checker_with_per_tile_variation():
    """Dividing the lit floor colour by FLOOR_COLOUR and the light gives each tile's tint:
    one per tile, grey, (1 + 0.05 on odd tiles) x (1 + N(0, 0.025))."""
    room = Room.rectangle(6.0, 6.0, 2.5)
    mesh = room_mesh(room)
    tri = mesh.positions.astype(float).reshape(-1, 3, 3)
    floor = np.all(tri[:, :, 2] == 0, axis=1)
    pts = tri[floor].reshape(-1, 3)
    up = np.tile([0.0, 0.0, 1.0], (len(pts), 1))
    f = lambert(up, Lighting()) + lamp(pts, up, np.array([3.0, 3.0, 2.2]), 0.35)
    tint = mesh.colours.reshape(-1, 3, 3)[floor].reshape(-1, 3) / (np.array(FLOOR_COLOUR) / 255 * f[:, None])
    np.testing.assert_allclose(tint, np.repeat(tint[:, :1], 3, axis=1), rtol=1e-5)        # grey
    centre = tri[floor].mean(axis=1)
    i, j = (centre[:, 0] // 0.3048).astype(int), (centre[:, 1] // 0.3048).astype(int)
    tiles = {}
    for a, b, t in zip(np.repeat(i, 3), np.repeat(j, 3), tint[:, 0]):
        tiles.setdefault((a, b), []).append(t)
    assert len(tiles) == 20 * 20                                        # 6 m / 0.3048 m: 20 tiles a side
    assert all(np.ptp(v) < 1e-5 for v in tiles.values())                # one tint per tile
    odd = np.array([v[0] for (a, b), v in tiles.items() if (a + b) % 2])
    even = np.array([v[0] for (a, b), v in tiles.items() if not (a + b) % 2])
    assert odd.mean() / even.mean() == pytest.approx(1.05, abs=0.01)
    assert even.mean() == pytest.approx(1.0, abs=0.01)
    assert 0.015 < even.std() < 0.035 and 0.015 < (odd / 1.05).std() < 0.035
    # the variation reaches every tile: no row or column of tiles is left at the plain checker
    spread = {}
    for (a, b), v in tiles.items():
        plain = 1.05 if (a + b) % 2 else 1.0
        spread.setdefault(("column", a), []).append(v[0] / plain)
        spread.setdefault(("row", b), []).append(v[0] / plain)
    assert min(np.std(v) for v in spread.values()) > 0.01


def test_a_sole_lit_from_below_takes_the_light_on_its_downward_normal():
    """A light travelling along (0.6, 0.48, 0.64) (a unit vector, upwards) reaches the
    downward normal at cos = 0.64."""
    m = sole(0.25, 2.0, np.array([200, 100, 50]), person=0, lighting=Lighting(direction=(0.6, 0.48, 0.64)))
    np.testing.assert_allclose(m.colours, np.tile(0.7 * np.array([200, 100, 50]) / 255 * (0.45 + 0.45 * 0.64),
                                                  (96, 1)), rtol=1e-5)


def test_people_meshes_take_the_lighting_given():
    """A light straight down (ambient 0.2, diffuse 0.3): the hair cap faces it (0.5), the
    side at angle 0 is perpendicular to it and the sole faces away (ambient 0.2 alone)."""
    colours = np.array([[200, 100, 50]], np.uint8)
    people = People(1, 0.25, 1.75, 1.0, colours)
    light = Lighting(direction=(0.0, 0.0, -1.0), ambient=0.2, diffuse=0.3)
    bodies, soles = people_mesh(people, light), soles_mesh(people, light)
    legs = 0.7 * colours[0] / 255
    _check_colours_at(bodies, [0.0, 0.0, 1.75], np.array(HAIR) / 255 * 0.5)       # the cap's centre
    _check_colours_at(bodies, [0.25, 0.0, 0.0], legs * 0.2)                       # the side, angle 0
    np.testing.assert_allclose(soles.colours, np.tile(legs * 0.2, (96, 1)), rtol=1e-5)


def test_concatenated_meshes_are_float32():
    one = Mesh(np.zeros((3, 3)), np.ones((3, 3)), np.full(3, -1.0))               # float64 parts
    two = Mesh(np.ones((3, 3), np.float32), np.zeros((3, 3), np.float32), np.zeros(3, np.float32))
    three = Mesh(np.full((3, 3), 2.0), np.ones((3, 3)), np.ones(3))             # the renderer joins three
    m = Mesh.concatenate(iter([one, two, three]))
    assert m.positions.dtype == m.colours.dtype == m.person.dtype == np.float32
    assert np.array_equal(m.person, [-1, -1, -1, 0, 0, 0, 1, 1, 1])
    assert np.array_equal(m.positions, np.concatenate([np.zeros((3, 3)), np.ones((3, 3)), np.full((3, 3), 2.0)]))
    assert np.array_equal(m.colours, np.concatenate([np.ones((3, 3)), np.zeros((3, 3)), np.ones((3, 3))]))


def test_room_mesh_takes_the_lighting_given():
    """Ambient 0.3 alone: every wall and ceiling vertex is its colour x 0.3. The lamp alone
    (strength 0.5, 0.5 m under the 2.5 m ceiling of the 4 x 3 m room: at (2, 1.5, 2)):
    wall 0 at (2, 0, 1.7) is d = (0, 1.5, 0.3) from it, cos = 1.5 / |d|, 4 / (1 + |d|^2)."""
    room = Room.rectangle(4.0, 3.0, 2.5)
    flat = room_mesh(room, Lighting(ambient=0.3, diffuse=0.0, lamp=0.0))
    _check_colours_at(flat, [2.0, 0.0, 1.7], np.array(WALL_COLOURS[0]) / 255 * 0.3)
    _check_colours_at(flat, [4.0, 1.0, 0.9], np.array(WALL_COLOURS[1]) / 255 * 0.3)
    _check_colours_at(flat, [2.0, 0.0, 0.0], np.array(BASEBOARD[1]) / 255 * 0.3)
    _check_colours_at(flat, [1.0, 1.0, 2.5], np.array(CEILING_COLOUR) / 255 * 0.3)
    lamp_only = room_mesh(room, Lighting(ambient=0.0, diffuse=0.0, lamp=0.5, lamp_drop=0.5))
    d2 = 1.5**2 + 0.3**2
    _check_colours_at(lamp_only, [2.0, 0.0, 1.7],
                      np.array(WALL_COLOURS[0]) / 255 * 0.5 * 1.5 / np.sqrt(d2) * 4 / (1 + d2))


@pytest.mark.parametrize("cell", [0.7, 5.0])
def test_wall_cells_are_no_larger_than_cell_and_as_few_as_that_allows(cell):
    """Wall 0 of the 4 x 3 x 2.5 m room is cut into ceil(4 / cell) equal columns and its
    2.4 m above the 0.1 m baseboard into ceil(2.4 / cell) equal rows: 0.7 m gives 6 columns
    of 0.67 m and 4 rows of 0.6 m, 5 m one column and one row."""
    tri = room_mesh(Room.rectangle(4.0, 3.0, 2.5), cell=cell).positions.astype(float).reshape(-1, 3, 3)
    z = tri[:, :, 2]
    walls = ~np.all(z == 0, axis=1) & ~np.all(np.abs(z - 2.5) < 1e-6, axis=1)
    wall0 = tri[walls & np.all(np.abs(tri[:, :, 1]) < 1e-6, axis=1)].reshape(-1, 3)
    columns = np.diff(np.unique(np.round(wall0[:, 0], 5)))
    rows = np.diff(np.unique(np.round(wall0[:, 2], 5)))[1:]                 # above the baseboard
    assert len(columns) == int(np.ceil(4.0 / cell)) and len(rows) == int(np.ceil(2.4 / cell))
    np.testing.assert_allclose(columns, 4.0 / len(columns), atol=1e-5)
    np.testing.assert_allclose(rows, 2.4 / len(rows), atol=1e-5)
    assert columns.max() <= cell and rows.max() <= cell


def test_floor_tiles_are_a_foot():
    """docs/render.md: the floor tiles are 1 ft (0.3048 m), from the room's corner."""
    tri = room_mesh(Room.rectangle(4.0, 3.0, 2.5)).positions.astype(float).reshape(-1, 3, 3)
    floor = tri[np.all(tri[:, :, 2] == 0, axis=1)]
    np.testing.assert_allclose(np.unique(np.round(floor[:, :, 0], 5)), [*np.arange(14) * 0.3048, 4.0], atol=1e-5)
    np.testing.assert_allclose(np.unique(np.round(floor[:, :, 1], 5)), [*np.arange(10) * 0.3048, 3.0], atol=1e-5)


def test_room_mesh_is_the_same_whatever_the_global_random_state():
    """The floor's per-tile variation is part of the room, not of a run."""
    room = Room.rectangle(4.0, 3.0, 2.5)
    np.random.seed(1)
    one = room_mesh(room)
    np.random.seed(2)
    two = room_mesh(room)
    for f in ("positions", "colours", "person"):
        assert np.array_equal(getattr(one, f), getattr(two, f))


def test_the_lamp_hangs_over_the_floors_centroid():
    """A right-triangle room with legs of 6 m: its centroid is (2, 2) (not the centre of its
    bounds, (3, 3)). The lamp alone (strength 0.1, 1 m under the 2.5 m ceiling): the
    ceiling at (2, 2) is straight above it, 4 / (1 + 1); at (1, 1), d = (1, 1, -1), cos
    1 / sqrt(3), 4 / (1 + 3)."""
    room = Room(np.array([[0.0, 0.0], [6.0, 0.0], [0.0, 6.0]]), 2.5)
    mesh = room_mesh(room, Lighting(ambient=0.0, diffuse=0.0, lamp=0.1, lamp_drop=1.0))
    ceiling = np.array(CEILING_COLOUR) / 255
    _check_colours_at(mesh, [2.0, 2.0, 2.5], ceiling * 0.1 * 4 / 2)
    _check_colours_at(mesh, [1.0, 1.0, 2.5], ceiling * 0.1 / np.sqrt(3))
