"""camtask export of an episode folder whose meta.json or calibration is not as `camtask render` writes them:
one line naming the file (and the key), before the progress bar and before any folder is made."""

import json
from pathlib import Path

import pytest

from scene import load_scene
from testbed.cli import main
from testbed.dataset import write_calibration


@pytest.fixture
def episode(tmp_path):
    """An episode folder copied out of its dataset (no manifest): meta.json, calibration, people.csv."""
    ep = tmp_path / "episode_0003"
    (ep / "calibration").mkdir(parents=True)
    lab = Path(__file__).parents[1] / "assets" / "scenes" / "lab.yaml"
    scene = load_scene("lab")
    for cam in scene.cameras[:2]:
        write_calibration(ep / "calibration" / f"cam{cam.number:02d}.yaml", cam)
    (ep / "meta.json").write_text(json.dumps({"episode": 3, "cameras": [1, 2], "frames": 1, "people": 1,
                                              "format": "png", "scene_yaml": lab.read_text()}))
    (ep / "people.csv").write_text("frame,person_id,x,y,radius,height\n0,0,2.0,2.0,0.25,1.75\n")
    return ep


def meta_with(ep, **changes):
    meta = json.loads((ep / "meta.json").read_text())
    for k, v in changes.items():
        if v is None:
            del meta[k]
        else:
            meta[k] = v
    (ep / "meta.json").write_text(json.dumps(meta))


