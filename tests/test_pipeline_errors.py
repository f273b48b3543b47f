"""Bad input: one-line ValueErrors naming the parameter and what was expected."""

import numpy as np
import pytest

import scene
from pipeline import Pipeline, PipelineParams, background_model, load_params
from pipeline.params import DEFAULT_PATH


def cam(w=32, h=24):
    return scene.Camera.from_pose(1, [0, 0, 1.5], 0.0, 0.1, w, h, np.radians(50), [-0.1, 0, 0, 0, 0])


BG = np.full((1, 24, 32, 3), 100, np.uint8)


def test_default_yaml_is_the_dataclass_default():
    assert load_params() == PipelineParams()
    assert load_params(DEFAULT_PATH) == PipelineParams()


def test_yaml_round_trip(tmp_path):
    p = PipelineParams(threshold_deg=7.5, median_kernel=9)
    p.to_yaml(tmp_path / "p.yaml", comment="tuned")
    assert load_params(tmp_path / "p.yaml") == p
    assert not [f for f in tmp_path.iterdir() if f.name.startswith(".")]


@pytest.mark.parametrize("changes, match", [
    ({"colour": 3}, r"unknown key 'colour'"),
    ({"opening_kernel": 4}, r"opening_kernel: expected an odd integer in 1..8191, got 4"),
    ({"median_kernel": -3}, r"median_kernel: expected an odd integer in 1..8191, got -3"),
    # a 10**5 opening asked OpenCV for 10 GB, and the process was killed without a word
    ({"opening_kernel": 100001}, r"opening_kernel: expected an odd integer in 1..8191, got 100001"),
    ({"spatial_kernel": 10**9 + 1}, r"spatial_kernel: expected an odd integer in 1..8191"),
    ({"spatial_kernel": 2.0}, r"spatial_kernel: expected an odd integer"),
    ({"threshold_deg": -1}, r"threshold_deg: expected a .*number"),
    ({"threshold_deg": 90}, r"threshold_deg: expected a number in \(0, 90\)"),
    ({"temporal_alpha": 0}, r"temporal_alpha: expected a number in \(0, 1\]"),
    ({"column_threshold": 0}, r"column_threshold: expected a finite number > 0"),
    ({"brightness_floor": "dark"}, r"brightness_floor: expected a number"),
    # overflowed float32 with a RuntimeWarning; no RGB difference exceeds 255 sqrt 3
    ({"dark_delta": 1e300}, r"dark_delta: expected a number in \[0, 442\], got 1e\+300"),
])
def test_bad_parameters(changes, match):
    with pytest.raises(ValueError, match=match):
        PipelineParams.from_mapping(changes)


def test_numpy_integers_and_exponent_floats_are_numbers(tmp_path):
    """A grid search over np.arange, and ``1e-3`` in a file (a string to YAML 1.1)."""
    assert PipelineParams(opening_kernel=np.int64(7), median_kernel=np.int32(9)).opening_kernel == 7
    (tmp_path / "p.yaml").write_text("temporal_alpha: 1e-3\ncolumn_threshold: 5E1\n")
    assert load_params(tmp_path / "p.yaml") == PipelineParams(temporal_alpha=0.001, column_threshold=50.0)


def test_a_file_that_is_not_utf8_is_named(tmp_path):
    (tmp_path / "b.yaml").write_bytes(b"\xff\xfe\x00bad")
    with pytest.raises(ValueError) as err:
        load_params(tmp_path / "b.yaml")
    assert str(err.value) == f"params: {str(tmp_path / 'b.yaml')!r} is not UTF-8 text (byte 0xff at offset 0)"


def test_bad_yaml_file(tmp_path):
    (tmp_path / "p.yaml").write_text("threshold_deg: 5\nkernel: 3\n")
    with pytest.raises(ValueError, match="unknown key 'kernel'"):
        load_params(tmp_path / "p.yaml")
    (tmp_path / "q.yaml").write_text("[1, 2]\n")
    with pytest.raises(ValueError, match="expected a mapping"):
        load_params(tmp_path / "q.yaml")


