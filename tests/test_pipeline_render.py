"""End to end: `camtask render` a few lab frames, then `camtask scanlines` (needs OpenGL)."""

import json

import numpy as np
import pytest

import scene
from pipeline import Pipeline, load_params

pytestmark = pytest.mark.render


@pytest.fixture(scope="module")
def lab_render(tmp_path_factory):
    from testbed.cli import main

    out = tmp_path_factory.mktemp("lab") / "render"
    assert main(["render", "lab", "--frames", "3", "--seed", "5", "--out", str(out), "--workers", "0"]) == 0
    return out / "episode_0000"


def test_scanlines_on_rendered_lab(lab_render, capsys, tmp_path):
    from testbed.cli import main

    capsys.readouterr()
    out = tmp_path / "scanlines.npz"
    assert main(["scanlines", str(lab_render), "--out", str(out), "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["cameras"] == 16 and m["width"] == 640 and m["frames"] == 3
    assert m["pixel"]["f1"] > 0.95
    assert m["f1"] > 0.95
    with np.load(out) as z:
        assert z["scanlines"].shape == z["gt_scanlines"].shape == (3, 16, 640)
        cams = scene.load_scene("lab").cameras
        np.testing.assert_allclose(z["bearings"], Pipeline(cams, load_params()).bearings, atol=1e-9)
