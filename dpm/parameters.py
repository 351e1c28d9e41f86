"""Declared parameters with ranges, and the validation every object-layer class uses.

A class declares ``parameters = {name: Parameter(...)}``; :func:`validate` checks a
keyword dictionary against it and raises one :class:`ParameterError` that lists every
problem: unknown names (with the allowed ones), missing required values, values outside
their range, NaN.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ParameterError

REQUIRED = object()


@dataclass(frozen=True)
class Parameter:
    """One scalar (or per-item array) parameter.

    ``low``/``high`` bound the value; ``low_open``/``high_open`` make the bound exclusive.
    ``array`` allows a 1-D array of values (e.g. one radius per particle).
    """

    default: Any = REQUIRED
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    unit: str = ""
    doc: str = ""
    array: bool = False
    kind: str = "float"  # "float", "int", "str", "vector", "bool", "any"

    def interval(self) -> str:
        lo = "(" if self.low_open or self.low == -math.inf else "["
        hi = ")" if self.high_open or self.high == math.inf else "]"
        return f"{lo}{_fmt(self.low)}, {_fmt(self.high)}{hi}"

    def problems(self, name: str, value: Any) -> list[str]:
        if self.kind == "bool":
            if isinstance(value, bool | np.bool_):
                return []
            return [f"{name}={value!r}; allowed: True or False"]
        if self.kind in ("str", "any"):
            return []
        if self.kind == "vector":
            arr = np.asarray(value, dtype=float)
            if arr.shape != (3,):
                return [f"{name}={value!r} must be a 3-vector"]
            if not np.all(np.isfinite(arr)):
                return [f"{name}={value!r} contains NaN or inf"]
            return []
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return [f"{name}={value!r} is not a number"]
        if arr.ndim > (1 if self.array else 0):
            return [f"{name} has shape {arr.shape}; allowed: a scalar"
                    + (" or a 1-D array" if self.array else "")]
        flat = arr.ravel()
        if flat.size == 0:
            return [f"{name} is empty"]
        if np.any(np.isnan(flat)):
            return [f"{name}={_show(value)} is NaN; allowed: {self.interval()}"]
        bad_low = flat <= self.low if self.low_open else flat < self.low
        bad_high = flat >= self.high if self.high_open else flat > self.high
        bad = bad_low | bad_high
        if np.any(bad):
            if flat.size == 1:
                shown = _show(value)
            else:
                shown = f"{_fmt(float(flat[bad][0]))} (item {int(np.argmax(bad))})"
            return [f"{name}={shown} is outside {self.interval()}"]
        return []


def _fmt(x: float) -> str:
    if x == math.inf:
        return "inf"
    if x == -math.inf:
        return "-inf"
    return f"{x:g}"


def _show(value: Any) -> str:
    if isinstance(value, float | int | np.floating | np.integer):
        return f"{float(value):g}"
    if np.ndim(value) == 0:
        try:
            return f"{float(value):g}"
        except (TypeError, ValueError):
            return repr(value)
    return repr(value)


def validate(call: str, spec: Mapping[str, Parameter], given: Mapping[str, Any]) -> dict[str, Any]:
    """Check ``given`` against ``spec``; return the full dict with defaults filled in.

    Raises one ParameterError listing every problem, each prefixed with ``call``.
    """
    problems: list[str] = []
    unknown = [k for k in given if k not in spec]
    if unknown:
        allowed = ", ".join(sorted(spec)) or "none"
        for k in unknown:
            problems.append(f"unknown parameter {k}={given[k]!r}; allowed: {allowed}")
    out: dict[str, Any] = {}
    for name, p in spec.items():
        if name in given and given[name] is not None:
            value = given[name]
        elif p.default is REQUIRED:
            problems.append(f"{name} is required ({p.doc or p.unit or p.kind})")
            continue
        else:
            value = p.default
        if value is not None:
            problems.extend(p.problems(name, value))
        out[name] = value
    if problems:
        raise ParameterError("\n".join(f"{call}: {m}" for m in problems))
    return out