@pytest.mark.parametrize("text, why", [
    ("hello\n", "expected a mapping of pipeline parameters (key: value lines), got str"),
    ("threshold_deg: -3\n", "threshold_deg: expected a finite number >= 0, got -3"),
    ("blur: 3\n", "pipeline parameters: unknown key 'blur'"),
])
def test_a_bad_parameters_file_is_named(tmp_path, text, why):
    (tmp_path / "p.txt").write_text(text)
    with pytest.raises(ValueError) as err:
        load_params(tmp_path / "p.txt")
    assert str(err.value).startswith(f"params: {str(tmp_path / 'p.txt')!r}: {why}")


def test_an_empty_parameters_file_is_the_defaults(tmp_path):
    (tmp_path / "p.yaml").write_text("")
    assert load_params(tmp_path / "p.yaml") == PipelineParams()


@pytest.mark.parametrize("name", ["threshold_deg", "brightness_floor", "dark_delta", "temporal_alpha",
                                  "column_threshold"])
def test_a_boolean_is_not_a_number(tmp_path, name):
    """``true`` in a file is YAML 1.2's boolean: it would pass as 1.0 (a bool is an int to Python)."""
    with pytest.raises(ValueError) as err:
        PipelineParams(**{name: True})
    assert str(err.value) == f"{name}: expected a number, got True"
    (tmp_path / "p.yaml").write_text(f"{name}: true\n")
    with pytest.raises(ValueError) as err:
        load_params(tmp_path / "p.yaml")
    assert str(err.value) == f"params: {str(tmp_path / 'p.yaml')!r}: {name}: expected a number, got True"


def test_parameters_under_a_pipeline_key(tmp_path):
    """A file may hold the parameters under one top-level ``pipeline`` key (as a larger
    configuration file would); beside another key it is an unknown parameter."""
    (tmp_path / "p.yaml").write_text("pipeline:\n  median_kernel: 5\n  column_threshold: 12.5\n")
    p = load_params(tmp_path / "p.yaml")
    assert (p.median_kernel, p.column_threshold) == (5, 12.5)
    assert p.threshold_deg == 3.0 and p.opening_kernel == 7         # the others: the defaults
    (tmp_path / "e.yaml").write_text("pipeline:\n")
    assert load_params(tmp_path / "e.yaml") == PipelineParams()
    (tmp_path / "q.yaml").write_text("pipeline:\n  median_kernel: 5\nthreshold_deg: 4\n")
    with pytest.raises(ValueError, match=r"^params: '.*q.yaml': pipeline parameters: unknown key 'pipeline'"):
        load_params(tmp_path / "q.yaml")
    (tmp_path / "r.yaml").write_text("pipeline:\n  median_kernel: 4\n")
    with pytest.raises(ValueError, match=r"^params: '.*r.yaml': median_kernel: expected an odd integer in 1..8191, got 4$"):
        load_params(tmp_path / "r.yaml")


def test_the_bounds_of_each_parameter_are_inside_the_range(tmp_path):
    """The widest filter, a floor or delta at the largest RGB norm (255 sqrt 3, every pixel
    dark) and zero floor and delta are parameters; one step beyond each is not."""
    top = 255 * np.sqrt(3)
    p = PipelineParams(opening_kernel=8191, spatial_kernel=8191, median_kernel=1, brightness_floor=top,
                       dark_delta=top, temporal_alpha=1.0)
    assert (p.opening_kernel, p.spatial_kernel, p.median_kernel) == (8191, 8191, 1)
    assert p.brightness_floor == p.dark_delta == top
    q = PipelineParams(brightness_floor=0, dark_delta=0.0)
    assert (q.brightness_floor, q.dark_delta) == (0.0, 0.0)
    for changes, message in (({"opening_kernel": 8193}, "opening_kernel: expected an odd integer in 1..8191, got 8193"),
                             ({"brightness_floor": 442.5}, "brightness_floor: expected a number in [0, 442], got 442.5"),
                             ({"dark_delta": -0.5}, "dark_delta: expected a finite number >= 0, got -0.5")):
        with pytest.raises(ValueError) as err:
            PipelineParams(**changes)
        assert str(err.value) == message


@pytest.mark.parametrize("name", ["opening_kernel", "spatial_kernel", "median_kernel"])
def test_a_boolean_is_not_a_filter_size(name):
    """True is an odd integer 1 to Python: ``opening_kernel: true`` would be no opening."""
    with pytest.raises(ValueError) as err:
        PipelineParams(**{name: True})
    assert str(err.value) == f"{name}: expected an odd integer in 1..8191, got True"


