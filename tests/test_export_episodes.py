"""testbed.wildtrack.export_episode of small hand-made episodes (no rendering): positions
worked by hand, boxes of hand-drawn masks, frames and calibration read back with OpenCV."""

import json
import os
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from scene.camera import Camera
from testbed.dataset import write_calibration
from testbed.png import write_png
from testbed.wildtrack import export_episode

LAB = Path(__file__).parents[1] / "assets" / "scenes" / "lab.yaml"
W, H = 64, 48                                          # pixels
K = np.array([[40.0, 0.0, 31.5], [0.0, 40.0, 23.5], [0.0, 0.0, 1.0]])


def make_episode(folder, positions, labels, dist=(0.05, 0.0, 0.0, 0.0, 0.0), cameras=(2, 5)):
    """An episode folder as `camtask render` writes one (the files export reads).

    positions : (frames, people, 2) metres, world frame
    labels : {(camera number, frame): (H, W) uint8 mask, person id + 1}; other masks empty;
        the silhouettes are the same pixels (bit i: person i)
    """
    frames, people = positions.shape[:2]
    rng = np.random.default_rng(7)
    (folder / "calibration").mkdir(parents=True)
    for n in cameras:
        write_calibration(folder / "calibration" / f"cam{n:02d}.yaml",
                          Camera(n, K, np.array(dist, float), np.eye(3), np.array([-1.0, -2.0, 4.0 + n]), W, H))
        for sub in ("frames", "masks", "silhouettes"):
            (folder / sub / f"cam{n:02d}").mkdir(parents=True)
        for f in range(frames):
            write_png(folder / "frames" / f"cam{n:02d}" / f"{f:06d}.png", rng.integers(0, 256, (H, W, 3), np.uint8))
            mask = labels.get((n, f), np.zeros((H, W), np.uint8))
            write_png(folder / "masks" / f"cam{n:02d}" / f"{f:06d}.png", mask)
            bits = np.where(mask > 0, np.left_shift(1, mask.astype(np.uint16) - 1), 0).astype(np.uint16)
            write_png(folder / "silhouettes" / f"cam{n:02d}" / f"{f:06d}.png", bits)   # no one hides anyone
    rows = [f"{f},{i},{float(x)!r},{float(y)!r},0.25,1.75" for f in range(frames) for i, (x, y) in enumerate(positions[f])]
    (folder / "people.csv").write_text("\n".join(["frame,person_id,x,y,radius,height", *rows]) + "\n")
    (folder / "meta.json").write_text(json.dumps({"episode": 0, "cameras": list(cameras), "frames": frames,
                                                  "people": people, "format": "png",
                                                  "scene_yaml": LAB.read_text()}))
    return folder


def annotations(out, frame):
    return json.loads((out / "annotations_positions" / f"{frame:08d}.json").read_text())


def box(view, xmin, ymin, xmax, ymax):
    return {"viewNum": view, "xmin": xmin, "ymin": ymin, "xmax": xmax, "ymax": ymax}


NONE = (-1, -1, -1, -1)


def test_the_defaults_copy_the_frames_keep_the_lens_and_box_the_masks_drawn(tmp_path):
    positions = np.array([[[1.0126, 0.4999], [0.0, 5.7899]],
                          [[6.7055, 0.001], [3.01, 3.01]]])
    labels = {(2, 0): np.zeros((H, W), np.uint8), (5, 0): np.zeros((H, W), np.uint8),
              (5, 1): np.zeros((H, W), np.uint8)}
    labels[2, 0][0:4, 60:64] = 1                       # person 0 in the top right corner of camera 2
    labels[5, 0][10:21, 5:10] = 1
    labels[5, 0][14, 7] = 0                            # a hole changes no bound
    labels[5, 0][47, 0] = 2                            # person 1: the bottom left pixel
    labels[5, 1][5:7, 30:32] = 1
    ep = make_episode(tmp_path / "episode_0000", positions, labels)
    calls = []
    out = export_episode(ep, tmp_path / "wt", progress=calls.append)     # the defaults: as `camtask export`
    assert calls == [1] * 4                                              # one per image written
    # positionID = x_index + 269 y_index, worked by hand: floor(1.0126 / 0.025) = 40, floor(0.4999 / 0.025) = 19
    assert annotations(out, 0) == [
        {"personID": 0, "positionID": 40 + 269 * 19, "views": [box(0, 60, 0, 63, 3), box(1, 5, 10, 9, 20)]},
        {"personID": 1, "positionID": 0 + 269 * 231, "views": [box(0, *NONE), box(1, 0, 47, 0, 47)]}]
    assert annotations(out, 1) == [
        {"personID": 0, "positionID": 268 + 269 * 0, "views": [box(0, *NONE), box(1, 30, 5, 31, 6)]},
        {"personID": 1, "positionID": 120 + 269 * 120, "views": [box(0, *NONE), box(1, *NONE)]}]
    for n in (2, 5):
        for f in (0, 1):
            exported = cv2.imread(str(out / "Image_subsets" / f"C{n}" / f"{f:08d}.png"), cv2.IMREAD_UNCHANGED)
            np.testing.assert_array_equal(exported, cv2.imread(str(ep / "frames" / f"cam{n:02d}" / f"{f:06d}.png")))
        fs = cv2.FileStorage(str(out / "calibrations" / "intrinsic_zero" / f"intr_C{n}.xml"), cv2.FILE_STORAGE_READ)
        np.testing.assert_array_equal(fs.getNode("camera_matrix").mat(), K)
        np.testing.assert_array_equal(fs.getNode("distortion_coefficients").mat(), [[0.05, 0, 0, 0, 0]])
        fs.release()
    grid = json.loads((out / "grid.json").read_text())
    assert (grid["undistorted"], grid["boxes"], grid["layout"]) == (False, "visible", "wildtrack")


