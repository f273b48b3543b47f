"""camtask scanlines: --video, --calibration and --background as their help and docs/pipeline.md say."""

import argparse
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from testbed.cli import UsageError
from testbed.commands import scanlines as scanlines_cmd
from tests.test_pipeline_cli import camtask, small_render_dir


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory):
    return small_render_dir(tmp_path_factory.mktemp("render"), 4, 3)


def video_args(render_dir, background, *extra):
    return ["scanlines", "--video", str(render_dir / "frames" / "cam01"), "--calibration",
            str(render_dir / "calibration" / "cam01.yaml"), "--background", str(background), *extra]


@pytest.mark.parametrize(("extra", "named"), [
    (["--background", "2"], "--background goes"),
    (["--calibration", "c.yaml", "--background", "2"], "--calibration and --background go"),
])
def test_video_options_given_with_a_render_directory_are_refused(render_dir, tmp_path, extra, named):
    """They were ignored without a word: the run used DIR's own background and calibration."""
    with pytest.raises(UsageError, match=f"^{named} with --video, not with DIR"):
        camtask(["scanlines", str(render_dir), "--out", str(tmp_path / "s.npz"), *extra])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("background", [4, 9])
def test_a_video_of_background_only_names_the_options(render_dir, tmp_path, background):
    """It said "frames: expected at least one frame after the background", naming no option."""
    with pytest.raises(ValueError, match=rf"^--background {background}: --video .*cam01 has 4 frames; "
                                         rf"expected more than the {background} background frames$"):
        camtask(video_args(render_dir, background, "--out", str(tmp_path / "s.npz")))
    assert list(tmp_path.iterdir()) == []


def test_frames_counts_the_frames_after_the_background(render_dir, tmp_path):
    for frames, expected in ((1, 1), (5, 2)):
        out = tmp_path / f"s{frames}.npz"
        assert camtask(video_args(render_dir, 2, "--frames", str(frames), "--out", str(out), "--json")) == 0
        assert np.load(out)["scanlines"].shape == (expected, 1, 160)


def test_help_usage_and_docs_name_the_same_arguments():
    parser = argparse.ArgumentParser(prog="camtask")
    scanlines_cmd.add_parser(parser.add_subparsers())
    text = " ".join(parser._subparsers._group_actions[0].choices["scanlines"].format_usage().split())
    usage = ("--video FILE_OR_FOLDER --calibration cam.yaml --background N [--params FILE] [--frames N] "
             "[--out FILE.npz] [--json]")
    for option in ("[--frames N]", "[--out FILE]", "[--video FILE_OR_FOLDER]", "[--calibration FILE]",
                   "[--background N]"):
        assert option in text
    docs = (Path(__file__).parents[1] / "docs" / "pipeline.md").read_text()
    assert f"camtask scanlines {usage}" in docs
    assert f"camtask scanlines {usage}" in " ".join(scanlines_cmd.__doc__.split())
    assert not re.search(r"--(frames|background) (FRAMES|BACKGROUND)", docs + scanlines_cmd.__doc__)


