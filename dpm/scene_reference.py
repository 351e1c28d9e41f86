"""The scene-file reference: every table and key, with its unit, default and range.

Rendered from the declarations the checks of :mod:`dpm.scene_file` use, so that it cannot
drift from them: the ``parameters`` the classes declare (:class:`dpm.Simulation`,
:class:`dpm.Material`, :class:`dpm.flow.Inlet`, and the registered boundaries, impact
models, motions, shapes and regions, plugins' included) and the keys of the file's own
(:data:`dpm.scene_file.SIMULATION_KEYS`, ...). Two renderings:

- :func:`markdown`: the page docs/scene-files.md, of the built-in classes only. It is
  written into the repository (so that it reads on the repository as on the site, as
  every page does) by ``python -m dpm.scene_reference --write docs/scene-files.md``;
  tests/io/test_scene_reference.py checks that the page equals a fresh rendering.
- :func:`text`: ``dpm run --reference [TABLE]`` in a terminal, plugins included.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .parameters import REQUIRED, Parameter

#: where the page lives in the repository
PAGE = Path(__file__).resolve().parents[1] / "docs" / "scene-files.md"


@dataclass
class Variant:
    """The keys of one kind of a table (``kind = "box"`` of [[boundaries]])."""

    name: str
    summary: str
    keys: dict[str, Parameter]
    source: str = ""


@dataclass
class Table:
    """A table of the scene file (or a table inside one, as ``motion`` or ``region``)."""

    name: str
    header: str
    call: str
    text: str
    keys: dict[str, Parameter]
    #: the key whose value picks a variant (``kind``), and the variants
    by: str = ""
    variants: list[Variant] = field(default_factory=list)


def _registered(kind: str, builtin_only: bool) -> list[Variant]:
    from .plugins import BUILTIN, registry

    reg = registry()
    out = []
    for name in reg.names(kind):
        entry = reg.entries[kind][name]
        if builtin_only and entry.source != BUILTIN:
            continue
        out.append(Variant(name, _summary(entry.cls),
                           dict(getattr(entry.cls, "parameters", {}) or {}),
                           "" if entry.source == BUILTIN else entry.source))
    return out


def _summary(cls: type) -> str:
    """The first sentence of a class's docstring (a literal block's ``::`` made ``.``)."""
    from .cli import summary_of

    text = summary_of(cls)
    return text[:-2] + "." if text.endswith("::") else text


def _names(kind: str, builtin_only: bool) -> list[str]:
    return [v.name for v in _registered(kind, builtin_only)]


def tables(builtin_only: bool = False) -> list[Table]:
    """Every table of a scene file, in the order of the page."""
    from . import scene_file as sf
    from .distributions import DISTRIBUTIONS

    def dist_variants() -> list[Variant]:
        return [Variant(n, _summary(c), dict(c.parameters)) for n, c in
                DISTRIBUTIONS.items()]

    return [
        Table("simulation", "[simulation]", "dpm.Simulation(...)",
              "The simulation: time step, gravity, integrator, backend. Required.",
              sf.simulation_keys()),
        Table("materials", "[materials.NAME]", "dpm.Material(NAME, ...)",
              "One table per material; the other tables name it by NAME.",
              sf.material_keys()),
        Table("contacts", "[[contacts]]", "sim.contact(a, b, model, ...)",
              "The contact law of a material pair (particle-particle and particle-wall "
              "alike): the keys below and those of its model.",
              dict(sf.CONTACT_KEYS), "model", _registered("impact_model", builtin_only)),
        Table("boundaries", "[[boundaries]]", "sim.add_boundary(kind, material=..., ...)",
              "A wall: the keys below and those of its kind. A mesh's file is relative to "
              "the scene file.", dict(sf.BOUNDARY_KEYS), "kind",
              _registered("boundary", builtin_only)),
        Table("motion", "motion = { type = NAME, ... }", "dpm.motion.NAME(...)",
              "A boundary's prescribed motion, an inline table of [[boundaries]] (or a "
              "list of them, applied in order): the keys below and those of its type.",
              dict(sf.MOTION_KEYS), "type", _registered("motion", builtin_only)),
        Table("periodic", "[[periodic]]", "sim.set_periodic(axis, lower, upper)",
              "A periodic axis.", dict(sf.PERIODIC_KEYS)),
        Table("particles", "[[particles]]", "sim.add_particles(shape, material=..., ...)",
              "Bodies placed at start: exactly one of csv, lattice and positions, the keys "
              "below and those of the shape. A shape's size key takes one value or one "
              "per body.", dict(sf.PARTICLE_OWN), "shape", _registered("shape", builtin_only)),
        Table("lattice", "lattice = { ... }", "dpm.lattice(...)",
              "The positions of a [[particles]] table on a simple cubic lattice.",
              sf.lattice_keys()),
        Table("inlets", "[[inlets]]", "sim.add_inlet(region, material, ...)",
              "Bodies inserted during the run: the keys below and those of the shape (as "
              "in [[particles]]), or a mix in shapes. A size key of the shape takes a "
              "value, a pair [low, high] (uniform between) or a distribution table.",
              sf.inlet_keys()),
        Table("shapes", "shapes = [{ ... }, ...]", "sim.add_inlet(..., shapes=[...])",
              "An entry of an inlet's mix of shapes: the keys below and those of the "
              "shape.", dict(sf.SHAPE_MIX_KEYS)),
        Table("region", "region = { NAME = { ... } }", "dpm.regions (BoxRegion, ...)",
              "Where an inlet inserts or an outlet removes: a one-key inline table naming "
              "a registered region (outlets: a region with a volume).", {}, "NAME",
              _registered("region", builtin_only)),
        Table("distributions", "radius = { NAME = { ... } }", "dpm.distributions",
              "A size distribution of an inlet's shape key: a one-key inline table. The "
              f"sizes ({', '.join(sf.DISTRIBUTION_SIZES)}) are in the unit of the key.",
              {}, "NAME", dist_variants()),
        Table("outlets", "[[outlets]]", "sim.add_outlet(region, ...)",
              "Bodies removed (and recorded) during the run.", dict(sf.OUTLET_KEYS)),
        Table("output", "[output]", "sim.output(path, ...)",
              "The HDF5 + XDMF output file (docs/output-format.md).", dict(sf.OUTPUT_KEYS)),
        Table("run", "[run]", "sim.run(...)",
              "How long to run (dpm run --steps / --until override it).", dict(sf.RUN_KEYS)),
        Table("checkpoint", "[checkpoint]", "sim.checkpoint_every(path, ...)",
              "Checkpoints during the run (dpm run --checkpoint-every and --checkpoint "
              "override it; docs/reliability.md).", dict(sf.CHECKPOINT_KEYS)),
    ]


#: keys whose value is a registered name: (table, key) -> registry kind ("*": any table)
_REGISTRY_KEYS = {("simulation", "integrator"): "integrator", ("simulation", "device"): "backend",
                  ("contacts", "model"): "impact_model", ("boundaries", "kind"): "boundary",
                  ("motion", "type"): "motion", ("particles", "shape"): "shape",
                  ("inlets", "shape"): "shape", ("shapes", "shape"): "shape",
                  ("*", "rolling_model"): "rolling_model"}


def _choices(table: str, key: str, builtin_only: bool) -> list[str] | None:
    kind = _REGISTRY_KEYS.get((table, key)) or _REGISTRY_KEYS.get(("*", key))
    if kind:
        return _names(kind, builtin_only)
    if (table, key) == ("simulation", "dt_check"):
        from .simulation import DT_CHECKS

        return list(DT_CHECKS)
    if (table, key) == ("outlets", "remove"):
        return ["inside", "outside"]
    if (table, key) == ("periodic", "axis"):
        return ["x", "y", "z"]
    return None


def fmt_default(p: Parameter) -> str:
    """A key's default as TOML writes it (``required``; ``unset``: the call's None)."""
    return "required" if p.default is REQUIRED else _toml(p.default)


def _toml(v: Any) -> str:
    if v is None:
        return "unset"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "inf" if v == math.inf else "-inf" if v == -math.inf else f"{v:g}"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return str(v)


def fmt_unit(p: Parameter) -> str:
    """The key's unit; ``1`` for a plain number, empty for a name or a flag."""
    if p.unit:
        return p.unit
    return "1" if p.kind in ("float", "int", "vector") else ""


