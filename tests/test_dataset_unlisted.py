"""What a run (or --resume) removes from --out as left behind: only what runs write."""

import json

from testbed.generate import remove_unlisted, unlisted


def test_only_a_runs_own_names_are_removed(tmp_path):
    for folder in ("episode_0000", "episode_0003", ".episode_0004.k2j3.tmp", "episode_notes", ".episode_notes.tmp"):
        (tmp_path / folder).mkdir()
    for name in ("episode_best.yaml", "episode_0007", ".manifest.json.x1y2.tmp", ".run_info.json.a.tmp",
                 "manifest.json", "notes.txt"):
        (tmp_path / name).write_text("x")
    (tmp_path / "episode_0009").symlink_to(tmp_path / "notes.txt")
    left = [p.name for p in unlisted(tmp_path, {0: {}})]
    assert left == [".episode_0004.k2j3.tmp", ".manifest.json.x1y2.tmp", ".run_info.json.a.tmp", "episode_0003"]
    remove_unlisted(tmp_path, {0: {}})
    # a user's episode_best.yaml (tune --out) and episode_notes/ were deleted too; a file or a
    # link named like an episode is no folder a run made
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        ".episode_notes.tmp", "episode_0000", "episode_0007", "episode_0009", "episode_best.yaml", "episode_notes", "manifest.json",
        "notes.txt"]


def test_by_default_the_episodes_the_manifest_lists_are_kept(tmp_path):
    """As after a run on local workers: episodes finished after the manifest's last write go."""
    for name in ("episode_0000", "episode_0001", "episode_0002"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "meta.json").write_text("{}")
    listed = [{"index": i, "name": f"episode_{i:04d}", "frames": 1, "files": {"meta.json": "x"}} for i in (0, 2)]
    (tmp_path / "manifest.json").write_text(json.dumps({"episodes": listed}))
    remove_unlisted(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episode_0000", "episode_0002", "manifest.json"]


def _users_folder_and_run(tmp_path):
    """tmp_path/mine, a user's folder holding keep.txt ("x"), and tmp_path/ds, an empty --out."""
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "keep.txt").write_text("x")
    out = tmp_path / "ds"
    out.mkdir()
    return mine, out


def test_a_link_to_a_folder_and_short_numbers_are_not_a_runs(tmp_path):
    """A run names its episodes with four digits or more and makes them as folders, never links."""
    mine, out = _users_folder_and_run(tmp_path)
    (out / "episode_0002").symlink_to(mine)
    for folder in ("episode_12", "episode_", "episode_0003"):
        (out / folder).mkdir()
    assert [p.name for p in unlisted(out, {})] == ["episode_0003"]
    remove_unlisted(out, {})
    assert sorted(p.name for p in out.iterdir()) == ["episode_", "episode_0002", "episode_12"]
    assert (mine / "keep.txt").read_text() == "x"


def test_a_link_named_as_a_runs_temporary_file_is_removed_not_its_target(tmp_path):
    mine, out = _users_folder_and_run(tmp_path)
    (out / ".manifest.json.x1y2.tmp").symlink_to(mine)
    remove_unlisted(out, {})
    assert list(out.iterdir()) == [] and (mine / "keep.txt").read_text() == "x"
