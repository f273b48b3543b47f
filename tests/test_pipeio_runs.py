"""pipeline.runs.run_sequence: a run starts from its first frame, labels pair with frames;
scanline_f1: the pooled F1 of other parameters."""

import numpy as np
import pytest

import scene
from pipeline import Pipeline, PipelineParams
from pipeline.runs import run_sequence, scanline_f1
from pipeline.synthetic import synthetic_sequence


@pytest.fixture(scope="module")
def sequence():
    cams = [scene.Camera.from_pose(i + 1, [x, 0.05, 2.2], np.radians(90 + d), np.radians(15), 160, 120,
                                   np.radians(49), [-0.18, 0.06, 0, 0, 0])
            for i, (x, d) in enumerate([(1.5, -20), (5.0, 20)])]
    bg, frames, labels = synthetic_sequence(cams, 8, np.random.default_rng(5))
    return cams, bg, frames, labels


def test_a_pipeline_reused_for_a_second_run_gives_the_same_run(sequence):
    cams, bg, frames, labels = sequence
    params = PipelineParams(column_threshold=3.0, temporal_alpha=0.5)
    pipe = Pipeline(cams, params, bg)
    first = run_sequence(pipe, frames, labels)
    again = run_sequence(pipe, frames, labels)          # smoothed with the first run's last frame
    fresh = run_sequence(Pipeline(cams, params, bg), frames, labels)
    np.testing.assert_array_equal(again.scanlines, first.scanlines)
    np.testing.assert_array_equal(fresh.scanlines, first.scanlines)
    assert again.metrics() == first.metrics()


def test_labels_that_do_not_pair_with_the_frames_are_refused(sequence):
    cams, bg, frames, labels = sequence
    pipe = Pipeline(cams, PipelineParams(column_threshold=3.0), bg)
    with pytest.raises(ValueError, match=r"^labels: ended after 5 batches, before the frames; expected one per frame$"):
        run_sequence(pipe, frames, labels[:5])
    with pytest.raises(ValueError, match=r"^labels: more batches than the 5 frames; expected one per frame$"):
        run_sequence(pipe, frames[3:], labels)             # frames skipped, labels not: misaligned
    assert run_sequence(pipe, iter(frames), iter(labels)).gt_scanlines.shape == (8, 2, 160)


def test_a_runs_metrics_are_its_frames_counted_plainly(sequence):
    """Every number of RunResult.metrics() recomputed from the pipeline's steps taken one by
    one: scanlines and true scanlines with numpy counts, the foreground (colour angle, then a
    scipy opening) against labels > 0 per camera, and the run lengths of rle_encode."""
    from scipy import ndimage

    from pipeline import colour_angle_foreground, rle_encode

    cams, bg, frames, labels = sequence
    params = PipelineParams(column_threshold=3.0, temporal_alpha=0.5)
    result = run_sequence(Pipeline(cams, params, bg), frames, labels)
    m = result.metrics()

    plain = Pipeline(cams, params, bg)
    scans = np.stack([plain.process(f) for f in frames])
    gts = np.stack([plain.ground_truth(lab)[1] for lab in labels])
    np.testing.assert_array_equal(result.scanlines, scans)
    np.testing.assert_array_equal(result.gt_scanlines, gts)
    assert (m["frames"], m["cameras"], m["width"], m["raw_bits"]) == (8, 2, 160, 160)
    runs = [len(rle_encode(s)) * 8 for s in scans.reshape(-1, 160)]       # 8 bits code 0..160
    assert (m["rle_bits_mean"], m["rle_bits_max"]) == (pytest.approx(np.mean(runs)), max(runs))
    assert (m["tp"], m["fp"], m["fn"]) == (np.sum(scans & gts), np.sum(scans & ~gts), np.sum(~scans & gts))
    assert [c["tp"] for c in m["per_camera"]] == np.sum(scans & gts, axis=(0, 2)).tolist()

    model = plain.background
    pixels = np.zeros((2, 4), int)
    for f, lab in zip(frames, labels):
        fg = colour_angle_foreground(f, model, params.threshold_deg, params.brightness_floor, params.dark_delta)
        k = np.ones((params.opening_kernel,) * 2)
        fg = np.stack([ndimage.binary_opening(x, k, border_value=0) for x in fg])
        t = np.asarray(lab) > 0
        pixels += np.stack([(fg & t).sum((1, 2)), (fg & ~t).sum((1, 2)), (~fg & t).sum((1, 2)),
                            (~fg & ~t).sum((1, 2))], 1)
    assert pixels[:, 0].min() > 0 and pixels[:, 1:3].sum() > 0                # people found, and some misses
    np.testing.assert_array_equal(result.pixel_counts, pixels)
    assert [m["pixel"][k] for k in ("tp", "fp", "fn", "tn")] == pixels.sum(0).tolist()
    for got, (tp, fp, fn, tn) in zip(m["pixel"]["per_camera"] + [m["pixel"]], [*pixels, pixels.sum(0)]):
        assert {k: got[k] for k in ("recall", "precision", "f1", "pwc", "specificity")} == pytest.approx(
            {"recall": tp / (tp + fn), "precision": tp / (tp + fp), "f1": 2 * tp / (2 * tp + fp + fn),
             "pwc": 100 * (fp + fn) / (tp + fp + fn + tn), "specificity": tn / (tn + fp)})
    assert len(m["pixel"]["per_camera"]) == 2


