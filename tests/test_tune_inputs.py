"""`camtask tune` refuses, before reading any frame, frames or trials the memory cannot hold and missing files."""

import numpy as np
import pytest

import pipeline.tuning
from pipeline.io import RenderDir
from pipeline.synthetic import synthetic_sequence, write_render_dir
from testbed import memory
from tests.test_pipeline_cli import camtask, small_cameras, small_render_dir

FRAME_BYTES = 2 * (160 * 120 * 3 + 160)         # the two small cameras: RGB and a true scanline


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory):
    return small_render_dir(tmp_path_factory.mktemp("render"), 3, 4)


@pytest.fixture
def no_work(monkeypatch):
    """Fail at the first frame read or the first search."""
    def stop(*args, **kwargs):
        raise AssertionError("work started")
    monkeypatch.setattr(RenderDir, "frames", stop)
    monkeypatch.setattr(pipeline.tuning, "tune", stop)


def test_frames_the_memory_cannot_hold_are_refused_first(render_dir, tmp_path, monkeypatch, no_work):
    monkeypatch.setattr(memory, "available_memory", lambda: 2 * FRAME_BYTES + 100)
    # --frames 30 of a 3-frame episode: its 3 frames are what is held
    with pytest.raises(ValueError, match=r"^--frames: 3 frames would hold about .* of memory for the search .*; "
                                         r"expected at most 2 frames here$"):
        camtask(["tune", str(render_dir), "--trials", "1", "--out", str(tmp_path / "t.yaml")])
    assert not (tmp_path / "t.yaml").exists()


@pytest.mark.parametrize("trials", ["100000000000000000000", "2000000000"])
def test_trials_the_memory_cannot_hold_are_refused_first(render_dir, tmp_path, monkeypatch, no_work, trials):
    monkeypatch.setattr(memory, "available_memory", lambda: 10**10)      # 10 GB
    with pytest.raises(ValueError, match=rf"^--trials: {trials} trials would hold about .* GB of memory \(Optuna "
                                         r"keeps every trial\), more than the 10 GB available beside the frames; "
                                         r"expected at most 624992 trials here$"):
        camtask(["tune", str(render_dir), "--trials", trials, "--frames", "1", "--out", str(tmp_path / "t.yaml")])


def test_frames_are_held_once(tmp_path, monkeypatch):
    """The frames were read into a list, then stacked: twice their size at the peak."""
    import tracemalloc

    cams = small_cameras()
    write_render_dir(tmp_path / "r", cams, *synthetic_sequence(cams, 100, np.random.default_rng(4)))
    seen = {}

    def tune(cameras, background, frames, *args):
        seen["frames"], seen["peak"] = frames.nbytes, tracemalloc.get_traced_memory()[1]
        raise KeyboardInterrupt
    monkeypatch.setattr(pipeline.tuning, "tune", tune)
    tracemalloc.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            camtask(["tune", str(tmp_path / "r"), "--trials", "1", "--frames", "100",
                     "--out", str(tmp_path / "t.yaml"), "--json"])
    finally:
        tracemalloc.stop()
    assert seen["frames"] == 100 * 2 * 160 * 120 * 3
    assert seen["peak"] < 1.5 * seen["frames"], seen


@pytest.mark.parametrize("gone", ["masks/cam02/000002.png", "background/cam01.png"])
def test_a_missing_file_of_the_frames_used_is_refused_before_reading(render_dir, tmp_path, no_work, gone):
    import shutil

    root = tmp_path / "r"
    shutil.copytree(render_dir, root)
    (root / gone).unlink()
    with pytest.raises(ValueError, match=rf"^DIR: .*r lacks 1 file of its first 3 frames: {gone}$"):
        camtask(["tune", str(root), "--trials", "1", "--out", str(tmp_path / "t.yaml")])
    shutil.copytree(render_dir, tmp_path / "r2")
    (tmp_path / "r2" / "masks" / "cam02" / "000002.png").unlink()        # not among the frames used
    with pytest.raises(AssertionError, match="work started"):
        camtask(["tune", str(tmp_path / "r2"), "--trials", "1", "--frames", "2", "--out", str(tmp_path / "t.yaml")])


