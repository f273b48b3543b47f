"""The scanlines and tune commands on small synthetic render directories and videos."""

import argparse
import json

import cv2
import numpy as np
import pytest

import scene
from pipeline import Pipeline, PipelineParams, load_params
from pipeline.synthetic import degrade, synthetic_sequence, write_render_dir
from testbed.commands import scanlines as scanlines_cmd
from testbed.commands import tune as tune_cmd


def camtask(argv):
    """Parse and run one of our commands as ``camtask`` would (without importing the others)."""
    parser = argparse.ArgumentParser(prog="camtask")
    sub = parser.add_subparsers(dest="command", required=True)
    scanlines_cmd.add_parser(sub)
    tune_cmd.add_parser(sub)
    args = parser.parse_args(argv)
    return args.func(args)


def small_cameras():
    return [scene.Camera.from_pose(i + 1, [x, 0.05, 2.2], np.radians(90 + d), np.radians(15), 160, 120,
                                   np.radians(49), [-0.18, 0.06, 0, 0, 0])
            for i, (x, d) in enumerate([(1.5, -20), (5.0, 20)])]


def small_render_dir(root, frames: int, seed: int):
    """``root`` made a render directory of :func:`small_cameras` and ``frames`` synthetic
    frames drawn with ``seed``; returns it."""
    cams = small_cameras()
    bg, images, labels = synthetic_sequence(cams, frames, np.random.default_rng(seed))
    write_render_dir(root, cams, bg, images, labels)
    return root


@pytest.fixture(scope="module")
def sequence():
    cams = small_cameras()
    bg, frames, labels = synthetic_sequence(cams, 10, np.random.default_rng(5))
    return cams, bg, frames, labels


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory, sequence):
    root = tmp_path_factory.mktemp("render")
    write_render_dir(root, *sequence)
    return root


