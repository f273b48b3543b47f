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


def test_frames_of_other_names_in_one_camera_are_refused(render_dir, tmp_path):
    """As many frames in each camera, but one named otherwise: frames are matched by name, not count."""
    root = tmp_path / "renamed"
    shutil.copytree(render_dir, root)
    (root / "frames" / "cam02" / "000003.png").rename(root / "frames" / "cam02" / "000004.png")
    with pytest.raises(ValueError, match=r"frames/cam02 and .*frames/cam01 hold different frames "
                                         r"\(4 and 4; 000003.png is in one only\)"):
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


def main_line(capsys, argv):
    """``camtask ARGV`` through the entry point: its exit code and its standard error's lines."""
    from testbed.cli import main

    capsys.readouterr()
    code = main(argv)
    return code, capsys.readouterr().err.splitlines()


@pytest.mark.parametrize(("argv", "line"), [
    (["{render}", "--frames", "0"], "--frames: expected an integer >= 1, got 0"),
    (["{render}", "--frames", "-3"], "--frames: expected an integer >= 1, got -3"),
    (["{render}", "--video", "{video}"], "give either DIR or --video, not both"),
    (["--video", "{video}"], "--video needs --calibration FILE and --background N"),
    (["--video", "{video}", "--calibration", "{calib}"], "--video needs --calibration FILE and --background N"),
    (["--video", "{video}", "--background", "1"], "--video needs --calibration FILE and --background N"),
    ([], "expected a render directory DIR, or --video FILE_OR_FOLDER"),
    (["--video", "{video}", "--calibration", "{calib}", "--background", "0"],
     "--background: expected an integer >= 1, got 0"),
    (["--video", "{video}", "--calibration", "{calib}", "--background", "1", "--frames", "0"],
     "--frames: expected an integer >= 1, got 0"),
])
def test_scanlines_usage_errors_are_one_line_and_write_nothing(render_dir, tmp_path, capsys, argv, line):
    before = sorted(p.relative_to(render_dir) for p in render_dir.rglob("*"))
    given = {"render": render_dir, "video": render_dir / "frames" / "cam01",
             "calib": render_dir / "calibration" / "cam01.yaml"}
    argv = ["scanlines", *(a.format(**given) for a in argv), "--out", str(tmp_path / "s.npz")]
    assert main_line(capsys, argv) == (2, [f"camtask scanlines: error: {line}"])
    assert list(tmp_path.iterdir()) == []
    assert sorted(p.relative_to(render_dir) for p in render_dir.rglob("*")) == before


def test_scanlines_on_a_dataset_of_several_episodes_asks_for_one(tmp_path, capsys):
    ds = tmp_path / "ds"
    for name in ("episode_0000", "episode_0001"):
        (ds / name).mkdir(parents=True)
    (ds / "manifest.json").write_text("{}")
    assert main_line(capsys, ["scanlines", str(ds), "--out", str(tmp_path / "s.npz")]) == (
        2, [(f"camtask scanlines: error: DIR: {ds} is a dataset of 2 episodes; give one episode folder, "
            f"e.g. {ds / 'episode_0000'}")])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds"]


def _assert_sight_range_of(root, npz, height, width):
    """The (gt_)blind_radius and (gt_)sight_radius in ``npz`` are the render directory's
    pipeline's sight range for people ``height`` m tall and ``width`` m wide (the true
    scanlines' far edge depends on the width)."""
    from pipeline import Pipeline, PipelineParams

    pipe = Pipeline(RenderDir(root).cameras, PipelineParams())
    with np.load(npz) as z:
        for prefix, truth in (("", False), ("gt_", True)):
            near, far = pipe.sight_range(height, truth=truth, object_width=width)
            np.testing.assert_array_equal(z[f"{prefix}blind_radius"], near)
            np.testing.assert_array_equal(z[f"{prefix}sight_radius"], far)


