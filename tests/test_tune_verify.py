"""`camtask verify` says which episode folder is missing or came from elsewhere, and which DIR is not a dataset."""

import json
import shutil

import pytest

from testbed.cli import main
from testbed.episodes import checksums
from testbed.generate import MANIFEST


def episode(root, index, seed, frames, payload):
    """A dataset's episode folder and its manifest entry."""
    name = f"episode_{index:04d}"
    folder = root / name
    folder.mkdir(parents=True)
    (folder / "meta.json").write_text(json.dumps({"episode": index, "seed": seed, "frames": frames,
                                                  "spawn_key": [index]}))
    (folder / "people.csv").write_text(payload)
    return {"index": index, "name": name, "seed": seed, "spawn_key": [index], "frames": frames,
            "files": checksums(folder)}


def dataset(root, seed):
    entries = [episode(root, i, seed, 4, f"frame {seed} {i}\n") for i in range(2)]
    (root / MANIFEST).write_text(json.dumps({"format_version": 2, "checksum": "blake3", "episodes_planned": 2,
                                             "episodes": entries}))
    return root


def verify(capsys, folder):
    code = main(["verify", str(folder)])
    out, err = capsys.readouterr()
    return code, [x for x in out.splitlines() if x.strip()], err.replace("\r", "\n").splitlines()[-1]


def test_a_missing_episode_folder_is_named_as_one(tmp_path, capsys):
    """It was every listed file one after the other: "229 missing (background/cam01.png, ...)"."""
    root = dataset(tmp_path / "ds", 1)
    shutil.rmtree(root / "episode_0001")
    code, out, _ = verify(capsys, root)
    assert code == 1 and out[0] == "episode_0001: folder missing (2 files listed)"


@pytest.mark.parametrize("source, says", [
    ("other/episode_0001", "episode 1 of seed 2 (4 frames), not episode 1 of seed 1 (4 frames)"),
    ("ds/episode_0000", "episode 0 of seed 1 (4 frames), not episode 1 of seed 1 (4 frames)"),
])
def test_an_episode_folder_from_elsewhere_is_named_so(tmp_path, capsys, source, says):
    """All its files "changed": nothing said the folder was another dataset's or episode's."""
    root, other = dataset(tmp_path / "ds", 1), dataset(tmp_path / "other", 2)
    copy = tmp_path / "copy"
    shutil.copytree(tmp_path / source, copy)
    shutil.rmtree(root / "episode_0001")
    copy.rename(root / "episode_0001")
    code, out, _ = verify(capsys, root)
    assert code == 1 and out[0] == (f"episode_0001: 2 changed (meta.json, people.csv); its meta.json is {says} "
                                    "as listed: a folder of another dataset or episode")
    assert other.is_dir()


