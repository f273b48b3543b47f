"""Hand-computable cases, round trips and equivalences of the pipeline steps."""

import functools
import os

import cv2
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy import ndimage

import scene
from pipeline import (
    Pipeline,
    PipelineParams,
    background_model,
    cdnet_metrics,
    colour_angle_foreground,
    confusion,
    evaluate,
    median_threshold,
    open_masks,
    rle_bits,
    rle_decode,
    rle_encode,
    scanline_bits,
    spatial_smooth,
)
from pipeline.reference import ReferencePipeline
from pipeline.synthetic import synthetic_sequence

LAB = scene.load_scene("lab").cameras


def flat_camera(width=64, height=48):
    return scene.Camera.from_pose(1, [0, 0, 1.5], 0.0, 0.0, width, height, np.radians(50), [0] * 5)


# --- foreground -----------------------------------------------------------------------

def test_square_of_colour_is_foreground():
    bg = np.full((1, 6, 8, 3), 100, np.uint8)
    fr = bg.copy()
    fr[0, 2:4, 3:6] = (100, 140, 60)
    fg = colour_angle_foreground(fr, background_model(bg), 5.0, 10.0, 20.0)
    expected = np.zeros((6, 8), bool)
    expected[2:4, 3:6] = True
    np.testing.assert_array_equal(fg[0], expected)


def test_angle_threshold_is_the_angle():
    b = np.array([200.0, 100.0, 50.0])
    # rotate b by 4 and by 6 degrees in the plane of b and a perpendicular vector
    perp = np.cross(b, [0.0, 0.0, 1.0]); perp /= np.linalg.norm(perp)
    u = b / np.linalg.norm(b)
    vecs = [np.linalg.norm(b) * (np.cos(np.radians(d)) * u + np.sin(np.radians(d)) * perp) for d in (4, 6)]
    fr = np.clip(np.rint(np.array(vecs)), 0, 255).astype(np.uint8).reshape(1, 1, 2, 3)
    bg = np.broadcast_to(b.astype(np.uint8), (1, 1, 2, 3)).copy()
    fg = colour_angle_foreground(fr, background_model(bg), 5.0, 0.0, 0.0)
    assert fg[0, 0].tolist() == [False, True]


def test_brightness_scaling_is_not_foreground_but_dark_floor_uses_difference():
    bg = np.full((1, 1, 3, 3), 150, np.uint8)
    fr = np.array([[[[75, 75, 75], [5, 5, 5], [4, 0, 0]]]], np.uint8)   # shadow, black, dark red
    fg = colour_angle_foreground(fr, background_model(bg), 5.0, 20.0, 30.0)
    # half brightness keeps the angle: background; near black is below the floor and
    # far from the background: foreground (the dark person in front of a lit wall)
    assert fg[0, 0].tolist() == [False, True, True]
    dark_bg = np.full((1, 1, 2, 3), 6, np.uint8)
    fr = np.array([[[[2, 9, 4], [90, 10, 10]]]], np.uint8)   # dark noise; lit red object
    fg = colour_angle_foreground(fr, background_model(dark_bg), 5.0, 20.0, 30.0)
    assert fg[0, 0].tolist() == [False, True]


def angle_formula(frames, background, threshold_deg, floor, delta):
    """The colour-angle test as the formulas of pipeline.foreground, in numpy float32."""
    a, b = frames.astype(np.float32), background.astype(np.float32)
    dot = a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]
    aa = a[..., 0] * a[..., 0] + a[..., 1] * a[..., 1] + a[..., 2] * a[..., 2]
    bb = b[..., 0] * b[..., 0] + b[..., 1] * b[..., 1] + b[..., 2] * b[..., 2]
    c = np.cos(np.radians(threshold_deg))
    c2bb = (c * c * bb.astype(np.float64)).astype(np.float32)
    floor2, delta2 = np.float32(floor) ** 2, np.float32(delta) ** 2
    dark = (aa < floor2) | (bb < floor2)
    return np.where(dark, (aa + bb) - np.float32(2) * dot > delta2, dot * dot < aa * c2bb)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.5, 30.0), st.floats(0.0, 60.0), st.floats(0.0, 80.0),
       st.booleans(), st.integers(0, 3))
def test_compiled_angle_test_is_the_float32_formula(seed, threshold, floor, delta, whole, extra_rows):
    """AngleTerms' compiled pass equals the formulas term by term (any background, mean or
    whole levels, dark patches, rows of a taller buffer left alone)."""
    from pipeline.foreground import AngleTerms

    rng = np.random.default_rng(seed)
    n, h, w = 2, 7, 13
    bg = rng.uniform(0, 255, (n, h, w, 3)).astype(np.float32)
    bg[:, :2] /= 20                                        # dark background rows
    if whole:
        bg = np.rint(bg)
    frames = np.clip(bg + rng.normal(0, 12, bg.shape), 0, 255).astype(np.uint8)
    frames[:, 3:5, 4:9] = rng.integers(0, 256, (n, 2, 5, 3))    # an object
    frames[:, -1, :4] //= 16                                   # dark frame pixels
    out = np.full((n, h + extra_rows, w), 7, np.uint8)
    terms = AngleTerms(bg, threshold, floor, delta)
    assert terms._levels.dtype == (np.uint8 if whole else np.float32)     # both compiled paths
    np.testing.assert_array_equal(terms.background, bg)
    terms.mask(frames, out)
    np.testing.assert_array_equal(out[:, :h], 255 * angle_formula(frames, bg, threshold, floor, delta))
    assert (out[:, h:] == 7).all()


def test_angle_terms_refuse_mismatched_buffers():
    from pipeline.foreground import AngleTerms

    terms = AngleTerms(np.ones((2, 4, 5, 3), np.float32), 3.0, 10.0, 20.0)
    frames = np.zeros((2, 4, 5, 3), np.uint8)
    with pytest.raises(ValueError, match="out: expected C-contiguous"):
        terms.mask(frames, np.zeros((2, 3, 5), np.uint8))
    with pytest.raises(ValueError, match="out: expected C-contiguous"):
        terms.mask(frames, np.zeros((2, 6, 5), np.uint8)[:, :4])
    with pytest.raises(ValueError, match="frames: expected"):
        terms.mask(frames[:1], np.zeros((2, 4, 5), np.uint8))
    # the compiled pass does not check bounds: a buffer of other cameras, columns or type is refused
    for out in (np.zeros((3, 4, 5), np.uint8), np.zeros((2, 4, 6), np.uint8), np.zeros((2, 4, 5), np.int16)):
        with pytest.raises(ValueError, match="out: expected C-contiguous"):
            terms.mask(frames, out)


def test_a_whole_valued_background_beyond_8_bits_is_not_wrapped():
    """A float32 model of whole numbers outside 0..255 (a model scaled or offset elsewhere)
    is compared as it is: wrapped around to uint8 levels it would equal the frame."""
    from pipeline.foreground import AngleTerms

    for v in (-100.0, 256.0, 356.0):
        bg = np.full((1, 1, 4, 3), 100.0, np.float32)
        bg[0, 0, 1:3, 0] = v
        frames = np.full((1, 1, 4, 3), 100, np.uint8)
        frames[0, 0, :, 0] = int(v) % 256                       # the wrapped level, in every column
        out = np.zeros((1, 1, 4), np.uint8)
        AngleTerms(bg, 5.0, 10.0, 20.0).mask(frames, out)
        np.testing.assert_array_equal(out[0, 0], 255 * angle_formula(frames, bg, 5.0, 10.0, 20.0)[0, 0])
        assert out[0, 0, 1:3].tolist() == [255, 255]


