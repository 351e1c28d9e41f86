"""Validation suite: each case runs impacts through the engine and compares with a reference.

``dpm validate`` (``dpm.cli``) runs the registered cases (:data:`CASES`) and prints one row
per (test, model, quantity): dpm's value, the reference, the error, the tolerance and
whether it passed. A sweep (many angles or spins) gives one row per quantity with its
worst point. The cases and their references are described in ``docs/validation.md``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass


@dataclass
class Row:
    """One compared quantity."""

    test: str          #: the case, e.g. "CO1 glass"
    model: str         #: the impact model
    quantity: str      #: what is compared (and over how many impacts)
    value: float       #: dpm's value (the worst point of a sweep)
    reference: float   #: the reference at that point
    error: float       #: abs(value - reference) / scale (scale: abs(reference) unless stated)
    tolerance: float   #: the largest error that passes
    passed: bool
    source: str = ""   #: where the reference comes from
    known: str = ""    #: why it fails, for a failure that is known and explained

    @property
    def status(self) -> str:
        """"yes", "NO", or "known" (a failure explained in docs/validation.md)."""
        if self.passed:
            return "yes"
        return "known" if self.known else "NO"


def unexpected(rows: Iterable[Row]) -> list[Row]:
    """The rows outside their tolerance without a known reason."""
    return [r for r in rows if not r.passed and not r.known]


def compare(test: str, model: str, quantity: str, pairs: Iterable[tuple[float, float]],
            tolerance: float, source: str, scale: float | None = None,
            bound: bool = False) -> Row:
    """One row from (value, reference) points: the worst of them.

    The error is abs(value - reference) / scale with ``scale`` (default abs(reference) of
    each point, relative error); with ``bound`` the reference is an upper bound and the
    error max(0, value - reference) / scale. A sweep's row shows its largest error.
    """
    worst = None
    n = 0
    for value, ref in pairs:
        n += 1
        s = abs(ref) if scale is None else scale
        diff = max(0.0, value - ref) if bound else abs(value - ref)
        err = diff / s if s > 0 else diff
        if not math.isfinite(err):
            err = math.inf
        if worst is None or err > worst[2]:
            worst = (value, ref, err)
    if worst is None:
        raise ValueError(f"{test} {model} {quantity}: no points to compare")
    label = quantity if n == 1 else f"{quantity} (worst of {n})"
    return Row(test, model, label, float(worst[0]), float(worst[1]), float(worst[2]),
               tolerance, bool(worst[2] <= tolerance), source)


@dataclass
class Case:
    """A registered validation case: ``run(quick, models)`` returns its rows."""

    name: str
    title: str
    models: tuple[str, ...]
    run: Callable[[bool, Sequence[str]], list[Row]]


#: name -> case, in the order they are run
CASES: dict[str, Case] = {}


def register(case: Case) -> Case:
    CASES[case.name] = case
    return case


def all_models() -> list[str]:
    """Every model some case applies to."""
    _load()
    seen: dict[str, None] = {}
    for c in CASES.values():
        for m in c.models:
            seen[m] = None
    return list(seen)


def _load() -> None:
    from . import analytic, chung_ooi, jkr  # noqa: F401  (they register their cases)


def run(cases: Sequence[str] | None = None, quick: bool = False,
        models: Sequence[str] | None = None,
        progress: Callable[[str], None] | None = None) -> list[Row]:
    """Run the named cases (default: all) for ``models`` (default: every one that applies).

    Raises :class:`dpm.ParameterError` for an unknown case or model name.
    """
    from ..errors import ParameterError

    _load()
    # the Chung & Ooi tests first, then the analytic cases
    names = (sorted(CASES, key=lambda n: not n.startswith("co")) if cases is None
             else list(cases))
    for n in names:
        if n not in CASES:
            raise ParameterError(f"dpm.validation.run: case={n!r} is unknown; allowed: "
                                 + ", ".join(CASES))
    known = all_models()
    for m in models or ():
        if m not in known:
            raise ParameterError(f"dpm.validation.run: model={m!r} is not validated here; "
                                 "allowed: " + ", ".join(known))
    rows: list[Row] = []
    for n in names:
        case = CASES[n]
        use = list(case.models) if models is None else [m for m in case.models
                                                         if m in models]
        if models is not None and not use:
            continue  # a case of other models (or of none: the flip) is left out
        if progress:
            progress(f"{n}: {case.title}")
        rows.extend(case.run(quick, use))
    if not rows:
        raise ParameterError(f"dpm.validation.run: no case of {names} applies to "
                             f"models={list(models or ())}")
    return rows


def _fmt(x: float) -> str:
    return f"{x:.5g}" if math.isfinite(x) else str(x)


def table(rows: Sequence[Row], markdown: bool = False) -> str:
    """The rows as a plain-text or Markdown table."""
    head = ["test", "model", "quantity", "dpm", "reference", "error", "tolerance", "pass"]
    body = [[r.test, r.model, r.quantity, _fmt(r.value), _fmt(r.reference),
             f"{r.error:.2e}", f"{r.tolerance:.1e}", r.status]
            for r in rows]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        lines += ["| " + " | ".join(b) + " |" for b in body]
        return "\n".join(lines)
    widths = [max(len(x) for x in col) for col in zip(head, *body, strict=True)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    out = [fmt.format(*head), fmt.format(*["-" * w for w in widths])]
    out += [fmt.format(*b) for b in body]
    return "\n".join(out)


def to_json(rows: Sequence[Row]) -> str:
    return json.dumps([asdict(r) for r in rows], indent=1)
