"""camtask render, the command: its options, the disk space it asks for, the workers it starts and what it
says at the end, with the rendering of an episode replaced by an empty one (no GL)."""

import argparse
import contextlib
import json
import os
import re
from pathlib import Path

import pytest

from testbed.cli import main
from testbed.commands.render import check_inputs_outside, parse_cameras, tree_bytes
from testbed.episodes import checksums

ONE = 1_000_000                       # bytes of an episode, as estimate_bytes is made to say below


def empty_episode(config, index, out, progress=None, seconds=None, overlap=None):
    """render_episode, minus the rendering: an episode folder of its meta.json, its frames counted."""
    folder = Path(out) / f"episode_{index:04d}"
    folder.mkdir()
    (folder / "meta.json").write_text(json.dumps({"scene_yaml": config.scene_yaml}))
    if progress:
        progress(config.frames)
    return {"index": index, "name": folder.name, "seed": config.seed, "spawn_key": [index],
            "frames": config.frames, "files": checksums(folder)}


@pytest.fixture
def quick(monkeypatch):
    """Episodes rendered as empty folders, ONE bytes each by the estimate."""
    from testbed import generate

    monkeypatch.setattr(generate, "render_episode", empty_episode)
    monkeypatch.setattr(generate, "estimate_bytes", lambda config, scene, episodes: ONE * episodes)
    return generate


def render(capsys, out, *argv):
    capsys.readouterr()
    code = main(["render", "lab", "--frames", "2", "--cameras", "1", "--workers", "0", "--out", str(out), *argv])
    return code, capsys.readouterr().err.replace("\r", "\n").strip().splitlines()


def test_cameras_may_be_spaced_and_empty_pieces_are_skipped():
    assert parse_cameras(" 3, 1 ,, ") == (3, 1)
    assert parse_cameras("5,") == (5,)
    assert parse_cameras(None) is None
    with pytest.raises(ValueError, match=r"^--cameras: expected comma-separated camera numbers, got '1 2'$") as err:
        parse_cameras("1 2")
    assert err.value.__cause__ is None and err.value.__suppress_context__      # no int() error chained


def test_too_many_people_given_are_named_by_the_option(tmp_path, capsys):
    code = main(["render", "lab", "--people", "17", "--out", str(tmp_path / "ds"), "--workers", "0"])
    assert code == 2 and capsys.readouterr().err.strip().splitlines()[-1] == (
        "camtask render: error: --people: silhouettes store one bit per person in a 16-bit PNG; "
        "expected at most 16, got 17")


def test_tree_bytes_counts_the_blocks_of_every_file_under_a_folder_and_links_as_themselves(tmp_path):
    tree = tmp_path / "tree"
    (tree / "a" / "b").mkdir(parents=True)
    (tree / "top.bin").write_bytes(b"\1" * 100_000)
    (tree / "a" / "b" / "deep.bin").write_bytes(b"\1" * 300_000)
    blocks = sum(os.lstat(f).st_blocks * 512 for f in (tree / "top.bin", tree / "a" / "b" / "deep.bin"))
    assert blocks >= 400_000 and tree_bytes(tree) == blocks
    (tmp_path / "outside.bin").write_bytes(b"\1" * 1_000_000)
    (tree / "a" / "link").symlink_to(tmp_path / "outside.bin")     # deleting the link frees none of its target
    (tree / "a" / "nowhere").symlink_to(tree / "gone")
    links = sum(os.lstat(tree / "a" / n).st_blocks * 512 for n in ("link", "nowhere"))
    assert tree_bytes(tree) == blocks + links < blocks + 1_000_000
    with open(tree / "sparse.bin", "wb") as f:             # what deleting frees is its blocks, not its size
        f.truncate(10**9)
    assert tree_bytes(tree) < blocks + links + 10**6
    assert tree_bytes(tmp_path / "none") == 0


def test_tree_bytes_skips_a_file_deleted_while_it_counts(tmp_path, monkeypatch):
    (tmp_path / "kept.bin").write_bytes(b"\1" * 10_000)
    walk = os.walk
    monkeypatch.setattr(os, "walk", lambda folder: ((root, dirs, [*files, "gone.bin"]) for root, dirs, files in walk(folder)))
    assert tree_bytes(tmp_path) == os.lstat(tmp_path / "kept.bin").st_blocks * 512


