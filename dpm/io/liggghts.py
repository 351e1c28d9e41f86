"""Read LIGGGHTS (LAMMPS) files into dpm: a data file (the ``read_data`` / ``write_data``
format, atom_style ``sphere`` or ``granular``) and a text dump of style ``custom`` (one or
more snapshots), and add their spheres to a :class:`dpm.Simulation`.

>>> from dpm.io import liggghts
>>> data = liggghts.read_data("data.packing")          # doctest: +SKIP
>>> ids = liggghts.add_particles(sim, data, material={1: glass, 2: steel})  # doctest: +SKIP
>>> last = liggghts.read_dump("post/dump1000.meshGran")[-1]   # doctest: +SKIP

Both readers return plain numpy arrays, rows sorted by atom id, values as written (no unit
conversion: LIGGGHTS inputs with ``units si``, as its tutorials, are in dpm's units; a
``units cgs`` file is not). A malformed file raises :class:`~dpm.errors.ParameterError`
naming the file, the line and what was expected there. A file ending in ``.gz`` is read
through gzip.
"""

from __future__ import annotations

import gzip
import math
import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError

__all__ = ["add_particles", "read_data", "read_dump"]

#: the atom styles whose Atoms lines are ``id type diameter density x y z [ix iy iz]``
SPHERE_STYLES = ("sphere", "granular")
_ATOMS_COLUMNS = "atom-ID atom-type diameter density x y z [ix iy iz]"
#: per-atom vectors of a dump: key in the result -> the three columns
_DUMP_VECTORS = {"velocity": ("vx", "vy", "vz"), "angular_velocity": ("omegax", "omegay", "omegaz"),
                 "force": ("fx", "fy", "fz"), "torque": ("tqx", "tqy", "tqz"),
                 "image": ("ix", "iy", "iz")}
_DUMP_SCALARS = ("mass", "density")


def _fail(path: Path, line: int | None, what: str) -> ParameterError:
    where = f"{path}:{line}" if line is not None else f"{path}"
    return ParameterError(f"{where}: {what}")


def _lines(path: str | Path) -> tuple[Path, list[str]]:
    path = Path(path)
    try:
        if path.suffix == ".gz":
            with gzip.open(path, "rt", encoding="utf-8", errors="replace") as f:
                text = f.read()
        else:
            text = path.read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise ParameterError(f"{path}: is a directory, not a file") from None
    except (OSError, EOFError) as e:
        raise ParameterError(f"{path}: cannot be read ({e})") from None
    return path, text.splitlines()


def _strip(line: str) -> str:
    """A line without its ``#`` comment and surrounding blanks."""
    return line.split("#", 1)[0].strip()


def _table(path: Path, rows: list[tuple[int, str]], ncols: tuple[int, ...],
           expected: str) -> np.ndarray:
    """The rows (line number, text) as a float array; each row must have one of the
    column counts ``ncols`` (the same for all) and numbers only."""
    if not rows:
        return np.zeros((0, ncols[0]))
    tokens = [text.split() for _, text in rows]
    width = len(tokens[0])
    for (lineno, _), tok in zip(rows, tokens, strict=True):
        if len(tok) != width or width not in ncols:
            raise _fail(path, lineno, f"expected {expected} ({' or '.join(map(str, ncols))} "
                                      f"numbers), got {len(tok)} value(s)")
    try:
        return np.array(tokens, dtype=float)
    except ValueError:
        for (lineno, _), tok in zip(rows, tokens, strict=True):
            for k, t in enumerate(tok):
                try:
                    float(t)
                except ValueError:
                    raise _fail(path, lineno, f"expected {expected}: value {k + 1}, {t!r}, "
                                              f"is not a number") from None
        raise


def _ints(path: Path, rows: list[tuple[int, str]], values: np.ndarray, what: str) -> np.ndarray:
    """Column ``values`` as int64, refusing non-integers (naming the row's line)."""
    out = values.astype(np.int64)
    bad = np.flatnonzero(out != values)
    if len(bad):
        raise _fail(path, rows[int(bad[0])][0], f"{what} {values[bad[0]]!r} is not an integer")
    return out