def test_the_people_size_of_an_episode_where_no_one_walked_is_its_scenes(render_dir, tmp_path, capsys):
    """No row in people.csv: the smallest person the scene in meta.json could have held, not none."""
    import json

    import yaml

    from scene import scene_path

    root = tmp_path / "render"
    shutil.copytree(render_dir, root)
    (root / "people.csv").write_text("frame,person_id,x,y,radius,height\n")
    assert main_line(capsys, ["scanlines", str(root), "--frames", "1", "--out", str(tmp_path / "a.npz")])[0] == 0
    assert "blind_radius" not in np.load(tmp_path / "a.npz").files           # nor a scene: no size known
    config = yaml.safe_load(scene_path("lab").read_text())
    config["people"].update(height=1.5, radius=0.2)
    (root / "meta.json").write_text(json.dumps({"scene_yaml": yaml.safe_dump(config)}))
    assert main_line(capsys, ["scanlines", str(root), "--frames", "1", "--out", str(tmp_path / "b.npz")])[0] == 0
    _assert_sight_range_of(root, tmp_path / "b.npz", height=1.5, width=0.4)


def test_the_people_size_is_the_shortest_and_the_thinnest_persons(render_dir, tmp_path, capsys):
    """Two people, one taller and thinner: the height of the one, the diameter of the other."""
    root = tmp_path / "render"
    shutil.copytree(render_dir, root)
    (root / "people.csv").write_text("frame,person_id,x,y,radius,height\n0,0,1.0,2.0,0.3,1.5\n"
                                     "0,1,3.0,2.0,0.2,1.9\n")
    assert main_line(capsys, ["scanlines", str(root), "--frames", "1", "--out", str(tmp_path / "s.npz")])[0] == 0
    _assert_sight_range_of(root, tmp_path / "s.npz", height=1.5, width=0.4)


@pytest.mark.parametrize("meta", ['{"episode": 0}', '{"scene_yaml": ""}', '{"scene_yaml": null}'])
def test_a_meta_json_without_a_scene_gives_no_people_size(render_dir, tmp_path, capsys, meta):
    root = tmp_path / "render"
    shutil.copytree(render_dir, root)
    (root / "meta.json").write_text(meta)
    assert main_line(capsys, ["scanlines", str(root), "--frames", "1", "--out", str(tmp_path / "s.npz")])[0] == 0
    assert "blind_radius" not in np.load(tmp_path / "s.npz").files


def test_frames_beyond_the_render_directory_take_all_of_it(render_dir, tmp_path, capsys):
    assert main_line(capsys, ["scanlines", str(render_dir), "--frames", "99", "--out", str(tmp_path / "s.npz"),
                              "--json"]) == (0, [])                  # --json: no progress bar either
    assert np.load(tmp_path / "s.npz")["scanlines"].shape == (4, 2, 160)


def test_a_render_directory_beside_a_manifest_json_of_its_own_is_still_one(render_dir, tmp_path, capsys):
    """A manifest.json makes a folder a dataset only when it has no calibration/ of its own."""
    root = tmp_path / "render"
    shutil.copytree(render_dir, root)
    (root / "manifest.json").write_text("{}")
    assert main_line(capsys, ["scanlines", str(root), "--out", str(tmp_path / "s.npz"), "--json"])[0] == 0
    assert np.load(tmp_path / "s.npz")["scanlines"].shape == (4, 2, 160)


def test_files_named_episode_beside_the_one_episode_are_no_episodes(render_dir, fake_dataset, tmp_path, capsys):
    """A dataset's folder holds other files named episode_* (a stopped run's episode_best.yaml):
    its one episode folder is still the one."""
    (fake_dataset / "episode_0000").rmdir()
    shutil.copytree(render_dir, fake_dataset / "episode_0001")
    (fake_dataset / "episode_0000.yaml").write_text("{}\n")
    (fake_dataset / "episode_best.yaml").write_text("{}\n")
    assert main_line(capsys, ["scanlines", str(fake_dataset), "--out", str(tmp_path / "s.npz"), "--json"]) == (0, [])
    assert np.load(tmp_path / "s.npz")["scanlines"].shape == (4, 2, 160)


