"""Small validators used at every boundary of the package.

Each ``check_*`` converts its input, checks shape and range, and raises
``ValueError`` naming the parameter and what was expected. They never ``assert``.

>>> check_positive("radius", 0.25)
0.25
>>> check_choice("backend", "egl", ("egl", "osmesa"))
'egl'
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np


def check_choice(name: str, value: Any, valid: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``valid``, else raise listing the valid values."""
    valid = tuple(valid)
    if value not in valid:
        raise ValueError(f"{name}: unknown value {shown(value)}; expected one of {', '.join(valid)}")
    return value


def used_or_refused(name: str, value: Any, used: bool, what: str, why: str) -> bool:
    """Whether option ``name`` is ``used`` by the run; a ``value`` given (not None) where it
    is not is refused in one line, ``name: what; why`` (silently unused, it was recorded as
    the run's own). The caller records None for an unused option left out."""
    if not used and value is not None:
        raise ValueError(f"{name}: {what}; {why}")
    return used


def check_input_file(name: str, path: str | os.PathLike) -> Path:
    """``path`` as a Path if it is a regular file to read, else a one-line error.

    FileNotFoundError when nothing is there; ValueError for a folder or a device.
    """
    path = Path(path)
    if path.is_file():
        return path
    if path.is_dir():
        raise ValueError(f"{name}: {str(path)!r} is a folder, not a file")
    if path.exists():
        raise ValueError(f"{name}: {str(path)!r} is not a regular file")
    raise FileNotFoundError(f"{name}: no such file {str(path)!r}")


def read_input_text(name: str, path: str | os.PathLike) -> str:
    """The UTF-8 text of the file at ``path`` (:func:`check_input_file`); a one-line
    ValueError naming the file and the first byte that is not UTF-8."""
    path = check_input_file(name, path)
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{name}: {str(path)!r} is not UTF-8 text (byte {exc.object[exc.start]:#04x} at "
                         f"offset {exc.start})") from None


def shown(value: Any) -> str:
    """``value`` as an error message shows it: its repr, but an integer of more than 16
    digits (YAML reads ``1000...0`` as one, however long) in six significant digits.

    >>> shown(10**400), shown(-123456789012345678901), shown(1e300), shown("49")
    ('1e+400', '-1.23457e+20', '1e+300', "'49'")
    """
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**16:
        return format(Decimal(value).normalize(), ".6g")
    return repr(value)


def names(paths: list[str], most: int = 3) -> str:
    """``a, b, c`` or ``a, b, c and 4 more``, for one-line messages.

    >>> names(["a", "b"]), names(list("abcde"))
    ('a, b', 'a, b, c and 2 more')
    """
    shown = ", ".join(paths[:most])
    return shown if len(paths) <= most else f"{shown} and {len(paths) - most} more"


def _number(name: str, value: Any) -> float:
    """``value`` as a float; booleans and strings are not numbers here. An integer beyond
    the float range is an infinity (refused as not finite, by the checks that need it)."""
    if isinstance(value, (bool, str, bytes)):
        raise ValueError(f"{name}: expected a number, got {shown(value)}")
    try:
        return float(value)
    except OverflowError:
        return float("inf") if value > 0 else float("-inf")
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {shown(value)}") from None


def check_finite(name: str, value: Any) -> float:
    """Return ``value`` as a finite float.

    >>> check_finite("yaw_deg", -45)
    -45.0
    """
    x = _number(name, value)
    if not np.isfinite(x):
        raise ValueError(f"{name}: expected a finite number, got {shown(value)}")
    return x


def check_positive(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """Return ``value`` as a finite float > 0 (or >= 0 with ``allow_zero``)."""
    x = _number(name, value)
    if not np.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name}: expected a finite number {bound}, got {shown(value)}")
    return x


def check_between(name: str, value: Any, low: float, high: float, unit: str, *, low_open: bool = False) -> float:
    """``value`` as a finite float > ``low`` (``low_open``) or >= ``low``, and at most ``high``, else
    a one-line ValueError naming ``name``, the range and ``unit``.

    >>> check_between("frame_rate", 1e-300, 1e-3, 1000, "Hz")
    Traceback (most recent call last):
    ...
    ValueError: frame_rate: expected a finite number >= 0.001 and at most 1000 Hz, got 1e-300
    """
    x = _number(name, value)
    if not (np.isfinite(x) and low <= x <= high) or (low_open and x == low):
        most = f" and at most {high:g}" if np.isfinite(high) else ""
        raise ValueError(f"{name}: expected a finite number {'>' if low_open else '>='} {low:g}{most} {unit}, "
                         f"got {shown(value)}")
    return x


def check_int(name: str, value: Any, *, minimum: int | None = None) -> int:
    """Return ``value`` as an int, optionally at least ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name}: expected an integer, got {shown(value)}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {shown(int(value))}")
    return int(value)


def check_array(name: str, value: Any, shape: tuple[int | None, ...], *, dtype=float) -> np.ndarray:
    """Return ``value`` as a finite array of ``shape`` (``None`` matches any length).

    >>> check_array("xy", [[1, 2]], (None, 2)).shape
    (1, 2)
    >>> check_array("xy", [["5", 4]], (None, 2))
    Traceback (most recent call last):
    ...
    ValueError: xy: expected numbers of shape (n, 2), got '5'
    """
    odd = _not_a_number(value)
    if odd is not None:                         # "5" and true would convert without a word
        raise ValueError(f"{name}: expected numbers of shape {_shape_text(shape)}, got {odd!r}")
    try:
        arr = np.asarray(value, dtype=dtype)
    except OverflowError:                       # an integer of more than 308 digits
        raise ValueError(f"{name}: expected finite numbers, got one beyond the float range") from None
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected numbers of shape {_shape_text(shape)}") from None
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        raise ValueError(
            f"{name}: expected shape {_shape_text(shape)}, got {tuple(arr.shape)}"
        )
    if np.issubdtype(arr.dtype, np.floating) and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected finite numbers, got NaN or infinity")
    return arr


def _not_a_number(value: Any):
    """The first boolean or string in nested lists (or an array of such), else None."""
    if isinstance(value, np.ndarray):
        return None if value.dtype.kind in "iuf" else _not_a_number(value.ravel().tolist())
    if isinstance(value, (list, tuple)):
        return next((odd for odd in map(_not_a_number, value) if odd is not None), None)
    return value if isinstance(value, (bool, np.bool_, str, bytes)) else None


def check_mapping(name: str, value: Any, allowed: Iterable[str], required: Iterable[str] = ()) -> Mapping:
    """Return ``value`` if it is a mapping with only ``allowed`` keys and all ``required``."""
    if not isinstance(value, Mapping):
        raise ValueError(f"{name}: expected a mapping, got {type(value).__name__}")
    allowed = tuple(allowed)
    unknown = [k for k in value if k not in allowed]
    if unknown:
        raise ValueError(
            f"{name}: unknown key {unknown[0]!r}; expected keys among {', '.join(allowed)}"
        )
    missing = [k for k in required if k not in value]
    if missing:
        raise ValueError(f"{name}: missing key {missing[0]!r}")
    return value


def _shape_text(shape: tuple[int | None, ...]) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def readonly(arr: np.ndarray) -> np.ndarray:
    """Return a read-only copy of ``arr`` (for frozen values)."""
    out = np.array(arr, copy=True)
    out.setflags(write=False)
    return out
