"""Units and small arithmetic expressions in scene-file values (``"30 deg"``, ``"2 mm / 2"``).

A string where a scene file's key takes a number is read as a quantity: numbers, the units
of :data:`UNITS`, the constant ``pi``, the functions of :data:`FUNCTIONS`, ``+ - * /``,
``**`` (or ``^``) and parentheses. A number followed by units is one quantity (``"2 mm"``;
``"2 mm / 1 m"`` is 0.002, ``"1 / 2 s"`` 0.5 per second); digits after a unit are its
power (``"5 kg/m3"``), as is ``^`` or ``**`` after it (``"9.81 m s^-2"``). The text is
rewritten with explicit products, parsed with :mod:`ast` and only the nodes of the grammar
are evaluated: no other name, attribute, call or operator, so nothing else can run.

The result is converted to the unit the key declares (:class:`dpm.parameters.Parameter`
``unit``: ``"30 deg"`` for a key in ``rad`` is 0.5236, for a key in ``deg`` 30; values are
read to 15 significant digits), and a quantity of another dimension is refused
(``radius = "30 deg"``). Angles are a dimension of their own (``rad``, ``deg``, ``rev``),
so that an angle is never taken for a plain number (a friction coefficient) and turns per
time (``rpm``, ``Hz``: 1/s) are not taken for an angular speed (``rad/s``; write
``"30 rev/min"`` for one). An expression without a unit (``"pi / 6"``,
``"sqrt(2) * 1e-3"``) is a number in the key's own unit; a string that is only a number
(``"30"``, ``"1 - 0.5"``: no unit, function or constant) is refused, as a number written in
quotes by mistake, and so is a unit without a number (``"mm"``).

Grammar (a number is ``1``, ``2.5``, ``.5``, ``1e-3``; a unit is one of :data:`UNITS`,
optionally with its power: ``m3``, ``s^2``, ``s**-1``, ``m^(1/2)``)::

    expression := term (("+" | "-") term)*
    term       := factor (("*" | "/") factor)*
    factor     := ("+" | "-") factor | atom [("**" | "^") factor]
    atom       := number [unit ...] | unit | "pi" | function "(" expression ")"
                | "(" expression ")"
"""

from __future__ import annotations

import ast
import math
import re
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache

#: the base dimensions, in the order of a :class:`Quantity`'s ``dim``
DIMENSIONS = ("length", "mass", "time", "angle")
#: the longest expression read (a value is a few words)
MAX_LENGTH = 200

Dim = tuple[Fraction, ...]
_NONE: Dim = (Fraction(0),) * 4


def _dim(length: int = 0, mass: int = 0, time: int = 0, angle: int = 0) -> Dim:
    return tuple(Fraction(x) for x in (length, mass, time, angle))


_L, _M, _T, _A = _dim(1), _dim(mass=1), _dim(time=1), _dim(angle=1)
_FORCE = _dim(1, 1, -2)
_PRESSURE = _dim(-1, 1, -2)
_ENERGY = _dim(2, 1, -2)
_FREQUENCY = _dim(time=-1)