def test_an_episode_of_no_one_exports_its_frames_and_empty_annotations(tmp_path):
    ep = make_episode(tmp_path / "episode_0000", np.zeros((2, 0, 2)), {})
    out = export_episode(ep, tmp_path / "wt")
    assert [annotations(out, f) for f in (0, 1)] == [[], []]
    assert sorted(p.name for p in (out / "Image_subsets" / "C5").iterdir()) == ["00000000.png", "00000001.png"]


def test_undistort_remaps_the_frames_and_the_border_outside_the_lens_is_black_and_no_one(tmp_path):
    """A pincushion lens (k1 > 0): the pinhole image's corners lie outside the rendered
    frame. They are black in the frame and no one's pixels in the masks, so a person
    nowhere in a view still has no box there."""
    dist = (0.3, 0.0, 0.0, 0.0, 0.0)
    mask = np.zeros((H, W), np.uint8)
    mask[20:28, 28:36] = 1                             # person 0 in the middle; person 1 not in view
    ep = make_episode(tmp_path / "episode_0000", np.array([[[1.0, 1.0], [2.0, 2.0]]]), {(2, 0): mask}, dist,
                      cameras=(2,))
    rows, cols = np.mgrid[0:H, 0:W]
    src = np.dstack([4 * cols, 5 * rows, 100 + cols + rows]).astype(np.uint8)   # smooth: interpolation agrees
    write_png(ep / "frames" / "cam02" / "000000.png", src)
    out = export_episode(ep, tmp_path / "pinhole", undistort=True)
    got = cv2.imread(str(out / "Image_subsets" / "C2" / "00000000.png"))[..., ::-1]
    want = cv2.undistort(src, K, np.array(dist))       # OpenCV's pinhole image of the same camera matrix
    assert (got[0, 0] == 0).all() and (got[-1, -1] == 0).all()
    inside = cv2.erode((want != 0).all(axis=2).astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    assert inside.mean() > 0.6 and np.abs(got.astype(int) - want)[inside].max() <= 1
    (a0, a1) = annotations(out, 0)
    assert a1["views"] == [box(0, *NONE)]
    whole = export_episode(ep, tmp_path / "whole", undistort=True, box="unoccluded")
    assert annotations(whole, 0) == [a0, a1]              # the silhouettes' border holds no one either
    rr, cc = np.nonzero(mask)
    pts = cv2.undistortPoints(np.c_[cc, rr].astype(float).reshape(-1, 1, 2), K, np.array(dist), P=K).reshape(-1, 2)
    b = a0["views"][0]
    assert np.abs(np.array([b["xmin"], b["ymin"], b["xmax"], b["ymax"]]) - np.r_[pts.min(0), pts.max(0)]).max() <= 1.5
    fs = cv2.FileStorage(str(out / "calibrations" / "intrinsic_zero" / "intr_C2.xml"), cv2.FILE_STORAGE_READ)
    assert not fs.getNode("distortion_coefficients").mat().any()
    fs.release()
    assert json.loads((out / "grid.json").read_text())["undistorted"] is True


def test_a_video_episode_exports_as_its_png_twin(tmp_path):
    from testbed.lossless import VideoWriter

    mask = np.zeros((H, W), np.uint8)
    mask[3:9, 10:20] = 1
    png = make_episode(tmp_path / "png" / "episode_0000", np.array([[[1.0, 1.0]], [[1.1, 1.0]], [[1.2, 1.0]]]),
                       {(5, 2): mask})
    video = tmp_path / "video" / "episode_0000"
    shutil.copytree(png, video)
    for n in (2, 5):
        writer = VideoWriter(video / "frames" / f"cam{n:02d}.mkv", W, H, 10.0)
        for f in range(3):
            writer.write(cv2.imread(str(png / "frames" / f"cam{n:02d}" / f"{f:06d}.png"))[..., ::-1])
        writer.close()
        shutil.rmtree(video / "frames" / f"cam{n:02d}")
    meta = json.loads((video / "meta.json").read_text())
    (video / "meta.json").write_text(json.dumps(meta | {"format": "video"}))
    a, b = export_episode(png, tmp_path / "a"), export_episode(video, tmp_path / "b")
    for n in (2, 5):
        for f in range(3):
            name = f"Image_subsets/C{n}/{f:08d}.png"
            np.testing.assert_array_equal(cv2.imread(str(b / name)), cv2.imread(str(a / name)))
    assert [annotations(b, f) for f in range(3)] == [annotations(a, f) for f in range(3)]
    assert annotations(b, 2)[0]["views"][1] == box(1, 10, 3, 19, 8)


def test_the_multiviewx_layout_names_and_matrices(tmp_path):
    """MultiviewX's names (4-digit images, 5-digit annotations, intr_/extr_Camera<n>.xml under
    calibrations/intrinsic) and rvec, tvec as 3 x 1 FileStorage matrices, as the episode's own."""
    mask = np.zeros((H, W), np.uint8)
    mask[2:5, 7:9] = 1
    ep = make_episode(tmp_path / "episode_0000", np.array([[[1.0, 2.0]], [[1.5, 2.0]]]), {(5, 1): mask})
    out = export_episode(ep, tmp_path / "mvx", layout="multiviewx")
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()) == [
        "Image_subsets/C2/0000.png", "Image_subsets/C2/0001.png", "Image_subsets/C5/0000.png",
        "Image_subsets/C5/0001.png", "annotations_positions/00000.json", "annotations_positions/00001.json",
        "calibrations/extrinsic/extr_Camera2.xml", "calibrations/extrinsic/extr_Camera5.xml",
        "calibrations/intrinsic/intr_Camera2.xml", "calibrations/intrinsic/intr_Camera5.xml", "grid.json"]
    assert json.loads((out / "annotations_positions" / "00001.json").read_text()) == [
        {"personID": 0, "positionID": 60 + 269 * 80, "views": [box(0, *NONE), box(1, 7, 2, 8, 4)]}]
    for n in (2, 5):
        fs = cv2.FileStorage(str(ep / "calibration" / f"cam{n:02d}.yaml"), cv2.FILE_STORAGE_READ)
        want = {k: fs.getNode(k).mat() for k in ("rvec", "tvec")}
        fs.release()
        np.testing.assert_array_equal(want["tvec"].ravel(), [-1.0, -2.0, 4.0 + n])
        fs = cv2.FileStorage(str(out / "calibrations" / "extrinsic" / f"extr_Camera{n}.xml"), cv2.FILE_STORAGE_READ)
        for k in ("rvec", "tvec"):
            got = fs.getNode(k).mat()
            assert got.shape == (3, 1) and got.dtype == np.float64, k
            np.testing.assert_array_equal(got, want[k].reshape(3, 1))
        fs.release()


