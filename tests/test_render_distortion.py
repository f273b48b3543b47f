"""Lens distortion without OpenGL: the canvas and its margin, resampling at the map,
per-region resampling, and the output regions a change on the canvas can reach."""

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from render.distortion import (
    BLOCK,
    distort,
    distort_region,
    distortion_maps,
    ideal_pixels,
    regions_of,
)

#: An 80 x 60 image, 67 degrees across, principal point at the centre.
K_SMALL = np.array([[60.0, 0.0, 39.5], [0.0, 60.0, 29.5], [0.0, 0.0, 1.0]])
BARREL = np.array([-0.25, 0.05, 0.002, -0.001, 0.0])
PINCUSHION = np.array([0.15, 0.0, 0.0, 0.0, 0.0])


def _ramp_canvas(maps):
    """RGBA canvas (Hc, Wc, 4) uint8: R = 2 u, G = 2 v (linear, so bilinear is exact), B = 7, A = 255."""
    cw, ch = maps.canvas_size
    v, u = np.mgrid[0:ch, 0:cw]
    assert 2 * max(cw, ch) < 256
    return np.stack([2 * u, 2 * v, np.full_like(u, 7), np.full_like(u, 255)], -1).astype(np.uint8)


def test_a_lens_without_distortion_is_the_identity():
    maps = distortion_maps(K_SMALL, np.zeros(5), 80, 60)
    assert maps.identity and maps.nearest is None
    assert maps.canvas_size == (80, 60) and maps.offset == (0, 0)
    v, u = np.mgrid[0:60, 0:80]
    assert np.array_equal(maps.map_xy, np.stack([u, v], -1)) and maps.map_xy.dtype == np.float32
    canvas = np.random.default_rng(0).integers(0, 256, (64, 90, 4), dtype=np.uint8)   # larger than the image
    image = distort(canvas, maps)
    assert np.array_equal(image, canvas[:60, :80]) and not np.shares_memory(image, canvas)
    labels = canvas[..., 3].copy()
    assert np.array_equal(distort(labels, maps, nearest=True), labels[:60, :80])
    out = np.zeros((60, 80, 4), np.uint8)
    assert distort(canvas, maps, out=out) is out and np.array_equal(out, canvas[:60, :80])
    part = np.zeros((20, 30, 4), np.uint8)
    assert distort_region(canvas, maps, (10, 30, 20, 50), part) is part
    assert np.array_equal(part, canvas[10:30, 20:50])
    part = np.zeros((20, 30), np.uint8)
    distort_region(labels, maps, (10, 30, 20, 50), part, nearest=True)
    assert np.array_equal(part, labels[10:30, 20:50])


@pytest.mark.parametrize("dist,message", [
    (np.zeros(4), r"^dist: expected shape \(5,\), got \(4,\)$"),       # no lens, but not the model's 5 numbers
    (BARREL[:4], r"^dist: expected shape \(5,\), got \(4,\)$"),
    ([np.nan, 0.0, 0.0, 0.0, 0.0], r"^dist: expected finite numbers"),
    (["-0.25", 0.0, 0.0, 0.0, 0.0], r"^dist: expected numbers of shape \(5,\), got '-0\.25'$"),
])
def test_a_malformed_lens_is_refused_by_name(dist, message):
    with pytest.raises(ValueError, match=message):
        distortion_maps(K_SMALL, dist, 80, 60)
    with pytest.raises(ValueError, match=message):
        ideal_pixels(K_SMALL, dist, 80, 60)
    with pytest.raises(ValueError, match=r"^K: expected shape \(3, 3\), got \(2, 3\)$"):
        ideal_pixels(K_SMALL[:2], BARREL, 80, 60)


