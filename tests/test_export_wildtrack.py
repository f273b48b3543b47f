"""camtask export wildtrack: boxes agree with the masks, calibration XML loads with cv2.FileStorage."""

import json
import os
import stat
import xml.etree.ElementTree as ET

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from scene import Room
from testbed.cli import main
from testbed.dataset import read_calibration, read_people
from testbed.wildtrack import CELL, boxes, ground_grid, position_id


def test_boxes_of_a_hand_made_mask():
    lab = np.zeros((2, 5, 6), int)
    lab[0, 1:3, 2:5] = 1
    lab[1, 4, 0] = 2
    np.testing.assert_array_equal(boxes(lab, 2), [[[2, 1, 4, 2], [-1, -1, -1, -1]],
                                                 [[-1, -1, -1, -1], [0, 4, 0, 4]]])


@given(st.sampled_from([Room.rectangle(6.7056, 5.7912, 2.7), Room.circle(3.0)]),
       st.floats(0, 1), st.floats(0, 1))
def test_position_ids_decode_to_the_cell_of_every_point_of_the_room(room, u, v):
    # the circle's world origin is its centre: the grid starts at the bounds' corner
    (ox, oy), width, height = ground_grid(room.polygon.bounds)
    minx, miny, maxx, maxy = room.polygon.bounds
    x, y = minx + u * (maxx - minx) * 0.999999, miny + v * (maxy - miny) * 0.999999
    pid = int(position_id([[x, y]], width, (ox, oy))[0])
    gx, gy = pid % width, pid // width
    assert 0 <= pid < width * height
    assert ox + gx * CELL <= x + 1e-9 and x < ox + (gx + 1) * CELL + 1e-9
    assert oy + gy * CELL <= y + 1e-9 and y < oy + (gy + 1) * CELL + 1e-9


def test_a_grid_is_as_many_whole_cells_as_the_room_spans_despite_rounding():
    """0.3 m is 12 cells of 2.5 cm, though 0.2 - (-0.1) is 0.30000000000000004 in floating
    point (and that / 0.025 is 12.000000000000002); 0.31 m needs a 13th cell. A room's
    grid starts at its corner, x along the grid's width."""
    assert ground_grid((-0.1, -0.1, 0.2, 0.2)) == ((-0.1, -0.1), 12, 12)
    assert ground_grid((-0.1, 0.5, 0.21, 0.6)) == ((-0.1, 0.5), 13, 4)
    # (0.01, 0.51) is cell (4, 0) of that grid, (0.2, 0.59) cell (12, 3): x + 13 y
    assert position_id([[0.01, 0.51], [0.2, 0.59]], 13, (-0.1, 0.5)).tolist() == [4, 12 + 13 * 3]