def test_unoccluded_boxes_of_persons_8_and_up_come_from_the_high_bits(tmp_path):
    """Ten people: person 9's silhouette is bit 9 of a 16-bit silhouette image."""
    mask = np.zeros((H, W), np.uint8)
    mask[1:3, 1:4] = 1                                 # person 0
    mask[30:35, 40:50] = 10                            # person 9
    positions = np.column_stack([np.linspace(1.0, 5.0, 10), np.full(10, 2.0)])[None]
    ep = make_episode(tmp_path / "episode_0000", positions, {(2, 0): mask}, cameras=(2,))
    assert cv2.imread(str(ep / "silhouettes" / "cam02" / "000000.png"), cv2.IMREAD_UNCHANGED)[30, 40] == 512
    for kind in ("visible", "unoccluded"):
        ann = annotations(export_episode(ep, tmp_path / kind, box=kind), 0)
        assert [a["views"] for a in ann] == [[box(0, 1, 1, 3, 2)], *[[box(0, *NONE)]] * 8, [box(0, 40, 30, 49, 34)]]


def test_an_export_replaces_an_earlier_one_whole_and_leaves_nothing_beside_it(tmp_path, monkeypatch):
    from testbed import wildtrack

    ep = make_episode(tmp_path / "episode_0000", np.array([[[1.0, 2.0]]]), {})
    out = export_episode(ep, tmp_path / "wt")
    (out / "stale.txt").write_text("x")
    export_episode(ep, out)
    assert not (out / "stale.txt").exists() and (out / "grid.json").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episode_0000", "wt"]
    real = os.rename

    def rename(src, dst):                              # the new export cannot be moved into place
        if Path(src).name.startswith(".wt.") and ".replaced-" not in Path(src).name:
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(wildtrack.os, "rename", rename)
    (out / "mine.txt").write_text("kept")
    with pytest.raises(OSError, match="No space left"):
        export_episode(ep, out)
    assert (out / "mine.txt").read_text() == "kept" and (out / "grid.json").is_file()   # the earlier one, back
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episode_0000", "wt"]


