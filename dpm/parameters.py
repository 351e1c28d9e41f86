"""Declared parameters with ranges, and the validation every object-layer class uses.

A class declares ``parameters = {name: Parameter(...)}``; :func:`validate` checks a
keyword dictionary against it and raises one :class:`ParameterError` that lists every
problem: unknown names (with the allowed ones), missing required values, values outside
their range, NaN and infinity (unless the parameter allows it), strings and booleans
where a number is wanted, non-integers where an integer is wanted.
"""

from __future__ import annotations

import math
import os
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
    ``array`` allows a 1-D array of values (e.g. one radius per particle). ``allow_inf``
    lets the value be infinite (e.g. an inlet's ``stop``: never); NaN is never allowed.
    Numbers must be given as numbers: strings, booleans and None inside a value are refused
    (``kind="bool"`` takes only True or False, ``kind="int"`` only integers, integral
    floats such as ``1e5`` included).
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
    allow_inf: bool = False

    def interval(self) -> str:
        lo = "(" if self.low_open or self.low == -math.inf else "["
        hi = ")" if self.high_open or self.high == math.inf else "]"
        return f"{lo}{_fmt(self.low)}, {_fmt(self.high)}{hi}"

    def problems(self, name: str, value: Any) -> list[str]:
        if self.kind == "bool":
            if isinstance(value, bool | np.bool_):
                return []
            return [f"{name}={value!r}; allowed: True or False"]
        if self.kind == "any":
            return []
        if self.kind == "str":
            if isinstance(value, str | os.PathLike):
                return []
            return [f"{name}={value!r} must be a string"]
        unit = f" [{self.unit}]" if self.unit else ""
        if self.kind == "vector":
            arr = numeric_array(value)
            if arr is None or arr.shape != (3,):
                return [f"{name}={value!r} must be a 3-vector of numbers{unit}"]
            if np.any(np.isnan(arr)) or (not self.allow_inf and np.any(np.isinf(arr))):
                return [f"{name}={value!r} contains NaN or inf; allowed: 3 finite "
                        f"numbers{unit}"]
            return []
        what = "an integer" if self.kind == "int" else "a number"
        arr = numeric_array(value)
        if arr is None:
            return [f"{name}={value!r} is not {what}; allowed: {what} in "
                    f"{self.interval()}{unit}"]
        if arr.ndim > (1 if self.array else 0):
            return [f"{name} has shape {arr.shape}; allowed: a scalar"
                    + (" or a 1-D array" if self.array else "")]
        flat = arr.ravel()
        if flat.size == 0:
            return [f"{name} is empty"]
        if np.any(np.isnan(flat)):
            return [f"{name}={_show(value)} is NaN; allowed: {self.interval()}"]
        if not self.allow_inf and np.any(np.isinf(flat)):
            return [f"{name}={_show(value)} is not finite; allowed: a finite number in "
                    f"{self.interval()}{unit}"]
        if self.kind == "int" and flat.dtype.kind == "f":
            frac = np.isfinite(flat) & (flat != np.round(flat))
            if np.any(frac):
                return [f"{name}={_show(value, exact=True)} is not {what}; allowed: {what} "
                        f"in {self.interval()}"]
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


#: Python and numpy scalar types accepted as numbers (bool is an int subclass: refused)
_NUMBER_TYPES = (int, float, np.integer, np.floating)


def numeric_array(value: Any) -> np.ndarray | None:
    """``value`` as a float array if it is made only of numbers (Python or numpy ints and
    floats, arrays of them, nested sequences of them); None if any item is a string, a
    boolean, None or anything else, or the nesting is ragged. Unlike ``np.asarray(value,
    float)``, ``"1e-3"`` and ``True`` are not numbers here."""
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "iuf":
            return value.astype(float, copy=False)
        if value.dtype.kind != "O":
            return None
    elif isinstance(value, str | bytes | bool | np.bool_) or value is None:
        return None
    elif isinstance(value, _NUMBER_TYPES):
        return np.asarray(value, dtype=float)
    try:
        obj = np.array(value, dtype=object)
    except (TypeError, ValueError):
        return None
    if obj.dtype != object:
        return None
    items = obj.ravel()
    for t in set(map(type, items)):
        if not issubclass(t, _NUMBER_TYPES) or issubclass(t, bool | np.bool_):
            return None
    try:
        return obj.astype(float)
    except (TypeError, ValueError, OverflowError):
        return None


def _fmt(x: float) -> str:
    if x == math.inf:
        return "inf"
    if x == -math.inf:
        return "-inf"
    return f"{x:g}"


def _show(value: Any, exact: bool = False) -> str:
    if isinstance(value, float | int | np.floating | np.integer):
        return repr(float(value)) if exact else f"{float(value):g}"
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