def test_frames_of_another_size_than_the_calibration_name_the_frame_and_both_options(render_dir, tmp_path):
    """They said "frames: expected shape ..." or "background: expected shape ...", naming no option
    (--frames and --background are counts) nor the frame; a mixed folder gave numpy's stack error."""
    import cv2

    from testbed.lossless import VideoWriter

    calib = str(render_dir / "calibration" / "cam01.yaml")
    folder = tmp_path / "mixed"
    shutil.copytree(render_dir / "frames" / "cam01", folder)
    names = sorted(p.name for p in folder.iterdir())
    for name in (names[0], names[2]):
        image = cv2.imread(str(folder / name))
        cv2.imwrite(str(folder / name), cv2.resize(image, (80, 60)))
    for background, bad in ((2, names[0]), (1, names[0])):
        with pytest.raises(ValueError, match=rf"^--video: {re.escape(str(folder / bad))} is 80 x 60 pixels; "
                                             rf"--calibration {re.escape(calib)} is for 160 x 120$"):
            camtask(["scanlines", "--video", str(folder), "--calibration", calib, "--background", str(background),
                     "--out", str(tmp_path / "s.npz")])
    cv2.imwrite(str(folder / names[0]), cv2.imread(str(render_dir / "frames" / "cam01" / names[0])))
    with pytest.raises(ValueError, match=rf"^--video: .*mixed/{names[2]} is 80 x 60 pixels"):   # after the background
        camtask(["scanlines", "--video", str(folder), "--calibration", calib, "--background", "1",
                 "--out", str(tmp_path / "s.npz")])
    video = tmp_path / "small.mkv"
    w = VideoWriter(video, 80, 60, 7.5)
    for _ in range(3):
        w.write(np.zeros((60, 80, 3), np.uint8))
    w.close()
    with pytest.raises(ValueError, match=r"^--video: frame 0 \(from 0, background frames included\) of .*small.mkv "
                                         r"is 80 x 60 pixels; --calibration .* is for 160 x 120$"):
        camtask(["scanlines", "--video", str(video), "--calibration", calib, "--background", "1",
                 "--out", str(tmp_path / "s.npz")])
    assert not (tmp_path / "s.npz").exists()


