"""The near field: blind radii against projection, wedges cut by them, rendered people near cameras."""

import cv2
import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, box

from pipeline import Pipeline, load_params, sight_range
from pipeline.nearfield import raw_pixels_per_radian
from pipeline.rectify import level_cameras
from scene import Camera
from tasking import free_wedges_from_scanlines, visual_hull_of_scanlines


def blind_radius(cameras, object_height, margin=1.0):
    """The blind radius alone: the ``near`` of :func:`pipeline.sight_range`."""
    return sight_range(cameras, object_height, margin)[0]


def pinhole(height_m: float, pitch_deg: float, yaw_deg: float = 30.0) -> Camera:
    return Camera.from_pose(1, [1.0, 2.0, height_m], np.radians(yaw_deg), np.radians(pitch_deg),
                            640, 480, np.radians(49.0), np.zeros(5))


def projected_blind_distance(camera: Camera, top: float, step: float = 1e-3) -> float:
    """Largest floor distance, over the band's columns, at which a point at height ``top``
    projects (cv2.projectPoints, no distortion) below the raw image's lower pixel edge."""
    from pipeline.rectify import column_bearings

    Ks, _, width = level_cameras([camera])
    bearings = column_bearings(camera, Ks[0], width)[::8]
    d = np.arange(step, 5.0, step)
    c = camera.center_world
    pts = np.stack([c[0] + d[None] * np.cos(bearings)[:, None], c[1] + d[None] * np.sin(bearings)[:, None],
                    np.full((bearings.size, d.size), top)], -1).reshape(-1, 1, 3)
    rvec = cv2.Rodrigues(camera.R)[0]
    uv = cv2.projectPoints(pts, rvec, camera.t, camera.K, camera.dist)[0].reshape(bearings.size, d.size, 2)
    below = uv[..., 1] > camera.height - 0.5
    return float(d[np.where(below.any(0))[0].max()]) if below.any() else 0.0


@pytest.mark.parametrize("height_m, pitch_deg", [(2.2, 15.0), (3.0, 30.0), (2.0, 5.0)])
def test_blind_radius_is_where_the_objects_top_leaves_the_image(height_m, pitch_deg):
    camera = pinhole(height_m, pitch_deg)
    expected = projected_blind_distance(camera, 1.75)
    got = float(blind_radius([camera], 1.75, margin=0.0)[0])
    assert expected <= got <= expected + 2e-3


def test_blind_radius_at_the_centre_column_of_a_pinhole_camera():
    """drop / tan(pitch + half the vertical field of view) on the optical axis' column;
    the band's outer columns look further sideways, so their distance is the larger."""
    camera = pinhole(2.2, 15.0)
    half_vfov = np.arctan((camera.height - 0.5 - camera.K[1, 2]) / camera.K[1, 1])
    centre = 0.45 / np.tan(np.radians(15.0) + half_vfov)
    got = float(blind_radius([camera], 1.75, margin=0.0)[0])
    half_hfov = np.radians(49.0) / 2
    assert centre < got <= centre / np.cos(half_hfov) + 1e-9


def test_blind_radius_grows_with_the_margin_and_is_zero_or_inf_at_the_extremes(lab):
    cams = lab.cameras[:2]
    r0, r1, r60 = (blind_radius(cams, 1.75, m) for m in (0.0, 1.0, 60.0))
    assert np.all(r0 < r1) and np.all(r1 < r60)
    assert np.all(blind_radius(cams, 2.5) == 0.0)           # no higher than the object: seen on the horizon
    looking_up = pinhole(2.2, -30.0)                         # lower edge above the horizon
    assert blind_radius([looking_up], 1.0)[0] == np.inf
    with pytest.raises(ValueError, match="object_height"):
        blind_radius(cams, 0.0)
    with pytest.raises(ValueError, match="margin"):
        blind_radius(cams, 1.75, -1.0)


