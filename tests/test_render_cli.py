"""camtask render: the layout on disk, calibration round trip, refusal, backend error."""

import json

import cv2
import numpy as np
import pytest

from testbed.cli import main
from testbed.dataset import read_calibration, read_people


@pytest.mark.render
def test_render_command_writes_layout(lab, tmp_path):
    top = tmp_path / "ds"
    assert main(["render", "lab", "--frames", "2", "--seed", "3", "--out", str(top), "--cameras", "2,7",
                 "--workers", "0"]) == 0
    out = top / "episode_0000"
    for name in ("cam02", "cam07"):
        for f in ("000000.png", "000001.png"):
            rgb = cv2.imread(str(out / "frames" / name / f))
            labels = cv2.imread(str(out / "masks" / name / f), cv2.IMREAD_UNCHANGED)
            assert rgb.shape == (480, 640, 3) and labels.shape == (480, 640) and labels.dtype == np.uint8
        assert (out / "background" / f"{name}.png").is_file()
    assert not (out / "frames" / "cam01").exists()
    for number in (2, 7):
        cam = lab.cameras[number - 1]
        c = read_calibration(out / "calibration" / f"cam{number:02d}.yaml")
        R, _ = cv2.Rodrigues(c["rvec"])
        np.testing.assert_allclose(c["K"], cam.K)
        np.testing.assert_allclose(c["dist"], cam.dist)
        np.testing.assert_allclose(R, cam.R, atol=1e-12)
        np.testing.assert_allclose(c["tvec"], cam.t)
        assert (c["width"], c["height"]) == (640, 480)
    people = read_people(out / "people.csv")
    assert len(people) == 2 * lab.people.count and set(people["frame"]) == {0, 1}
    meta = json.loads((out / "meta.json").read_text())
    assert meta["seed"] == 3 and meta["frames"] == 2 and meta["cameras"] == [2, 7]
    # same seed, same bytes
    again = tmp_path / "again" / "episode_0000"
    assert main(["render", "lab", "--frames", "2", "--seed", "3", "--out", str(again.parent), "--cameras", "2,7",
                 "--workers", "0"]) == 0
    for p in sorted(out.rglob("*.png")) + [out / "people.csv"]:
        assert p.read_bytes() == (again / p.relative_to(out)).read_bytes(), p
    assert not list(top.glob(".*tmp"))                      # no temporary folder left


def test_existing_output_dir_is_refused(tmp_path, capsys):
    out = tmp_path / "ds"
    out.mkdir()
    (out / "keep.txt").write_text("x")
    assert main(["render", "lab", "--frames", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "not empty" in err and "--overwrite" in err
    assert (out / "keep.txt").read_text() == "x"


def test_missing_gl_libraries_give_one_clear_error(monkeypatch):
    from render import gl

    monkeypatch.setattr(gl, "_CONTEXT", None)
    monkeypatch.setattr(gl, "_imported_platform", lambda: None)
    monkeypatch.setattr(gl, "probe", lambda backend: {"egl": "libEGL.so.1", "osmesa": "libOSMesa.so.8"}[backend])
    with pytest.raises(gl.BackendError) as err:
        gl.select_backend("egl")
    msg = str(err.value)
    assert "libEGL.so.1" in msg and "libOSMesa.so.8" in msg
    assert "apt-get install -y libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri libxrender1" in msg
    assert "apt-get install -y libosmesa6" in msg


def test_osmesa_is_the_fallback_when_egl_is_missing(monkeypatch):
    from render import gl

    monkeypatch.setattr(gl, "_CONTEXT", None)
    monkeypatch.setattr(gl, "_imported_platform", lambda: None)
    monkeypatch.setattr(gl, "probe", lambda backend: "libEGL.so.1" if backend == "egl" else None)
    assert gl.select_backend("egl") == "osmesa"
    with pytest.raises(ValueError, match="egl, osmesa"):
        gl.select_backend("vulkan")