def test_dark_difference_just_above_the_delta_is_foreground():
    """Below the floor, |a - b|^2 = 1601 (one more than 40^2) is above a delta of 40 and
    1600 is not: the squared delta is compared exactly, with nothing added."""
    bg = np.full((1, 1, 2, 3), (9, 12, 0), np.uint8)           # |b| = 15: below the floor
    fr = np.array([[[[10, 12, 40], [9, 12, 40]]]], np.uint8)   # differences (1, 0, 40), (0, 0, 40)
    expected = np.linalg.norm(fr.astype(float) - bg.astype(float), axis=-1) > 40.0
    assert expected[0, 0].tolist() == [True, False]
    fg = colour_angle_foreground(fr, background_model(bg), 3.0, 25.0, 40.0)
    np.testing.assert_array_equal(fg, expected)


def test_angle_terms_with_other_thresholds_leave_the_original_alone():
    """with_thresholds gives a new test over the same background; the original keeps its own
    thresholds (a pixel 10 degrees off: foreground at 5 degrees, not at 20)."""
    from pipeline.foreground import AngleTerms

    b = np.array([200.0, 100.0, 50.0])
    perp = np.cross(b, [0.0, 0.0, 1.0])
    perp /= np.linalg.norm(perp)
    u = b / np.linalg.norm(b)
    a = np.linalg.norm(b) * (np.cos(np.radians(10)) * u + np.sin(np.radians(10)) * perp)
    fr = np.rint(a).astype(np.uint8).reshape(1, 1, 1, 3)
    bg = b.astype(np.uint8).reshape(1, 1, 1, 3)
    off = np.degrees(np.arccos(a.round() @ b / (np.linalg.norm(a.round()) * np.linalg.norm(b))))
    assert 9.5 < off < 10.5
    terms = AngleTerms(bg.astype(np.float32), 5.0, 10.0, 20.0)
    wide = terms.with_thresholds(20.0, 10.0, 20.0)
    out = np.zeros((1, 1, 1), np.uint8)
    assert wide.mask(fr, out)[0, 0, 0] == 0
    assert terms.mask(fr, out)[0, 0, 0] == 255
    assert wide._levels is terms._levels                       # the background is shared


def test_angle_terms_refuse_frames_of_another_type():
    """The compiled pass reads 8-bit levels: frames of the right shape in another dtype
    (float 0..1, or 16-bit) are refused rather than compared as if they were levels."""
    from pipeline.foreground import AngleTerms

    terms = AngleTerms(np.full((1, 2, 3, 3), 100, np.float32), 3.0, 10.0, 20.0)
    out = np.zeros((1, 2, 3), np.uint8)
    for dtype in (np.float32, np.uint16, np.int64):
        with pytest.raises(ValueError, match="frames: expected"):
            terms.mask(np.full((1, 2, 3, 3), 100, dtype), out)


def test_opening_removes_specks_keeps_blocks_and_edges():
    m = np.zeros((2, 10, 10), bool)
    m[0, 2:6, 2:6] = True
    m[0, 8, 8] = True
    m[1, 7:, :4] = True            # touches the border: kept whole
    out = open_masks(m, 3)
    assert out[0, 8, 8] == False
    np.testing.assert_array_equal(out[0, 2:6, 2:6], True)
    np.testing.assert_array_equal(out[1], m[1])
    ref = np.stack([ndimage.binary_opening(x, np.ones((3, 3)), border_value=0) for x in m])
    np.testing.assert_array_equal(out, ref)
    m[1] = True
    for k in (9, 11, 8191):        # 11 and up: taller than the masks, so always empty (without OpenCV)
        ref = np.stack([ndimage.binary_opening(x, np.ones((min(k, 13),) * 2), border_value=0) for x in m])
        np.testing.assert_array_equal(open_masks(m, k), ref)
    assert open_masks(m, 9)[1].all() and not open_masks(m, 11).any()


def test_opening_keeps_stacked_cameras_apart():
    """Two rows of foreground at the bottom of one camera and one at the top of the next are
    each thinner than a 3 x 3 square: opened per camera (scipy, zero border) both vanish.
    Stacked without a zero row between the cameras they would make a band three rows tall
    that survives; open_masks and the pipeline's own stacked pass keep them apart."""
    h, w = 6, 8
    m = np.zeros((2, h, w), bool)
    m[0, h - 2:] = True
    m[1, 0] = True
    ref = np.stack([ndimage.binary_opening(x, np.ones((3, 3)), border_value=0) for x in m])
    assert not ref.any()
    np.testing.assert_array_equal(open_masks(m, 3), ref)
    cams = [flat_camera(w, h), flat_camera(w, h)]
    bg = np.full((2, h, w, 3), 120, np.uint8)
    fr = bg.copy()
    fr[m] = (200, 40, 40)
    out = Pipeline(cams, PipelineParams(opening_kernel=3), bg).step(fr)
    np.testing.assert_array_equal(colour_angle_foreground(fr, background_model(bg), 3.0, 25.0, 40.0), m)
    np.testing.assert_array_equal(out.foreground, ref)


@pytest.mark.parametrize("shape", [(7, 12), (12, 7)])
def test_a_kernel_as_tall_or_as_wide_as_the_mask_fits_it_once(shape):
    """An opening with a kernel of the mask's full height (or width) keeps what a square of
    that size covers, as scipy's opening does; one larger always empties the mask."""
    k = min(shape)
    m = np.ones((2,) + shape, bool)
    m[1, shape[0] // 2, shape[1] // 2] = False                  # in every k x k square: none fits now
    ref = np.stack([ndimage.binary_opening(x, np.ones((k, k)), border_value=0) for x in m])
    out = open_masks(m, k)
    np.testing.assert_array_equal(out, ref)
    assert out[0].all() and not out[1].any()
    assert not open_masks(m, k + 2).any()


def test_opening_of_kernel_one_returns_a_new_array():
    """With no opening the masks are returned as a copy: writing the result leaves the input alone."""
    m = np.zeros((1, 3, 4), bool)
    m[0, 1, 2] = True
    out = open_masks(m, 1)
    out[0, 0, 0] = True
    assert m.sum() == 1 and m[0, 1, 2]


def test_angle_terms_keep_a_read_only_model_without_a_copy():
    """A read-only float32 model (background_model's mean of frames, not whole levels) is kept
    as it is: AngleTerms' background is that array, not a second copy of every pixel."""
    from pipeline.foreground import AngleTerms

    frames = np.stack([np.full((1, 2, 3, 3), 100, np.uint8), np.full((1, 2, 3, 3), 101, np.uint8)])
    model = background_model(frames)
    assert not model.flags.writeable and np.all(model == 100.5)
    assert np.shares_memory(AngleTerms(model, 3.0, 25.0, 40.0).background, model)


# --- rectification and the bearing map -------------------------------------------------

def test_square_gives_its_columns_without_distortion():
    cam = flat_camera()
    bg = np.full((1, 48, 64, 3), 120, np.uint8)
    p = PipelineParams(opening_kernel=3, spatial_kernel=1, median_kernel=1, column_threshold=0.5)
    pipe = Pipeline([cam], p, background=bg)
    fr = bg.copy()
    fr[0, 10:30, 20:28] = (40, 200, 40)
    assert np.flatnonzero(pipe.process(fr)[0]).tolist() == list(range(20, 28))


@functools.cache
def lab_rectifier():
    from pipeline import Rectifier

    return Rectifier.build(LAB[:4])


@functools.cache
def lab_float_maps():
    from pipeline.rectify import float_maps

    return float_maps(LAB[:4])


def float_map_remap(stacked):
    """Each camera's own rows remapped with its float maps (of :func:`lab_rectifier`), as the
    reference pipeline does."""
    rect = lab_rectifier()
    src = stacked.reshape(rect.n_cams, -1, stacked.shape[-1])[:, :rect.height]
    return np.stack([cv2.remap(src[i], *lab_float_maps()[i], cv2.INTER_NEAREST,
                               borderMode=cv2.BORDER_CONSTANT, borderValue=0) for i in range(rect.n_cams)])


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([480, 483, 500]),
       st.lists(st.tuples(st.integers(0, 3), st.integers(0, 479), st.integers(0, 639), st.integers(1, 200),
                          st.integers(1, 300), st.sampled_from([1, 128, 255])), max_size=6),
       st.booleans())
