"""Rendered frames: labels agree with cv2.projectPoints silhouettes, seeded noise, backgrounds;
the rasteriser itself on hand-made triangles (labels, depth ties, near cameras, bands, boxes)."""

import re

import cv2
import numpy as np
import pytest

from testbed.dataset import read_calibration, write_calibration

pytestmark = pytest.mark.render


def _cylinder_points(xy, radius, height, n_around=180, n_up=60):
    a = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    z = np.linspace(0, height, n_up)
    A, Z = np.meshgrid(a, z)
    side = np.column_stack([xy[0] + radius * np.cos(A.ravel()), xy[1] + radius * np.sin(A.ravel()), Z.ravel()])
    r = np.linspace(0, radius, 20)
    Rr, Aa = np.meshgrid(r, a)
    top = np.column_stack([xy[0] + Rr.ravel() * np.cos(Aa.ravel()), xy[1] + Rr.ravel() * np.sin(Aa.ravel()),
                           np.full(Rr.size, height)])
    return np.concatenate([side, top])


@pytest.mark.parametrize("number,xy", [(1, (2.5, 2.5)), (6, (3.5, 2.0)), (11, (3.0, 2.5)), (15, (2.0, 3.5))])
def test_label_mask_matches_projected_silhouette(lab, lab_renderer, tmp_path, number, xy):
    cam = lab.cameras[number - 1]
    write_calibration(tmp_path / "cam.yaml", cam)
    calib = read_calibration(tmp_path / "cam.yaml")
    positions = np.full((lab.people.count, 2), np.nan)
    positions[1] = xy                                     # person 1 alone in the room
    frames = lab_renderer.render(positions, cameras=[number], clean=True)
    mask = frames.labels[0] == 2
    assert set(np.unique(frames.labels[0])) <= {0, 2}
    pts = _cylinder_points(np.array(xy), lab.people.radius, lab.people.height)
    uv, _ = cv2.projectPoints(pts, calib["rvec"], calib["tvec"], calib["K"], calib["dist"])
    expected = np.zeros_like(mask, np.uint8)
    cv2.fillConvexPoly(expected, np.round(cv2.convexHull(uv.astype(np.float32))[:, 0]).astype(np.int32), 1)
    expected = expected.astype(bool)
    iou = (mask & expected).sum() / (mask | expected).sum()
    assert mask.sum() > 2000
    assert iou > 0.95, iou


def test_masks_are_where_any_person_is():
    from render.renderer import Frames

    labels = np.array([[[0, 1, 0], [3, 0, 254]]], np.uint8)
    f = Frames(np.zeros((1, 2, 3, 3), np.uint8), labels, (4,))
    assert f.masks.tolist() == [[[False, True, False], [True, False, True]]]


def test_same_seed_same_frames_different_seed_different_noise(lab, lab_renderer, three_people):
    a = lab_renderer.render(three_people, cameras=[3, 9], rng=np.random.default_rng(5))
    b = lab_renderer.render(three_people, cameras=[3, 9], rng=np.random.default_rng(5))
    c = lab_renderer.render(three_people, cameras=[3, 9], rng=np.random.default_rng(6))
    clean = lab_renderer.render(three_people, cameras=[3, 9], clean=True)
    assert np.array_equal(a.rgb, b.rgb) and np.array_equal(a.labels, b.labels)
    assert not np.array_equal(a.rgb, c.rgb)
    assert np.array_equal(a.labels, c.labels)             # labels are exact, never noisy
    noise = a.rgb.astype(float) - clean.rgb
    assert 1.0 < noise.std() < 6.0                          # noise_std 2 plus a 2 % gain


def test_frames_are_shaded_not_flat(lab, lab_renderer, three_people):
    f = lab_renderer.render(three_people, cameras=[1], clean=True)
    person = f.rgb[0][f.labels[0] == 1]
    assert len(np.unique(person, axis=0)) > 20              # shading varies across the body
    assert f.rgb.shape == (1, 480, 640, 3) and f.rgb.dtype == np.uint8


