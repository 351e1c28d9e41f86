"""A TOML scene file read and checked as a whole before anything is built.

:func:`read_scene` returns the parsed document of a scene file (layout in
:mod:`dpm.io.scene`) after checking, per table, its form (``[simulation]``, ``[output]``,
``[run]`` single tables; ``[materials.NAME]`` tables of tables; ``[[contacts]]``,
``[[boundaries]]``, ``[[particles]]``, ``[[periodic]]``, ``[[inlets]]``, ``[[outlets]]``
arrays of tables) and its keys against the parameters of the call it mirrors. Every
problem found is listed in one :class:`~dpm.errors.ParameterError`, each unknown key with
the keys allowed in that table. Values are checked by the calls themselves when the scene
is built.
"""

from __future__ import annotations

import difflib
import re
import reprlib
import tomllib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from .errors import DpmError, ParameterError

SINGLE = ("simulation", "output", "run")
ARRAYS = ("contacts", "boundaries", "particles", "periodic", "inlets", "outlets")
TABLES = ("materials",)
#: keys a [[particles]] table takes besides its shape's parameters
PARTICLE_KEYS = ("shape", "material", "csv", "lattice", "positions", "velocities",
                 "angular_velocities", "orientations")
#: deepest nesting of arrays and inline tables a scene file may have (its own ones: 5)
MAX_DEPTH = 64
#: characters of a value a message echoes (a longer one is cut, with its length)
ECHO = 80
#: what a [[particles]] table's csv file holds
CSV_FORM = "comma-separated numbers in columns x,y,z[,vx,vy,vz[,r]] under one header line"


def read_scene(path: str | Path) -> dict[str, Any]:
    """Parse the scene file at ``path`` and check its tables and keys; return the document.

    Raises ParameterError for a missing or unreadable file, invalid TOML, a table of the
    wrong form, and unknown keys (all of them, named per table with the allowed ones).
    """
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"{path}: the scene file does not exist"
                             + (" (it is a directory)" if path.is_dir() else ""))
    too_deep = (f"{path}: arrays or tables nested more than {MAX_DEPTH} deep; allowed: at "
                f"most {MAX_DEPTH} levels")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML: {exc}{_line_of(path, exc)}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{path}: the scene file could not be read: {exc}") from None
    except RecursionError:  # tomllib parses nested arrays and inline tables recursively
        raise ParameterError(too_deep) from None
    if _depth(doc) > MAX_DEPTH:
        raise ParameterError(too_deep)
    problems = scene_problems(doc, path.parent)
    if problems:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
        raise ParameterError("\n".join(f"{path}: {m}{_where_in_file(lines, m)}"
                                       for m in problems))
    return doc


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
_UNKNOWN = re.compile(r"^(?P<where>.*?): unknown key (?P<key>\S+) = ")


def _where_in_file(lines: list[str], message: str) -> str:
    """`` (line N)`` for an unknown-key message: the line of the key in the table the
    message names (``[simulation]``, ``boundaries[1]``, ``the file``; an inline table's
    key on its line); empty where it cannot be told."""
    m = _UNKNOWN.match(message)
    if not m:
        return ""
    where, key = m.group("where"), m.group("key")
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
    pat = re.compile(r"(^|[{,]\s*)" + re.escape(key) + r"\s*=")
    spans = [(wanted[3], wanted[4])] if wanted else []
    for lo, hi in spans + [(0, len(lines))]:
        hits = [i for i in range(lo, hi) if pat.search(lines[i].split("#")[0].strip())]
        if len(hits) == 1 or (hits and (lo, hi) != (0, len(lines))):
            return f" (line {hits[0] + 1})"
    return ""


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
    return _unknown(f"{where}: motion", spec, ["type", *getattr(cls, "parameters", {})])


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
    from .flow import Inlet
    from .material import Material
    from .scene_tools import _LATTICE
    from .simulation import Simulation

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
        problems += _unknown("[simulation]", doc["simulation"],
                             [*Simulation.parameters, "device"])
    for name, kw in doc.get("materials", {}).items():
        problems += _unknown(f"[materials.{name}]", kw, Material.parameters)
    for k, c in enumerate(doc.get("contacts", [])):
        names, bad = _params("impact_model", c.get("model", "hertz_mindlin"),
                             f"contacts[{k}]: model")
        problems += (bad + _misspelt(f"contacts[{k}]", c, ["materials", "model"],
                                                     "impact_model") if bad
                     else _unknown(f"contacts[{k}]", c, ["materials", "model", *names]))
    for k, b in enumerate(doc.get("boundaries", [])):
        names, bad = _params("boundary", b.get("kind"), f"boundaries[{k}]: kind")
        own = ["kind", "material", "motion", "switch_off", "switch_on"]
        problems += (bad + _misspelt(f"boundaries[{k}]", b, own, "boundary") if bad
                     else _unknown(f"boundaries[{k}]", b, [*own, *names]))
        if "motion" in b:
            problems += _motion(f"boundaries[{k}]", b["motion"])
    for k, per in enumerate(doc.get("periodic", [])):
        problems += _unknown(f"periodic[{k}]", per, ["axis", "lower", "upper"])
    for k, spec in enumerate(doc.get("inlets", [])):
        where = f"inlets[{k}]"
        problems += _region(where, spec.get("region"))
        own = ["material", "region", "shapes", *Inlet.parameters]
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
                                            ["shape", "fraction", *names])
                problems += _distributions(f"{where}: shapes[{j}]", s, ["shape", "fraction"])
        else:
            names, bad = _params("shape", spec.get("shape", "sphere"), f"{where}: shape")
            problems += bad or _unknown(where, spec, [*own, *names])
            problems += _distributions(where, spec, own)
    for k, spec in enumerate(doc.get("outlets", [])):
        problems += _region(f"outlets[{k}]", spec.get("region"))
        problems += _unknown(f"outlets[{k}]", spec, ["region", "remove", "every", "name"])
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
            problems += _unknown(f"{where}: lattice", p["lattice"], _LATTICE)
        elif "lattice" in p:
            problems.append(f"{where}: lattice = {echo(p['lattice'])} must be a table "
                            "{ lower = [...], upper = [...], spacing = ... }")
        if "csv" in p:
            if not isinstance(p["csv"], str):
                problems.append(f"{where}: csv = {echo(p['csv'])} must be a file name")
            elif base is not None:
                problems += _csv_file(f"{where}: csv = {echo(p['csv'])}", base / p["csv"])
    if "output" in doc:
        problems += _unknown("[output]", doc["output"],
                             ["path", "every", "every_steps", "overwrite", "fields",
                              "contacts", "solids"])
    if "run" in doc:
        problems += _unknown("[run]", doc["run"], ["steps", "until"])
    return problems