def test_remap_of_the_non_zero_boxes_is_each_cameras_own_remap(rows, blobs, junk_between):
    """Remapping only what a camera's non-zero pixels can reach gives its whole-image remap with
    its float maps; the rows between cameras (and the other cameras) are never read."""
    rect = lab_rectifier()
    stacked = np.zeros((4, rows, 640), np.uint8)
    for cam, y, x, h, w, value in blobs:
        stacked[cam, y:y + h, x:x + w] = value
    if junk_between:
        stacked[:, 480:] = 7
    flat = stacked.reshape(-1, 640)
    np.testing.assert_array_equal(rect.remap_stacked(flat), float_map_remap(flat))


@settings(max_examples=80, deadline=None)
@given(hnp.arrays(np.uint8, st.tuples(st.integers(1, 40), st.integers(1, 120)),
                  elements=st.sampled_from([0, 0, 0, 0, 1, 255])),
       st.integers(1, 20))
def test_nonzero_boxes_hold_every_non_zero_pixel_in_runs_of_columns(image, gap):
    from pipeline.rectify import nonzero_boxes

    boxes = nonzero_boxes(image, gap)
    covered = np.zeros(image.shape, bool)
    for x, y, w, h in boxes:
        covered[y:y + h, x:x + w] = True
        part = image[y:y + h, x:x + w]
        assert part[:, 0].any() and part[:, -1].any() and part[0].any() and part[-1].any()  # tight
    assert not (image.astype(bool) & ~covered).any()
    starts, ends = [x for x, _, _, _ in boxes], [x + w for x, _, w, _ in boxes]
    assert starts == sorted(starts)
    assert all(s - e >= gap for e, s in zip(ends, starts[1:]))     # at least gap zero columns between
    assert all(not image[:, e:s].any() for e, s in zip(ends, starts[1:]))


def test_remap_of_empty_full_and_noise_masks():
    rect = lab_rectifier()
    empty = np.zeros((4 * 480, 640), np.uint8)
    assert not rect.remap_stacked(empty).any()
    full = np.full_like(empty, 255)
    np.testing.assert_array_equal(rect.remap_stacked(full), float_map_remap(full))
    assert 0.9 < rect.remap_stacked(full).mean() / 255 < 1.0     # a few output pixels fall outside the image
    noise = np.random.default_rng(3).integers(0, 256, empty.shape, dtype=np.uint8)
    np.testing.assert_array_equal(rect.remap_stacked(noise), float_map_remap(noise))
    np.testing.assert_array_equal(rect.remap_stacked(noise.reshape(4, 480, 640)), float_map_remap(noise))
    with pytest.raises(ValueError, match="at least 480 rows"):
        rect.remap_stacked(noise.reshape(4, 480, 640)[:, :479])


@pytest.mark.parametrize("index", [0, 4, 9, 15])
def test_bearing_of_projected_world_point(index):
    cam = LAB[index]
    pipe = Pipeline([cam])
    rng = np.random.default_rng(index)
    checked = 0
    for _ in range(40):
        p_world = np.array([rng.uniform(0.3, 6.4), rng.uniform(0.3, 5.5), rng.uniform(0.0, 2.0)])
        uv, _ = cv2.projectPoints(p_world[None], cv2.Rodrigues(cam.R)[0], cam.t, cam.K, cam.dist)
        u, v = uv.ravel()
        if (cam.R @ p_world + cam.t)[2] <= 0 or not (3 <= u < cam.width - 3 and 3 <= v < cam.height - 3):
            continue
        mask = np.zeros((1, cam.height, cam.width), bool)
        r, c = round(v), round(u)
        mask[0, r - 2:r + 3, c - 2:c + 3] = True
        cols = np.flatnonzero(pipe.rectifier.rectify(mask)[0].any(axis=0))
        d = p_world[:2] - cam.center_world[:2]
        expected = np.arctan2(d[1], d[0])
        step = abs(pipe.bearings[0, 1] - pipe.bearings[0, 0])
        if not cols.size:
            # seen only near a side edge of the raw image, low down: outside the band of
            # columns covered at every height, so outside the scanline's field of view
            off = np.angle(np.exp(1j * (expected - pipe.bearings[0, [0, -1]])))
            assert off[0] > -3 * step or off[1] < 3 * step
            assert np.min(np.abs(off)) < np.radians(6)
            continue
        col = cols.mean()
        got = np.interp(col, np.arange(cam.width), np.unwrap(pipe.bearings[0]))
        err = np.angle(np.exp(1j * (got - expected)))
        assert abs(err) <= 1.0 * step + 1e-9   # within a column
        checked += 1
    assert checked >= 5


def test_bearings_cover_the_field_of_view():
    pipe = Pipeline(LAB[:2])
    b = np.unwrap(pipe.bearings, axis=1)
    assert np.all(np.diff(b, axis=1) < 0)         # left to right turns clockwise
    span = b[:, 0] - b[:, -1]
    assert np.all(span >= LAB[0].hfov)            # the virtual camera covers the real one
    mid = b[:, LAB[0].width // 2]
    np.testing.assert_allclose(np.angle(np.exp(1j * (mid - [c.yaw for c in LAB[:2]]))), 0, atol=0.01)


@st.composite
def rectifiable_cameras(draw):
    """A small camera with any yaw, a pitch of -30..40 degrees, a 20..90 degree lens, its
    principal point off centre and mild distortion, that check_rectifiable accepts."""
    from hypothesis import reject

    from pipeline.rectify import check_rectifiable

    w, h = draw(st.integers(8, 120)), draw(st.integers(8, 120))
    principal = ((w - 1) / 2 + draw(st.floats(-0.1, 0.1)) * w, (h - 1) / 2 + draw(st.floats(-0.1, 0.1)) * h)
    dist = [draw(st.floats(-0.3, 0.3)), draw(st.floats(-0.1, 0.1)), draw(st.floats(-0.005, 0.005)),
            draw(st.floats(-0.005, 0.005)), draw(st.floats(-0.05, 0.05))]
    cam = scene.Camera.from_pose(1, [1.0, 2.0, 1.5], draw(st.floats(-np.pi, np.pi)),
                                 draw(st.floats(np.radians(-30), np.radians(40))), w, h,
                                 draw(st.floats(np.radians(20), np.radians(90))), dist, principal)
    try:
        check_rectifiable([cam])
    except ValueError:
        reject()
    return cam


def _project(cam, n):
    """Raw pixels (m, 2) of normalised points n (m, 2) through the lens (cv2.projectPoints)."""
    pts = np.column_stack([n, np.ones(len(n))])
    return cv2.projectPoints(pts, np.zeros(3), np.zeros(3), cam.K, cam.dist)[0].reshape(-1, 2)


def _world_bearings(cam, uv):
    """atan2(dy, dx) of the world ray through raw pixels uv (m, 2), distortion removed.

    OpenCV's fixed-point iterations (run until they converge: 100 stopped 2.6e-5 px short)
    can settle on a point that projects elsewhere under strong distortion (a raw pixel of an
    8 x 59 camera with k2 0.0625: 4.0 off axis, projecting 5.2 px away, where the ray is 2.1
    off axis; beyond the lens's fold, at 4.0, lies a second point that projects onto it).
    Such pixels are reached again from the principal point: scipy's least squares on the
    projection, for pixels stepped out along the line to it, each from the last solution,
    so the points stay on the lens's branch through the axis. Every point is checked to
    project onto its pixel within 1e-8 px.
    """
    from scipy.optimize import least_squares

    uv = np.asarray(uv, float).reshape(-1, 2)
    n = cv2.undistortPoints(uv.reshape(-1, 1, 2), cam.K, cam.dist, None, None, None,
                            (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100_000, 1e-12)).reshape(-1, 2)
    centre = cam.K[:2, 2]
    for i in np.flatnonzero(np.hypot(*(_project(cam, n) - uv).T) > 1e-8):
        x = np.zeros(2)
        for t in np.linspace(0.05, 1.0, 20):
            target = centre + t * (uv[i] - centre)
            x = least_squares(lambda x, target=target: _project(cam, x[None])[0] - target, x,
                              xtol=1e-15, ftol=1e-15, gtol=1e-15).x
        n[i] = x
    assert np.hypot(*(_project(cam, n) - uv).T).max() < 1e-8
    d = np.column_stack([n, np.ones(len(n))]) @ cam.R            # R.T @ ray, batched
    return np.arctan2(d[:, 1], d[:, 0])


#: A draw where OpenCV's undistortion settled beyond the lens's fold (see _world_bearings).
STRONG_K2 = scene.Camera(1, np.array([[7.32195089, 0.0, 3.5], [0.0, 7.32195089, 29.0], [0.0, 0.0, 1.0]]),
                         np.array([0.0, 0.0625, 0.0, 0.0, -0.00390625]),
                         np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]),
                         np.array([2.0, 1.5, -1.0]), 8, 59)


