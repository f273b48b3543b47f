"""Pipeline parameters: one frozen, validated dataclass, loadable from YAML.

Every error is one line naming the parameter and what was expected.

>>> p = PipelineParams()
>>> p.opening_kernel % 2
1
>>> PipelineParams.from_mapping({"median_kernel": 4})
Traceback (most recent call last):
...
ValueError: median_kernel: expected an odd integer in 1..8191, got 4
"""

from __future__ import annotations

import dataclasses
import numbers
import os
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import yaml

from scene import yamlio
from scene.checks import check_mapping, check_positive, read_input_text, shown

from .files import write_atomic

DEFAULT_PATH = Path(__file__).resolve().parent.parent / "assets" / "pipeline" / "default.yaml"
#: The widest filter, pixels: more than twice the width of a 4K (3840-pixel) image. Wider
#: ones change nothing an image could show, and would only take memory (a 10**5 opening
#: asked for 10 GB).
MAX_KERNEL = 8191


def check_odd_kernel(name: str, value: Any) -> int:
    """Return ``value`` as an odd integer in 1..``MAX_KERNEL`` (a filter size, pixels; NumPy
    integers too), else raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not 1 <= value <= MAX_KERNEL \
            or value % 2 == 0:
        raise ValueError(f"{name}: expected an odd integer in 1..{MAX_KERNEL}, got {shown(value)}")
    return int(value)


def check_range(name: str, value: Any, low: float, high: float, *, low_open=False, high_open=False) -> float:
    """Return ``value`` as a float in the interval ``low``..``high`` (open ends as asked)."""
    if isinstance(value, bool):
        raise ValueError(f"{name}: expected a number, got {value!r}")
    x = check_positive(name, value, allow_zero=True) if low >= 0 else float(value)
    if (x < low or (low_open and x == low)) or (x > high or (high_open and x == high)):
        lo, hi = ("(" if low_open else "["), (")" if high_open else "]")
        raise ValueError(f"{name}: expected a number in {lo}{low:g}, {high:g}{hi}, got {shown(value)}")
    return x


@dataclass(frozen=True)
class PipelineParams:
    """Parameters of the node-side pipeline (section 5.2.2 of the paper).

    threshold_deg : colour-angle threshold, degrees in (0, 90): a pixel is foreground when
        the angle between its RGB vector and the background's exceeds it
    brightness_floor : RGB-vector norm (0..441, 8-bit levels) below which the angle is
        meaningless; where the pixel's or the background's norm is below it, the pixel is
        foreground when the RGB difference norm exceeds ``dark_delta`` instead
    dark_delta : RGB difference norm, 8-bit levels, used below the brightness floor
    opening_kernel : side of the square structuring element of the opening, odd >= 1
        (1 = no opening)
    spatial_kernel : width of the box filter over the column sums, odd >= 1 (1 = none)
    temporal_alpha : weight of the new frame in the exponential smoothing of the column
        sums across frames, (0, 1] (1 = no temporal smoothing)
    median_kernel : width of the median filter over the scanline, odd >= 1 (1 = none)
    column_threshold : a column is occupied when its smoothed foreground count (pixels of
        the rectified mask) exceeds this, > 0
    """

    threshold_deg: float = 3.0
    brightness_floor: float = 25.0
    dark_delta: float = 40.0
    opening_kernel: int = 7
    spatial_kernel: int = 1
    temporal_alpha: float = 0.9
    median_kernel: int = 15
    column_threshold: float = 55.0

    def __post_init__(self):
        set_ = lambda k, v: object.__setattr__(self, k, v)
        set_("threshold_deg", check_range("threshold_deg", self.threshold_deg, 0, 90, low_open=True, high_open=True))
        set_("brightness_floor", check_range("brightness_floor", self.brightness_floor, 0, 442))
        set_("dark_delta", check_range("dark_delta", self.dark_delta, 0, 442))    # |RGB difference| <= 255 sqrt 3
        for name in ("opening_kernel", "spatial_kernel", "median_kernel"):
            set_(name, check_odd_kernel(name, getattr(self, name)))
        set_("temporal_alpha", check_range("temporal_alpha", self.temporal_alpha, 0, 1, low_open=True))
        set_("column_threshold", check_positive("column_threshold", self.column_threshold))

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any] | None) -> PipelineParams:
        """Parameters from a mapping; unknown keys raise, missing keys take the defaults."""
        if values is None:
            values = {}
        check_mapping("pipeline parameters", values, [f.name for f in fields(cls)])
        return cls(**dict(values))

    @classmethod
    def from_yaml(cls, path: str | os.PathLike, name: str = "params") -> PipelineParams:
        """Parameters from a YAML file (a mapping at top level, or under a ``pipeline`` key);
        an error names ``name`` (a command passes its option, ``--params``), then the file."""
        text = read_input_text(name, path)
        try:
            data = yamlio.load(text)
        except yaml.YAMLError as exc:
            raise ValueError(f"{name}: {path} is not valid YAML ({yamlio.error_text(exc, text)})") from None
        if isinstance(data, Mapping) and set(data) == {"pipeline"}:
            data = data["pipeline"]
        if data is not None and not isinstance(data, Mapping):        # empty: the defaults
            raise ValueError(f"{name}: {str(path)!r}: expected a mapping of pipeline parameters "
                             f"(key: value lines), got {type(data).__name__}")
        try:
            return cls.from_mapping(data)
        except ValueError as exc:               # name the file: a bad value would not say where it is
            raise ValueError(f"{name}: {str(path)!r}: {exc}") from None

    def to_dict(self) -> dict:
        """Plain dict of the parameters (YAML/JSON friendly)."""
        return dataclasses.asdict(self)

    def replace(self, **changes) -> PipelineParams:
        """A copy with ``changes`` applied (validated)."""
        return dataclasses.replace(self, **changes)

    def to_yaml(self, path: str | os.PathLike, comment: str = "") -> None:
        """Write the parameters as YAML, atomically (temp file + os.replace)."""
        text = "".join(f"# {line}\n" for line in comment.splitlines()) + yaml.safe_dump(
            self.to_dict(), sort_keys=False)
        write_atomic(path, text.encode())


def params_option(path: str | os.PathLike | None) -> str:
    """How a command's error names the parameters it runs with: ``--params`` when ``path``
    was given, else the default file it falls back on (an error about a default value said
    ``--params`` to a user who had given none).

    >>> params_option(None)
    '--params (not given: the default assets/pipeline/default.yaml)'
    """
    if path is not None:
        return "--params"
    return f"--params (not given: the default {DEFAULT_PATH.relative_to(DEFAULT_PATH.parents[2]).as_posix()})"


def load_params(path: str | os.PathLike | None = None, name: str = "params") -> PipelineParams:
    """Parameters from ``path``, or the defaults in ``assets/pipeline/default.yaml``; an
    error names ``name`` (the option that gave ``path``, e.g. ``--params``)."""
    return PipelineParams.from_yaml(DEFAULT_PATH if path is None else path, name)