@pytest.mark.parametrize("kwargs, match", [
    (dict(object_width=0.0), "object_width"),
    (dict(object_width=-0.5), "object_width"),
    (dict(object_width=0.5, columns=0.0), "columns"),
    (dict(object_width=0.5, columns=-1.0), "columns"),
    (dict(object_width=0.5, raw_columns=0.0), "raw_columns"),
    (dict(object_width=0.5, raw_columns=-1.0), "raw_columns"),
    (dict(margin=np.inf), "margin"),
])
def test_sight_range_refuses_a_width_or_margin_it_could_not_use(lab, kwargs, match):
    """An object no wider than nothing, a run of no columns, or an endless margin has no
    sight radius: refused by name, not turned into a radius of 0, inf or a negative one."""
    with pytest.raises(ValueError, match=match):
        sight_range(lab.cameras[:1], 1.75, **kwargs)


def level_camera(dist=(0.0, 0.0, 0.0, 0.0, 0.0)) -> Camera:
    """1.5 m high, level, 64 x 48 pixels, 50 degrees across, lens distortion ``dist``."""
    return Camera.from_pose(1, [0.0, 0.0, 1.5], 0.0, 0.0, 64, 48, np.radians(50.0), list(dist))


def test_width_limits_default_to_one_rectified_column_and_one_raw_pixel():
    """A 10 cm object before a level undistorted camera: its raw image has fewest pixels per
    radian at the two centre pixels, g = 1 / atan(1 / f) with f = 32 / tan(25 deg), and the
    level camera f_v columns per radian; by height alone it is seen out to ~118 m, so the
    width sets far = w f_v / columns or w g / raw_columns, whichever is smaller."""
    cam = level_camera()
    g = 1.0 / np.arctan(np.tan(np.radians(25.0)) / 32.0)
    assert raw_pixels_per_radian(cam) == pytest.approx(g, rel=1e-12)
    f_v = level_cameras([cam])[0][0, 0, 0]
    assert f_v < g and sight_range([cam], 1.75)[1][0] > 100.0
    far = lambda **kw: sight_range([cam], 1.75, object_width=0.1, **kw)[1][0]
    assert far() == pytest.approx(0.1 * f_v, rel=1e-12)                 # columns = 1
    assert far(columns=0.5) == pytest.approx(0.1 * g, rel=1e-12)         # raw_columns = 1
    assert far(columns=0.5, raw_columns=2.0) == pytest.approx(0.05 * g, rel=1e-12)
    assert far(columns=4.0, raw_columns=2.0) == pytest.approx(0.025 * f_v, rel=1e-12)
    assert far(columns=0.5, pixels_per_radian=[g / 2]) == pytest.approx(0.05 * g, rel=1e-12)   # given, not recomputed


@pytest.mark.parametrize("camera, widest", [
    ("lab", (32, None)),                   # pitched down: the bottom row, near the centre
    ("top right", (0, 63)),                # barrel lens, tangential terms: a corner pixel
    ("bottom right", (32, 63)),
])
def test_raw_pixels_per_radian_is_the_widest_pixel_step_in_bearing(lab, camera, widest):
    """Recomputed with OpenCV: pixel edges u = -0.5 .. W - 0.5 on 33 rows from the first pixel
    row to the last, undistorted (cv2.undistortPoints), turned to the world (R^T) and taken
    to bearings; one over the largest bearing step of a pixel, wherever in the image that
    pixel lies (``widest``: its row and column)."""
    p1 = {"top right": 0.01, "bottom right": -0.01}.get(camera)
    cam = lab.cameras[0] if p1 is None else level_camera([-0.3, 0.0, p1, -0.01, 0.0])
    us = np.arange(cam.width + 1) - 0.5
    vs = np.linspace(0.0, cam.height - 1.0, 33)
    uv = np.stack(np.meshgrid(us, vs), -1).reshape(-1, 1, 2)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    norm = cv2.undistortPoints(uv, cam.K, cam.dist, None, None, None, criteria).reshape(-1, 2)
    rays = np.c_[norm, np.ones(len(norm))] @ cam.R                      # rows: R^T ray, world frame
    bearings = np.unwrap(np.arctan2(rays[:, 1], rays[:, 0]).reshape(33, -1), axis=1)
    steps = np.abs(np.diff(bearings, axis=1))                            # radians per pixel
    assert raw_pixels_per_radian(cam) == pytest.approx(1.0 / steps.max(), rel=1e-9)
    row, col = np.unravel_index(steps.argmax(), steps.shape)
    assert row == widest[0] and widest[1] in (None, col)