@settings(max_examples=120, deadline=None)
@given(rectifiable_cameras(), st.integers(0, 2**32 - 1))
@example(STRONG_K2, 0)
def test_rectification_band_bearings_and_maps_agree_with_the_raw_rays(cam, seed):
    from pipeline.rectify import (
        _border_points,
        column_bearings,
        level_points,
        level_rotation,
        rectify_maps,
        virtual_camera_matrix,
        virtual_extent,
    )

    W = cam.width
    Kv, out_h = virtual_camera_matrix(cam)
    f, cx, cy = Kv[0, 0], Kv[0, 2], Kv[1, 2]
    # bearings turn clockwise, strictly, from the left column to the right one
    assert np.all(np.diff(np.unwrap(column_bearings(cam, Kv, W))) < 0)
    # the band is covered over the whole height of the raw image, and the output rows cover
    # its full height (checked on a border 30 times finer than virtual_extent samples; 0.1 px)
    xmin, xmax, ymin, ymax = virtual_extent(cam)
    x, y = level_points(cam, _border_points(cam.width, cam.height, 2000))
    tol = 0.1 / f
    assert x[4000:6000].max() <= xmin + tol and x[6000:].min() >= xmax - tol
    assert y.min() >= ymin - tol and y.max() <= ymax + tol
    # every raw point of the band lands in the rectified image, on the column whose bearing is
    # its world ray's
    rng = np.random.default_rng(seed)
    uv = rng.uniform([-0.5, -0.5], [cam.width - 0.5, cam.height - 0.5], (200, 2))
    lx, ly = level_points(cam, uv)
    col, row = f * lx + cx, f * ly + cy
    band = (lx >= xmin) & (lx <= xmax)
    assert np.all(col[band] >= -1e-9) and np.all(col[band] <= W - 1 + 1e-9)
    assert np.all(row >= -1e-9) and np.all(row <= out_h - 1 + 1e-9)
    shifted = np.broadcast_to(Kv, (len(col), 3, 3)).copy()
    shifted[:, 0, 2] -= col                                       # column 0 of each is fractional column col
    got = np.array([column_bearings(cam, k, 1)[0] for k in shifted])
    assert np.abs(np.angle(np.exp(1j * (got - _world_bearings(cam, uv))))).max() < 1e-7
    # the remap reads, for each output pixel, the raw pixel its level ray projects to
    # (forward through the lens, no iterative inverse: float32 maps, 1e-3 px)
    mx, my = rectify_maps(cam, Kv, (W, out_h))
    r, c = rng.integers(0, out_h, 100), rng.integers(0, W, 100)
    src = np.column_stack([mx[r, c], my[r, c]]).astype(float)
    inside = (src[:, 0] > 0) & (src[:, 0] < cam.width - 1) & (src[:, 1] > 0) & (src[:, 1] < cam.height - 1)
    rays = np.column_stack([c, r, np.ones(len(c))]) @ np.linalg.inv(Kv).T @ level_rotation(cam)   # level -> camera
    ahead = rays[:, 2] > 0
    want = cv2.projectPoints(rays[inside & ahead], np.zeros(3), np.zeros(3), cam.K, cam.dist)[0].reshape(-1, 2)
    np.testing.assert_allclose(src[inside & ahead], want, atol=1e-3)


# --- scanline filters ------------------------------------------------------------------

@settings(max_examples=60, deadline=None)
@given(hnp.arrays(np.int64, st.tuples(st.integers(1, 3), st.integers(1, 40)), elements=st.integers(0, 50)),
       st.sampled_from([1, 3, 5, 7]), st.floats(0.0, 40.0))
def test_median_threshold_equals_scipy_median(x, k, t):
    x = x.astype(float)
    ref = np.stack([ndimage.median_filter(r, size=k, mode="nearest") for r in x]) > t
    np.testing.assert_array_equal(median_threshold(x, k, t), ref)


@settings(max_examples=40, deadline=None)
@given(hnp.arrays(np.int64, st.tuples(st.integers(1, 3), st.integers(9, 40)), elements=st.integers(0, 500)),
       st.sampled_from([1, 3, 5, 9]))