def test_every_default_colour_stands_out_from_the_room_by_colour_angle(lab_renderer):
    """The pipeline is blind to brightness: a grey person (the palette's tenth, once) was
    invisible against the grey room, and the hull lost them."""
    from scene.config import default_colours

    bg = lab_renderer.background().rgb.reshape(-1, 3).astype(float)
    bg = bg[np.linalg.norm(bg, axis=1) > 25]                 # above the brightness floor
    bg /= np.linalg.norm(bg, axis=1, keepdims=True)
    colours = default_colours(10).astype(float)
    colours /= np.linalg.norm(colours, axis=1, keepdims=True)
    angles = np.degrees(np.arccos(np.clip(bg @ colours.T, -1, 1)))     # (pixels, 10)
    assert angles.min(axis=0).min() > 20


def test_background_has_no_people(lab, lab_renderer):
    bg = lab_renderer.background()
    assert bg.rgb.shape == (16, 480, 640, 3)
    assert not bg.labels.any()
    hidden = np.full((lab.people.count, 2), np.nan)
    assert np.array_equal(bg.rgb, lab_renderer.render(hidden, clean=True).rgb)


def test_render_checks_its_input(lab, lab_renderer, three_people):
    with pytest.raises(ValueError, match="positions_xy"):
        lab_renderer.render(three_people[:2], clean=True)
    with pytest.raises(ValueError, match="rng"):
        lab_renderer.render(three_people)
    with pytest.raises(ValueError, match="cameras"):
        lab_renderer.render(three_people, cameras=[17], clean=True)


@pytest.mark.parametrize("people", [[[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]],
                                    [[3.0, 3.0], [3.45, 3.05], [3.2, 3.5]]])   # apart, and occluding each other
def test_culling_back_faces_keeps_every_label(lab, lab_renderer, people):
    """The people's back faces are culled: same labels as drawing both faces, colour only on outlines."""
    pos = np.array(people)
    culled = lab_renderer.render(pos, clean=True)
    lab_renderer.raster.cull_back_faces = False
    try:
        both = lab_renderer.render(pos, clean=True)
    finally:
        lab_renderer.raster.cull_back_faces = True
    assert np.array_equal(culled.labels, both.labels)
    changed = (culled.rgb != both.rgb).any(-1)
    assert changed.sum() <= 1e-4 * changed.size, changed.sum()
    outline = np.zeros_like(changed)
    for k in range(len(culled.labels)):             # a changed pixel lies on a person's outline
        lab_k = culled.labels[k]
        edge = cv2.morphologyEx(lab_k, cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0
        outline[k] = cv2.dilate(edge.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    assert not (changed & ~outline).any()


# -- the rasteriser on hand-made triangles ---------------------------------------------
# With an identity view-projection matrix the vertex positions are normalised device
# coordinates: a canvas of S x S pixels spans [-1, 1]^2, pixel column c covers
# x in [2c/S - 1, 2(c+1)/S - 1], and the rows come out bottom first (no row flip here);
# window depth is (z + 1) / 2, and z outside [-1, 1] is clipped (unless depth-clamped).

S = 64
EYE = np.eye(4, dtype=np.float32)[None]


def _quad(cx, cy, half, z, colour, person):
    """Two triangles covering [cx - half, cx + half] x [cy - half, cy + half] at depth z."""
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, -1], [1, 1], [-1, 1]], float) * half + [cx, cy]
    return (np.column_stack([corners, np.full(6, z)]), np.tile(colour, (6, 1)), np.full(6, float(person)))