def test_scanlines_refuses_a_missing_file_of_the_frames_used_before_reading(render_dir, tmp_path, monkeypatch):
    """The same check, at the render directory's depth: scanlines found a lost mask only at its frame."""
    import shutil

    from pipeline import io as pipeline_io

    root = tmp_path / "r"
    shutil.copytree(render_dir, root)
    (root / "masks" / "cam01" / "000002.png").unlink()
    monkeypatch.setattr(pipeline_io.RenderDir, "frames", lambda self, i: pytest.fail("a frame was read"))
    with pytest.raises(ValueError, match=r"^DIR: .*r lacks 1 file of its first 3 frames: masks/cam01/000002.png$"):
        camtask(["scanlines", str(root), "--out", str(tmp_path / "s.npz")])
    assert not (tmp_path / "s.npz").exists()


def test_a_column_threshold_above_the_rectified_column_is_refused_first(render_dir, tmp_path, no_work):
    """scanlines, render and run refuse it (every scanline would be empty); tune searched
    from it, reported F1 0 and could write it as the best: a file scanlines then refused."""
    from pipeline import PipelineParams

    PipelineParams(column_threshold=500.0).to_yaml(tmp_path / "p.yaml")
    with pytest.raises(ValueError, match=r"^--params: column_threshold 500 is not below the \d+ pixels of a rectified "
                                         r"column; every scanline would be empty$"):
        camtask(["tune", str(render_dir), "--trials", "1", "--params", str(tmp_path / "p.yaml"),
                 "--out", str(tmp_path / "t.yaml")])
    assert not (tmp_path / "t.yaml").exists()


def test_the_search_stays_below_the_rows_of_a_small_cameras_rectified_column(monkeypatch):
    """SPACE searched column_threshold up to 60 pixels whatever the camera: a 64 x 40 camera's
    rectified columns have 46 rows, so a trial above that emptied every scanline and, were it
    the best, tune wrote a file scanlines refuses."""
    from pipeline import PipelineParams
    from pipeline.rectify import level_cameras

    cams = tiny_cameras()
    rows = level_cameras(cams)[1]
    assert rows < pipeline.tuning.SPACE["column_threshold"][2]
    bg, frames, _ = synthetic_sequence(cams, 2, np.random.default_rng(0))
    gt = np.zeros((2, 2, 64), bool)                 # the search space, not the F1, is under test
    tried = []
    real = pipeline.tuning.scanline_f1

    def scanline_f1(base, frames, gt, params):
        tried.append(params.column_threshold)
        return real(base, frames, gt, params)

    monkeypatch.setattr(pipeline.tuning, "scanline_f1", scanline_f1)
    pipeline.tuning.tune(cams, bg, frames, gt, 25, seed=0, start=PipelineParams(column_threshold=20.0))
    assert len(tried) == 25 and max(tried) <= rows - 1   # a column must exceed it: rows empty every scanline


def test_columns_of_one_row_are_searched_at_half_a_row(monkeypatch):
    """The search's top is one below the rows of a column; for columns of one row that would
    be 0, which column_threshold (> 0) refuses."""
    import pipeline.rectify

    cams = tiny_cameras()
    real = pipeline.rectify.level_cameras
    monkeypatch.setattr(pipeline.rectify, "level_cameras", lambda c: (real(c)[0], 1))
    assert pipeline.tuning.searched_space(cams)["column_threshold"] == ("float", 0.5, 0.5)
    monkeypatch.setattr(pipeline.rectify, "level_cameras", lambda c: (real(c)[0], 2))
    assert pipeline.tuning.searched_space(cams)["column_threshold"] == ("float", 1.0, 1.0)


def test_frames_with_nobody_in_view_are_warned_of(tmp_path, capsys):
    """With no occupied true column, F1 is 1 for parameters that detect nothing and 0 for any
    false positive: tune silently favoured parameters that never detect anyone."""
    cams = small_cameras()
    bg, images, labels = synthetic_sequence(cams, 2, np.random.default_rng(1))
    write_render_dir(tmp_path / "empty", cams, bg, bg[None].repeat(2, axis=0), np.zeros_like(labels))
    write_render_dir(tmp_path / "people", cams, bg, images, labels)
    warning = "warning: nobody is in view in the 2 frames tuned on"
    for name, warned in (("empty", True), ("people", False)):
        capsys.readouterr()
        camtask(["tune", str(tmp_path / name), "--trials", "2", "--out", str(tmp_path / f"{name}.yaml")])
        assert (warning in capsys.readouterr().err) == warned, name