def test_spatial_smooth_equals_convolution(x, k):
    ref = np.stack([np.convolve(np.pad(r.astype(float), k // 2, mode="edge"), np.ones(k), mode="valid") / k
                    for r in x])
    np.testing.assert_array_equal(spatial_smooth(x, k), ref)


def test_a_run_cut_by_the_image_border_keeps_its_border_columns():
    x = np.zeros((1, 30))
    x[0, :6] = 40.0                       # a person cut by the left border
    x[0, 20:] = 40.0                      # and one by the right border
    s = median_threshold(spatial_smooth(x, 5), 7, 10.0)
    assert s[0, :5].all() and s[0, 21:].all() and not s[0, 9:17].any()


def test_median_threshold_of_a_window_wider_than_a_byte_counts():
    """A median window of 301 columns (kernels go up to 8191): the votes in a window pass
    127 and must still be counted, as scipy's median filter has it."""
    x = np.zeros((1, 700))
    x[0, 100:600] = 9.0
    ref = ndimage.median_filter(x[0], size=301, mode="nearest") > 5.0
    assert ref[100:600].all() and not ref[:100].any() and not ref[600:].any()
    np.testing.assert_array_equal(median_threshold(x, 301, 5.0)[0], ref)


def test_spatial_smooth_of_fractional_counts_is_float64_accurate():
    """Smoothed counts carry fractions (temporal smoothing, or a caller's own): the box mean
    over 640 columns of values near 500 stays within float64 rounding of the direct mean."""
    rng = np.random.default_rng(4)
    x = rng.uniform(400.0, 500.0, (2, 640))
    ref = np.stack([np.convolve(np.pad(r, 2, mode="edge"), np.ones(5), mode="valid") / 5 for r in x])
    np.testing.assert_allclose(spatial_smooth(x, 5), ref, rtol=1e-11, atol=0)


def test_smoothing_returns_new_arrays():
    """spatial_smooth with no filter and temporal_smooth at the first frame (or alpha 1) give
    new arrays: writing them (the pipeline keeps the result as its state) leaves the input alone."""
    from pipeline.scanline import temporal_smooth

    x = np.array([[1.0, 2.0, 3.0]])
    for out in (spatial_smooth(x, 1), temporal_smooth(x, None, 0.5), temporal_smooth(x, x + 1, 1.0)):
        out[0, 0] = 99.0
        assert x.tolist() == [[1.0, 2.0, 3.0]]
    state = np.array([[10.0, 0.0, 3.0]])
    np.testing.assert_allclose(temporal_smooth(x, state, 0.25), [[0.25 * 1 + 0.75 * 10, 0.5, 3.0]])


def test_a_single_true_pixel_makes_its_column_true():
    from pipeline.scanline import true_scanlines

    m = np.zeros((2, 3, 4), bool)
    m[0, 2, 1] = True
    m[1, :, 3] = True
    assert true_scanlines(m).tolist() == [[False, True, False, False], [False, False, False, True]]


# --- run-length coding -----------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(hnp.arrays(bool, st.integers(1, 700)))
def test_rle_round_trip(s):
    runs = rle_encode(s)
    decoded = rle_decode(runs, s.size)
    assert decoded.dtype == bool
    np.testing.assert_array_equal(decoded, s)
    assert runs.sum() == s.size and np.all(runs[1:] > 0)
    assert scanline_bits(s[None])[0] == rle_bits(runs, s.size)


def test_rle_bits_of_640_columns():
    s = np.zeros(640, bool)
    assert rle_bits(rle_encode(s), 640) == 10
    s[100:150] = True
    s[300:310] = True
    assert rle_encode(s).tolist() == [100, 50, 150, 10, 330]
    assert scanline_bits(s) == 50


@pytest.mark.parametrize("width, bits", [(1, 1), (2, 2), (3, 2), (511, 9), (512, 10), (640, 10), (1023, 10),
                                         (1024, 11)])
def test_a_run_length_takes_the_bits_of_the_width_itself(width, bits):
    """Run lengths go from 0 to W: W + 1 values, ceil(log2(W + 1)) bits (a 512-column run needs 10)."""
    from pipeline import bits_per_run

    assert bits_per_run(width) == bits
    assert 2 ** (bits - 1) <= width < 2 ** bits


@pytest.mark.parametrize("runs", [[3, -1, 2], [[2, 2]], [1, 2]])
def test_rle_decode_refuses_runs_that_do_not_make_the_width(runs):
    with pytest.raises(ValueError, match="runs: expected non-negative run lengths summing to width 4"):
        rle_decode(runs, 4)


def test_an_empty_scanline_is_no_runs_and_decodes_back():
    runs = rle_encode(np.zeros(0, bool))
    assert runs.shape == (0,) and rle_bits(runs, 0) == 0
    assert rle_decode(runs, 0).shape == (0,)


@pytest.mark.parametrize("s", [np.array(True), np.zeros((2, 3), bool)])
def test_rle_encode_refuses_what_is_not_one_scanline(s):
    with pytest.raises(ValueError, match=r"scanline: expected shape \(W,\), got"):
        rle_encode(s)


# --- metrics ---------------------------------------------------------------------------

def test_metrics_on_known_confusion():
    pred = np.array([1, 1, 1, 0, 0, 0, 0, 1, 0, 0], bool)
    true = np.array([1, 1, 0, 1, 0, 0, 0, 0, 0, 0], bool)
    c = confusion(pred, true)
    assert (c["tp"], c["fp"], c["fn"], c["tn"]) == (2, 2, 1, 5)
    m = cdnet_metrics(**c)
    assert m["recall"] == pytest.approx(2 / 3)
    assert m["precision"] == pytest.approx(0.5)
    assert m["f1"] == pytest.approx(2 * 0.5 * (2 / 3) / (0.5 + 2 / 3))
    assert m["pwc"] == pytest.approx(30.0)
    assert m["specificity"] == pytest.approx(5 / 7)


def test_confusion_counts_each_kind_once():
    pred = np.array([[1, 1, 1, 1, 1, 0, 0], [0, 0, 0, 0, 0, 0, 1]], bool)
    true = np.array([[1, 0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1, 0]], bool)
    c = confusion(pred, true)
    assert (c["tp"], c["fp"], c["fn"], c["tn"]) == (1, 5, 2, 6)
    per_row = confusion(pred, true, axis=1)
    assert [per_row[k].tolist() for k in ("tp", "fp", "fn", "tn")] == [[1, 0], [4, 1], [1, 1], [1, 5]]


@pytest.mark.parametrize("counts, expected", [
    # a single column of each kind: the ratios are 0 or 1, not the empty-denominator 1
    ((0, 0, 1, 0), dict(recall=0.0, precision=1.0, f1=0.0, pwc=100.0, specificity=1.0)),
    ((0, 1, 0, 0), dict(recall=1.0, precision=0.0, f1=0.0, pwc=100.0, specificity=0.0)),
    ((0, 3, 2, 5), dict(recall=0.0, precision=0.0, f1=0.0, pwc=50.0, specificity=5 / 8)),    # P + R = 0
    ((1, 3, 1, 5), dict(recall=0.5, precision=0.25, f1=1 / 3, pwc=40.0, specificity=5 / 8)),  # P + R < 1
    ((0, 0, 0, 0), dict(recall=1.0, precision=1.0, f1=1.0, pwc=0.0, specificity=1.0)),
])
def test_metrics_of_few_columns(counts, expected):
    assert cdnet_metrics(*counts) == pytest.approx(expected)


def test_metrics_empty_cases():
    m = cdnet_metrics(0, 0, 0, 10)
    assert (m["recall"], m["precision"], m["pwc"]) == (1.0, 1.0, 0.0)
    assert cdnet_metrics(0, 5, 0, 5)["f1"] == 0.0


def test_confusion_refuses_a_prediction_of_another_shape():
    """A (1,) prediction would broadcast against (3,) truth and be counted three times."""
    with pytest.raises(ValueError, match=r"pred: expected the shape of the ground truth \(3,\), got \(1,\)"):
        confusion([True], [True, False, True])


@pytest.mark.parametrize("camera_axis", [1, -2])
def test_evaluate_counts_per_camera_on_any_axis_in_plain_python_numbers(camera_axis):
    # (frames, cameras, columns): camera 0 has 1 TP, 1 FP over its 4 columns; camera 1 has 1 FN
    pred = np.array([[[1, 1], [0, 0]], [[0, 0], [0, 0]]], bool)
    truth = np.array([[[1, 0], [0, 0]], [[0, 0], [1, 0]]], bool)
    r = evaluate(pred, truth, camera_axis=camera_axis)
    assert [(c["tp"], c["fp"], c["fn"], c["tn"]) for c in r["per_camera"]] == [(1, 1, 0, 2), (0, 0, 1, 3)]
    assert (r["tp"], r["fp"], r["fn"], r["tn"]) == (1, 1, 1, 5)
    assert r["per_camera"][0]["precision"] == 0.5 and r["per_camera"][1]["recall"] == 0.0
    assert r["pwc"] == 25.0
    leaves = [v for k, v in r.items() if k != "per_camera"] + [v for c in r["per_camera"] for v in c.values()]
    assert {type(v) for v in leaves} == {int, float}          # JSON-ready: no NumPy scalars


# --- production equals the straightforward reference -----------------------------------

def test_production_matches_reference_on_lab_frames():
    cams = LAB[:3]
    rng = np.random.default_rng(3)
    bg, frames, _labels = synthetic_sequence(cams, 3, rng)
    bg[:, 380:, :150] //= 10                       # a dark corner exercises the brightness floor
    frames[:, :, 380:, :150] //= 10
    params = PipelineParams(temporal_alpha=0.6)
    model = background_model(bg)
    fast, ref = Pipeline(cams, params, model), ReferencePipeline(cams, params, model)
    for f in frames:
        np.testing.assert_array_equal(fast.process(f), ref.process(f))


def _speckled_sequence(cams, n_frames, rng):
    """Synthetic frames with what clean people lack: single-pixel specks, one-pixel lines
    of both orientations, black pixels over the lit room, and a dark corner whose
    background and frame norms sit exactly on the default floor (25) and difference
    (40) (as 8-bit whole levels they are exact: (15, 20, 0) has norm 25)."""
    bg, frames, _ = synthetic_sequence(cams, n_frames, rng)
    h, w = bg.shape[1:3]
    bg[:, h - 30:, :30] = (15, 20, 0)                                   # |b| = 25: on the floor
    frames[:, :, h - 30:, :30] = (15, 20, 0)
    frames[:, :, h - 30:h - 20, :10] = (15, 20, 40)                     # |a - b| = 40: on the delta
    frames[:, :, h - 20:h - 10, :10] = (15, 20, 41)                     # just above it
    frames[:, :, h - 10:, :10] = (9, 12, 0)                             # norm 15, difference 10
    for f in frames:
        for i in range(len(cams)):
            ys, xs = rng.integers(0, h, 200), rng.integers(0, w, 200)
            f[i, ys, xs] = rng.integers(0, 256, (200, 3))              # specks, black ones too
            x, y = rng.integers(0, w - 1), rng.integers(0, h - 1)
            f[i, :, x] = (250, 10, 10)                                  # a one-pixel column
            f[i, y, :] = (10, 250, 10)                                  # a one-pixel row
            f[i, 5:12, w - 4:] = 0                                      # black at the right edge
    return bg, frames


@pytest.mark.parametrize("params", [
    PipelineParams(opening_kernel=1, spatial_kernel=1, median_kernel=1, temporal_alpha=1.0, column_threshold=10),
    PipelineParams(opening_kernel=3, spatial_kernel=5, median_kernel=5, temporal_alpha=0.5, column_threshold=12),
    PipelineParams(opening_kernel=1, spatial_kernel=3, median_kernel=7, temporal_alpha=1.0, column_threshold=8,
                   brightness_floor=0.0),
    PipelineParams(threshold_deg=10.0, opening_kernel=5, spatial_kernel=1, median_kernel=3, column_threshold=4),
])
def test_production_matches_reference_on_speckled_frames(params):
    """Parameters off the defaults (no filter, small kernels, no floor, integer thresholds that
    column counts reach exactly) on frames with specks, lines, black pixels and exact ties."""
    cams = [scene.Camera.from_pose(i + 1, [x, 0.05, 2.2], np.radians(90 + d), np.radians(15), 160, 120,
                                   np.radians(49), [-0.18, 0.06, 0, 0, 0]) for i, (x, d) in enumerate([(1.5, -20), (5.0, 20)])]
    bg, frames = _speckled_sequence(cams, 3, np.random.default_rng(11))
    fast, ref = Pipeline(cams, params, bg), ReferencePipeline(cams, params, bg)
    for f in frames:
        expected = fast.step(f)
        np.testing.assert_array_equal(ref.process(f), expected.scanlines)


def test_reference_foreground_on_the_floor_and_delta_ties():
    """The reference's own foreground on exact ties: |b| = 25 is not below the floor 25, so
    the angle decides; |a - b| = 40 is not above the delta 40; a black pixel over the lit
    room is dark (it differs by 120 sqrt 3), and with no floor has no angle: background, as
    the production test has it."""
    cam = flat_camera(8, 6)
    bg = np.full((1, 6, 8, 3), 120, np.uint8)
    bg[0, 0] = (15, 20, 0)                                        # |b| = 25: the angle decides
    bg[0, 1] = (9, 12, 0)                                         # |b| = 15: dark
    frame = bg.copy()
    frame[0, 0, :3] = [(30, 40, 0), (15, 20, 1), (15, 20, 5)]     # 0, 2.3 and 11.3 degrees off
    frame[0, 1, :3] = [(9, 12, 40), (9, 12, 41), (9, 12, 39)]     # |a - b| = 40, 41, 39
    frame[0, 2, :2] = [(0, 0, 0), (1, 0, 0)]                      # black, all but black
    expected = np.zeros((6, 8), bool)
    expected[0, 2] = expected[1, 1] = expected[2, 0] = expected[2, 1] = True
    params = PipelineParams(threshold_deg=3.0, brightness_floor=25.0, dark_delta=40.0)
    np.testing.assert_array_equal(ReferencePipeline([cam], params, bg).foreground(frame[0], 0), expected)
    no_floor = PipelineParams(threshold_deg=3.0, brightness_floor=0.0, dark_delta=40.0)
    expected[2, 0] = False                                        # black: no angle
    expected[1, :3] = True                                        # 73-75 degrees off (9, 12, 0)
    np.testing.assert_array_equal(ReferencePipeline([cam], no_floor, bg).foreground(frame[0], 0), expected)
    np.testing.assert_array_equal(colour_angle_foreground(frame, bg.astype(np.float32), 3.0, 0.0, 40.0)[0], expected)


def test_step_returns_the_intermediates_of_process():
    """Pipeline.step: the opened foreground, its rectification, the smoothed column counts
    and the scanlines are each what the step before them gives, and the scanlines are process()'s."""
    cams = [scene.Camera.from_pose(i + 1, [x, 0.05, 2.2], np.radians(90 + d), np.radians(15), 160, 120,
                                   np.radians(49), [-0.18, 0.06, 0, 0, 0]) for i, (x, d) in enumerate([(1.5, -20), (5.0, 20)])]
    bg, frames, _labels = synthetic_sequence(cams, 3, np.random.default_rng(7))
    p = PipelineParams(temporal_alpha=0.6, column_threshold=3.0)
    stepped, plain = Pipeline(cams, p, bg), Pipeline(cams, p, bg)
    state = None
    for f in frames:
        out = stepped.step(f)
        fg = open_masks(colour_angle_foreground(f, stepped.background, p.threshold_deg, p.brightness_floor,
                                                p.dark_delta), p.opening_kernel)
        np.testing.assert_array_equal(out.foreground, fg)
        rect = stepped.rectifier.rectify(fg)
        np.testing.assert_array_equal(out.rectified, rect)
        assert rect.any(axis=(1, 2)).all()
        sums = spatial_smooth(rect.sum(axis=1), p.spatial_kernel)
        state = sums if state is None else p.temporal_alpha * sums + (1 - p.temporal_alpha) * state
        np.testing.assert_allclose(out.smoothed, state, atol=1e-9)
        np.testing.assert_array_equal(out.scanlines, plain.process(f))


@pytest.mark.parametrize("spatial, median, opening", [(9, 11, 1), (1, 1, 15)])
def test_at_the_width_limit_an_object_still_leaves_a_run_the_filters_keep(spatial, median, opening):
    """Pipeline.sight_range with an object's width: out to its far radius a 10 cm object spans
    at least w f / far rectified columns (f: the level camera's pixels per radian, fewest at its
    centre) and w g / far raw pixels (g = raw_pixels_per_radian). The column centres in such a
    span (one fewer than its width, at worst), at the fewest rows a new object is sent with
    (column_threshold / temporal_alpha), come through the box and median filters, and a bar
    over the pixel centres of its raw span survives the opening.
    (The first parameters make the columns the limit, the second the raw pixels.)"""
    from pipeline.nearfield import raw_pixels_per_radian

    cam = flat_camera()
    p = PipelineParams(spatial_kernel=spatial, median_kernel=median, opening_kernel=opening, column_threshold=3.0,
                       temporal_alpha=0.5)
    near, far = Pipeline([cam], p).sight_range(1.75, object_width=0.1)
    assert near[0] == 0.0 and far[0] < 1.0                       # the width is the limit, not the height
    assert not near.flags.writeable and not far.flags.writeable  # the pipeline's cached answer
    columns = int(np.ceil(0.1 * Pipeline([cam], p).rectifier.K_virtual[0, 0, 0] / far[0] - 1e-9)) - 1
    counts = np.zeros((1, 64))
    counts[0, 20:20 + columns] = p.column_threshold / p.temporal_alpha + 1e-6
    smoothed = p.temporal_alpha * spatial_smooth(counts, spatial)    # a new object after empty frames
    assert median_threshold(smoothed, median, p.column_threshold).any()
    pixels = int(np.ceil(0.1 * raw_pixels_per_radian(cam) / far[0] - 1e-9)) - 1   # pixel centres in its span
    bar = np.zeros((1, 48, 64), bool)
    bar[0, 5:40, 20:20 + pixels] = True
    assert open_masks(bar, opening).any()


def test_temporal_state_and_reset():
    cam = flat_camera()
    bg = np.full((1, 48, 64, 3), 120, np.uint8)
    p = PipelineParams(opening_kernel=1, spatial_kernel=1, median_kernel=1, temporal_alpha=0.5,
                       column_threshold=12.0)
    pipe = Pipeline([cam], p, background=bg)
    fr = bg.copy()
    fr[0, :, 30:32] = (200, 40, 40)                # 48 rows of foreground in 2 columns
    assert pipe.process(fr)[0, 30:32].all()
    assert pipe.process(bg)[0, 30:32].all()        # 24 left after one empty frame
    assert not pipe.process(bg)[0].any()           # 12: not above the threshold
    pipe.process(fr)
    pipe.reset()
    assert not pipe.process(bg)[0].any()


@pytest.mark.parametrize("opening", [1, 5])
def test_process_with_truth_equals_process_and_ground_truth(opening):
    cams = LAB[:3]
    rng = np.random.default_rng(5)
    bg, frames, labels = synthetic_sequence(cams, 4, rng)
    labels = np.asarray(labels).copy()
    labels[1, :, :, :7] = 2                        # truth on the image borders and in every row
    labels[2, :, -3:] = 1
    labels[3] = rng.integers(0, 2, labels[3].shape)  # noise: isolated true pixels
    params = PipelineParams(opening_kernel=opening, temporal_alpha=0.6)
    model = background_model(bg)
    both, apart = Pipeline(cams, params, model), Pipeline(cams, params, model)
    for f, lab in zip(frames, labels):
        scan, gt = both.process_with_truth(f, lab)
        np.testing.assert_array_equal(scan, apart.process(f))       # temporal state included
        np.testing.assert_array_equal(gt, apart.ground_truth(lab)[1])
        assert scan.dtype == gt.dtype == bool and gt.shape == (3, 640)
    with pytest.raises(ValueError, match="labels: expected shape"):
        both.process_with_truth(frames[0], labels[0][:2])


def test_compiled_angle_test_runs_without_a_writable_cache():
    """Where numba finds no cache folder, the kernel is compiled per process instead of failing at import."""
    import subprocess
    import sys

    code = ("import numpy as np\n"
            "from pipeline.foreground import colour_angle_foreground, background_model\n"
            "bg = np.full((1, 4, 4, 3), 100, np.uint8); fr = bg.copy(); fr[0, 1, 2] = (200, 50, 50)\n"
            "print(int(colour_angle_foreground(fr, background_model(bg), 5.0, 10.0, 20.0).sum()))\n")
    env = {**os.environ, "NUMBA_CACHE_LOCATOR_CLASSES": "_IPythonCacheLocator"}   # no locator for a .py file
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "1"


def test_with_params_equals_a_pipeline_built_with_them():
    """Tuning's shared pipeline: other thresholds, kernels and smoothing give the same
    scanlines as a pipeline built from scratch, and the original keeps its own."""
    cams = LAB[:3]
    rng = np.random.default_rng(11)
    bg, frames, _labels = synthetic_sequence(cams, 3, rng)
    base = Pipeline(cams, PipelineParams(), bg)
    for params in (PipelineParams(threshold_deg=9.0, brightness_floor=0.0, opening_kernel=3, temporal_alpha=0.5),
                   PipelineParams(threshold_deg=1.5, dark_delta=10.0, opening_kernel=9, median_kernel=5)):
        shared, fresh = base.with_params(params), Pipeline(cams, params, bg)
        assert shared.rectifier is base.rectifier and shared.params == params
        for f in frames:
            np.testing.assert_array_equal(shared.process(f), fresh.process(f))
    own = Pipeline(cams, PipelineParams(), bg)
    for f in frames:
        np.testing.assert_array_equal(base.process(f), own.process(f))


@pytest.mark.parametrize("width", [64, 63, 640])
def test_a_level_undistorted_camera_sees_into_both_edge_columns(width):
    """Its band's edge columns sit on the image's outer edges (u = -0.5 and W - 0.5); rounding
    half to even sent W - 0.5 out of the image for an even W, so column W - 1 never saw."""
    cam = scene.Camera.from_pose(1, [0.0, 0.0, 1.5], 0.0, 0.0, width, 48, np.radians(50), [0, 0, 0, 0, 0])
    bg = np.full((1, 48, width, 3), 120, np.uint8)
    params = PipelineParams(opening_kernel=1, spatial_kernel=1, median_kernel=1, column_threshold=0.5)
    frame = bg.copy()
    frame[0, :, width - 3:] = (200, 40, 40)                   # someone cut by the right border
    for pipe in (Pipeline([cam], params, bg), ReferencePipeline([cam], params, bg)):
        assert pipe.process(frame)[0].nonzero()[0].tolist() == [width - 3, width - 2, width - 1]


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 4), st.integers(1, 20), st.integers(0, 3), st.integers(1, 33),
       st.sampled_from([np.uint8, np.int32, np.int64, bool]), st.integers(0, 2**32 - 1))
