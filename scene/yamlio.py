"""YAML as people write numbers: ``1e-3`` and ``5E1`` are floats.

PyYAML follows YAML 1.1, whose floats need a dot and a signed exponent, so it reads
``1e-3`` (a float in YAML 1.2 and in every programming language) as the string
``"1e-3"``. :class:`Loader` is PyYAML's safe loader (its libyaml binding when present)
with one more implicit float rule for exponents without a dot or a sign; nothing that
YAML 1.1 reads as a number reads otherwise.

>>> load("a: 1e-3\\nb: 5E1\\nc: 10\\nd: 1.5\\ne: '2e3'\\nf: 1.0e3")
{'a': 0.001, 'b': 50.0, 'c': 10, 'd': 1.5, 'e': '2e3', 'f': 1000.0}
"""

from __future__ import annotations

import re

import yaml


class Loader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """The safe loader, with YAML 1.2's exponent floats (``1e-3``, ``5E1``, ``1.0e3``), that
    refuses a key given twice in one mapping (YAML requires unique keys; PyYAML keeps the last)."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = set()
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":      # ``<<: *anchor`` may be overridden
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    duplicate = key in seen
                except TypeError:                                   # unhashable: PyYAML's own error
                    break
                if duplicate:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {key!r}", key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep)

    def construct_yaml_int(self, node):
        """An integer; one too long for Python to read (more than ``sys.get_int_max_str_digits()``
        digits, whose ValueError named no file or line) is a YAML error at its line and column."""
        try:
            return super().construct_yaml_int(node)
        except ValueError:
            raise yaml.constructor.ConstructorError(
                None, None, f"an integer of {len(node.value)} characters is too long to read",
                node.start_mark) from None


Loader.add_constructor("tag:yaml.org,2002:int", Loader.construct_yaml_int)

Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


def load(text: str):
    """The document in ``text``, as :class:`Loader` reads it (raises yaml.YAMLError)."""
    return yaml.load(text, Loader=Loader)


def error_text(exc: yaml.YAMLError, text: str | None = None) -> str:
    """One line for a YAML error: what is wrong and where (its first line alone, e.g.
    "while parsing a block mapping", says neither). A reader's error (a control character)
    gives a character offset into ``text``, the document it read: its line and column.

    >>> try:
    ...     load("a: 1\\nb: \\x07")
    ... except yaml.YAMLError as exc:
    ...     print(error_text(exc, "a: 1\\nb: \\x07"))
    unacceptable character #x0007: control characters are not allowed at line 2, column 4
    """
    problem = getattr(exc, "problem", None)
    mark = getattr(exc, "problem_mark", None)
    if problem is None:
        first = str(exc).splitlines()[0]
        at = getattr(exc, "position", None)
        if text is None or not isinstance(at, int) or not 0 <= at <= len(text):
            return first
        before = text[:at]
        line, column = before.count("\n") + 1, at - before.rfind("\n")
        return first + f" at line {line}, column {column}"
    return problem + ("" if mark is None else f" at line {mark.line + 1}, column {mark.column + 1}")
