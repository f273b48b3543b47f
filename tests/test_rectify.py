"""Rectification to a level virtual camera against independent references: OpenCV's
undistortion and projection, the level camera's rotation written out from its yaw, and
pinhole formulas."""

import cv2
import numpy as np
import pytest

import scene
from scene import load_scene

LAB = load_scene("lab").cameras


def level_rotation_by_hand(cam):
    """Camera frame -> level frame: the level camera's axes (x right, y down, z along the
    yaw on the floor) as rows in the world frame, after the real camera's R.T."""
    c, s = np.cos(cam.yaw), np.sin(cam.yaw)
    return np.array([[s, -c, 0.0], [0.0, 0.0, -1.0], [c, s, 0.0]]) @ cam.R.T


def level_xy(cam, uv):
    """Raw pixels (m, 2) -> (x, y) on the level camera's z = 1 plane, by cv2.undistortPoints."""
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    norm = cv2.undistortPoints(np.asarray(uv, float).reshape(-1, 1, 2), cam.K, cam.dist, None, None, None,
                               crit).reshape(-1, 2)
    rays = np.c_[norm, np.ones(len(norm))] @ level_rotation_by_hand(cam).T
    return rays[:, 0] / rays[:, 2], rays[:, 1] / rays[:, 2]


def dense_border(w, h, n):
    """(4n, 2) points on the outer pixel edges: top, bottom, left, right, corners included."""
    us, vs = np.linspace(-0.5, w - 0.5, n), np.linspace(-0.5, h - 0.5, n)
    return np.concatenate([np.c_[us, np.full(n, -0.5)], np.c_[us, np.full(n, h - 0.5)],
                           np.c_[np.full(n, -0.5), vs], np.c_[np.full(n, w - 0.5), vs]])


CAMERAS = {
    "lab 1": LAB[0],
    "lab 9": LAB[8],
    "pitched up, off-centre, pincushion": scene.Camera.from_pose(
        2, [1.0, 2.0, 1.2], 2.0, np.radians(-20.0), 160, 120, np.radians(60.0), [0.08, -0.02, 0.001, -0.002, 0.0],
        principal=(90.0, 52.0)),
}


@pytest.mark.parametrize("name", CAMERAS)
def test_virtual_extent_is_the_band_and_height_of_the_raw_image_border(name):
    """xmin: the rightmost point of the left edge, xmax: the leftmost of the right edge, y the
    whole border's range, from 4001 OpenCV-undistorted points per side (corners included),
    within 1e-4 pixels of the level camera."""
    from pipeline.rectify import virtual_camera_matrix, virtual_extent

    cam = CAMERAS[name]
    n = 4001
    x, y = level_xy(cam, dense_border(cam.width, cam.height, n))
    want = [x[2 * n:3 * n].max(), x[3 * n:].min(), y.min(), y.max()]
    f = virtual_camera_matrix(cam)[0][0, 0]
    np.testing.assert_allclose(virtual_extent(cam), want, rtol=0, atol=1e-4 / f)


@pytest.mark.parametrize("name", CAMERAS)
def test_the_virtual_camera_puts_the_band_on_its_end_columns_and_the_image_in_its_rows(name):
    """Square pixels; column 0 at the band's left limit and column W - 1 at its right one; row 0
    at the image's top and the last row at or just past its bottom (the border from OpenCV)."""
    from pipeline.rectify import virtual_camera_matrix

    cam = CAMERAS[name]
    n = 4001
    x, y = level_xy(cam, dense_border(cam.width, cam.height, n))
    xmin, xmax, ymin, ymax = x[2 * n:3 * n].max(), x[3 * n:].min(), y.min(), y.max()
    for width in (cam.width, 97):
        K, out_h = virtual_camera_matrix(cam, width)
        f = K[0, 0]
        assert K[1, 1] == f and K[0, 1] == K[1, 0] == 0 and K[2].tolist() == [0, 0, 1]
        tol = 1e-4 / f                                              # 1e-4 pixels
        assert abs((0 - K[0, 2]) / f - xmin) < tol and abs((width - 1 - K[0, 2]) / f - xmax) < tol
        assert abs((0 - K[1, 2]) / f - ymin) < tol
        assert (out_h - 2 - K[1, 2]) / f < ymax - tol and (out_h - 1 - K[1, 2]) / f >= ymax - tol


