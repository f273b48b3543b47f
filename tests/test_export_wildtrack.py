"""camtask export wildtrack: boxes agree with the masks, calibration XML loads with cv2.FileStorage."""

import json

import cv2
import numpy as np
import pytest

from testbed.cli import main
from testbed.dataset import read_people
from testbed.wildtrack import CELL, boxes, position_id


def test_boxes_of_a_hand_made_mask():
    lab = np.zeros((2, 5, 6), int)
    lab[0, 1:3, 2:5] = 1
    lab[1, 4, 0] = 2
    np.testing.assert_array_equal(boxes(lab, 2), [[[2, 1, 4, 2], [-1, -1, -1, -1]],
                                                 [[-1, -1, -1, -1], [0, 4, 0, 4]]])


@pytest.mark.render
def test_export_wildtrack(tmp_path):
    data, out = tmp_path / "data", tmp_path / "wild"
    assert main(["render", "lab", "--frames", "2", "--seed", "9", "--cameras", "1,6,12", "--out", str(data),
                 "--workers", "0"]) == 0
    assert main(["export", "wildtrack", str(data), str(out), "--episode", "0"]) == 0
    ep = data / "episode_0000"
    grid = json.loads((out / "grid.json").read_text())
    assert grid["grid_width"] == 269 and grid["grid_height"] == 232 and grid["views"] == {"0": 1, "1": 6, "2": 12}
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
        fs = cv2.FileStorage(str(out / "calibrations" / "intrinsic_zero" / f"intr_C{n}.xml"), cv2.FILE_STORAGE_READ)
        K, dist = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
        fs.release()
        fs = cv2.FileStorage(str(out / "calibrations" / "extrinsic" / f"extr_C{n}.xml"), cv2.FILE_STORAGE_READ)
        rvec, tvec = fs.getNode("rvec").mat(), fs.getNode("tvec").mat()
        fs.release()
        assert K.shape == (3, 3) and dist.shape == (1, 5) and rvec.shape == tvec.shape == (3, 1)
    assert position_id([[0.0, 0.0]], 269).tolist() == [0]
    assert main(["export", "wildtrack", str(data), str(out)]) == 2          # OUT exists
    assert main(["export", "wildtrack", str(data), str(tmp_path / "x"), "--episode", "5"]) == 2