def _raster(quads, n_people, n_tiles=1, near_only=0):
    from render.geometry import Mesh
    from render.raster import Rasteriser

    mesh = Mesh(*(np.concatenate([q[i] for q in quads]).astype(np.float32) for i in range(3)))
    r = Rasteriser(mesh, n_people, S, S, n_tiles, near_only=near_only)
    r.cull_back_faces = False           # the quads' winding does not matter here
    return r


def _px(ndc):
    """The pixel columns (or rows) whose centres lie in NDC interval ``ndc``."""
    lo, hi = ((np.asarray(ndc) + 1) * S / 2)
    return slice(int(np.ceil(lo - 0.5)), int(np.ceil(hi - 0.5)))


ROOM = (0.2, 0.4, 0.6)                  # -> RGB (51, 102, 153)


def test_raster_labels_every_person_up_to_max_people():
    """254 people (the uint8 label limit) in a 16 x 16 grid of 4 px cells: each cell has
    its person's label, index + 1, and its colour; a 255th person is refused."""
    from render.raster import MAX_PEOPLE, Rasteriser

    assert MAX_PEOPLE == 254
    quads = [_quad(0.0, 0.0, 0.05, 0.0, (k / 255, 0.2, 0.6), k) for k in range(MAX_PEOPLE)]
    cells = np.arange(MAX_PEOPLE)
    offsets = np.column_stack([(4 * (cells % 16) + 2) / 32 - 1, (4 * (cells // 16) + 2) / 32 - 1])
    r = _raster(quads, MAX_PEOPLE)
    try:
        px = r.draw(EYE, offsets).copy()[0]
    finally:
        r.close()
    for k in range(256):
        cell = px[4 * (k // 16):4 * (k // 16) + 4, 4 * (k % 16):4 * (k % 16) + 4].reshape(-1, 4)
        expected = [k, 51, 153, k + 1] if k < MAX_PEOPLE else [0, 0, 0, 0]    # the last two cells: empty
        assert (cell == expected).all(), (k, cell[0])
    with pytest.raises(ValueError, match="at most 254 people"):
        Rasteriser(None, MAX_PEOPLE + 1, S, S, 1)


def test_raster_of_a_room_without_people():
    r = _raster([_quad(0.0, 0.0, 1.0, 0.5, ROOM, -1)], 0)
    try:
        px = r.draw(EYE, np.zeros((0, 2)))[0]
        assert (px.reshape(-1, 4) == [51, 102, 153, 0]).all()
    finally:
        r.close()


def test_raster_room_wins_a_depth_tie_with_a_person():
    """Room first, GL_LESS: where a person lies at exactly the room's depth (the floor line
    of a foot) the room stays, as docs/render.md says."""
    room = _quad(-0.5, 0.0, 0.5, 0.0, ROOM, -1)               # x in [-1, 0]
    person = _quad(0.0, 0.0, 0.5, 0.0, (1.0, 0.0, 0.0), 0)     # x in [-0.5, 0.5], same depth
    r = _raster([room, person], 1)
    try:
        px = r.draw(EYE, np.zeros((1, 2)))[0]
        rows = _px([-0.5, 0.5])
        assert (px[rows, _px([-1.0, 0.0])].reshape(-1, 4) == [51, 102, 153, 0]).all()
        assert (px[rows, _px([0.0, 0.5])].reshape(-1, 4) == [255, 0, 0, 1]).all()
    finally:
        r.close()


@pytest.mark.parametrize("per_page", [None, 1])         # one framebuffer, or one per camera
def test_raster_near_cameras_draw_people_unclipped_and_their_soles(monkeypatch, per_page):
    """For a camera flagged ``near`` the people are depth-clamped (a person nearer than the
    near plane is drawn, in front of the room) and their last ``near_only`` vertices (the
    soles) are drawn; the room is clipped as for any camera; other cameras clip the
    people and skip the soles. Flags alternate so that each change is applied; on pages
    each camera keeps its own flag."""
    from render.raster import Rasteriser

    if per_page:
        monkeypatch.setattr(Rasteriser, "max_page_height", per_page * S)
    back = _quad(0.0, 0.0, 1.0, 0.5, ROOM, -1)
    room_near = _quad(-0.5, 0.5, 0.5, -1.5, (0.0, 1.0, 0.0), -1)     # top left, nearer than near
    body = _quad(0.5, 0.5, 0.5, -1.5, (1.0, 0.0, 0.0), 0)             # top right, idem
    sole = _quad(0.0, -0.5, 0.5, 0.0, (0.0, 0.0, 1.0), 0)             # bottom, in range
    r = _raster([back, room_near, body, sole], 1, n_tiles=3, near_only=6)
    try:
        assert len(r.pages) == (3 if per_page else 1)
        px = r.draw(np.repeat(EYE, 3, axis=0), np.zeros((1, 2)), bands=[0, 1, 2], near=[True, False, True]).copy()
    finally:
        r.close()
    top, bottom = _px([0.0, 1.0]), _px([-1.0, 0.0])
    left, right, middle = _px([-1.0, 0.0]), _px([0.0, 1.0]), _px([-0.5, 0.5])
    room = [51, 102, 153, 0]
    for k, near in enumerate([True, False, True]):
        assert (px[k, top, left].reshape(-1, 4) == room).all()
        assert (px[k, top, right].reshape(-1, 4) == ([255, 0, 0, 1] if near else room)).all()
        assert (px[k, bottom, middle].reshape(-1, 4) == ([0, 0, 255, 1] if near else room)).all()


def test_raster_draw_clears_the_bands_it_draws():
    """A person drawn in bands 0-3, then bands 1-2 drawn with the person hidden: no trace left."""
    r = _raster([_quad(0.0, 0.0, 1.0, 0.5, ROOM, -1), _quad(0.0, 0.0, 0.5, 0.0, (1.0, 0.0, 0.0), 0)], 1,
                n_tiles=4)
    try:
        four = np.repeat(EYE, 4, axis=0)
        assert (r.draw(four, np.zeros((1, 2)))[:, S // 2, S // 2] == [255, 0, 0, 1]).all()
        for hidden in ([[np.nan, np.nan]], [[0.0, np.inf]]):
            for bands in ([1, 2], [2, 0]):
                px = r.draw(four[:2], np.array(hidden), bands=bands)
                assert (px.reshape(-1, 4) == [51, 102, 153, 0]).all(), (hidden, bands)
    finally:
        r.close()


def test_raster_draw_returns_a_view_of_its_pixels_for_consecutive_bands():
    """docs: band b is read into ``pixels[b]``; the result is a view of it when the bands
    are consecutive (no copy per call), a copy in the bands' order otherwise."""
    r = _raster([_quad(0.0, 0.0, 1.0, 0.5, ROOM, -1), _quad(0.0, 0.0, 0.5, 0.0, (1.0, 0.0, 0.0), 0)], 1,
                n_tiles=3)
    try:
        three = np.repeat(EYE, 3, axis=0)
        r.draw(three, np.zeros((1, 2)))                                   # the person in every band
        px = r.draw(three[:2], np.full((1, 2), np.nan), bands=[1, 2])     # bands 1, 2: the room
        assert px.base is r.pixels or px.base is r.pixels.base
        assert np.shares_memory(px, r.pixels) and px.shape == (2, S, S, 4)
        assert (px.reshape(-1, 4) == [51, 102, 153, 0]).all()
        assert (r.pixels[0, S // 2, S // 2] == [255, 0, 0, 1]).all()     # band 0 not read again
        px = r.draw(three[:2], np.zeros((1, 2)), bands=[2, 0])
        assert not np.shares_memory(px, r.pixels)
        assert (px[:, S // 2, S // 2] == [255, 0, 0, 1]).all()
        assert (r.pixels[1, S // 2, S // 2] == [51, 102, 153, 0]).all()    # band 1 left as it was
    finally:
        r.close()


def test_raster_hidden_people_stay_out_of_a_frustum_kilometres_wide():
    """A person whose offset row is not finite (NaN, either coordinate, or infinite) is
    hidden: not drawn even by a camera seeing 20 km across (1e-4 NDC per metre), near
    flag or not. The person is a 4 km square at the origin: shown, it covers NDC
    [-0.2, 0.2] both ways (a person moved 10 m would be drawn too). No non-finite offset
    reaches OpenGL, where a NaN or infinite vertex is undefined: the person is moved to
    ``HIDDEN``."""
    from render.raster import HIDDEN

    person = _quad(0.0, 0.0, 2000.0, 0.0, (1.0, 0.0, 0.0), 0)
    r = _raster([_quad(0.0, 0.0, 2e4, 0.5, ROOM, -1), person], 1, n_tiles=2)       # the room: everywhere
    wide = np.repeat(np.diag([1e-4, 1e-4, 1.0, 1.0]).astype(np.float32)[None], 2, axis=0)
    try:
        px = r.draw(wide, np.zeros((1, 2)), near=[False, True]).copy()
        expected = np.zeros((S, S), bool)
        expected[_px([-0.2, 0.2]), _px([-0.2, 0.2])] = True
        for k in range(2):
            assert np.array_equal(px[k, ..., 3] == 1, expected)
        GL = r.GL
        uniform = GL.glGetUniformLocation(r.program, "offsets[0]")
        for row in ([np.nan, np.nan], [np.nan, 0.0], [0.0, np.nan], [0.0, np.inf], [-np.inf, 5.0]):
            px = r.draw(wide, np.array([row]), near=[False, True])
            assert (px.reshape(-1, 4) == [51, 102, 153, 0]).all(), row
            # no non-finite vertex reaches OpenGL (undefined there): the person is at HIDDEN
            got = np.zeros(2, np.float32)
            GL.glGetUniformfv(r.program, uniform, got)
            assert (got == [HIDDEN, HIDDEN]).all(), (row, got)
    finally:
        r.close()


def test_raster_draw_people_reads_only_its_rectangles():
    """Over the stored room only the people are drawn, and each rectangle (rows top first
    as read, x0, y0, x1, y1 end exclusive) is read into ``out``; nothing else is touched,
    a camera without rectangles included."""
    person = _quad(0.25, 0.25, 0.25, 0.0, (1.0, 0.0, 0.0), 0)      # pixels 32..47 both ways
    r = _raster([_quad(0.0, 0.0, 1.0, 0.5, ROOM, -1), person], 1, n_tiles=2)
    try:
        with pytest.raises(RuntimeError, match="store_room"):
            r.draw_people(EYE, np.zeros((1, 2)), [0], [[(0, 0, 4, 4)]], np.zeros_like(r.pixels))
        r.draw(np.repeat(EYE, 2, axis=0), np.full((1, 2), np.nan))
        r.store_room()
        out = np.zeros_like(r.pixels)
        r.draw_people(np.repeat(EYE, 2, axis=0), np.zeros((1, 2)), [0, 1], [[(24, 28, 44, 52)], []], out)
    finally:
        r.close()
    expected = np.zeros_like(out)
    expected[0, 28:52, 24:44] = [51, 102, 153, 0]
    expected[0, 32:48, 32:44] = [255, 0, 0, 1]
    assert np.array_equal(out, expected)


def test_raster_draw_people_on_a_later_page_starts_from_the_room(monkeypatch):
    """With one band per page, each camera's rectangles get the room's colour and depth
    back before the people are drawn, on every page: a person drawn in one call is gone
    in the next call that hides them."""
    from render.raster import Rasteriser

    monkeypatch.setattr(Rasteriser, "max_page_height", S)
    person = _quad(0.25, 0.25, 0.25, 0.0, (1.0, 0.0, 0.0), 0)      # pixels 32..47 both ways
    r = _raster([_quad(0.0, 0.0, 1.0, 0.5, ROOM, -1), person], 1, n_tiles=2)
    two, rects = np.repeat(EYE, 2, axis=0), [[(24, 28, 44, 52)], [(24, 28, 44, 52)]]
    try:
        assert [(p.first, p.tiles) for p in r.pages] == [(0, 1), (1, 1)]
        r.draw(two, np.full((1, 2), np.nan))
        r.store_room()
        shown, hidden = np.zeros_like(r.pixels), np.zeros_like(r.pixels)
        r.draw_people(two, np.zeros((1, 2)), [0, 1], rects, shown)
        r.draw_people(two, np.full((1, 2), np.nan), [0, 1], rects, hidden)
    finally:
        r.close()
    expected = np.zeros_like(shown)
    expected[:, 28:52, 24:44] = [51, 102, 153, 0]
    assert np.array_equal(hidden, expected)
    expected[:, 32:48, 32:44] = [255, 0, 0, 1]
    assert np.array_equal(shown, expected)


def test_raster_checks_its_arguments():
    from render.raster import Rasteriser

    room = _quad(0.0, 0.0, 1.0, 0.5, ROOM, -1)
    person = _quad(0.0, 0.0, 0.5, 0.0, (1.0, 0.0, 0.0), 0)
    with pytest.raises(ValueError, match="room's vertices first"):
        _raster([room, person, room], 1)
    with pytest.raises(ValueError, match=r"near_only: expected 0\.\.6 "):
        _raster([room, person], 1, near_only=7)
    with pytest.raises(ValueError, match=r"near_only: expected 0\.\.6 "):
        _raster([room, person], 1, near_only=-1)
    r = _raster([room, person], 1, n_tiles=2, near_only=6)      # all of the people's vertices: allowed
    try:
        assert isinstance(r, Rasteriser)
        two = np.repeat(EYE, 2, axis=0)
        with pytest.raises(ValueError, match="view_projs: expected 1..2 cameras, got 3"):
            r.draw(np.repeat(EYE, 3, axis=0), np.zeros((1, 2)))
        with pytest.raises(ValueError, match="view_projs: expected 1..2 cameras, got 0"):
            r.draw(EYE[:0], np.zeros((1, 2)))
        for bands in ([0, 0], [1, 2], [-1, 0], [0]):
            with pytest.raises(ValueError, match="bands: expected 2 distinct band numbers in 0..1"):
                r.draw(two, np.zeros((1, 2)), bands=bands)
        with pytest.raises(ValueError, match=r"near: expected one flag per camera \(2\), got 1"):
            r.draw(two, np.zeros((1, 2)), near=[True])
        r.draw(two, np.full((1, 2), np.nan))
        r.store_room()
        with pytest.raises(ValueError, match="view_projs, bands, rects: expected one per camera, got 2, 2, 1"):
            r.draw_people(two, np.zeros((1, 2)), [0, 1], [[(0, 0, 4, 4)]], np.zeros_like(r.pixels))
        for out in (np.zeros((1, S, S, 4), np.uint8), np.zeros(r.pixels.shape, np.float32),
                    np.zeros((2, S, S, 8), np.uint8)[..., ::2]):
            with pytest.raises(ValueError, match=r"out: expected a C-contiguous uint8 array of shape \(2, 64, 64, 4\)"):
                r.draw_people(two, np.zeros((1, 2)), [0, 1], [[(0, 0, 4, 4)], []], out)
        out = np.zeros_like(r.pixels)
        for bands in ([0, 0], [1, 2], [-1, 0]):          # as draw: a camera drawn or read elsewhere
            with pytest.raises(ValueError, match="bands: expected 2 distinct band numbers in 0..1"):
                r.draw_people(two, np.zeros((1, 2)), bands, [[(0, 0, 4, 4)], [(0, 0, 4, 4)]], out)
            assert not out.any()
        for rect in ((-1, 0, 4, 4), (0, -1, 4, 4), (0, 0, S + 1, 4), (0, 0, 4, S + 1), (5, 0, 4, 4),
                     (0, 5, 4, 4)):
            with pytest.raises(ValueError, match=r"rects\[1\]: rectangle .* is not within the 64x64 canvas"):
                r.draw_people(two, np.zeros((1, 2)), [0, 1], [[(0, 0, 4, 4)], [(0, 0, 2, 2), rect]], out)
            assert not out.any()                                   # refused before anything is read
        r.draw_people(two[:0], np.zeros((1, 2)), [], [], out)                    # no camera: nothing to do
        r.draw_people(two, np.zeros((1, 2)), [0, 1], [[(0, 0, S, S)], [(7, 7, 7, 9)]], out)  # edges, empty: allowed
        assert out[0].any() and not out[1].any()
    finally:
        r.close()
    r.close()                                                      # twice: nothing left to free


def test_positions_of_another_shape_are_refused_not_reshaped(lab_renderer, three_people):
    """(2, 3) - the x row and the y row - or a flat (6,) used to be read as three (x, y) pairs;
    (3, 3) rows are not (x, y) pairs either."""
    for wrong in (three_people.T.copy(), three_people.ravel(), three_people[None],
                  np.column_stack([three_people, np.zeros(3)])):       # (3, 3): x, y, z
        with pytest.raises(ValueError, match=rf"^positions_xy: expected shape \(3, 2\), got {re.escape(str(wrong.shape))}$"):
            lab_renderer.render(wrong, clean=True)
        with pytest.raises(ValueError, match=r"^positions_xy: expected shape \(3, 2\)"):
            lab_renderer.labels(wrong)


def test_noisy_frames_without_an_rng_say_how_to_get_clean_ones(lab_renderer, three_people):
    with pytest.raises(ValueError, match=r"^rng: expected an np\.random\.Generator \(or clean=True"):
        lab_renderer.render(three_people)


def test_cameras_come_in_the_order_asked(lab_renderer, three_people):
    both = lab_renderer.render(three_people, cameras=[9, 2], clean=True)
    assert both.cameras == (9, 2)
    for k, n in enumerate((9, 2)):
        alone = lab_renderer.render(three_people, cameras=[n], clean=True)
        assert alone.cameras == (n,)
        assert np.array_equal(both.rgb[k], alone.rgb[0]) and np.array_equal(both.labels[k], alone.labels[0])
    assert np.array_equal(lab_renderer.labels(three_people, cameras=[9, 2]), both.labels)
    assert lab_renderer.background(cameras=[9, 2]).cameras == (9, 2)
    assert np.array_equal(lab_renderer.background(cameras=[9, 2]).rgb, lab_renderer.background().rgb[[8, 1]])


def test_a_scene_of_floor_plane_cameras_is_not_rendered():
    from render import Renderer
    from scene import load_scene

    with pytest.raises(ValueError, match=r"^scene: 'circle' has floor-plane cameras only; rendering needs calibrated"):
        Renderer(load_scene("circle"))


def test_cameras_of_two_image_sizes_are_not_rendered_together(lab):
    """One canvas and one frame size for all: refused before any GL work, naming both sizes."""
    import dataclasses

    from render import Renderer

    c = lab.cameras
    K = c[1].K.copy()
    K[:2] /= 2
    small = dataclasses.replace(c[1], K=K, width=320, height=240)
    scene = dataclasses.replace(lab, cameras=(c[0], small, *c[2:]))
    with pytest.raises(ValueError, match=r"^cameras: expected one image size for all rendered cameras, "
                                         r"got \[\(320, 240\), \(640, 480\)\]$"):
        Renderer(scene)
    with pytest.raises(ValueError, match="one image size"):
        Renderer(scene, cameras=[2, 5])
