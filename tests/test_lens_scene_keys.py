"""Scene camera keys checked against their honest ranges on loading, in one line naming the
key; numbers of any length shown readably."""

import re

import pytest

from scene import Scene, scene_path

LAB = scene_path("lab").read_text()


@pytest.mark.parametrize("old, new, match", [
    # "its lens distortion [-0.18, 0.06, 0.0, 0.0, 0.0] folds over inside its image" at render time
    ("principal: [322.4, 236.8]", "principal: [1e300, 236.8]",
     (r"^cameras\.intrinsics\.principal: expected \[u, v\] pixels at most one image size outside the image, "
      r"u in -640\.5\.\.1279\.5 and v in -480\.5\.\.959\.5, got \[1e\+300, 236\.8\]$")),
    ("principal: [322.4, 236.8]", "principal: [-1e300, -1e300]", r"^cameras\.intrinsics\.principal: .*got \[-1e"),
    ("principal: [322.4, 236.8]", "principal: [322.4, 1e300]", r"^cameras\.intrinsics\.principal: .*v in "),
    # "no column of its image spans the image's whole height" at render time
    ("principal: [322.4, 236.8]", "principal: [2000, 236.8]", r"^cameras\.intrinsics\.principal: .*got \[2000, "),
    ("resolution: [640, 480]", "resolution: [2, 2]", r"^cameras\.intrinsics\.principal: .*u in -2\.5\.\.3\.5"),
    # "(principal point 322.4, 236.8 pixels far from the image's centre?)" at render time
    ("hfov_deg: 49.0", "hfov_deg: 1e-300",
     r"^cameras\.intrinsics\.hfov_deg: expected a field of view in \[1, 179\] degrees, got 1e-300$"),
    # "camera 2 sees all black" after rendering the background
    ("hfov_deg: 49.0", "hfov_deg: 1e-10", r"^cameras\.intrinsics\.hfov_deg: .*got 1e-10$"),
    # rendered, a pixel off (float32 in OpenGL)
    ("hfov_deg: 49.0", "hfov_deg: 0.001", r"^cameras\.intrinsics\.hfov_deg: .*got 0\.001$"),
])
def test_camera_keys_out_of_range_are_named_on_loading(old, new, match):
    assert old in LAB
    with pytest.raises(ValueError, match=match):
        Scene.from_text(LAB.replace(old, new), "s.yaml")


def test_camera_keys_at_their_limits_load():
    for old, new in [("hfov_deg: 49.0", "hfov_deg: 1.0"), ("principal: [322.4, 236.8]", "principal: [-640.5, 959.5]"),
                     ("principal: [322.4, 236.8]", "principal: [1279.5, -480.5]")]:
        Scene.from_text(LAB.replace(old, new), "s.yaml")


BIG = "1" + "0" * 400


@pytest.mark.parametrize("old, new", [
    ("frame_rate: 7.5", f"frame_rate: {BIG}"),
    ("hfov_deg: 49.0", f"hfov_deg: {BIG}"),
    ("hfov_deg: 49.0", f"hfov_deg: -{BIG}"),
    ("principal: [322.4, 236.8]", f"principal: [{BIG}, 236.8]"),
    ("distortion: [-0.18, 0.06, 0.0, 0.0, 0.0]", f"distortion: [{BIG}, 0.06, 0.0, 0.0, 0.0]"),
    ("resolution: [640, 480]", f"resolution: [{BIG}, 480]"),
    ("resolution: [640, 480]", f"resolution: [-{BIG}, 480]"),
    ("position: [0.781, 0.05, 2.2]", f"position: [{BIG}, 0.05, 2.2]"),
    ("number: 1, position: [0.781, 0.05, 2.2]", f"number: {BIG}, position: [0.781, 0.05, 2.2]"),
    ("number: 1, position: [0.781, 0.05, 2.2]", f"number: {BIG}, position: [100, 0.05, 2.2]"),
    ("yaw_deg: 47.9", f"yaw_deg: {BIG}"),
    ("pitch_deg: 15.0}", f"pitch_deg: -{BIG}}}"),
    ("width: 6.7056", f"width: {BIG}"),
    ("count: 3", f"count: {BIG}"),
    ("radius: 0.25", f"radius: {BIG}"),
    ("speed: 1.0", f"speed: {BIG}"),
    ("  6: [1, 3, 7, 11, 13, 15]", f"  {BIG}: [1, 3, 7, 11, 13, 15]"),
])
def test_integers_of_400_digits_are_refused_in_one_short_line(old, new):
    """YAML reads them as integers: float() of one raised OverflowError (a traceback), and
    the messages that printed them printed all 400 digits."""
    assert old in LAB
    with pytest.raises(ValueError) as info:
        Scene.from_text(LAB.replace(old, new, 1), "s.yaml")
    text = str(info.value)
    assert "\n" not in text and len(text) < 250 and not re.search(r"\d{17}", text), text
