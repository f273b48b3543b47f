"""The top view draws each tasked camera's occluded cone where its scanline says."""

import itertools

import cv2
import numpy as np
import pytest

from scene import load_scene
from testbed.loop import FrameResult
from testbed.topview import BACKGROUND, CAMERA_OFF, TopView


def _frame(camera: int, scan: np.ndarray) -> FrameResult:
    return FrameResult(0, (camera,), scan[None], [], 0.0, 0.0, 0, (), (), np.zeros((0, 2)),
                       np.zeros((0, 2)), np.zeros(0, int), np.zeros((0, 2)))


def test_cone_crossing_pi_is_the_narrow_wedge():
    # lab camera 7 looks along -170.5 deg: its bearings jump from -pi to pi inside the image
    scene = load_scene("lab")
    width = 200
    b = np.radians(np.linspace(-145.0, -196.0, width))
    b = np.arctan2(np.sin(b), np.cos(b))                    # wrapped into (-pi, pi] as the pipeline gives them
    jump = int(np.flatnonzero(np.abs(np.diff(b)) > np.pi)[0])
    scan = np.zeros(width, bool)
    scan[jump - 3: jump + 3] = True                         # a narrow run straight across the wrap
    bearings = {n: b for n in range(1, len(scene.cameras) + 1)}
    img = TopView(scene, width=400).draw(_frame(7, scan), bearings, title=" ")
    view = TopView(scene, width=400)
    shaded = np.any(img != BACKGROUND, axis=2) & (view.inside > 0)
    assert shaded.mean() < 0.2                              # a thin wedge, not the rest of the circle


def test_two_video_writers_to_one_path_do_not_share_a_temporary_file(tmp_path):
    """Two runs given one --video: each writes its own temporary file; the last to finish wins whole."""
    import imageio_ffmpeg

    from testbed.video import VideoWriter

    a, b = VideoWriter(tmp_path / "v.mp4", fps=5), VideoWriter(tmp_path / "v.mp4", fps=5)
    assert a.tmp != b.tmp
    for _ in range(3):
        a.write(np.zeros((32, 32, 3), np.uint8))
        b.write(np.full((32, 32, 3), 255, np.uint8))
    a.close()
    b.close()                                          # used to fail: "ffmpeg wrote nothing"
    reader = imageio_ffmpeg.read_frames(str(tmp_path / "v.mp4"))
    next(reader)
    frames = [np.frombuffer(f, np.uint8) for f in reader]
    assert len(frames) == 3 and all(f.mean() > 200 for f in frames)   # b's white frames, not a's
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.mp4"]


def test_hull_hole_is_not_painted():
    """A hull polygon with a hole (free space carved inside it, as when the cameras' sight
    radius ends before the far wall) leaves the hole unpainted: its exterior alone used to
    paint the whole room as hull."""
    from shapely.geometry import box

    from testbed.topview import HULL

    scene = load_scene("lab")
    ring = box(0.5, 0.5, 6.0, 5.0).difference(box(2.0, 2.0, 4.0, 4.0))
    frame = _frame(1, np.zeros(640, bool))
    frame.polygons.append(ring)
    view = TopView(scene, width=400)
    img = view.draw(frame, {n: np.linspace(1.0, 0.2, 640) for n in range(1, 17)}, title=" ")
    (u_hole, v_hole), (u_hull, v_hull) = view.px([[3.0, 3.0], [1.0, 1.0]])
    assert tuple(img[v_hull, u_hull]) == HULL
    assert tuple(img[v_hole, u_hole]) != HULL


CORRIDOR = """\
room: {shape: rectangle, width: 1.0, depth: 100.0, height: 3.0}
cameras:
  intrinsics: {resolution: [320, 240], hfov_deg: 60, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 1, position: [0.5, 0.1, 2.5], yaw_deg: 90, pitch_deg: 10}
people: {count: 1, radius: 0.25}
"""