@pytest.mark.parametrize("dist", [BARREL, PINCUSHION])
@pytest.mark.parametrize("margin", [0, 2, 5])
def test_the_canvas_holds_the_map_with_margin_pixels_to_spare(dist, margin):
    """Where the lens reaches beyond the image, the canvas reaches ``margin`` pixels
    (less than one more) beyond the map's farthest canvas position; elsewhere it is the
    image's own edge, not moved."""
    maps = distortion_maps(K_SMALL, dist, 80, 60, margin=margin)
    cw, ch = maps.canvas_size
    du, dv = maps.offset
    spare_lo = maps.map_xy.reshape(-1, 2).min(axis=0).astype(float)                 # canvas (u, v)
    spare_hi = np.array([cw - 1, ch - 1]) - maps.map_xy.reshape(-1, 2).max(axis=0).astype(float)
    for axis, (shift, size) in enumerate([(du, 80), (dv, 60)]):
        if shift:                       # the lens reaches left of (above) the image
            assert margin <= spare_lo[axis] < margin + 1
        else:
            assert spare_lo[axis] >= margin
        if (cw, ch)[axis] - shift > size:
            assert margin <= spare_hi[axis] < margin + 1
        else:
            assert (cw, ch)[axis] - shift == size and spare_hi[axis] >= margin
    # the map is that of the image: shifting it back by the offset gives the same map
    # as any other margin's
    ref = distortion_maps(K_SMALL, dist, 80, 60, margin=0)
    np.testing.assert_allclose(maps.map_xy - [du, dv], ref.map_xy - ref.offset, atol=1e-4)


def test_barrel_and_pincushion_canvases():
    """Barrel distortion pulls the image's corners from beyond the ideal frame (a larger
    canvas, moved). The pincushion lens shows canvas u 2.17 .. 76.83 (inside the frame by
    more than the 2 px margin: width 80, not moved) and v 0.97 .. 58.03: floor(0.97) - 2 =
    -2 moves the canvas 2 px down, ceil(58.03) + 2 = 61 is its last row: 62 + 2 = 64 rows."""
    barrel = distortion_maps(K_SMALL, BARREL, 80, 60)
    assert barrel.offset[0] > 2 and barrel.offset[1] > 2
    assert barrel.canvas_size[0] > 80 + 2 * 2 and barrel.canvas_size[1] > 60 + 2 * 2
    pincushion = distortion_maps(K_SMALL, PINCUSHION, 80, 60)
    assert pincushion.canvas_size == (80, 64) and pincushion.offset == (0, 2)
    # a stronger pincushion (k1 = 0.2) without a margin lies inside the frame on every side:
    # at the top edge's centre y (1 + 0.2 y^2) = -29.5 / 60 gives y = -0.4708, v = 1.25
    # (u 2.76 .. 76.24, v 1.25 .. 57.75): the canvas is the image, not moved (never a
    # negative offset, never smaller than the image)
    tight = distortion_maps(K_SMALL, np.array([0.2, 0.0, 0.0, 0.0, 0.0]), 80, 60, margin=0)
    assert tight.canvas_size == (80, 60) and tight.offset == (0, 0)
    assert 1.2 < tight.map_xy[0, 40, 1] < 1.3


def test_the_labs_canvas_is_the_documented_685_by_515(lab):
    cam = lab.cameras[0]
    maps = distortion_maps(cam.K, cam.dist, cam.width, cam.height)
    assert maps.canvas_size == (685, 515)                              # docs/render.md
    np.testing.assert_array_equal(maps.canvas_K(cam.K)[:2, 2], cam.K[:2, 2] + maps.offset)


@pytest.mark.parametrize("dist", [BARREL, PINCUSHION])
def test_distort_samples_the_canvas_where_the_map_says(dist):
    """Bilinear: a linear ramp is resampled exactly at the map (OpenCV rounds maps to
    1/32 px, and to whole grey levels); nearest: the label of the nearest canvas pixel."""
    maps = distortion_maps(K_SMALL, dist, 80, 60)
    image = distort(_ramp_canvas(maps), maps)
    assert image.shape == (60, 80, 4)
    m = maps.map_xy.astype(float)
    np.testing.assert_allclose(image[..., :2], 2 * m, atol=0.5 + 2 / 32)
    assert np.all(image[..., 2:] == [7, 255])
    cw, ch = maps.canvas_size
    v, u = np.mgrid[0:ch, 0:cw]
    labels = (u % 16 + 16 * (v % 16)).astype(np.uint8)              # distinct within 16 px
    got = distort(labels, maps, nearest=True)
    near = np.rint(m).astype(int)
    clear = (np.abs(m - np.floor(m) - 0.5) > 1 / 16).all(axis=-1)      # not a tie
    assert clear.mean() > 0.7
    assert np.array_equal(got[clear], labels[near[..., 1], near[..., 0]][clear])