def test_inputs_in_an_overwritten_folder_are_found_by_their_real_paths(tmp_path, monkeypatch):
    def check(out, scene, params=None):
        check_inputs_outside(Path(out), argparse.Namespace(scene=scene, params=params))

    (tmp_path / "ds" / "notes").mkdir(parents=True)
    (tmp_path / "ds" / "notes" / "s.yaml").write_text("x")
    (tmp_path / "elsewhere").symlink_to(tmp_path / "ds")
    monkeypatch.chdir(tmp_path)
    for out, scene in (("ds", str(tmp_path / "ds" / "notes" / "s.yaml")), ("elsewhere", "ds/notes/s.yaml"),
                       (str(tmp_path / "ds"), "elsewhere/notes/s.yaml")):
        with pytest.raises(ValueError, match=rf"^--overwrite: SCENE {re.escape(scene)} lies in {out}, "):
            check(out, scene)
    check("ds", "lab")                                     # not a file: a built-in scene
    monkeypatch.chdir(tmp_path / "ds")
    check(".", "lab")                                      # even with DIR the working folder
    check(".", "notes")                                    # a folder is no scene file
    with pytest.raises(ValueError, match=r"^--overwrite: --params notes/s.yaml lies in \., "):
        check(".", "lab", "notes/s.yaml")


