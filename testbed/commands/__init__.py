"""The ``camtask`` subcommands, one module each (see :mod:`testbed.cli`)."""

from __future__ import annotations

import re

__all__ = ["plain_help"]


def plain_help(doc: str) -> str:
    """A module docstring as ``--help`` text: reST roles and double backquotes dropped.

    >>> plain_help("``camtask verify DIR``: see :mod:`testbed.wildtrack` and :func:`f`.")
    'camtask verify DIR: see testbed.wildtrack and f.'
    """
    text = re.sub(r":(?:mod|func|class|meth|attr|data):`~?([^`]+)`", r"\1", doc)
    return text.replace("``", "")
