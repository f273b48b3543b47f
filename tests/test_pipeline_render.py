"""End to end on a few rendered lab frames (needs OpenGL: EGL or OSMesa)."""

import argparse
import json

import numpy as np
import pytest

import scene
from pipeline import Pipeline, load_params
from pipeline.synthetic import write_render_dir

pytestmark = pytest.mark.render


def camtask(argv):
    from testbed.commands import scanlines

    parser = argparse.ArgumentParser(prog="camtask")
    scanlines.add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


@pytest.fixture(scope="module")
def lab_render(tmp_path_factory):
    render = pytest.importorskip("render")
    from scene.motion import random_waypoint

    sc = scene.load_scene("lab")
    rng = np.random.default_rng(7)
    people = sc.people
    pos = random_waypoint(sc.room.polygon, np.full(people.count, people.radius), 3, sc.dt, people.speed, rng)
    try:
        renderer = render.Renderer(sc)
    except Exception as exc:  # no GL backend on this machine
        pytest.skip(f"renderer unavailable: {exc}")
    with renderer:
        bg = renderer.background().rgb
        shots = [renderer.render(p, rng=rng) for p in pos]
    root = tmp_path_factory.mktemp("lab")
    write_render_dir(root, sc.cameras, bg, np.stack([s.rgb for s in shots]), np.stack([s.labels for s in shots]))
    return root, sc


def test_scanlines_on_rendered_lab(lab_render, capsys):
    root, sc = lab_render
    assert camtask(["scanlines", str(root), "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["cameras"] == 16 and m["width"] == 640
    assert m["pixel"]["f1"] > 0.95
    assert m["recall"] > 0.95 and m["f1"] > 0.9
    with np.load(root / "scanlines.npz") as z:
        assert z["scanlines"].shape == (3, 16, 640)
        np.testing.assert_allclose(z["bearings"], Pipeline(sc.cameras, load_params()).bearings)
