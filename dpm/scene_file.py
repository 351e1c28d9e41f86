"""A TOML scene file read and checked as a whole before anything is built.

:func:`read_scene` returns the parsed document of a scene file (layout in
:mod:`dpm.io.scene`; every table and key in :mod:`dpm.scene_reference`, rendered as
docs/scene-files.md and by ``dpm run --reference``) after checking, per table, its form
(``[simulation]``, ``[output]``, ``[run]``, ``[checkpoint]`` single tables;
``[materials.NAME]`` tables of tables; ``[[contacts]]``, ``[[boundaries]]``,
``[[particles]]``, ``[[periodic]]``, ``[[inlets]]``, ``[[outlets]]`` arrays of tables) and
its keys against the parameters of the call it mirrors: the ``parameters`` the classes
declare (:class:`dpm.parameters.Parameter`) and, for the keys of the file's own, the
tables declared here (:data:`SIMULATION_KEYS`, :data:`CONTACT_KEYS`, ...). Every problem
found is listed in one :class:`~dpm.errors.ParameterError`, each with the file and, where
it can be told, the line; each unknown key with the keys allowed in that table.

Strings where a key takes a number are quantities with units or expressions
(``radius = "2 mm"``, ``angle = "sin(30 deg)"``; :mod:`dpm.units`), converted to the key's
declared unit (:func:`convert_values`); a quantity of another dimension is refused by
name. ``dpm run --set PATH=VALUE`` edits the parsed document before the checks
(:func:`apply_set`). Values are otherwise checked by the calls themselves when the scene
is built.
"""

from __future__ import annotations

import difflib
import re
import reprlib
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from .errors import DpmError, ParameterError
from .parameters import Parameter

SINGLE = ("simulation", "output", "run", "checkpoint")
ARRAYS = ("contacts", "boundaries", "particles", "periodic", "inlets", "outlets")
TABLES = ("materials",)
#: deepest nesting of arrays and inline tables a scene file may have (its own ones: 5)
MAX_DEPTH = 64
#: characters of a value a message echoes (a longer one is cut, with its length)
ECHO = 80
#: what a [[particles]] table's csv file holds
CSV_FORM = "comma-separated numbers in columns x,y,z[,vx,vy,vz[,r]] under one header line"

# ---- the keys of the file's own (the rest are the parameters the classes declare) ----