def test_a_run_without_labels_has_no_truth_and_reports_each_frame(sequence):
    cams, bg, frames, _ = sequence
    ticks = []
    result = run_sequence(Pipeline(cams, PipelineParams(column_threshold=3.0), bg), frames[:3],
                          progress=lambda: ticks.append(1))
    assert len(ticks) == 3
    assert result.scanlines.shape == (3, 2, 160)
    assert result.gt_scanlines is None and result.pixel_counts is None
    m = result.metrics()
    assert "f1" not in m and "pixel" not in m and m["frames"] == 3


def test_a_run_of_no_frames_is_refused(sequence):
    cams, bg, *_ = sequence
    with pytest.raises(ValueError, match=r"^frames: expected at least one frame after the background$"):
        run_sequence(Pipeline(cams, PipelineParams(column_threshold=3.0), bg), [])


def test_a_runs_bearings_are_its_columns_bearings(sequence):
    """Each camera's columns sweep its 49 degree field of view, right to left, the middle one
    along its heading (70 and 110 degrees)."""
    cams, bg, frames, labels = sequence
    pipe = Pipeline(cams, PipelineParams(column_threshold=3.0), bg)
    bearings = run_sequence(pipe, frames[:2], labels[:2]).bearings
    np.testing.assert_array_equal(bearings, Pipeline(cams).bearings)
    deg = np.degrees(bearings)
    assert np.all(np.diff(deg, axis=1) < 0)
    assert deg[:, 0] - deg[:, -1] == pytest.approx([49, 49], abs=0.5)
    assert deg[:, 80] == pytest.approx([70, 110], abs=0.5)


def test_scanline_f1_is_the_pooled_f1_of_the_params_given(sequence):
    """2 TP / (2 TP + FP + FN) over every frame, camera and column, of the parameters given,
    not the pipeline's own; here precision (0.81) is not recall (0.99)."""
    cams, bg, frames, labels = sequence
    base = Pipeline(cams, PipelineParams(column_threshold=10.0), bg)
    gts = np.stack([base.ground_truth(lab)[1] for lab in labels])
    params = PipelineParams(column_threshold=3.0, temporal_alpha=0.5)
    plain = Pipeline(cams, params, bg)
    pred = np.stack([plain.process(f) for f in frames])
    tp, fp, fn = np.sum(pred & gts), np.sum(pred & ~gts), np.sum(~pred & gts)
    assert tp / (tp + fp) < 0.9 < tp / (tp + fn)
    assert scanline_f1(base, np.asarray(frames), gts, params) == pytest.approx(2 * tp / (2 * tp + fp + fn), abs=1e-12)