def test_scanlines_on_render_dir(render_dir, sequence, capsys, tmp_path):
    params = PipelineParams(column_threshold=3.0)
    params.to_yaml(tmp_path / "p.yaml")
    assert camtask(["scanlines", str(render_dir), "--params", str(tmp_path / "p.yaml"), "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["frames"] == 10 and m["cameras"] == 2
    assert m["f1"] > 0.85 and m["pixel"]["f1"] > 0.9
    assert len(m["per_camera"]) == 2 and {"precision", "recall", "f1", "pwc"} <= set(m["per_camera"][0])
    with np.load(render_dir / "scanlines.npz") as z:
        assert z["scanlines"].shape == z["gt_scanlines"].shape == (10, 2, 160)
        assert z["scanlines"].dtype == bool
        assert z["bearings"].shape == (2, 160)
        cams = sequence[0]
        np.testing.assert_allclose(z["bearings"], Pipeline(cams).bearings, atol=1e-6)
    assert camtask(["scanlines", str(render_dir), "--frames", "2", "--out", str(tmp_path / "s.npz")]) == 0
    text = capsys.readouterr().out
    assert "precision" in text and "bandwidth" in text
    assert np.load(tmp_path / "s.npz")["scanlines"].shape == (2, 2, 160)


def test_scanlines_writes_nothing_on_error(tmp_path, render_dir, sequence):
    broken = tmp_path / "broken"
    cams, bg, frames, labels = sequence
    write_render_dir(broken, cams, bg, frames[:2], labels[:2])
    img = cv2.imread(str(broken / "frames" / "cam02" / "000001.png"))
    cv2.imwrite(str(broken / "frames" / "cam02" / "000001.png"), img[:, :100])
    before = sorted(p.name for p in broken.iterdir())
    with pytest.raises(ValueError, match=r"frames: frames/cam02/000001.png is 100x120; expected 160x120 to match the calibration"):
        camtask(["scanlines", str(broken)])
    assert sorted(p.name for p in broken.iterdir()) == before
    (tmp_path / "bad.yaml").write_text("opening_kernel: 4\n")
    with pytest.raises(ValueError, match="opening_kernel: expected an odd integer"):
        camtask(["scanlines", str(render_dir), "--params", str(tmp_path / "bad.yaml")])


def test_scanlines_on_video(tmp_path, sequence, capsys):
    cams, bg, frames, _ = sequence
    path = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 7.5, (160, 120))
    assert writer.isOpened()
    for img in [bg[0]] * 3 + list(frames[:, 0]):
        writer.write(cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
    writer.release()
    write_render_dir(tmp_path / "r", cams[:1], bg[:1], frames[:1, :1], np.zeros((1, 1, 120, 160), int))
    calib = tmp_path / "r" / "calibration" / "cam01.yaml"
    params = PipelineParams(column_threshold=3.0, opening_kernel=3, median_kernel=5)
    params.to_yaml(tmp_path / "p.yaml")
    assert camtask(["scanlines", "--video", str(path), "--calibration", str(calib), "--background", "3",
                    "--params", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "v.npz"), "--json"]) == 0
    with np.load(tmp_path / "v.npz") as z:
        s = z["scanlines"]
        assert s.shape == (10, 1, 160) and z["bearings"].shape == (1, 160)
    # the same frames straight through the pipeline (no JPEG) agree on most columns
    pipe = Pipeline(cams[:1], params, np.stack([bg[:1]] * 3))
    direct = np.stack([pipe.process(f[:1]) for f in frames])
    assert (s == direct).mean() > 0.95 and s.any()
    # a folder of images works the same way
    folder = tmp_path / "imgs"
    folder.mkdir()
    for k, img in enumerate([bg[0]] * 2 + list(frames[:4, 0])):
        cv2.imwrite(str(folder / f"{k:04d}.png"), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
    assert camtask(["scanlines", "--video", str(folder), "--calibration", str(calib), "--background", "2",
                    "--json"]) == 0
    assert np.load(tmp_path / "imgs_scanlines.npz")["scanlines"].shape == (4, 1, 160)
    assert "is grey" not in capsys.readouterr().err
    grey = tmp_path / "grey"                       # the same images in grey: a warning, not silence
    grey.mkdir()
    for img in sorted(folder.iterdir()):
        cv2.imwrite(str(grey / img.name), cv2.cvtColor(cv2.imread(str(img), cv2.IMREAD_GRAYSCALE), cv2.COLOR_GRAY2BGR))
    assert camtask(["scanlines", "--video", str(grey), "--calibration", str(calib), "--background", "2",
                    "--json"]) == 0
    assert f"warning: --video: {grey} is grey (R = G = B)" in capsys.readouterr().err
    with pytest.raises(ValueError, match=r"--video: .*big/0.png is 80 x 60 pixels; --calibration .* is for 160 x 120"):
        big = tmp_path / "big"
        big.mkdir()
        for k in range(3):
            cv2.imwrite(str(big / f"{k}.png"), np.full((60, 80, 3), 90, np.uint8))
        camtask(["scanlines", "--video", str(big), "--calibration", str(calib), "--background", "1"])


def test_tune_beats_defaults_on_dark_noisy_scene(tmp_path, render_dir, sequence, capsys):
    """Parameters that do well on the clean scene do poorly when it is darker and noisier;
    tuning on the degraded scene beats them there."""
    cams, bg, frames, labels = sequence
    start = tmp_path / "start.yaml"
    PipelineParams(column_threshold=3.0, opening_kernel=3, median_kernel=5).to_yaml(start)
    assert camtask(["scanlines", str(render_dir), "--params", str(start), "--json",
                    "--out", str(tmp_path / "clean.npz")]) == 0
    clean_f1 = json.loads(capsys.readouterr().out)["f1"]
    rng = np.random.default_rng(11)
    dark = tmp_path / "dark"
    write_render_dir(dark, cams, degrade(bg, rng, 0.3, 6.0), degrade(frames, rng, 0.3, 6.0), labels)
    assert camtask(["scanlines", str(dark), "--params", str(start), "--json"]) == 0
    default_f1 = json.loads(capsys.readouterr().out)["f1"]
    assert clean_f1 > 0.85 and default_f1 < clean_f1 - 0.1
    out, plot = tmp_path / "best.yaml", tmp_path / "search.png"
    argv = ["tune", str(dark), "--trials", "25", "--seed", "3", "--params", str(start), "--json"]
    assert camtask(argv + ["--out", str(out), "--plot", str(plot)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["start_f1"] == pytest.approx(default_f1)
    assert result["best_f1"] > default_f1 + 0.1
    assert plot.stat().st_size > 1000
    assert f"--seed 3 --frames 10 --params {start}`" in out.read_text()     # the command that reproduces it
    tuned = load_params(out)
    assert camtask(["scanlines", str(dark), "--params", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["f1"] == pytest.approx(result["best_f1"])
    # reproducible under --seed
    assert camtask(argv + ["--out", str(tmp_path / "again.yaml")]) == 0
    capsys.readouterr()
    assert load_params(tmp_path / "again.yaml") == tuned


def test_tune_refuses_a_seed_optuna_cannot_take(tmp_path, render_dir):
    for seed in ("-1", str(2**32)):
        with pytest.raises(ValueError, match=f"--seed: expected an integer in 0..4294967295, got {seed}"):
            camtask(["tune", str(render_dir), "--trials", "1", "--seed", seed, "--out", str(tmp_path / "p.yaml")])
    assert not (tmp_path / "p.yaml").exists()


def test_scanlines_records_the_blind_radii_of_the_shortest_person(render_dir, tmp_path, capsys):
    import shutil

    root = tmp_path / "render"
    shutil.copytree(render_dir, root)
    (root / "scanlines.npz").unlink(missing_ok=True)
    assert camtask(["scanlines", str(root), "--frames", "1"]) == 0
    assert "blind_radius" not in np.load(root / "scanlines.npz").files          # no people.csv: no heights
    (root / "people.csv").write_text("frame,person_id,x,y,radius,height\n0,0,1.0,2.0,0.25,1.75\n"
                                     "0,1,3.0,2.0,0.25,1.6\n")
    capsys.readouterr()
    assert camtask(["scanlines", str(root), "--frames", "1", "--json"]) == 0
    from pipeline.io import RenderDir

    params = PipelineParams.from_mapping(json.loads(capsys.readouterr().out)["params"])
    pipe = Pipeline(RenderDir(root).cameras, params)            # the calibration as the command read it
    with np.load(root / "scanlines.npz") as z:
        for prefix, truth in (("", False), ("gt_", True)):
            near, far = pipe.sight_range(1.6, truth=truth, object_width=0.5)
            np.testing.assert_array_equal(z[f"{prefix}blind_radius"], near)
            np.testing.assert_array_equal(z[f"{prefix}sight_radius"], far)


def test_ctrl_c_during_tune_is_one_line(tmp_path, render_dir, monkeypatch, capsys):
    """Optuna logged the interrupted trial with its traceback ("Trial 3 failed ...") before
    camtask's "interrupted" line: a page for every Ctrl-C."""
    from pipeline import tuning
    from testbed.cli import main

    real, calls = tuning.scanline_f1, []

    def interrupted(*a, **k):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(tuning, "scanline_f1", interrupted)
    capsys.readouterr()
    assert main(["tune", str(render_dir), "--trials", "5", "--out", str(tmp_path / "p.yaml")]) == 130
    err = capsys.readouterr().err
    lines = [x for x in err.replace("\r", "\n").splitlines() if x.strip() and not x.startswith("tune:")]
    assert lines == ["camtask tune: interrupted"], err
    assert not (tmp_path / "p.yaml").exists()