#: unit name -> (value in SI, dimension, what it measures); ``rad``/``deg``/``rev`` are
#: angles (their own dimension), ``Hz`` and ``rpm`` count cycles and turns (1/s)
UNITS: dict[str, tuple[float, Dim, str]] = {
    "m": (1.0, _L, "length"),
    "km": (1e3, _L, "length"),
    "cm": (1e-2, _L, "length"),
    "mm": (1e-3, _L, "length"),
    "um": (1e-6, _L, "length"),
    "µm": (1e-6, _L, "length"),
    "nm": (1e-9, _L, "length"),
    "rad": (1.0, _A, "angle"),
    "deg": (math.pi / 180.0, _A, "angle"),
    "rev": (2.0 * math.pi, _A, "angle (a turn, 2 pi rad)"),
    "s": (1.0, _T, "time"),
    "ms": (1e-3, _T, "time"),
    "us": (1e-6, _T, "time"),
    "µs": (1e-6, _T, "time"),
    "min": (60.0, _T, "time"),
    "h": (3600.0, _T, "time"),
    "kg": (1.0, _M, "mass"),
    "g": (1e-3, _M, "mass"),
    "mg": (1e-6, _M, "mass"),
    "N": (1.0, _FORCE, "force"),
    "J": (1.0, _ENERGY, "energy"),
    "Pa": (1.0, _PRESSURE, "pressure, stress, modulus"),
    "kPa": (1e3, _PRESSURE, "pressure, stress, modulus"),
    "MPa": (1e6, _PRESSURE, "pressure, stress, modulus"),
    "GPa": (1e9, _PRESSURE, "pressure, stress, modulus"),
    "bar": (1e5, _PRESSURE, "pressure"),
    "Hz": (1.0, _FREQUENCY, "frequency (cycles per second)"),
    "kHz": (1e3, _FREQUENCY, "frequency"),
    "rpm": (1.0 / 60.0, _FREQUENCY, "turns per minute (1/min)"),
}
#: what Python's parser makes of the micro sign (NFKC: U+00B5 -> U+03BC)
_ALIASES = {"μm": "µm", "μs": "µs"}
#: constants (dimensionless)
CONSTANTS = {"pi": math.pi}
#: functions of one argument; the trigonometric ones take an angle (or a plain number:
#: radians), sqrt any quantity (the dimension's powers halved)
FUNCTIONS = ("sin", "cos", "tan", "sqrt")


class ExpressionError(ValueError):
    """A value that is not a quantity this module reads, or of the wrong dimension."""


@dataclass(frozen=True)
class Quantity:
    """A value in SI units with its dimension (powers of :data:`DIMENSIONS`); ``units``:
    whether the expression named a unit, ``plain``: whether it had no unit, function or
    constant (only numbers), ``number``: whether it had a number or constant (not only
    units)."""

    value: float
    dim: Dim = _NONE
    units: bool = False
    plain: bool = True
    number: bool = True


def dimension_text(dim: Dim) -> str:
    """``length/time^2``, ``dimensionless``: a dimension for a message."""
    up = [f"{n}^{p}" if p != 1 else n for n, p in zip(DIMENSIONS, dim, strict=True) if p > 0]
    down = [f"{n}^{-p}" if p != -1 else n for n, p in zip(DIMENSIONS, dim, strict=True)
            if p < 0]
    if not up and not down:
        return "dimensionless"
    text = "*".join(up) or "1"
    return text + ("/" + "/".join(down) if down else "")


_TOKEN = re.compile(r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
                    r"|(?P<name>[A-Za-zµμ_]+)(?P<power>\d+)?"
                    r"|(?P<op>\*\*|[-+*/^()]))")
#: the power of a unit written after it: ``m^2``, ``s**-1``, ``m^(1/2)``
_POWER = re.compile(r"\s*(?:\*\*|\^)\s*(?P<p>[-+]?\d+|\(\s*[-+]?\d+\s*(?:/\s*\d+\s*)?\))")


def _to_python(text: str) -> str:
    """The expression with its implicit products and unit powers made explicit, a number
    and the units after it grouped (``2 mm / 1 m`` -> ``(2*mm)/(1*m)``, ``kg/m3`` ->
    ``kg/(m**3)``, ``^`` -> ``**``); ExpressionError for text outside the grammar."""
    out: list[str] = []
    prev = ""  # "value" after a number, name or ")"; "func" after a function's name
    group = False  # a number and the units after it, in parentheses
    pos = 0
    text = text.rstrip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            at = len(text) - len(text[pos:].lstrip())
            raise ExpressionError(f"unexpected {text[at]!r} at character {at + 1}")
        pos = m.end()
        num, name, op = m.group("num"), m.group("name"), m.group("op")
        if name is not None:
            name = _ALIASES.get(name, name)
        unit = name is not None and name in UNITS
        if prev == "func" and op != "(":
            raise ExpressionError(f"{out[-1]} is a function: write {out[-1]}(...)")
        if group and not unit:
            out.append(")")
            group = False
        if num is not None:
            if prev == "value":
                raise ExpressionError(f"a number after a value at {num!r}; allowed: an "
                                      "operator between them")
            out.append(f"({num}")
            group = True
        elif name is not None:
            if prev == "value":
                out.append("*")
            power = m.group("power")
            if power is not None and not unit:
                raise ExpressionError(f"unknown name {name + power!r}")
            after = _POWER.match(text, pos) if unit and power is None else None
            if after:
                power = after.group("p")
                pos = after.end()
            out.append(f"({_ident(name)}**{power})" if power is not None else _ident(name))
        else:
            if op == "(" and prev == "value":
                out.append("*")
            out.append("**" if op == "^" else op)
        prev = ("func" if name in FUNCTIONS else "value" if num is not None or name is not None
                or op == ")" else "")
    if group:
        out.append(")")
    return " ".join(out)