def test_numpy_and_integer_values_are_kept_as_python_numbers(tmp_path):
    """A grid search's NumPy scalars and integers in a file become int and float: the
    parameters write as plain YAML and JSON (PyYAML's safe_dump refuses NumPy scalars)."""
    import json

    p = PipelineParams(threshold_deg=np.float32(7.5), brightness_floor=np.int64(30), dark_delta=20,
                       opening_kernel=np.int64(5), median_kernel=np.int32(9), temporal_alpha=1,
                       column_threshold=np.float64(12.5))
    types = {k: type(v) for k, v in p.to_dict().items()}
    assert types == {"threshold_deg": float, "brightness_floor": float, "dark_delta": float, "opening_kernel": int,
                     "spatial_kernel": int, "temporal_alpha": float, "median_kernel": int, "column_threshold": float}
    assert json.loads(json.dumps(p.to_dict()))["brightness_floor"] == 30.0
    p.to_yaml(tmp_path / "p.yaml")
    assert load_params(tmp_path / "p.yaml") == p


def test_parameters_are_written_in_the_order_they_are_documented(tmp_path):
    PipelineParams().to_yaml(tmp_path / "p.yaml", comment="first\nsecond")
    lines = (tmp_path / "p.yaml").read_text().splitlines()
    assert lines[:2] == ["# first", "# second"]
    assert [line.split(":")[0] for line in lines[2:]] == [
        "threshold_deg", "brightness_floor", "dark_delta", "opening_kernel", "spatial_kernel", "temporal_alpha",
        "median_kernel", "column_threshold"]
    default = [line.split(":")[0] for line in DEFAULT_PATH.read_text().splitlines() if not line.startswith("#")]
    assert default == [line.split(":")[0] for line in lines[2:]]


def test_a_file_that_is_not_yaml_is_named_with_the_option(tmp_path):
    (tmp_path / "p.yaml").write_text("threshold_deg: [1, 2\n")
    with pytest.raises(ValueError) as err:
        load_params(tmp_path / "p.yaml", name="--params")
    assert str(err.value) == (f"--params: {tmp_path / 'p.yaml'} is not valid YAML (did not find expected ',' or "
                              "']' at line 2, column 1)")


def test_a_file_with_an_integer_too_long_to_read_is_named_with_the_option(tmp_path):
    (tmp_path / "p.yaml").write_text("opening_kernel: " + "1" * 5000 + "\n")
    with pytest.raises(ValueError) as err:
        load_params(tmp_path / "p.yaml", name="--params")
    assert str(err.value) == (f"--params: {tmp_path / 'p.yaml'} is not valid YAML (an integer of 5000 characters "
                              "is too long to read at line 1, column 17)")


def test_replace_is_a_validated_copy():
    p = PipelineParams(threshold_deg=5.0)
    q = p.replace(median_kernel=3, column_threshold=7)
    assert (q.threshold_deg, q.median_kernel, q.column_threshold) == (5.0, 3, 7.0)
    assert isinstance(q.column_threshold, float)
    assert (p.median_kernel, p.column_threshold) == (15, 55.0)         # the original unchanged
    with pytest.raises(ValueError, match=r"^opening_kernel: expected an odd integer in 1..8191, got 8$"):
        p.replace(opening_kernel=8)
    with pytest.raises(TypeError):
        p.replace(kernel=3)


def test_a_huge_integer_is_named_in_six_digits():
    """An integer of 5000 digits stopped Python's repr (its 4300-digit limit) with an error
    that named no parameter; one of 21 digits was shown whole."""
    with pytest.raises(ValueError) as err:
        PipelineParams(opening_kernel=10**5000)
    assert str(err.value) == "opening_kernel: expected an odd integer in 1..8191, got 1e+5000"
    with pytest.raises(ValueError) as err:
        PipelineParams(dark_delta=10**20)
    assert str(err.value) == "dark_delta: expected a number in [0, 442], got 1e+20"


@pytest.mark.parametrize("name", ["opening_kernel", "spatial_kernel", "median_kernel"])
def test_a_float_is_not_a_filter_size(name):
    """3.0 and 5.5 are odd-looking numbers in range, but a filter is a whole number of pixels."""
    for value in (3.0, 5.5, np.float64(7.0)):
        with pytest.raises(ValueError) as err:
            PipelineParams(**{name: value})
        assert str(err.value) == f"{name}: expected an odd integer in 1..8191, got {value!r}"


