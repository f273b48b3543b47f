"""Scene files: the built-in scenes load, and bad input gets one-line errors."""

import copy
import dataclasses
import re

import cv2
import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from scene import Camera, FloorCamera, Scene, load_scene, rotation_from_yaw_pitch, scene_path


@pytest.fixture(scope="module")
def lab_config():
    return yaml.safe_load(scene_path("lab").read_text())


def test_lab_has_sixteen_calibrated_cameras():
    lab = load_scene("lab")
    assert lab.is_calibrated and len(lab.cameras) == 16
    assert [c.number for c in lab.cameras] == list(range(1, 17))
    assert lab.room.area == pytest.approx(6.7056 * 5.7912)
    for cam in lab.cameras:
        assert (cam.width, cam.height) == (640, 480)
        assert np.degrees(cam.hfov) == pytest.approx(49.0, abs=0.1)
        assert cam.dist[0] != 0 and cam.dist[1] != 0
        assert 0 < np.degrees(cam.pitch) < 30
        assert lab.room.contains_point(cam.xy)


def test_lab_cameras_look_inward_and_odd_cameras_spread_evenly():
    lab = load_scene("lab")
    centre = np.array([6.7056, 5.7912]) / 2
    for cam in lab.cameras:
        to_centre = centre - cam.xy
        bearing = np.arctan2(to_centre[1], to_centre[0])
        assert abs(np.angle(np.exp(1j * (bearing - cam.yaw)))) < np.radians(24.5)
    odd = np.array([lab.cameras[i].xy for i in range(0, 16, 2)])
    walls = {tuple(np.round(p, 1) == 0.1) for p in odd}
    assert len(odd) == 8 and len(walls) >= 2
    assert lab.uniform_indices()[8] == tuple(range(0, 16, 2))
    assert lab.uniform_sets[6] == (1, 3, 7, 11, 13, 15)
    assert lab.uniform_sets[10] == (1, 3, 5, 7, 8, 9, 11, 13, 15, 16)


def test_circle_scene_is_the_papers_simulation():
    circle = load_scene("circle")
    xy, yaw, fov = circle.floor_poses()
    assert xy.shape == (16, 2) and np.allclose(np.linalg.norm(xy, axis=1), 1.0)
    assert np.allclose(fov, np.pi)
    # every camera looks at the centre
    assert np.allclose(np.cos(yaw) * -xy[:, 0] + np.sin(yaw) * -xy[:, 1], 1.0)
    assert circle.people.radius == 0.1 and circle.people.count == 5


def test_calibration_projects_like_opencv():
    cam = load_scene("lab").cameras[0]
    point = cam.center_world + 3.0 * np.array([np.cos(cam.yaw), np.sin(cam.yaw), 0.0])
    rvec, _ = cv2.Rodrigues(cam.R)
    uv, _ = cv2.projectPoints(point[None], rvec, cam.t, cam.K, cam.dist)
    u, v = uv[0, 0]
    # a point straight ahead at eye level is on the centre column, above the centre row
    assert abs(u - cam.K[0, 2]) < 1.0 and v < cam.K[1, 2]


def test_a_camera_from_a_pose_projects_as_the_pinhole_formula():
    """Level, looking along +x, 90 degrees across 640 x 480: f = 320 px, the principal point
    at the image's centre (319.5, 239.5), square pixels, no skew."""
    cam = Camera.from_pose(1, [1.0, 2.0, 1.5], 0.0, 0.0, 640, 480, np.radians(90), np.zeros(5))
    ahead = np.array([[3.0, 0.0, 0.0], [3.0, -1.2, 0.6], [2.0, 0.5, -1.0]])   # forward, right, up of the camera
    x, y, z = -ahead[:, 1], -ahead[:, 2], ahead[:, 0]                          # camera right, down, forward
    want = np.column_stack([320 * x / z + 319.5, 320 * y / z + 239.5])
    homogeneous = (cam.K @ (cam.R @ (cam.center_world + ahead).T + cam.t[:, None])).T   # the renderer's K @ X
    np.testing.assert_allclose(homogeneous[:, :2] / homogeneous[:, 2:], want, atol=1e-9)
    uv = cv2.projectPoints(cam.center_world + ahead, cv2.Rodrigues(cam.R)[0], cam.t, cam.K, cam.dist)[0][:, 0]
    np.testing.assert_allclose(uv, want, atol=1e-9)


def test_rotation_is_orthonormal():
    R = rotation_from_yaw_pitch(0.7, 0.3)
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)


@settings(max_examples=200, deadline=None)
@given(st.floats(-4 * np.pi, 4 * np.pi), st.floats(-np.radians(89.9), np.radians(89.9)),
       st.tuples(*[st.floats(-10.0, 10.0)] * 3))
def test_rotation_from_yaw_pitch_round_trips_through_a_camera(yaw, pitch, position):
    """R is a rotation (orthonormal, det +1) whose rows are right, down and forward: forward
    has the stated yaw and pitch, right is level, down points below the horizon; a camera
    built from it gives back yaw, pitch and centre, and they rebuild the same R."""
    R = rotation_from_yaw_pitch(yaw, pitch)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    forward = np.array([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), -np.sin(pitch)])
    np.testing.assert_allclose(R[2], forward, atol=1e-12)
    assert abs(R[0, 2]) < 1e-12 and R[1, 2] < 0                     # no roll; down is down
    cam = Camera.from_pose(1, position, yaw, pitch, 64, 48, 1.0, np.zeros(5))
    assert abs(np.angle(np.exp(1j * (cam.yaw - yaw)))) < 1e-9
    assert cam.pitch == pytest.approx(pitch, abs=1e-9)
    np.testing.assert_allclose(cam.center_world, position, atol=1e-9)
    np.testing.assert_allclose(rotation_from_yaw_pitch(cam.yaw, cam.pitch), R, atol=1e-9)


@settings(max_examples=100, deadline=None)
@given(st.integers(2, 4000), st.integers(2, 4000), st.floats(0.01, np.radians(179.0)))
def test_hfov_of_a_camera_is_the_hfov_it_was_built_with(width, height, hfov):
    cam = Camera.from_pose(1, [0.0, 0.0, 1.0], 0.0, 0.0, width, height, hfov, np.zeros(5))
    assert cam.hfov == pytest.approx(hfov, rel=1e-12)