def export_error(ep, capsys, *extra):
    out = ep.parent / "new" / "wt"
    capsys.readouterr()
    assert main(["export", "wildtrack", str(ep), str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "export:" not in err.replace("camtask export:", "")   # no bar
    assert not (ep.parent / "new").exists()
    return err.strip().splitlines()[-1].removeprefix("camtask export: error: ")


@pytest.mark.parametrize(("change", "message"), [
    ({"frames": None}, "meta.json: no 'frames' (expected an integer >= 1)"),
    ({"people": None}, "meta.json: no 'people' (expected an integer >= 0)"),
    ({"cameras": None}, "meta.json: no 'cameras' (expected a non-empty list of distinct camera numbers >= 1)"),
    ({"frames": "2"}, 'meta.json: frames: expected an integer >= 1, got "2"'),
    ({"frames": 0}, "meta.json: frames: expected an integer >= 1, got 0"),
    ({"cameras": [1, 1]}, ("meta.json: cameras: expected a non-empty list of distinct camera numbers >= 1, "
                           "got [1, 1]")),
    ({"cameras": [1, 0]}, ("meta.json: cameras: expected a non-empty list of distinct camera numbers >= 1, "
                           "got [1, 0]")),
    ({"people": -1}, "meta.json: people: expected an integer >= 0, got -1"),
    ({"scene_yaml": None}, "meta.json: no 'scene_yaml' (expected the scene file's text)"),
])
def test_a_meta_json_without_what_export_reads_is_one_line(episode, capsys, change, message):
    meta_with(episode, **change)
    assert export_error(episode, capsys) == f"{episode}/{message}"


def test_a_meta_json_that_is_not_an_object_or_not_json_names_the_file(episode, capsys):
    (episode / "meta.json").write_text("[1, 2]")
    assert export_error(episode, capsys) == f"{episode}/meta.json: expected a JSON object, got list"
    (episode / "meta.json").write_text("{bad")
    assert export_error(episode, capsys).startswith(f"{episode}/meta.json: not valid JSON (Expecting property")
    # with --episode, whose check read it first
    assert export_error(episode, capsys, "--episode", "3").startswith(f"{episode}/meta.json: not valid JSON")


def test_a_missing_or_malformed_calibration_names_the_file(episode, capsys):
    """A missing one was AttributeError: 'NoneType' object has no attribute 'ravel'."""
    (episode / "calibration" / "cam02.yaml").unlink()
    assert export_error(episode, capsys) == f"calibration: no such file '{episode}/calibration/cam02.yaml'"
    (episode / "calibration" / "cam02.yaml").write_text("%YAML:1.0\n---\ncamera_number: 2\n")
    assert export_error(episode, capsys).startswith("calibration: cam02.yaml has no ")


@pytest.mark.parametrize("where", [".", "calibration/.."])
def test_an_episode_given_as_the_current_folder_is_checked_against_its_manifest(episode, capsys, monkeypatch,
                                                                               where):
    """Given as ``.`` (or a path ending in ``..``) the episode's name was ``""``: no manifest
    entry matched, and a changed file was exported with "warning: no manifest lists ;"."""
    from testbed.checksum import file_digest

    data = episode.parent / "data"                  # a dataset beside OUT, not holding it
    data.mkdir()
    episode = episode.rename(data / episode.name)
    files = {p.relative_to(episode).as_posix(): file_digest(p) for p in sorted(episode.rglob("*")) if p.is_file()}
    (data / "manifest.json").write_text(json.dumps(
        {"format_version": 2, "episode_layout": 3, "checksum": "blake3", "episodes_planned": 4,
         "episodes": [{"index": 3, "name": "episode_0003", "seed": 0, "spawn_key": [3], "frames": 1,
                       "files": files}]}))
    (episode / "people.csv").write_text("frame,person_id,x,y,radius,height\n0,0,3.0,2.0,0.25,1.75\n")
    monkeypatch.chdir(episode)
    capsys.readouterr()
    assert main(["export", "wildtrack", where, str(data.parent / "wt")]) == 2
    assert capsys.readouterr().err.strip() == ("camtask export: error: DIR: episode_0003 differs from its manifest "
                                               "(1 changed (people.csv)); `camtask verify` names every such file")
    assert not (data.parent / "wt").exists()


def test_a_dir_that_does_not_exist_or_is_a_file_is_named_so(episode, capsys):
    """It said 'no episode 0 in DIR', as if the folder held other episodes."""
    expected = " (expected a dataset or episode folder written by `camtask render`)"
    assert export_error(episode.parent / "nowhere", capsys) == f"DIR: {episode.parent / 'nowhere'}: no such folder{expected}"
    assert export_error(episode / "people.csv", capsys) == f"DIR: {episode / 'people.csv'}: not a folder{expected}"


def test_an_episode_folder_that_is_a_link_is_checked_against_the_manifest_beside_the_link(episode, capsys):
    """Resolved, the link led to the target's parent, where no manifest lists it: a changed file was
    exported with only a warning."""
    from testbed.checksum import file_digest

    files = {p.relative_to(episode).as_posix(): file_digest(p) for p in sorted(episode.rglob("*")) if p.is_file()}
    data = episode.parent / "data"
    data.mkdir()
    (data / "episode_0003").symlink_to(episode)
    (data / "manifest.json").write_text(json.dumps(
        {"format_version": 2, "episode_layout": 3, "checksum": "blake3", "episodes_planned": 4,
         "episodes": [{"index": 3, "name": "episode_0003", "seed": 0, "spawn_key": [3], "frames": 1,
                       "files": files}]}))
    (episode / "people.csv").write_text("frame,person_id,x,y,radius,height\n0,0,3.0,2.0,0.25,1.75\n")
    capsys.readouterr()
    assert main(["export", "wildtrack", str(data / "episode_0003"), str(data.parent / "wt")]) == 2
    assert capsys.readouterr().err.strip() == ("camtask export: error: DIR: episode_0003 differs from its manifest "
                                               "(1 changed (people.csv)); `camtask verify` names every such file")


@pytest.mark.parametrize(("change", "message"), [
    ({"frames": True}, "frames: expected an integer >= 1, got true"),
    ({"people": False}, "people: expected an integer >= 0, got false"),
    ({"cameras": []}, "cameras: expected a non-empty list of distinct camera numbers >= 1, got []"),
    ({"cameras": [1, True]}, "cameras: expected a non-empty list of distinct camera numbers >= 1, got [1, true]"),
    ({"scene_yaml": 5}, "scene_yaml: expected the scene file's text, got 5"),
    ({"frames": 2.0}, "frames: expected an integer >= 1, got 2.0"),
    ({"cameras": [1, 2.0]}, "cameras: expected a non-empty list of distinct camera numbers >= 1, got [1, 2.0]"),
])
def test_read_meta_takes_no_booleans_or_floats_for_counts_and_needs_a_camera(episode, change, message):
    from testbed.dataset import read_meta

    meta_with(episode, **change)
    with pytest.raises(ValueError) as err:
        read_meta(episode)
    assert str(err.value) == f"{episode / 'meta.json'}: {message}"


def test_read_meta_takes_an_episode_of_no_people_and_an_incomplete_one_when_asked(episode):
    from testbed.dataset import read_meta

    meta_with(episode, people=0)
    assert read_meta(episode)["people"] == 0
    meta_with(episode, frames=None, cameras=None)
    assert sorted(read_meta(episode, complete=False)) == ["episode", "format", "people", "scene_yaml"]
    with pytest.raises(ValueError, match="no 'cameras'"):
        read_meta(episode)


def test_read_meta_shows_a_long_value_cut_short(episode):
    """A scene given as a parsed mapping, not its text, is shown by its first characters only."""
    from testbed.dataset import read_meta

    meta_with(episode, scene_yaml={"cameras": [{"number": n, "position": [1.0, 2.0, 3.0]} for n in range(16)]})
    with pytest.raises(ValueError) as err:
        read_meta(episode)
    assert str(err.value).startswith(f"{episode / 'meta.json'}: scene_yaml: expected the scene file's text, "
                                     'got {"cameras": [{"number": 0,')
    assert len(str(err.value)) < len(str(episode)) + 150


def test_read_meta_of_a_missing_or_unreadable_meta_json_names_it(episode):
    """Named as other input files are: open() says "[Errno 2] No such file or directory" and
    raises IsADirectoryError for a folder and UnicodeDecodeError for bytes not UTF-8."""
    from testbed.dataset import read_meta

    path = episode / "meta.json"
    path.unlink()
    with pytest.raises(FileNotFoundError) as err:
        read_meta(episode)
    assert str(err.value) == f"meta.json: no such file {str(path)!r}"
    path.mkdir()
    with pytest.raises(ValueError) as err:
        read_meta(episode)
    assert str(err.value) == f"meta.json: {str(path)!r} is a folder, not a file"
    path.rmdir()
    path.write_bytes(b'{"episode": 3, "scene_yaml": "caf\xe9"}')
    with pytest.raises(ValueError) as err:
        read_meta(episode, complete=False)
    assert str(err.value) == f"meta.json: {str(path)!r} is not UTF-8 text (byte 0xe9 at offset 33)"