def test_writing_parameters_replaces_the_file_whole(tmp_path):
    """A reader of the old file (a run that opened it) keeps reading the old parameters: the
    new file is put in its place, the old one is not truncated and rewritten."""
    path = tmp_path / "p.yaml"
    PipelineParams(median_kernel=5).to_yaml(path)
    with open(path) as old:
        PipelineParams(median_kernel=9).to_yaml(path)
        assert "median_kernel: 5" in old.read()
    assert load_params(path).median_kernel == 9


def test_the_params_option_is_named_when_given_and_the_default_file_when_not():
    from pipeline.params import params_option

    assert params_option("p.yaml") == params_option(DEFAULT_PATH) == "--params"
    assert params_option("") == "--params"                  # --params "" was given (an unset variable)
    assert params_option(None) == "--params (not given: the default assets/pipeline/default.yaml)"


def test_an_empty_params_path_is_not_the_defaults():
    """``--params "$P"`` with P unset is a mistake to report, not a run on the default file."""
    with pytest.raises(ValueError, match="^--params: "):
        load_params("", "--params")


@pytest.mark.parametrize("frames, match", [
    (np.zeros((1, 24, 31, 3), np.uint8), r"frames: expected shape \(1, 24, 32, 3\) to match the calibration"),
    (np.zeros((2, 24, 32, 3), np.uint8), r"frames: expected shape \(1, 24, 32, 3\)"),
    (np.zeros((1, 24, 32, 3), np.float32), r"frames: expected dtype uint8"),
    (np.zeros((1, 24, 32), np.uint8), r"frames: expected shape \(n_cams, H, W, 3\)"),
    (np.zeros((24, 32, 3), np.uint8), r"frames: expected shape \(n_cams, H, W, 3\), got \(24, 32, 3\)"),
    (np.zeros((1, 24, 32, 4), np.uint8), r"frames: expected shape \(n_cams, H, W, 3\), got \(1, 24, 32, 4\)"),
    (np.zeros((1, 0, 32, 3), np.uint8), r"frames: expected non-empty images"),
])
def test_bad_frames(frames, match):
    pipe = Pipeline([cam()], background=BG)
    with pytest.raises(ValueError, match=match):
        pipe.process(frames)


def test_bad_background():
    with pytest.raises(ValueError, match=r"background: expected shape \(1, 24, 32, 3\) to match"):
        Pipeline([cam()], background=np.full((1, 24, 30, 3), 9, np.uint8))
    # named by number: `camtask run` gives each camera a pipeline of its own, where the index is always 0
    with pytest.raises(ValueError, match="background: camera 1 sees all black; expected an image of the lit"):
        Pipeline([cam()], background=np.zeros((1, 24, 32, 3), np.uint8))
    with pytest.raises(ValueError, match="background: camera 1 sees all black"):
        Pipeline([cam()], background=np.zeros((1, 24, 32, 3), np.float32))
    with pytest.raises(ValueError, match="background: camera index 0 sees all black"):
        background_model(np.zeros((1, 24, 32, 3), np.uint8))
    with pytest.raises(ValueError, match="background: expected uint8 frames"):
        background_model(np.zeros((1, 0, 32, 3), np.uint8))
    with pytest.raises(ValueError, match="background: not set"):
        Pipeline([cam()]).process(BG)
    # a float64 model (np.full of 100.0) and RGBA frames are not empty-room RGB frames
    with pytest.raises(ValueError, match=r"background: expected uint8 frames .* got float64 \(1, 1, 24, 32, 3\)"):
        Pipeline([cam()], background=np.full((1, 24, 32, 3), 100.0))
    # frames in float32 are not a model: only (n_cams, H, W, 3) float32 is taken as one
    with pytest.raises(ValueError, match=r"background: expected uint8 frames .* got float32 \(2, 1, 24, 32, 3\)"):
        Pipeline([cam()], background=np.full((2, 1, 24, 32, 3), 100.0, np.float32))
    with pytest.raises(ValueError, match=r"background: expected uint8 frames .* got uint8 \(1, 1, 24, 32, 4\)"):
        background_model(np.full((1, 24, 32, 4), 100, np.uint8))