def test_an_overwrite_that_frees_less_than_it_deletes_is_refused_once_deleted(tmp_path, capsys, monkeypatch, quick):
    """Deleting the old episodes counts as free before they are deleted; hard links or a
    snapshot may keep them on the disk: then the folder is checked again."""
    out = tmp_path / "ds"
    assert render(capsys, out)[0] == 0
    (out / "episode_0000" / "old.bin").write_bytes(b"\1" * 2 * ONE)
    monkeypatch.setattr(quick, "free_bytes", lambda path: (ONE // 2, "/fake"))
    code, err = render(capsys, out, "--overwrite")
    assert (code, err[-1]) == (2, "camtask render: error: --out: 0.5 MB free on /fake; one episode needs about 1 MB")
    assert not (out / "episode_0000").exists()


def test_a_resume_warns_of_the_room_for_the_episodes_left_not_all(tmp_path, capsys, monkeypatch, quick):
    out = tmp_path / "ds"
    assert render(capsys, out, "--episodes", "2")[0] == 0
    monkeypatch.setattr(quick, "free_bytes", lambda path: (3 * ONE // 2, "/fake"))
    code, err = render(capsys, out, "--episodes", "4", "--resume")
    assert code == 0 and [line for line in err if line.startswith("warning")] == [
        ("warning: --out: 1.5 MB free on /fake; 2 episodes need about 2 MB: the run stops when the disk is full "
         "(the finished episodes stay valid; --resume finishes it)")]
    monkeypatch.setattr(quick, "free_bytes", lambda path: (2 * ONE, "/fake"))   # exactly the room needed
    code, err = render(capsys, out, "--episodes", "6", "--resume")
    assert code == 0 and not [line for line in err if "warning" in line]


def test_the_last_line_counts_the_episodes_this_run_wrote_and_the_bar_the_frames_left(tmp_path, capsys, quick):
    code, err = render(capsys, tmp_path / "one", "--frames", "1")
    assert (code, err[-1]) == (0, f"wrote 1 episode x 1 frame to {tmp_path / 'one'} (1/1 finished)")
    out = tmp_path / "ds"
    assert render(capsys, out)[0] == 0
    code, err = render(capsys, out, "--episodes", "3", "--resume")
    assert (code, err[-1]) == (0, f"wrote 2 episodes x 2 frames to {out} (3/3 finished)")
    assert re.search(r"^render: 100%.* 4/4 ", err[-2])
    code, err = render(capsys, out, "--episodes", "3", "--resume")
    assert (code, err[-1]) == (0, f"{out}: all 3 episodes already finished")
    verify = [line for line in err if line.startswith("verify:")]           # one bar over the 3 episodes
    assert [bool(re.match(r"verify: +0%", line)) for line in verify].count(True) == 1
    assert re.search(r"^verify: 100%.* 3/3 ", verify[-1])


def test_a_resume_starts_no_more_workers_than_the_episodes_left(tmp_path, capsys, monkeypatch, quick):
    """Two episodes of five left, --workers 4: a cluster of two, not of four."""
    from testbed import parallel

    asked = []

    @contextlib.contextmanager
    def client(workers, scheduler):
        asked.append(workers)
        raise ValueError("no cluster here")
        yield

    out = tmp_path / "ds"
    assert render(capsys, out, "--episodes", "3")[0] == 0
    monkeypatch.setattr(parallel, "open_client", client)
    for workers, episodes, started in (("4", "4", 0), ("4", "5", 2), ("0", "5", 0)):
        code, err = render(capsys, out, "--episodes", episodes, "--resume", "--workers", workers)
        assert (code, err[-1]) == (2, "camtask render: error: no cluster here") and asked[-1] == started


def test_a_frame_rate_that_video_cannot_hold_is_refused_before_any_work(tmp_path, capsys, quick):
    from scene import scene_path

    scene = tmp_path / "fast.yaml"
    scene.write_text(scene_path("lab").read_text().replace("frame_rate: 7.5", "frame_rate: 2000", 1))
    code = main(["render", str(scene), "--frames", "1", "--cameras", "1", "--format", "video", "--workers", "0",
                 "--out", str(tmp_path / "ds")])
    assert code == 2 and capsys.readouterr().err.strip().splitlines()[-1] == (
        "camtask render: error: --format video: the scene's frame_rate: Matroska stores milliseconds, so at most "
        "1000 frames per second; got a frame rate of 2000 Hz (use --format png)")
    assert not (tmp_path / "ds").exists()


def test_a_refused_resume_with_local_workers_touches_nothing(tmp_path, capsys, quick):
    """The clean-up after the workers is for a run that started: a resume refused before its
    cluster leaves a killed run's temporary folder for the resume that is not refused."""
    out = tmp_path / "ds"
    assert render(capsys, out)[0] == 0
    (out / ".episode_0001.killed.tmp").mkdir()
    code, err = render(capsys, out, "--episodes", "3", "--seed", "1", "--workers", "2", "--resume")
    assert code == 2 and "seed: 0 then, 1 now" in err[-1]
    assert sorted(p.name for p in out.iterdir()) == [".episode_0001.killed.tmp", "episode_0000", "manifest.json",
                                                    "run_info.json"]


def test_overwrite_leaves_only_the_new_run(tmp_path, capsys, quick):
    out = tmp_path / "ds"
    assert render(capsys, out, "--episodes", "3")[0] == 0
    (out / "notes.txt").write_text("mine")
    (out / "episode_0000" / "old.bin").write_bytes(b"old")
    code, err = render(capsys, out, "--seed", "5", "--overwrite")
    assert (code, err[-1]) == (0, f"wrote 1 episode x 2 frames to {out} (1/1 finished)")
    assert sorted(p.name for p in out.rglob("*")) == ["episode_0000", "manifest.json", "meta.json", "run_info.json"]
    assert json.loads((out / "manifest.json").read_text())["config"]["seed"] == 5


def test_a_local_run_that_stops_leaves_no_folder_of_its_workers(tmp_path, capsys, monkeypatch, quick):
    """The local workers stopped with the run: an episode they finished after the manifest's
    last write and one they were writing are removed; the manifest stays."""
    from testbed import parallel

    @contextlib.contextmanager
    def client(workers, scheduler):
        yield object()

    def generate(config, episodes, out, keep, client, progress=None, run_info=None):
        empty_episode(config, 0, out)
        (out / ".episode_0001.a1b2.tmp").mkdir()
        raise OSError("cannot write: No space left on device")

    monkeypatch.setattr(parallel, "open_client", client)
    monkeypatch.setattr(quick, "generate", generate)
    out = tmp_path / "ds"
    code, err = render(capsys, out, "--episodes", "2", "--workers", "2")
    assert (code, err[-1]) == (1, (f"camtask render: error: cannot write: No space left on device; stopped with 0 "
                                   f"of 2 episodes finished, listed in {out / 'manifest.json'} (--resume finishes "
                                   "the run)"))
    assert [p.name for p in out.iterdir()] == ["manifest.json"]


@pytest.mark.parametrize("check", ["wait_for_a_worker", "check_worker_versions", "check_workers_share"])
def test_an_existing_cluster_is_checked_before_any_work(tmp_path, capsys, monkeypatch, quick, check):
    from testbed import parallel

    @contextlib.contextmanager
    def client(workers, scheduler):
        yield object()

    def refused(*args):
        raise ValueError(f"--scheduler: refused by {check}")

    def rendering(*args, **kwargs):
        raise ValueError("rendering started")

    monkeypatch.setattr(parallel, "open_client", client)
    for name, module in (("wait_for_a_worker", parallel), ("check_worker_versions", quick),
                         ("check_workers_share", quick)):
        monkeypatch.setattr(module, name, refused if name == check else lambda *args: None)
    monkeypatch.setattr(quick, "generate", rendering)
    code = main(["render", "lab", "--frames", "1", "--out", str(tmp_path / "new" / "ds"), "--scheduler",
                 "tcp://10.0.0.5:8786"])
    assert code == 2 and capsys.readouterr().err.strip().splitlines()[-1] == (
        f"camtask render: error: --scheduler: refused by {check}")
    assert not (tmp_path / "new").exists()