def test_a_camera_that_never_sees_the_object_has_no_range(lab):
    """near = far = inf where the object never shows: a lab camera and an object so thin
    that it is under one column wide (far = w min(f_v, g)) before it leaves the blind radius,
    and cameras on or below the floor. 1% wider, the range is [near, w min(f_v, g)]."""
    cams = lab.cameras[:1]
    near = sight_range(cams, 1.75)[0][0]
    per_radian = min(level_cameras(cams)[0][0, 0, 0], raw_pixels_per_radian(cams[0]))
    width = near / per_radian                       # one column wide at the blind radius
    got = sight_range(cams, 1.75, object_width=1.01 * width)
    assert got[0][0] == near and got[1][0] == pytest.approx(1.01 * near, rel=1e-12)
    assert np.concatenate(sight_range(cams, 1.75, object_width=0.99 * width)).tolist() == [np.inf, np.inf]
    for z, pitch in ((0.0, 0.0), (-0.2, 10.0)):        # a level camera's centre is exact on any BLAS
        low = Camera.from_pose(1, [1.0, 2.0, z], 0.0, np.radians(pitch), 640, 480, np.radians(49.0), np.zeros(5))
        assert low.center_world[2] == 0.0 if z == 0.0 else low.center_world[2] < 0.0   # on the floor, or below
        assert np.concatenate(sight_range([low], 0.5)).tolist() == [np.inf, np.inf]


@pytest.mark.parametrize("lower", [True, False])
def test_image_edge_follows_the_raw_image_edge_across_every_column(lab, lower):
    """The lower (upper) edge of a distorted lab camera, level frame, against the edge sampled
    at 20001 points from u = -0.5 to W - 0.5: the level camera's columns span exactly the
    upper edge's x, so a sampling that starts inside the image misses its ends."""
    from pipeline.nearfield import image_edge
    from pipeline.rectify import level_points

    cam = lab.cameras[0]
    Ks, _, width = level_cameras([cam])
    us = np.linspace(-0.5, cam.width - 0.5, 20001)
    x, y = level_points(cam, np.c_[us, np.full_like(us, cam.height - 0.5 if lower else -0.5)])
    columns = (np.arange(width) - Ks[0, 0, 2]) / Ks[0, 0, 0]
    assert x.min() <= columns[0] and columns[-1] <= x.max()
    want = np.interp(columns, x[np.argsort(x)], y[np.argsort(x)])
    np.testing.assert_allclose(image_edge(cam, Ks[0], width, lower), want, rtol=0, atol=1e-5)


def test_the_pipelines_margin_is_its_threshold_over_alpha_plus_the_opening(lab):
    params = load_params()
    pipe = Pipeline(lab.cameras[:1], params)
    margin = params.column_threshold / params.temporal_alpha + params.opening_kernel
    assert pipe.sight_range(1.75)[0][0] == blind_radius(lab.cameras[:1], 1.75, margin)[0]
    assert pipe.sight_range(1.75, truth=True)[0][0] == blind_radius(lab.cameras[:1], 1.75, 1.0)[0]


# --- wedges cut by the near field (hypothesis) ------------------------------------------

rigs = st.fixed_dictionaries({
    "seed": st.integers(0, 2**32 - 1),
    "n": st.integers(1, 6),
    # 0 (the plain hull) or a physical blind radius: a vertex nanometres from the apex is
    # rounded by ~1e-16 m, which tilts the wedge's sides by ~1e-8 rad (1e-8 m^2 at 16 m)
    "near": st.one_of(st.just(0.0), st.floats(1e-3, 3.0)),
    "fov": st.floats(0.2, 3.0),
})


def random_rig(rig):
    """Cameras in a 6 x 5 m room with random scanlines: (xy, bearings, scanlines, room)."""
    rng = np.random.default_rng(rig["seed"])
    n, w = rig["n"], 64
    xy = rng.uniform([0.2, 0.2], [5.8, 4.8], (n, 2))
    yaw = rng.uniform(-np.pi, np.pi, n)
    bearings = yaw[:, None] + np.linspace(rig["fov"] / 2, -rig["fov"] / 2, w)[None]
    scanlines = rng.random((n, w)) < 0.3
    return xy, bearings, scanlines, box(0, 0, 6, 5)


