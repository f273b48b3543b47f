"""scanlines and tune on inputs that are not as expected: every one stops before any work, in one line."""

import os
import shutil

import numpy as np
import pytest

from pipeline.io import RenderDir
from testbed.output import check_output_file
from tests.test_pipeline_cli import camtask, small_render_dir


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory):
    return small_render_dir(tmp_path_factory.mktemp("render"), 4, 2)


@pytest.fixture
def fake_dataset(tmp_path):
    """A folder that looks like a dataset: a manifest beside an episode folder."""
    (tmp_path / "ds" / "episode_0000").mkdir(parents=True)
    (tmp_path / "ds" / "manifest.json").write_text("{}")
    return tmp_path / "ds"


def test_an_output_that_is_not_a_regular_file_is_refused_and_kept(tmp_path):
    """An atomic write replaces the name: /dev/null as --out would have become a file."""
    os.mkfifo(tmp_path / "pipe")
    with pytest.raises(ValueError, match="--out: .*pipe exists and is not a regular file"):
        check_output_file("--out", tmp_path / "pipe")
    assert not (tmp_path / "pipe").is_file() and (tmp_path / "pipe").exists()


@pytest.mark.parametrize("name", ["", "newdir/"])
def test_an_output_name_that_names_no_file_is_refused(tmp_path, monkeypatch, name):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match=f"--out: expected a file name, got '{name}'"):
        check_output_file("--out", name)
    assert list(tmp_path.iterdir()) == []


def test_a_long_output_name_that_the_file_system_takes_is_taken(tmp_path):
    """The write probe was named after the file, longer than it: a 250-character name was refused."""
    name = tmp_path / ("p" * 246 + ".png")
    assert check_output_file("--plot", name, ".png") == name
    assert list(tmp_path.iterdir()) == []


def test_an_output_where_no_file_can_be_made_is_refused_first():
    with pytest.raises(ValueError, match=r"--out: cannot write to /proc \("):
        check_output_file("--out", "/proc/scanlines.npz")


@pytest.mark.parametrize("argv", [
    ["scanlines", "{render}", "--out", "{ds}/episode_0000/scanlines.npz"],
    ["tune", "{render}", "--trials", "1", "--out", "{ds}/episode_0000/tuned.yaml"],
    ["tune", "{render}", "--trials", "1", "--out", "{tmp}/t.yaml", "--plot", "{ds}/episode_0000/t.png"],
])
def test_outputs_inside_an_episode_of_a_dataset_are_refused(render_dir, fake_dataset, tmp_path, argv):
    """Its manifest checksums the episode's files: `render --resume` would delete them."""
    argv = [a.format(render=render_dir, ds=fake_dataset, tmp=tmp_path) for a in argv]
    with pytest.raises(ValueError, match=r"is inside .*episode_0000, an episode of the dataset"):
        camtask(argv)
    assert list((fake_dataset / "episode_0000").iterdir()) == []


def test_a_video_in_an_episode_needs_out_and_dot_is_a_video_folder(render_dir, fake_dataset, tmp_path, monkeypatch):
    calib = render_dir / "calibration" / "cam01.yaml"
    frames = fake_dataset / "episode_0000" / "clip"
    shutil.copytree(render_dir / "frames" / "cam01", frames)
    with pytest.raises(ValueError, match=r"--out: .*clip_scanlines.npz is inside .*episode_0000"):
        camtask(["scanlines", "--video", str(frames), "--calibration", str(calib), "--background", "1"])
    monkeypatch.chdir(tmp_path)
    shutil.copytree(render_dir / "frames" / "cam01", tmp_path / "imgs")
    monkeypatch.chdir(tmp_path / "imgs")
    assert camtask(["scanlines", "--video", ".", "--calibration", str(calib), "--background", "1", "--json"]) == 0
    assert np.load(tmp_path / "imgs_scanlines.npz")["scanlines"].shape == (3, 1, 160)


def test_frames_missing_from_one_camera_are_refused(render_dir, tmp_path):
    """Frame i must be the same moment in every camera; a frame gone from camera 1 shifted all the others."""
    for number in (1, 2):
        root = tmp_path / f"miss{number}"
        shutil.copytree(render_dir, root)
        (root / "frames" / f"cam{number:02d}" / "000001.png").unlink()
        with pytest.raises(ValueError, match=r"frames/cam02 and .*frames/cam01 hold different frames "
                                             r"\((3 and 4|4 and 3); 000001.png is in one only\)"):
            RenderDir(root)


def test_a_bad_people_table_or_meta_stops_before_the_frames(render_dir, tmp_path, monkeypatch):
    root = tmp_path / "render"
    shutil.copytree(render_dir, root)
    seen = []
    monkeypatch.setattr(RenderDir, "frames", lambda self, i: seen.append(i))
    (root / "people.csv").write_text("frame,person_id,x,y,radius,height\n0,0,1.0\n")
    with pytest.raises(ValueError, match=r"people.csv: cannot read \(Some errors were detected ! Line #2 "
                                         r"\(got 3 columns instead of 6\)\)$"):
        camtask(["scanlines", str(root), "--out", str(tmp_path / "s.npz")])
    (root / "people.csv").unlink()
    (root / "meta.json").write_text("{bad")
    with pytest.raises(ValueError, match=r"meta.json: not valid JSON \("):
        camtask(["scanlines", str(root), "--out", str(tmp_path / "s.npz")])
    assert seen == [] and not (tmp_path / "s.npz").exists()


def test_a_start_outside_the_search_space_warns_once_in_our_words(render_dir, tmp_path, capsys):
    (tmp_path / "s.yaml").write_text("threshold_deg: 45\nopening_kernel: 11\n")
    assert camtask(["tune", str(render_dir), "--trials", "2", "--params", str(tmp_path / "s.yaml"),
                    "--out", str(tmp_path / "t.yaml"), "--json"]) == 0
    err = capsys.readouterr().err.splitlines()
    tail = ": the first trial uses it, the others search the range (docs/pipeline.md)"
    assert err == ["warning: --params: threshold_deg 45 is outside the searched range 1..30" + tail,
                   "warning: --params: opening_kernel 11 is outside the searched range 1..9" + tail]


def test_an_opening_taller_than_the_image_is_empty(render_dir, tmp_path):
    (tmp_path / "p.yaml").write_text("opening_kernel: 8191\ncolumn_threshold: 1e-3\n")
    assert camtask(["scanlines", str(render_dir), "--params", str(tmp_path / "p.yaml"),
                    "--out", str(tmp_path / "s.npz"), "--json"]) == 0
    assert not np.load(tmp_path / "s.npz")["scanlines"].any()