@pytest.mark.parametrize("text", [CORRIDOR, CORRIDOR.replace("width: 1.0, depth: 100.0", "width: 3.0, depth: 4.0")])
def test_room_deeper_than_wide_fits_a_square(text):
    """A room deeper than it is wide is drawn within a square canvas, centred: a 1 x 100 m
    corridor made a 720 x 66254-pixel top view, which `run --video` could not encode after
    the whole run."""
    from scene import Scene

    scene = Scene.from_text(text, "corridor.yaml")
    view = TopView(scene, width=720)
    assert view.height <= view.width
    u, v = view.px(scene.room.vertices).T
    assert v.min() == view.margin and v.max() == view.height - view.margin   # the depth fills the height
    assert u.min() + u.max() == pytest.approx(view.width, abs=1)             # centred across


def test_a_cone_spans_its_columns_edges_as_the_hull_carves_it():
    """A run of occupied columns is shaded out to its outer column edges, half a column
    beyond the outer bearings, as the hull carves it (tasking.cones.scanline_intervals):
    drawn through the column centres, a one-column cone had no width at all."""
    scene = load_scene("lab")
    xy, yaw, fov = scene.floor_poses()
    width = 10                                              # 4.9 degree columns: wide enough to see
    b = yaw[0] + np.linspace(0.45, -0.45, width) * fov[0]   # decreasing left to right, as the pipeline gives
    step = b[0] - b[1]
    view = TopView(scene, width=400)
    for j in (3, 4, 9):                                     # inner columns, and the last one at the fov edge
        scan = np.zeros(width, bool)
        scan[j] = True
        img = view.draw(_frame(1, scan), {n: b for n in range(1, 17)}, title=" ")
        for side in (-0.4, 0.4):                            # within the column, 3 m out
            a = b[j] + side * step
            u, v = view.px(xy[0] + 3.0 * np.array([np.cos(a), np.sin(a)]))
            assert tuple(img[v, u]) != BACKGROUND, (j, side)
        for side in (-0.7, 0.7):                            # beyond its edges: not the cone (no neighbour set)
            a = b[j] + side * step
            u, v = view.px(xy[0] + 3.0 * np.array([np.cos(a), np.sin(a)]))
            assert tuple(img[v, u]) == BACKGROUND, (j, side)


def test_video_tiles_show_the_columns_of_the_scanlines_under_them(monkeypatch):
    """`run --video`: each tasked frame is drawn with its scanline under it. The raw frame was
    drawn, whose columns pitch and lens bend: a person at raw columns 560-599 from row 200
    down in lab camera 5's image had a true run of columns 569-639 under it."""
    from types import SimpleNamespace

    from pipeline import Pipeline
    from scene import Scene, scene_path
    from testbed import topview
    from testbed.commands.run import _painter

    text = scene_path("lab").read_text()             # camera 9 pitched less: a level view of another height
    scene = Scene.from_text(text.replace("yaw_deg: -132.1, pitch_deg: 15.0}", "yaw_deg: -132.1, pitch_deg: 5.0}"))
    numbers = (5, 9)
    pipes = {n: Pipeline([scene.cameras[n - 1]]) for n in numbers}
    heights = [p.rectifier.out_height for p in pipes.values()]
    assert heights[0] != heights[1]
    labels = np.zeros((len(numbers), 480, 640), np.int32)
    labels[:, 120:, :100] = 1                                # people at both edges of the images
    labels[:, 200:, 560:600] = 2
    rgb = np.where(labels[..., None] > 0, 255, 0).astype(np.uint8).repeat(3, axis=3)
    scans = np.stack([pipes[n].ground_truth(labels[i:i + 1])[1][0] for i, n in enumerate(numbers)])
    result = FrameResult(0, numbers, scans, [], 0.0, 0.0, 0, (), (), np.zeros((0, 2)), np.zeros((0, 2)),
                         np.zeros(0, int), np.zeros((0, 2)), rgb=rgb)
    tiled = {}

    def mosaic(frames, scanlines, tasked, width):
        tiled.update(frames=frames, scanlines=scanlines)
        return np.full((10, width, 3), 7, np.uint8)

    monkeypatch.setattr(topview, "mosaic", mosaic)
    source = SimpleNamespace(pipes=pipes, bearings={n: p.bearings[0] for n, p in pipes.items()})
    painted = _painter(scene, source)(result)
    assert np.all(painted[:10] == 7)                         # the tiles, then the top view under them
    assert np.array_equal(painted[10:], TopView(scene, width=720).draw(result, source.bearings))
    assert np.array_equal(tiled["scanlines"], scans)
    assert len(tiled["frames"]) == 2
    for frame, scan in zip(tiled["frames"], scans):
        assert np.array_equal(frame.any(axis=(0, 2)), scan)  # the people's columns are the runs' columns
        assert frame.shape == (max(heights), scan.size, 3)   # one tile height for every frame of the video


