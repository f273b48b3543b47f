"""Studies that reproduce the paper's simulation figures (``camtask study NAME``).

Each study module exposes ``add_arguments(parser)``, ``parse(args) -> dict``,
``run(opts, trials, seed, runner) -> {"records": [...], ...}``, ``format_table(result)``
and ``plot(result, path)``. ``runner(func, tasks, weights, desc)`` maps a module-level
function over argument tuples (see :mod:`testbed.parallel`).
"""