def test_truth_kernels_equal_their_numpy_formulas(n, h, extra, w, dtype, seed):
    """process_with_truth's compiled steps: bit 7 kept and bit 0 set where a label is
    positive (rows between cameras untouched), then per column the bit-7 count and any bit 0."""
    from pipeline.truth_kernel import count_columns, mark_truth

    rng = np.random.default_rng(seed)
    rows = h + extra
    opened = rng.choice(np.array([0, 255], np.uint8), (n * rows, w))
    labels = rng.integers(-2 if np.issubdtype(dtype, np.signedinteger) else 0, 4, (n, h, w)).astype(dtype)
    want = opened.copy().reshape(n, rows, w)
    want[:, :h] = (want[:, :h] & 128) | (labels > 0)
    got = mark_truth(opened, labels, rows)
    np.testing.assert_array_equal(got.reshape(n, rows, w), want)
    rect = rng.choice(np.array([0, 1, 128, 129], np.uint8), (n, h, w), p=[0.7, 0.1, 0.1, 0.1])
    counts, truth = np.empty((n, w), np.int32), np.empty((n, w), bool)
    count_columns(rect, counts, truth)
    np.testing.assert_array_equal(counts, (rect >= 128).sum(axis=1))
    np.testing.assert_array_equal(truth, (rect & 1).any(axis=1))