def _sphere_mass(radius: np.ndarray, density: np.ndarray) -> np.ndarray:
    """LAMMPS' atom_style sphere: mass = 4/3 pi r^3 density, or the density column itself
    for a point particle (diameter 0)."""
    return np.where(radius > 0, 4.0 / 3.0 * math.pi * radius**3 * density, density)


# --------------------------------------------------------------------------- data file
_HEADER_WORDS = re.compile(r"^([-+0-9.eE\s]+?)\s+([a-z][a-z ]*)$")


def read_data(path: str | Path) -> dict[str, Any]:
    """Read a LIGGGHTS/LAMMPS data file (``read_data`` format, what ``write_data`` writes)
    of atom_style ``sphere`` or ``granular``.

    Returns a dict of numpy arrays, rows sorted by atom id: ``id`` (n,) int64, ``type``
    (n,) int64, ``position`` (n, 3) [m], ``radius`` (n,) (half the ``diameter`` column),
    ``density`` (n,) (the column; for a point particle of diameter 0 LAMMPS reads it as
    the mass), ``mass`` (n,), ``image`` (n, 3) int64 (zeros when the file has no image
    flags), ``velocity`` and ``angular_velocity`` (n, 3) (the ``Velocities`` section;
    zeros without it, as LAMMPS sets them); and ``box`` (``lower``, ``upper`` (3,),
    ``tilt``: (xy, xz, yz) or None), ``atom_types`` (the header's count), ``timestep``
    (from the title ``write_data`` writes, else None) and ``path``.

    Sections other than Atoms and Velocities (Masses, Pair Coeffs, Bonds, ...) are
    skipped. Raises :class:`~dpm.errors.ParameterError` naming the file and line for
    anything else: a header or an Atoms line that is not what this format has, an atom
    style other than sphere or granular, a section whose line count differs from the
    header's ``atoms``, a velocity of an atom the Atoms section lacks.
    """
    path, lines = _lines(path)
    if not lines:
        raise _fail(path, None, "is empty; expected a LAMMPS data file (a title line, then "
                                "the header: 'N atoms', 'xlo xhi', ...)")
    title = lines[0]
    m = re.search(r"timestep\s*=\s*(\d+)", title)
    out: dict[str, Any] = {"path": str(path), "timestep": int(m.group(1)) if m else None}
    header: dict[str, list[float]] = {}
    i = 1
    n = len(lines)
    # the header: "<numbers> <keyword>" lines up to the first section keyword
    while i < n:
        text = _strip(lines[i])
        if not text:
            i += 1
            continue
        if text[0].isalpha():
            break
        hm = _HEADER_WORDS.match(text)
        if hm is None:
            raise _fail(path, i + 1, f"expected a header line ('N atoms', 'N atom types', "
                                     f"'xlo xhi', ...) or a section keyword, got {text!r}")
        try:
            header[hm.group(2).strip()] = [float(v) for v in hm.group(1).split()]
        except ValueError:
            raise _fail(path, i + 1, f"expected numbers before {hm.group(2)!r}, got "
                                     f"{hm.group(1)!r}") from None
        i += 1
    if "atoms" not in header:
        raise _fail(path, i + 1 if i < n else None,
                    "the header has no 'N atoms' line (expected e.g. '30 atoms' before "
                    "the first section)")
    natoms = int(header["atoms"][0])
    lower, upper = np.zeros(3), np.zeros(3)
    for k, ax in enumerate("xyz"):
        key = f"{ax}lo {ax}hi"
        if key not in header or len(header[key]) != 2:
            raise _fail(path, None, f"the header has no '{key}' line (expected e.g. "
                                    f"'0.0 0.1 {key}')")
        lower[k], upper[k] = header[key]
    tilt = header.get("xy xz yz")
    out["box"] = {"lower": lower, "upper": upper,
                  "tilt": None if tilt is None else np.array(tilt, float)}
    out["atom_types"] = int(header.get("atom types", [0])[0])
    # the sections: a keyword line, then its rows up to the next keyword
    sections: dict[str, tuple[int, str, list[tuple[int, str]]]] = {}
    while i < n:
        raw = lines[i]
        text = _strip(raw)
        if not text:
            i += 1
            continue
        if not text[0].isalpha():
            raise _fail(path, i + 1, f"expected a section keyword (Atoms, Velocities, "
                                     f"Masses, ...), got {text!r}")
        name, comment = text, raw.split("#", 1)[1].strip() if "#" in raw else ""
        start = i + 1
        i += 1
        rows: list[tuple[int, str]] = []
        while i < n:
            t = _strip(lines[i])
            if t and t[0].isalpha():
                break
            if t:
                rows.append((i + 1, t))
            i += 1
        if name in sections:
            raise _fail(path, start, f"a second {name} section (the first is at line "
                                     f"{sections[name][0]})")
        sections[name] = (start, comment, rows)
    if "Atoms" not in sections:
        raise _fail(path, None, f"has no Atoms section (expected 'Atoms' followed by "
                                f"{natoms} lines: {_ATOMS_COLUMNS})")
    start, style, rows = sections["Atoms"]
    style = style.split()[0] if style else ""
    if style and style not in SPHERE_STYLES:
        raise _fail(path, start, f"atom_style {style!r}: expected sphere or granular "
                                 f"(Atoms lines: {_ATOMS_COLUMNS})")
    if len(rows) != natoms:
        raise _fail(path, start, f"the Atoms section has {len(rows)} line(s), the header "
                                 f"says {natoms} atoms")
    a = _table(path, rows, (7, 10), f"an Atoms line of atom_style sphere/granular: "
                                    f"{_ATOMS_COLUMNS}")
    ids = _ints(path, rows, a[:, 0], "atom-ID")
    dup = _first_duplicate(ids)
    if dup is not None:
        raise _fail(path, rows[dup][0], f"atom-ID {ids[dup]} appears twice in the Atoms "
                                        f"section")
    types = _ints(path, rows, a[:, 1], "atom-type")
    if (a[:, 2] < 0).any():
        k = int(np.flatnonzero(a[:, 2] < 0)[0])
        raise _fail(path, rows[k][0], f"diameter {a[k, 2]!r} is negative")
    order = np.argsort(ids, kind="stable")
    radius = 0.5 * a[order, 2]
    density = a[order, 3]
    image = np.zeros((natoms, 3), np.int64)
    if a.shape[1] == 10:
        image = np.stack([_ints(path, rows, a[:, c], "image flag") for c in (7, 8, 9)],
                         axis=1)[order]
    out.update(id=ids[order], type=types[order], radius=radius, density=density,
               mass=_sphere_mass(radius, density), position=a[order, 4:7].copy(),
               image=image)
    vel = np.zeros((natoms, 3))
    omega = np.zeros((natoms, 3))
    if "Velocities" in sections:
        vstart, _, vrows = sections["Velocities"]
        if len(vrows) != natoms:
            raise _fail(path, vstart, f"the Velocities section has {len(vrows)} line(s), "
                                      f"the header says {natoms} atoms")
        v = _table(path, vrows, (7, 4), "a Velocities line: atom-ID vx vy vz "
                                        "[omegax omegay omegaz]")
        vid = _ints(path, vrows, v[:, 0], "atom-ID")
        row = np.searchsorted(out["id"], vid)
        row = np.minimum(row, natoms - 1)
        bad = np.flatnonzero(out["id"][row] != vid)
        if len(bad):
            raise _fail(path, vrows[int(bad[0])][0], f"a velocity of atom-ID {vid[bad[0]]}, "
                                                     f"which the Atoms section does not have")
        dup = _first_duplicate(vid)
        if dup is not None:
            raise _fail(path, vrows[dup][0], f"atom-ID {vid[dup]} appears twice in the "
                                             f"Velocities section")
        vel[row] = v[:, 1:4]
        if v.shape[1] == 7:
            omega[row] = v[:, 4:7]
    out["velocity"] = vel
    out["angular_velocity"] = omega
    return out