def test_a_dataset_with_no_episode_is_named_so(tmp_path, capsys):
    (tmp_path / "ds").mkdir()
    (tmp_path / "ds" / "manifest.json").write_text("{}")
    code, err = main_line(capsys, ["scanlines", str(tmp_path / "ds"), "--out", str(tmp_path / "s.npz")])
    assert code == 2 and err == [(f"camtask scanlines: error: DIR: {tmp_path / 'ds'} is a dataset of 0 episodes; "
                                 f"give one episode folder, e.g. {tmp_path / 'ds' / 'episode_0000'}")]


@pytest.mark.parametrize(("command", "name"), [(["scanlines"], "scanlines.npz"),
                                               (["tune", "--trials", "1"], "tuned_params.yaml")])
def test_the_default_output_in_an_episode_of_a_dataset_asks_for_out(render_dir, fake_dataset, capsys, command, name):
    episode = fake_dataset / "episode_0000"
    episode.rmdir()
    shutil.copytree(render_dir, episode)
    before = sorted(p.relative_to(fake_dataset) for p in fake_dataset.rglob("*"))
    assert main_line(capsys, [command[0], str(episode), *command[1:]]) == (
        2, [(f"camtask {command[0]}: error: --out: {episode} is an episode of the dataset {fake_dataset}, whose "
            f"manifest.json checksums its files; give --out FILE to write {name} elsewhere")])
    assert sorted(p.relative_to(fake_dataset) for p in fake_dataset.rglob("*")) == before


@pytest.mark.parametrize(("command", "name"), [(["scanlines"], "scanlines.npz"),
                                               (["tune", "--trials", "1"], "tuned_params.yaml")])
def test_an_episode_named_relatively_names_its_dataset_so(render_dir, fake_dataset, tmp_path, capsys, monkeypatch,
                                                            command, name):
    """The dataset is named as the user named the episode: ds for ds/episode_0000; for "."
    (which names no folder) by its real path."""
    episode = fake_dataset / "episode_0000"
    episode.rmdir()
    shutil.copytree(render_dir, episode)
    tail = f"whose manifest.json checksums its files; give --out FILE to write {name} elsewhere"
    for cwd, given, dataset in ((tmp_path, "ds/episode_0000", "ds"), (episode, ".", fake_dataset.resolve())):
        monkeypatch.chdir(cwd)
        assert main_line(capsys, [command[0], given, *command[1:]]) == (
            2, [f"camtask {command[0]}: error: --out: {given} is an episode of the dataset {dataset}, {tail}"])
    assert sorted(p.name for p in episode.iterdir()) == sorted(p.name for p in render_dir.iterdir())


def test_a_render_directory_inside_an_episode_is_no_episode(render_dir, fake_dataset, capsys):
    """Its default output is refused as a file inside the episode, not called an episode itself."""
    inner = fake_dataset / "episode_0000" / "render"
    shutil.copytree(render_dir, inner)
    assert main_line(capsys, ["scanlines", str(inner)]) == (
        2, [(f"camtask scanlines: error: --out: {inner / 'scanlines.npz'} is inside {fake_dataset / 'episode_0000'}, "
             f"an episode of the dataset {fake_dataset}, whose manifest.json checksums its files; choose a folder "
             "outside that dataset")])
    assert not (inner / "scanlines.npz").exists()


def test_a_video_without_json_prints_its_frames_and_bandwidth_only(render_dir, tmp_path, capsys):
    """No ground truth for a video: no table of precision and recall."""
    out = tmp_path / "s.npz"
    capsys.readouterr()
    assert camtask(["scanlines", "--video", str(render_dir / "frames" / "cam01"), "--calibration",
                    str(render_dir / "calibration" / "cam01.yaml"), "--background", "1", "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2 and lines[0] == f"3 frames x 1 cameras -> {out}" and lines[1].startswith("bandwidth: ")