@pytest.mark.parametrize("region", [(0, 60, 0, 80), (0, 16, 0, 16), (7, 33, 50, 80), (44, 60, 3, 4)])
def test_a_region_is_the_same_pixels_of_the_whole_image(region):
    maps = distortion_maps(K_SMALL, BARREL, 80, 60)
    cw, ch = maps.canvas_size
    rng = np.random.default_rng(1)
    canvas = rng.integers(0, 256, (ch, cw, 4), dtype=np.uint8)
    labels = rng.integers(0, 4, (ch, cw), dtype=np.uint8)
    r0, r1, c0, c1 = region
    out = np.zeros((r1 - r0, c1 - c0, 4), np.uint8)
    assert distort_region(canvas, maps, region, out) is out
    assert np.array_equal(out, distort(canvas, maps)[r0:r1, c0:c1])
    out = np.zeros((r1 - r0, c1 - c0), np.uint8)
    distort_region(labels, maps, region, out, nearest=True)
    assert np.array_equal(out, distort(labels, maps, nearest=True)[r0:r1, c0:c1])


@pytest.mark.parametrize("size,tiles", [((80, 60), (4, 5)),       # ceil(60 / 16), ceil(80 / 16)
                                        ((49, 33), (3, 4))])      # one column and one row in the last tiles
def test_block_bounds_are_each_tiles_smallest_and_largest_map_position(size, tiles):
    maps = distortion_maps(K_SMALL, BARREL, *size)
    assert maps.block_lo.shape == maps.block_hi.shape == (*tiles, 2)
    for i in range(tiles[0]):
        for j in range(tiles[1]):
            tile = maps.map_xy[BLOCK * i:BLOCK * (i + 1), BLOCK * j:BLOCK * (j + 1)].reshape(-1, 2)
            assert np.array_equal(maps.block_lo[i, j], tile.min(axis=0))
            assert np.array_equal(maps.block_hi[i, j], tile.max(axis=0))


def _shifted_bounds(H, W, shift):
    """Block bounds of the map ``(u + shift, v + shift)`` of an H x W image, (1, nby, nbx, 2)."""
    maps = distortion_maps(K_SMALL, np.zeros(5), W, H)
    return maps.block_lo[None] + shift, maps.block_hi[None] + shift


def test_regions_by_hand():
    """A 40 x 30 image (tiles of 16: 2 rows, 3 columns) whose map reads the canvas 0.4 px
    right of and below each pixel, and one reading 0.6 px left of and above it."""
    lo, hi = _shifted_bounds(30, 40, 0.4)
    rects = np.array([[
        [20, 5, 30, 10],                # inside the middle column of the first row of tiles
        [16, 16, 18, 18],               # pixel 15 reads 15.4, i.e. canvas pixels 15 and 16: tile 0 too
        [np.nan] * 4,                   # nobody
        [-np.inf, -np.inf, np.inf, np.inf],   # everything
        [45, 0, 60, 10],                # beyond the canvas the map reads (at most 39.4)
        [38, 25, np.inf, np.inf],       # the last tiles, clamped to the image
    ]])
    assert regions_of(lo, hi, rects, (30, 40)) == [[(0, 16, 16, 32), (0, 30, 0, 32), (0, 30, 0, 40),
                                                     (16, 30, 32, 40)]]
    lo, hi = _shifted_bounds(30, 40, -0.6)
    rects = np.array([[[10, 10, 15, 15]]])    # pixel 16 reads 15.4, i.e. canvas pixels 15 and 16
    assert regions_of(lo, hi, rects, (30, 40)) == [[(0, 30, 0, 32)]]
    # pixel 15 reads 13.99, which OpenCV rounds to 14 (1/32 px): canvas pixels 14 and 15 (the
    # second at weight 0 in its tables, but read: the half pixel of margin covers the rounding)
    lo, hi = _shifted_bounds(30, 40, -1.01)
    assert regions_of(lo, hi, np.array([[[15, 15, 20, 20]]]), (30, 40)) == [[(0, 30, 0, 32)]]
    # a 40 x 50 image read where it lies: pixel 15 reads canvas pixels 15 and 16, not 17, and
    # pixel 32 reads 32 and 33, not 30: the tiles around the middle one stay out
    lo, hi = _shifted_bounds(50, 40, 0.0)
    assert regions_of(lo, hi, np.array([[[17, 17, 30, 30]]]), (50, 40)) == [[(16, 32, 16, 32)]]