def test_no_two_legend_entries_look_alike():
    """The legend showed tracks and tasked cameras as the same red square, and people (green
    rings in the picture) as a filled square: each coloured entry is now drawn as its mark is."""
    view = TopView(load_scene("lab"), width=720)
    img = np.full((view.height, view.width, 3), BACKGROUND, np.uint8)
    view._legend(img)
    strip = img[view.height - view.margin:]
    rgb = strip.astype(int)
    coloured = rgb.max(axis=2) - rgb.min(axis=2) > 40          # the marks; the text is grey
    cols = np.flatnonzero(coloured.any(axis=0))
    glyphs = []
    for g in np.split(cols, np.flatnonzero(np.diff(cols) > 1) + 1):
        rows = np.flatnonzero(coloured[:, g].any(axis=1))
        glyphs.append(strip[rows[0]:rows[-1] + 1, g[0]:g[-1] + 1])
    assert len(glyphs) == 5                                     # person, track, hull, occluded, tasked camera
    for i in range(len(glyphs)):
        for j in range(i):
            assert glyphs[i].shape != glyphs[j].shape or not np.array_equal(glyphs[i], glyphs[j]), (i, j)
    person = glyphs[0]
    assert np.array_equal(person[person.shape[0] // 2, person.shape[1] // 2], BACKGROUND)   # a ring
    # and the other cameras' grey dot, after them: solid 3 x 3 (text's edges only touch its grey)
    solid = cv2.erode((strip == CAMERA_OFF).all(axis=2).astype(np.uint8), np.ones((3, 3), np.uint8))
    grey = np.flatnonzero(solid.any(axis=0))
    assert grey.size and grey.min() > cols.max()


def test_a_room_centred_on_the_origin_is_drawn_within_the_margins():
    """The circle room's corner of bounds is (-1, -1) m, not the origin (the lab's): the room
    fills the width less the margins and the height likewise, its centre at the canvas's
    centre, y up (the top of the room is the top of the canvas)."""
    scene = load_scene("circle")
    view = TopView(scene, width=640, margin=30)
    assert view.scale == pytest.approx(580 / 2.0) and view.height == 640
    u, v = view.px(scene.room.vertices).T
    assert (u.min(), u.max(), v.min(), v.max()) == (30, 610, 30, 610)
    assert view.px([0.0, 0.0]).tolist() == [320, 320]
    assert view.px([0.0, 1.0]).tolist() == [320, 30] and view.px([1.0, 0.0]).tolist() == [610, 320]
    assert view.inside[320, 320] == 1 and view.inside[35, 35] == 0         # a corner of the canvas: outside


def test_a_track_s_tail_is_its_last_40_positions_and_no_more_is_kept():
    """Tails were kept for the whole run (one point per track per frame, for hours of video)."""
    from testbed.topview import TAIL

    scene = load_scene("lab")
    view = TopView(scene, width=400)
    bearings = {n: np.linspace(0.5, -0.5, 64) for n in range(1, 17)}
    path = np.column_stack([np.linspace(1.0, 5.0, 100), np.full(100, 3.0)])
    for k, p in enumerate(path):
        frame = FrameResult(k, (1,), np.zeros((1, 64), bool), [], 0.0, 0.0, 0, (), (), np.zeros((0, 2)),
                            np.zeros((0, 2)), np.array([7]), p[None])
        img = view.draw(frame, bearings, title=" ")
    assert TAIL == 40 and len(view.tails[7]) == TAIL
    np.testing.assert_array_equal(view.tails[7], path[-TAIL:])
    untracked = FrameResult(99, (1,), np.zeros((1, 64), bool), [], 0.0, 0.0, 0, (), (), np.zeros((0, 2)),
                            np.zeros((0, 2)), np.zeros(0, int), np.zeros((0, 2)))
    drawn = np.any(img != TopView(scene, width=400).draw(untracked, bearings, title=" "), axis=2)
    row = view.px([0.0, 3.0])[1]
    us = np.flatnonzero(drawn[row - 1: row + 2].any(axis=0))
    assert abs(us.min() - view.px(path[-TAIL])[0]) <= 1                  # from the 40th last point on


def test_mosaic_tiles_frames_left_to_right_with_their_scanlines_under_them():
    """Four 40 x 80 frames, 3 to a row of 300 pixels: tiles 100 x 50 (the frame's aspect),
    each followed by a 10-pixel strip (black where the scanline is set, light grey where
    not) and 4 white rows; the fourth frame starts the second row; the rest stays white."""
    from testbed.topview import mosaic

    grey = np.array([30, 90, 150, 210], np.uint8)
    rgb = np.broadcast_to(grey[:, None, None, None], (4, 40, 80, 3)).copy()
    scans = np.zeros((4, 80), bool)
    for i in range(4):
        scans[i, 20 * i: 20 * i + 20] = True                 # a quarter of the columns, another each frame
    out = mosaic(rgb, scans, (1, 5, 9, 13), 300)
    assert out.shape == (2 * (50 + 10 + 4), 300, 3) and out.dtype == np.uint8
    for i in range(4):
        r, c = divmod(i, 3)
        y, x = 64 * r, 100 * c
        tile = out[y + 20:y + 50, x:x + 100]                 # below the "cam N" label
        assert np.all(tile == grey[i])
        strip = out[y + 50:y + 60, x:x + 100]
        on = np.zeros(100, bool)
        on[25 * i: 25 * i + 25] = True                       # 80 columns stretched to 100
        assert np.all(strip[:, on] == 0) and np.all(strip[:, ~on] == 220)
        assert np.all(out[y + 60:y + 64, x:x + 100] == 255)
        assert np.any(out[y:y + 20, x:x + 100] != grey[i])   # the label is drawn on the tile
    assert np.all(out[64:, 100:] == 255)                     # no fifth or sixth frame
    assert mosaic(rgb[:3], scans[:3], (1, 5, 9), 300).shape == (64, 300, 3)   # a full row: no empty one under it


def test_floor_points_map_to_rounded_pixels_from_the_room_s_own_corner():
    """A room from (1, 3) to (5, 5.01) m drawn 400 pixels wide with 30-pixel margins: 85
    pixels a metre (340 / 4 m), the canvas 2.01 * 85 + 60 = 230.85 -> 231 pixels high,
    (1, 3) at (30, 201), y up; points go to the nearest pixel, not the one below."""
    from types import SimpleNamespace

    from scene import Room

    room = Room(np.array([[1.0, 3.0], [5.0, 3.0], [5.0, 5.01], [1.0, 5.01]]), 2.5)
    view = TopView(SimpleNamespace(room=room), width=400, margin=30)
    assert view.scale == pytest.approx(85.0) and view.height == 231
    assert view.px([[1.0, 3.0], [5.0, 5.01]]).tolist() == [[30, 201], [370, 30]]
    # u = 30 + 1.01 * 85 = 115.85, v = 201 - 0.51 * 85 = 157.65
    assert view.px([2.01, 3.51]).tolist() == [116, 158]


def _lab_frame(tasked, scans, truth=((0.0, 0.0),)[:0]):
    return FrameResult(0, tuple(tasked), np.asarray(scans, bool), [], 0.0, 0.0, 0, (), (),
                       np.zeros((0, 2)), np.asarray(truth, float).reshape(-1, 2), np.zeros(0, int), np.zeros((0, 2)))


def test_a_cone_is_shaded_half_way_to_its_colour_out_to_the_far_walls():
    """One tasked camera's occluded cone blends the background half way to CONE:
    (250 + 120) / 2, (250 + 160) / 2, (250 + 230) / 2; the same 5 m from the camera (beyond
    half the room's length) as 2 m from it."""
    from testbed.topview import CONE

    scene = load_scene("lab")
    xy, yaw, fov = scene.floor_poses()
    view = TopView(scene, width=400)
    b = yaw[0] + np.linspace(0.45, -0.45, 10) * fov[0]
    img = view.draw(_lab_frame((1,), np.ones((1, 10))), {n: b for n in range(1, 17)}, title=" ")
    assert tuple(CONE) == (120, 160, 230)
    for d in (2.0, 5.0):                                        # camera 1 at (0.78, 0.05) m looks at 47.9 degrees
        u, v = view.px(xy[0] + d * np.array([np.cos(yaw[0]), np.sin(yaw[0])]))
        assert tuple(img[v, u]) == (185, 205, 240), d


def test_a_cone_wider_than_a_right_angle_follows_its_arc():
    """A 170-degree run (a wide-angle lens) is shaded as a fan out to its arc: the triangle
    of its two outer edges alone leaves out the room 3 m in front of the camera."""
    scene = load_scene("lab")
    xy, yaw, _ = scene.floor_poses()
    view = TopView(scene, width=400)
    b = yaw[0] + np.radians(np.linspace(85.0, -85.0, 20))
    img = view.draw(_lab_frame((1,), np.ones((1, 20))), {n: b for n in range(1, 17)}, title=" ")
    u, v = view.px(xy[0] + 3.0 * np.array([np.cos(yaw[0]), np.sin(yaw[0])]))
    assert tuple(img[v, u]) == (185, 205, 240)


def test_field_of_view_edges_are_drawn_at_both_outer_column_edges_and_end_at_the_walls():
    """Each tasked camera's two outer column edges are drawn as lines (half a column beyond
    its first and last bearings), inside the room only: outside it the picture is as when
    no camera is tasked, but for the camera's own mark."""
    from shapely.geometry import LineString

    scene = load_scene("lab")
    xy, yaw, fov = scene.floor_poses()
    view = TopView(scene, width=400)
    b = yaw[0] + np.linspace(0.45, -0.45, 10) * fov[0]
    step = b[0] - b[1]
    bearings = {n: b for n in range(1, 17)}
    img = view.draw(_lab_frame((1,), np.zeros((1, 10))), bearings, title=" ")
    untasked = view.draw(_lab_frame((), np.zeros((0, 10))), bearings, title=" ")
    for a in (b[0] + step / 2, b[-1] - step / 2):
        ray = np.array([np.cos(a), np.sin(a)])
        for d in (1.0, 2.0, 3.0):
            u, v = view.px(xy[0] + d * ray)
            assert np.any(img[v - 1:v + 2, u - 1:u + 2] != BACKGROUND), (a, d)
        # where the edge leaves the room, and 0.3 m beyond it (in the margin): background
        exit_ = np.asarray(LineString([xy[0] + 0.2 * ray, xy[0] + 20 * ray]).intersection(
            scene.room.polygon.exterior).coords[0])
        u, v = view.px(exit_ + 0.3 * ray)
        assert 0 <= u < view.width and 0 <= v < view.height and view.inside[v, u] == 0
        assert np.all(img[v - 1:v + 2, u - 1:u + 2] == BACKGROUND), a
    differ = np.any(img != untasked, axis=2) & (view.inside == 0)
    rr, cc = np.nonzero(differ)
    u1, v1 = view.px(xy[0])
    assert np.hypot(cc - u1, rr - v1).max(initial=0) <= 8          # camera 1's mark, drawn larger when tasked


def test_people_are_rings_of_their_radius_and_tasked_cameras_larger_red_dots():
    """A person of the lab's 0.25 m radius is a ring about 12.7 pixels (at 50.7 pixels a
    metre) round their position, empty inside; a tasked camera a red dot 6 pixels in radius,
    the others grey dots of 4."""
    from testbed.topview import CAMERA_ON, TRUTH

    scene = load_scene("lab")
    xy, _, _ = scene.floor_poses()
    view = TopView(scene, width=400)
    assert view.scale == pytest.approx(340 / 6.7056)
    img = view.draw(_lab_frame((3,), np.zeros((1, 10)), truth=[[3.0, 3.0]]), {n: np.linspace(0.5, -0.5, 10)
                                                                          for n in range(1, 17)}, title=" ")
    u, v = view.px([3.0, 3.0])
    assert tuple(img[v, u + 12]) == TRUTH and tuple(img[v - 12, u]) == TRUTH
    assert np.all(img[v - 6:v + 7, u - 6:u + 7] == BACKGROUND)
    u, v = view.px(xy[2])                                       # camera 3, tasked
    assert all(tuple(img[v + dv, u + du]) == CAMERA_ON for du, dv in ((0, 0), (-5, 0), (5, 0), (0, -5)))
    u, v = view.px(xy[1])                                       # camera 2, not tasked
    assert tuple(img[v, u]) == CAMERA_OFF and tuple(img[v, u - 3]) == CAMERA_OFF
    assert tuple(img[v, u - 6]) != CAMERA_OFF


def test_legend_words_end_before_the_next_mark():
    """Each legend entry's word is written out before the next entry's mark: a clear gap
    of background just left of every coloured mark but the first."""
    view = TopView(load_scene("lab"), width=720)
    img = np.full((view.height, view.width, 3), BACKGROUND, np.uint8)
    view._legend(img)
    strip = img[view.height - view.margin:].astype(int)
    coloured = strip.max(axis=2) - strip.min(axis=2) > 40
    cols = np.flatnonzero(coloured.any(axis=0))
    starts = [g[0] for g in np.split(cols, np.flatnonzero(np.diff(cols) > 1) + 1)]
    assert len(starts) == 5
    assert all(s2 - s1 > 40 for s1, s2 in itertools.pairwise(starts))     # a word of 4+ letters between marks
    for s in starts[1:]:
        assert np.all(strip[:, s - 10:s - 3] == BACKGROUND), s          # (the mark's own soft edge nearer)


def test_overlapping_cones_darken_and_reach_the_far_corner():
    """Each of k tasked cameras' cones shades the floor 1/k of the way to half CONE: where
    cameras 1 and 2 both see occlusion the blend is half way, where camera 1 alone a
    quarter; the cones reach the room's far corner, 8.2 m from camera 1 (further than the
    room is long)."""
    scene = load_scene("lab")
    _, yaw, fov = scene.floor_poses()
    view = TopView(scene, width=400)
    bearings = {n: yaw[n - 1] + np.linspace(0.45, -0.45, 10) * fov[n - 1] for n in range(1, 17)}
    img = view.draw(_lab_frame((1, 2), np.ones((2, 10))), bearings, title=" ")
    for p, blend in (([6.6, 5.7], (185, 205, 240)),              # both cameras' cones, at the far corner
                     ([3.3, 3.0], (185, 205, 240)),
                     ([5.0, 2.5], (217.5, 227.5, 245))):         # camera 1's alone (camera 2 sees 46-95 deg)
        u, v = view.px(p)
        np.testing.assert_allclose(img[v, u], blend, atol=1, err_msg=str(p))


def test_with_no_camera_tasked_the_floor_is_unshaded():
    """No tasked camera: no cone, the floor is background (no 0 / 0 shade)."""
    import warnings

    scene = load_scene("lab")
    view = TopView(scene, width=400)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        img = view.draw(_lab_frame((), np.zeros((0, 10))), {n: np.linspace(0.5, -0.5, 10) for n in range(1, 17)},
                        title=" ")
    u, v = view.px([3.0, 3.0])
    assert tuple(img[v, u]) == BACKGROUND


def test_the_walls_are_drawn_all_round_the_room():
    """The room's outline in WALL, its closing side (last corner back to the first) too."""
    from testbed.topview import WALL

    scene = load_scene("lab")
    view = TopView(scene, width=400)
    img = view.draw(_lab_frame((), np.zeros((0, 10))), {n: np.linspace(0.5, -0.5, 10) for n in range(1, 17)},
                    title=" ")
    corners = scene.room.vertices
    for a, b in zip(corners, np.roll(corners, -1, axis=0)):
        for t in (0.2, 0.7):                                    # clear of the cameras' marks on the walls
            u, v = view.px(a + t * (b - a))
            assert tuple(img[v, u]) == WALL, (a, b, t)


def test_every_camera_is_marked_and_numbered():
    """Cameras 1 to 16 each get a grey dot and their number in dark text up and right of
    it (clear of the walls); two-digit numbers are written wider than one-digit ones."""
    import cv2

    scene = load_scene("lab")
    xy, _, _ = scene.floor_poses()
    view = TopView(scene, width=400)
    img = view.draw(_lab_frame((), np.zeros((0, 10))), {n: np.linspace(0.5, -0.5, 10) for n in range(1, 17)},
                    title=" ")
    near_wall = np.zeros((view.height, view.width), np.uint8)
    cv2.polylines(near_wall, [view.px(scene.room.vertices)], True, 1, 8)
    dark = (img.max(axis=2) < 120) & (near_wall == 0)
    widths = {}
    for n in range(1, 17):
        u, v = view.px(xy[n - 1])
        assert tuple(img[v, u]) == CAMERA_OFF, n
        cols = np.flatnonzero(dark[v - 18:v - 4, u + 5:u + 30].any(axis=0))
        assert cols.size, n
        widths[n] = cols.max() - cols.min()
    assert max(widths[n] for n in range(1, 10)) < min(widths[n] for n in range(10, 17))


def test_a_track_is_a_cross_at_its_position_with_its_number_below_right():
    """A track is marked by a red cross at its position, its number written down and right
    of it: tracks 7 and 8 at one place differ only there."""
    from testbed.topview import TRACK

    scene = load_scene("lab")
    bearings = {n: np.linspace(0.5, -0.5, 10) for n in range(1, 17)}

    def draw(i):
        frame = FrameResult(0, (), np.zeros((0, 10), bool), [], 0.0, 0.0, 0, (), (), np.zeros((0, 2)),
                            np.zeros((0, 2)), np.array([i]), np.array([[3.0, 3.0]]))
        return view.draw(frame, bearings, title=" ")

    view = TopView(scene, width=400)
    seven = draw(7)
    u, v = view.px([3.0, 3.0])
    for du, dv in ((0, 0), (-4, 0), (4, 0), (0, -4), (0, 4)):
        assert tuple(seven[v + dv, u + du]) == TRACK, (du, dv)
    assert tuple(seven[v - 4, u - 4]) == BACKGROUND                  # a cross, not a square
    view = TopView(scene, width=400)
    rr, cc = np.nonzero(np.any(seven != draw(8), axis=2))
    assert rr.size and rr.min() > v - 6 and cc.min() > u + 4         # only the number differs


def test_the_title_is_the_frame_s_unless_given():
    """Without a title the top left reads the frame's index, hull area and residual: frames
    of other hull areas are titled otherwise; a given title replaces it."""
    scene = load_scene("lab")
    view = TopView(scene, width=400)
    bearings = {n: np.linspace(0.5, -0.5, 10) for n in range(1, 17)}

    def draw(hull, title):
        frame = FrameResult(0, (), np.zeros((0, 10), bool), [], hull, 0.0, 0, (), (), np.zeros((0, 2)),
                            np.zeros((0, 2)), np.zeros(0, int), np.zeros((0, 2)))
        return view.draw(frame, bearings, title=title)[:25, :300]

    assert not np.array_equal(draw(1.0, ""), draw(2.0, ""))
    assert np.array_equal(draw(1.0, "a title"), draw(2.0, "a title"))
    assert not np.array_equal(draw(1.0, "a title"), draw(1.0, " "))


def test_a_person_s_ring_has_their_radius_in_pixels_and_at_least_2():
    """At 96 pixels a metre a 0.25 m person is a ring 24 pixels round (2 thick: solid from
    23 to 25, clear at 21 and 27); a 0.01 m one (1 pixel) a ring of 2."""
    from scene import Scene
    from testbed.topview import TRUTH

    for radius, r in ((0.25, 24), (0.01, 2)):
        scene = Scene.from_text(CORRIDOR.replace("width: 1.0, depth: 100.0", "width: 3.0, depth: 4.0")
                                .replace("radius: 0.25", f"radius: {radius}"), "room.yaml")
        view = TopView(scene, width=444, margin=30)
        assert view.scale == pytest.approx(96.0)
        img = view.draw(_lab_frame((), np.zeros((0, 10)), truth=[[1.5, 2.0]]), {1: np.linspace(0.5, -0.5, 10)},
                        title=" ")
        u, v = view.px([1.5, 2.0])
        for d in (r - 1, r, r + 1):
            assert tuple(img[v, u + d]) == TRUTH and tuple(img[v - d, u]) == TRUTH, (radius, d)
        assert tuple(img[v, u + r + 3]) == BACKGROUND, radius
        if r > 3:
            assert tuple(img[v, u + r - 3]) == BACKGROUND, radius


def test_draw_puts_the_legend_in_the_bottom_margin_each_mark_level_with_its_word():
    """The picture's bottom margin (below the wall) holds the legend's five coloured marks,
    each vertically within the rows of the word written after it."""
    view = TopView(load_scene("lab"), width=720)
    img = view.draw(_lab_frame((), np.zeros((0, 10))), {n: np.linspace(0.5, -0.5, 10) for n in range(1, 17)},
                    title=" ")
    strip = img[view.height - view.margin + 6:].astype(int)
    coloured = strip.max(axis=2) - strip.min(axis=2) > 40
    text = (strip.max(axis=2) < 200) & ~coloured
    cols = np.flatnonzero(coloured.any(axis=0))
    groups = np.split(cols, np.flatnonzero(np.diff(cols) > 1) + 1)
    assert len(groups) == 5
    for g, nxt in zip(groups, [*(h[0] for h in groups[1:]), strip.shape[1]]):
        mark = np.flatnonzero(coloured[:, g].any(axis=1))
        word = np.flatnonzero(text[:, g[-1] + 4:nxt - 3].any(axis=1))
        assert word.size and word.min() <= (mark.min() + mark.max()) / 2 <= word.max(), g[0]


def test_mosaic_tiles_average_their_frames_keep_their_aspect_and_name_their_cameras():
    """A 200-column frame in a 100-pixel tile averages each pair of columns (one-pixel black
    and white stripes come out mid grey, not all one or the other); a 47 x 80 frame's tile
    is the nearest 59 rows high (58.75); the label is the camera's number: renumbering one
    camera changes its tile's label alone."""
    from testbed.topview import mosaic

    stripes = np.zeros((3, 40, 200, 3), np.uint8)
    stripes[:, :, ::2] = 255
    out = mosaic(stripes, np.zeros((3, 200), bool), (1, 5, 9), 300)
    assert out.shape == (20 + 14, 300, 3)
    assert np.all(np.abs(out[15:20].astype(int) - 127.5) <= 1)    # below the labels
    small = np.full((3, 47, 80, 3), 90, np.uint8)
    scans = np.zeros((3, 80), bool)
    out = mosaic(small, scans, (1, 5, 9), 300)
    assert out.shape == (59 + 14, 300, 3) and np.all(out[58, :, 0] == 90) and np.all(out[59, :, 0] == 220)
    rr, cc = np.nonzero(np.any(out != mosaic(small, scans, (1, 6, 9), 300), axis=2))
    assert rr.size and rr.max() < 20 and cc.min() >= 100 and cc.max() < 200