def tiny_cameras():
    """Two 64 x 40 cameras: their rectified columns have 46 rows, fewer than SPACE's 60."""
    import scene

    return [scene.Camera.from_pose(i + 1, [x, 0.05, 2.2], np.radians(90 + d), np.radians(15), 64, 40,
                                   np.radians(49), [-0.18, 0.06, 0, 0, 0])
            for i, (x, d) in enumerate([(1.5, -20), (5.0, 20)])]


def test_a_start_outside_the_search_is_warned_of_with_the_range_searched(tmp_path, capsys):
    """The warning named SPACE's 1..60 for column_threshold where the search covered 1..45."""
    cams = tiny_cameras()
    bg, images, labels = synthetic_sequence(cams, 2, np.random.default_rng(2))
    write_render_dir(tmp_path / "tiny", cams, bg, images, labels)
    (tmp_path / "s.yaml").write_text("column_threshold: 0.5\n")
    assert camtask(["tune", str(tmp_path / "tiny"), "--trials", "1", "--params", str(tmp_path / "s.yaml"),
                    "--out", str(tmp_path / "t.yaml"), "--json"]) == 0
    assert capsys.readouterr().err.splitlines()[0].startswith(
        "warning: --params: column_threshold 0.5 is outside the searched range 1..45: ")


@pytest.mark.parametrize("trials", [0, -3])
def test_tune_refuses_fewer_than_one_trial(trials, monkeypatch):
    """No trial: no best parameters to return (and no F1 of the start)."""
    cams = tiny_cameras()
    bg, frames, _ = synthetic_sequence(cams, 1, np.random.default_rng(0))
    monkeypatch.setattr(pipeline.tuning, "scanline_f1", lambda *a: pytest.fail("a trial ran"))
    with pytest.raises(ValueError) as err:
        pipeline.tuning.tune(cams, bg, frames, np.zeros((1, 2, 64), bool), trials)
    assert str(err.value) == f"trials: expected an integer >= 1, got {trials}"


def _f1_by_hand(cams, params, bg, frames, gt):
    """Pooled scanline F1 of ``params``: 2 TP / (2 TP + FP + FN) over every frame, camera and column."""
    from pipeline import Pipeline

    pipe = Pipeline(cams, params, bg)
    pred = np.stack([pipe.process(f) for f in frames])
    tp, fp, fn = (pred & gt).sum(), (pred & ~gt).sum(), (~pred & gt).sum()
    return 2 * tp / (2 * tp + fp + fn)


def test_tune_returns_the_best_trial_and_the_f1_of_every_trial():
    from pipeline import Pipeline, PipelineParams

    cams = tiny_cameras()
    bg, frames, labels = synthetic_sequence(cams, 3, np.random.default_rng(0))
    gt = np.stack([Pipeline(cams, background=bg).ground_truth(x)[1] for x in labels])
    start = PipelineParams(column_threshold=3.0, median_kernel=1, opening_kernel=1)
    seen = []
    result = pipeline.tuning.tune(cams, bg, frames, gt, 4, seed=0, start=start, progress=seen.append)
    assert len(result.f1) == 4 and seen == result.f1.tolist()
    assert result.baseline_f1 == result.f1[0] == pytest.approx(_f1_by_hand(cams, start, bg, frames, gt), abs=1e-12)
    assert result.best_f1 == max(seen) > 0.9
    assert _f1_by_hand(cams, result.best, bg, frames, gt) == pytest.approx(result.best_f1, abs=1e-12)
    assert len(set(seen)) > 1                       # the trials after the start tried other parameters