def test_regions_of_several_cameras_and_none():
    lo0, hi0 = _shifted_bounds(30, 40, 0.0)
    lo1, hi1 = _shifted_bounds(30, 40, 20.0)        # camera 1 reads the canvas 20 px further
    lo, hi = np.concatenate([lo0, lo1]), np.concatenate([hi0, hi1])
    rects = np.array([[[2, 2, 5, 5]], [[2, 2, 5, 5]]], float)
    assert regions_of(lo, hi, rects, (30, 40)) == [[(0, 16, 0, 16)], []]
    assert regions_of(lo, hi, np.zeros((2, 0, 4)), (30, 40)) == [[], []]


@st.composite
def rect_sets(draw):
    """(k, 4) canvas rects: integer bounds, some open to the canvas edge, some NaN."""
    k = draw(st.integers(1, 12))
    rects = []
    for _ in range(k):
        x0, x1 = sorted(draw(st.integers(-5, 100)) for _ in range(2))
        y0, y1 = sorted(draw(st.integers(-5, 80)) for _ in range(2))
        r = [float(x0), float(y0), float(x1), float(y1)]
        kind = draw(st.integers(0, 9))
        if kind == 0:
            r = [np.nan] * 4
        elif kind == 1:
            r[0] = -np.inf
        elif kind == 2:
            r[3] = np.inf
        rects.append(r)
    return np.array(rects)


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([BARREL, PINCUSHION, np.array([-0.1, 0.0, 0.004, 0.003, 0.0])]), rect_sets())
def test_every_output_pixel_that_reads_a_rect_lies_in_its_region(dist, rects):
    """Brute force: a pixel whose bilinear source pixels (floor(m) and floor(m) + 1 on each
    axis, of the float map and of OpenCV's 1/32 px rounding of it) or nearest source pixel
    meet a rect lies in that rect's region (one region per rect at most, in their order)."""
    maps = distortion_maps(K_SMALL, dist, 80, 60)
    got = regions_of(maps.block_lo[None], maps.block_hi[None], rects[None], (60, 80))[0]
    m = maps.map_xy.astype(float)
    m32 = np.rint(m * 32) / 32
    first = np.minimum(np.floor(m), np.floor(m32))
    last = np.maximum(np.floor(m) + 1, np.floor(m32) + 1)
    alone = [regions_of(maps.block_lo[None], maps.block_hi[None], r[None, None], (60, 80))[0] for r in rects]
    assert got == [region for one in alone for region in one]       # in the order of the rects
    for (x0, y0, x1, y1), one in zip(rects, alone):
        assert len(one) <= 1
        if np.isnan(x0):
            assert not one
            continue
        reads = (last[..., 0] >= x0) & (first[..., 0] <= x1) & (last[..., 1] >= y0) & (first[..., 1] <= y1)
        if not reads.any():
            continue
        (r0, r1, c0, c1), = one
        rows, cols = np.nonzero(reads)
        assert r0 <= rows.min() and rows.max() < r1 and c0 <= cols.min() and cols.max() < c1
        assert r0 % BLOCK == 0 and c0 % BLOCK == 0 and 0 <= r0 < r1 <= 60 and 0 <= c0 < c1 <= 80


def test_a_skewed_lens_maps_each_pixel_to_where_the_canvas_draws_its_ray():
    """cv2.projectPoints and the OpenGL projection both leave out the skew K[0, 1]: each
    output pixel reads the canvas where OpenGL draws the ray that cv2.projectPoints sends
    to that pixel, not up to 3.8 px beside it (in the corners) as the skew would have it."""
    from render.pose import project_opengl
    from scene.camera import undistort_points

    K = K_SMALL.copy()
    K[0, 1] = 6.0
    maps = distortion_maps(K, BARREL, 80, 60)
    v, u = np.mgrid[0:60, 0:80]
    uv = np.column_stack([u.ravel(), v.ravel()]).astype(float)
    rays = np.column_stack([undistort_points(uv, K, BARREL), np.ones(len(uv))])
    back = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, BARREL)[0].reshape(-1, 2)
    np.testing.assert_allclose(back, uv, atol=1e-6)
    cw, ch = maps.canvas_size
    drawn = project_opengl(rays, np.eye(3), np.zeros(3), maps.canvas_K(K), cw, ch)
    np.testing.assert_allclose(maps.map_xy.reshape(-1, 2), drawn, atol=1e-4)