@settings(max_examples=40, deadline=None)
@given(rigs)
def test_near_field_wedges_leave_the_blind_disc_and_only_it(rig):
    xy, bearings, scans, room = random_rig(rig)
    near = np.full(len(xy), rig["near"])
    plain = free_wedges_from_scanlines(xy, bearings, scans, room)
    cut = free_wedges_from_scanlines(xy, bearings, scans, room, near)
    for c in range(len(xy)):
        disc = Point(xy[c]).buffer(rig["near"], quad_segs=64)
        assert cut[c].intersection(disc).area < 1e-12
        assert cut[c].difference(plain[c]).area < 1e-9              # only ever smaller
        # what is lost lies within the chords' reach of the disc (at most 8% past its radius)
        wider = Point(xy[c]).buffer(rig["near"] * 1.09 + 1e-9, quad_segs=64)
        assert plain[c].difference(cut[c]).difference(wider).area < 1e-9
    hull, hull_near = (visual_hull_of_scanlines(xy, bearings, scans, room, r) for r in (None, near))
    assert hull.difference(hull_near).area < 1e-9                  # the hull only grows


def test_near_zero_is_the_plain_hull_and_inf_frees_nothing():
    rig = {"seed": 3, "n": 4, "near": 0.0, "fov": 1.0}
    xy, bearings, scans, room = random_rig(rig)
    plain = visual_hull_of_scanlines(xy, bearings, scans, room)
    assert shapely.equals_exact(plain, visual_hull_of_scanlines(xy, bearings, scans, room, 0.0), 0.0)
    blind = free_wedges_from_scanlines(xy, bearings, scans, room, [np.inf, 0.5, 0.5, 0.5])
    assert blind[0].is_empty and not blind[1].is_empty
    with pytest.raises(ValueError, match="near"):
        visual_hull_of_scanlines(xy, bearings, scans, room, [0.1, 0.2])
    with pytest.raises(ValueError, match="near"):
        visual_hull_of_scanlines(xy, bearings, scans, room, -0.1)


# --- rendered people near cameras -------------------------------------------------------

@pytest.mark.render
def test_hulls_keep_people_who_stand_close_to_a_camera(lab, lab_renderer):
    """A person 0.5-0.8 m in front of a camera, partly or wholly below its image: with the
    cameras' blind radii that camera proves none of the person empty, from the true or
    from the pipeline's scanlines, and the true scanlines' hull keeps every person; without
    them, the camera clears part of such a person."""
    pipe = Pipeline(lab.cameras, load_params(), background=lab_renderer.background().rgb)
    xy, yaw, _ = lab.floor_poses()
    r, height, room = lab.people.radius, lab.people.height, lab.room.polygon
    near, gt_near = pipe.sight_range(height)[0], pipe.sight_range(height, truth=True)[0]
    rng = np.random.default_rng(5)
    cleared_without = []
    for camera, distance in ((8, 0.574), (0, 0.5), (5, 0.65), (12, 0.8)):
        # one person in front of `camera`, two elsewhere, all apart and inside the room
        front = xy[camera] + distance * np.array([np.cos(yaw[camera]), np.sin(yaw[camera])])
        people = [front]
        while len(people) < 3:
            p = rng.uniform([0.5, 0.5], [6.2, 5.3])
            if all(np.hypot(*(p - q)) > 2 * r + 0.1 for q in people):
                people.append(p)
        people = np.array(people)
        assert room.buffer(-r + 1e-6).contains(Point(front))
        frame = lab_renderer.render(people, rng=rng)
        pipe.reset()
        scans, gt = pipe.process_with_truth(frame.rgb, frame.labels)
        discs = [Point(p).buffer(r, quad_segs=64) for p in people]
        for s, rad in ((gt, gt_near), (scans, near)):
            free = free_wedges_from_scanlines(xy, pipe.bearings, s, room, rad)[camera]
            assert free.intersection(discs[0]).area < 1e-9
            plain = free_wedges_from_scanlines(xy, pipe.bearings, s, room)[camera]
            cleared_without.append(plain.intersection(discs[0]).area)
        hull = visual_hull_of_scanlines(xy, pipe.bearings, gt, room, gt_near)
        assert max(d.difference(hull).area for d in discs) < 5e-5           # column quantisation
    assert max(cleared_without) > 5e-3