def _ident(name: str) -> str:
    """A Python identifier for a name (the micro sign is not one Python keeps as it is)."""
    return name.replace("µ", "_micro_")


_NAMES = {_ident(n): n for n in [*UNITS, *CONSTANTS, *FUNCTIONS]}


def evaluate(text: str) -> Quantity:
    """The quantity ``text`` describes, in SI units; ExpressionError naming the problem."""
    if not isinstance(text, str):
        raise ExpressionError(f"{text!r} is not text")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"longer than {MAX_LENGTH} characters")
    if not text.strip():
        raise ExpressionError("empty")
    source = _to_python(text)
    try:
        tree = ast.parse(source, mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        raise ExpressionError("not an expression (numbers, units, + - * / ** and "
                              "parentheses)") from None
    try:
        return _eval(tree.body)
    except OverflowError:
        raise ExpressionError("a number too large") from None
    except ZeroDivisionError:
        raise ExpressionError("a division by zero") from None
    except RecursionError:
        raise ExpressionError("nested too deeply") from None


def _eval(node: ast.AST) -> Quantity:
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, int | float):
            raise ExpressionError(f"{node.value!r} is not a number")
        return Quantity(float(node.value))
    if isinstance(node, ast.Name):
        name = _NAMES.get(node.id)
        if name in UNITS:
            si, dim, _ = UNITS[name]
            return Quantity(si, dim, units=True, plain=False, number=False)
        if name in CONSTANTS:
            return Quantity(CONSTANTS[name], plain=False)
        if name in FUNCTIONS:
            raise ExpressionError(f"{name} is a function: write {name}(...)")
        raise ExpressionError(f"unknown name {node.id!r}; units: {', '.join(UNITS)}; "
                              f"constants: {', '.join(CONSTANTS)}; functions: "
                              f"{', '.join(FUNCTIONS)}")
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.UAdd | ast.USub):
        q = _eval(node.operand)
        sign = -1.0 if isinstance(node.op, ast.USub) else 1.0
        return Quantity(sign * q.value, q.dim, q.units, q.plain, q.number)
    if isinstance(node, ast.BinOp):
        a, b = _eval(node.left), _eval(node.right)
        flags = (a.units or b.units, a.plain and b.plain, a.number or b.number)
        if isinstance(node.op, ast.Add | ast.Sub):
            if a.dim != b.dim:
                verb = "adds" if isinstance(node.op, ast.Add) else "subtracts"
                to = "to" if isinstance(node.op, ast.Add) else "from"
                raise ExpressionError(f"{verb} {dimension_text(b.dim)} {to} "
                                      f"{dimension_text(a.dim)}")
            v = a.value + b.value if isinstance(node.op, ast.Add) else a.value - b.value
            return Quantity(v, a.dim, *flags)
        if isinstance(node.op, ast.Mult):
            return Quantity(a.value * b.value, _add(a.dim, b.dim, 1), *flags)
        if isinstance(node.op, ast.Div):
            return Quantity(a.value / b.value, _add(a.dim, b.dim, -1), *flags)
        if isinstance(node.op, ast.Pow):
            if b.dim != _NONE:
                raise ExpressionError(f"a power of {dimension_text(b.dim)}; allowed: a "
                                      "plain number")
            p = Fraction(b.value).limit_denominator(12)
            if a.dim != _NONE and abs(float(p) - b.value) > 1e-12:
                raise ExpressionError(f"{dimension_text(a.dim)} to the power {b.value:g}")
            value = a.value ** b.value
            if isinstance(value, complex):
                raise ExpressionError(f"a negative number to the power {b.value:g}")
            return Quantity(float(value), tuple(x * p for x in a.dim), *flags)
    if isinstance(node, ast.Call):
        name = _NAMES.get(getattr(node.func, "id", ""))
        if name not in FUNCTIONS or node.keywords or len(node.args) != 1:
            raise ExpressionError("a call of something other than "
                                  f"{', '.join(f'{f}(x)' for f in FUNCTIONS)}")
        x = _eval(node.args[0])
        if name == "sqrt":
            if x.value < 0:
                raise ExpressionError(f"sqrt of a negative number ({x.value:g})")
            return Quantity(math.sqrt(x.value), tuple(d / 2 for d in x.dim), x.units, False,
                            x.number)
        if x.dim not in (_NONE, _A):
            raise ExpressionError(f"{name} of {dimension_text(x.dim)}; allowed: an angle "
                                  "(or a plain number: radians)")
        return Quantity(getattr(math, name)(x.value), _NONE, x.units, False, x.number)
    raise ExpressionError("not an expression of numbers, units, + - * / ** and parentheses")