def test_a_black_camera_is_named_among_lit_ones_with_black_pixels():
    """Only a camera whose whole background is black is refused, and it is the one named:
    black pixels, or a colour channel at 0 everywhere, are a lit image."""
    cams = [scene.Camera.from_pose(n, [0, 0, 1.5], 0.0, 0.1, 32, 24, np.radians(50), [-0.1, 0, 0, 0, 0])
            for n in (4, 7, 9)]
    bg = np.zeros((3, 24, 32, 3), np.uint8)
    bg[0, 5:, :, 0] = 90                               # camera 4: red only, its top rows black
    bg[2, 12, 20] = (0, 1, 0)                          # camera 9: one dim green pixel
    with pytest.raises(ValueError, match="background: camera 7 sees all black"):
        Pipeline(cams, background=bg)
    bg[1, :, :, 2] = 200                               # camera 7 lit: blue only
    assert Pipeline(cams, background=bg).background.shape == (3, 24, 32, 3)


def test_the_background_model_cannot_be_changed_from_outside():
    """background_model's result and Pipeline.background are read-only (a write would
    change what every later frame is compared with)."""
    model = background_model(np.stack([BG, BG + 1]))            # means of 100.5: kept as float32
    assert model.dtype == np.float32 and not model.flags.writeable
    for bg in (model, BG):
        pipe = Pipeline([cam()], background=bg)
        with pytest.raises(ValueError, match="read-only"):
            pipe.background[0, 0, 0] = 0


def test_a_writeable_float_background_is_the_callers_own_after_the_pipeline_took_it():
    """A writeable float32 background (not of whole levels) was kept without a copy: reading
    ``pipe.background`` made the caller's array read-only, and the caller's writes before
    that changed the pipeline's model."""
    mine = np.full((1, 24, 32, 3), 100.5, np.float32)
    pipe = Pipeline([cam()], background=mine)
    mine[0, 0, 0] = 7.0                                   # the caller reuses its buffer
    model = pipe.background
    assert mine.flags.writeable
    assert not np.shares_memory(model, mine)
    assert np.all(model == 100.5)


def test_bad_labels_and_cameras():
    pipe = Pipeline([cam()], background=BG)
    with pytest.raises(ValueError, match=r"labels: expected shape \(1, 24, 32\)"):
        pipe.ground_truth(np.zeros((1, 24, 33), int))
    with pytest.raises(ValueError, match="cameras: expected at least one"):
        Pipeline([])
    with pytest.raises(ValueError, match="cameras: expected every camera to have the same resolution"):
        Pipeline([cam(), cam(40, 30)])


def _calibration_text(tmp_path, camera_number=None):
    """The text of a calibration file as ``camtask render`` writes it (camera 5 of the lab)."""
    from scene import load_scene
    from testbed.dataset import write_calibration

    path = tmp_path / "written.yaml"
    write_calibration(path, load_scene("lab").cameras[4])
    return path.read_text()


@pytest.mark.parametrize("edit, message", [
    (lambda t: "hello: [1, 2\n", "bad.yaml is not an OpenCV FileStorage file"),
    (lambda t: t.replace("image_width: 640", "image_width: abc"), "bad.yaml image_width: expected an integer"),
    (lambda t: t.replace("image_height: 480\n", ""), "bad.yaml has no 'image_height'"),
    (lambda t: t.replace("data: [ 1.689", "data: [ 1.689, 0.5", 1).replace("rows: 3\n   cols: 1", "rows: 4\n   cols: 1", 1),
     "bad.yaml rvec: expected 3 finite numbers"),
    (lambda t: t.replace("data: [ 702.", "data: [ -702.", 1), r"bad.yaml: camera.K: expected \[\[fx, s, cx\]"),
])
def test_a_malformed_calibration_file_is_one_line(tmp_path, edit, message):
    from pipeline.io import load_calibration

    text = _calibration_text(tmp_path)
    bad = tmp_path / "bad.yaml"
    bad.write_text(edit(text))
    with pytest.raises(ValueError, match=message) as info:
        load_calibration(bad)
    assert str(info.value).startswith("calibration: ") and "\n" not in str(info.value)


def test_the_camera_number_written_in_the_file_counts_over_its_name(tmp_path):
    from pipeline.io import load_calibration

    text = _calibration_text(tmp_path)
    for name in ("cam.yaml", "cam0.yaml", "cam07.yaml"):
        (tmp_path / name).write_text(text)
        assert load_calibration(tmp_path / name).number == 5
    (tmp_path / "cam07b.yaml").write_text(text.replace("camera_number: 5\n", ""))
    assert load_calibration(tmp_path / "cam07b.yaml").number == 7
    assert load_calibration(tmp_path / "cam07b.yaml", number=3).number == 3