# --- the far field ------------------------------------------------------------------------

def projected_sight_distance(camera: Camera, top: float, step: float = 2e-3) -> float:
    """Smallest, over the band's columns, largest floor distance at which some point of the
    segment from the floor to ``top`` projects (cv2.projectPoints, no distortion) inside
    the raw image's rows."""
    from pipeline.rectify import column_bearings

    Ks, _, width = level_cameras([camera])
    bearings = column_bearings(camera, Ks[0], width)[::16]
    d = np.arange(step, 15.0, step)
    z = np.linspace(0.0, top, 60)
    c = camera.center_world
    pts = np.stack(np.broadcast_arrays(c[0] + d[None, :, None] * np.cos(bearings)[:, None, None],
                                       c[1] + d[None, :, None] * np.sin(bearings)[:, None, None],
                                       z[None, None, :]), -1).reshape(-1, 1, 3)
    rvec = cv2.Rodrigues(camera.R)[0]
    v = cv2.projectPoints(pts, rvec, camera.t, camera.K, camera.dist)[0][..., 1].reshape(bearings.size, d.size, z.size)
    seen = ((v >= -0.5) & (v <= camera.height - 0.5)).any(axis=2)        # (bearings, d)
    return float(min(d[np.flatnonzero(row)].max() for row in seen))


@pytest.mark.parametrize("height_m, pitch_deg", [(2.2, 40.0), (3.0, 55.0)])
def test_sight_radius_is_where_the_object_leaves_the_top_of_the_image(height_m, pitch_deg):
    camera = pinhole(height_m, pitch_deg)
    expected = projected_sight_distance(camera, 1.75)
    near, far = sight_range([camera], 1.75, margin=0.0)
    assert far[0] == pytest.approx(expected, abs=5e-3)       # the 2 mm grid, every 16th column
    assert near[0] < far[0]


def test_a_low_camera_pitched_up_sees_people_only_up_to_a_distance():
    """1 m high, 40 degrees up: its lower edge is above the horizon, so a 1.75 m person's top
    drops below the image with distance (blind radius 0, sight radius ~2 m)."""
    camera = pinhole(1.0, -40.0)
    near, far = sight_range([camera], 1.75, margin=0.0)
    assert near[0] == 0.0 and 1.0 < far[0] < 3.0
    assert far[0] == pytest.approx(projected_sight_distance(camera, 1.75), abs=4e-3)


def test_a_camera_with_its_upper_edge_on_the_horizon_sees_a_foot_out_to_h_f_over_margin():
    """A pinhole 1 m high pitched down by its upper half field of view: its upper edge lies
    on the horizon (y = 0 in every column), so a taller object's foot shows ``margin`` rows
    below it out to d = H s / m (m = margin / f_v, s = sqrt(1 + x^2), least at the centre
    column); its top, above the image, limits nothing, and there is no blind radius."""
    level = pinhole(1.0, 0.0)
    pitch = np.degrees(np.arctan((level.K[1, 2] + 0.5) / level.K[1, 1]))
    camera = pinhole(1.0, pitch)
    Ks, _, width = level_cameras([camera])
    s = np.sqrt(1.0 + ((np.arange(width) - Ks[0, 0, 2]) / Ks[0, 0, 0]) ** 2)
    for margin in (1.0, 10.0):
        near, far = sight_range([camera], 1.75, margin)
        assert near[0] == 0.0
        assert far[0] == pytest.approx(1.0 * s.min() * Ks[0, 1, 1] / margin, rel=1e-9)


def test_the_documented_sight_radii_of_the_steep_lab():
    """docs/pipeline.md and docs/dataset.md quote them (lab intrinsics, principal point included)."""
    from scene import Scene
    from scene.config import read_scene_text, scene_path

    steep = Scene.from_text(read_scene_text(scene_path("lab")).replace("pitch_deg: 15.0", "pitch_deg: 40.0"), "steep")
    pipe = Pipeline(steep.cameras, load_params())
    np.testing.assert_allclose(pipe.sight_range(1.75, truth=True)[1], 5.72, atol=0.005)
    np.testing.assert_allclose(pipe.sight_range(1.75)[1], 4.52, atol=0.005)