_NAME = "a registered name"
#: [simulation]: dpm.Simulation's parameters and these
SIMULATION_KEYS = {
    "device": Parameter(default=None, kind="str", doc="the backend, a registered name "
                        "(default: mpi under mpiexec on several ranks, else cpu)"),
}
#: [[contacts]]: the impact model's parameters and these
CONTACT_KEYS = {
    "materials": Parameter(kind="any", doc='the pair, two material names: ["a", "b"]'),
    "model": Parameter(default="hertz_mindlin", kind="str", doc="the impact model, " + _NAME),
}
#: [[boundaries]]: the boundary kind's parameters and these
BOUNDARY_KEYS = {
    "kind": Parameter(kind="str", doc="the boundary kind, " + _NAME),
    "material": Parameter(kind="str", doc="a material name"),
    "motion": Parameter(default=None, kind="any", doc="a motion table "
                        '{ type = "rotation", ... } or a list of them (applied in order)'),
    "switch_off": Parameter(default=None, low=0.0, unit="s",
                            doc="switched off at this time (sim.switch_off)"),
    "switch_on": Parameter(default=None, low=0.0, unit="s",
                           doc="switched on at this time (sim.switch_on)"),
}
#: a motion table: the motion type's parameters and these
MOTION_KEYS = {"type": Parameter(kind="str", doc="the motion type, " + _NAME)}
#: [[periodic]]: sim.set_periodic's arguments
PERIODIC_KEYS = {
    "axis": Parameter(kind="str", doc="x, y or z"),
    "lower": Parameter(unit="m", doc="lower end of the period"),
    "upper": Parameter(unit="m", doc="upper end of the period"),
}
#: [[inlets]]: dpm.Inlet's parameters, these, and the shape's parameters (without shapes)
INLET_KEYS = {
    "material": Parameter(kind="str", doc="a material name"),
    "region": Parameter(kind="any", doc="where bodies are inserted: { NAME = {...} }, a "
                        "registered region"),
    "shapes": Parameter(default=None, kind="any", doc="a mix: a list of tables "
                        '{ shape = "name", fraction = f, ... } instead of shape'),
}
#: an entry of an inlet's shapes list: these and the shape's parameters
SHAPE_MIX_KEYS = {
    "shape": Parameter(default="sphere", kind="str", doc="the shape, " + _NAME),
    "fraction": Parameter(default=1.0, low=0.0, doc="share of the bodies (by number)"),
}
#: [[outlets]]: sim.add_outlet's arguments
OUTLET_KEYS = {
    "region": Parameter(kind="any", doc="where bodies are removed: { NAME = {...} }, a "
                        "registered region with a volume"),
    "remove": Parameter(default="inside", kind="str", doc="inside or outside"),
    "every": Parameter(default=1e-3, low=0.0, low_open=True, unit="s",
                       doc="interval of the removals"),
    "name": Parameter(default="", kind="str", doc="label in the output"),
}
#: [[particles]]: these and the shape's parameters
PARTICLE_OWN = {
    "shape": Parameter(default="sphere", kind="str", doc="the shape, " + _NAME),
    "material": Parameter(kind="str", doc="a material name"),
    "csv": Parameter(default=None, kind="str", doc="a file of " + CSV_FORM + ", relative "
                     "to the scene file"),
    "lattice": Parameter(default=None, kind="any",
                         doc="a table { lower, upper, spacing, ... } (dpm.lattice)"),
    "positions": Parameter(default=None, kind="any", unit="m", doc="[[x, y, z], ...]"),
    "velocities": Parameter(default=None, kind="any", unit="m/s", doc="[[vx, vy, vz], ...]"),
    "angular_velocities": Parameter(default=None, kind="any", unit="rad/s",
                                    doc="[[wx, wy, wz], ...]"),
    "orientations": Parameter(default=None, kind="any",
                              doc="unit quaternions [[w, x, y, z], ...]"),
}
#: keys a [[particles]] table takes besides its shape's parameters
PARTICLE_KEYS = tuple(PARTICLE_OWN)
#: [output]: sim.output's arguments
OUTPUT_KEYS = {
    "path": Parameter(default="SCENE.h5", kind="str", doc="the HDF5 file, relative to the "
                      "working directory (default: the scene file's name)"),
    "every": Parameter(default=None, low=0.0, low_open=True, unit="s",
                       doc="interval of the frames (or every_steps)"),
    "every_steps": Parameter(default=None, low=1, kind="int",
                             doc="interval of the frames in steps (or every)"),
    "overwrite": Parameter(default=False, kind="bool", doc="replace an existing file "
                           "(dpm run --overwrite)"),
    "fields": Parameter(default=(), kind="any", doc='optional per-particle fields: a list '
                        'of names, or "all"'),
    "contacts": Parameter(default=False, kind="bool", doc="write the touching pairs"),
    "solids": Parameter(default=False, kind="bool", doc="write the clustered bodies' solids"),
}
#: [run]: sim.run's arguments (dpm run --steps / --until override them)
RUN_KEYS = {
    "steps": Parameter(default=None, low=0, kind="int", doc="steps to run (or until)"),
    "until": Parameter(default=None, low=0.0, unit="s", doc="simulated time to run to"),
}
#: [checkpoint]: sim.checkpoint_every's arguments (dpm run --checkpoint-every overrides)
CHECKPOINT_KEYS = {
    "path": Parameter(default="SCENE.ckpt.h5", kind="str", doc="base name of the numbered "
                      "checkpoint files, relative to the working directory (default: the "
                      "scene file's name)"),
    "every": Parameter(default=None, low=0.0, low_open=True, unit="s",
                       doc="interval in simulated time (or every_steps)"),
    "every_steps": Parameter(default=None, low=1, kind="int",
                             doc="interval in steps (or every)"),
    "keep": Parameter(default=2, low=1, kind="int", doc="the last ones kept"),
}
#: the keys of a size distribution table (``radius = { normal = {...} }``) that are sizes:
#: in the unit of the shape's parameter they stand for
DISTRIBUTION_SIZES = ("mean", "std", "low", "high", "median", "edges")


def simulation_keys() -> dict[str, Parameter]:
    """Every key of [simulation]: dpm.Simulation's parameters and :data:`SIMULATION_KEYS`."""
    from .simulation import Simulation

    return {**Simulation.parameters, **SIMULATION_KEYS}


def material_keys() -> dict[str, Parameter]:
    """Every key of a [materials.NAME] table: dpm.Material's parameters."""
    from .material import Material

    return dict(Material.parameters)


def inlet_keys() -> dict[str, Parameter]:
    """The keys of an [[inlets]] table besides its shape's: :data:`INLET_KEYS` and
    dpm.Inlet's parameters."""
    from .flow import Inlet

    return {**INLET_KEYS, **Inlet.parameters}


def lattice_keys() -> dict[str, Parameter]:
    """The keys of a [[particles]] table's lattice table: dpm.lattice's arguments."""
    from .scene_tools import _LATTICE

    return dict(_LATTICE)


def registered(kind: str, name: Any) -> type | None:
    """The registered class of ``kind`` called ``name`` (None: none)."""
    from .plugins import registry

    if not isinstance(name, str):
        return None
    try:
        return registry().lookup(kind, name, "")
    except DpmError:
        return None