def fmt_allowed(p: Parameter, choices: list[str] | None = None) -> str:
    """What the key takes: a range, 3 numbers, true or false, the registered names."""
    if choices:
        return "one of " + ", ".join(choices)
    if p.kind == "vector":
        return "3 numbers"
    if p.kind == "bool":
        return "true or false"
    if p.kind in ("float", "int"):
        what = "integer" if p.kind == "int" else "number"
        bounded = p.low != -math.inf or p.high != math.inf
        text = f"{what} in {p.interval()}" if bounded else f"any {what}"
        if p.allow_inf:
            text += ", inf"
        return text + (" (or one per body)" if p.array else "")
    if p.kind == "str":
        return "text"
    return ""


#: ranges that depend on the machine, as the page writes them (the same everywhere)
_MACHINE = {("simulation", "threads"): "integer in [1, NUMBA_NUM_THREADS] (the cores)"}


def rows(table: str, keys: Mapping[str, Parameter], builtin_only: bool = False
         ) -> list[tuple[str, str, str, str, str]]:
    """(key, unit, default, allowed, meaning) of each key (``builtin_only``: the page's
    rendering, the same on every machine: built-in names only, no machine's ranges)."""
    from .scene_file import DISTRIBUTION_SIZES

    return [(k, "the key's" if table == "distributions" and k in DISTRIBUTION_SIZES
             else fmt_unit(p), fmt_default(p),
             (builtin_only and _MACHINE.get((table, k)))
             or fmt_allowed(p, _choices(table, k, builtin_only)),
             p.doc) for k, p in keys.items()]