@pytest.mark.render
def test_hulls_keep_people_beyond_what_steep_cameras_see(lab):
    """The lab with every camera pitched 40 degrees down: people farther than ~5.7 m from a
    camera are above its image. Between the blind and sight radii the true scanlines' hull
    keeps everyone; with the blind radius alone it loses whole people."""
    from render import Renderer
    from scene import Scene
    from scene.config import read_scene_text, scene_path

    steep = Scene.from_text(read_scene_text(scene_path("lab")).replace("pitch_deg: 15.0", "pitch_deg: 40.0"), "steep")
    people = np.array([[1.0, 1.0], [5.5, 4.5], [3.4, 2.9]])
    with Renderer(steep) as renderer:
        pipe = Pipeline(steep.cameras, load_params(), background=renderer.background().rgb)
        frame = renderer.render(people, rng=np.random.default_rng(0))
    _, gt = pipe.ground_truth(frame.labels)
    xy, _, _ = steep.floor_poses()
    near, far = pipe.sight_range(steep.people.height, truth=True)
    assert np.all(far < 6.0) and np.all(near < 0.5)
    discs = [Point(p).buffer(steep.people.radius, quad_segs=64) for p in people]
    room = steep.room.polygon
    hull = visual_hull_of_scanlines(xy, pipe.bearings, gt, room, near, far)
    assert max(d.difference(hull).area for d in discs) < 5e-5
    near_only = visual_hull_of_scanlines(xy, pipe.bearings, gt, room, near)
    assert max(d.difference(near_only).area for d in discs) > 0.1


@pytest.mark.render
def test_hulls_keep_people_too_thin_for_far_cameras_to_see(lab):
    """People 6 cm across: beyond ~4.5 m they are narrower than the opening's kernel in the
    raw image, so the pipeline sends them as empty. With the sight radii of their width,
    every person keeps all but the edge columns' sliver; by height alone (18 m) a far camera
    carves a whole person out."""
    from render import Renderer
    from scene import Scene
    from scene.config import read_scene_text, scene_path

    thin = Scene.from_text(read_scene_text(scene_path("lab")).replace("radius: 0.25 ", "radius: 0.03 "), "thin")
    people = np.array([[3.35, 2.9], [1.0, 4.8], [5.9, 0.8]])
    with Renderer(thin) as renderer:
        pipe = Pipeline(thin.cameras, load_params(), background=renderer.background().rgb)
        scans = pipe.process(renderer.render(people, rng=np.random.default_rng(0)).rgb)
    xy, _, _ = thin.floor_poses()
    discs = [Point(p).buffer(thin.people.radius, quad_segs=64) for p in people]
    lost = {}
    for width in (None, 2 * thin.people.radius):
        near, far = pipe.sight_range(thin.people.height, object_width=width)
        hull = visual_hull_of_scanlines(xy, pipe.bearings, scans, thin.room.polygon, near, far)
        lost[width] = [d.difference(hull).area / d.area for d in discs]
    assert max(lost[None]) > 0.9
    assert max(lost[2 * thin.people.radius]) < 0.04
    near, far = pipe.sight_range(thin.people.height, object_width=0.06)
    assert np.allclose(far, far[0]) and 4.0 < far[0] < 5.0


def farthest(geom, centre) -> float:
    """Largest distance (metres) from ``centre`` to a vertex of ``geom``: a polygon lies in a
    disc about ``centre`` if and only if its vertices do (the disc is convex)."""
    return float(np.max(np.hypot(*(shapely.get_coordinates(geom) - centre).T), initial=0.0))


def test_near_and_far_hold_per_camera_beside_cameras_without_them():
    """A camera with no blind radius (near 0) or no sight limit (far inf) beside others does
    not lift theirs: the others' wedges still avoid their blind discs and end at their far."""
    xy, bearings, scans, room = random_rig({"seed": 5, "n": 4, "near": 0.0, "fov": 1.5})
    near, far = np.array([0.0, 0.7, 0.0, 0.7]), np.array([np.inf, np.inf, 2.0, 2.0])
    plain = free_wedges_from_scanlines(xy, bearings, scans, room)
    cut = free_wedges_from_scanlines(xy, bearings, scans, room, near, far)
    assert cut[0].symmetric_difference(plain[0]).area < 1e-12
    for c in (1, 3):
        assert not cut[c].is_empty
        assert cut[c].intersection(Point(xy[c]).buffer(near[c], quad_segs=64)).area < 1e-12
    for c in (2, 3):
        assert not cut[c].is_empty
        assert farthest(cut[c], xy[c]) <= far[c] * (1 + 1e-12)


