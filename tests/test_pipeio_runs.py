"""pipeline.runs.run_sequence: a run starts from its first frame, labels pair with frames."""

import numpy as np
import pytest

import scene
from pipeline import Pipeline, PipelineParams
from pipeline.runs import run_sequence
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