def test_an_unknown_layout_or_box_is_refused_before_any_folder_is_made(tmp_path):
    ep = make_episode(tmp_path / "episode_0000", np.array([[[1.0, 2.0]]]), {})
    with pytest.raises(ValueError, match=r"^layout: expected one of wildtrack, multiviewx, got 'mot'$"):
        export_episode(ep, tmp_path / "new" / "wt", layout="mot")
    with pytest.raises(ValueError, match=r"^box: expected one of visible, unoccluded, got 'all'$"):
        export_episode(ep, tmp_path / "new" / "wt", box="all")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episode_0000"]


def test_a_room_centred_on_the_origin_has_its_grid_from_the_corner_of_its_bounds(tmp_path):
    """The circle scene's room, radius 1 m about the origin: the grid starts at (-1, -1) m,
    80 x 80 cells; a person at the origin is in cell (40, 40): positionID 40 + 80 * 40."""
    ep = make_episode(tmp_path / "episode_0000", np.array([[[0.0, 0.0], [-0.99, 0.99]]]), {})
    meta = json.loads((ep / "meta.json").read_text())
    circle = (LAB.parent / "circle.yaml").read_text()
    (ep / "meta.json").write_text(json.dumps(meta | {"scene_yaml": circle}))
    out = export_episode(ep, tmp_path / "wt")
    grid = json.loads((out / "grid.json").read_text())
    assert (grid["origin_m"], grid["grid_width"], grid["grid_height"]) == ([-1.0, -1.0], 80, 80)
    # (-0.99, 0.99): floor(0.01 / 0.025) = 0, floor(1.99 / 0.025) = 79
    assert [a["positionID"] for a in annotations(out, 0)] == [40 + 80 * 40, 0 + 80 * 79]


def test_grid_json_holds_the_grid_the_position_ids_are_on(tmp_path):
    """grid.json's cell, origin and width decode each positionID back to the cell of its
    person; the lab (22 x 19 ft = 6.7056 x 5.7912 m) is ceil(268.22) x ceil(231.65) cells."""
    positions = np.array([[[1.0126, 0.4999], [6.7, 5.79], [3.3, 0.02]]])
    ep = make_episode(tmp_path / "episode_0000", positions, {})
    out = export_episode(ep, tmp_path / "wt")
    grid = json.loads((out / "grid.json").read_text())
    assert (grid["cell_m"], grid["origin_m"], grid["grid_width"], grid["grid_height"]) == (0.025, [0.0, 0.0], 269, 232)
    assert grid["views"] == {"0": 2, "1": 5} and grid["units"] == "metres, world frame"
    assert grid["source"] == str(ep.resolve())
    for a, (x, y) in zip(annotations(out, 0), positions[0], strict=True):
        gx, gy = a["positionID"] % grid["grid_width"], a["positionID"] // grid["grid_width"]
        assert gy < grid["grid_height"]
        assert grid["origin_m"][0] + gx * grid["cell_m"] <= x < grid["origin_m"][0] + (gx + 1) * grid["cell_m"]
        assert grid["origin_m"][1] + gy * grid["cell_m"] <= y < grid["origin_m"][1] + (gy + 1) * grid["cell_m"]


def test_ctrl_c_while_the_new_export_is_moved_into_place_leaves_the_new_one_whole(tmp_path, monkeypatch):
    """Ctrl-C just after the earlier export was moved aside waits until the new one is in
    place: taken there, the earlier one was deleted and the new one never moved in (no export left)."""
    import signal

    from testbed import wildtrack

    ep = make_episode(tmp_path / "episode_0000", np.array([[[1.0, 2.0]]]), {})
    out = export_episode(ep, tmp_path / "wt")
    (out / "stale.txt").write_text("x")
    real = os.replace

    def replace(src, dst):                             # Ctrl-C once the earlier export is aside
        real(src, dst)
        os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(wildtrack.os, "replace", replace)
    with pytest.raises(KeyboardInterrupt):
        export_episode(ep, out)
    assert (out / "grid.json").is_file() and not (out / "stale.txt").exists()     # the new export
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episode_0000", "wt"]