@pytest.mark.parametrize("far", [0.3, 0.8, 2.0])
def test_a_sight_radius_alone_frees_the_field_of_view_up_to_it(far):
    """far without near: an empty scanline proves empty the sector of radius far (its
    polygon, chords inside the circle), however short the sight radius."""
    from shapely.geometry import Polygon

    bearings = np.linspace(0.5, -0.5, 64)[None]
    hull = visual_hull_of_scanlines([[0.0, 0.0]], bearings, np.zeros((1, 64), bool),
                                    box(-3, -3, 3, 3), far=far)
    empty = box(-3, -3, 3, 3).difference(hull)
    half = 0.5 * (1.0 + 1.0 / 63)                     # column edges: half a step past the ends
    arc = np.linspace(-half, half, 9)
    sector = far * np.c_[np.cos(arc), np.sin(arc)]
    inscribed = Polygon([(0, 0), *sector])            # the sector's polygon, chords inside
    assert farthest(empty, (0.0, 0.0)) <= far + 1e-12     # the overlays snap to 6e-13 m
    assert inscribed.difference(empty).area < 1e-12 * far**2


@pytest.mark.parametrize("pitch_deg", [30.0, 45.0, 60.0])
def test_a_column_shorter_than_the_margin_never_shows_the_object(pitch_deg):
    """A 64 x 40 pinhole pitched down: its image's upper and lower edges are level lines on the
    level camera, at tan(pitch - a_top) and tan(pitch + a_bottom) (a: the half pixel edges'
    angles off its axis), so every column is f_v (tan(pitch + a_bottom) - tan(pitch - a_top))
    rows tall. An object cannot show more rows than that: with a margin 5% above it the camera
    never sees it (near = far = inf); 5% below, it does at some distance."""
    camera = Camera.from_pose(1, [1.0, 2.0, 2.2], 0.3, np.radians(pitch_deg), 64, 40, np.radians(49.0), np.zeros(5))
    f_v = level_cameras([camera])[0][0, 1, 1]
    a_top = np.arctan((camera.K[1, 2] + 0.5) / camera.K[1, 1])
    a_bottom = np.arctan((camera.height - 0.5 - camera.K[1, 2]) / camera.K[1, 1])
    p = np.radians(pitch_deg)
    column = f_v * (np.tan(p + a_bottom) - np.tan(p - a_top))
    near, far = sight_range([camera], 1.75, margin=0.95 * column)
    assert 0.0 < near[0] < far[0] < np.inf
    assert np.concatenate(sight_range([camera], 1.75, margin=1.05 * column)).tolist() == [np.inf, np.inf]


def test_a_camera_with_its_upper_edge_just_above_the_horizon_sees_a_foot_out_to_twice_h_f_over_margin():
    """A pinhole 1 m high pitched down by its upper half field of view less 1 degree: its upper
    edge is a level line at y = -tan(1 degree) on the level camera. With a margin of twice that
    (m = margin / f_v = 2 tan(1 degree)) a 5 m object's foot shows ``margin`` rows below the edge
    out to d = H s / (m / 2), least at the centre column (s = 1); its size (h s / m) and its top
    (above the camera) limit less, and it is seen from the camera's feet on."""
    level = pinhole(1.0, 0.0)
    a_top = np.degrees(np.arctan((level.K[1, 2] + 0.5) / level.K[1, 1]))
    camera = pinhole(1.0, a_top - 1.0)
    f_v = level_cameras([camera])[0][0, 1, 1]
    margin = 2 * np.tan(np.radians(1.0)) * f_v
    near, far = sight_range([camera], 5.0, margin)
    assert near[0] == 0.0
    assert far[0] == pytest.approx(1.0 / np.tan(np.radians(1.0)), rel=1e-6)