@pytest.mark.render
def test_export_wildtrack(tmp_path, capsys, monkeypatch):
    data, out = tmp_path / "data", tmp_path / "wild"
    assert main(["render", "lab", "--frames", "2", "--seed", "9", "--cameras", "1,6,12", "--out", str(data),
                 "--workers", "0"]) == 0
    assert main(["export", "wildtrack", str(data), str(out), "--episode", "0"]) == 0
    ep = data / "episode_0000"
    grid = json.loads((out / "grid.json").read_text())
    assert grid["grid_width"] == 269 and grid["grid_height"] == 232 and grid["origin_m"] == [0.0, 0.0]
    assert grid["views"] == {"0": 1, "1": 6, "2": 12}
    assert grid["source"] == str(ep.resolve())
    # the episode given as "." from inside it: the same source, not "." (which names nothing elsewhere)
    monkeypatch.chdir(ep)
    assert main(["export", "wildtrack", ".", str(tmp_path / "wild2")]) == 0
    assert json.loads((tmp_path / "wild2" / "grid.json").read_text()) == grid
    people = read_people(ep / "people.csv")
    for f in (0, 1):
        ann = json.loads((out / "annotations_positions" / f"{f:08d}.json").read_text())
        rows = people[people["frame"] == f]
        assert [a["personID"] for a in ann] == rows["person_id"].tolist()
        for a, row in zip(ann, rows):
            gx, gy = a["positionID"] % 269, a["positionID"] // 269
            assert gx * CELL <= row["x"] < (gx + 1) * CELL and gy * CELL <= row["y"] < (gy + 1) * CELL
            assert [v["viewNum"] for v in a["views"]] == [0, 1, 2]
        for v, n in enumerate((1, 6, 12)):
            labels = cv2.imread(str(ep / "masks" / f"cam{n:02d}" / f"{f:06d}.png"), cv2.IMREAD_UNCHANGED)
            img = cv2.imread(str(out / "Image_subsets" / f"C{n}" / f"{f:08d}.png"))
            assert img.shape == (480, 640, 3)
            for a in ann:
                b = a["views"][v]
                mask = labels == a["personID"] + 1
                if not mask.any():
                    assert (b["xmin"], b["ymin"], b["xmax"], b["ymax"]) == (-1, -1, -1, -1)
                    continue
                rr, cc = np.nonzero(mask)
                assert (b["xmin"], b["ymin"], b["xmax"], b["ymax"]) == (cc.min(), rr.min(), cc.max(), rr.max())
    seen = sum(a["views"][v]["xmin"] >= 0 for a in ann for v in range(3))
    assert seen >= 3
    for n in (1, 6, 12):
        K, dist, rvec, tvec = _calibration(out, n)
        assert K.shape == (3, 3) and dist.shape == (1, 5) and rvec.shape == tvec.shape == (3, 1)
        c = read_calibration(ep / "calibration" / f"cam{n:02d}.yaml")
        assert np.array_equal(rvec.ravel(), c["rvec"].ravel()) and np.array_equal(tvec.ravel(), c["tvec"].ravel())
        # as MVDet's WILDTRACK reader parses them: the element's text split on single spaces
        root = ET.parse(out / "calibrations" / "extrinsic" / f"extr_C{n}.xml").getroot()
        for name, value in (("rvec", rvec), ("tvec", tvec)):
            text = root.findall(name)[0].text.lstrip().rstrip().split(" ")
            assert np.array_equal(np.array([float(x) for x in text]), value.ravel())
    assert position_id([[0.0, 0.0]], 269).tolist() == [0]
    assert main(["export", "wildtrack", str(data), str(out)]) == 2          # OUT exists
    before = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    (out / "stale.txt").write_text("x")
    assert main(["export", "wildtrack", str(data), str(out), "--overwrite"]) == 0   # an earlier export: replaced
    assert {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("x")
    capsys.readouterr()
    assert main(["export", "wildtrack", str(data), str(tmp_path / "mine"), "--overwrite"]) == 2  # not an export
    assert capsys.readouterr().err.strip() == (
        f"camtask export: error: --overwrite: {tmp_path / 'mine'} is not an export of camtask (no grid.json; "
        "it holds notes.txt); empty it yourself or choose another folder")
    assert [p.name for p in (tmp_path / "mine").iterdir()] == ["notes.txt"]
    (tmp_path / "mine" / "grid.json").write_text('{"rows": 3}')     # another tool's grid.json: not ours either
    assert main(["export", "wildtrack", str(data), str(tmp_path / "mine"), "--overwrite"]) == 2
    assert capsys.readouterr().err.strip() == (
        f"camtask export: error: --overwrite: {tmp_path / 'mine'} is not an export of camtask (its grid.json is "
        "not one; it holds grid.json, notes.txt); empty it yourself or choose another folder")
    assert sorted(p.name for p in (tmp_path / "mine").iterdir()) == ["grid.json", "notes.txt"]
    assert main(["export", "wildtrack", str(data), str(tmp_path / "x"), "--episode", "5"]) == 2
    with open(ep / "people.csv", "a") as fh:     # a file changed since the manifest: refused
        fh.write("0,9,1.0,1.0,0.25,1.8\n")
    capsys.readouterr()
    assert main(["export", "wildtrack", str(data), str(tmp_path / "x")]) == 2
    assert capsys.readouterr().err.strip() == ("camtask export: error: DIR: episode_0000 differs from its manifest "
                                               "(1 changed (people.csv)); `camtask verify` names every such file")
    assert not (tmp_path / "x").exists()


def _calibration(out, n):
    fs = cv2.FileStorage(str(out / "calibrations" / "intrinsic_zero" / f"intr_C{n}.xml"), cv2.FILE_STORAGE_READ)
    K, dist = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
    fs.release()
    fs = cv2.FileStorage(str(out / "calibrations" / "extrinsic" / f"extr_C{n}.xml"), cv2.FILE_STORAGE_READ)
    rvec, tvec = (np.array([[node.at(i).real()] for i in range(node.size())])   # sequences, (3, 1)
                  for node in (fs.getNode("rvec"), fs.getNode("tvec")))
    fs.release()
    return K, dist, rvec, tvec


def _box_errors(out, people, frames, ignore_distortion=False):
    """Largest |box - projected cylinder's box|, pixels, per view where one person is wholly in the image."""
    errors = []
    a, z = np.meshgrid(np.linspace(0, 2 * np.pi, 720, endpoint=False), np.linspace(0, 1, 200))
    views = json.loads((out / "grid.json").read_text())["views"]
    for f in range(frames):
        (ann,) = json.loads((out / "annotations_positions" / f"{f:08d}.json").read_text())
        (p,) = people[people["frame"] == f]
        surface = np.stack([p["x"] + p["radius"] * np.cos(a).ravel(), p["y"] + p["radius"] * np.sin(a).ravel(),
                            p["height"] * z.ravel()], 1)                       # metres, world frame
        for v, n in views.items():
            K, dist, rvec, tvec = _calibration(out, n)
            if (cv2.Rodrigues(rvec)[0] @ surface.T + tvec)[2].min() <= 0:
                continue
            uv = cv2.projectPoints(surface, rvec, tvec, K, 0 * dist if ignore_distortion else dist)[0].reshape(-1, 2)
            if uv.min() < 0 or uv[:, 0].max() > 639 or uv[:, 1].max() > 479:
                continue
            b = ann["views"][int(v)]
            box = np.array([b["xmin"], b["ymin"], b["xmax"], b["ymax"]])
            errors.append(np.abs(np.r_[uv.min(0), uv.max(0)] - box).max())
    return np.array(errors)


@pytest.mark.render
def test_boxes_match_the_exported_calibration_with_and_without_undistortion(tmp_path):
    # one person: the box is the whole cylinder's, which the exported calibration projects
    data = tmp_path / "data"
    assert main(["render", "lab", "--frames", "3", "--seed", "5", "--people", "1", "--out", str(data),
                 "--workers", "0"]) == 0
    people = read_people(data / "episode_0000" / "people.csv")
    raw, pinhole = tmp_path / "raw", tmp_path / "pinhole"
    assert main(["export", "wildtrack", str(data), str(raw)]) == 0
    assert main(["export", "wildtrack", str(data), str(pinhole), "--undistort"]) == 0
    assert not json.loads((raw / "grid.json").read_text())["undistorted"]
    assert json.loads((pinhole / "grid.json").read_text())["undistorted"]
    for n in range(1, 17):
        assert np.abs(_calibration(raw, n)[1]).max() > 0 and not _calibration(pinhole, n)[1].any()
    e_raw, e_pinhole = _box_errors(raw, people, 3), _box_errors(pinhole, people, 3)
    assert len(e_raw) >= 10 and len(e_pinhole) >= 10
    assert e_raw.max() < 1.5 and e_pinhole.max() < 1.5          # rasterisation: within a pixel and a half
    # the distorted frames projected with the camera matrix alone miss by several pixels
    assert _box_errors(raw, people, 3, ignore_distortion=True).max() > 4
    img = cv2.imread(str(pinhole / "Image_subsets" / "C3" / "00000000.png"))
    assert img.shape == (480, 640, 3) and (img.reshape(-1, 3).any(axis=1)).all()   # no empty border


@pytest.mark.parametrize("given, out, extra, message", [
    ("data", "data", [], "is DIR"),
    ("data", "data/episode_0000/wild", [], "is inside DIR"),
    ("data", "data/wild", [], "is inside DIR"),
    ("data/episode_0000", ".", ["--overwrite"], "holds DIR"),
    ("data/episode_0000", "data", ["--overwrite"], "holds DIR"),
    # an episode given as DIR: its dataset is kept clear too (--resume would delete the export)
    ("data/episode_0000", "data/episode_0002", [], f"is inside the dataset {{tmp}}{os.sep}data;"),
    ("data/episode_0000", "data/wild", [], "is inside the dataset"),
])
def test_export_refuses_an_out_that_is_in_or_holds_the_dataset(tmp_path, monkeypatch, capsys, given, out, extra,
                                                               message):
    """--overwrite would delete the dataset; inside it, the export would break an episode's checksums."""
    episode = tmp_path / "data" / "episode_0000"
    episode.mkdir(parents=True)
    (episode / "meta.json").write_text("{}")
    (tmp_path / "data" / "manifest.json").write_text("{}")
    message = message.format(tmp=tmp_path.resolve())
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    monkeypatch.chdir(tmp_path)
    assert main(["export", "wildtrack", given, out, *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("camtask export: error: OUT: ") and message in err and "\n" not in err
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before


def test_episode_option_that_contradicts_an_episode_dir_is_refused(tmp_path, capsys):
    episode = tmp_path / "ds" / "episode_0001"
    episode.mkdir(parents=True)
    (episode / "meta.json").write_text(json.dumps({"episode": 1}))
    capsys.readouterr()
    assert main(["export", "wildtrack", str(episode), str(tmp_path / "wt"), "--episode", "5"]) == 2
    err = capsys.readouterr().err
    assert "--episode 5: DIR" in err and "is episode 1 itself" in err and not (tmp_path / "wt").exists()


@pytest.mark.render
def test_undistorted_boxes_of_several_people_bound_their_own_undistorted_pixels(tmp_path):
    """--undistort with several people: each box is that person's label pixels moved to the
    pinhole image (cv2.undistortPoints, independent of the export's remap), within 2 pixels.
    Labels remapped bilinearly would blend ids 0 and 3 into 1 and 2 around person 2 and
    stretch the other people's boxes over it."""
    import json

    import cv2

    from testbed.cli import main
    from testbed.dataset import read_calibration

    data, out = tmp_path / "data", tmp_path / "pinhole"
    assert main(["render", "lab", "--frames", "1", "--seed", "3", "--cameras", "1,6,12", "--out", str(data),
                 "--workers", "0"]) == 0
    assert main(["export", "wildtrack", str(data), str(out), "--undistort"]) == 0
    ep = data / "episode_0000"
    ann = json.loads((out / "annotations_positions" / "00000000.json").read_text())
    checked = 0
    for v, n in enumerate((1, 6, 12)):
        c = read_calibration(ep / "calibration" / f"cam{n:02d}.yaml")
        labels = cv2.imread(str(ep / "masks" / f"cam{n:02d}" / "000000.png"), cv2.IMREAD_UNCHANGED)
        for a in ann:
            b = a["views"][v]
            rr, cc = np.nonzero(labels == a["personID"] + 1)
            if rr.size == 0:
                continue
            pts = cv2.undistortPoints(np.c_[cc, rr].astype(float).reshape(-1, 1, 2), c["K"], c["dist"], P=c["K"])
            pts = pts.reshape(-1, 2)
            inside = (pts[:, 0] >= -0.5) & (pts[:, 0] < 639.5) & (pts[:, 1] >= -0.5) & (pts[:, 1] < 479.5)
            if inside.sum() < 50:
                continue                               # (nearly) all outside the pinhole image
            pts = pts[inside]
            want = np.r_[pts.min(0), pts.max(0)]
            got = np.array([b["xmin"], b["ymin"], b["xmax"], b["ymax"]])
            assert np.abs(got - want).max() <= 2.0, (n, a["personID"], got, want)
            checked += 1
    assert checked >= 3


@pytest.mark.render
def test_ctrl_c_stops_the_export_at_the_next_frame(tmp_path, monkeypatch):
    """Ctrl-C during an export waited until every camera being exported had written all its
    frames (a thread pool's shutdown): ~9 s for 300 frames. It stops at the next frame."""
    import signal
    import threading

    from testbed import wildtrack

    data, out = tmp_path / "data", tmp_path / "wild"
    assert main(["render", "lab", "--frames", "12", "--seed", "9", "--cameras", "1,6", "--out", str(data),
                 "--workers", "0"]) == 0
    monkeypatch.setattr("testbed.parallel.default_workers", lambda: 2)
    written = []
    lock = threading.Lock()
    interrupted = threading.Event()

    def ctrl_c(signum, frame):                          # Python's own handler, and marks when it ran
        interrupted.set()
        raise KeyboardInterrupt

    def progress(n):
        with lock:
            written.append(n)
            if len(written) == 1:
                os.kill(os.getpid(), signal.SIGINT)      # Ctrl-C after the first image
        # the main thread takes the signal; on a loaded machine that can take longer than the
        # cameras' every frame, so the cameras wait for it here, then take a while per frame
        interrupted.wait(30)
        threading.Event().wait(0.05)

    previous = signal.signal(signal.SIGINT, ctrl_c)
    try:
        with pytest.raises(KeyboardInterrupt):
            wildtrack.export_episode(data / "episode_0000", out, "wildtrack", undistort=True, progress=progress)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert interrupted.is_set()
    assert len(written) <= 4, len(written)               # not 2 cameras x 12 frames
    assert not out.exists() and not list(tmp_path.glob(".wild*"))


@pytest.mark.render
def test_ctrl_c_while_an_earlier_export_is_replaced_keeps_a_whole_one(tmp_path, monkeypatch, capsys):
    """--overwrite deleted the earlier export, then renamed the new one into place: Ctrl-C while
    it deleted left part of the old one without its grid.json, which --overwrite then refused."""
    import shutil

    from testbed import wildtrack

    data, out = tmp_path / "data", tmp_path / "wild"
    assert main(["render", "lab", "--frames", "2", "--seed", "9", "--cameras", "1,6", "--out", str(data),
                 "--workers", "0"]) == 0
    assert main(["export", "wildtrack", str(data), str(out)]) == 0
    real, calls = shutil.rmtree, []

    def interrupted(path, *a, **k):              # deletes grid.json first, then Ctrl-C
        calls.append(path)
        if len(calls) == 1 and os.path.isfile(os.path.join(path, "grid.json")):
            os.unlink(os.path.join(path, "grid.json"))
            raise KeyboardInterrupt
        return real(path, *a, **k)

    monkeypatch.setattr(wildtrack.shutil, "rmtree", interrupted)
    assert main(["export", "wildtrack", str(data), str(out), "--overwrite", "--undistort"]) == 130
    monkeypatch.undo()
    assert (out / "grid.json").is_file()         # a whole export, the old or the new one
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "wild"]
    assert main(["export", "wildtrack", str(data), str(out), "--overwrite"]) == 0


def hand_made_episode(folder):
    """A one-frame episode of one person, two small cameras, no manifest (test_export_episodes)."""
    import numpy as np

    from tests.test_export_episodes import H, W, make_episode

    mask = np.zeros((H, W), np.uint8)
    mask[5:9, 10:12] = 1
    return make_episode(folder, np.array([[[1.0, 2.0]]]), {(2, 0): mask})


def export_files(root):
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


@pytest.mark.parametrize(("argv", "line"), [
    (["--episode", "-1"], "--episode: expected an integer >= 0, got -1"),
    (["--boxes", "all"], None),                     # argparse's own choices
])
def test_bad_options_are_one_line_and_write_nothing(tmp_path, capsys, argv, line):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    capsys.readouterr()
    if line is None:
        with pytest.raises(SystemExit) as stop:
            main(["export", "wildtrack", str(episode.parent), str(tmp_path / "wt"), *argv])
        assert stop.value.code == 2 and "argument --boxes: invalid choice: 'all'" in capsys.readouterr().err
    else:
        assert main(["export", "wildtrack", str(episode.parent), str(tmp_path / "wt"), *argv]) == 2
        assert capsys.readouterr().err.splitlines() == [f"camtask export: error: {line}"]
    assert not (tmp_path / "wt").exists()


def test_an_unknown_layout_is_refused_before_anything_is_read(tmp_path, capsys):
    """argparse's choices: the export's own check came after DIR and OUT were looked at."""
    capsys.readouterr()
    with pytest.raises(SystemExit) as stop:
        main(["export", "mvdet", str(tmp_path / "none"), str(tmp_path / "wt")])
    assert stop.value.code == 2 and "argument layout: invalid choice: 'mvdet'" in capsys.readouterr().err
    assert not (tmp_path / "wt").exists()


@pytest.mark.parametrize("kind", ["file", "fifo"])
def test_an_out_that_is_a_file_is_refused_and_kept(tmp_path, capsys, kind):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    if kind == "file":
        (tmp_path / "wt").write_text("mine")
    else:
        os.mkfifo(tmp_path / "wt")                  # neither a folder nor a regular file
    capsys.readouterr()
    for extra in ([], ["--overwrite"]):
        assert main(["export", "wildtrack", str(episode), str(tmp_path / "wt"), *extra]) == 2
        assert capsys.readouterr().err.splitlines() == [
            f"camtask export: error: OUT: {tmp_path / 'wt'} exists and is not a directory"]
    if kind == "file":
        assert (tmp_path / "wt").read_text() == "mine"
    else:
        assert stat.S_ISFIFO(os.lstat(tmp_path / "wt").st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds", "wt"]


@pytest.mark.parametrize("grid", ["not json {", '{"layout": "wildtrack"}', "[1, 2]",
                                  '{"layout": "wildtrack", "cell_m": 0.025, "views": {"0": 1}}',   # no position_id
                                  '{"layout": "wildtrack", "position_id": {}, "views": {"0": 1}}',  # no cell_m
                                  '{"layout": "wildtrack", "cell_m": 0.025, "position_id": {}}',    # no views
                                  '{"layout": "other", "cell_m": 0.025, "position_id": {}, "views": []}'])
def test_overwrite_refuses_a_folder_whose_grid_json_is_not_an_exports(tmp_path, capsys, grid):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    out = tmp_path / "wt"
    out.mkdir()
    (out / "grid.json").write_text(grid)
    capsys.readouterr()
    assert main(["export", "wildtrack", str(episode), str(out), "--overwrite"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"camtask export: error: --overwrite: {out} is not an export of camtask (its grid.json is not one; it holds "
        "grid.json); empty it yourself or choose another folder")]
    assert export_files(out) == {"grid.json": grid.encode()}


@pytest.mark.parametrize("index", [0, 3])
def test_an_episode_dir_is_taken_whatever_its_index_and_an_episode_option_that_agrees(tmp_path, index):
    """Without --episode, an episode folder is taken whatever its index (0 is only the
    dataset's default); --episode with its own index is taken too, of the episode or the
    dataset folder: the same export."""
    episode = hand_made_episode(tmp_path / "ds" / f"episode_{index:04d}")
    meta = json.loads((episode / "meta.json").read_text())
    (episode / "meta.json").write_text(json.dumps(meta | {"episode": index}))
    assert main(["export", "wildtrack", str(episode), str(tmp_path / "a")]) == 0
    assert main(["export", "wildtrack", str(episode), str(tmp_path / "b"), "--episode", str(index)]) == 0
    assert main(["export", "wildtrack", str(episode.parent), str(tmp_path / "c"), "--episode", str(index)]) == 0
    a = export_files(tmp_path / "a")
    assert "annotations_positions/00000000.json" in a
    assert export_files(tmp_path / "b") == a == export_files(tmp_path / "c")


def test_a_dir_or_episode_that_is_not_there_is_named(tmp_path, capsys):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    (tmp_path / "file").write_text("x")
    capsys.readouterr()
    for folder, extra, line in (
            (tmp_path / "none", [], (f"DIR: {tmp_path / 'none'}: no such folder (expected a dataset or episode folder "
                                    "written by `camtask render`)")),
            (tmp_path / "file", [], (f"DIR: {tmp_path / 'file'}: not a folder (expected a dataset or episode folder "
                                    "written by `camtask render`)")),
            (episode.parent, ["--episode", "3"], (f"DIR: no episode 3 in {episode.parent} (expected "
                                                 f"{episode.parent / 'episode_0003'}/meta.json)"))):
        assert main(["export", "wildtrack", str(folder), str(tmp_path / "wt"), *extra]) == 2
        assert capsys.readouterr().err.splitlines() == [f"camtask export: error: {line}"]
    assert not (tmp_path / "wt").exists()


def test_an_out_that_holds_the_current_folder_is_refused(tmp_path, monkeypatch, capsys):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    (tmp_path / "wt" / "here").mkdir(parents=True)
    monkeypatch.chdir(tmp_path / "wt" / "here")
    capsys.readouterr()
    assert main(["export", "wildtrack", str(episode), str(tmp_path / "wt"), "--overwrite"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"camtask export: error: OUT: {tmp_path / 'wt'} is the current folder or holds it, which the export would "
        "replace; give a folder beside it")]
    assert (tmp_path / "wt" / "here").is_dir()


def test_an_episode_folder_that_is_a_link_is_checked_where_its_manifest_lists_it(tmp_path, capsys):
    """The manifest lists the link by its name beside it; OUT inside the folder it points to is refused."""
    import json

    from testbed.episodes import checksums

    target = hand_made_episode(tmp_path / "elsewhere" / "episode_0000")
    (tmp_path / "ds").mkdir()
    (tmp_path / "ds" / "episode_0000").symlink_to(target, target_is_directory=True)
    entry = {"index": 0, "name": "episode_0000", "seed": 0, "spawn_key": [0], "frames": 1, "files": checksums(target)}
    (tmp_path / "ds" / "manifest.json").write_text(json.dumps({"format_version": 2, "checksum": "blake3",
                                                               "episodes_planned": 1, "episodes": [entry]}))
    capsys.readouterr()
    assert main(["export", "wildtrack", str(tmp_path / "ds"), str(target / "wt")]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"camtask export: error: OUT: {target / 'wt'} is inside DIR {tmp_path / 'ds' / 'episode_0000'}; "
        "choose a folder outside the dataset")]
    assert main(["export", "wildtrack", str(tmp_path / "ds"), str(tmp_path / "wt")]) == 0
    assert "no manifest lists" not in capsys.readouterr().err and (tmp_path / "wt" / "grid.json").is_file()


def test_the_last_line_names_the_episode_the_layout_and_out(tmp_path, capsys):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    for layout, extra, line in (("wildtrack", [], "as WILDTRACK layout to"),
                                ("multiviewx", ["--undistort"], "as MultiviewX layout (undistorted) to")):
        capsys.readouterr()
        assert main(["export", layout, str(episode), str(tmp_path / layout), *extra]) == 0
        err = capsys.readouterr().err
        assert err.splitlines()[-1] == f"wrote {episode} {line} {tmp_path / layout}"
        assert "100%" in err and "| 2/2 [" in err                # the bar counts images: 2 cameras x 1 frame
        grid = json.loads((tmp_path / layout / "grid.json").read_text())
        assert (grid["layout"], grid["undistorted"], grid["boxes"]) == (layout, bool(extra), "visible")


def test_overwrite_refuses_a_folder_whose_grid_json_is_a_folder(tmp_path, capsys):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    out = tmp_path / "wt"
    (out / "grid.json").mkdir(parents=True)
    capsys.readouterr()
    assert main(["export", "wildtrack", str(episode), str(out), "--overwrite"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"camtask export: error: --overwrite: {out} is not an export of camtask (its grid.json is not one; it holds "
         "grid.json); empty it yourself or choose another folder")]
    assert (out / "grid.json").is_dir() and not any((out / "grid.json").iterdir())


def test_read_grid_gives_an_exports_grid(tmp_path):
    from testbed.commands.export import read_grid

    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    assert main(["export", "multiviewx", str(episode), str(tmp_path / "wt")]) == 0
    grid = read_grid(tmp_path / "wt" / "grid.json")
    assert grid == json.loads((tmp_path / "wt" / "grid.json").read_text())
    assert (grid["layout"], grid["source"]) == ("multiviewx", str(episode))


def test_an_episode_of_a_sha256_manifest_is_checked_with_sha256(tmp_path, capsys):
    """A dataset written before manifest format 2 lists sha256 checksums (no "checksum" key):
    its episodes export, and a changed file is still named."""
    from testbed.episodes import checksums

    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    entry = {"index": 0, "name": "episode_0000", "seed": 0, "spawn_key": [0], "frames": 1,
             "files": checksums(episode, algorithm="sha256")}
    (tmp_path / "ds" / "manifest.json").write_text(json.dumps({"format_version": 1, "episodes_planned": 1,
                                                               "episodes": [entry]}))
    capsys.readouterr()
    assert main(["export", "wildtrack", str(tmp_path / "ds"), str(tmp_path / "wt")]) == 0
    assert "warning" not in capsys.readouterr().err and (tmp_path / "wt" / "grid.json").is_file()
    (episode / "people.csv").write_text((episode / "people.csv").read_text().replace("1.0,2.0", "1.5,2.0"))
    assert main(["export", "wildtrack", str(tmp_path / "ds"), str(tmp_path / "wt2")]) == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        "camtask export: error: DIR: episode_0000 differs from its manifest (1 changed (people.csv)); "
        "`camtask verify` names every such file")


def test_an_out_inside_the_dataset_that_lists_an_episode_link_is_refused(tmp_path, capsys):
    """DIR an episode folder that is a link: the dataset beside the link (whose manifest lists
    it) is kept clear as an episode's own dataset is, and so is the dataset the link leads into.
    Only the link target's folder was looked at: an export into the dataset beside the link was written."""
    from testbed.episodes import checksums

    target = hand_made_episode(tmp_path / "elsewhere" / "episode_0000")
    (tmp_path / "elsewhere" / "manifest.json").write_text("{}")
    (tmp_path / "ds").mkdir()
    (tmp_path / "ds" / "episode_0000").symlink_to(target, target_is_directory=True)
    entry = {"index": 0, "name": "episode_0000", "seed": 0, "spawn_key": [0], "frames": 1, "files": checksums(target)}
    (tmp_path / "ds" / "manifest.json").write_text(json.dumps({"format_version": 2, "checksum": "blake3",
                                                               "episodes_planned": 1, "episodes": [entry]}))
    for dataset in ("ds", "elsewhere"):
        capsys.readouterr()
        assert main(["export", "wildtrack", str(tmp_path / "ds" / "episode_0000"),
                     str(tmp_path / dataset / "episode_0001")]) == 2
        assert capsys.readouterr().err.splitlines() == [
            (f"camtask export: error: OUT: {tmp_path / dataset / 'episode_0001'} is inside the dataset "
             f"{tmp_path / dataset}; choose a folder outside the dataset")]
    assert sorted(p.name for p in (tmp_path / "ds").iterdir()) == ["episode_0000", "manifest.json"]
    assert sorted(p.name for p in (tmp_path / "elsewhere").iterdir()) == ["episode_0000", "manifest.json"]
    assert main(["export", "wildtrack", str(tmp_path / "ds" / "episode_0000"), str(tmp_path / "wt")]) == 0


def test_an_out_that_is_a_link_into_the_dataset_is_refused(tmp_path, capsys):
    """OUT is where its link leads: the export would be written into the dataset."""
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    (tmp_path / "link").symlink_to(tmp_path / "ds" / "wt")      # to a folder not made yet
    capsys.readouterr()
    assert main(["export", "wildtrack", str(tmp_path / "ds"), str(tmp_path / "link")]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"camtask export: error: OUT: {tmp_path / 'link'} is inside DIR {tmp_path / 'ds'}; "
         "choose a folder outside the dataset")]
    assert sorted(p.name for p in (tmp_path / "ds").iterdir()) == [episode.name]


