"""Errors of the pipeline's readers name what the user gave: DIR, --video, or the file."""

import argparse
import os

import cv2
import numpy as np
import pytest

import scene
from pipeline.io import RenderDir, iter_video_frames, number_in_name, read_labels
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
    (tmp_path / "frames" / "cam01.mkv").mkdir()                # a folder so named is no video
    with pytest.raises(ValueError) as err:
        RenderDir(tmp_path)
    assert str(err.value) == f"DIR: {tmp_path / 'frames' / 'cam01'} has no frames"
    (tmp_path / "frames" / "cam01.mkv").rmdir()
    # no masks either for the videos of `render --format video`
    (tmp_path / "frames" / "cam01.mkv").write_bytes(b"")
    for png in (tmp_path / "masks").glob("cam*/*.png"):
        png.unlink()
    with pytest.raises(ValueError) as err:
        RenderDir(tmp_path, name="--dir")
    assert str(err.value) == f"--dir: {tmp_path / 'masks' / 'cam01'} has no frames"


def test_cameras_are_numbered_by_their_file_names_over_the_number_inside(tmp_path):
    """frames/cam02 goes with calibration/cam02.yaml, whatever camera_number that file holds."""
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 1, 4)
    path = tmp_path / "calibration" / "cam02.yaml"
    path.write_text(path.read_text() + "camera_number: 7\n")
    assert [c.number for c in RenderDir(tmp_path).cameras] == [1, 2]


def test_cameras_of_another_height_alone_are_refused(tmp_path):
    cams = [scene.Camera.from_pose(n, [1.0 + n, 0.05, 2.2], np.radians(70), np.radians(15), 40, h,
                                   np.radians(49), [0, 0, 0, 0, 0]) for n, h in ((1, 30), (2, 32))]
    for cam in cams:
        write_render_dir(tmp_path, [cam], *synthetic_sequence([cam], 1, np.random.default_rng(0)))
    with pytest.raises(ValueError) as err:
        RenderDir(tmp_path)
    assert str(err.value) == ("DIR: calibration/cam02.yaml is 40x32 pixels, calibration/cam01.yaml 40x30; "
                              "the node pipeline takes cameras of one resolution")


def test_uncalibrated_cameras_are_frame_folders_and_videos_only(tmp_path):
    """A note beside the frames is no camera; a folder or a video without its calibration is,
    and the first such is named."""
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 1, 4)
    (tmp_path / "frames" / "cam03.txt").write_text("lens cap on")
    assert len(RenderDir(tmp_path).cameras) == 2
    (tmp_path / "frames" / "cam05.mkv").write_bytes(b"")
    with pytest.raises(ValueError, match=r"^DIR: frames/cam05.mkv has no calibration/cam05.yaml; "):
        RenderDir(tmp_path)
    (tmp_path / "frames" / "cam04").mkdir()
    with pytest.raises(ValueError, match=r"^DIR: frames/cam04 has no calibration/cam04.yaml; "):
        RenderDir(tmp_path)


def test_png_frames_are_read_even_beside_a_video(tmp_path):
    """A render directory with its PNG frames is read from them; a video beside them is not used."""
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 2, 4)
    (tmp_path / "frames" / "cam01.mkv").write_bytes(b"not a video")
    r = RenderDir(tmp_path)
    assert r.videos is None and r.frame_names == ("000000.png", "000001.png")
    png = cv2.imread(str(tmp_path / "frames" / "cam01" / "000001.png"))
    np.testing.assert_array_equal(r.frames(1)[0], png[..., ::-1])


def test_frames_in_grey_with_alpha_16_bit_or_an_upper_case_suffix_are_read_as_rgb(tmp_path):
    """A folder of images is any camera's export: grey, RGBA, 16-bit, `.PNG` are frames too,
    as 8-bit RGB (16-bit levels / 256)."""
    folder = tmp_path / "clip"
    folder.mkdir()
    grey = np.arange(24, dtype=np.uint8).reshape(4, 6)
    bgra = np.zeros((4, 6, 4), np.uint8)
    bgra[..., 0], bgra[..., 1], bgra[..., 2], bgra[..., 3] = 10, 20, 30, 255       # blue 10, red 30
    cv2.imwrite(str(folder / "f1.png"), grey)
    cv2.imwrite(str(folder / "f2.png"), bgra)
    cv2.imwrite(str(folder / "f3.PNG"), bgra[..., :3])
    cv2.imwrite(str(folder / "f4.png"), np.full((4, 6, 3), (0x0A00, 0x1401, 0x1EFF), np.uint16))
    got = list(iter_video_frames(folder))
    assert [(f.shape, f.dtype) for f in got] == [((4, 6, 3), np.uint8)] * 4
    np.testing.assert_array_equal(got[0], np.repeat(grey[..., None], 3, axis=2))
    assert got[1][0, 0].tolist() == got[2][0, 0].tolist() == got[3][0, 0].tolist() == [30, 20, 10]