def _first_duplicate(ids: np.ndarray) -> int | None:
    """The row of the first repeated value of ``ids`` (None: all distinct)."""
    if len(np.unique(ids)) == len(ids):
        return None
    seen: set[int] = set()
    for k, v in enumerate(ids.tolist()):
        if v in seen:
            return k
        seen.add(v)
    return None  # pragma: no cover


# --------------------------------------------------------------------------- dump
def read_dump(path: str | Path) -> list[dict[str, Any]]:
    """Read a LIGGGHTS/LAMMPS text dump of style ``custom`` (``dump ID group custom N file
    id type x y z ... radius``): every snapshot of the file, in order.

    A snapshot is ``ITEM: TIMESTEP``, ``ITEM: NUMBER OF ATOMS``, ``ITEM: BOX BOUNDS`` and
    ``ITEM: ATOMS <columns>`` with one row per atom (the columns in any order; a column
    named twice, as the tutorials' ``id type type x y z``, is read from its first place);
    ``ITEM: TIME`` and ``ITEM: UNITS`` are read where present, other items skipped.

    Each snapshot is a dict, rows sorted by atom id: ``timestep``, ``time`` (or None),
    ``units`` (where the dump has them), ``path``,
    ``box`` (``lower``, ``upper`` (3,), ``tilt`` (xy, xz, yz) or None, ``boundary`` the
    three flags such as ``"ff"``), ``id`` and ``type`` (n,) int64, ``position`` (n, 3)
    (from x y z, else xu yu zu, else the scaled xs ys zs or xsu ysu zsu), and where the
    dump has their columns: ``radius`` (``radius``, or half of ``diameter``),
    ``velocity`` (vx vy vz), ``angular_velocity`` (omegax omegay omegaz), ``force``,
    ``torque`` (tqx tqy tqz), ``image`` (ix iy iz, int64), ``mass``, ``density``; and
    ``columns``: every column by its name (floats).

    Raises :class:`~dpm.errors.ParameterError` naming the file and line: a file that
    does not start with ``ITEM: TIMESTEP``, a value that is not a number, a row with
    another number of values than the ATOMS line names, a snapshot with fewer rows than
    its NUMBER OF ATOMS, no id or position columns.
    """
    path, lines = _lines(path)
    n = len(lines)
    i = 0
    while i < n and not lines[i].strip():
        i += 1
    if i == n:
        raise _fail(path, None, "is empty; expected a LAMMPS dump ('ITEM: TIMESTEP' ...)")
    if lines[i].strip() != "ITEM: TIMESTEP":
        raise _fail(path, i + 1, f"expected 'ITEM: TIMESTEP' (a LAMMPS/LIGGGHTS text dump "
                                 f"of style custom), got {lines[i].strip()[:60]!r}")
    snaps: list[dict[str, Any]] = []
    snap: dict[str, Any] | None = None

    def value_line(k: int, kind: type, what: str) -> Any:
        if k >= n:
            raise _fail(path, k, f"the file ends where {what} was expected")
        text = lines[k].strip()
        try:
            return kind(text)
        except ValueError:
            raise _fail(path, k + 1, f"expected {what}, got {text[:60]!r}") from None

    while i < n:
        text = lines[i].strip()
        if not text:
            i += 1
            continue
        if not text.startswith("ITEM:"):
            raise _fail(path, i + 1, f"expected an 'ITEM: ...' line, got {text[:60]!r}"
                        + (f" (more rows than NUMBER OF ATOMS = {snap['n']}?)"
                           if snap is not None and "_rows" in snap else ""))
        item = text[5:].strip()
        if item == "TIMESTEP":
            if snap is not None:
                _finish(path, snap)
            snap = {"timestep": value_line(i + 1, int, "the timestep (an integer)"),
                    "time": None, "path": str(path), "_line": i + 1}
            snaps.append(snap)
            i += 2
            continue
        assert snap is not None
        if item == "TIME":
            snap["time"] = value_line(i + 1, float, "the time (a number)")
            i += 2
        elif item == "UNITS":
            snap["units"] = lines[i + 1].strip() if i + 1 < n else ""
            i += 2
        elif item == "NUMBER OF ATOMS":
            snap["n"] = value_line(i + 1, int, "the number of atoms (an integer)")
            i += 2
        elif item.startswith("BOX BOUNDS"):
            words = item.split()[2:]
            tri = words[:3] == ["xy", "xz", "yz"]
            flags = words[3:] if tri else words
            b = np.zeros((3, 3 if tri else 2))
            for k in range(3):
                if i + 1 + k >= n:
                    raise _fail(path, n, "the file ends inside BOX BOUNDS (expected 3 lines)")
                row = lines[i + 1 + k].split()
                try:
                    vals = [float(v) for v in row]
                except ValueError:
                    vals = []
                if len(vals) != b.shape[1]:
                    raise _fail(path, i + 2 + k, f"expected {b.shape[1]} numbers of the box "
                                                 f"({'lo hi tilt' if tri else 'lo hi'}), got "
                                                 f"{lines[i + 1 + k].strip()[:60]!r}")
                b[k] = vals
            snap["box"] = _box(b, tri, tuple(flags))
            i += 4
        elif item.startswith("ATOMS"):
            cols = item.split()[1:]
            if "n" not in snap:
                raise _fail(path, i + 1, "ITEM: ATOMS before ITEM: NUMBER OF ATOMS")
            if not cols:
                raise _fail(path, i + 1, "ITEM: ATOMS names no columns (expected e.g. "
                                         "'ITEM: ATOMS id type x y z vx vy vz radius')")
            count = snap["n"]
            rows = []
            k = i + 1
            while len(rows) < count:
                if k >= n or lines[k].lstrip().startswith("ITEM:"):
                    raise _fail(path, k if k >= n else k + 1,
                                f"the snapshot of timestep {snap['timestep']} has "
                                f"{len(rows)} atom row(s), its NUMBER OF ATOMS says {count}")
                t = lines[k].strip()
                if t:
                    rows.append((k + 1, t))
                k += 1
            table = _table(path, rows, (len(cols),), f"an atom row of the columns "
                                                     f"{' '.join(cols)}")
            snap["_rows"] = rows
            snap["columns"] = {}
            for c, name in enumerate(cols):
                snap["columns"].setdefault(name, table[:, c])
            i = k
        else:  # another item: skip to the next
            i += 1
            while i < n and not lines[i].lstrip().startswith("ITEM:"):
                i += 1
    if snap is not None:
        _finish(path, snap)
    return snaps