def test_a_column_threshold_below_the_rows_of_a_column_is_allowed_and_the_rows_are_not():
    """The lab's rectified columns are 552 rows: the ceiling of the image's height on the level
    camera in its pixels, plus one (OpenCV's border, f from the band's width). A column is
    occupied when its count exceeds the threshold, so a threshold of 552 leaves every
    scanline empty, even of a column that is foreground from top to bottom."""
    from pipeline.rectify import check_column_threshold
    from pipeline.scanline import median_threshold

    cam = LAB[0]
    n = 4001
    x, y = level_xy(cam, dense_border(cam.width, cam.height, n))
    f = (cam.width - 1) / (x[3 * n:].min() - x[2 * n:3 * n].max())
    rows = int(np.ceil((y.max() - y.min()) * f)) + 1
    assert rows == 552
    full = np.full((1, 8), float(rows))                 # every pixel of every column foreground
    assert median_threshold(full, 1, rows - 0.5).all() and not median_threshold(full, 1, rows).any()
    check_column_threshold(rows - 0.5, LAB[:2], "--params")
    for refused in (rows, rows + 0.5):
        with pytest.raises(ValueError, match=rf"^--params: column_threshold {refused:g} is not below the 552 pixels"):
            check_column_threshold(refused, LAB[:2], "--params")


@pytest.mark.parametrize("pitch_deg, refused", [(65.0, False), (70.0, True), (-70.0, True)])
def test_a_camera_whose_pixels_look_about_87_degrees_from_level_cannot_be_levelled(pitch_deg, refused):
    """docs/conventions.md: pitch plus half the vertical field of view below about 87 degrees;
    the lab's lens (49 degrees, 18.9 degrees half vertically) pitched 70 degrees down (or up) is
    refused, 65 degrees is not."""
    from pipeline.rectify import level_points

    lab = LAB[0]
    cam = scene.Camera.from_pose(1, [1.0, 2.0, 2.2], 0.5, np.radians(pitch_deg), lab.width, lab.height,
                                 np.radians(49.0), np.zeros(5))
    assert np.degrees(np.arctan((cam.height - 0.5 - cam.K[1, 2]) / cam.K[1, 1])) == pytest.approx(18.9, abs=0.05)
    corners = [[-0.5, -0.5], [cam.width - 0.5, cam.height - 0.5]]
    if refused:
        with pytest.raises(ValueError, match="pitch too steep"):
            level_points(cam, corners)
    else:
        x, y = level_points(cam, corners)
        assert np.all(np.isfinite(x)) and np.all(np.isfinite(y))


