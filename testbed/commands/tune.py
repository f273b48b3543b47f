"""``camtask tune``: search the pipeline parameters for the best scanline F1 (Optuna TPE).

    camtask tune DIR --trials N [--out params.yaml] [--seed S] [--plot FILE.png] [--frames N]
                     [--params FILE] [--json]

The first trial is the starting parameters (``--params``, default the defaults); the best
are written as YAML (default DIR/tuned_params.yaml; ``--out`` is required for an episode
of a dataset written by ``camtask render``), atomically. DIR is a render directory, or a
dataset of one episode. Same data, same seed, same result.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from testbed.commands import plain_help


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("tune", help="tune pipeline parameters for scanline F1 (Optuna)",
                              description=plain_help(__doc__), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dir", metavar="DIR", help="render directory (from `camtask render`), or a dataset of one episode")
    p.add_argument("--trials", type=int, required=True, help="number of Optuna trials")
    p.add_argument("--seed", type=int, default=0, help="sampler seed (default 0)")
    p.add_argument("--out", metavar="FILE", help="best parameters YAML (default DIR/tuned_params.yaml; "
                                 "required for an episode of a dataset)")
    p.add_argument("--plot", metavar="FILE.png", help="PNG of F1 per trial and best so far")
    p.add_argument("--params", metavar="FILE", help="starting parameters YAML (default assets/pipeline/default.yaml)")
    p.add_argument("--frames", metavar="N", type=int, default=30, help="use at most this many frames (default 30)")
    p.add_argument("--json", action="store_true", help="print the result as one JSON document")
    p.set_defaults(func=run)


def run(args) -> int:
    from pipeline.core import Pipeline
    from pipeline.files import write_atomic
    from pipeline.io import RenderDir
    from pipeline.params import load_params, params_option
    from pipeline.rectify import check_column_threshold
    from pipeline.tuning import outside_space, searched_space, tune
    from testbed.cli import check_seed
    from testbed.commands.scanlines import default_output, episode_dir
    from testbed.output import check_output_file

    if args.trials < 1:
        raise ValueError(f"--trials: expected an integer >= 1, got {args.trials}")
    if args.frames < 1:
        raise ValueError(f"--frames: expected an integer >= 1, got {args.frames}")
    check_seed(args.seed)
    if args.plot is not None:
        check_output_file("--plot", args.plot, ".png")
    start = load_params(args.params, "--params")
    render = RenderDir(episode_dir(Path(args.dir)))
    # as scanlines refuses it: a start no other command runs, and the best if no trial beats it
    check_column_threshold(start.column_threshold, render.cameras, params_option(args.params))
    for name, (value, low, high) in outside_space(start, searched_space(render.cameras)).items():
        print(f"warning: --params: {name} {value:g} is outside the searched range {low:g}..{high:g}: the first "
              "trial uses it, the others search the range (docs/pipeline.md)", file=sys.stderr)
    out = check_output_file("--out", args.out) if args.out is not None else \
        default_output(render.root, "tuned_params.yaml")
    if args.plot is not None and Path(args.plot).resolve() == out.resolve():
        raise ValueError(f"--out and --plot: both name {out}; expected two files")
    n = min(args.frames, len(render))
    check_memory(render.cameras, n, args.trials)
    render.check_complete(n)
    background = render.background()
    pipe = Pipeline(render.cameras, start)
    frames, gt = None, []
    with tqdm(total=n, desc="tune: read", unit="frame", file=sys.stderr, disable=args.json) as bar:
        for i in range(n):                  # filled in place: a stack of a list held them twice
            f = render.frames(i)
            if frames is None:
                frames = np.empty((n, *f.shape), f.dtype)
            frames[i] = f
            gt.append(pipe.ground_truth(render.labels(i))[1])
            bar.update()
    render.close()                          # a video episode's decoders (~60 MB each) idle through the trials
    gt = np.stack(gt)
    if not gt.any():
        print(f"warning: nobody is in view in the {n} frame{'s' * (n != 1)} tuned on (no column of a true scanline "
              "is occupied): F1 is 1 only where nothing is detected, so the search favours parameters that "
              "detect nothing; tune on frames with people in view (--frames, or another render)", file=sys.stderr)
    with tqdm(total=args.trials, desc="tune", unit="trial", file=sys.stderr, disable=args.json) as bar:
        best = [0.0]

        def progress(f1):
            best[0] = max(best[0], f1)
            bar.set_postfix(f1=f"{f1:.4f}", best=f"{best[0]:.4f}")
            bar.update()

        result = tune(render.cameras, background, frames, gt, args.trials, args.seed, start, progress)
    # drawn before either file is written (~1.5 s): a Ctrl-C then leaves both as they were
    png = history_png(result.f1) if args.plot is not None else None
    result.best.to_yaml(out, comment=(
        f"Tuned by `camtask tune {args.dir} --trials {args.trials} --seed {args.seed} --frames {n}"
        + (f" --params {args.params}" if args.params else "") + "`:\n"
        f"scanline F1 {result.best_f1:.4f} (starting parameters {result.baseline_f1:.4f})"))
    if png is not None:
        write_atomic(args.plot, png)
    summary = {"best_f1": result.best_f1, "start_f1": result.baseline_f1, "trials": args.trials,
               "seed": args.seed, "frames": n, "params": result.best.to_dict(), "out": str(out)}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"best scanline F1 {result.best_f1:.4f} (start {result.baseline_f1:.4f}) -> {out}")
        for k, v in result.best.to_dict().items():
            print(f"  {k}: {v:.4g}" if isinstance(v, float) else f"  {k}: {v}")
    return 0


#: Memory an Optuna trial holds until the search ends, bytes: the process grew by 32 MB
#: over 2000 trials of this search space (in-memory study, TPE sampler).
TRIAL_BYTES = 16_000


def check_memory(cameras, frames: int, trials: int) -> None:
    """Refuse, in one line before any frame is read, ``frames`` frames of ``cameras`` (held
    in memory for every trial) or ``trials`` trials (Optuna keeps each) that the memory
    available now cannot hold."""
    from testbed.memory import check_fits

    per_frame = sum(c.width * c.height * 3 + c.width for c in cameras)     # RGB, true scanline
    check_fits("--frames", frames, "frames", per_frame, "for the search (every trial runs on all of them)")
    check_fits("--trials", trials, "trials", TRIAL_BYTES, "(Optuna keeps every trial)", reserved=frames * per_frame,
               beside=" beside the frames")


#: The plot's F1 axis runs over this range at most (a logit scale: 0 and 1 are infinitely
#: far); trials outside it are drawn at its edge, with their own marker.
PLOT_RANGE = (0.01, 0.99999)


def history_png(f1) -> bytes:
    """F1 per trial and best so far (:func:`history_figure`) as PNG bytes."""
    from testbed.output import figure_png

    return figure_png(history_figure(f1), dpi=100)


def history_figure(f1):
    """The figure of :func:`history_png`. F1 is drawn on a logit scale (0.9, 0.99, 0.999
    equally spaced): a search near F1 1 shows its gains (0.997 to 0.999 is a third of the
    errors), which a linear axis from the worst trial to 1 flattened into one line."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, NullFormatter

    from testbed.output import count_axis

    f1 = np.asarray(f1, float)
    low, high = PLOT_RANGE
    shown = np.clip(f1, low, high)
    trials = np.arange(1, len(f1) + 1)
    best = np.maximum.accumulate(f1)
    fig, ax = plt.subplots(figsize=(7.5, 3.8), dpi=100)
    ax.set_yscale("logit")
    inside = (f1 >= low) & (f1 <= high)
    ax.plot(trials[inside], f1[inside], "o", ms=3, alpha=0.6, color="C0", label="trial")
    for mask, marker, text in ((f1 < low, "v", f"trial, F1 below {low:g}"),
                               (f1 > high, "^", f"trial, F1 above {high:g}")):
        if mask.any():
            ax.plot(trials[mask], shown[mask], marker, ms=4, color="C0", label=text)
    ax.plot(trials, np.clip(best, low, high), "-", lw=1.5, color="C1", drawstyle="steps-post", label="best so far")
    ax.plot(trials[:1], shown[:1], "*", ms=10, color="C3", label="start (first trial)")
    k = int(np.argmax(f1))
    ax.set_title(f"best scanline F1 {f1[k]:.4f} (trial {k + 1} of {len(f1)}); start {f1[0]:.4f}", fontsize=10)
    lo, hi = (np.log(x / (1 - x)) for x in (shown.min(), shown.max()))
    pad = max(0.05 * (hi - lo), 0.2)
    ax.set_ylim(*(1 / (1 + np.exp(-y)) for y in (lo - pad, hi + pad)))
    count_axis(ax.xaxis)                    # trials: one trial's axis had fallen back to 0.945, 0.96, ...
    ax.yaxis.set_major_formatter(FuncFormatter(_decimal))
    shown_major = [y for y in ax.get_yticks() if ax.get_ylim()[0] <= y <= ax.get_ylim()[1]]
    # fewer than two labelled lines within one decade of errors: label the ones between too
    ax.yaxis.set_minor_formatter(FuncFormatter(_decimal) if len(shown_major) < 2 else NullFormatter())
    ax.set_xlabel("trial")
    ax.set_ylabel("scanline F1 (logit scale)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)    # beside: never over a trial
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    return fig


def _decimal(y: float, _=None) -> str:
    """An F1 tick as a decimal with the digits its distance from 0 or 1 needs.

    >>> [_decimal(y) for y in (0.5, 0.9, 0.97, 0.998, 0.9985, 1 - 2e-5, 0.02)]
    ['0.5', '0.9', '0.97', '0.998', '0.9985', '0.99998', '0.02']
    """
    if not 0 < y < 1:
        return ""
    m = min(y, 1 - y)
    digits = next(d for d in range(1, 17) if abs(round(y, d) - y) <= 1e-6 * m)
    return f"{y:.{digits}f}"