def test_names_of_equal_numbers_are_ordered_as_text():
    """``f01`` and ``f1`` have the same number: ordered by the name itself, whatever the
    order the folder lists them in."""
    from pipeline.io import number_order

    assert number_order("f01.png") < number_order("f1.png") < number_order("f2.png") < number_order("f10.png")
    assert sorted(["f1.png", "f01.png", "f001.png"], key=number_order) == ["f001.png", "f01.png", "f1.png"]


@pytest.mark.parametrize("kind", ["masks", "frames"])
def test_a_folder_in_place_of_a_frame_file_is_missing(tmp_path, kind):
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 2, 4)
    gone = tmp_path / kind / "cam02" / "000001.png"
    gone.unlink()
    gone.mkdir()
    r = RenderDir(tmp_path)
    r.check_complete(1)                                     # frame 0 only: complete
    with pytest.raises(ValueError) as err:
        r.check_complete(2)
    assert str(err.value) == f"DIR: {tmp_path} lacks 1 file of its first 2 frames: {kind}/cam02/000001.png"


def test_a_folder_of_images_of_every_suffix_is_read(tmp_path):
    """PNG, JPEG, BMP, TIFF, PPM and PGM exports are frames, any other file is not."""
    folder = tmp_path / "clip"
    folder.mkdir()
    suffixes = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm", ".pgm")
    for i, suffix in enumerate(suffixes):                   # a PGM is grey, a PPM colour
        assert cv2.imwrite(str(folder / f"f{i}{suffix}"), np.full((4, 6, 1 if suffix == ".pgm" else 3), 10 * i + 5,
                                                                    np.uint8))
    (folder / "f9.txt").write_text("notes")
    got = list(iter_video_frames(folder))
    assert [f.shape for f in got] == [(4, 6, 3)] * len(suffixes)
    assert [int(f[0, 0, 0]) for f in got] == [10 * i + 5 for i in range(len(suffixes))]


def test_the_number_of_a_calibration_file_name():
    """``camNN`` anywhere in the file's name, of any number of digits; a name without it has
    the default, ``None`` unless given."""
    assert number_in_name("calibration/cam07.yaml") == 7
    assert number_in_name("left_cam123b.xml") == 123
    assert number_in_name("lens.yaml") is None and number_in_name("cam.yaml") is None
    assert number_in_name("lens.yaml", default=4) == 4


def test_a_label_image_of_another_size_is_named_as_a_mask(tmp_path):
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 2, 4)
    cv2.imwrite(str(tmp_path / "masks" / "cam02" / "000001.png"), np.zeros((4, 6), np.uint8))
    r = RenderDir(tmp_path)
    assert r.labels(0).shape == (2, 120, 160)
    with pytest.raises(ValueError) as err:
        r.labels(1)
    assert str(err.value) == "masks: masks/cam02/000001.png is 6x4; expected 160x120 to match the calibration"


def test_files_and_folders_not_named_cam_are_no_cameras(tmp_path):
    """A note in calibration/ or a folder of previews in frames/ is left alone."""
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 1, 4)
    (tmp_path / "calibration" / "notes.yaml").write_text("lens: rented\n")
    (tmp_path / "frames" / "previews").mkdir()
    (tmp_path / "frames" / "all.mkv").write_bytes(b"")
    assert [c.name for c in RenderDir(tmp_path).cameras] == ["cam01", "cam02"]


@pytest.mark.parametrize("stem, want", [("cam1", "cam01.yaml for camera 1"), ("cam007", "cam07.yaml for camera 7"),
                                        ("camera", "camNN.yaml")])
def test_a_calibration_file_not_named_as_its_camera_is_refused_by_its_name(tmp_path, stem, want):
    """Camera N's frames and masks are looked for as camNN: calibration/cam1.yaml beside
    frames/cam1/ was refused as 'frames/cam1 has no calibration/cam1.yaml', a file that is there."""
    from tests.test_pipeline_cli import small_render_dir

    small_render_dir(tmp_path, 2, 4)
    (tmp_path / "calibration" / "cam02.yaml").rename(tmp_path / "calibration" / f"{stem}.yaml")
    (tmp_path / "frames" / "cam02").rename(tmp_path / "frames" / stem)
    with pytest.raises(ValueError) as err:
        RenderDir(tmp_path)
    assert str(err.value) == (f"DIR: calibration/{stem}.yaml: expected the name {want} (camNN, the camera's "
                              "number in two digits or more, as `camtask render` writes)")