def test_nearest_map_picks_the_pixel_that_cv2_remap_reads():
    """Float map entries at and between pixel centres, halves (OpenCV rounds them to even),
    the outer edges, beyond them, and NaN: the integer map's pixel is the one whose value
    cv2.remap (INTER_NEAREST, zero border) returns, and (-1, -1) where it returns the border."""
    from pipeline.rectify import nearest_map

    w, h = 7, 5
    src = (np.arange(w * h, dtype=np.float32).reshape(h, w) + 1)          # every pixel its own non-zero value
    xs = np.array([-1.0, -0.6, -0.5, -0.4, 0.0, 0.5, 1.5, 2.5, 2.49, 2.51, 5.5, 6.0, 6.4, 6.5, 6.6, 7.0, np.nan])
    ys = np.array([-0.6, -0.5, 0.0, 0.5, 1.5, 3.5, 4.0, 4.5, 4.6, np.nan])
    mx, my = (a.astype(np.float32) for a in np.meshgrid(xs, ys))
    want = cv2.remap(src, mx, my, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    fixed = nearest_map(mx, my, (w, h))
    assert fixed.dtype == np.int16 and fixed.shape == mx.shape + (2,)
    outside = np.all(fixed == -1, axis=-1)
    assert np.all(fixed[~outside] >= 0)
    got = np.where(outside, 0, src[fixed[..., 1].clip(0), fixed[..., 0].clip(0)])
    np.testing.assert_array_equal(got, want)
    assert outside.sum() > 0 and (~outside).sum() > 0


def test_entries_on_the_outer_edge_of_the_image_go_onto_its_edge_pixels():
    """x in [-0.5, w - 0.5] is clipped to [0, w - 1], anything else kept; y likewise (by hand)."""
    from pipeline.rectify import onto_edge_pixels

    w, h = 8, 6
    x = np.array([[-0.6, -0.5, -0.2, 0.3, 7.2, 7.5, 7.51, np.nan]])
    y = np.array([[-0.51, -0.5, -0.1, 2.5, 5.3, 5.5, 5.6, 9.0]])
    gx, gy = onto_edge_pixels(x, y, (w, h))
    assert gx.dtype == gy.dtype == np.float32
    np.testing.assert_array_equal(gx, np.float32([[-0.6, 0.0, 0.0, 0.3, 7.0, 7.0, 7.51, np.nan]]))
    np.testing.assert_array_equal(gy, np.float32([[-0.51, 0.0, 0.0, 2.5, 5.0, 5.0, 5.6, 9.0]]))


def test_envelopes_are_the_source_ranges_of_each_output_column_and_row():
    """Against a plain loop over a random integer map with pixels outside (-1, -1), a column
    and a row with none inside, and pixels on source column and row 0."""
    from pipeline.rectify import _envelopes

    rng = np.random.default_rng(4)
    n, ho, wo = 2, 6, 9
    fixed = np.stack([rng.integers(0, 20, (n, ho, wo)), rng.integers(0, 15, (n, ho, wo))], -1)
    fixed[rng.random((n, ho, wo)) < 0.3] = -1
    fixed[0, :, 4] = -1
    fixed[1, 2, :] = -1
    fixed[0, 1, 2] = (0, 0)
    fixed[1, 3, :] = (0, 7)
    column_x, row_y = _envelopes(fixed.astype(np.int16))
    for i in range(n):
        for c in range(wo):
            xs = [fixed[i, r, c, 0] for r in range(ho) if fixed[i, r, c, 0] >= 0]
            if xs:
                assert column_x[i, :, c].tolist() == [min(xs), max(xs)]
            else:
                assert column_x[i, 0, c] > column_x[i, 1, c]
        for r in range(ho):
            ys = [fixed[i, r, c, 1] for c in range(wo) if fixed[i, r, c, 0] >= 0]
            if ys:
                assert row_y[i, :, r].tolist() == [min(ys), max(ys)]
            else:
                assert row_y[i, 0, r] > row_y[i, 1, r]


def test_a_folding_lens_is_found_beside_a_camera_of_the_same_matrix_and_named_by_its_file():
    """Lenses are checked once per camera matrix, distortion and size: a second camera with the
    first's K and size but coefficients that fold over is refused, under its own name."""
    import dataclasses

    from pipeline.rectify import check_rectifiable

    good = LAB[1]
    bad = dataclasses.replace(LAB[2], K=good.K.copy(), dist=np.array([-0.6, 0.0, 0.0, 0.0, 0.0]))
    names = ["DIR: calibration/cam02.yaml", "DIR: calibration/cam03.yaml", "DIR: calibration/cam04.yaml"]
    check_rectifiable([good, LAB[3]], names[::2])
    with pytest.raises(ValueError, match=r"^DIR: calibration/cam03\.yaml: camera 3: its lens distortion "
                                         r"\[-0\.6, 0\.0, 0\.0, 0\.0, 0\.0\] folds over inside its image"):
        check_rectifiable([good, bad, LAB[3]], names)


def test_a_rig_needs_a_camera_and_one_resolution():
    import dataclasses

    from pipeline.rectify import level_cameras

    with pytest.raises(ValueError, match=r"^cameras: expected at least one calibrated camera$"):
        level_cameras([])
    small = dataclasses.replace(LAB[1], width=320, height=240)
    with pytest.raises(ValueError, match=r"^cameras: expected every camera to have the same resolution$"):
        level_cameras([LAB[0], small])


def test_rectify_takes_any_non_zero_mask_value_and_refuses_other_shapes():
    """Masks of 255 (the opening's) rectify as masks of True; the precomputed maps are read-only."""
    from pipeline import Rectifier

    cam = scene.Camera.from_pose(1, [0.0, 0.0, 1.5], 0.2, np.radians(10.0), 40, 30, np.radians(50),
                                 [-0.1, 0.01, 0, 0, 0])
    rect = Rectifier.build([cam])
    mask = np.zeros((1, 30, 40), bool)
    mask[0, 5:20, 8:30] = True
    want = rect.rectify(mask)
    assert want.any()
    for value in (1, 7, 255):
        np.testing.assert_array_equal(rect.rectify(mask.astype(np.uint8) * value), want)
    for bad in (mask[0], mask[None], np.zeros((2, 30, 40), bool)):
        with pytest.raises(ValueError, match=r"^masks: expected 1 cameras of \(H, W\), got shape"):
            rect.rectify(bad)
    for name in ("K_virtual", "bearings", "fixed_map", "column_x", "row_y"):
        assert not getattr(rect, name).flags.writeable, name