def test_a_rig_rectifies_each_camera_as_it_would_alone():
    """Cameras of one rig pitched differently need different output heights: the rig's is the
    tallest, and each camera's rectified image is the one it has alone, zero below."""
    from pipeline import Rectifier

    cams = [scene.Camera.from_pose(n, [0.0, 0.0, 1.5], 0.3 * n, np.radians(pitch), 40, 30, np.radians(50),
                                   [-0.1, 0.01, 0, 0, 0]) for n, pitch in ((1, 0.0), (2, 35.0), (3, -10.0))]
    rig = Rectifier.build(cams)
    rng = np.random.default_rng(0)
    masks = rng.random((3, 30, 40)) < 0.5
    masks[:, 5:25, 10:30] = True
    out = rig.rectify(masks)
    heights = []
    for i, cam in enumerate(cams):
        alone = Rectifier.build([cam])
        heights.append(alone.out_height)
        np.testing.assert_array_equal(out[i, :alone.out_height], alone.rectify(masks[i:i + 1])[0])
        assert not out[i, alone.out_height:].any()
    assert rig.out_height == max(heights) > min(heights)


@pytest.mark.parametrize("pitch_deg, dist", [(15.0, [-0.18, 0.06, 0.0, 0.0, 0.0]), (-8.0, [0.1, -0.05, 0.002, -0.003, 0.0]),
                                            (0.0, [0.0] * 5)])
