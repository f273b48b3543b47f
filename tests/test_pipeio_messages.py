"""Errors of the pipeline's readers name what the user gave: DIR, --video, or the file."""

import argparse
import os

import cv2
import numpy as np
import pytest

import scene
from pipeline.io import RenderDir, iter_video_frames, read_labels
from pipeline.synthetic import synthetic_sequence, write_render_dir
from testbed.commands import scanlines as scanlines_cmd


def camtask(argv):
    parser = argparse.ArgumentParser(prog="camtask")
    scanlines_cmd.add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory):
    cams = [scene.Camera.from_pose(1, [1.5, 0.05, 2.2], np.radians(70), np.radians(15), 160, 120,
                                   np.radians(49), [0, 0, 0, 0, 0])]
    root = tmp_path_factory.mktemp("render")
    write_render_dir(root, cams, *synthetic_sequence(cams, 2, np.random.default_rng(0)))
    return root


def test_render_dir_errors_name_dir(tmp_path, render_dir):
    with pytest.raises(FileNotFoundError, match=r"^DIR: no such folder '.*nothere'$"):
        RenderDir(tmp_path / "nothere")
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ValueError, match=r"^DIR: '.*afile' is a file, not a folder"):
        RenderDir(tmp_path / "afile")
    with pytest.raises(ValueError, match=r"^DIR: .* is not a render directory: it has no calibration/camNN.yaml"):
        RenderDir(tmp_path)
    with pytest.raises(FileNotFoundError, match=r"^--dir: no such folder"):
        RenderDir(tmp_path / "nothere", name="--dir")
    assert len(RenderDir(render_dir)) == 2


def test_scanlines_names_dir(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ValueError, match=r"^DIR: '.*afile' is a file, not a folder"):
        camtask(["scanlines", str(tmp_path / "afile"), "--out", str(tmp_path / "s.npz")])


def test_silhouette_that_cannot_be_read_is_not_called_a_mask(tmp_path):
    path = tmp_path / "silhouettes" / "cam01" / "000000.png"
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not a png")
    with pytest.raises(ValueError, match=r"^label image: cannot read '.*silhouettes/cam01/000000.png'$"):
        read_labels(path)


def test_video_errors_name_the_option(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"^--video: no such file or folder '.*nothere'$"):
        next(iter_video_frames(tmp_path / "nothere"))
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match=r"^--video: folder '.*empty' has no images \(.png, "):
        next(iter_video_frames(tmp_path / "empty"))
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "0.png").write_bytes(b"not a png")
    with pytest.raises(ValueError, match=r"^--video: cannot read '.*bad/0.png'$"):
        next(iter_video_frames(tmp_path / "bad"))
    (tmp_path / "clip.mp4").write_text("not a video")
    with pytest.raises(ValueError, match=r"^--video: cannot read '.*clip.mp4': Error opening input files: Invalid "
                                         r"data found when processing input \(not a video ffmpeg can open, or corrupt\)$"):
        next(iter_video_frames(tmp_path / "clip.mp4"))
    os.mkfifo(tmp_path / "pipe")
    with pytest.raises(ValueError, match=r"^--video: '.*pipe' is neither a video file nor a folder of images$"):
        next(iter_video_frames(tmp_path / "pipe"))
    cv2.imwrite(str(tmp_path / "bad" / "0.png"), np.zeros((4, 6, 3), np.uint8))
    assert next(iter_video_frames(tmp_path / "bad")).shape == (4, 6, 3)


def test_frames_of_a_camera_without_its_calibration_are_refused(tmp_path):
    """A render directory whose calibration/cam02.yaml was lost ran on the other cameras,
    leaving camera 2's frames out without a word."""
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 1, 4)
    lost = max((tmp_path / "calibration").glob("cam*.yaml"))
    lost.unlink()
    with pytest.raises(ValueError, match=rf"^DIR: frames/{lost.stem} has no calibration/{lost.stem}.yaml; "):
        RenderDir(tmp_path)


def test_a_folder_of_images_is_read_in_the_order_of_their_numbers(tmp_path):
    """frame10.png came before frame2.png (sorted as text): unpadded numbers put the frames out of time
    order, which the temporal smoothing then mixed up, without a word."""
    folder = tmp_path / "clip"
    folder.mkdir()
    for i in (1, 2, 3, 10, 11, 20):
        cv2.imwrite(str(folder / f"frame{i}.png"), np.full((4, 6, 3), i, np.uint8))
    cv2.imwrite(str(folder / "frame010b.png"), np.full((4, 6, 3), 99, np.uint8))   # after frame10: same number, longer
    order = [int(f[0, 0, 0]) for f in iter_video_frames(folder)]
    assert order == [1, 2, 3, 10, 99, 11, 20]


def test_cameras_numbered_past_99_are_read_in_number_order(tmp_path):
    """calibration/cam100.yaml sorts between cam10 and cam11 as text: `camtask scanlines` on
    an episode of 100 or more cameras wrote them in that order, not the render's number order,
    so its scanlines.npz no longer equalled the episode's own (camera_numbers, rows)."""
    cams = [scene.Camera.from_pose(n, [1.0 + 0.01 * n, 0.05, 2.2], np.radians(70), np.radians(15), 32, 24,
                                   np.radians(49), [0, 0, 0, 0, 0]) for n in (100, 9, 11, 10)]
    write_render_dir(tmp_path, cams, *synthetic_sequence(cams, 1, np.random.default_rng(0)))
    out = tmp_path / "s.npz"
    camtask(["scanlines", str(tmp_path), "--out", str(out), "--params", str(small_params(tmp_path)), "--json"])
    assert [c.number for c in RenderDir(tmp_path).cameras] == [9, 10, 11, 100]
    assert np.load(out)["camera_numbers"].tolist() == [9, 10, 11, 100]


def small_params(folder):
    path = folder / "params.yaml"
    path.write_text("opening_kernel: 1\nmedian_kernel: 1\ncolumn_threshold: 2.0\n")
    return path


def test_a_label_image_saved_in_colour_reads_as_its_labels(tmp_path):
    """A grey label image saved as RGB (three equal channels), 8 or 16 bit: the labels, (H, W)."""
    labels = np.array([[0, 1, 2], [3, 0, 300]])
    for depth in (np.uint8, np.uint16):
        want = labels if depth == np.uint16 else labels % 256
        path = tmp_path / f"{depth.__name__}.png"
        cv2.imwrite(str(path), np.repeat(want.astype(depth)[..., None], 3, axis=2))
        assert cv2.imread(str(path), cv2.IMREAD_UNCHANGED).shape == (2, 3, 3)
        got = read_labels(path)
        assert got.shape == (2, 3) and got.dtype == np.int32
        assert got.tolist() == want.tolist()


def test_camera_folders_without_frames_are_refused(tmp_path):
    """frames/camNN folders that hold no PNG (and no frames/camNN.mkv beside them)."""
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 2, 4)
    for png in (tmp_path / "frames").glob("cam*/*.png"):
        png.unlink()
    with pytest.raises(ValueError) as err:
        RenderDir(tmp_path)
    assert str(err.value) == f"DIR: {tmp_path / 'frames' / 'cam01'} has no frames"
    # no masks either for the videos of `render --format video`
    (tmp_path / "frames" / "cam01.mkv").write_bytes(b"")
    for png in (tmp_path / "masks").glob("cam*/*.png"):
        png.unlink()
    with pytest.raises(ValueError) as err:
        RenderDir(tmp_path, name="--dir")
    assert str(err.value) == f"--dir: {tmp_path / 'masks' / 'cam01'} has no frames"
