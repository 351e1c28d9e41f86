"""Settable attributes declared once (the model is HOOMD-blue's ``ParameterDict``).

A class lists its parameters once, in ``parameters`` (name -> :class:`dpm.parameters.
Parameter`: kind, range, unit, default). ``name = Declared(doc)`` then makes the
attribute settable at any time with the same checks as the constructor's, converted on
assignment and stored in ``_name``; ``after`` names a method run after each change (what
the change invalidates). One declaration gives the check, the conversion, the docs and
the scene-file reference; no hand-written property pairs.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .errors import ParameterError
from .parameters import validate


class Declared:
    """A data descriptor for the owner's parameter of the same name (see the module
    docstring). ``convert`` turns the checked value into what is stored; ``choices``
    restricts a string; ``nullable`` lets None through (a parameter whose default is
    None)."""

    def __init__(self, doc: str, convert: Callable[[Any], Any] = float,
                 after: str | None = None, choices: tuple[str, ...] = ()) -> None:
        self.__doc__ = doc
        self.convert = convert
        self.after = after
        self.choices = choices
        self.name = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name
        self.attr = "_" + name

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        return getattr(obj, self.attr)

    def __set__(self, obj: Any, value: Any) -> None:
        call = f"sim.{self.name}"
        spec = type(obj).parameters[self.name]
        if self.choices:
            if value not in self.choices:
                raise ParameterError(f"{call}={value!r}; allowed: {', '.join(self.choices)}")
        elif value is None and spec.default is not None:
            raise ParameterError(f"{call}=None; allowed: a value (the default is "
                                 f"{spec.default!r})")
        checked = validate(call, {self.name: spec}, {self.name: value})[self.name]
        setattr(obj, self.attr, None if checked is None else self.convert(checked))
        if self.after:
            getattr(obj, self.after)()