def test_a_full_mask_rectifies_to_the_rays_that_land_on_the_raw_image(pitch_deg, dist):
    """Each output pixel's level ray, turned back into the camera and projected through its
    lens (cv2.projectPoints), lands on the raw image (its pixels' outer edges included) exactly
    where a raw mask of ones rectifies to one; pixels within float32 rounding of the image's
    edge may go either way."""
    from pipeline import Rectifier
    from pipeline.rectify import level_rotation

    cam = scene.Camera.from_pose(1, [0.0, 0.0, 1.5], 0.4, np.radians(pitch_deg), 48, 36, np.radians(55), dist)
    rect = Rectifier.build([cam])
    got = rect.rectify(np.ones((1, 36, 48), bool))[0]
    r, c = np.mgrid[0:rect.out_height, 0:rect.width]
    rays = np.column_stack([c.ravel(), r.ravel(), np.ones(c.size)]) @ np.linalg.inv(rect.K_virtual[0]).T
    rays = rays @ level_rotation(cam)                                  # level frame -> camera frame
    ahead = rays[:, 2] > 0
    uv = np.full((c.size, 2), np.inf)
    uv[ahead] = cv2.projectPoints(rays[ahead], np.zeros(3), np.zeros(3), cam.K, cam.dist)[0].reshape(-1, 2)
    lo, hi = np.array([-0.5, -0.5]), np.array([cam.width - 0.5, cam.height - 0.5])
    want = np.all((uv >= lo) & (uv <= hi), axis=1).reshape(got.shape)
    near_edge = np.any(np.abs(np.concatenate([uv - lo, uv - hi], 1)) < 1e-3, axis=1).reshape(got.shape)
    assert want.sum() > 0.8 * want.size
    np.testing.assert_array_equal(got[~near_edge], want[~near_edge])


def test_a_new_background_starts_a_new_sequence():
    """set_background forgets the temporal state: after it, an empty frame gives empty
    scanlines, as in a fresh pipeline, not the decaying trace of the person seen before."""
    cam = flat_camera()
    bg = np.full((1, 48, 64, 3), 120, np.uint8)
    fr = bg.copy()
    fr[0, 4:44, 30:34] = (200, 40, 40)
    p = PipelineParams(opening_kernel=1, spatial_kernel=1, median_kernel=1, temporal_alpha=0.5,
                       column_threshold=12.0)
    pipe = Pipeline([cam], p, bg)
    assert pipe.process(fr)[0, 30:34].all()                    # 40 rows > 12
    pipe.set_background(bg)
    assert not pipe.process(bg).any()                          # 0.5 * 40 = 20 > 12 had the state stayed


def test_process_with_truth_marks_each_cameras_own_rows():
    """Truth only in the top two rows of the second and third cameras (nothing in front of
    any): it is found in each, with the opening's zero rows between the cameras."""
    cams = [flat_camera(), flat_camera(), flat_camera()]
    bg = np.full((3, 48, 64, 3), 120, np.uint8)
    labels = np.zeros((3, 48, 64), np.int32)
    labels[1:, :2, 20:40] = 1
    pipe = Pipeline(cams, PipelineParams(opening_kernel=5), bg)
    scan, truth = pipe.process_with_truth(bg, labels)
    assert not scan.any()
    assert not truth[0].any() and truth[1:].any(axis=1).all()
    np.testing.assert_array_equal(truth, pipe.ground_truth(labels)[1])


def test_the_true_sight_range_of_an_objects_width_is_one_column_and_one_raw_pixel():
    """With truth, an object of a given width needs one row, one rectified column and one raw
    pixel across, whatever the filters: the range of pipeline.sight_range with those."""
    from pipeline import sight_range
    from pipeline.nearfield import raw_pixels_per_radian

    cam = flat_camera()
    pipe = Pipeline([cam], PipelineParams(spatial_kernel=9, median_kernel=11, opening_kernel=15))
    near, far = pipe.sight_range(1.75, truth=True, object_width=0.02)
    want = sight_range([cam], 1.75, 1.0, pipe.rectifier.width, 0.02, 1.0, 1.0, [raw_pixels_per_radian(cam)])
    assert far[0] < pipe.sight_range(1.75, truth=True)[1][0]  # the width is the limit
    assert (near[0], far[0]) == (want[0][0], want[1][0])


def test_views_that_are_not_contiguous_are_taken_as_their_values():
    """A BGR image flipped to RGB by a view (``[..., ::-1]``), labels in Fortran order and a
    read-only model subsampled by a strided view give what their contiguous copies give."""
    cams = [flat_camera(), flat_camera()]
    rng = np.random.default_rng(3)
    bg = rng.integers(60, 200, (2, 48, 64, 3)).astype(np.uint8)
    fr = bg.copy()
    fr[:, 10:30, 20:30] = (200, 40, 40)
    labels = np.zeros((2, 48, 64), np.int32)
    labels[:, 10:30, 20:30] = 1
    bgr = np.ascontiguousarray(fr[..., ::-1])
    p = PipelineParams(opening_kernel=3, median_kernel=1, column_threshold=5.0)
    mine, plain = Pipeline(cams, p, bg), Pipeline(cams, p, bg)
    scan, truth = mine.process_with_truth(bgr[..., ::-1], np.asfortranarray(labels))
    want_scan, want_truth = plain.process_with_truth(fr, labels)
    assert want_scan.any() and want_truth.any()
    np.testing.assert_array_equal(scan, want_scan)
    np.testing.assert_array_equal(truth, want_truth)
    big = np.repeat(np.repeat(bg.astype(np.float32) + 0.5, 2, axis=1), 2, axis=2)   # not whole levels
    big.setflags(write=False)                      # read-only, as background_model's: kept, not copied
    model = big[:, ::2, ::2]
    assert not model.flags.c_contiguous
    np.testing.assert_array_equal(colour_angle_foreground(fr, model, 3.0, 25.0, 40.0),
                                  colour_angle_foreground(fr, model.copy(), 3.0, 25.0, 40.0))
