"""TOML scene files: the Python API written down (``dpm run scene.toml``).

Every table and key, with its unit, default and range, is in docs/scene-files.md and
``dpm run --reference [TABLE]`` (both rendered by :mod:`dpm.scene_reference` from the
declarations the checks use). A string where a number goes is a quantity with units or an
expression, converted to the key's unit: ``radius = "2 mm"``, ``young = "5 MPa"``,
``angle = "30 deg"``, ``amplitude = [0, 0, "sin(30 deg) * 2 mm"]`` (:mod:`dpm.units`).
``dpm run scene.toml --set contacts[0].friction=0.3`` changes a value before the checks.

Layout (every table mirrors a call; keys are the call's keyword arguments)::

    [simulation]                 # dpm.Simulation(...)
    dt = 1e-5
    gravity = [0, 0, -9.81]
    integrator = "velocity_verlet"

    [materials.glass]            # dpm.Material("glass", ...)
    density = 2500
    young = 5e6
    poisson = 0.45

    [[contacts]]                 # sim.contact(glass, glass, ...)
    materials = ["glass", "glass"]
    model = "hertz_mindlin"
    restitution = 0.3
    friction = 0.5

    [[boundaries]]               # sim.add_boundary("box", material=glass, ...)
    kind = "box"
    material = "glass"
    lower = [0, 0, 0]
    upper = [0.042, 0.042, 0.0609]
    open = ["+z"]
    # any boundary may move: motion = { type = "rotation", rpm = 30, axis = [1, 0, 0] }
    # (types: translation, rotation, oscillation, triangular_oscillation, tumbling; a list
    # of such tables composes them in order); a mesh's file is relative to the scene file;
    # switch_off = 0.5 / switch_on = 1.0 switch it off / on at those times [s]

    [[periodic]]                 # sim.set_periodic("x", 0.0, 0.1)
    axis = "x"
    lower = 0.0
    upper = 0.1

    [[inlets]]                   # sim.add_inlet(dpm.BoxRegion(...), glass, ...)
    material = "glass"
    region = { box = { lower = [0, 0, 0.1], upper = [0.04, 0.04, 0.12] } }
    rate = 1000                  # or mass_rate (kg/s)
    radius = [1e-3, 1.2e-3]      # a pair: uniform between
    # count = 5000 or mass = 2.0 (kg): the total, then the inlet stops (alone: all at
    # start); a size distribution (dpm.distributions) instead of the pair:
    # radius = { normal = { mean = 1.1e-3, std = 1e-4, low = 9e-4, high = 1.3e-3 } }
    # radius = { lognormal = { median = 1e-3, gsd = 1.2, low = 6e-4, high = 2e-3 } }
    #          (or mu, sigma of ln(radius); basis = "mass" for a mass distribution's x50)
    # radius = { sieve = { edges = [5e-4, 1e-3, 2e-3], fractions = [0.3, 0.7] } }
    #          (mass fractions retained between consecutive edges: radii, half apertures)

    [[outlets]]                  # sim.add_outlet(dpm.BoxRegion(...), remove="inside")
    region = { cylinder = { start = [0, 0, -1], axis = [0, 0, 1], length = 0.9, radius = 1 } }

    [[particles]]                # sim.add_particles("sphere", material=glass, ...)
    shape = "sphere"
    material = "glass"
    radius = 1e-3
    lattice = { lower = [0, 0, 0], upper = [0.042, 0.042, 0.05], spacing = 2.1e-3 }
    # or csv = "file.csv" (columns x,y,z[,vx,vy,vz[,r]], header line; path relative to
    # the scene file), or positions = [[x, y, z], ...]

    [output]                     # sim.output(...)
    path = "run.h5"              # relative to the working directory
    every = 0.01
    # fields = ["force", "contact_count"]   # or "all"; contacts = true; solids = true

    [run]                        # sim.run(...)
    until = 0.2

    [checkpoint]                 # sim.checkpoint_every(...) (dpm run --checkpoint-every wins)
    every = 0.05                 # or every_steps
    path = "run.ckpt.h5"         # numbered files beside it; keep = 2 (the last ones kept)
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..material import Material
from ..scene_file import CSV_FORM, echo
from ..scene_tools import lattice
from ..simulation import Simulation

_TOP = {"simulation", "materials", "contacts", "boundaries", "particles", "output", "run",
        "periodic", "inlets", "outlets", "checkpoint"}
#: the first name=value of a call's message: the key it is about
_KEY = re.compile(r"\b([A-Za-z_]\w*)=(?!=)")


def _located(path: Path, lines: list[str], sets: Sequence[str] = ()):
    """A context manager factory: ``with at("boundaries[1]"):`` re-raises a ParameterError
    of the calls that build that table with the file, the table and the line of the key
    the message names (else of the table's header), or the ``--set`` edit that gave it, on
    each of its lines."""
    from ..scene_file import edit_table, origin

    edits = [edit_table(s) for s in sets]

    @contextmanager
    def at(where: str) -> Iterator[None]:
        try:
            yield
        except ParameterError as exc:
            out = []
            for msg in str(exc).split("\n"):
                if msg.startswith(f"{path}:"):
                    out.append(msg)
                    continue
                m = _KEY.search(msg)
                out.append(f"{path}: {where}: {msg}"
                           + origin(lines, where, m.group(1) if m else None, edits))
            raise ParameterError("\n".join(out)) from None

    return at


def _motion(where: str, spec: Any) -> Any:
    """A motion table ``{ type = "name", ... }`` (a registered motion, built-in or a
    plugin's), or a list of them (composed, applied in order)."""
    from .. import motion as mo
    from ..plugins import registry

    if isinstance(spec, list):
        return mo.Compose(*[_motion(f"{where}[{k}]", s) for k, s in enumerate(spec)])
    names = registry().names("motion")
    if not isinstance(spec, dict) or spec.get("type") not in names:
        raise ParameterError(f"{where}: motion={echo(spec)} needs type = one of "
                             f"{', '.join(names)}")
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in spec.items() if k != "type"}
    return registry().lookup("motion", spec["type"], where)(**kw)


def _region(where: str, spec: Any) -> Any:
    """A region table ``{ name = {...} }`` of a registered region (box, cylinder, a
    plugin's)."""
    from ..plugins import registry

    names = registry().names("region")
    if not isinstance(spec, dict) or len(spec) != 1 or next(iter(spec)) not in names:
        raise ParameterError(f"{where}: region={echo(spec)} must be one of "
                             + ", ".join(f"{{ {n} = {{...}} }}" for n in names))
    kind, kw = next(iter(spec.items()))
    return registry().lookup("region", kind, where)(**kw)


def _csv(where: str, name: str, base: Path) -> np.ndarray:
    """The rows of a [[particles]] table's csv file (relative to the scene file's folder
    ``base``), at least three columns; ParameterError naming the file otherwise."""
    file = base / name
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # no rows: refused below
            data = np.loadtxt(file, delimiter=",", skiprows=1, ndmin=2)
    except (ValueError, OSError) as exc:
        if isinstance(exc, UnicodeDecodeError):
            why = f"not UTF-8 text (byte {exc.start} is {exc.object[exc.start]:#04x})"
        else:  # numpy counts rows after the header from 0 ("could not convert"), or from 1
            why = str(exc).split("; use `usecols`")[0]
            row = re.search(r" at row (\d+)", why)
            if row:
                n = int(row.group(1)) + ("could not convert" in why)
                why = f"{why[:row.start()]} in data row {n} under the header"
        raise ParameterError(f"{where}: csv={name!r} ({file}) could not be read: {why}; "
                             f"allowed: {CSV_FORM}") from None
    if data.size == 0 or data.shape[1] < 3:
        got = f"{data.shape[1]} column(s)" if data.size else "no rows under the header"
        raise ParameterError(f"{where}: csv={name!r} ({file}) has {got}; allowed: {CSV_FORM}")
    return data


def load_scene(path: str | Path, output: bool = True, overwrite: bool | None = None,
               create_output: bool = True, sets: Sequence[str] = ()
               ) -> tuple[Simulation, dict[str, Any]]:
    """Build the Simulation a TOML scene describes; return it and the ``[run]`` arguments.

    The file, its tables and their keys are checked first, the edits ``sets``
    (``"PATH=VALUE"``, as ``dpm run --set``) applied before, the quantities converted to
    the keys' units (:func:`dpm.scene_file.read_scene`). A value a call refuses while the
    scene is built is named with the file, the table and the line.
    ``output=False`` leaves the ``[output]`` and ``[checkpoint]`` tables out (a restart
    goes on writing the file of the checkpoint; ``dpm advise``'s pilot runs write
    nothing); ``overwrite`` (when not None) overrides the ``overwrite`` key of
    ``[output]``. ``create_output=False`` records the ``[output]`` settings without the
    checks of a file to create (``dpm run --restart`` compares them with the checkpoint's
    run). ``[checkpoint]`` calls :meth:`~dpm.Simulation.checkpoint_every`."""
    from ..scene_file import read_scene

    path = Path(path)
    doc = read_scene(path, sets)
    text = path.read_text(encoding="utf-8")
    at = _located(path, text.splitlines(), sets)
    if not output:
        doc.pop("output", None)
        doc.pop("checkpoint", None)
    elif overwrite is not None and "output" in doc:
        doc["output"] = dict(doc["output"], overwrite=bool(overwrite))
    target = doc.get("output", {}).get("path", path.with_suffix(".h5").name)
    if not isinstance(target, str):
        raise ParameterError(f"{path}: [output]: path={echo(target)}; allowed: a file name "
                             '(a string: path = "run.h5")')
    unknown = sorted(set(doc) - _TOP)
    if unknown:
        raise ParameterError(f"{path}: unknown table(s) {unknown}; allowed: {sorted(_TOP)}")
    if "simulation" not in doc:
        raise ParameterError(f"{path}: the [simulation] table (with dt) is required")
    with at("[simulation]"):
        sim = Simulation(**doc["simulation"])
    # the scene file's text goes into the output file (run.scene_toml), with the edits
    if sets:
        text += ("\n# edited on the command line (dpm run FILE --set ...):\n"
                 + "".join(f"# --set {s}\n" for s in sets))
    sim._scene_source = (str(path), text)
    mats: dict[str, Material] = {}
    for name, kw in doc.get("materials", {}).items():
        with at(f"[materials.{name}]"):
            mats[name] = Material(name, **kw)

    def mat(where: str, name: Any) -> Material:
        if name not in mats:
            raise ParameterError(f"{path}: {where}: material={echo(name)} is not defined; "
                                 f"defined: {', '.join(mats) or 'none'}")
        return mats[name]

    for k, c in enumerate(doc.get("contacts", [])):
        c = dict(c)
        pair = c.pop("materials", None)
        if not isinstance(pair, list) or len(pair) != 2:
            raise ParameterError(f"{path}: contacts[{k}]: materials must be a list of two names")
        a, b = mat(f"contacts[{k}]", pair[0]), mat(f"contacts[{k}]", pair[1])
        with at(f"contacts[{k}]"):
            sim.contact(a, b, **c)
    for k, b in enumerate(doc.get("boundaries", [])):
        b = dict(b)
        kind = b.pop("kind", None)
        m = mat(f"boundaries[{k}]", b.pop("material", None))
        if "motion" in b:
            with at(f"boundaries[{k}]: motion"):
                b["motion"] = _motion(f"{path}: boundaries[{k}]", b["motion"])
        if kind == "mesh" and "file" in b:
            b["file"] = str(path.parent / b["file"])
        off, on = b.pop("switch_off", None), b.pop("switch_on", None)
        with at(f"boundaries[{k}]"):
            bd = sim.add_boundary(kind, material=m, **b)
            if off is not None:
                sim.switch_off(bd, at=off)
            if on is not None:
                sim.switch_on(bd, at=on)
    for k, per in enumerate(doc.get("periodic", [])):
        with at(f"periodic[{k}]"):
            sim.set_periodic(**per)
    for k, spec in enumerate(doc.get("inlets", [])):
        spec = dict(spec)
        m = mat(f"inlets[{k}]", spec.pop("material", None))
        with at(f"inlets[{k}]"):
            region = _region(f"{path}: inlets[{k}]", spec.pop("region", None))
            spec = {key: (tuple(v) if isinstance(v, list) and key != "shapes" else v)
                    for key, v in spec.items()}
            sim.add_inlet(region, m, **spec)
    for k, spec in enumerate(doc.get("outlets", [])):
        spec = dict(spec)
        with at(f"outlets[{k}]"):
            region = _region(f"{path}: outlets[{k}]", spec.pop("region", None))
            sim.add_outlet(region, **spec)
    for k, p in enumerate(doc.get("particles", [])):
        p = dict(p)
        shape = p.pop("shape", "sphere")
        m = mat(f"particles[{k}]", p.pop("material", None))
        sources = [s for s in ("csv", "lattice", "positions") if s in p]
        if len(sources) != 1:
            raise ParameterError(f"{path}: particles[{k}]: give exactly one of csv, lattice, "
                                 f"positions (got {sources or 'none'})")
        if "csv" in p:
            data = _csv(f"{path}: particles[{k}]", p.pop("csv"), path.parent)
            p["positions"] = data[:, :3]
            if data.shape[1] >= 6 and "velocities" not in p:
                p["velocities"] = data[:, 3:6]
            if data.shape[1] >= 7 and shape == "sphere" and "radius" not in p:
                p["radius"] = data[:, 6]
        elif "lattice" in p:
            with at(f"particles[{k}]: lattice"):
                p["positions"] = lattice(**p.pop("lattice"))
        with at(f"particles[{k}]"):
            sim.add_particles(shape, material=m, **p)
    if "output" in doc:
        out = dict(doc["output"])
        # inputs (csv) are relative to the scene file, the output to the working directory
        keep = out.pop("overwrite", False)
        with at("[output]"):
            sim.output(out.pop("path", path.with_suffix(".h5").name),
                       overwrite=keep if create_output else True, **out)
        if not create_output:
            sim._output_overwrite = bool(keep)
    if "checkpoint" in doc:
        ck = dict(doc["checkpoint"])
        with at("[checkpoint]"):
            sim.checkpoint_every(ck.pop("path", path.with_suffix(".ckpt.h5").name), **ck)
    return sim, dict(doc.get("run", {}))