def test_undistort_maps_point_each_pinhole_pixel_at_its_distorted_pixel():
    """The maps, worked with the Brown-Conrady model by hand: pinhole pixel (u, v) is the
    normalised point ((u - cx) / fx, (v - cy) / fy), distorted, then through the same K
    (whose principal point is off the image centre here: it stays where it is)."""
    from testbed.wildtrack import undistort_maps

    K = np.array([[40.0, 0.0, 29.0], [0.0, 42.0, 26.5], [0.0, 0.0, 1.0]])
    dist = np.array([-0.2, 0.05, 0.001, -0.002, 0.01])
    mx, my = undistort_maps(K, dist, (W, H))
    assert mx.shape == my.shape == (H, W) and mx.dtype == my.dtype == np.float32
    v, u = np.mgrid[0:H, 0:W].astype(float)
    x, y = (u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1]
    k1, k2, p1, p2, k3 = dist
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    np.testing.assert_allclose(mx, K[0, 0] * xd + K[0, 2], atol=1e-3)
    np.testing.assert_allclose(my, K[1, 1] * yd + K[1, 2], atol=1e-3)


def test_without_undistort_the_images_are_the_episodes_own_png_files_byte_for_byte(tmp_path):
    """The rendered frames are copied, not decoded and encoded again (which keeps the pixels
    but not the file: its compression, chunks, bit depth)."""
    ep = make_episode(tmp_path / "episode_0000", np.array([[[1.0, 2.0]], [[1.5, 2.0]]]), {})
    frame = ep / "frames" / "cam05" / "000001.png"
    cv2.imwrite(str(frame), cv2.imread(str(frame)), [cv2.IMWRITE_PNG_COMPRESSION, 0])   # as no encoder of ours
    for layout, digits in (("wildtrack", 8), ("multiviewx", 4)):
        out = export_episode(ep, tmp_path / layout, layout=layout)
        for n in (2, 5):
            for f in (0, 1):
                assert (out / "Image_subsets" / f"C{n}" / f"{f:0{digits}d}.png").read_bytes() == \
                    (ep / "frames" / f"cam{n:02d}" / f"{f:06d}.png").read_bytes()


def test_the_new_export_and_the_earlier_one_wait_beside_out_and_the_episode_is_left_alone(tmp_path, monkeypatch):
    """While the new export is renamed into place, it and the earlier one moved aside are
    hidden folders beside OUT (renames in one folder, on one file system); the episode folder
    (a dataset that may be read-only) never holds any of it."""
    from testbed import wildtrack

    ep = make_episode(tmp_path / "data" / "episode_0000", np.array([[[1.0, 2.0]]]), {})
    files = sorted(p.relative_to(ep) for p in ep.rglob("*"))
    out = export_episode(ep, tmp_path / "exports" / "wt")
    real, seen = os.rename, []

    def rename(src, dst):
        seen.append((Path(src), Path(dst), sorted(p.relative_to(ep) for p in ep.rglob("*")),
                     sorted(p.name for p in out.parent.iterdir())))
        return real(src, dst)

    monkeypatch.setattr(wildtrack.os, "rename", rename)
    export_episode(ep, out)
    ((src, dst, in_episode, beside),) = seen
    assert dst == out and src.parent == out.parent and src.name.startswith(".wt.")
    assert len(beside) == 2 and src.name in beside
    aside = next(name for name in beside if name != src.name)
    assert aside.startswith(".wt.replaced-")
    assert in_episode == files
    assert sorted(p.name for p in out.parent.iterdir()) == ["wt"]


def test_an_episode_whose_meta_json_names_no_format_exports_its_png_frames(tmp_path):
    """meta.json's "format" is not one of the keys read_meta requires: without it the frames
    are the PNG files under frames/, as in a `--format png` episode."""
    ep = make_episode(tmp_path / "episode_0000", np.array([[[1.0, 2.0]]]), {})
    meta = json.loads((ep / "meta.json").read_text())
    del meta["format"]
    (ep / "meta.json").write_text(json.dumps(meta))
    out = export_episode(ep, tmp_path / "wt")
    for n in (2, 5):
        assert (out / "Image_subsets" / f"C{n}" / "00000000.png").read_bytes() == \
            (ep / "frames" / f"cam{n:02d}" / "000000.png").read_bytes()