def _write_xml_calibration(path, camera, dist):
    """``camera``'s calibration as an OpenCV XML file, with ``dist`` as its coefficients."""
    import cv2

    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("camera_matrix", camera.K)
    fs.write("distortion_coefficients", np.asarray(dist, float).reshape(1, -1))
    fs.write("rvec", cv2.Rodrigues(camera.R)[0])
    fs.write("tvec", camera.t.reshape(3, 1))
    fs.write("image_width", camera.width)
    fs.write("image_height", camera.height)
    fs.release()


@pytest.mark.parametrize("dist, expected", [
    ([-0.18, 0.06, 0.001, -0.002], [-0.18, 0.06, 0.001, -0.002, 0.0]),                  # k1 k2 p1 p2: k3 = 0
    ([-0.2], [-0.2, 0.0, 0.0, 0.0, 0.0]),
    ([-0.18, 0.06, 0.001, -0.002, 0.01, 0, 0, 0], [-0.18, 0.06, 0.001, -0.002, 0.01]),  # rational model, k4-k6 = 0
    ([-0.18, 0.06, 0.001, -0.002, 0.01] + [0] * 9, [-0.18, 0.06, 0.001, -0.002, 0.01]),
    ([-0.18, 0.06, 0.001, -0.002, 0.01, 0], [-0.18, 0.06, 0.001, -0.002, 0.01]),       # one zero too many
])
def test_a_calibration_of_fewer_or_more_distortion_coefficients_is_read_as_five(tmp_path, dist, expected):
    """OpenCV writes 4, 5, 8, 12 or 14 coefficients; the terms past k3 are the identity when zero."""
    import cv2

    from pipeline.io import load_calibration
    from scene import load_scene

    lab = load_scene("lab").cameras[4]
    _write_xml_calibration(tmp_path / "cam05.xml", lab, dist)
    cam = load_calibration(tmp_path / "cam05.xml")
    assert cam.dist.tolist() == expected
    assert cam.number == 5 and (cam.width, cam.height) == (640, 480)
    np.testing.assert_array_equal(cam.K, lab.K)
    np.testing.assert_allclose(cam.R, lab.R, atol=1e-12)
    np.testing.assert_array_equal(cam.t, lab.t)
    # the same pixels as OpenCV's own model with every coefficient given
    points = np.array([[1.0, 2.0, 0.5], [3.0, 1.0, 1.2], [0.5, 4.0, 0.0]])
    rvec = cv2.Rodrigues(lab.R)[0]
    full = np.asarray(dist if len(dist) in (4, 5, 8, 12, 14) else expected, float)   # the counts OpenCV takes
    theirs = cv2.projectPoints(points, rvec, lab.t, lab.K, full)[0]
    ours = cv2.projectPoints(points, rvec, lab.t, cam.K, cam.dist)[0]
    np.testing.assert_allclose(ours, theirs, atol=1e-9)


@pytest.mark.parametrize("dist, term", [
    ([-0.18, 0.06, 0, 0, 0.01, 0, 0.3, 0], "k5 = 0.3"),
    ([-0.18, 0.06, 0, 0, 0, 1e-9, 0, 0], "k4 = 1e-09"),
    ([-0.18, 0.06, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, -0.01], "tauY = -0.01"),
    ([-0.18, 0.06, 0, 0, 0, 0, 0, 0, 0.2, 0.5, 0, 0], "s1 = 0.2"),
    ([-0.18, 0.06, 0, 0, 0] + [0] * 9 + [0.5], "coefficient 15 = 0.5"),        # the first past tauY
    ([-0.18, 0.06, 0, 0, 0] + [0] * 10 + [0.5], "coefficient 16 = 0.5"),       # more than OpenCV has
])
def test_distortion_coefficients_past_k3_that_are_not_zero_are_refused(tmp_path, dist, term):
    """The message said "got 8 non-zero" of 8 coefficients of which two were zero; it names
    the first term the pipeline cannot model."""
    from pipeline.io import load_calibration
    from scene import load_scene

    _write_xml_calibration(tmp_path / "cam05.xml", load_scene("lab").cameras[4], dist)
    with pytest.raises(ValueError) as err:
        load_calibration(tmp_path / "cam05.xml")
    assert str(err.value) == (f"calibration: cam05.xml distortion_coefficients: expected at most 5 (k1 k2 p1 p2 k3), "
                              f"got {len(dist)} with {term} (the terms past k3 must be zero)")