def test_frozen_and_read_only():
    cam = load_scene("lab").cameras[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        cam.number = 3
    with pytest.raises(ValueError):
        cam.K[0, 0] = 1.0
    for derived in (cam.center_world, cam.xy):
        with pytest.raises(ValueError, match="read-only"):
            derived[0] = 1.0
    floor = FloorCamera(1, [0.5, 0.5], 0.0, 1.0)
    with pytest.raises(ValueError, match="read-only"):
        floor.xy[0] = 1.0


def _edited(text: str, old: str, new: str) -> str:
    """A scene file's ``text`` with ``old``, which it must hold once, replaced by ``new``."""
    assert text.count(old) == 1, old
    return text.replace(old, new)


def _set(config, path, value):
    """A copy of ``config`` with the key or list index at ``path`` set to ``value``."""
    c = copy.deepcopy(config)
    node = c
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return c


@pytest.mark.parametrize("path, value, match", [
    (("bogus",), 1, "scene: unknown key 'bogus'"),
    (("room", "colour"), "red", "room: unknown key 'colour'"),
    (("room", "width"), -1, r"room.width: expected a finite number > 0"),
    (("room", "height"), 0, r"room.height: expected a finite number > 0"),
    (("people", "radius"), 0, r"people.radius: expected a finite number >= 0.001 m, got 0"),
    (("people", "count"), -2, r"people.count: expected an integer >= 0"),
    (("cameras", "intrinsics", "hfov_deg"), 0, r"hfov_deg: expected a field of view in \[1, 179\]"),
    (("cameras", "intrinsics", "hfov_deg"), 200, r"hfov_deg: expected a field of view"),
    (("cameras", "intrinsics", "resolution"), [0, 480], r"resolution: expected an integer >= 2"),
    (("cameras", "intrinsics", "resolution"), [1, 1], r"resolution: expected an integer >= 2, got 1"),
    (("cameras", "intrinsics", "resolution"), [100000, 100000],
     r"resolution: expected at most 16380 pixels a side, got 100000 x 100000"),
    # strings and booleans are not numbers, in arrays either
    (("cameras", "intrinsics", "hfov_deg"), "49", r"hfov_deg: expected a field of view in \[1, 179\] degrees, got '49'"),
    (("cameras", "intrinsics", "distortion"), [True, 0, 0, 0, 0], r"distortion: expected numbers of shape \(5,\), got True"),
    (("people", "positions"), [["5", 4], [1, 1], [3, 3]], r"people.positions: expected numbers .*, got '5'"),
    (("people", "colours"), [[True, 2, 3]] * 3, r"people.colours: expected numbers of shape \(n, 3\), got True"),
    (("cameras", "intrinsics", "resolution"), [640], r"resolution: expected \[width, height\]"),
    (("cameras", "intrinsics", "distortion"), [0.1, 0.2], r"distortion: expected shape \(5,\)"),
    (("render", "backend"), "vulkan", "render.backend: unknown value 'vulkan'; expected one of egl, osmesa"),
    (("uniform_sets",), {6: [1, 2, 3]}, r"uniform_sets\[6\]: expected 6 distinct camera numbers"),
    (("uniform_sets",), {6: 3}, r"uniform_sets\[6\]: expected a list of 6 camera numbers, got 3"),
    (("uniform_sets",), {2: [1, "a"]}, r"uniform_sets\[2\]: expected an integer, got 'a'"),
    (("uniform_sets",), {2: [1, 1.7]}, r"uniform_sets\[2\]: expected an integer, got 1.7"),
    (("cameras", "poses", 0, "yaw_deg"), None, r"cameras.poses\[0\].yaw_deg: expected a number, got None"),
    (("cameras", "poses", 0, "yaw_deg"), "abc", r"cameras.poses\[0\].yaw_deg: expected a number, got 'abc'"),
    (("cameras", "poses", 0, "yaw_deg"), [1, 2], r"cameras.poses\[0\].yaw_deg: expected a number"),
    (("cameras", "poses", 2, "pitch_deg"), float("nan"), r"cameras.poses\[2\].pitch_deg: expected a finite number"),
    (("cameras", "poses", 2, "pitch_deg"), 120, r"cameras.poses\[2\].pitch_deg: expected a pitch in \(-90, 90\)"),
    (("people", "radius"), True, r"people.radius: expected a number, got True"),
    (("people", "radius"), "0.25", r"people.radius: expected a number, got '0.25'"),
    (("people", "colours"), [[0.5, 0, 0]] * 3, r"people.colours: expected at least 3 RGB triples of integers"),
    (("people", "count"), 200, r"people.count: 200 people of radius 0.25 m do not fit in the room; expected at most 49"),
    (("name",), None, r"name: expected a non-empty string, got None"),
    (("name",), "", r"name: expected a non-empty string, got ''"),
    (("name",), 5, r"name: expected a non-empty string, got 5"),
    (("room", "shape"), "oval", r"room.shape: unknown value 'oval'; expected one of rectangle, circle"),
    (("room",), {"width": 6.0, "depth": 5.0, "height": 2.7}, r"room: missing key 'shape'"),
    (("room",), {"shape": "circle", "radius": 3.0, "width": 6.0}, r"room: unknown key 'width'; expected keys among shape, radius, height$"),
    (("room", "radius"), 1.0, r"room: unknown key 'radius'; expected keys among shape, width, depth, height$"),
    (("cameras", "lens"), 1, r"cameras: unknown key 'lens'; expected keys among intrinsics, poses, ring$"),
    (("cameras", "intrinsics", "resolution"), "64", r"resolution: expected \[width, height\], got '64'"),
    (("cameras", "intrinsics", "resolution"), [640, 480, 3], r"resolution: expected \[width, height\], got \[640, 480, 3\]"),
    (("cameras", "intrinsics", "resolution"), [640, 1], r"resolution: expected an integer >= 2, got 1"),
    (("cameras", "poses"), [], r"cameras.poses: expected a non-empty list of camera poses"),
    (("cameras", "poses"), {"number": 1}, r"cameras.poses: expected a non-empty list of camera poses"),
    (("cameras", "poses", 0, "roll_deg"), 0, r"cameras.poses\[0\]: unknown key 'roll_deg'"),
    (("cameras", "poses", 0, "number"), 0, r"cameras.poses\[0\].number: expected an integer >= 1, got 0"),
    (("cameras", "poses", 1, "number"), 1, r"cameras.poses: expected camera numbers 1..16 once each, got \[1, 1, 3, 4, "),
    (("cameras", "poses", 0, "position"), [0.781, 0.05, 0.0], r"poses\[0\].position: camera 1 at .* is outside the room"),
    (("cameras", "poses", 0, "position"), [0.781, 0.05, 2.7], r"poses\[0\].position: camera 1 at .* is outside the room"),
    (("cameras", "poses", 0, "pitch_deg"), 90, r"pitch_deg: expected a pitch in \(-90, 90\) degrees \(down is positive\), got 90"),
    (("cameras", "poses", 0, "pitch_deg"), -90, r"pitch_deg: expected a pitch in \(-90, 90\) degrees .*, got -90"),
    (("people", "colour"), "red", r"people: unknown key 'colour'"),
    (("people", "speed"), 0, r"people.speed: expected a finite number > 0 and at most 100 m/s, got 0"),
    (("people", "radius"), float("inf"), r"people.radius: expected a finite number >= 0.001 m, got inf"),
    (("people", "count"), True, r"people.count: expected an integer, got True"),
    (("people", "colours"), [[-1, 0, 0]] * 3, r"people.colours: expected at least 3 RGB triples of integers in 0..255"),
    (("people", "colours"), [[0, 256, 0]] * 3, r"people.colours: expected at least 3 RGB triples of integers in 0..255"),
    (("people", "colours"), [[0, 0, 0]] * 2, r"people.colours: expected at least 3 RGB triples of integers in 0..255"),
    (("people", "positions"), [[2, 2], [2.4, 2.0], [4, 4]], r"people.positions\[1\]: person overlaps person 0"),
    (("render", "fps"), 3, r"render: unknown key 'fps'"),
    (("uniform_sets",), [1, 2], r"uniform_sets: expected a mapping k -> list of camera numbers"),
    (("uniform_sets",), {0: []}, r"uniform_sets key: expected an integer >= 1, got 0"),
    (("uniform_sets",), {2: [1, 2, 2]}, r"uniform_sets\[2\]: expected 2 distinct camera numbers in 1..16"),
    (("uniform_sets",), {2: [1, 1]}, r"uniform_sets\[2\]: expected 2 distinct camera numbers in 1..16"),
    (("uniform_sets",), {2: [1, 17]}, r"uniform_sets\[2\]: expected 2 distinct camera numbers in 1..16"),
    (("uniform_sets",), {2: [0, 1]}, r"uniform_sets\[2\]: expected 2 distinct camera numbers in 1..16"),
])
def test_bad_scene_fields(lab_config, path, value, match):
    with pytest.raises(ValueError, match=match):
        Scene.from_config(_set(lab_config, path, value))


def test_camera_outside_the_room(lab_config):
    poses = copy.deepcopy(lab_config["cameras"]["poses"])
    poses[3]["position"] = [9.0, 1.0, 2.2]
    with pytest.raises(ValueError, match=r"poses\[3\].position: camera 4 .* is outside the room"):
        Scene.from_config(_set(lab_config, ("cameras", "poses"), poses))
    poses[3]["position"] = [3.0, 1.0, 3.5]
    with pytest.raises(ValueError, match="outside the room"):
        Scene.from_config(_set(lab_config, ("cameras", "poses"), poses))


def test_people_overlapping_wall_or_each_other(lab_config):
    with pytest.raises(ValueError, match=r"people.positions\[1\]: person at .* overlaps a wall"):
        Scene.from_config(_set(lab_config, ("people", "positions"), [[2, 2], [0.1, 3], [4, 4]]))
    with pytest.raises(ValueError, match=r"people.positions\[2\]: person overlaps person 0"):
        Scene.from_config(_set(lab_config, ("people", "positions"), [[2, 2], [4, 4], [2.3, 2.1]]))


@pytest.mark.parametrize("text, match", [
    ("", "empty scene file"),
    ("- 1\n- 2\n", "expected a mapping at the top level, got list"),
    ("room: [1, 2\n", "not valid YAML"),
])
def test_bad_documents(tmp_path, text, match):
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        Scene.from_yaml(path)


def test_exponents_without_a_dot_are_numbers(tmp_path):
    """``25e-2`` and ``175E-2`` are floats in YAML 1.2 and every language; YAML 1.1 read them as strings."""
    text = scene_path("lab").read_text()
    assert "radius: 0.25 " in text and "height: 1.75 " in text
    path = tmp_path / "s.yaml"
    path.write_text(text.replace("radius: 0.25 ", "radius: 25e-2 ").replace("height: 1.75 ", "height: 175E-2 "))
    people = Scene.from_yaml(path).people
    assert (people.radius, people.height) == (0.25, 1.75)


def test_missing_file_and_camera_validation(tmp_path):
    with pytest.raises(FileNotFoundError, match="scene file: no such file"):
        load_scene(tmp_path / "nope.yaml")
    with pytest.raises(ValueError, match="camera.R: expected a rotation matrix"):
        Camera(1, np.eye(3), np.zeros(5), 2 * np.eye(3), np.zeros(3), 640, 480)
    good = np.array([[500.0, 0.0, 319.5], [0.0, 500.0, 239.5], [0.0, 0.0, 1.0]])
    for bad in ({(0, 0): 0.0}, {(1, 1): 0.0}, {(1, 0): 0.1}, {(2, 2): 2.0}):    # no focal length, skew below, scaled
        K = good.copy()
        for at, value in bad.items():
            K[at] = value
        with pytest.raises(ValueError, match=r"camera.K: expected \[\[fx, s, cx\], \[0, fy, cy\], \[0, 0, 1\]\]"):
            Camera(1, K, np.zeros(5), np.eye(3), np.zeros(3), 640, 480)
    with pytest.raises(ValueError, match="camera.resolution"):
        Camera(1, good, np.zeros(5), np.eye(3), np.zeros(3), 0, 480)
    assert Camera(1, good, np.zeros(5), np.eye(3), np.zeros(3), 1, 1).width == 1


@pytest.mark.parametrize("kind", ["folder", "device"])
def test_inputs_that_are_not_files_are_named_as_such(tmp_path, kind):
    """A folder or /dev/null given as a scene, params or calibration file is not "missing"."""
    from pipeline.io import load_calibration
    from pipeline.params import PipelineParams

    path, words = (tmp_path, "is a folder") if kind == "folder" else ("/dev/null", "is not a regular file")
    for what, load in [("scene file", load_scene), ("params", PipelineParams.from_yaml),
                       ("calibration", load_calibration)]:
        with pytest.raises(ValueError, match=f"^{what}: .* {words}"):
            load(path)


def test_cameras_are_in_number_order_whatever_the_files_order(lab_config):
    # the loop, the uniform sets and the top view index cameras by number - 1
    poses = copy.deepcopy(lab_config["cameras"]["poses"])
    poses[0], poses[8] = poses[8], poses[0]
    swapped = Scene.from_config(_set(lab_config, ("cameras", "poses"), poses))
    lab = Scene.from_config(lab_config)
    assert [c.number for c in swapped.cameras] == list(range(1, 17))
    for got, want in zip(swapped.floor_poses(), lab.floor_poses()):
        np.testing.assert_array_equal(got, want)
    for a, b in zip(swapped.cameras, lab.cameras):
        np.testing.assert_array_equal(a.R, b.R)
        np.testing.assert_array_equal(a.t, b.t)


def test_a_ring_with_poses_is_refused():
    config = yaml.safe_load(scene_path("circle").read_text())
    config["cameras"]["poses"] = []
    with pytest.raises(ValueError, match="cameras: expected either ring or intrinsics and poses, not both"):
        Scene.from_config(config)


def test_no_people_at_given_positions(lab_config):
    config = _set(_set(lab_config, ("people", "count"), 0), ("people", "positions"), [])
    scene = Scene.from_config(config)
    assert scene.people.count == 0 and scene.people.positions.shape == (0, 2)


def test_arrays_of_objects_are_judged_by_their_elements():
    from scene.checks import check_array

    assert check_array("xy", np.array([1.0, 2.0], dtype=object), (None,)).tolist() == [1.0, 2.0]
    with pytest.raises(ValueError, match=r"xy: expected numbers of shape \(n,\), got 'a'"):
        check_array("xy", np.array([0, "a"], dtype=object), (None,))


# ---- found by reading scene files as a user writes them
LAB = scene_path("lab").read_text()


def test_duplicate_keys_are_refused_not_overridden():
    with pytest.raises(ValueError, match=r"duplicate key 'frame_rate' at line \d+"):
        Scene.from_text(LAB + "\nframe_rate: 30\n", "s.yaml")
    with pytest.raises(ValueError, match=r"duplicate key 'count' at line 43"):
        Scene.from_text(LAB.replace("  count: 3\n", "  count: 3\n  count: 20\n"), "s.yaml")


def test_an_integer_too_long_for_python_to_read_is_a_yaml_error_with_its_place():
    """Python reads at most 4300 digits: its own ValueError named neither the file nor the line.
    Integers of other forms read as before."""
    with pytest.raises(ValueError) as err:
        Scene.from_text(LAB.replace("count: 3", "count: " + "1" * 5000), "s.yaml")
    assert str(err.value) == "s.yaml: not valid YAML (an integer of 5000 characters is too long to read at line 42, column 10)"
    from scene import yamlio

    assert yamlio.load("a: 12\nb: 0x1f\nc: 1_000\nd: -7\ne: " + "9" * 4300) == {
        "a": 12, "b": 31, "c": 1000, "d": -7, "e": int("9" * 4300)}


def test_merge_keys_may_still_be_overridden():
    text = LAB.replace("    - {number: 1,", "    - &c1 {number: 1,").replace(
        "    - {number: 2, position: [2.343, 0.05, 2.2], yaw_deg: 70.5, pitch_deg: 15.0}",
        "    - {<<: *c1, number: 2, position: [2.343, 0.05, 2.2], yaw_deg: 70.5}")
    assert len(Scene.from_text(text, "s.yaml").cameras) == 16


def test_yaml_syntax_error_says_what_and_where():
    with pytest.raises(ValueError, match=r"not valid YAML \(did not find expected ',' or '\]' at line 16, column \d+\)"):
        Scene.from_text(LAB.replace("[640, 480]", "[640, 480"), "s.yaml")


def test_a_control_character_is_one_line_naming_it_and_where_it_is():
    """The reader's errors have no ``problem``: their first line says what is wrong (the
    next one, 'in "<unicode string>", position N', names no file); where it is comes from
    the character offset (it said nothing of where)."""
    with pytest.raises(ValueError) as err:
        Scene.from_text(LAB.replace("name: lab", "name: l\x07ab"), "s.yaml")
    assert str(err.value) == ("s.yaml: not valid YAML (unacceptable character #x0007: control characters are not "
                              "allowed at line 6, column 8)")
    with pytest.raises(ValueError) as err:                               # the first character of the text
        Scene.from_text("\x07" + LAB, "s.yaml")
    assert str(err.value).endswith("not allowed at line 1, column 1)")


def test_non_utf8_scene_file_is_one_line_naming_the_file(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_bytes(LAB.replace("name: lab", "name: caf\xe9").encode("latin-1"))
    with pytest.raises(ValueError, match=r"scene file: '.*s.yaml' is not UTF-8 text \(byte 0xe9"):
        load_scene(path)


def test_huge_people_count_is_refused_without_allocating(monkeypatch):
    import scene.config

    def colours(count):                       # made for 10**9 people, it filled the memory
        raise AssertionError(f"default colours made for {count} people before the capacity check")

    monkeypatch.setattr(scene.config, "default_colours", colours)
    with pytest.raises(ValueError, match=r"people.count: 1000000000 people .* do not fit"):
        Scene.from_text(LAB.replace("  count: 3\n", "  count: 1000000000\n"), "s.yaml")


def test_person_wider_than_the_room_is_refused_on_loading():
    """Capacity by area alone let one disc wider than a corridor through (an error named ``radii`` came later)."""
    text = scene_path("circle").read_text().replace("  count: 5\n  radius: 0.1\n", "  count: 1\n  radius: 1.2\n")
    with pytest.raises(ValueError, match=r"people.radius: a person of radius 1.2 m does not fit anywhere"):
        Scene.from_text(text, "s.yaml")


@pytest.mark.parametrize("dist", [[0, 0, 2.0, 0, 0], [0, 0, 0, -3.0, 0], [0, 0, 1.0, 0, 0]])
def test_lens_that_cannot_be_undistorted_is_refused(dist):
    from pipeline.rectify import check_rectifiable

    cam = dataclasses.replace(load_scene("lab").cameras[0], dist=np.array(dist, float))
    with pytest.raises(ValueError, match="camera 1: its lens distortion .* folds over"):
        check_rectifiable([cam])


def test_params_yaml_syntax_error_says_what_and_where(tmp_path):
    from pipeline.params import PipelineParams

    path = tmp_path / "p.yaml"
    path.write_text("angle_deg: [1, 2\n")
    with pytest.raises(ValueError, match=r"params: .*p.yaml is not valid YAML \(.* at line 2, column 1\)"):
        PipelineParams.from_yaml(path)
    path.write_text("angle_deg: 3\n\x07\n")
    with pytest.raises(ValueError, match=r"p.yaml is not valid YAML \(unacceptable character #x0007: .* at line 2, "
                                         r"column 1\)$"):
        PipelineParams.from_yaml(path)


def test_people_taller_than_the_ceiling_are_refused():
    with pytest.raises(ValueError, match=r"people.height: 10 m is above the ceiling \(2.7 m, room.height\)"):
        Scene.from_text(LAB.replace("  height: 1.75 ", "  height: 10.0 "), "s.yaml")


# ---- extreme numbers: each was a traceback, a hang, or loaded without a word
CIRCLE = scene_path("circle").read_text()


@pytest.mark.parametrize("text, match", [
    # OverflowError (dt**2) in `run`'s tracker, not naming the key
    (LAB.replace("frame_rate: 7.5", "frame_rate: 1e-300"), r"frame_rate: expected a finite number >= 0.001 and at most 10000 Hz, got 1e-300"),
    # an ffmpeg error after the first frame of `run --video`
    (LAB.replace("frame_rate: 7.5", "frame_rate: 1e300"), r"frame_rate: expected .* at most 10000 Hz, got 1e\+300"),
    # "Maximum allowed size exceeded" from the floor's tiles, not naming the key
    (LAB.replace("width: 6.7056", "width: 1e300"), r"room.width: expected a finite number > 0 and at most 100 m, got 1e\+300"),
    (LAB.replace("height: 2.7", "height: 1e300"), r"room.height: expected .* at most 100 m"),
    # a 10**6 m room loaded, then `run` tiled its floor for hours
    (LAB.replace("depth: 5.7912", "depth: 1000000.0"), r"room.depth: expected .* at most 100 m, got 1000000.0"),
    # "camera.xy: expected finite numbers" (the cameras' positions overflowed)
    (CIRCLE.replace("radius: 1.0", "radius: 1e300"), r"room.radius: expected .* at most 100 m"),
    # ZeroDivisionError in the capacity check
    (LAB.replace("radius: 0.25 ", "radius: 1e-300 "), r"people.radius: expected a finite number >= 0.001 m, got 1e-300"),
    (LAB.replace("height: 1.75 ", "height: 1e-300 "), r"people.height: expected a finite number >= 0.001 m"),
    # OverflowError (accel_std**2) in `run`'s tracker
    (LAB.replace("speed: 1.0 ", "speed: 1e300 "), r"people.speed: expected a finite number > 0 and at most 100 m/s"),
    # a ring of 10**9 cameras filled the memory (20000 loaded, slowly enough to show the point)
    (CIRCLE.replace("count: 16", "count: 20000"), r"cameras.ring.count: expected at most 10000 cameras, got 20000"),
])
def test_extreme_numbers_are_refused_on_loading_naming_the_key(text, match):
    with pytest.raises(ValueError, match=match):
        Scene.from_text(text, "s.yaml")


def test_the_bounds_keep_the_built_in_scenes_and_their_edges():
    assert Scene.from_text(LAB.replace("frame_rate: 7.5", "frame_rate: 10000"), "s.yaml").frame_rate == 10000
    assert Scene.from_text(LAB.replace("frame_rate: 7.5", "frame_rate: 0.001"), "s.yaml").frame_rate == 0.001
    assert Scene.from_text(LAB.replace("width: 6.7056", "width: 100"), "s.yaml").room.polygon.bounds[2] == 100
    assert len(Scene.from_text(CIRCLE.replace("count: 16", "count: 10000"), "s.yaml").cameras) == 10000


@pytest.mark.parametrize("old, new, match", [
    # a hull covering the whole room (residual 64.9): the frames were noise
    ("noise_std: 2.0 ", "noise_std: 1e300 ", r"render.noise_std: expected a finite number >= 0 and at most 255"),
    ("gain_jitter: 0.02 ", "gain_jitter: 5 ", r"render.gain_jitter: expected a finite number >= 0 and at most 1"),
    # cos and sin of 1e300 degrees point nowhere in particular
    ("yaw_deg: 70.5", "yaw_deg: 1e300", r"yaw_deg: expected a finite number >= -360 and at most 360 degrees"),
])
def test_render_settings_and_yaw_beyond_any_meaning_are_refused(old, new, match):
    with pytest.raises(ValueError, match=match):
        Scene.from_text(_edited(LAB, old, new), "s.yaml")


# ---- what a scene file may leave out, and the edges of what it may say
SMALL = """\
room: {shape: rectangle, width: 4.0, depth: 3.0, height: 2.5}
cameras:
  intrinsics: {resolution: [64, 48], hfov_deg: 60, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 1, position: [0.1, 0.1, 2.0], yaw_deg: 45, pitch_deg: 10}
people: {count: 2, radius: 0.25}
"""


@pytest.mark.parametrize("extra", ["", "render:\nuniform_sets:\n"])
def test_a_scene_without_its_optional_keys_has_the_documented_defaults(extra):
    """docs/conventions.md: name from the file, 7.5 Hz, people 1.75 m tall walking 1 m/s in
    the palette's colours, the principal point at the image's centre, egl with 2 grey levels
    of noise and 2 % gain jitter; an empty ``render`` or ``uniform_sets`` is left out."""
    from scene import RenderSettings
    from scene.config import default_colours

    scene = Scene.from_text(SMALL + extra, "rooms/small.yaml")
    assert scene.name == "small" and scene.frame_rate == 7.5 and scene.uniform_sets == {}
    assert scene.render == RenderSettings() == RenderSettings("egl", 2.0, 0.02)
    people = scene.people
    assert (people.count, people.height, people.speed, people.positions) == (2, 1.75, 1.0, None)
    np.testing.assert_array_equal(people.colours, default_colours(2))
    np.testing.assert_array_equal(people.colours, [[200, 30, 30], [30, 70, 200]])
    assert (scene.cameras[0].K[0, 2], scene.cameras[0].K[1, 2]) == (31.5, 23.5)      # ((64 - 1) / 2, (48 - 1) / 2)
    bare = Scene("bare", scene.room, scene.cameras, scene.people)
    assert bare.frame_rate == 7.5 and bare.render == RenderSettings() and bare.uniform_sets == {}


def test_the_time_between_frames_is_one_over_the_frame_rate():
    assert Scene.from_text(SMALL + "frame_rate: 4\n").dt == 0.25


def test_a_scene_and_its_parts_are_frozen():
    scene = Scene.from_text(SMALL)
    for obj, field in ((scene, "frame_rate"), (scene.people, "count"), (scene.render, "backend")):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(obj, field, 1)


def test_the_principal_point_given_is_the_cameras():
    cam = load_scene("lab").cameras[4]
    assert (cam.K[0, 2], cam.K[1, 2]) == (322.4, 236.8)


def test_a_built_in_scene_is_named_by_one_of_its_names():
    with pytest.raises(ValueError, match=r"^scene: unknown value 'hall'; expected one of lab, circle$"):
        scene_path("hall")


@pytest.mark.parametrize("old, new, loaded, want", [
    ("position: [0.1, 0.1, 2.0]", "position: [0.1, 0.1, 0.01]",              # just above the floor
     lambda s: s.cameras[0].center_world.tolist(), [0.1, 0.1, 0.01]),
    ("position: [0.1, 0.1, 2.0]", "position: [0.0, 0.4, 2.0]",               # on a wall
     lambda s: s.cameras[0].center_world.tolist(), [0.0, 0.4, 2.0]),
    ("pitch_deg: 10", "pitch_deg: 89.5", lambda s: round(np.degrees(s.cameras[0].pitch), 9), 89.5),
    ("pitch_deg: 10", "pitch_deg: -89.5", lambda s: round(np.degrees(s.cameras[0].pitch), 9), -89.5),
    ("resolution: [64, 48]", "resolution: [2, 2]", lambda s: (s.cameras[0].width, s.cameras[0].height), (2, 2)),
    ("resolution: [64, 48]", "resolution: [16380, 2]", lambda s: (s.cameras[0].width, s.cameras[0].height), (16380, 2)),
    ("radius: 0.25}", "radius: 0.25, height: 2.5}", lambda s: s.people.height, 2.5),      # as tall as the ceiling
    ("radius: 0.25}", "radius: 0.25, colours: [[0, 0, 0], [255, 255, 255]]}",
     lambda s: np.asarray(s.people.colours).tolist(), [[0, 0, 0], [255, 255, 255]]),
    ("radius: 0.25}", "radius: 0.25, positions: [[1.0, 1.0], [1.5, 1.0]]}",          # touching, not overlapping
     lambda s: np.asarray(s.people.positions).tolist(), [[1.0, 1.0], [1.5, 1.0]]),
    ("radius: 0.25}", "radius: 0.25}\nuniform_sets: {1: [1]}", lambda s: s.uniform_sets, {1: (1,)}),
])
def test_values_at_the_edges_of_their_ranges_load(old, new, loaded, want):
    got = loaded(Scene.from_text(_edited(SMALL, old, new)))
    assert got == want or np.allclose(got, want, rtol=0, atol=1e-12), got


def test_two_people_overlapping_are_refused():
    text = SMALL.replace("radius: 0.25}", "radius: 0.25, positions: [[1.0, 1.0], [1.4, 1.0]]}")
    with pytest.raises(ValueError, match=r"people.positions\[1\]: person overlaps person 0"):
        Scene.from_text(text)


def test_more_colours_than_people_keep_the_first():
    text = SMALL.replace("radius: 0.25}", "radius: 0.25, colours: [[1, 2, 3], [4, 5, 6], [7, 8, 9]]}")
    np.testing.assert_array_equal(Scene.from_text(text).people.colours, [[1, 2, 3], [4, 5, 6]])


@pytest.mark.parametrize("positions, match", [
    ("[[1.0, 1.0]]", r"people.positions: expected shape \(0, 2\), got \(1, 2\)"),
    ("{}", r"people.positions: expected numbers of shape \(0, 2\)"),
])
def test_no_people_and_positions_for_someone_is_refused(positions, match):
    text = SMALL.replace("{count: 2, radius: 0.25}", f"{{count: 0, radius: 0.25, positions: {positions}}}")
    with pytest.raises(ValueError, match=match):
        Scene.from_text(text)


def test_a_crowd_covering_exactly_a_quarter_of_the_floor_may_be_dropped():
    """A person of radius 1 m covers pi m2, a quarter of a pi x 4 m floor: at most a quarter may be covered."""
    text = SMALL.replace("width: 4.0, depth: 3.0", f"width: {np.pi!r}, depth: 4.0")
    scene = Scene.from_text(text.replace("{count: 2, radius: 0.25}", "{count: 1, radius: 1.0}"))
    assert scene.people.count == 1
    with pytest.raises(ValueError, match=r"people.count: 2 people of radius 1 m do not fit in the room; expected at most 1"):
        Scene.from_text(text.replace("{count: 2, radius: 0.25}", "{count: 2, radius: 1.0}"))


def test_cameras_without_poses_or_a_ring_elsewhere_are_refused(lab_config):
    with pytest.raises(ValueError, match=r"^cameras: missing key 'poses'$"):
        Scene.from_config(_set(lab_config, ("cameras",), {"intrinsics": lab_config["cameras"]["intrinsics"]}))
    with pytest.raises(ValueError, match=r"^cameras.ring: a ring of cameras needs a circular room$"):
        Scene.from_config(_set(lab_config, ("cameras",), {"ring": {"count": 4, "fov_deg": 90}}))


@pytest.mark.parametrize("old, new, match", [
    ("count: 16, fov_deg: 180", "count: 16", r"^cameras.ring: missing key 'fov_deg'$"),
    ("count: 16", "count: 0", r"^cameras.ring.count: expected an integer >= 1, got 0$"),
    ("fov_deg: 180", "fov_deg: 400", r"^cameras.ring.fov_deg: expected a field of view in \[1e-06, 180\] degrees, got 400$"),
    ("ring: {count: 16", "ring: {count: 16, extra: 1", r"^cameras.ring: unknown key 'extra'"),
    ("ring:", "lens: 1\n  ring:", r"^cameras: unknown key 'lens'; expected keys among intrinsics, poses, ring$"),
])
def test_bad_rings_are_one_line(old, new, match):
    with pytest.raises(ValueError, match=match):
        Scene.from_text(_edited(CIRCLE, old, new))


def test_a_ring_is_the_studies_cameras_numbered_from_angle_zero():
    """The paper's ring (testbed.studies.core.circle_cameras): camera 1 at angle 0, the rest
    evenly counter-clockwise on the wall, each facing the centre."""
    from testbed.studies.core import circle_cameras

    for count, fov in ((16, 180), (1, 0.5), (5, 90)):
        scene = Scene.from_text(CIRCLE.replace("count: 16, fov_deg: 180", f"count: {count}, fov_deg: {fov}"))
        xy, yaw, fovs = scene.floor_poses()
        want_xy, want_yaw = circle_cameras(count)
        assert [c.number for c in scene.cameras] == list(range(1, count + 1))
        np.testing.assert_allclose(xy, want_xy, atol=1e-12)
        np.testing.assert_allclose(np.exp(1j * yaw), np.exp(1j * want_yaw), atol=1e-12)
        np.testing.assert_allclose(fovs, np.radians(fov), rtol=1e-12)


# ---- one step past each edge is refused, and what the loader keeps
@pytest.mark.parametrize("old, new, match", [
    ("resolution: [64, 48]", "resolution: [2, 16381]",
     r"^cameras.intrinsics.resolution: expected at most 16380 pixels a side, got 2 x 16381$"),
    ("resolution: [64, 48]", "resolution: [16381, 2]", r"^cameras.intrinsics.resolution: .*got 16381 x 2$"),
    ("hfov_deg: 60", "hfov_deg: true", r"^cameras.intrinsics.hfov_deg: expected a field of view in \[1, 179\] degrees, got True$"),
    ("hfov_deg: 60", "hfov_deg: 179.001", r"^cameras.intrinsics.hfov_deg: .*got 179.001$"),
    ("hfov_deg: 60", "hfov_deg: 0.999", r"^cameras.intrinsics.hfov_deg: .*got 0.999$"),
    # u in -64.5..127.5, v in -48.5..95.5 for a 64 x 48 image
    ("hfov_deg: 60,", "hfov_deg: 60, principal: [127.6, 23.5],", r"^cameras.intrinsics.principal: .*u in -64.5..127.5 and v in -48.5..95.5, got \[127.6, 23.5\]$"),
    ("hfov_deg: 60,", "hfov_deg: 60, principal: [-64.6, 23.5],", r"^cameras.intrinsics.principal: .*got \[-64.6, 23.5\]$"),
    ("hfov_deg: 60,", "hfov_deg: 60, principal: [31.5, 95.6],", r"^cameras.intrinsics.principal: .*got \[31.5, 95.6\]$"),
    ("hfov_deg: 60,", "hfov_deg: 60, principal: [31.5, -48.6],", r"^cameras.intrinsics.principal: .*got \[31.5, -48.6\]$"),
    ("radius: 0.25}", "radius: 0.25, height: 2.51}", r"^people.height: 2.51 m is above the ceiling \(2.5 m, room.height\)$"),
    ("people: {count: 2, radius: 0.25}\n", "", r"^scene: missing key 'people'$"),
    # a missing key or a value of another kind: one line naming the key, not a KeyError or TypeError
    ("height: 2.5}", "}", r"^room: missing key 'height'$"),
    ("  intrinsics: {resolution: [64, 48], hfov_deg: 60, distortion: [0, 0, 0, 0, 0]}\n", "",
     r"^cameras: missing key 'intrinsics'$"),
    ("hfov_deg: 60, ", "", r"^cameras.intrinsics: missing key 'hfov_deg'$"),
    (", distortion: [0, 0, 0, 0, 0]", "", r"^cameras.intrinsics: missing key 'distortion'$"),
    ("count: 2, radius: 0.25", "count: 2", r"^people: missing key 'radius'$"),
    ("hfov_deg: 60", "hfov_deg: null", r"^cameras.intrinsics.hfov_deg: expected a field of view in \[1, 179\] degrees, got None$"),
    ("hfov_deg: 60", "hfov_deg: [60]", r"^cameras.intrinsics.hfov_deg: expected a field of view .*, got \[60\]$"),
    ("radius: 0.25}", "radius: 0.25, positions: []}", r"^people.positions: expected shape \(2, 2\), got \(0,\)$"),
])
def test_one_step_past_an_edge_a_missing_key_or_another_kind_is_refused(old, new, match):
    with pytest.raises(ValueError, match=match):
        Scene.from_text(_edited(SMALL, old, new))


def test_edges_of_the_principal_point_and_field_of_view_of_a_small_image_load():
    for old, new, principal in [("hfov_deg: 60,", "hfov_deg: 60, principal: [127.5, 95.5],", (127.5, 95.5)),
                                ("hfov_deg: 60,", "hfov_deg: 60, principal: [-64.5, -48.5],", (-64.5, -48.5)),
                                ("hfov_deg: 60", "hfov_deg: 179", (31.5, 23.5)), ("hfov_deg: 60", "hfov_deg: 1", (31.5, 23.5))]:
        K = Scene.from_text(_edited(SMALL, old, new)).cameras[0].K
        assert (K[0, 2], K[1, 2]) == principal


@pytest.mark.parametrize("old, new, match", [
    ("count: 16", "count: 10001", r"^cameras.ring.count: expected at most 10000 cameras, got 10001$"),
    ("fov_deg: 180", "fov_deg: true", r"^cameras.ring.fov_deg: expected a field of view in \[1e-06, 180\] degrees, got True$"),
    ("fov_deg: 180", "fov_deg: 9e-7", r"^cameras.ring.fov_deg: .*got 9e-07$"),
])
def test_a_ring_one_step_past_its_edges_is_refused(old, new, match):
    with pytest.raises(ValueError, match=match):
        Scene.from_text(_edited(CIRCLE, old, new))


def test_uniform_sets_are_kept_in_number_order():
    scene = Scene.from_text(LAB.replace("  6: [1, 3, 7, 11, 13, 15]", "  6: [15, 1, 13, 3, 11, 7]"))
    assert scene.uniform_sets[6] == (1, 3, 7, 11, 13, 15)
    assert scene.uniform_indices()[6] == (0, 2, 6, 10, 12, 14)


def test_the_default_colours_are_ten_distinct_ones_then_round_again():
    text = SMALL.replace("width: 4.0, depth: 3.0", "width: 10.0, depth: 10.0").replace("count: 2,", "count: 12,")
    colours = Scene.from_text(text).people.colours
    assert len({tuple(c) for c in colours[:10].tolist()}) == 10
    np.testing.assert_array_equal(colours[10:], [[200, 30, 30], [30, 70, 200]])


def test_a_scene_with_a_floor_camera_among_calibrated_ones_is_not_calibrated():
    small = Scene.from_text(SMALL)
    mixed = Scene("mixed", small.room, (small.cameras[0], FloorCamera(2, [1.0, 1.0], 0.0, 1.0)), small.people)
    assert small.is_calibrated and not mixed.is_calibrated


def test_a_circular_room_needs_its_radius_and_a_ring_a_field_of_view_that_is_a_number():
    with pytest.raises(ValueError, match=r"^room: missing key 'radius'$"):
        Scene.from_text(_edited(CIRCLE, "  radius: 1.0\n", ""))
    with pytest.raises(ValueError, match=r"^cameras.ring.fov_deg: expected a field of view in \[1e-06, 180\] degrees, got None$"):
        Scene.from_text(_edited(CIRCLE, "fov_deg: 180", "fov_deg: null"))


def test_a_ring_stands_on_the_wall_of_a_room_of_any_radius():
    scene = Scene.from_text(_edited(CIRCLE, "radius: 1.0", "radius: 2.5").replace("count: 16,", "count: 4,"))
    xy, yaw, _ = scene.floor_poses()
    np.testing.assert_allclose(xy, [[2.5, 0.0], [0.0, 2.5], [-2.5, 0.0], [0.0, -2.5]], atol=1e-12)
    np.testing.assert_allclose(np.exp(1j * yaw), [-1, -1j, 1, 1j], atol=1e-12)


def test_the_people_count_refused_names_the_most_that_fit():
    """12 m2 / (pi 0.3**2 m2) / 4 = 10.6 people of radius 0.3 m: 10 may be dropped, 11 may not."""
    text = SMALL.replace("{count: 2, radius: 0.25}", "{count: 10, radius: 0.3}")
    assert Scene.from_text(text).people.count == 10
    with pytest.raises(ValueError, match=r"^people.count: 11 people of radius 0.3 m do not fit in the room; expected at most 10$"):
        Scene.from_text(text.replace("count: 10,", "count: 11,"))


@pytest.mark.parametrize("x", [0.2, 0.25])
def test_a_person_given_closer_to_the_wall_than_their_radius_or_touching_it_is_refused(x):
    text = SMALL.replace("radius: 0.25}", f"radius: 0.25, positions: [[1.0, 1.0], [{x}, 1.0]]}}")
    with pytest.raises(ValueError, match=rf"^people.positions\[1\]: person at \[{x}, 1.0\] overlaps a wall or is outside the room$"):
        Scene.from_text(text)


def test_a_person_given_just_clear_of_the_wall_loads():
    text = SMALL.replace("radius: 0.25}", "radius: 0.25, positions: [[1.0, 1.0], [0.26, 1.0]]}")
    assert Scene.from_text(text).people.positions.tolist() == [[1.0, 1.0], [0.26, 1.0]]


def test_of_people_overlapping_in_several_pairs_the_first_pair_is_named():
    text = SMALL.replace("{count: 2, radius: 0.25}", "{count: 3, radius: 0.25, positions: [[1.0, 1.0], [1.2, 1.0], [1.1, 1.2]]}")
    with pytest.raises(ValueError, match=r"^people.positions\[1\]: person overlaps person 0$"):
        Scene.from_text(text)


def test_the_people_given_positions_and_colours_are_read_only():
    scene = Scene.from_text(SMALL.replace("radius: 0.25}", "radius: 0.25, positions: [[1.0, 1.0], [2.0, 1.0]]}"))
    for array in (scene.people.positions, scene.people.colours):
        with pytest.raises(ValueError, match="read-only"):
            array[0, 0] = 0


def test_the_colours_given_are_uint8_like_the_default_ones():
    scene = Scene.from_text(SMALL.replace("radius: 0.25}", "radius: 0.25, colours: [[255, 0, 1], [2.0, 3, 4]]}"))
    assert scene.people.colours.dtype == np.uint8 == Scene.from_text(SMALL).people.colours.dtype
    assert scene.people.colours.tolist() == [[255, 0, 1], [2, 3, 4]]


def test_a_gain_jitter_of_100_percent_loads_and_past_it_is_refused():
    assert Scene.from_text(SMALL + "render: {gain_jitter: 1.0}\n").render.gain_jitter == 1.0
    with pytest.raises(ValueError, match=r"^render.gain_jitter: expected a finite number >= 0 and at most 1 \(relative\), got 1.001$"):
        Scene.from_text(SMALL + "render: {gain_jitter: 1.001}\n")


def test_a_scene_is_named_after_its_file_and_its_errors_name_the_file(tmp_path):
    path = tmp_path / "hall.yaml"
    path.write_text(SMALL)
    assert Scene.from_yaml(path).name == "hall" and load_scene(path).name == "hall"
    assert Scene.from_config(yaml.safe_load(SMALL), source="rooms/hall.yaml").name == "hall"
    path.write_text("")
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}: empty scene file"):
        Scene.from_yaml(path)
    with pytest.raises(ValueError, match=r"^rooms/hall.yaml: expected a mapping at the top level, got list$"):
        Scene.from_config([1], source="rooms/hall.yaml")


# ---- the camera's checks and derived values at their edges, against hand-computed values
GOOD_K = np.array([[500.0, 0.0, 319.5], [0.0, 500.0, 239.5], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize("R", [np.diag([1.0, 1.0, -1.0]), 1.001 * np.eye(3), (1 + 1e-5) * np.eye(3)])
# a mirror; R R^T 0.2 % off the identity; 2e-5 off, past the 1e-6 it allows
def test_a_mirror_or_a_stretched_rotation_is_refused(R):
    with pytest.raises(ValueError, match=r"^camera.R: expected a rotation matrix$"):
        Camera(1, GOOD_K, np.zeros(5), R, np.zeros(3), 640, 480)


def test_a_camera_needs_a_pixel_of_height_and_a_number_from_one():
    with pytest.raises(ValueError, match=r"^camera.resolution: expected an integer >= 1, got 0$"):
        Camera(1, GOOD_K, np.zeros(5), np.eye(3), np.zeros(3), 640, 0)
    with pytest.raises(ValueError, match=r"^camera.number: expected an integer >= 1, got 0$"):
        Camera(0, GOOD_K, np.zeros(5), np.eye(3), np.zeros(3), 640, 480)


def test_a_camera_looking_straight_down_has_a_pitch_of_90_degrees_though_r_rounds_past_one():
    """Rows right (world -y), down (world -x) and forward (world -z); a rotation read from a
    file may be a few ulps long (R[2, 2] = -1 - 1e-12, within the rotation check)."""
    R = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]) * (1 + 1e-12)
    cam = Camera(1, GOOD_K, np.zeros(5), R, -R @ [1.0, 2.0, 2.5], 640, 480)
    assert cam.pitch == pytest.approx(np.pi / 2, abs=1e-6)
    np.testing.assert_allclose(cam.center_world, [1.0, 2.0, 2.5], atol=1e-9)


def test_the_field_of_view_of_an_off_centre_camera_spans_its_image_edges():
    """From the left edge of pixel 0 (u = -0.5) to the right edge of the last (u = width - 0.5),
    as the angle between those two rays; fy differs from fx and plays no part."""
    K = np.array([[500.0, 0.0, 100.0], [0.0, 800.0, 239.5], [0.0, 0.0, 1.0]])
    cam = Camera(1, K, np.zeros(5), np.eye(3), np.zeros(3), 640, 480)
    left, right = np.array([-0.5 - 100.0, 0.0, 500.0]), np.array([639.5 - 100.0, 0.0, 500.0])
    want = np.arccos(left @ right / np.linalg.norm(left) / np.linalg.norm(right))
    assert cam.hfov == pytest.approx(want, rel=1e-12) and cam.fov == cam.hfov
    assert np.degrees(cam.hfov) == pytest.approx(np.degrees(np.arctan(100.5 / 500) + np.arctan(539.5 / 500)))


@pytest.mark.parametrize("position", [[1.0, 2.0], [1.0, 2.0, np.nan]])
def test_a_camera_from_a_pose_needs_a_position_of_three_finite_numbers(position):
    with pytest.raises(ValueError, match=r"^camera.position: expected "):
        Camera.from_pose(1, position, 0.0, 0.0, 640, 480, 1.0, np.zeros(5))


def test_camera_names_have_two_digits_at_least():
    assert Camera(5, GOOD_K, np.zeros(5), np.eye(3), np.zeros(3), 640, 480).name == "cam05"
    assert Camera(123, GOOD_K, np.zeros(5), np.eye(3), np.zeros(3), 640, 480).name == "cam123"
    assert FloorCamera(7, [0.0, 0.0], 0.0, 1.0).name == "cam07"


def test_a_floor_cameras_field_of_view_is_checked_in_degrees_at_its_edges():
    assert FloorCamera(1, [0.0, 0.0], 0.0, np.radians(1e-6)).fov == np.radians(1e-6)
    assert FloorCamera(1, [0.0, 0.0], 0.0, np.pi).fov == np.pi
    for degrees in (0.9e-6, 180.001, 200.0):
        with pytest.raises(ValueError, match=rf"^camera.fov: expected a field of view in \[1e-06, 180\] degrees, got {degrees:g}$"):
            FloorCamera(1, [0.0, 0.0], 0.0, np.radians(degrees))
    with pytest.raises(ValueError, match=r"^camera.number: expected an integer >= 1, got 0$"):
        FloorCamera(0, [0.0, 0.0], 0.0, 1.0)


@pytest.mark.parametrize("fov", [0.0, -1.0, np.nan, np.inf])
def test_a_floor_cameras_field_of_view_must_be_a_positive_number(fov):
    with pytest.raises(ValueError, match=r"^camera.fov: expected a finite number > 0, got "):
        FloorCamera(1, [0.0, 0.0], 0.0, fov)


@pytest.mark.parametrize("xy", [[0.0, 0.0, 1.0], [0.0, np.nan]])
def test_a_floor_cameras_position_must_be_two_finite_numbers(xy):
    with pytest.raises(ValueError, match=r"^camera.xy: expected "):
        FloorCamera(1, xy, 0.0, 1.0)
