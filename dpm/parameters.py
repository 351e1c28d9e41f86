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
from collections.abc import Mapping, Sequence
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
            return [f"{name}={shown(value)}; allowed: True or False"]
        if self.kind == "any":
            return []
        if self.kind == "str":
            if isinstance(value, str | os.PathLike):
                return []
            return [f"{name}={shown(value)} must be a string"]
        unit = f" [{self.unit}]" if self.unit else ""
        if self.kind == "vector":
            arr = numeric_array(value)
            if arr is None or arr.shape != (3,):
                return [f"{name}={shown(value)} must be a 3-vector of numbers{unit}"]
            if np.any(np.isnan(arr)) or (not self.allow_inf and np.any(np.isinf(arr))):
                return [f"{name}={shown(value)} contains NaN or inf; allowed: 3 finite "
                        f"numbers{unit}"]
            return []
        what = "an integer" if self.kind == "int" else "a number"
        arr = numeric_array(value)
        if arr is None:
            return [f"{name}={shown(value)} is not {what}; allowed: {what} in "
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
                echo = _show(value)
            else:
                echo = f"{_fmt(float(flat[bad][0]))} (item {int(np.argmax(bad))})"
            return [f"{name}={echo} is outside {self.interval()}"]
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


#: items of a sequence a message shows before it cuts the rest
SHOWN_ITEMS = 8


def shown(value: Any, digits: int | None = None) -> str:
    """``repr(value)`` for a message, with numpy's scalars and arrays shown as plain
    numbers: ``(0.1, 0.2)``, not ``(np.float64(0.1), np.float64(0.2))`` nor
    ``array([0.1, 0.2])`` (a 1-D array as a tuple, a 2-D one as a list of them); tuples
    and lists are followed inside, and those of more than :data:`SHOWN_ITEMS` items cut
    (``(1.0, 2.0, ..., (100 items))``). ``digits``: floats with at most that many
    significant digits, as ``format(x, "g")`` writes them (``2500``, ``5e+06``)."""
    if isinstance(value, bool | np.bool_):
        return str(bool(value))
    if digits is not None and isinstance(value, float | np.floating):
        return format(float(value), f".{digits}g")
    if isinstance(value, np.number):
        return str(value)  # (numpy's shortest digits of its own precision: float32 0.1)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, os.PathLike):
        return repr(os.fspath(value))
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return shown(value.item(), digits)
        brackets = "()" if value.ndim == 1 else "[]"
    elif type(value) is tuple:
        brackets = "()"
    elif type(value) is list:
        brackets = "[]"
    else:
        return repr(value)
    parts = [shown(v, digits) for v in value[:SHOWN_ITEMS]]
    if len(value) > SHOWN_ITEMS:
        parts.append(f"... ({len(value)} items)")
    elif brackets == "()" and len(parts) == 1:
        parts[0] += ","
    return brackets[0] + ", ".join(parts) + brackets[1]


def _same(a: Any, b: Any) -> bool:
    """Whether a parameter's value is its default (numbers and arrays by value)."""
    if a is b:
        return True
    if a is None or b is None:
        return False
    x, y = numeric_array(a), numeric_array(b)
    if x is not None and y is not None:
        return x.shape == y.shape and bool(np.all(x == y))
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False


def declared_repr(name: str, parameters: Mapping[str, Parameter], values: Mapping[str, Any],
                  leading: Sequence[str] = (), trailing: Sequence[str] = ()) -> str:
    """``Name(lead, p=v, ..., trail)``: an object by its declared parameters, each required
    one and each that differs from its default, numbers with 12 significant digits
    (``Tube(material='steel', length=1, radius=0.05)``); an array of more than one
    dimension or of more than :data:`SHOWN_ITEMS` items by its shape only."""
    parts = list(leading)
    for key, p in parameters.items():
        if key not in values:
            continue
        v = values[key]
        if p.default is not REQUIRED and _same(v, p.default):
            continue
        arr = numeric_array(v) if not isinstance(v, str | os.PathLike) else None
        if arr is not None and (arr.ndim > 1 or arr.size > SHOWN_ITEMS):
            parts.append(f"{key}=<array of shape {arr.shape}>")
        else:
            parts.append(f"{key}={shown(v, digits=12)}")
    parts += list(trailing)
    return f"{name}({', '.join(parts)})"


def _show(value: Any, exact: bool = False) -> str:
    if isinstance(value, float | int | np.floating | np.integer):
        return repr(float(value)) if exact else f"{float(value):g}"
    if np.ndim(value) == 0:
        try:
            return f"{float(value):g}"
        except (TypeError, ValueError):
            return shown(value)
    return shown(value)


def validate(call: str, spec: Mapping[str, Parameter], given: Mapping[str, Any]) -> dict[str, Any]:
    """Check ``given`` against ``spec``; return the full dict with defaults filled in.

    Raises one ParameterError listing every problem, each prefixed with ``call``.
    """
    problems: list[str] = []
    unknown = [k for k in given if k not in spec]
    if unknown:
        allowed = ", ".join(sorted(spec)) or "none"
        for k in unknown:
            problems.append(f"unknown parameter {k}={shown(given[k])}; allowed: {allowed}")
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