def test_a_calibration_without_a_number_is_camera_1_and_a_single_coefficient_is_k1(tmp_path):
    """Neither ``camera_number`` nor ``camNN`` in the name: camera 1. A scalar (not a
    list) where numbers are expected is one number."""
    from pipeline.io import load_calibration

    text = _calibration_text(tmp_path).replace("camera_number: 5\n", "")
    start = text.index("distortion_coefficients:")
    end = text.index("rvec:")
    (tmp_path / "lens.yaml").write_text(text[:start] + "distortion_coefficients: -0.25\n" + text[end:])
    cam = load_calibration(tmp_path / "lens.yaml")
    assert cam.number == 1 and cam.dist.tolist() == [-0.25, 0.0, 0.0, 0.0, 0.0]


def test_a_whole_number_where_numbers_are_expected_is_that_number(tmp_path):
    """``distortion_coefficients: 0`` is an integer to FileStorage, not a real: k1 = 0."""
    from pipeline.io import load_calibration

    text = _calibration_text(tmp_path)
    start = text.index("distortion_coefficients:")
    end = text.index("rvec:")
    (tmp_path / "lens.yaml").write_text(text[:start] + "distortion_coefficients: 0\n" + text[end:])
    assert load_calibration(tmp_path / "lens.yaml").dist.tolist() == [0.0] * 5


def test_calibration_keys_may_be_lists_of_numbers(tmp_path):
    """A hand-written file holds plain lists (``rvec: [1.5, 0, 0]``), not ``!!opencv-matrix``."""
    from pipeline.io import load_calibration

    text = ("%YAML:1.0\n"
            "camera_matrix: [700.0, 0, 320.5, 0, 700, 240.5, 0, 0, 1]\n"
            "distortion_coefficients: [-0.1, 0.02, 0, 0]\n"
            "rvec: [1.5, 0.0, 0.0]\n"
            "tvec: [-1, 0.5, 3]\n"
            "image_width: 640\nimage_height: 480\n")
    (tmp_path / "cam07.yaml").write_text(text)
    cam = load_calibration(tmp_path / "cam07.yaml")
    assert cam.K.tolist() == [[700.0, 0.0, 320.5], [0.0, 700.0, 240.5], [0.0, 0.0, 1.0]]
    assert cam.dist.tolist() == [-0.1, 0.02, 0.0, 0.0, 0.0]
    c, s = np.cos(1.5), np.sin(1.5)                                 # 1.5 rad about x
    np.testing.assert_allclose(cam.R, [[1, 0, 0], [0, c, -s], [0, s, c]], atol=1e-12)
    assert cam.t.tolist() == [-1.0, 0.5, 3.0] and cam.number == 7
    for bad, key in (("rvec: [1.5, x, 0.0]", "rvec: expected 3"), ("rvec: [1.5, 0.0]", "rvec: expected 3"),
                     ("tvec: [-1, 0.5, [3]]", "tvec: expected 3"), ("rvec: [1.5, .nan, 0.0]", "rvec: expected 3"),
                     ("camera_matrix: [700.0, 0, 320.5, 0, 700, 240.5, 0, 0]", "camera_matrix: expected 9")):
            line = bad.split(":")[0]
            edited = "".join(bad + "\n" if t.startswith(line + ":") else t for t in text.splitlines(keepends=True))
            (tmp_path / "bad.yaml").write_text(edited)
            with pytest.raises(ValueError) as err:
                load_calibration(tmp_path / "bad.yaml")
            assert str(err.value).startswith(f"calibration: bad.yaml {key} finite numbers"), bad


def lab_like(dist=(-0.18, 0.06, 0, 0, 0), principal=None):
    c = scene.Camera.from_pose(3, [1.0, 0.05, 2.2], np.radians(90), np.radians(15), 640, 480, np.radians(49),
                               list(dist))
    if principal is not None:
        K = c.K.copy()
        K[:2, 2] = principal
        c = scene.Camera(c.number, K, c.dist, c.R, c.t, c.width, c.height)
    return c