# ---- Markdown (docs/scene-files.md) ----------------------------------------------------

def _md_cell(text: str) -> str:
    for c in "\\|*$<":
        text = text.replace(c, "\\" + c)
    return text


def _md_table(table: str, keys: Mapping[str, Parameter], builtin_only: bool) -> list[str]:
    if not keys:
        return ["No keys of its own."]
    out = ["| key | unit | default | allowed | meaning |", "|---|---|---|---|---|"]
    for key, unit, default, allowed, doc in rows(table, keys, builtin_only):
        out.append(f"| `{key}` | {_md_cell(unit)} | `{default}` | {_md_cell(allowed)} | "
                   f"{_md_cell(doc)} |")
    return out


_INTRO = """\
# Scene files

<!-- Generated from the declarations the checks use (dpm/scene_file.py and the classes'
`parameters`) by `python -m dpm.scene_reference --write docs/scene-files.md`: edit those,
not this page. tests/io/test_scene_reference.py checks that it is up to date. -->

A scene file is the Python API written down in TOML: each table mirrors a call and its
keys are the call's keyword arguments (`[simulation]` is `dpm.Simulation(...)`,
`[[boundaries]]` is `sim.add_boundary(...)`). `examples/box_settle.toml` is one:

    dpm run examples/box_settle.toml

The tables and keys of the whole file are checked before anything is built: every
unknown key is named with the keys its table takes, every value of the wrong unit with
the unit, each with the file and the line. A value a call refuses while the scene is built
(out of its range) is named the same way, before any step. This page lists every table
and key, with its unit, default and allowed values; `dpm run --reference [TABLE]` prints
the same in a terminal (with plugins' kinds).

## Running a scene file

    dpm run scene.toml [--steps N | --until T] [--set PATH=VALUE ...] [--overwrite]
                       [--checkpoint-every SECONDS] [--checkpoint PATH] [--restart CKPT]
    dpm run --reference [TABLE]      # the tables below, or one (boundaries, boundaries.box)
    dpm sweep scene.toml --set PATH=V1,V2,... [--set ...] [--jobs N] [--out DIR]
                         [--steps N | --until T] [--overwrite] [--csv FILE]

`--set PATH=VALUE` (repeatable) changes one value of the parsed file before it is
checked and built. `PATH` is `TABLE.KEY`, `ARRAY[N].KEY` or deeper
(`simulation.dt`, `contacts[0].friction`, `materials.glass.young`,
`boundaries[1].motion.rpm`, `inlets[0].region.box.lower`); `VALUE` is a TOML value (`0.3`,
`[0, 0, -9.81]`, `true`, `"gear4"`; a number in quotes is the number, as the shell's
quotes and TOML's cannot be told apart), or else taken as text (`gear4`, `2 mm`). A path whose
tables do not exist is refused with what exists there; a new last key is checked like any
other. The output file records the edits (`run.scene_toml`).

`dpm sweep` runs the scene once for every combination of the values given as
`--set PATH=V1,V2,...` (the product of all of them; commas inside brackets or quotes do
not split) on a pool of `--jobs` processes. Each run writes its own output file and
checkpoints (where the scene has `[output]`, `[checkpoint]`), named after the `[output]`
file and the values (`run-friction=0.3.h5`), in `--out`. Every combination is checked
before the first run starts. The sweep prints a table of the values with each run's
steps, simulated time, wall time, particles, kinetic energy and mean height of the
particles, or its error (`--csv FILE` writes the table); its exit status is 1 if a run
failed.
"""