def _box(b: np.ndarray, tri: bool, flags: tuple[str, ...]) -> dict[str, Any]:
    """The box of a dump's BOX BOUNDS rows: a triclinic box's rows are the bounding box
    and the tilt (LAMMPS' dump convention), turned back into lo, hi."""
    if not tri:
        return {"lower": b[:, 0].copy(), "upper": b[:, 1].copy(), "tilt": None,
                "boundary": flags}
    xy, xz, yz = b[0, 2], b[1, 2], b[2, 2]
    lower = np.array([b[0, 0] - min(0.0, xy, xz, xy + xz), b[1, 0] - min(0.0, yz), b[2, 0]])
    upper = np.array([b[0, 1] - max(0.0, xy, xz, xy + xz), b[1, 1] - max(0.0, yz), b[2, 1]])
    return {"lower": lower, "upper": upper, "tilt": np.array([xy, xz, yz]), "boundary": flags}


def _finish(path: Path, snap: dict[str, Any]) -> None:
    """Turn a snapshot's columns into the named arrays, sorted by id."""
    line = snap.pop("_line")
    snap.pop("n", None)
    if "columns" not in snap:
        raise _fail(path, line, f"the snapshot of timestep {snap['timestep']} has no "
                                f"'ITEM: ATOMS ...' section")
    rows = snap.pop("_rows")
    cols = snap["columns"]  # (in the file's order)
    if "box" not in snap:
        raise _fail(path, line, f"the snapshot of timestep {snap['timestep']} has no "
                                f"'ITEM: BOX BOUNDS' section")
    if "id" not in cols:
        raise _fail(path, line, f"the snapshot of timestep {snap['timestep']} has no id "
                                f"column (ITEM: ATOMS id type x y z ...)")
    ids = _ints(path, rows, cols["id"], "id")
    dup = _first_duplicate(ids)
    if dup is not None:
        raise _fail(path, rows[dup][0], f"the snapshot of timestep {snap['timestep']} has "
                                        f"atom id {ids[dup]} twice")
    types = (_ints(path, rows, cols["type"], "type") if "type" in cols
             else np.ones(len(ids), np.int64))
    image = ({c: _ints(path, rows, cols[c], "image flag " + c) for c in ("ix", "iy", "iz")}
             if all(c in cols for c in ("ix", "iy", "iz")) else None)
    order = np.argsort(ids, kind="stable")
    snap["columns"] = cols = {k: v[order] for k, v in cols.items()}
    snap["id"] = ids[order]
    snap["type"] = types[order]
    box = snap["box"]
    if all(c in cols for c in ("x", "y", "z")):
        pos = np.stack([cols["x"], cols["y"], cols["z"]], axis=1)
    elif all(c in cols for c in ("xu", "yu", "zu")):
        pos = np.stack([cols["xu"], cols["yu"], cols["zu"]], axis=1)
    else:
        scaled = next((s for s in (("xs", "ys", "zs"), ("xsu", "ysu", "zsu"))
                       if all(c in cols for c in s)), None)
        if scaled is None:
            raise _fail(path, line, f"the snapshot of timestep {snap['timestep']} has no "
                                    f"position columns (x y z, xu yu zu, xs ys zs or "
                                    f"xsu ysu zsu)")
        s = np.stack([cols[c] for c in scaled], axis=1)
        lo, hi = box["lower"], box["upper"]
        xy, xz, yz = box["tilt"] if box["tilt"] is not None else (0.0, 0.0, 0.0)
        size = hi - lo
        pos = np.stack([lo[0] + s[:, 0] * size[0] + s[:, 1] * xy + s[:, 2] * xz,
                        lo[1] + s[:, 1] * size[1] + s[:, 2] * yz,
                        lo[2] + s[:, 2] * size[2]], axis=1)
    snap["position"] = pos
    if "radius" in cols:
        snap["radius"] = cols["radius"].copy()
    elif "diameter" in cols:
        snap["radius"] = 0.5 * cols["diameter"]
    for key, names in _DUMP_VECTORS.items():
        if key == "image":
            if image is not None:
                snap[key] = np.stack([image[c][order] for c in names], axis=1)
        elif all(c in cols for c in names):
            snap[key] = np.stack([cols[c] for c in names], axis=1)
    for key in _DUMP_SCALARS:
        if key in cols:
            snap[key] = cols[key].copy()