def declared(cls: type | None) -> dict[str, Parameter]:
    """A registered class's declared ``parameters`` (none for None)."""
    return dict(getattr(cls, "parameters", {}) or {}) if cls is not None else {}


def read_scene(path: str | Path, sets: Sequence[str] = ()) -> dict[str, Any]:
    """Parse the scene file at ``path``, apply the edits ``sets`` (``"PATH=VALUE"``, as
    ``dpm run --set``: :func:`apply_set`), check its tables and keys and convert its
    quantities (:func:`convert_values`); return the document.

    Raises ParameterError for a missing or unreadable file, invalid TOML, an edit of a
    path that does not exist, a table of the wrong form, unknown keys (all of them, named
    per table with the allowed ones) and values that are not quantities of the key's
    unit; each problem names the file and, where it can be told, its line.
    """
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"{path}: the scene file does not exist"
                             + (" (it is a directory)" if path.is_dir() else ""))
    too_deep = (f"{path}: arrays or tables nested more than {MAX_DEPTH} deep; allowed: at "
                f"most {MAX_DEPTH} levels")
    try:
        text = path.read_text(encoding="utf-8")
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML: {exc}{_line_of(path, exc)}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{path}: the scene file could not be read: {exc}") from None
    except RecursionError:  # tomllib parses nested arrays and inline tables recursively
        raise ParameterError(too_deep) from None
    edits = [apply_set(doc, s, f"{path}: ") for s in sets]
    if _depth(doc) > MAX_DEPTH:
        raise ParameterError(too_deep)
    problems = scene_problems(doc, path.parent)
    if not problems:  # (the values of keys of unknown tables cannot be told apart)
        problems = convert_values(doc)
    if problems:
        lines = text.splitlines()
        raise ParameterError("\n".join(f"{path}: {m}{_where(lines, m, edits)}"
                                       for m in problems))
    return doc


def _where(lines: list[str], message: str, edits: Sequence[tuple[str, str]]) -> str:
    """Where a problem comes from (:func:`origin`) for a message about a key (``WHERE:
    KEY = ...``); empty for another message."""
    m = _KEYED.match(message)
    return origin(lines, m.group("where"), m.group("key"), edits) if m else ""


def origin(lines: list[str], where: str, key: str | None,
           edits: Sequence[tuple[str, str]] = ()) -> str:
    """`` (set on the command line: --set PATH=VALUE)`` for the ``key`` of the table
    ``where`` given by one of ``edits`` (:func:`apply_set`'s results), else `` (line N)``,
    the line of the key in the file (or of its table's header; :func:`line_of`), else
    empty."""
    for first, text in edits:
        last = text.split("=", 1)[0].rsplit(".", 1)[-1].split("[")[0].strip().strip('"')
        if key == last and where.startswith(first):
            return f" (set on the command line: --set {text})"
    line = line_of(lines, where, key)
    return "" if line is None else f" (line {line})"


def edit_table(text: str) -> tuple[str, str]:
    """(the table an edit ``PATH=VALUE`` changes, as the checks name it, ``text``), as
    :func:`apply_set` returns; ParameterError for a path of another form."""
    parts = parse_path(text.split("=", 1)[0].strip())
    return _table_name(parts), text


def _depth(doc: dict[str, Any]) -> int:
    """The deepest nesting of tables and arrays in a parsed document (without recursion;
    it stops counting beyond :data:`MAX_DEPTH`)."""
    deepest = 0
    stack: list[tuple[Any, int]] = [(doc, 0)]
    while stack and deepest <= MAX_DEPTH:
        value, level = stack.pop()
        if isinstance(value, dict):
            value = list(value.values())
        if isinstance(value, list):
            deepest = max(deepest, level)
            stack.extend((v, level + 1) for v in value)
    return deepest


# a repr whose first ECHO characters are those of the full one, of bounded length
_REPR = reprlib.Repr()
_REPR.maxlevel = ECHO
_REPR.maxlist = _REPR.maxdict = ECHO // 2
_REPR.maxstring = _REPR.maxother = 4 * ECHO


def echo(value: Any) -> str:
    """``repr(value)`` for a message, on one line: beyond :data:`ECHO` characters cut
    there, followed by ``...`` and the value's length (the full repr is never built)."""
    text = _REPR.repr(value)
    if len(text) <= ECHO:
        return text
    size = (f" ({len(value):,} characters)" if isinstance(value, str)
            else f" ({len(value):,} item{'s' * (len(value) != 1)})"
            if isinstance(value, list | dict) else "")
    return f"{text[:ECHO]}...{size}"


_HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\"-]+)\s*\]\]?")
#: a message about a key: ``WHERE: [unknown key ]KEY = VALUE...`` or ``WHERE: KEY=VALUE``
_KEYED = re.compile(r"^(?P<where>.*?): (?:unknown key )?(?P<key>[A-Za-z_][\w-]*) ?= ")


