"""What a run (or --resume) removes from --out as left behind: only what runs write."""

from testbed.generate import remove_unlisted, unlisted


def test_only_a_runs_own_names_are_removed(tmp_path):
    for folder in ("episode_0000", "episode_0003", ".episode_0004.k2j3.tmp", "episode_notes"):
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
        "episode_0000", "episode_0007", "episode_0009", "episode_best.yaml", "episode_notes", "manifest.json",
        "notes.txt"]
