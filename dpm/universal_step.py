"""The universal step module: one compiled step per integrator that runs every scene made
of dpm's built-in parts, so that a new scene starts without compiling.

A scene's own step module (:func:`dpm.plan.step_module`) is specialised to its contact
laws, boundary kinds, periodic axes and force form: the fastest code, but each new
combination compiles for about a minute. The universal module is the same template
(:mod:`dpm.kernels.step`) generated once per integrator with

- one contact law that picks its parts at run time: the pair row starts with the codes
  of the normal, tangential, adhesion and rolling parts and the history offsets of the
  last three, then each part's constants in a region of its own (:data:`REGIONS`); the
  scene's tables are repacked into this layout (:func:`universal_tables`);
- every built-in boundary kind, periodic wrapping on (a no-op on axes of zero period),
  the two-pass force sum (correct for every scene; sphere scenes fuse it when
  specialised).

Every part function is called with the same arguments as in the specialised law, so a
scene gives the same results bit for bit with either module (tested); only the speed
differs (the dispatch, the two-pass sum). :mod:`dpm.warm` decides which module a run
uses and compiles the specialised one in the background.
"""

from __future__ import annotations

from functools import lru_cache
from types import ModuleType

import numpy as np

#: the part kinds, in the order of their regions in the universal pair row
KINDS = ("normal", "tangential", "adhesion", "rolling")
#: header of the universal pair row: 4 part codes, the history offsets of the rolling,
#: normal and adhesion parts (the tangential part's is always 0)
HEADER = 7
#: the universal pair row's width (dpm.kernels.config.pair_row16)
WIDTH = 16


@lru_cache(maxsize=1)
def builtin_parts() -> dict[str, tuple]:
    """The parts of dpm's own impact models, per kind, in a fixed order (their codes:
    the index in the kind's tuple; 0 means "none" for the optional kinds, whose parts
    start at 1). Parts marked ``universal = False`` (JKR's: wider rows, detection at a
    separation) are left out: their scenes compile their own module."""
    from .impact.parts import Part
    from .plugins import registry

    found: dict[str, dict[tuple, Part]] = {k: {} for k in KINDS}
    reg = registry()
    for name in reg.names("impact_model"):
        cls = reg.lookup("impact_model", name)
        if not cls.__module__.startswith("dpm.") or cls.normal is None:
            continue
        parts = [cls.normal, cls.tangential, cls.adhesion,
                 *getattr(cls, "rolling_parts", {}).values()]
        for p in parts:
            if (isinstance(p, Part) and p.target()[0].startswith("dpm.")
                    and getattr(p, "universal", True)):
                found[p.kind].setdefault(p.key(), p)
    out = {}
    for kind in KINDS:
        ordered = tuple(found[kind][k] for k in sorted(found[kind], key=repr))
        out[kind] = ordered if kind == "normal" else (None, *ordered)
    return out


def regions() -> dict[str, int]:
    """Start of each kind's constants in the universal pair row."""
    parts = builtin_parts()
    start, out = HEADER, {}
    for kind in KINDS:
        out[kind] = start
        start += max([len(p.slots) for p in parts[kind] if p is not None] + [0])
    if start > WIDTH:
        raise RuntimeError(f"the universal pair row needs {start} slots; at most {WIDTH}")
    return out


def _code(kind: str, part) -> int | None:
    """The code of ``part`` (None: not a built-in part)."""
    for i, p in enumerate(builtin_parts()[kind]):
        if (p is None and part is None) or (p is not None and part is not None
                                            and p.key() == part.key()):
            return i
    return None


def covers(laws) -> bool:
    """Whether the universal law can stand for every law of a scene (composed laws of
    built-in parts only)."""
    from .impact.parts import LawSpec

    for law in laws:
        if not isinstance(law, LawSpec):
            return False
        by_kind = {p.kind: p for p in law.parts}
        if any(_code(kind, by_kind.get(kind)) is None for kind in KINDS):
            return False
    return True


def universal_tables(laws, pair_model: np.ndarray, pair_params: np.ndarray) -> np.ndarray:
    """The scene's pair constants repacked for the universal law: per material pair, the
    part codes, history offsets and each part's constants in its region."""
    reg = regions()
    nm = pair_model.shape[0]
    out = np.zeros((nm, nm, WIDTH))
    rows = []
    for law in laws:
        by_kind = {p.kind: p for p in law.parts}
        head = [float(_code(kind, by_kind.get(kind))) for kind in KINDS]
        head += [float(law.layout.offset.get(kind, 0))
                 for kind in ("rolling", "normal", "adhesion")]
        # each part's slots: (index in the scene's row, index in the universal row)
        moves = [(law.layout.slots[s], reg[p.kind] + i) for p in law.parts
                 for i, s in enumerate(p.slots)]
        rows.append((head, moves))
    for a in range(nm):
        for b in range(nm):
            head, moves = rows[int(pair_model[a, b])] if laws else ([0.0] * HEADER, [])
            out[a, b, :HEADER] = head
            for src, dst in moves:
                out[a, b, dst] = pair_params[a, b, src]
    return out