def where_in_file(lines: list[str], message: str) -> str:
    """`` (line N)`` for a message about a key (``WHERE: KEY = ...``, ``WHERE: unknown
    key KEY = ...``): the line of the key in the table the message names
    (``[simulation]``, ``[materials.glass]``, ``boundaries[1]``, ``the file``; an inline
    table's key on its line); empty where it cannot be told."""
    m = _KEYED.match(message)
    if not m:
        return ""
    line = line_of(lines, m.group("where"), m.group("key"))
    return "" if line is None else f" (line {line})"


def line_of(lines: list[str], where: str, key: str | None = None) -> int | None:
    """The line (from 1) of ``key`` in the table ``where`` names (``[simulation]``,
    ``[materials.glass]``, ``boundaries[1]``, ``contacts[0]: motion``, ``the file``), or of
    the table's header when ``key`` is None or not found there; None where neither can be
    told."""
    # sections: (header, name, occurrence of an [[array]] name, first line, end line)
    sections: list[list] = [["", "", 0, 0, len(lines)]]
    seen: dict[str, int] = {}
    for i, text in enumerate(lines):
        h = _HEADER.match(text)
        if h:
            sections[-1][4] = i
            name = h.group(2)
            k = seen.get(name, 0)
            if h.group(1) == "[[":
                seen[name] = k + 1
            sections.append([h.group(1), name, k, i + 1, len(lines)])
    wanted = None
    arr = re.match(r"^(\w+)\[(\d+)\]", where)
    if where.startswith("the file"):
        wanted = sections[0]
    elif where.startswith("["):
        name = where[1:where.find("]")]
        wanted = next((s for s in sections if s[0] == "[" and s[1] == name), None)
    elif arr:
        wanted = next((s for s in sections if s[0] == "[[" and s[1] == arr.group(1)
                       and s[2] == int(arr.group(2))), None)
    if key is not None:
        pat = re.compile(r"(^|[{,]\s*)" + re.escape(key) + r"\s*=")
        spans = [(wanted[3], wanted[4])] if wanted else []
        for lo, hi in spans + [(0, len(lines))]:
            hits = [i for i in range(lo, hi) if pat.search(lines[i].split("#")[0].strip())]
            if len(hits) == 1 or (hits and (lo, hi) != (0, len(lines))):
                return hits[0] + 1
    if wanted is not None and wanted[3] > 0:
        return wanted[3]  # the header's line
    return None


def _line_of(path: Path, exc: Exception) -> str:
    """The text of the line a TOML error names (so that the key is in the message)."""
    import re

    m = re.search(r"line (\d+)", str(exc))
    if not m:
        return ""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
        return f"; line {m.group(1)}: {echo(lines[int(m.group(1)) - 1].strip())}"
    except (OSError, IndexError):
        return ""