def test_a_bad_calibration_file_names_the_option(tmp_path, capsys):
    """`--calibration x` missing or not a calibration said "calibration: ...", not the option."""
    from testbed import cli

    video = tmp_path / "frames"
    video.mkdir()
    (tmp_path / "cam.yaml").write_text("hello\n")
    for calibration, why in ((tmp_path / "none.yaml", "no such file"), (tmp_path / "cam.yaml", "cam.yaml is not")):
        assert cli.main(["scanlines", "--video", str(video), "--calibration", str(calibration),
                         "--background", "1"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"camtask scanlines: error: --calibration: {why}"), err


def folding_copy(render_dir, root):
    """A copy of ``render_dir`` in ``root`` whose cam01 has k1 = -0.5: on its 160 x 120 image
    the lens folds over (pipeline.rectify.check_lens), yet every column still spans its height."""
    import dataclasses

    from pipeline.io import load_calibration
    from testbed.dataset import write_calibration

    copy = root / "render"
    shutil.copytree(render_dir, copy)
    path = copy / "calibration" / "cam01.yaml"
    cam = load_calibration(path)
    write_calibration(path, dataclasses.replace(cam, dist=np.array([-0.5, 0.0, 0.0, 0.0, 0.0])))
    return copy


def test_a_lens_that_folds_over_is_refused_before_any_frame(render_dir, tmp_path):
    """`camtask render` and `run` refuse such a lens; `scanlines` remapped with it and wrote
    scanlines and bearings of rays the lens renders twice, without a word."""
    bad = folding_copy(render_dir, tmp_path)
    out = tmp_path / "s.npz"
    with pytest.raises(ValueError, match=r"^DIR: .*cam01\.yaml: camera 1: its lens distortion \[-0\.5, .*folds over"):
        camtask(["scanlines", str(bad), "--out", str(out)])
    with pytest.raises(ValueError, match=r"^--calibration: .*cam01\.yaml: camera 1: its lens distortion .*folds over"):
        camtask(["scanlines", "--video", str(bad / "frames" / "cam01"), "--calibration",
                 str(bad / "calibration" / "cam01.yaml"), "--background", "1", "--out", str(out)])
    with pytest.raises(ValueError, match=r"^DIR: .*cam01\.yaml: camera 1: its lens distortion .*folds over"):
        camtask(["tune", str(bad), "--trials", "1", "--out", str(tmp_path / "p.yaml")])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["render"]


def test_a_column_threshold_above_every_column_is_refused(render_dir, tmp_path):
    """Every scanline would be empty: `render` and `run` refuse it; `scanlines --video` wrote
    them, with no metric to show that nothing could ever be sent."""
    from pipeline.rectify import level_cameras

    rows = level_cameras(small_cameras_of(render_dir))[1]
    params = tmp_path / "p.yaml"
    params.write_text(f"column_threshold: {rows + 1}\n")
    out = tmp_path / "s.npz"
    message = rf"^--params: column_threshold {rows + 1} is not below the {rows} pixels of a rectified column"
    with pytest.raises(ValueError, match=message):
        camtask(video_args(render_dir, 1, "--params", str(params), "--out", str(out)))
    with pytest.raises(ValueError, match=message):
        camtask(["scanlines", str(render_dir), "--params", str(params), "--out", str(out)])
    assert not out.exists()


def small_cameras_of(render_dir):
    from pipeline.io import RenderDir

    return RenderDir(render_dir).cameras


def test_cameras_of_two_resolutions_are_named_by_their_files(render_dir, tmp_path):
    """It said 'cameras: expected every camera to have the same resolution', naming neither DIR nor a file."""
    import dataclasses

    from pipeline.io import load_calibration
    from testbed.dataset import write_calibration

    copy = tmp_path / "render"
    shutil.copytree(render_dir, copy)
    names = sorted(p.name for p in (copy / "calibration").glob("cam*.yaml"))
    path = copy / "calibration" / names[-1]
    cam = load_calibration(path)
    K = cam.K.copy()
    K[:2] *= 2
    write_calibration(path, dataclasses.replace(cam, K=K, width=2 * cam.width, height=2 * cam.height))
    with pytest.raises(ValueError) as err:
        camtask(["scanlines", str(copy), "--out", str(tmp_path / "s.npz")])
    assert str(err.value) == (f"DIR: calibration/{names[-1]} is {2 * cam.width}x{2 * cam.height} pixels, "
                              f"calibration/{names[0]} {cam.width}x{cam.height}; the node pipeline takes "
                              "cameras of one resolution")


def test_a_frame_of_another_size_is_named_in_a_folder_whose_numbers_are_unpadded(render_dir, tmp_path):
    """The frames are read in the order of the numbers in their names (frame2 before frame10),
    but the message took the name from the folder sorted as text: a wrong frame2.png was
    reported as frame10.png."""
    import cv2

    calib = str(render_dir / "calibration" / "cam01.yaml")
    image = cv2.imread(str(min((render_dir / "frames" / "cam01").iterdir())))
    folder = tmp_path / "unpadded"
    folder.mkdir()
    for i in range(12):
        cv2.imwrite(str(folder / f"frame{i}.png"), cv2.resize(image, (80, 60)) if i == 2 else image)
    with pytest.raises(ValueError, match=rf"^--video: {re.escape(str(folder / 'frame2.png'))} is 80 x 60 pixels"):
        camtask(["scanlines", "--video", str(folder), "--calibration", calib, "--background", "1",
                 "--out", str(tmp_path / "s.npz")])


@pytest.mark.parametrize(("damage", "reason"), [
    (lambda data: data[: len(data) * 2 // 3], "File ended prematurely"),
    (lambda data: data[: len(data) // 2] + bytes([data[len(data) // 2] ^ 0xFF]) + data[len(data) // 2 + 1:],
     "slice CRC mismatch"),
])
def test_a_truncated_or_corrupt_video_is_one_line_naming_it(render_dir, tmp_path, damage, reason, capfd):
    """cv2.VideoCapture decoded a slice whose CRC failed as ffmpeg concealed it, and the run
    ended with exit code 0 and scanlines of the damaged frame; a truncated video was
    'has 1 frame; expected more than the 1 background frames'; both put ffmpeg's own lines,
    pointer addresses and all, on stderr."""
    import cv2

    from testbed.lossless import VideoWriter

    folder = render_dir / "frames" / "cam01"
    images = [cv2.imread(str(p))[..., ::-1] for p in sorted(folder.iterdir())]
    video = tmp_path / "cam01.mkv"
    w = VideoWriter(video, images[0].shape[1], images[0].shape[0], 7.5)
    for image in images:
        w.write(image)
    w.close()
    out = tmp_path / "s.npz"
    args = ["scanlines", "--video", str(video), "--calibration", str(render_dir / "calibration" / "cam01.yaml"),
            "--background", "1", "--out", str(out), "--json"]
    assert camtask(args) == 0                       # the sound video reads as its PNG frames do
    with np.load(out) as z:
        sound = z["scanlines"]
    assert camtask(args[:2] + [str(folder)] + args[3:]) == 0
    np.testing.assert_array_equal(np.load(out)["scanlines"], sound)
    out.unlink()
    capfd.readouterr()
    video.write_bytes(damage(video.read_bytes()))
    with pytest.raises(ValueError, match=rf"^--video: cannot read '{re.escape(str(video))}' after \d+ frames?: "
                                         rf"{reason}.* \(truncated or corrupt\)$"):
        camtask(args)
    assert not out.exists() and " @ 0x" not in capfd.readouterr().err


def test_the_json_names_the_parameters_and_the_file_of_the_run(render_dir, tmp_path, capsys):
    """A video's scanlines.npz holds the number of its calibration's camera; --json prints
    the parameters used (not the defaults) and the output file, and no progress bar."""
    from pipeline import load_params

    params = tmp_path / "p.yaml"
    params.write_text("opening_kernel: 5\ncolumn_threshold: 2.5\n")
    for argv in (["scanlines", str(render_dir)],
                 ["scanlines", "--video", str(render_dir / "frames" / "cam02"), "--calibration",
                  str(render_dir / "calibration" / "cam02.yaml"), "--background", "1"]):
        out = tmp_path / "s.npz"
        capsys.readouterr()
        assert camtask(argv + ["--params", str(params), "--out", str(out), "--json"]) == 0
        printed = capsys.readouterr()
        assert printed.err == ""
        m = json.loads(printed.out)
        assert m["params"] == load_params(params).to_dict() and m["out"] == str(out)
    assert np.load(out)["camera_numbers"].tolist() == [2]


def test_a_video_of_one_background_frame_says_frame(render_dir, tmp_path):
    folder = tmp_path / "one"
    folder.mkdir()
    shutil.copy(min((render_dir / "frames" / "cam01").iterdir()), folder)
    with pytest.raises(ValueError, match=r"^--background 1: --video .*one has 1 frame; expected more than the 1 "
                                         r"background frames$"):
        camtask(["scanlines", "--video", str(folder), *video_args(render_dir, 1)[3:], "--out", str(tmp_path / "s.npz")])


@pytest.mark.parametrize("size", [(160, 60), (80, 120)])
def test_frames_as_wide_or_as_tall_as_the_calibration_are_still_refused(render_dir, tmp_path, size):
    """Frames of the calibration's height but another width, or its width but another height."""
    import cv2

    folder = tmp_path / "frames"
    shutil.copytree(render_dir / "frames" / "cam01", folder)
    last = max(folder.iterdir())
    cv2.imwrite(str(last), cv2.resize(cv2.imread(str(last)), size))
    with pytest.raises(ValueError, match=rf"^--video: {re.escape(str(last))} is {size[0]} x {size[1]} pixels; "):
        camtask(["scanlines", "--video", str(folder), *video_args(render_dir, 1)[3:],
                 "--out", str(tmp_path / "s.npz")])
    assert not (tmp_path / "s.npz").exists()


def test_frames_with_two_equal_channels_only_are_not_grey(render_dir, tmp_path, capsys):
    """R = G but B otherwise is a colour: no warning that the colour angle cannot tell pixels apart."""
    import cv2

    folder = tmp_path / "frames"
    folder.mkdir()
    for path in sorted((render_dir / "frames" / "cam01").iterdir()):
        image = cv2.imread(str(path))
        image[..., 1] = image[..., 2]                           # BGR: G = R, B as it was
        cv2.imwrite(str(folder / path.name), image)
    capsys.readouterr()
    assert camtask(["scanlines", "--video", str(folder), *video_args(render_dir, 1)[3:],
                    "--out", str(tmp_path / "s.npz"), "--json"]) == 0
    assert "grey" not in capsys.readouterr().err


def test_the_background_is_all_the_background_frames(render_dir, tmp_path):
    """--background 3 makes the background model of the first three frames, not of the first alone."""
    from pipeline import Pipeline, PipelineParams
    from pipeline.io import iter_video_frames, load_calibration
    from pipeline.runs import run_sequence

    folder = tmp_path / "frames"
    folder.mkdir()
    frames = sorted((render_dir / "frames" / "cam01").iterdir())
    for k, path in enumerate([frames[1], render_dir / "background" / "cam01.png",
                              render_dir / "background" / "cam01.png", *frames]):
        shutil.copy(path, folder / f"{k:02d}.png")
    out = tmp_path / "s.npz"
    assert camtask(["scanlines", "--video", str(folder), *video_args(render_dir, 3)[3:],
                    "--out", str(out), "--json"]) == 0
    images = np.stack(list(iter_video_frames(folder)))
    pipe = Pipeline([load_calibration(render_dir / "calibration" / "cam01.yaml")], PipelineParams(),
                    images[:3, None])
    expected = run_sequence(pipe, images[3:, None]).scanlines
    assert expected.any()
    np.testing.assert_array_equal(np.load(out)["scanlines"], expected)


def test_the_table_prints_each_cameras_metrics_and_their_totals(render_dir, tmp_path, capsys):
    """Without --json: a row per camera (its number, then precision, recall, F1, PWC and pixel
    F1), a row of all of them and the pixels' metrics, as --json gives them."""
    out = tmp_path / "s.npz"
    capsys.readouterr()
    assert camtask(["scanlines", str(render_dir), "--out", str(out), "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert camtask(["scanlines", str(render_dir), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    assert "4/4" in printed.err                                  # the progress bar counts to the frames
    lines = printed.out.splitlines()
    assert lines[0] == f"4 frames x 2 cameras -> {out}"
    assert re.fullmatch(r"bandwidth: RLE ([\d.]+) bits per scanline on average \(max (\d+)\), raw 160",
                        lines[1]).groups() == (f"{m['rle_bits_mean']:.1f}", str(m["rle_bits_max"]))
    assert lines[2].split() == ["camera", "precision", "recall", "F1", "PWC", "pixel", "F1"]
    rows = [(c["precision"], c["recall"], c["f1"], c["pwc"], px["f1"])
            for c, px in zip(m["per_camera"], m["pixel"]["per_camera"])]
    rows.append((m["precision"], m["recall"], m["f1"], m["pwc"], m["pixel"]["f1"]))
    assert len(lines) == 7
    printed = 5e-4 + 1e-9, 5e-4 + 1e-9, 5e-4 + 1e-9, 5e-3 + 1e-9, 5e-4 + 1e-9     # to 3 decimals, PWC to 2
    for line, name, row in zip(lines[3:6], ["1", "2", "all"], rows):
        assert line.split()[0] == name
        assert np.all(np.abs(np.array(line.split()[1:], float) - row) <= printed), (line, row)
    px = m["pixel"]
    words = lines[6].split()
    assert words[0] == "pixels:" and words[1::2] == ["precision", "recall", "F1", "PWC"]
    assert np.all(np.abs(np.array(words[2::2], float) - [px["precision"], px["recall"], px["f1"], px["pwc"]])
                  <= [5e-4 + 1e-9] * 3 + [5e-3 + 1e-9]), (lines[6], px)
