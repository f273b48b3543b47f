"""testbed.dataset.read_calibration: the arrays back, or one line naming the file and key."""

import cv2
import numpy as np
import pytest

from scene import load_scene
from testbed.dataset import read_calibration, write_calibration


def test_round_trip(tmp_path):
    cam = load_scene("lab").cameras[2]
    write_calibration(tmp_path / "cam03.yaml", cam)
    c = read_calibration(tmp_path / "cam03.yaml")
    np.testing.assert_allclose(c["K"], cam.K)
    np.testing.assert_allclose(c["dist"], np.ravel(cam.dist))
    np.testing.assert_allclose(c["tvec"], np.ravel(cam.t))
    R, _ = cv2.Rodrigues(c["rvec"])                     # the rotation back, not only its vector
    np.testing.assert_allclose(R, cam.R, atol=1e-12)
    assert (c["width"], c["height"]) == (cam.width, cam.height)


def test_the_arrays_have_the_documented_shapes(tmp_path):
    """K (3, 3); dist, rvec and tvec flat (5,), (3,), (3,), as the file's 1x5 and 3x1 are not."""
    write_calibration(tmp_path / "cam01.yaml", load_scene("lab").cameras[0])
    c = read_calibration(tmp_path / "cam01.yaml")
    assert [c[k].shape for k in ("K", "dist", "rvec", "tvec")] == [(3, 3), (5,), (3,), (3,)]
    assert type(c["width"]) is int and type(c["height"]) is int


def test_missing_file_is_one_line_naming_it(tmp_path):
    with pytest.raises(FileNotFoundError, match="cam05.yaml") as exc:
        read_calibration(tmp_path / "cam05.yaml")
    assert "\n" not in str(exc.value)


def test_missing_key_is_one_line_naming_it(tmp_path):
    cam = load_scene("lab").cameras[0]
    path = tmp_path / "cam01.yaml"
    write_calibration(path, cam)
    text = path.read_text()
    cut = text.index("tvec:")
    path.write_text(text[:cut])                         # tvec and what follows gone
    with pytest.raises(ValueError, match="cam01.yaml.*tvec"):
        read_calibration(path)


def test_the_file_holds_the_documented_shapes_and_camera_number(tmp_path):
    """docs/dataset.md: distortion_coefficients 1x5, rvec and tvec 3x1, camera_number."""
    cam = load_scene("lab").cameras[6]
    write_calibration(tmp_path / "cam07.yaml", cam)
    fs = cv2.FileStorage(str(tmp_path / "cam07.yaml"), cv2.FILE_STORAGE_READ)
    try:
        assert fs.getNode("camera_number").real() == 7
        assert fs.getNode("camera_matrix").mat().shape == (3, 3)
        assert fs.getNode("distortion_coefficients").mat().shape == (1, 5)
        assert fs.getNode("rvec").mat().shape == (3, 1) and fs.getNode("tvec").mat().shape == (3, 1)
        assert (fs.getNode("image_width").real(), fs.getNode("image_height").real()) == (640, 480)
    finally:
        fs.release()
