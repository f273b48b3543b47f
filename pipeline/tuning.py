"""Search the pipeline parameters with Optuna to maximise scanline F1 (TPE, seeded).

The objective is deterministic, and the sampler is ``TPESampler(seed=seed)`` run in one
process, so the same data and seed give the same trials and the same best parameters.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .core import Pipeline
from .params import PipelineParams
from .runs import scanline_f1

#: Search space: name -> (kind, low, high[, step]).
SPACE = {
    "threshold_deg": ("float", 1.0, 30.0),
    "brightness_floor": ("float", 0.0, 80.0),
    "dark_delta": ("float", 5.0, 120.0),
    "opening_kernel": ("int", 1, 9, 2),
    "spatial_kernel": ("int", 1, 15, 2),
    "temporal_alpha": ("float", 0.3, 1.0),
    "median_kernel": ("int", 1, 15, 2),
    "column_threshold": ("float", 1.0, 60.0),
}


def outside_space(params: PipelineParams, space: dict | None = None) -> dict[str, tuple]:
    """The parameters of ``params`` that ``space`` (default :data:`SPACE`; the search's is
    :func:`searched_space`) does not reach: name -> (value, low, high). The first trial
    still uses them; the search never comes back to them.

    >>> outside_space(PipelineParams(threshold_deg=45.0, opening_kernel=11))
    {'threshold_deg': (45.0, 1.0, 30.0), 'opening_kernel': (11, 1, 9)}
    """
    return {name: (getattr(params, name), low, high) for name, (_, low, high, *_) in (space or SPACE).items()
            if not low <= getattr(params, name) <= high}


@dataclass(frozen=True)
class TuneResult:
    """best : PipelineParams; best_f1 : float; baseline_f1 : F1 of the starting parameters;
    f1 : (n_trials,) float, F1 of each trial in order."""

    best: PipelineParams
    best_f1: float
    baseline_f1: float
    f1: np.ndarray


def searched_space(cameras) -> dict[str, tuple]:
    """:data:`SPACE` for ``cameras``: ``column_threshold`` at most one below the rows of their
    rectified columns (a column is occupied when its count exceeds the threshold: from the
    rows on, every scanline is empty, a file ``scanlines`` refuses); half a row for columns
    of one row.

    >>> from scene import load_scene
    >>> searched_space(load_scene("lab").cameras)["column_threshold"]
    ('float', 1.0, 60.0)
    """
    from .rectify import level_cameras

    kind, low, high = SPACE["column_threshold"]
    rows = level_cameras(cameras)[1]
    top = float(min(high, rows - 1)) if rows >= 2 else rows / 2
    return {**SPACE, "column_threshold": (kind, min(low, top), top)}


def suggest(trial, space: dict | None = None) -> PipelineParams:
    """Parameters drawn by an Optuna trial from ``space`` (default :data:`SPACE`)."""
    values = {}
    for name, (kind, low, high, *step) in (SPACE if space is None else space).items():
        if kind == "int":
            values[name] = trial.suggest_int(name, low, high, step=step[0])
        else:
            values[name] = trial.suggest_float(name, low, high)
    return PipelineParams(**values)


def tune(cameras, background, frames, gt_scanlines, n_trials: int, seed: int = 0,
         start: PipelineParams | None = None, progress: Callable[[float], None] | None = None) -> TuneResult:
    """Maximise scanline F1 over ``n_trials`` Optuna trials, the first being ``start``.

    background : (n_cams, H, W, 3) uint8 or float32 model
    frames : (n_frames, n_cams, H, W, 3) uint8; gt_scanlines : (n_frames, n_cams, W) bool
    progress : called with each trial's F1
    """
    import optuna

    if n_trials < 1:
        raise ValueError(f"trials: expected an integer >= 1, got {n_trials}")
    start = PipelineParams() if start is None else start
    # not WARNING: Optuna logs a trial that raised with its traceback ("Trial 12 failed ..."),
    # a page on every Ctrl-C; the error itself is re-raised here either way
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    base = Pipeline(cameras, start, background)   # maps and background serve every trial
    space = searched_space(cameras)
    study = optuna.create_study(direction="maximize", sampler=optuna.samplers.TPESampler(seed=seed))
    with warnings.catch_warnings():        # a start outside SPACE: see outside_space
        warnings.filterwarnings("ignore", message="Fixed parameter .* is out of range", category=UserWarning)
        study.enqueue_trial({k: getattr(start, k) for k in SPACE})
    f1s = []

    def objective(trial):
        f1 = scanline_f1(base, frames, gt_scanlines, suggest(trial, space))
        f1s.append(f1)
        if progress is not None:
            progress(f1)
        return f1

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Fixed parameter .* is out of range", category=UserWarning)
        study.optimize(objective, n_trials=n_trials)
    best = PipelineParams(**study.best_params)
    return TuneResult(best, float(study.best_value), f1s[0], np.array(f1s))
