"""``camtask study NAME``: reproduce the paper's simulation figures.

Prints a table (or one JSON document with ``--json``), optionally draws the figure to
``--plot FILE.png``, shows a progress bar on stderr, and runs trials on Dask: a local
cluster of ``--workers`` processes (``0``: in this process) or ``--scheduler ADDRESS``.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import sys
import time

from testbed.cli import check_seed
from testbed.commands import plain_help
from testbed.output import check_output_file
from testbed.parallel import default_workers, open_client, run_tasks, wait_for_a_worker

STUDY_HELP = {
    "cameras": "residual vs number of cameras and objects (paper figs 5, 6)",
    "static": "taskers on static objects (paper fig 8)",
    "moving": "taskers on walking objects, update rates (paper figs 9, 10)",
    "lab": "taskers on the rendered lab (or --scene), normalised by all its cameras (paper fig 13)",
    "tracking": "tracking with tasked vs uniform cameras (paper section 6, fig 14)",
}


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("study", help="reproduce the paper's simulation figures",
                              description=plain_help(__doc__))
    sub = p.add_subparsers(dest="study", metavar="NAME", required=True)
    for name, text in STUDY_HELP.items():
        sp = sub.add_parser(name, help=text, description=text)
        _module(name).add_arguments(sp)
        g = sp.add_argument_group("common options")
        trials = getattr(_module(name), "DEFAULT_TRIALS", 500)
        g.add_argument("--trials", type=int, default=trials,
                       help=f"trials per setting (default {trials}" + (", as the paper)" if trials == 500 else ")"))
        g.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
        g.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
        g.add_argument("--plot", metavar="FILE.png", help="draw the paper's figure to this PNG")
        g.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
        x = g.add_mutually_exclusive_group()
        x.add_argument("--workers", type=int, default=None,
                       help=f"local Dask worker processes (default: cores = {default_workers()}; 0 = in-process)")
        x.add_argument("--scheduler", metavar="ADDRESS", help="use an existing Dask scheduler, e.g. tcp://host:8786")
        sp.set_defaults(func=run)


def _module(name: str):
    return importlib.import_module(f"testbed.studies.{name}")


#: The most trials per setting (200 times the paper's 500): every trial is a task argument
#: before the first runs, and ``--trials 10**12`` had the machine kill the run.
MAX_TRIALS = 100_000


def local_workers(workers: int | None, tasks: int) -> int | None:
    """The local worker processes to start for ``tasks`` tasks: never more than the tasks
    (one more would only start up), and one task in this process (as ``camtask render``
    does for episodes). ``workers``: ``--workers``, None for one per core.

    >>> local_workers(None, 1), local_workers(8, 3), local_workers(1, 5), local_workers(0, 9)
    (0, 3, 1, 0)
    """
    if workers is None:
        workers = min(default_workers(), tasks)
        return 0 if workers == 1 else workers
    return 0 if workers and tasks <= 1 else min(workers, tasks)


def run(args) -> int:
    mod = _module(args.study)
    if not 1 <= args.trials <= MAX_TRIALS:
        raise ValueError(f"--trials: expected an integer >= 1 and at most {MAX_TRIALS}, got {args.trials}")
    check_seed(args.seed)
    if args.workers is not None and args.workers < 0:
        raise ValueError(f"--workers: expected an integer >= 0, got {args.workers}")
    if args.plot is not None:
        check_output_file("--plot", args.plot, ".png")
    opts = mod.parse(args)
    from testbed.studies.core import TASKING_BACKEND

    t0 = time.perf_counter()
    used = {"workers": 0}
    with contextlib.ExitStack() as stack:
        clients: list = []

        def runner(func, tasks, weights, desc):
            tasks = list(tasks)
            if not clients:      # the cluster starts once the study knows how many tasks it has
                client = stack.enter_context(open_client(
                    local_workers(args.workers, len(tasks)) if args.scheduler is None else None, args.scheduler))
                clients.append(client)
                if args.scheduler is not None:
                    wait_for_a_worker(client, args.scheduler)
                used["workers"] = 0 if client is None else len(client.scheduler_info().get("workers", {}))
            return run_tasks(func, tasks, client=clients[0], workers=0, progress=not args.no_progress,
                             desc=desc, weights=weights)

        result = mod.run(opts, args.trials, args.seed, runner)
    elapsed = time.perf_counter() - t0
    workers = used["workers"]
    result["meta"] = {
        "study": args.study, "seed": args.seed, "trials": args.trials,
        "arguments": {k: v for k, v in opts.items()},
        "workers": workers, "scheduler": args.scheduler, "elapsed_s": round(elapsed, 3),
        "tasking_backend": TASKING_BACKEND,
        "command": "camtask " + " ".join(sys.argv[1:]) if sys.argv and "camtask" in sys.argv[0] else None,
    }
    # the results first: a figure that cannot be drawn loses no hour of trials
    if args.json:
        json.dump(result, sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(mod.format_table(result))
    sys.stdout.flush()
    if args.plot is not None:
        mod.plot(result, args.plot)
    if not args.json:
        print(f"\n{args.study}: {args.trials} trials, seed {args.seed}, {elapsed:.1f} s"
              + (f", plot {args.plot}" if args.plot is not None else ""))
    return 0