def test_the_size_limit_of_a_band_off_the_axis_is_at_its_column_nearest_the_axis():
    """A level pinhole whose principal point is 100 px left of its image: every column looks
    right of the axis, the nearest at x0 = (-0.5 - cx) / f. Level, it sees the horizon, so the
    foot of any object, and the top of one taller than the camera from its feet on; far is
    where the object is ``margin`` rows tall in that column: h sqrt(1 + x0^2) f_v / margin."""
    cam = Camera.from_pose(1, [1.0, 2.0, 2.2], 0.4, 0.0, 640, 480, np.radians(49.0), np.zeros(5),
                           principal=(-100.0, 239.5))
    x0 = (-0.5 - cam.K[0, 2]) / cam.K[0, 0]
    assert x0 > 0.1
    f_v = level_cameras([cam])[0][0, 1, 1]
    near, far = sight_range([cam], 3.0, margin=3.0)
    assert near[0] == 0.0
    assert far[0] == pytest.approx(3.0 * np.sqrt(1 + x0**2) * f_v / 3.0, rel=1e-9)


def test_given_pixels_per_radian_are_each_cameras_own_and_a_range_of_one_distance_is_none(lab):
    """far = w g_i / raw_columns with each camera's own g_i (given); where that is exactly the
    blind radius (g a power of two, so w = near / g is exact) the object shows at no distance
    but one: near = far = inf, as when it ends before the blind radius."""
    cams = lab.cameras[:2]
    far = sight_range(cams, 1.75, object_width=0.1, columns=0.01, pixels_per_radian=[300.0, 200.0])[1]
    np.testing.assert_allclose(far, [30.0, 20.0], rtol=1e-12)
    blind = sight_range(cams[:1], 1.75)[0][0]
    assert 0.5 < blind < 1.0
    got = sight_range(cams[:1], 1.75, object_width=blind / 1024.0, columns=0.5, pixels_per_radian=[1024.0])
    assert np.concatenate(got).tolist() == [np.inf, np.inf]
    got = sight_range(cams[:1], 1.75, object_width=blind / 1000.0, columns=0.5, pixels_per_radian=[1024.0])
    assert got[0][0] == blind and got[1][0] == pytest.approx(1.024 * blind, rel=1e-12)


def test_raw_pixels_per_radian_finds_the_widest_pixel_in_an_inner_row():
    """A level pincushion lens (k1 > 0) whose principal point lies on row 10: its raw pixels
    span most bearing at the principal point, neither on the first, the middle nor the last
    row. Against every pixel row, undistorted by OpenCV: within the rows' spacing."""
    cam = Camera.from_pose(1, [0.0, 0.0, 1.5], 0.0, 0.0, 64, 48, np.radians(50.0), [0.5, 0.0, 0.0, 0.0, 0.0],
                           principal=(31.5, 10.0))
    us = np.arange(cam.width + 1) - 0.5
    uv = np.stack(np.meshgrid(us, np.arange(cam.height, dtype=float)), -1).reshape(-1, 1, 2)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    x = cv2.undistortPoints(uv, cam.K, cam.dist, None, None, None, criteria)[:, 0, 0].reshape(cam.height, -1)
    steps = np.diff(np.arctan(x), axis=1)                     # level: the bearing is atan(x)
    assert np.unravel_index(steps.argmax(), steps.shape)[0] == 10
    assert raw_pixels_per_radian(cam) == pytest.approx(1.0 / steps.max(), rel=1e-4)


def test_margin_and_columns_are_pixels_of_the_width_given(lab):
    """Rectified to 2 W - 1 columns the level camera has twice the pixels per radian (the same
    band, columns 0 and width - 1 at its ends), so a margin and a run of columns twice as many
    there give the range of the default width's (to the finer grid's column nearer the axis,
    where the height limits far); the default's margin there gives another."""
    cams = lab.cameras[:2]
    width = 2 * cams[0].width - 1
    assert level_cameras(cams, width)[0][:, 0, 0] == pytest.approx(2 * level_cameras(cams)[0][:, 0, 0], rel=1e-12)
    for kw in (dict(), dict(object_width=0.03, raw_columns=0.01)):
        want = sight_range(cams, 1.75, 3.0, columns=1.0, **kw)
        got = sight_range(cams, 1.75, 6.0, width, columns=2.0, **kw)
        np.testing.assert_allclose(np.concatenate(got), np.concatenate(want), rtol=1e-6)
    assert np.all(sight_range(cams, 1.75, 3.0, width)[0] < want[0])