_VALUES = """\
## Values: units and expressions

A number is written as a TOML number in the key's unit (the unit column below: SI, except
where a key says otherwise, as `rpm` in 1/min). A string where a number goes is a
quantity, converted to the key's unit:

```toml
dt = "10 us"
young = "5 MPa"
density = "2.5 g/cm3"
radius = "2 mm / 2"
gravity = [0, 0, "-9.81 m/s2"]
angle = "30 deg"                     # a key in rad: 0.5236
amplitude = [0, 0, "sin(30 deg) * 2 mm"]
rpm = "0.5 Hz"                       # 30 (turns per minute)
omega = "30 rev/min"                 # 3.1416 rad/s
```

A quantity of another dimension than the key's is refused by name
(`radius = "30 deg"`: an angle where a length goes). Angles are a dimension of their
own, so an angle is never taken for a plain number (`friction = "30 deg"` is refused;
`friction = "tan(30 deg)"` is 0.577). `rpm` and `Hz` count turns and cycles (1/s), not
an angle per time: an angular speed (`omega`, rad/s) takes `"30 rev/min"`, not
`"30 rpm"`. An expression without a unit (`"pi / 6"`, `"sqrt(2) * 1e-3"`) is a number in
the key's own unit; a string that is only a number (`"30"`, `"1 - 0.5"`) is refused, as
a number quoted by mistake. Text keys (names of shapes, models, materials) stay text, and
so does a single word where a number goes (`dt = "auto"`): the call judges it. Values are
read to 15 significant digits (`"30 deg"` in a key in deg is 30).

The grammar (a number is `1`, `2.5`, `.5`, `1e-3`; a unit may carry its power, `m3`,
`s^2`, `s**-1`; a number followed by units is one quantity, so `"2 mm / 1 m"` is 0.002 and
`"1 / 2 s"` is 0.5 per second):

    expression := term (("+" | "-") term)*
    term       := factor (("*" | "/") factor)*
    factor     := ("+" | "-") factor | atom [("**" | "^") factor]
    atom       := number [unit ...] | unit | "pi" | function "(" expression ")"
                | "(" expression ")"

The text is parsed with Python's `ast` and only these nodes are evaluated (no other
name, attribute, call or operator), so a scene file runs no code. The functions are
`sin`, `cos`, `tan` (of an angle, or of a plain number in radians) and `sqrt`; the
constant is `pi`. The units:
"""


def markdown(builtin_only: bool = True) -> str:
    """The page docs/scene-files.md (built-in kinds only: the page is the same wherever it
    is rendered)."""
    from .units import units_table

    out = [_INTRO, _VALUES, "| unit | value | measures |", "|---|---|---|"]
    out += [f"| `{u}` | {_md_cell(si)} | {_md_cell(what)} |" for u, si, what in units_table()]
    out += ["", "## Tables", "",
            "The forms: `[name]` is a single table, `[[name]]` one entry of an array of "
            "tables (write one per entry), `[materials.NAME]` one table per name; `key = { "
            "... }` is an inline table. Default `unset`: the key is optional and the call "
            "decides without it (one of two keys, as `every` or `every_steps`). Unit `1`: a "
            "plain number.", ""]
    for t in tables(builtin_only):
        out += [f"### `{t.header}`", "", f"{t.text} Mirrors `{t.call}`.", ""]
        out += _md_table(t.name, t.keys, builtin_only)
        out.append("")
        for v in t.variants:
            out += [f"#### {t.name}: `{t.by} = {v.name}`" if t.by not in ("NAME",)
                    else f"#### {t.name}: `{v.name}`", ""]
            if v.summary:
                out += [_md_cell(v.summary), ""]
            out += _md_table(t.name, v.keys, builtin_only)
            out.append("")
    return "\n".join(out).rstrip() + "\n"


