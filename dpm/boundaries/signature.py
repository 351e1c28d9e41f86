"""Signatures and parameter tables generated from a class's declared ``parameters``.

Boundaries and motions take their parameters as keywords checked by
:func:`dpm.parameters.validate` (so a misspelt name gets dpm's
:class:`~dpm.errors.ParameterError` listing the allowed ones, not Python's TypeError).
Their ``__init__`` therefore reads ``**params``; this module gives each such class an
``inspect.signature`` naming every declared parameter with its default (``help()``,
IPython's ``?`` and Sphinx show it) and a numpy-style "Parameters" section with units and
ranges appended to its docstring. :class:`dpm.Boundary` and :class:`dpm.Motion` apply it
to every subclass, plugins' included.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping, Sequence
from typing import Any

from ..parameters import REQUIRED, Parameter

_KW = inspect.Parameter.KEYWORD_ONLY
_POS = inspect.Parameter.POSITIONAL_OR_KEYWORD

_TYPES: dict[str, Any] = {
    "float": float,
    "int": int,
    "str": str,
    "bool": bool,
    "vector": tuple[float, float, float],
    "any": Any,
}


def annotation(p: Parameter) -> Any:
    """The type a parameter takes (``X | None`` where its default is None)."""
    t = _TYPES.get(p.kind, Any)
    if p.array and t is float:
        t = float | Sequence[float]
    if p.default is None and t is not Any:
        t = t | None
    return t


def signature(parameters: Mapping[str, Parameter],
              leading: Sequence[inspect.Parameter] = (),
              trailing: Sequence[inspect.Parameter] = ()) -> inspect.Signature:
    """``leading`` parameters, then every declared parameter as keyword-only (no default
    where it is required), then ``trailing`` keyword-only ones."""
    items = list(leading)
    for name, p in parameters.items():
        default = inspect.Parameter.empty if p.default is REQUIRED else p.default
        items.append(inspect.Parameter(name, _KW, default=default, annotation=annotation(p)))
    items += list(trailing)
    return inspect.Signature(items)


def _range(p: Parameter) -> str:
    if p.kind not in ("float", "int") or (p.low == -math.inf and p.high == math.inf):
        return ""
    return f" in {p.interval()}"


def describe(name: str, p: Parameter) -> str:
    """One line: unit, kind and range, meaning and default of a declared parameter."""
    bits = []
    if p.unit:
        bits.append(f"[{p.unit}]")
    if p.kind == "vector":
        bits.append("3-vector")
    elif p.kind in ("float", "int"):
        what = "integer" if p.kind == "int" else "number"
        if p.array:
            what += " or one per item"
        bits.append(what + _range(p))
    elif p.kind == "bool":
        bits.append("True or False")
    text = " ".join(bits)
    if p.doc:
        text = f"{text}; {p.doc}" if text else p.doc
    default = "(required)" if p.default is REQUIRED else f"(default {p.default!r})"
    return f"{text} {default}" if text else default


def parameters_section(parameters: Mapping[str, Parameter],
                       extra: Sequence[tuple[str, str, str]] = ()) -> str:
    """A numpy-style "Parameters" section: ``extra`` (name, type, text) rows first, then
    each declared parameter with its unit, range and default."""
    lines = ["Parameters", "----------"]
    for name, typ, text in extra:
        lines += [f"{name} : {typ}", f"    {text}"]
    for name, p in parameters.items():
        typ = inspect.formatannotation(annotation(p))
        lines += [f"{name} : {typ}", f"    {describe(name, p)}"]
    return "\n".join(lines)


def document(cls: type, leading: Sequence[inspect.Parameter] = (),
             trailing: Sequence[inspect.Parameter] = (),
             extra: Sequence[tuple[str, str, str]] = ()) -> None:
    """Give ``cls`` a signature and a "Parameters" docstring section made from its
    ``parameters``, if its ``__init__`` takes them as ``**params`` (a class that spells
    out its own keywords keeps its own signature)."""
    init = inspect.signature(cls.__init__)
    if not any(q.kind is inspect.Parameter.VAR_KEYWORD for q in init.parameters.values()):
        cls.__signature__ = None  # a parent's generated one would be wrong here
        return
    declared = getattr(cls, "parameters", {})
    cls.__signature__ = signature(declared, leading, trailing)
    doc = inspect.cleandoc(cls.__dict__.get("__doc__") or "")
    if "\nParameters\n----------" not in doc:
        section = parameters_section(declared, extra)
        cls.__doc__ = f"{doc}\n\n{section}\n" if doc else section + "\n"


def keyword(name: str, default: Any = inspect.Parameter.empty, ann: Any = Any,
            positional: bool = False) -> inspect.Parameter:
    """A signature parameter (keyword-only unless ``positional``)."""
    return inspect.Parameter(name, _POS if positional else _KW, default=default,
                             annotation=ann)
