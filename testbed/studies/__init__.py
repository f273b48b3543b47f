"""Studies that reproduce the paper's simulation figures (``camtask study NAME``).

Each study module exposes ``add_arguments(parser)``, ``parse(args) -> dict``,
``run(opts, trials, seed, runner) -> {"records": [...], ...}``, ``format_table(result)``
and ``plot(result, path)``. Options that several studies take (``--objects``, ``--k``,
``--taskers``, ``--radius``, ...) are declared and checked once, in :mod:`.core`; those of
every study (``--trials``, ``--seed``, ``--json``, ``--plot``, ``--workers``, ...) in
:mod:`testbed.commands.study`. ``runner(func, tasks, weights, desc)`` maps a module-level
function over argument tuples (see :mod:`testbed.parallel`); ``weights`` are the trials of
each task, which the progress bar counts. ``format_table`` and ``plot`` get the result with
its ``meta``: ``seed``, ``trials`` and ``arguments``, the dict ``parse`` returned.
"""