# --------------------------------------------------------------------------- into dpm
def add_particles(sim: Any, data: Mapping[str, Any], material: Any,
                  check_density: bool = True) -> np.ndarray:
    """Add the atoms of ``data`` (a :func:`read_data` result or one snapshot of
    :func:`read_dump`) to ``sim`` as spheres with their positions, radii, velocities and
    angular velocities (those the data has; zero otherwise), through
    ``sim.add_particles("sphere", ...)``.

    ``material``: a :class:`dpm.Material` for every atom, or a mapping atom type ->
    Material (every type of the data needs one). dpm takes the density from the material:
    with ``check_density`` (default) a type whose density in the file (the ``density``
    column, or the ``mass`` column over the sphere's volume) differs from its material's
    by more than 0.1 % is warned about (:class:`UserWarning`).

    Returns the dpm ids of the new bodies, one per row of ``data`` (rows in the order of
    ``data["id"]``, the LIGGGHTS ids). Raises :class:`~dpm.errors.ParameterError` for a
    list of snapshots (pass one, e.g. ``read_dump(path)[-1]``), data without positions or
    radii, a radius that is not positive, or a type without a material.
    """
    call = "dpm.io.liggghts.add_particles()"
    if isinstance(data, list | tuple):
        raise ParameterError(f"{call}: data is a list of {len(data)} snapshot(s); pass one "
                             f"of them (e.g. read_dump(path)[-1])")
    if not isinstance(data, Mapping) or "position" not in data:
        raise ParameterError(f"{call}: data must be the dict of read_data() or of one "
                             f"snapshot of read_dump(), with a 'position' array")
    src = data.get("path", "the data")
    pos = np.asarray(data["position"], float).reshape(-1, 3)
    n = len(pos)
    if data.get("radius") is None:
        raise ParameterError(f"{call}: {src} has no radii (a dump needs a radius or "
                             f"diameter column: dump ... custom ... radius)")
    radius = np.asarray(data["radius"], float).reshape(n)
    bad = np.flatnonzero(~(radius > 0))
    if len(bad):
        raise ParameterError(f"{call}: atom id {_id(data, bad[0])} has radius "
                             f"{radius[bad[0]]!r}; dpm spheres need a radius > 0")
    types = np.asarray(data.get("type", np.ones(n, np.int64)), np.int64).reshape(n)
    vel = np.asarray(data.get("velocity", np.zeros((n, 3))), float).reshape(n, 3)
    omega = np.asarray(data.get("angular_velocity", np.zeros((n, 3))), float).reshape(n, 3)
    if isinstance(material, Mapping):
        missing = sorted(set(types.tolist()) - {int(k) for k in material})
        if missing:
            raise ParameterError(f"{call}: no material for atom type(s) "
                                 f"{', '.join(map(str, missing))}; give material={{type: "
                                 f"Material, ...}} for every type "
                                 f"({', '.join(map(str, sorted(set(types.tolist()))))})")
        mats = {int(k): v for k, v in material.items()}
    else:
        mats = {int(t): material for t in set(types.tolist())}
    if check_density:
        _check_density(data, radius, types, mats, src)
    out = np.full(n, -1, np.int64)
    groups: dict[int, list[int]] = {}
    for t, m in mats.items():
        groups.setdefault(id(m), []).append(t)
    for ts in groups.values():
        sel = np.flatnonzero(np.isin(types, ts))
        if len(sel) == 0:
            continue
        out[sel] = sim.add_particles("sphere", material=mats[ts[0]], positions=pos[sel],
                                     velocities=vel[sel], angular_velocities=omega[sel],
                                     radius=radius[sel])
    return out


def _id(data: Mapping[str, Any], row: int) -> Any:
    ids = data.get("id")
    return int(ids[row]) if ids is not None else f"(row {row})"


def _check_density(data: Mapping[str, Any], radius: np.ndarray, types: np.ndarray,
                   mats: dict[int, Any], src: Any) -> None:
    if data.get("density") is not None:
        rho = np.asarray(data["density"], float)
    elif data.get("mass") is not None:
        rho = np.asarray(data["mass"], float) / (4.0 / 3.0 * math.pi * radius**3)
    else:
        return
    for t, m in sorted(mats.items()):
        sel = types == t
        if not sel.any() or getattr(m, "density", None) is None:
            continue
        r = rho[sel]
        worst = float(r[np.argmax(np.abs(r - m.density))])
        if abs(worst - m.density) > 1e-3 * m.density:
            warnings.warn(f"dpm.io.liggghts.add_particles(): atom type {t} of {src} has "
                          f"density {worst:.6g} kg/m3, its material {m.name!r} "
                          f"{m.density:.6g}: dpm uses the material's", stacklevel=3)