def test_a_start_outside_the_space_raises_no_optuna_warning():
    """Optuna warns of a fixed parameter out of range, when the trial is queued and when it
    runs; the command's own warning line says it once, naming the option (docs/pipeline.md)."""
    import warnings

    from pipeline import PipelineParams

    cams = tiny_cameras()
    bg, frames, _ = synthetic_sequence(cams, 1, np.random.default_rng(0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = pipeline.tuning.tune(cams, bg, frames, np.zeros((1, 2, 64), bool), 2,
                                      start=PipelineParams(threshold_deg=45.0, column_threshold=0.5))
    assert [str(w.message) for w in caught] == []
    assert len(result.f1) == 2


def test_tune_logs_nothing_of_its_trials():
    """Optuna logs every trial at INFO ("Trial 0 finished with value ..."), a page of lines
    over the command's progress bar; tune keeps it to errors, whatever was set before."""
    import logging

    import optuna

    cams = tiny_cameras()
    bg, frames, _ = synthetic_sequence(cams, 1, np.random.default_rng(0))
    records = []
    handler = logging.Handler()
    handler.emit = records.append
    logger = logging.getLogger("optuna")
    before = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.INFO)
    logger.addHandler(handler)
    try:
        pipeline.tuning.tune(cams, bg, frames, np.zeros((1, 2, 64), bool), 2)
    finally:
        logger.removeHandler(handler)
        optuna.logging.set_verbosity(before)
    assert [r.getMessage() for r in records] == []


def test_a_trial_that_raises_is_not_logged(monkeypatch):
    """Optuna logs a failed trial at WARNING with its traceback ("Trial 1 failed ..."): the
    error is raised to the caller, who says it once."""
    import logging

    import optuna

    cams = tiny_cameras()
    bg, frames, _ = synthetic_sequence(cams, 1, np.random.default_rng(0))
    records, calls = [], []
    handler = logging.Handler()
    handler.emit = records.append
    logger = logging.getLogger("optuna")

    def scanline_f1(*args):
        calls.append(1)
        if len(calls) == 2:
            raise ValueError("a trial failed")
        return 0.5
    monkeypatch.setattr(pipeline.tuning, "scanline_f1", scanline_f1)
    before = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.INFO)
    logger.addHandler(handler)
    try:
        with pytest.raises(ValueError, match="^a trial failed$"):
            pipeline.tuning.tune(cams, bg, frames, np.zeros((1, 2, 64), bool), 3)
    finally:
        logger.removeHandler(handler)
        optuna.logging.set_verbosity(before)
    assert len(calls) == 2
    assert [r.getMessage() for r in records] == []