def law_lines() -> list[str]:
    """The bindings lines of the universal law (``pair_force``, ``pair_normal``, the
    16-wide ``pair_row``, ``ROLLING``), in the form :func:`dpm.plan.law_lines` gives a
    scene's laws."""
    from .plan import _LAW_ARGS, _NORMAL_ARGS, _wrap

    parts, reg = builtin_parts(), regions()
    imports = ["from .config import pair_row16 as pair_row"]
    for kind in KINDS:
        for code, p in enumerate(parts[kind]):
            if p is not None:
                mod, fn = p.target()
                imports.append(f"from {mod} import {fn} as {kind}_u{code}")

    def q(p) -> str:
        s = reg[p.kind]
        items = [f"p[{s + i}]" for i in range(len(p.slots))]
        return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"

    def chain(kind: str, code_slot: int, call) -> list[str]:
        """An if/elif chain over the kind's codes, ``call(p, code)`` giving each branch's
        lines (the "none" code has no branch)."""
        out, first = [], True
        for code, p in enumerate(parts[kind]):
            if p is None:
                continue
            last = kind == "normal" and code == len(parts[kind]) - 1
            if last and not first:
                out.append("    else:")
            else:
                out.append(f"    {'if' if first else 'elif'} p[{code_slot}] == {code}.0:")
            out += call(p, code)
            first = False
        return out

    #: per kind: (the call's left-hand side, its arguments after the constants)
    calls = {
        "normal": ("fn, kn =", "delta, ddelta, meff, reff, dt, hist, k, hn"),
        "tangential": ("ftx, fty, ftz =", "fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, "
                       "reff, dt, hist, k, 0"),
        "adhesion": ("fn = fn -", "delta, ddelta, meff, reff, dt, hist, k, ha"),
        "rolling": ("rx, ry, rz =", "fn, reff, meff, wx, wy, wz, dt, hist, k, hr"),
    }

    def call(p, code):
        lhs, args = calls[p.kind]
        return _wrap(f"{lhs} {p.kind}_u{code}", f"{q(p)}, {args}", "        ")

    offsets = ["    hr = int(p[4])", "    hn = int(p[5])", "    ha = int(p[6])"]
    body = ["", "ROLLING = True", "", "", "@inline_jit",
            *_wrap("def pair_force", f"model, {_LAW_ARGS}", "")]
    body[-1] += ":"
    body += ['    """F_n, F_t, rolling torque of the parts the row\'s codes name (p[0:4])."""',
             *offsets, "    fn = 0.0", "    kn = 0.0", *chain("normal", 0, call),
             "    ftx = 0.0", "    fty = 0.0", "    ftz = 0.0",
             *chain("tangential", 1, call), *chain("adhesion", 2, call),
             "    rx = 0.0", "    ry = 0.0", "    rz = 0.0", *chain("rolling", 3, call),
             "    return fn, ftx, fty, ftz, rx, ry, rz", "", "", "@inline_jit",
             f"def pair_normal(model, {_NORMAL_ARGS}):",
             '    """The normal force F_n of the parts the row\'s codes name."""',
             *offsets, "    fn = 0.0", "    kn = 0.0", *chain("normal", 0, call),
             *chain("adhesion", 2, call), "    return fn"]
    return imports + body + plan_attached_lines()


def plan_attached_lines() -> list[str]:
    """No universal part acts at a separation: ``RANGED`` False, ``pair_attached`` False."""
    from .plan import attached_lines

    return attached_lines({}, 1)


def universal_module(integrator_module: str) -> ModuleType:
    """Import (generating if needed) the universal step module of this integrator."""
    from . import plan
    from .boundaries.primitives import BUILTIN_CODES

    kinds = sorted(BUILTIN_CODES)
    lines = law_lines() + plan.integrator_lines(integrator_module)
    lines += plan._closest_lines(kinds, True, False, inline=False)
    parts = {p.target()[0] for ps in builtin_parts().values() for p in ps if p is not None}
    src = plan._splice("step.py", lines)
    # the laws and (inline=False above) the geometry dispatch compiled once each, called
    # (not inlined) from every loop: inlined at each call site of every driver they made
    # the module compile for ~8 minutes
    for name in ("pair_force", "pair_normal"):
        src = src.replace(f"@inline_jit\ndef {name}(", f"@jit\ndef {name}(")
    return plan._load(src, parts | {integrator_module}, "dpm_universal")