def test_a_changed_meta_json_of_the_same_episode_is_only_changed(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    meta = root / "episode_0000" / "meta.json"
    meta.write_text(meta.read_text() + " ")
    assert verify(capsys, root)[:2] == (1, ["episode_0000: 1 changed (meta.json)",
                                            f"{root}: 1 of 2 episodes differ from manifest.json (episode_0000)"])


def test_a_dir_that_is_no_dataset_is_named_for_what_it_is(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    expected = "(expected a dataset folder written by `camtask render`)"
    lines = {root / "episode_0000": (f"DIR: {root}/episode_0000 is an episode of the dataset {root}, whose "
                                     f"manifest.json lists it: verify the dataset (camtask verify {root})"),
             tmp_path / "nowhere": f"DIR: {tmp_path}/nowhere: no such folder {expected}",
             root / MANIFEST: f"DIR: {root}/manifest.json: not a folder {expected}"}
    for folder, line in lines.items():
        assert verify(capsys, folder) == (2, [], f"camtask verify: error: {line}")


def test_an_intact_dataset_exits_0_and_says_so(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    assert verify(capsys, root)[:2] == (0, [f"{root}: 2 episodes intact (4 files, blake3)"])


def test_an_episode_folder_that_is_a_link_to_nowhere_is_named_so(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    shutil.rmtree(root / "episode_0001")
    (root / "episode_0001").symlink_to(tmp_path / "gone")
    code, out, _ = verify(capsys, root)
    assert code == 1 and out[0] == "episode_0001: a link to nowhere, not a folder (2 files listed)"


@pytest.mark.parametrize("change, problem", [
    ({"episodes_planned": -1}, "episodes_planned is -1, expected an integer >= 0"),
    ({"episodes_planned": 1.5}, "episodes_planned is 1.5, expected an integer >= 0"),
    ({"episode_layout": 0}, "episode_layout is 0, expected an integer >= 1"),
    ({"episode_layout": True}, "episode_layout is True, expected an integer >= 1"),
    ({"index": "0"}, "episodes[0] lacks an integer index and frames, a name or a files mapping"),
    ({"frames": True}, "episodes[0] lacks an integer index and frames, a name or a files mapping"),
    ({"index": -1}, "episodes[0]: index -1, expected >= 0"),
    ({"files": ["meta.json", "people.csv"]}, "episodes[0] lacks an integer index and frames, a name or a files mapping"),
])
def test_a_manifest_with_a_value_out_of_bounds_is_not_read(tmp_path, capsys, change, problem):
    root = dataset(tmp_path / "ds", 1)
    m = json.loads((root / MANIFEST).read_text())
    top = {k: v for k, v in change.items() if k.startswith("episode")}
    m.update(top)
    m["episodes"][0].update({k: v for k, v in change.items() if k not in top})
    (root / MANIFEST).write_text(json.dumps(m))
    line = f"camtask verify: error: cannot read {root / MANIFEST} (not a camtask manifest: {problem})"
    assert verify(capsys, root) == (2, [], line)


def test_a_manifest_of_an_unknown_checksum_is_not_verified(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    m = json.loads((root / MANIFEST).read_text())
    (root / MANIFEST).write_text(json.dumps(m | {"checksum": "md5"}))
    line = "camtask verify: error: manifest: checksum 'md5'; expected one of blake3, sha256"
    assert verify(capsys, root) == (2, [], line)


def test_a_manifest_at_its_bounds_is_read(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    m = json.loads((root / MANIFEST).read_text())
    (root / MANIFEST).write_text(json.dumps(m | {"episodes_planned": 0, "episode_layout": 1}))
    assert verify(capsys, root)[:2] == (0, [f"{root}: 2 episodes intact (4 files, blake3)"])


def test_an_unfinished_run_is_said_so_without_failing(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    manifest = json.loads((root / MANIFEST).read_text())
    manifest["episodes_planned"] = 5
    (root / MANIFEST).write_text(json.dumps(manifest))
    code, out, _ = verify(capsys, root)
    assert code == 0 and out == ["2 of 5 planned episodes listed: an unfinished run (`--resume` finishes it)",
                                 f"{root}: 2 episodes intact (4 files, blake3)"]


@pytest.mark.parametrize("meta", ["not json {", '{"episode": 1}', "[1, 2]"])
def test_a_changed_meta_json_that_names_no_episode_is_only_changed(tmp_path, capsys, meta):
    root = dataset(tmp_path / "ds", 1)
    (root / "episode_0001" / "meta.json").write_text(meta)
    code, out, _ = verify(capsys, root)
    assert code == 1 and out == ["episode_0001: 1 changed (meta.json)",
                                 f"{root}: 1 of 2 episodes differ from {MANIFEST} (episode_0001)"]


def test_an_episode_named_dot_is_sent_to_its_dataset(tmp_path, capsys, monkeypatch):
    root = dataset(tmp_path / "ds", 1)
    monkeypatch.chdir(root / "episode_0000")
    assert main(["verify", "."]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"camtask verify: error: DIR: . is an episode of the dataset {root.resolve()}, whose {MANIFEST} lists it: "
        f"verify the dataset (camtask verify {root.resolve()})")]


def test_one_episode_of_a_manifest_that_plans_none_is_intact(tmp_path, capsys):
    root = dataset(tmp_path / "ds", 1)
    shutil.rmtree(root / "episode_0001")
    manifest = json.loads((root / MANIFEST).read_text())
    manifest["episodes"] = manifest["episodes"][:1]
    del manifest["episodes_planned"]
    (root / MANIFEST).write_text(json.dumps(manifest))
    code, out, _ = verify(capsys, root)
    assert code == 0 and out == [f"{root}: 1 episode intact (2 files, blake3)"]