# ---- text (dpm run --reference) --------------------------------------------------------

def _text_table(table: str, keys: Mapping[str, Parameter], indent: str) -> list[str]:
    if not keys:
        return [f"{indent}(no keys of its own)"]
    body = [("key", "unit", "default", "allowed", "meaning"), *rows(table, keys)]
    w = [max(len(r[i]) for r in body) for i in range(4)]
    return [indent + "  ".join(f"{r[i]:<{w[i]}}" for i in range(4)) + "  " + r[4]
            for r in body]


def index() -> str:
    """One line per table: what ``dpm run --help`` lists."""
    ts = tables()
    w1, w2 = max(len(t.name) for t in ts), max(len(t.header) for t in ts)
    return "\n".join(f"  {t.name:<{w1}}  {t.header:<{w2}}  {t.call}" for t in ts)


def names() -> list[str]:
    """What ``dpm run --reference`` takes: the tables, ``TABLE.VARIANT`` and ``units``."""
    out = []
    for t in tables():
        out.append(t.name)
        out += [f"{t.name}.{v.name}" for v in t.variants]
    return [*out, "units"]


def text(name: str | None = None) -> str:
    """The reference in plain text: every table, one (``boundaries``), one variant
    (``boundaries.box``) or the units (``units``); ParameterError for another name, with
    the names there are."""
    import difflib

    from .errors import ParameterError
    from .units import CONSTANTS, FUNCTIONS, units_table

    if name == "units":
        w = max(len(u) for u, _, _ in units_table())
        return "\n".join([f"  {u:<{w}}  {si:<22} {what}" for u, si, what in units_table()]
                         + [f"constants: {', '.join(CONSTANTS)}; functions: "
                            f"{', '.join(FUNCTIONS)} (docs/scene-files.md: the grammar)"])
    table, _, variant = (name or "").partition(".")
    chosen = [t for t in tables() if name is None or t.name == table]
    if not chosen or (variant and not any(v.name == variant for v in chosen[0].variants)):
        close = difflib.get_close_matches(name or "", names(), n=1)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise ParameterError(f"dpm run --reference {name}: no such table{hint}; tables: "
                             f"{', '.join(t.name for t in tables())}, units (and "
                             "TABLE.KIND, e.g. boundaries.box)")
    out: list[str] = []
    for t in chosen[:1] if variant else chosen:
        if not variant:
            out += [f"{t.header}    {t.call}", f"  {t.text}"]
            out += _text_table(t.name, t.keys, "  ")
        for v in t.variants:
            if variant and v.name != variant:
                continue
            by = f' ({t.by} = "{v.name}")' if t.by != "NAME" else ""
            src = f" [{v.source}]" if v.source else ""
            out += ["", f"  {t.name}.{v.name}{by}{src}: {v.summary}"]
            out += _text_table(t.name, v.keys, "    ")
        out.append("")
    return "\n".join(out).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    """``python -m dpm.scene_reference [--write PAGE | --check PAGE]``."""
    p = argparse.ArgumentParser(prog="python -m dpm.scene_reference",
                                description="render the scene-file reference page")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--write", metavar="PAGE", help="write the page (docs/scene-files.md)")
    g.add_argument("--check", metavar="PAGE", help="exit 1 if the page is out of date")
    args = p.parse_args(argv)
    page = markdown()
    if args.write:
        Path(args.write).write_text(page, encoding="utf-8")
        return 0
    if args.check:
        same = Path(args.check).read_text(encoding="utf-8") == page
        if not same:
            print(f"{args.check} is out of date: python -m dpm.scene_reference --write "
                  f"{args.check}", file=sys.stderr)
        return 0 if same else 1
    sys.stdout.write(page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