def _add(a: Dim, b: Dim, sign: int) -> Dim:
    return tuple(x + sign * y for x, y in zip(a, b, strict=True))


@lru_cache(maxsize=256)
def unit_quantity(unit: str) -> Quantity | None:
    """The quantity of a declared unit string (``"m/s2"``, ``"1/min"``, ``"kg/m3"``;
    ``""``: a plain number); None for a unit this module cannot read (then a value's
    dimension is not checked)."""
    if not unit:
        return Quantity(1.0)
    try:
        return evaluate(unit)
    except ExpressionError:
        return None


def convert(text: str, unit: str = "", integer: bool = False) -> float | int:
    """The value of ``text`` in the declared ``unit`` (a number in the key's own unit when
    ``text`` names no unit); ExpressionError for a quantity of another dimension, for a
    string that is only a plain number and for one this module cannot read.
    ``integer``: an integral result is returned as an int (a non-integral one is left to
    the key's own check)."""
    q = evaluate(text)
    if q.plain:
        raise ExpressionError("a plain number in quotes; write it without quotes (a string "
                              'is for a quantity with a unit, "2 mm", or an expression with '
                              'a unit, function or pi, "2 mm / 2", "sin(30 deg)")')
    if not q.number:
        raise ExpressionError(f"a unit without a number; write the number before it: "
                              f'"1 {text.strip()}"')
    target = unit_quantity(unit)
    if not q.units:
        value = q.value  # a number in the key's own unit
    elif target is None:
        value = q.value  # (a unit this module does not know: the value in SI)
    elif q.dim != target.dim:
        want = f"{unit} ({dimension_text(target.dim)})" if unit else "a plain number"
        raise ExpressionError(f"a quantity of {dimension_text(q.dim)}; the key takes {want}")
    else:
        value = q.value / target.value
    if not math.isfinite(value):
        raise ExpressionError("not finite")
    value = float(f"{value:.15g}")  # (no 29.999999999999996 for "30 deg" in deg)
    if integer and value.is_integer():
        return int(value)
    return value


def units_table() -> list[tuple[str, str, str]]:
    """(unit, its value in SI, what it measures) of every unit, for the reference."""
    rows = []
    for name, (si, dim, what) in UNITS.items():
        base = {(1, 0, 0, 0): "m", (0, 1, 0, 0): "kg", (0, 0, 1, 0): "s", (0, 0, 0, 1): "rad",
                (1, 1, -2, 0): "kg m/s2", (2, 1, -2, 0): "kg m2/s2", (-1, 1, -2, 0): "kg/(m s2)",
                (0, 0, -1, 0): "1/s"}[tuple(int(x) for x in dim)]
        rows.append((name, f"{si:.10g} {base}", what))
    return rows
