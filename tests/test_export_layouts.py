"""camtask export: the MultiviewX layout, boxes of unoccluded silhouettes, and OUTs or episodes that are not as expected."""

import json
import os
import shutil

import cv2
import numpy as np
import pytest

from testbed.cli import main
from testbed.dataset import read_people
from testbed.wildtrack import boxes, silhouette_boxes

pytestmark = pytest.mark.render

CAMERAS = (1, 6, 12)


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """A 2-frame lab dataset of 6 people seen by cameras 1, 6 and 12 (someone is behind someone)."""
    out = tmp_path_factory.mktemp("export") / "data"
    assert main(["render", "lab", "--frames", "2", "--seed", "4", "--people", "6", "--cameras", "1,6,12",
                 "--out", str(out), "--workers", "0"]) == 0
    return out


def annotations(out, frame, digits=8):
    return {a["personID"]: a for a in json.loads((out / "annotations_positions" / f"{frame:0{digits}d}.json").read_text())}


def files(root):
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def test_multiviewx_layout_reads_as_multiviewx_readers_read_it(data, tmp_path):
    wild, mvx = tmp_path / "wild", tmp_path / "mvx"
    assert main(["export", "wildtrack", str(data), str(wild)]) == 0
    assert main(["export", "multiviewx", str(data), str(mvx)]) == 0
    assert json.loads((mvx / "grid.json").read_text())["layout"] == "multiviewx"
    for n in CAMERAS:
        assert sorted(p.name for p in (mvx / "Image_subsets" / f"C{n}").iterdir()) == ["0000.png", "0001.png"]
        for f in (0, 1):
            assert (mvx / "Image_subsets" / f"C{n}" / f"{f:04d}.png").read_bytes() == \
                (wild / "Image_subsets" / f"C{n}" / f"{f:08d}.png").read_bytes()
        # as MVDet's MultiviewX reader: calibrations/intrinsic, FileStorage matrices for rvec and tvec
        fs = cv2.FileStorage(str(mvx / "calibrations" / "intrinsic" / f"intr_Camera{n}.xml"), cv2.FILE_STORAGE_READ)
        K = fs.getNode("camera_matrix").mat()
        fs.release()
        fs = cv2.FileStorage(str(mvx / "calibrations" / "extrinsic" / f"extr_Camera{n}.xml"), cv2.FILE_STORAGE_READ)
        rvec, tvec = fs.getNode("rvec").mat().squeeze(), fs.getNode("tvec").mat().squeeze()
        fs.release()
        fs = cv2.FileStorage(str(wild / "calibrations" / "intrinsic_zero" / f"intr_C{n}.xml"), cv2.FILE_STORAGE_READ)
        np.testing.assert_array_equal(K, fs.getNode("camera_matrix").mat())
        fs.release()
        fs = cv2.FileStorage(str(wild / "calibrations" / "extrinsic" / f"extr_C{n}.xml"), cv2.FILE_STORAGE_READ)
        for got, name in ((rvec, "rvec"), (tvec, "tvec")):
            node = fs.getNode(name)
            np.testing.assert_array_equal(got, [node.at(i).real() for i in range(3)])
        fs.release()
    for f in (0, 1):
        assert annotations(mvx, f, 5) == annotations(wild, f)
    assert not (mvx / "calibrations" / "intrinsic_zero").exists()


def test_unoccluded_boxes_bound_the_silhouettes_and_hold_the_visible_boxes(data, tmp_path):
    vis, whole = tmp_path / "vis", tmp_path / "whole"
    assert main(["export", "wildtrack", str(data), str(vis)]) == 0
    assert main(["export", "wildtrack", str(data), str(whole), "--boxes", "unoccluded"]) == 0
    assert json.loads((whole / "grid.json").read_text())["boxes"] == "unoccluded"
    ep = data / "episode_0000"
    differ = 0
    for f in (0, 1):
        a_vis, a_whole = annotations(vis, f), annotations(whole, f)
        for v, n in enumerate(CAMERAS):
            sil = cv2.imread(str(ep / "silhouettes" / f"cam{n:02d}" / f"{f:06d}.png"), cv2.IMREAD_UNCHANGED)
            for pid, a in a_whole.items():
                b, bv = a["views"][v], a_vis[pid]["views"][v]
                rr, cc = np.nonzero((sil.astype(int) >> pid) & 1)
                want = (cc.min(), rr.min(), cc.max(), rr.max()) if rr.size else (-1, -1, -1, -1)
                assert (b["xmin"], b["ymin"], b["xmax"], b["ymax"]) == want
                if bv["xmin"] >= 0:        # the visible pixels are a part of the silhouette
                    assert b["xmin"] <= bv["xmin"] and b["ymin"] <= bv["ymin"]
                    assert b["xmax"] >= bv["xmax"] and b["ymax"] >= bv["ymax"]
                differ += (b != bv)
    assert differ >= 1                      # somebody is partly hidden in this walk


def test_box_helpers_agree_on_a_person_nobody_hides():
    labels = np.zeros((1, 4, 5), int)
    labels[0, 1:3, 1:4] = 1
    np.testing.assert_array_equal(silhouette_boxes(labels, 1), boxes(labels, 1))