def test_the_search_space_is_the_one_documented():
    """pipeline.tuning.SPACE against the table of docs/pipeline.md."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "pipeline.md").read_text()
    table = text[text.index("The search covers (`pipeline.tuning.SPACE`):"):].split("\n\n")[1]
    documented = {}
    for row in table.splitlines()[2:]:
        names, values = row.strip("|").split("|")
        numbers = [float(x) for x in re.findall(r"\d+(?:\.\d+)?", values.split(", at most")[0])]  # not 46
        if "..." in values:
            entry = ("int", int(numbers[0]), int(numbers[-1]), int(numbers[1] - numbers[0]))
        else:
            entry = ("float", numbers[0], numbers[1])
        documented.update({name: entry for name in re.findall(r"`(\w+)`", names)})
    assert documented == pipeline.tuning.SPACE


@pytest.mark.parametrize("seed", [0, 2**32 - 1])
def test_the_seeds_the_command_accepts_seed_the_search(seed):
    """`tune --seed` takes 0..2**32 - 1 (NumPy's seeds): the largest seeds the search too,
    and the same seed gives the same trials."""
    from pipeline import Pipeline

    cams = tiny_cameras()
    bg, frames, labels = synthetic_sequence(cams, 1, np.random.default_rng(0))
    gt = np.stack([Pipeline(cams, background=bg).ground_truth(x)[1] for x in labels])
    runs = [pipeline.tuning.tune(cams, bg, frames, gt, 3, seed=seed) for _ in range(2)]
    assert runs[0].best == runs[1].best and len(runs[0].f1) == 3
    assert runs[0].f1.tolist() == runs[1].f1.tolist()


def _tried(monkeypatch, n_trials, seed, f1=lambda params: 0.5):
    """The parameters of each trial of tune on the tiny cameras, scored by ``f1``."""
    cams = tiny_cameras()
    bg, frames, _ = synthetic_sequence(cams, 1, np.random.default_rng(0))
    tried = []

    def scanline_f1(base, frames, gt, params):
        tried.append(params)
        return f1(params)
    monkeypatch.setattr(pipeline.tuning, "scanline_f1", scanline_f1)
    pipeline.tuning.tune(cams, bg, frames, np.zeros((1, 2, 64), bool), n_trials, seed=seed)
    return tried


def test_other_seeds_try_other_parameters(monkeypatch):
    """The start is the first trial whatever the seed; the seed draws the ones after it."""
    runs = {seed: _tried(monkeypatch, 3, seed) for seed in (0, 1, 2**32 - 1)}
    assert len({run[0] for run in runs.values()}) == 1
    assert len({tuple(run[1:]) for run in runs.values()}) == 3


def test_suggest_draws_from_the_whole_searched_range():
    """Each parameter drawn by a random sampler's trials stays in its searched range and
    reaches both of its ends: an integer takes them, a float comes within a fifth of the range."""
    import optuna

    space = pipeline.tuning.searched_space(tiny_cameras())
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    drawn = [pipeline.tuning.suggest(study.ask(), space) for _ in range(100)]
    for name, (kind, low, high, *_) in space.items():
        values = [getattr(p, name) for p in drawn]
        assert low <= min(values) and max(values) <= high, name
        reach = 0 if kind == "int" else (high - low) / 5
        assert min(values) <= low + reach and max(values) >= high - reach, (name, min(values), max(values))


def test_the_search_draws_near_the_best_trials(monkeypatch):
    """TPE: after the start and ten random trials, most trials are near the best F1 (here
    threshold_deg within 5 of 20); a random search over 1..30 puts about one in three there."""
    near = []
    for seed in (0, 1):
        tried = _tried(monkeypatch, 40, seed, lambda p: 1 - abs(p.threshold_deg - 20.0) / 30)
        near += [abs(p.threshold_deg - 20.0) < 5 for p in tried[11:]]
    assert np.mean(near) > 0.6, np.mean(near)


@pytest.mark.parametrize(("argv", "line"), [
    (["--trials", "0"], "--trials: expected an integer >= 1, got 0"),
    (["--trials", "-2"], "--trials: expected an integer >= 1, got -2"),
    (["--trials", "1", "--frames", "0"], "--frames: expected an integer >= 1, got 0"),
    (["--trials", "1", "--frames", "-1"], "--frames: expected an integer >= 1, got -1"),
])
def test_trials_or_frames_below_one_are_one_line_and_write_nothing(render_dir, tmp_path, capsys, no_work, argv, line):
    from testbed.cli import main

    capsys.readouterr()
    assert main(["tune", str(render_dir), *argv, "--out", str(tmp_path / "t.yaml"),
                 "--plot", str(tmp_path / "t.png")]) == 2
    assert capsys.readouterr().err.splitlines() == [f"camtask tune: error: {line}"]
    assert list(tmp_path.iterdir()) == []


def test_a_plot_that_is_not_a_png_is_refused_first(render_dir, tmp_path, capsys, no_work):
    from testbed.cli import main

    capsys.readouterr()
    assert main(["tune", str(render_dir), "--trials", "1", "--out", str(tmp_path / "t.yaml"),
                 "--plot", str(tmp_path / "t.jpg")]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"camtask tune: error: --plot: expected a .png file name, got '{tmp_path / 't.jpg'}'"]
    assert list(tmp_path.iterdir()) == []


def test_the_summary_counts_the_frames_tuned_on_and_the_bar_the_best_trial(render_dir, tmp_path, capsys,
                                                                           monkeypatch):
    """--frames 99 of a 3-frame directory tunes on 3; the progress bar's best is the best
    trial so far, not the last one."""
    import json

    from pipeline.tuning import TuneResult
    from testbed.cli import main

    def tune(cameras, background, frames, gt, trials, seed, start, progress):
        for f1 in (0.75, 0.5):
            progress(f1)
        return TuneResult(best=start, best_f1=0.75, baseline_f1=0.75, f1=[0.75, 0.5])
    monkeypatch.setattr(pipeline.tuning, "tune", tune)
    capsys.readouterr()
    assert main(["tune", str(render_dir), "--trials", "2", "--frames", "99", "--out", str(tmp_path / "t.yaml"),
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["frames"] == 3
    assert main(["tune", str(render_dir), "--trials", "2", "--out", str(tmp_path / "t.yaml")]) == 0
    bar = capsys.readouterr().err.replace("\r", "\n").splitlines()
    assert [x for x in bar if x.startswith("tune: 100%")][-1].endswith("best=0.7500, f1=0.5000]")