def test_an_episode_option_takes_the_dataset_folder_of_that_name(tmp_path):
    """Only an episode DIR's own index is held against --episode: a dataset's episode_0002
    is episode 2, whatever index its meta.json (here a copy of episode 0's) holds."""
    episode = hand_made_episode(tmp_path / "ds" / "episode_0002")
    assert json.loads((episode / "meta.json").read_text())["episode"] == 0
    assert main(["export", "wildtrack", str(tmp_path / "ds"), str(tmp_path / "wt"), "--episode", "2"]) == 0
    assert json.loads((tmp_path / "wt" / "grid.json").read_text())["source"] == str(episode)


def test_a_refused_out_names_its_first_files_in_name_order(tmp_path, capsys):
    episode = hand_made_episode(tmp_path / "ds" / "episode_0000")
    out = tmp_path / "mine"
    out.mkdir()
    for name in ("e.txt", "b.txt", "f.txt", "a.txt", "d.txt", "c.txt"):
        (out / name).write_text("x")
    capsys.readouterr()
    assert main(["export", "wildtrack", str(episode), str(out), "--overwrite"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"camtask export: error: --overwrite: {out} is not an export of camtask (no grid.json; it holds a.txt, "
         "b.txt, c.txt and 3 more); empty it yourself or choose another folder")]
    assert len(list(out.iterdir())) == 6