def test_boxes_follow_person_ids_not_row_order_and_a_missing_row_is_refused(data, tmp_path, capsys):
    ep = tmp_path / "copied"
    shutil.copytree(data / "episode_0000", ep)
    ref = tmp_path / "ref"
    assert main(["export", "wildtrack", str(ep), str(ref)]) == 0
    lines = (ep / "people.csv").read_text().splitlines()
    (ep / "people.csv").write_text("\n".join([lines[0], *reversed(lines[1:])]) + "\n")
    shuffled = tmp_path / "shuffled"
    assert main(["export", "wildtrack", str(ep), str(shuffled)]) == 0
    for f in (0, 1):
        assert annotations(shuffled, f) == annotations(ref, f)
    (ep / "people.csv").write_text("\n".join(line for line in lines if not line.startswith("0,2,")) + "\n")
    capsys.readouterr()
    assert main(["export", "wildtrack", str(ep), str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"camtask export: error: {ep}/people.csv: expected one row per person (0..5) and frame "
                       "(0..1), as meta.json says; its 11 rows do not") and "image/s" not in err[-2]  # no bar
    assert not (tmp_path / "x").exists()


def test_damaged_episode_gives_one_line_and_leaves_nothing(data, tmp_path, capsys):
    ep = tmp_path / "copied"
    shutil.copytree(data / "episode_0000", ep)
    (ep / "frames" / "cam06" / "000001.png").unlink()
    for extra in ([], ["--undistort"]):
        capsys.readouterr()
        assert main(["export", "wildtrack", str(ep), str(tmp_path / "deep" / "wt"), *extra]) == 2
        err = capsys.readouterr().err
        assert err.splitlines()[-1] == f"camtask export: error: image: cannot read '{ep}/frames/cam06/000001.png'"
        assert "Traceback" not in err and not (tmp_path / "deep").exists()   # the folder made for OUT is gone too


@pytest.mark.parametrize("out", [".", ""])
def test_out_that_is_the_current_folder_is_refused_and_kept(data, tmp_path, monkeypatch, capsys, out):
    earlier = tmp_path / "earlier"
    assert main(["export", "wildtrack", str(data), str(earlier)]) == 0
    before = files(earlier)
    monkeypatch.chdir(earlier)
    capsys.readouterr()
    assert main(["export", "wildtrack", str(data), out, "--overwrite"]) == 2
    assert capsys.readouterr().err.strip() == (
        "camtask export: error: OUT: . is the current folder or holds it, which the export would replace; "
        "give a folder beside it")
    assert files(earlier) == before


def test_out_inside_another_datasets_episode_or_under_a_file_is_refused(data, tmp_path, capsys):
    other = tmp_path / "other"
    (other / "episode_0000").mkdir(parents=True)
    (other / "manifest.json").write_text("{}")
    (tmp_path / "afile").write_text("x")
    for out, message in ((other / "episode_0000" / "wt", "is inside"), (tmp_path / "afile" / "sub", "afile is not")):
        capsys.readouterr()
        assert main(["export", "wildtrack", str(data), str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("camtask export: error: OUT: ") and message in err and "\n" not in err
    assert sorted(p.name for p in (other / "episode_0000").iterdir()) == []


def test_an_out_whose_folders_cannot_be_made_leaves_none_and_proc_is_refused_first(data, tmp_path, capsys):
    from testbed.commands.export import check_export_out

    out = tmp_path / "newdir" / ("x" * 300) / "out"          # a name too long for the file system
    assert main(["export", "wildtrack", str(data), str(out)]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith(
        f"camtask export: error: OUT: cannot make the folder {out.parent} (File name too long")
    assert not (tmp_path / "newdir").exists()
    with pytest.raises(ValueError, match=r"OUT: cannot write to /proc \("):   # os.access says yes to root
        check_export_out("/proc/xx", False)


def test_out_that_links_to_an_empty_folder_is_written_through(data, tmp_path):
    (tmp_path / "target").mkdir()
    os.symlink(tmp_path / "target", tmp_path / "link")
    assert main(["export", "wildtrack", str(data), str(tmp_path / "link")]) == 0
    assert (tmp_path / "link").is_symlink() and (tmp_path / "target" / "grid.json").is_file()


def test_truncated_video_is_named(tmp_path, capsys):
    data = tmp_path / "vid"
    assert main(["render", "lab", "--frames", "3", "--cameras", "2", "--format", "video", "--out", str(data),
                 "--workers", "0"]) == 0
    ep = tmp_path / "copied"
    shutil.copytree(data / "episode_0000", ep)
    video = ep / "frames" / "cam02.mkv"
    video.write_bytes(video.read_bytes()[: video.stat().st_size // 2])
    capsys.readouterr()
    assert main(["export", "wildtrack", str(ep), str(tmp_path / "wt")]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    # Matroska's demuxer reports the cut when it opens the file, before the first frame: none is taken
    assert err.startswith(f"camtask export: error: video: cannot read '{video}' after 0 frames") and err.endswith(
        "(truncated or corrupt)")
    assert not (tmp_path / "wt").exists()
    assert read_people(ep / "people.csv").size == 9
    # a video longer than meta.json says is named too (it was cut short without a word)
    shutil.copy(data / "episode_0000" / "frames" / "cam02.mkv", video)
    meta = json.loads((ep / "meta.json").read_text())
    (ep / "meta.json").write_text(json.dumps(meta | {"frames": 2}))
    lines = (ep / "people.csv").read_text().splitlines()
    (ep / "people.csv").write_text("\n".join(line for line in lines if not line.startswith("2,")) + "\n")
    assert main(["export", "wildtrack", str(ep), str(tmp_path / "wt")]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        f"camtask export: error: video: {video} holds more than 2 frames; meta.json says 2")