@pytest.mark.parametrize("camera, match", [
    (lab_like((-0.6, 0, 0, 0, 0)), r"camera 3: its lens distortion \[-0.6, 0.0, 0.0, 0.0, 0.0\] folds over inside"),
    (lab_like((0, 0, 0, 0, -3.0)), "camera 3: its lens distortion .* folds over inside its image"),
    (lab_like(principal=(2000, 240)), "camera 3: once turned level, no column of its image spans the image's whole"),
])
def test_lenses_that_fold_over_or_cannot_be_levelled_are_refused_in_one_line(camera, match):
    """They rendered rays twice ("a glass ball"), or asked OpenCV for 18 EB of maps."""
    from pipeline.rectify import check_rectifiable

    check_rectifiable([lab_like()])              # the lab's own lens
    with pytest.raises(ValueError, match=match):
        check_rectifiable([camera])


@pytest.mark.parametrize("argv", [
    ["render", "lab", "--frames", "1"], ["run", "lab", "--frames", "1"], ["scanlines", "DIR"],
    ["tune", "DIR", "--trials", "1"], ["study", "lab", "--trials", "1", "--workers", "0", "--no-progress"],
])
def test_every_command_names_the_params_option_the_user_typed(tmp_path, capsys, argv):
    """Each command said 'params: ...' of a bad --params file, not the option's name."""
    from testbed import cli

    argv = [str(tmp_path / "out") if a == "DIR" else a for a in argv]
    if argv[0] == "render":
        argv += ["--out", str(tmp_path / "out")]
    bad, folder, missing = tmp_path / "bad.yaml", tmp_path / "folder.yaml", tmp_path / "missing.yaml"
    bad.write_text("median_kernel: 4\n")
    folder.mkdir()
    for path, why in ((bad, "median_kernel: expected an odd integer in 1..8191, got 4"),
                      (folder, "is a folder, not a file"), (missing, "no such file")):
        assert cli.main([*argv, "--params", str(path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"camtask {argv[0]}: error: --params: ") and why in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_a_camera_that_cannot_be_levelled_is_told_why():
    """A centred lens was told its principal point (319.5, 239.5) was 'far from the image's centre?'."""
    from pipeline.rectify import virtual_extent

    head = "camera 3: once turned level, no column of its image spans the image's whole height ("
    tail = "); it cannot be rectified to a level camera"
    with pytest.raises(ValueError) as err:
        virtual_extent(lab_like((-0.6, 0, 0, 0, 0)))
    assert str(err.value) == head + "its lens distortion [-0.6, 0.0, 0.0, 0.0, 0.0] bends the image's sides too far" + tail
    with pytest.raises(ValueError) as err:
        virtual_extent(lab_like(principal=(2000, 240)))
    assert str(err.value) == head + "its principal point 2000, 240 is far from the image's centre 319.5, 239.5" + tail


def test_the_first_of_several_black_cameras_is_named():
    """Cameras 7 and 9 both see all black: the error names camera 7, the first."""
    cams = [scene.Camera.from_pose(n, [0, 0, 1.5], 0.0, 0.1, 32, 24, np.radians(50), [-0.1, 0, 0, 0, 0])
            for n in (4, 7, 9)]
    bg = np.zeros((3, 24, 32, 3), np.uint8)
    bg[0] = 100
    with pytest.raises(ValueError, match="background: camera 7 sees all black"):
        Pipeline(cams, background=bg)
    with pytest.raises(ValueError, match="background: camera index 1 sees all black"):
        background_model(bg)


def test_params_and_a_missing_background_are_refused_by_name():
    """A mapping is not a PipelineParams (load_params or PipelineParams.from_mapping make one),
    with_params needs the background it shares, and background_model a camera axis."""
    with pytest.raises(ValueError, match="^params: expected PipelineParams, got dict$"):
        Pipeline([cam()], {"median_kernel": 3})
    with pytest.raises(ValueError, match="background: not set"):
        Pipeline([cam()]).with_params(PipelineParams(median_kernel=3))
    with pytest.raises(ValueError, match="background: not set"):
        _ = Pipeline([cam()]).background
    # one image without the camera axis is neither (n_cams, H, W, 3) nor (n_frames, n_cams, H, W, 3)
    with pytest.raises(ValueError, match=r"background: expected uint8 frames .* got uint8 \(24, 32, 3\)"):
        background_model(np.full((24, 32, 3), 100, np.uint8))