def _unknown(where: str, table: dict, allowed: Iterable[str]) -> list[str]:
    allowed = sorted(set(allowed))
    out = []
    for k in table:
        if k not in allowed:
            close = difflib.get_close_matches(k, allowed, n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            out.append(f"{where}: unknown key {k} = {echo(table[k])}{hint}; allowed: "
                       f"{', '.join(allowed)}")
    return out


def _misspelt(where: str, table: dict, base: Iterable[str], kind: str = "") -> list[str]:
    """Keys that no registered ``kind`` (boundary, shape, impact model) takes and that are
    not in ``base``, when the table's own kind is missing or unknown and the rest of the
    table cannot be checked exactly."""
    from .plugins import registry

    base = list(base)
    known = set(base)
    if kind:
        reg = registry()
        for name in reg.names(kind):
            known.update(getattr(reg.lookup(kind, name, where), "parameters", {}))
    out = []
    for k in table:
        if k in known:
            continue
        close = difflib.get_close_matches(k, sorted(known), n=1)
        hint = f" (did you mean {close[0]}?)" if close else ""
        out.append(f"{where}: unknown key {k} = {echo(table[k])}{hint}")
    return out


def _params(kind: str, name: Any, where: str) -> tuple[list[str], list[str]]:
    """(parameter names, problems) of the registered ``kind`` called ``name``."""
    from .plugins import registry

    if not isinstance(name, str):
        return [], [f"{where}: {echo(name)} must be a registered {kind.replace('_', ' ')} name"]
    try:
        cls = registry().lookup(kind, name, where)
    except DpmError as exc:
        return [], [str(exc)]
    return list(getattr(cls, "parameters", {})), []


def _region(where: str, spec: Any) -> list[str]:
    from .plugins import registry

    reg = registry()
    names = reg.names("region")
    if not isinstance(spec, dict) or len(spec) != 1 or next(iter(spec)) not in names:
        return [f"{where}: region = {echo(spec)} must be one of "
                + ", ".join(f"{{ {n} = {{...}} }}" for n in names)]
    kind, kw = next(iter(spec.items()))
    if not isinstance(kw, dict):
        return [f"{where}: region.{kind} = {echo(kw)} must be a table"]
    return _unknown(f"{where}: region.{kind}", kw,
                    getattr(reg.lookup("region", kind, where), "parameters", {}))


def _motion(where: str, spec: Any) -> list[str]:
    from .plugins import registry

    if isinstance(spec, list):
        return [m for k, s in enumerate(spec) for m in _motion(f"{where}[{k}]", s)]
    reg = registry()
    names = reg.names("motion")
    if not isinstance(spec, dict) or spec.get("type") not in names:
        return [f"{where}: motion = {echo(spec)} needs type = one of {', '.join(names)}"]
    cls = reg.lookup("motion", spec["type"], where)
    return _unknown(f"{where}: motion", spec, [*MOTION_KEYS, *getattr(cls, "parameters", {})])


def _distributions(where: str, table: dict, own: Iterable[str]) -> list[str]:
    """The problems of the size distributions among a shape's parameters (tables such as
    ``radius = { normal = { mean = ..., std = ..., low = ..., high = ... } }``: a known
    distribution, its keys known and the required ones present; :mod:`dpm.distributions`);
    the values are checked when the inlet is built."""
    from .distributions import table_problems

    own = set(own)
    return [m for k, v in table.items() if k not in own and isinstance(v, dict)
            for m in table_problems(f"{where}: {k}", v)]


def _csv_file(lead: str, file: Path) -> list[str]:
    """The problem of a [[particles]] table's csv ``file`` (none for a regular file)."""
    try:
        if file.is_file():
            return []
        if not file.exists():
            return [f"{lead}: no such file ({file})"]
        why = f"is not a regular file ({file})"
    except OSError as exc:  # (a name too long)
        why = f"cannot be looked up ({exc.strerror})"
    return [f"{lead} {why}; allowed: a file of {CSV_FORM}"]


def scene_problems(doc: dict[str, Any], base: Path | None = None) -> list[str]:
    """Every problem of form and keys in a parsed scene document (empty: none)."""
    problems = _unknown("the file", doc, [*SINGLE, *ARRAYS, *TABLES])
    for name in SINGLE:
        if name in doc and not isinstance(doc[name], dict):
            problems.append(f"{name} must be a table: write [{name}]")
    for name in ARRAYS:
        if name in doc and not (isinstance(doc[name], list)
                                and all(isinstance(t, dict) for t in doc[name])):
            problems.append(f"{name} must be an array of tables: write [[{name}]] (one per "
                            "entry)")
    if "materials" in doc and not (isinstance(doc["materials"], dict) and all(
            isinstance(t, dict) for t in doc["materials"].values())):
        problems.append("materials must be tables: write [materials.NAME] (one per material)")
    if problems:
        return problems  # the forms are wrong: the keys below cannot be read
    if "simulation" not in doc:
        problems.append("the [simulation] table (with dt) is required")
    else:
        problems += _unknown("[simulation]", doc["simulation"], simulation_keys())
    for name, kw in doc.get("materials", {}).items():
        problems += _unknown(f"[materials.{name}]", kw, material_keys())
    for k, c in enumerate(doc.get("contacts", [])):
        names, bad = _params("impact_model", c.get("model", CONTACT_KEYS["model"].default),
                             f"contacts[{k}]: model")
        problems += (bad + _misspelt(f"contacts[{k}]", c, CONTACT_KEYS, "impact_model")
                     if bad else _unknown(f"contacts[{k}]", c, [*CONTACT_KEYS, *names]))
    for k, b in enumerate(doc.get("boundaries", [])):
        names, bad = _params("boundary", b.get("kind"), f"boundaries[{k}]: kind")
        own = list(BOUNDARY_KEYS)
        problems += (bad + _misspelt(f"boundaries[{k}]", b, own, "boundary") if bad
                     else _unknown(f"boundaries[{k}]", b, [*own, *names]))
        if "motion" in b:
            problems += _motion(f"boundaries[{k}]", b["motion"])
    for k, per in enumerate(doc.get("periodic", [])):
        problems += _unknown(f"periodic[{k}]", per, PERIODIC_KEYS)
    for k, spec in enumerate(doc.get("inlets", [])):
        where = f"inlets[{k}]"
        problems += _region(where, spec.get("region"))
        own = list(inlet_keys())
        if "shapes" in spec:
            problems += _unknown(where, spec, own)
            mix = spec["shapes"]
            if not (isinstance(mix, list) and all(isinstance(s, dict) for s in mix)):
                problems.append(f"{where}: shapes = {echo(mix)} must be a list of tables "
                                '{ shape = "name", fraction = f, ... }')
                continue
            for j, s in enumerate(mix):
                names, bad = _params("shape", s.get("shape", "sphere"),
                                     f"{where}: shapes[{j}]: shape")
                problems += bad or _unknown(f"{where}: shapes[{j}]", s,
                                            [*SHAPE_MIX_KEYS, *names])
                problems += _distributions(f"{where}: shapes[{j}]", s, SHAPE_MIX_KEYS)
        else:
            names, bad = _params("shape", spec.get("shape", "sphere"), f"{where}: shape")
            problems += bad or _unknown(where, spec, [*own, *names])
            problems += _distributions(where, spec, own)
    for k, spec in enumerate(doc.get("outlets", [])):
        problems += _region(f"outlets[{k}]", spec.get("region"))
        problems += _unknown(f"outlets[{k}]", spec, OUTLET_KEYS)
    for k, p in enumerate(doc.get("particles", [])):
        where = f"particles[{k}]"
        names, bad = _params("shape", p.get("shape", "sphere"), f"{where}: shape")
        problems += (bad + _misspelt(where, p, PARTICLE_KEYS, "shape") if bad
                     else _unknown(where, p, [*PARTICLE_KEYS, *names]))
        sources = [s for s in ("csv", "lattice", "positions") if s in p]
        if len(sources) != 1:
            problems.append(f"{where}: give exactly one of csv, lattice, positions (got "
                            f"{', '.join(sources) or 'none'})")
        if isinstance(p.get("lattice"), dict):
            problems += _unknown(f"{where}: lattice", p["lattice"], lattice_keys())
        elif "lattice" in p:
            problems.append(f"{where}: lattice = {echo(p['lattice'])} must be a table "
                            "{ lower = [...], upper = [...], spacing = ... }")
        if "csv" in p:
            if not isinstance(p["csv"], str):
                problems.append(f"{where}: csv = {echo(p['csv'])} must be a file name")
            elif base is not None:
                problems += _csv_file(f"{where}: csv = {echo(p['csv'])}", base / p["csv"])
    if "output" in doc:
        problems += _unknown("[output]", doc["output"], OUTPUT_KEYS)
    if "run" in doc:
        problems += _unknown("[run]", doc["run"], RUN_KEYS)
    if "checkpoint" in doc:
        problems += _unknown("[checkpoint]", doc["checkpoint"], CHECKPOINT_KEYS)
    return problems


# ---- quantities with units in values -------------------------------------------------


def convert_values(doc: dict[str, Any]) -> list[str]:
    """Convert, in place, every string where a key takes a number (``"2 mm"``,
    ``"sin(30 deg)"``, ``["0 m", 0, "-9.81 m/s2"]``) to a number in the key's declared
    unit (:func:`dpm.units.convert`); return the problems, each naming the table and the
    key (a quantity of another dimension, a plain number in quotes, text that is no
    expression). Names stay strings (keys of kind ``str``, and keys of kind ``any``
    without a unit: ``open = ["+z"]``). Run after :func:`scene_problems` found none (the
    tables' kinds decide their keys' units)."""
    problems: list[str] = []

    def table(where: str, kw: Any, spec: Mapping[str, Parameter]) -> None:
        if not isinstance(kw, dict):
            return
        for key, value in kw.items():
            p = spec.get(key)
            if p is not None:
                kw[key] = _convert(where, key, value, p, problems)

    def region(where: str, spec: Any) -> None:
        if isinstance(spec, dict) and len(spec) == 1:
            name, kw = next(iter(spec.items()))
            table(f"{where}: region.{name}", kw, declared(registered("region", name)))

    def shape_table(where: str, kw: dict, own: Mapping[str, Parameter]) -> None:
        shape = declared(registered("shape", kw.get("shape", "sphere")))
        table(where, kw, {**shape, **own})

    table("[simulation]", doc.get("simulation"), simulation_keys())
    for name, kw in doc.get("materials", {}).items():
        table(f"[materials.{name}]", kw, material_keys())
    for k, c in enumerate(doc.get("contacts", [])):
        model = declared(registered("impact_model", c.get("model", "hertz_mindlin")))
        table(f"contacts[{k}]", c, {**model, **CONTACT_KEYS})
    for k, b in enumerate(doc.get("boundaries", [])):
        table(f"boundaries[{k}]", b, {**declared(registered("boundary", b.get("kind"))),
                                      **BOUNDARY_KEYS})
        motions = b.get("motion")
        for j, m in (enumerate(motions) if isinstance(motions, list) else [(None, motions)]):
            if isinstance(m, dict):
                at = f"boundaries[{k}]" + ("" if j is None else f"[{j}]") + ": motion"
                table(at, m, {**declared(registered("motion", m.get("type"))), **MOTION_KEYS})
    for k, per in enumerate(doc.get("periodic", [])):
        table(f"periodic[{k}]", per, PERIODIC_KEYS)
    for k, spec in enumerate(doc.get("inlets", [])):
        region(f"inlets[{k}]", spec.get("region"))
        if isinstance(spec.get("shapes"), list):
            table(f"inlets[{k}]", spec, inlet_keys())
            for j, s in enumerate(spec["shapes"]):
                if isinstance(s, dict):
                    shape_table(f"inlets[{k}]: shapes[{j}]", s, SHAPE_MIX_KEYS)
        else:
            shape_table(f"inlets[{k}]", spec, inlet_keys())
    for k, spec in enumerate(doc.get("outlets", [])):
        region(f"outlets[{k}]", spec.get("region"))
        table(f"outlets[{k}]", spec, OUTLET_KEYS)
    for k, p in enumerate(doc.get("particles", [])):
        shape_table(f"particles[{k}]", p, PARTICLE_OWN)
        table(f"particles[{k}]: lattice", p.get("lattice"), lattice_keys())
    for name, spec in (("output", OUTPUT_KEYS), ("run", RUN_KEYS),
                       ("checkpoint", CHECKPOINT_KEYS)):
        table(f"[{name}]", doc.get(name), spec)
    return problems


def _takes_numbers(p: Parameter) -> bool:
    """Whether a key's strings are quantities: a number, vector or array key, or a key of
    kind ``any`` with a unit (``positions``, ``half_extents``); the others take names."""
    return p.kind in ("float", "int", "vector") or (p.kind == "any" and bool(p.unit))


def _convert(where: str, key: str, value: Any, p: Parameter, problems: list[str]) -> Any:
    """``value`` with its quantities converted to ``p``'s unit (a string, the strings in a
    list, the sizes of a distribution table); a problem for each one refused."""
    from .units import ExpressionError, convert

    if not _takes_numbers(p):
        return value

    def one(v: Any, item: str = "") -> Any:
        if isinstance(v, str):
            if p.kind != "any" and re.fullmatch(r"\s*[A-Za-z_]+\s*", v) and not _known_name(v):
                return v  # a word (dt = "auto"): the call decides
            try:
                return convert(v, p.unit, integer=p.kind == "int")
            except ExpressionError as exc:
                at = f" {key}{item} = {echo(v)}:" if item else ""
                problems.append(f"{where}: {key} = {echo(value)}:{at} {exc}")
                return v
        if isinstance(v, list):
            return [one(x, f"{item}[{i}]") for i, x in enumerate(v)]
        return v

    if isinstance(value, dict) and len(value) == 1:  # a size distribution
        (name, kw), = value.items()
        if isinstance(kw, dict):
            for k, v in kw.items():
                if k in DISTRIBUTION_SIZES:
                    kw[k] = _convert(f"{where}: {key}.{name}", k, v, p, problems)
        return value
    return one(value)


def _known_name(word: str) -> bool:
    from .units import CONSTANTS, FUNCTIONS, UNITS

    return word.strip() in UNITS or word.strip() in CONSTANTS or word.strip() in FUNCTIONS


# ---- edits of the parsed document (dpm run --set PATH=VALUE) ---------------------------

_SEGMENT = re.compile(r'\s*(?:(?P<name>[A-Za-z0-9_-]+)|"(?P<quoted>[^"]*)")'
                      r'(?P<index>(?:\s*\[\s*-?\d+\s*\])*)\s*')


def parse_path(text: str) -> list[str | int]:
    """``contacts[0].friction`` -> ``["contacts", 0, "friction"]`` (a name in double quotes
    may hold dots: ``materials."glass.1".density``); ParameterError for another form."""
    parts: list[str | int] = []
    pos = 0
    while True:
        m = _SEGMENT.match(text, pos)
        if not m or m.end() == pos:
            raise ParameterError(f"{text!r} is not a path: write TABLE.KEY, ARRAY[N].KEY "
                                 "(contacts[0].friction, simulation.dt, "
                                 "materials.glass.young, boundaries[1].motion.rpm)")
        parts.append(m.group("name") if m.group("name") is not None else m.group("quoted"))
        parts += [int(i) for i in re.findall(r"-?\d+", m.group("index"))]
        pos = m.end()
        if pos == len(text):
            return parts
        if text[pos] != ".":
            raise ParameterError(f"{text!r} is not a path: {text[pos]!r} at character "
                                 f"{pos + 1}; write TABLE.KEY or ARRAY[N].KEY")
        pos += 1


def parse_value(text: str) -> Any:
    """A value on the command line: a TOML value (``0.3``, ``[0, 0, -9.81]``, ``true``,
    ``"gear4"``, ``{ box = {...} }``), else the text itself as a string (``gear4``,
    ``2 mm``). A number in quotes is the number (``"1e-5"``: on a command line quotes
    are the shell's as often as TOML's)."""
    text = text.strip()
    if not text:
        raise ParameterError("the value is empty")
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text
    if isinstance(value, str):
        try:
            number = tomllib.loads(f"v = {value.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            return value
        if isinstance(number, int | float) and not isinstance(number, bool):
            return number
    return value


def split_values(text: str) -> list[str]:
    """The comma-separated values of ``dpm sweep --set PATH=V1,V2``: commas inside
    brackets, braces and quotes do not split (``[0, 0, -9.81],[0, 0, -1]`` is two)."""
    out, depth, quote, start = [], 0, "", 0
    for i, c in enumerate(text):
        if quote:
            if c == quote:
                quote = ""
        elif c in "\"'":
            quote = c
        elif c in "[{(":
            depth += 1
        elif c in "]})":
            depth -= 1
        elif c == "," and depth == 0:
            out.append(text[start:i].strip())
            start = i + 1
    out.append(text[start:].strip())
    return out


def _describe(node: Any) -> str:
    if isinstance(node, dict):
        return f"its keys: {', '.join(map(str, node)) or 'none'}"
    if isinstance(node, list):
        return (f"{len(node)} entr{'y' if len(node) == 1 else 'ies'} (0 to {len(node) - 1})"
                if node else "no entries")
    return f"a value, {echo(node)}"


def apply_set(doc: dict[str, Any], text: str, lead: str = "") -> tuple[str, str]:
    """Apply ``dpm run --set PATH=VALUE`` to the parsed document ``doc``: the key at
    ``PATH`` (:func:`parse_path`) takes ``VALUE`` (:func:`parse_value`). The tables on the
    way must exist (a missing single table, ``[output]``, ``[run]``, ``[checkpoint]``,
    is made); the last key may be new (the checks then judge it). Returns (the table as
    the checks name it, ``text``); ParameterError naming the path and what exists there
    otherwise (``lead`` before the message: the file)."""
    if not isinstance(text, str) or "=" not in text:
        raise ParameterError(f"{lead}--set {text!r}: write PATH=VALUE "
                             "(contacts[0].friction=0.3)")
    path_text, value_text = text.split("=", 1)
    call = f"{lead}--set {text}"
    try:
        parts = parse_path(path_text.strip())
        value = parse_value(value_text)
    except ParameterError as exc:
        raise ParameterError(f"{call}: {exc}") from None
    if len(parts) < 2 or not isinstance(parts[0], str):
        raise ParameterError(f"{call}: the path names a table, not a key; write TABLE.KEY "
                             f"or ARRAY[N].KEY (tables: {', '.join([*SINGLE, *TABLES, *ARRAYS])})")
    node: Any = doc
    done: list[str] = []
    for i, part in enumerate(parts[:-1]):
        here = _path_text(done) or "the file"
        if isinstance(part, int):
            if not isinstance(node, list):
                raise ParameterError(f"{call}: {here} is not an array; {here} has "
                                     f"{_describe(node)}")
            if not -len(node) <= part < len(node):
                raise ParameterError(f"{call}: {here} has {_describe(node)}; no [{part}]")
            part = part % len(node)
            parts[i] = part
        elif isinstance(node, list):
            raise ParameterError(f"{call}: {here} is an array of tables with "
                                 f"{_describe(node)}: write {here}[N].{part}")
        elif not isinstance(node, dict):
            raise ParameterError(f"{call}: {here} is not a table; {here} has "
                                 f"{_describe(node)}")
        elif part not in node:
            if i == 0 and part in SINGLE:
                node[part] = {}
            else:
                close = difflib.get_close_matches(part, list(map(str, node)), n=1)
                hint = f" (did you mean {close[0]}?)" if close else ""
                raise ParameterError(f"{call}: {here} has no {part}{hint}; "
                                     f"{_describe(node)}")
        node = node[part]
        done.append(part)
    last = parts[-1]
    here = _path_text(done)
    if isinstance(last, int):
        if not isinstance(node, list) or not -len(node) <= last < len(node):
            raise ParameterError(f"{call}: {here} has {_describe(node)}; no [{last}]")
        node[last] = value
    elif isinstance(node, dict):
        node[last] = value
    elif isinstance(node, list):
        raise ParameterError(f"{call}: {here} is an array with {_describe(node)}: write "
                             f"{here}[N].{last}")
    else:
        raise ParameterError(f"{call}: {here} is not a table; {here} has {_describe(node)}")
    return _table_name(parts), text


def _table_name(parts: Sequence[str | int]) -> str:
    """The table a path is in, as the checks name it: ``[simulation]``,
    ``[materials.glass]``, ``contacts[0]``."""
    if len(parts) > 1 and parts[0] == "materials":
        return f"[materials.{parts[1]}]"
    if parts[0] in SINGLE:
        return f"[{parts[0]}]"
    if len(parts) > 1 and isinstance(parts[1], int):
        return f"{parts[0]}[{parts[1]}]"
    return str(parts[0])


def _path_text(parts: Sequence[str | int]) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out
