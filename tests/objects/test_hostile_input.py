"""Property-based hostile input: generated wrong types (strings, booleans, None, lists,
dicts), NaN and +-inf, negative and zero sizes, huge counts, misspelt parameter names
(made by mutating the real ones), degenerate meshes and broken scene files. Every case
must raise a :class:`dpm.errors.DpmError` whose message names the parameter: never
another exception type, never a scene built with a converted value. No case runs a
step (nothing is compiled): each fails at construction, at ``read_scene``/``load_scene``,
or in :func:`dpm.scene_check.validate_scene` called directly.

The examples tried are counted in ``CASES``; the last test prints the counts."""

from __future__ import annotations

import json
import math
import string
import tempfile
from collections import Counter
from pathlib import Path

import numba
import numpy as np
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import dpm
from dpm import _memory
from dpm.errors import DpmError
from dpm.flow import Inlet
from dpm.io.scene import load_scene
from dpm.scene_file import read_scene

CASES: Counter[str] = Counter()
EXAMPLES = 100
FAST = settings(max_examples=EXAMPLES, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])

GLASS = dict(density=2500.0, young=5e6, poisson=0.45)
R = 1e-3
REGION = dpm.BoxRegion((0, 0, 0), (0.02, 0.02, 0.02))


def refused(key: str, name: str, fn, *args, **kwargs) -> str:
    """Call ``fn``; it must raise a DpmError whose message contains ``name``."""
    CASES[key] += 1
    try:
        fn(*args, **kwargs)
    except DpmError as exc:
        msg = str(exc)
        assert name in msg, f"{type(exc).__name__} does not name {name!r}: {msg}"
        return msg
    raise AssertionError(f"{key}: accepted {name} in {args!r} {kwargs!r}")


# values that are never a number, whatever the range ------------------------------------------
junk = st.one_of(
    st.text(max_size=6),
    st.text(alphabet="0123456789.e-", min_size=1, max_size=6),  # numeric-looking strings
    st.booleans(),
    st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=2, max_size=4),
    st.dictionaries(st.text(max_size=3), st.floats(), max_size=2),
    st.just([]),
    st.just({"value": 1.0}),
)
non_finite = st.sampled_from([math.nan, math.inf, -math.inf, np.float64("nan")])


def not_positive():
    return st.one_of(st.just(0.0), st.just(0), st.floats(max_value=0.0, allow_nan=False,
                                                         allow_infinity=False),
                     st.integers(max_value=0))


def bad_positive():
    """Never a valid value of a positive finite scalar."""
    return st.one_of(junk, non_finite, not_positive())


def bad_non_negative():
    return st.one_of(junk, non_finite,
                     st.floats(max_value=-1e-12, allow_nan=False, allow_infinity=False))


def bad_vector():
    return st.one_of(
        st.text(max_size=6), st.booleans(), st.dictionaries(st.text(max_size=2), st.floats(),
                                                            max_size=3),
        st.lists(st.floats(allow_nan=False, allow_infinity=False), max_size=2),
        st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=4, max_size=5),
        st.tuples(st.floats(allow_nan=False), st.floats(), non_finite),
        st.tuples(st.booleans(), st.floats(allow_nan=False, allow_infinity=False),
                  st.floats(allow_nan=False, allow_infinity=False)),
        st.tuples(st.floats(allow_nan=False, allow_infinity=False), st.text(max_size=3),
                  st.floats(allow_nan=False, allow_infinity=False)),
    )


def bad_count():
    """Never a valid count >= 0."""
    return st.one_of(junk, non_finite, st.integers(max_value=-1),
                     st.floats(min_value=-1e6, max_value=1e6, allow_nan=False).filter(
                         lambda x: x != round(x)))


def mutated(names: list[str]):
    """A misspelling of one of ``names`` that is none of them: a character dropped,
    doubled, swapped with its neighbour, replaced or inserted."""
    def mutate(args):
        name, op, k, ch = args
        k %= max(1, len(name))
        if op == 0:
            out = name[:k] + name[k + 1:]
        elif op == 1:
            out = name[:k] + name[k] + name[k:]
        elif op == 2 and len(name) > 1:
            k = min(k, len(name) - 2)
            out = name[:k] + name[k + 1] + name[k] + name[k + 2:]
        elif op == 3:
            out = name[:k] + ch + name[k + 1:]
        else:
            out = name[:k] + ch + name[k:]
        return out

    return (st.tuples(st.sampled_from(names), st.integers(0, 4), st.integers(0, 30),
                      st.sampled_from(string.ascii_lowercase + "_"))
            .map(mutate).filter(lambda s: s not in names and s.isidentifier()))


def new_sim():
    sim = dpm.Simulation(dt=1e-6, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", **GLASS)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    return sim, glass


# API arguments -----------------------------------------------------------------------------
@FAST
@given(name=st.sampled_from(["density", "young"]), value=bad_positive())
def test_material_numbers(name, value):
    refused("Material", name, dpm.Material, "glass", **dict(GLASS, **{name: value}))


@FAST
@given(value=st.one_of(junk, non_finite, st.floats(max_value=-1.0, allow_nan=False),
                       st.floats(min_value=0.5, allow_nan=False)))
def test_material_poisson(value):
    refused("Material", "poisson", dpm.Material, "glass", **dict(GLASS, poisson=value))


@FAST
@given(bad=mutated(["density", "young", "poisson"]))
def test_material_misspelt(bad):
    refused("Material misspelt", bad, dpm.Material, "glass", density=2500.0, **{bad: 1.0})


def valid_threads(v) -> bool:
    """Whether ``v`` is a thread count ``Simulation`` takes: an int (not a bool) from 1 to
    numba's NUMBA_NUM_THREADS."""
    return (isinstance(v, int) and not isinstance(v, bool)
            and 1 <= v <= numba.config.NUMBA_NUM_THREADS)


SIM_BAD = {
    "dt": bad_positive(),
    "gravity": bad_vector(),
    "max_overlap": st.one_of(junk, non_finite, not_positive(), st.floats(min_value=2.01)),
    "overlap_tolerance": bad_non_negative(),
    "skin": bad_positive(),
    # (and the integers about the valid counts but those: zero, counts past the cores)
    "threads": st.one_of(bad_count(), st.integers(0, numba.config.NUMBA_NUM_THREADS + 8)
                         ).filter(lambda v: not valid_threads(v)),
    "sphere_orientation": st.one_of(st.integers(), st.floats(), st.text(max_size=3)),
}


@FAST
@given(data=st.data(), name=st.sampled_from(sorted(SIM_BAD)))
def test_simulation_arguments(data, name):
    value = data.draw(SIM_BAD[name])
    if name == "dt" and value == "auto":
        return
    kw = {"dt": 1e-6, name: value}
    refused("Simulation", name, dpm.Simulation, **kw)


CONTACT_BAD = {
    "restitution": st.one_of(junk, non_finite, not_positive(), st.floats(min_value=1.001)),
    "friction": bad_non_negative(),
    "rolling_friction": bad_non_negative(),
    "rolling_damping": st.one_of(junk, non_finite, st.floats(min_value=1.0),
                                 st.floats(max_value=-1e-9)),
}


@FAST
@given(data=st.data(), name=st.sampled_from(sorted(CONTACT_BAD)))
def test_contact_arguments(data, name):
    sim, glass = new_sim()
    value = data.draw(CONTACT_BAD[name])
    kw = {"restitution": 0.5, "friction": 0.5, name: value}
    refused("sim.contact", name, sim.contact, glass, glass, model="hertz_mindlin", **kw)


@FAST
@given(bad=mutated(["restitution", "friction", "rolling_friction", "rolling_damping",
                    "rolling_model"]))
def test_contact_misspelt(bad):
    sim, glass = new_sim()
    refused("sim.contact misspelt", bad, sim.contact, glass, glass, restitution=0.5,
            **{bad: 0.3})


rows_bad = st.one_of(
    st.none(), st.text(max_size=5), st.booleans(),
    st.lists(st.tuples(st.floats(allow_nan=False, allow_infinity=False), st.text(max_size=2),
                       st.floats(allow_nan=False, allow_infinity=False)), min_size=1,
             max_size=3),
    st.lists(st.tuples(st.booleans(), st.floats(allow_nan=False, allow_infinity=False),
                       st.floats(allow_nan=False, allow_infinity=False)), min_size=1,
             max_size=3),
    st.lists(st.tuples(st.floats(), non_finite, st.floats()), min_size=1, max_size=3),
    st.lists(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=2,
                      max_size=2), min_size=1, max_size=3),
    st.dictionaries(st.text(max_size=2), st.floats(), max_size=2),
)


@FAST
@given(data=st.data(), name=st.sampled_from(["positions", "velocities", "radius", "misspelt"]))
def test_add_particles_arguments(data, name):
    sim, glass = new_sim()
    kw = dict(positions=[(0, 0, 0)], radius=R)
    if name == "radius":
        kw["radius"] = data.draw(st.one_of(st.none(), bad_positive()))
    elif name == "misspelt":
        name = data.draw(mutated(["radius"]))
        kw[name] = R
    else:
        kw[name] = data.draw(rows_bad)
        if name == "velocities" and kw[name] is None:
            return  # no velocities: the default
    refused("sim.add_particles", name, sim.add_particles, "sphere", material=glass, **kw)
    assert len(sim.bodies) == 0


@FAST
@given(data=st.data(), case=st.sampled_from(["box.lower", "box.upper", "plane.normal",
                                             "tube.length", "tube.radius", "misspelt"]))
def test_boundary_arguments(data, case):
    sim, glass = new_sim()
    if case == "misspelt":
        kind = "box"
        name = data.draw(mutated(["lower", "upper", "open"]))
        kw = dict(lower=(0, 0, 0), upper=(1, 1, 1), **{name: 1.0})
    else:
        kind, name = case.split(".")
        base = {"box": dict(lower=(0, 0, 0), upper=(1, 1, 1)), "plane": {},
                "tube": dict(length=0.1, radius=0.01)}[kind]
        value = data.draw(bad_vector() if name in ("lower", "upper", "normal")
                          else bad_positive())
        kw = dict(base, **{name: value})
    refused(f"add_boundary({kind})", name, sim.add_boundary, kind, material=glass, **kw)
    assert sim.boundaries == []


INLET_BAD = {
    "rate": bad_positive(),
    "every": bad_positive(),
    "start": st.one_of(junk, non_finite),
    "stop": st.one_of(junk, st.just(math.nan)),
    "seed": bad_count(),
    "max_attempts": st.one_of(bad_count(), st.just(0)),
    "velocity": bad_vector(),
    "random_orientation": st.one_of(st.integers(), st.floats(), st.text(max_size=2),
                                    st.none().map(lambda _: "yes")),
}


@FAST
@given(data=st.data(), name=st.sampled_from(sorted(INLET_BAD)))
def test_inlet_arguments(data, name):
    glass = dpm.Material("glass", **GLASS)
    value = data.draw(INLET_BAD[name])
    kw = {"rate": 10.0, "radius": R, name: value}
    refused("Inlet", name, Inlet, REGION, glass, **kw)


sizes = st.floats(min_value=1e-4, max_value=3e-3)


@FAST
@given(lo=st.one_of(sizes, st.floats(max_value=0.0, allow_nan=False, allow_infinity=False),
                    non_finite, st.text(max_size=3)),
       hi=st.one_of(sizes, non_finite, st.text(min_size=1, max_size=3)),
       fraction=st.one_of(st.just(1.0), st.floats(max_value=-1e-9), st.just(math.nan)),
       typo=st.booleans())
def test_inlet_ranges(lo, hi, fraction, typo):
    glass = dpm.Material("glass", **GLASS)
    valid_end = lambda v: isinstance(v, float) and math.isfinite(v) and v > 0  # noqa: E731
    ok = (valid_end(lo) and valid_end(hi) and lo <= hi and fraction == 1.0 and not typo)
    key = "radious" if typo else "radius"
    spec = {"shape": "sphere", "fraction": fraction, key: (lo, hi)}
    if ok:
        CASES["Inlet range (valid)"] += 1
        Inlet(REGION, glass, rate=10.0, shapes=[spec])
        return
    if fraction != 1.0:
        name = "fraction"
    elif isinstance(lo, str) and not isinstance(hi, str):
        name = "radius"  # ("x", 1e-3) is not a range: the value itself is refused
    else:
        name = key
    refused("Inlet range", name, Inlet, REGION, glass, rate=10.0, shapes=[spec])


@FAST
@given(spacing=st.floats(min_value=1e-9, max_value=2e-4),
       size=st.floats(min_value=1.0, max_value=100.0))
def test_huge_lattice(spacing, size):
    n = (size / spacing) ** 3
    if n * (_memory.BYTES_PER_BODY + _memory.BYTES_PER_ELEMENT) <= _memory.physical_memory():
        return
    refused("dpm.lattice huge", "spacing", dpm.lattice, (0, 0, 0), (size, size, size),
            spacing)


@FAST
@given(factor=st.floats(min_value=1.01, max_value=1e6))
def test_huge_add_particles(factor):
    sim, glass = new_sim()
    n = int(factor * _memory.physical_memory()
            / (_memory.BYTES_PER_BODY + _memory.BYTES_PER_ELEMENT)) + 1
    huge = np.broadcast_to(np.zeros(3), (n, 3))  # n rows that take no memory
    refused("add_particles huge", "positions", sim.add_particles, "sphere", material=glass,
            positions=huge, radius=R)


# meshes ------------------------------------------------------------------------------------
@settings(max_examples=25, deadline=None)
@given(kind=st.sampled_from(["collinear", "repeated", "empty", "nan"]),
       n=st.integers(1, 6), seed=st.integers(0, 1000))
def test_degenerate_meshes(kind, n, seed):
    rng = np.random.default_rng(seed)
    if kind == "collinear":
        t = rng.uniform(0, 1, (3 * n, 1))
        v = t * rng.normal(size=3)  # all on one line: every face has zero area
    elif kind == "repeated":
        v = np.repeat(rng.normal(size=(n, 3)), 3, axis=0)  # each face one point, thrice
    elif kind == "nan":
        v = rng.normal(size=(3 * n, 3))
        v[rng.integers(3 * n), rng.integers(3)] = math.nan
    else:
        v = np.zeros((0, 3))
    faces = np.arange(len(v)).reshape(-1, 3)
    sim, glass = new_sim()
    refused("mesh arrays", "vertices", sim.add_boundary, "mesh", material=glass,
            vertices=v, faces=faces)
    if kind in ("collinear", "repeated"):
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "degenerate.stl"
            trimesh.Trimesh(v, faces, process=False).export(path)
            refused("mesh STL", "file=", sim.add_boundary, "mesh", material=glass, file=path)
    assert sim.boundaries == []


# inlet regions -------------------------------------------------------------------------
@settings(max_examples=30, deadline=None)
@given(offset=st.floats(min_value=0.06, max_value=10.0), axis=st.integers(0, 2),
       sign=st.sampled_from([-1, 1]))
def test_inlet_region_outside_closed_box(offset, axis, sign):
    from dpm.scene_check import validate_scene

    sim, glass = new_sim()
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.05, 0.05, 0.05))
    sim.add_particles("sphere", material=glass, positions=[(0.02, 0.02, 0.02)], radius=R)
    lo = np.zeros(3)
    lo[axis] = sign * offset if sign > 0 else -offset - 0.02
    sim.add_inlet(dpm.BoxRegion(lo, lo + 0.02), glass, rate=10.0, radius=R)
    refused("inlet region", "inlet 0", validate_scene, sim)


# scene files ---------------------------------------------------------------------------
BASE_SCENE = {
    "simulation": {"dt": 1e-5, "gravity": [0, 0, -9.81]},
    "materials": {"glass": dict(GLASS)},
    "contacts": [{"materials": ["glass", "glass"], "model": "hertz_mindlin",
                  "restitution": 0.3, "friction": 0.5}],
    "boundaries": [{"kind": "box", "material": "glass", "lower": [0, 0, 0],
                    "upper": [0.02, 0.02, 0.04], "open": ["+z"]}],
    "inlets": [{"material": "glass", "rate": 100.0, "radius": [1e-3, 1.2e-3],
                "region": {"box": {"lower": [0, 0, 0.02], "upper": [0.02, 0.02, 0.03]}}}],
    "particles": [{"shape": "sphere", "material": "glass", "radius": 1e-3,
                   "lattice": {"lower": [0, 0, 0], "upper": [0.02, 0.02, 0.01],
                               "spacing": 2.2e-3}}],
    "run": {"steps": 10},
}
#: (path of a value in BASE_SCENE, strategy of values it must refuse)
SCENE_VALUES = [
    (("simulation", "dt"), bad_positive()),
    (("simulation", "gravity"), bad_vector()),
    (("materials", "glass", "density"), bad_positive()),
    (("materials", "glass", "young"), bad_positive()),
    (("contacts", 0, "restitution"), st.one_of(junk, non_finite, not_positive())),
    (("contacts", 0, "friction"), bad_non_negative()),
    (("boundaries", 0, "lower"), bad_vector()),
    (("inlets", 0, "rate"), bad_positive()),
    (("particles", 0, "radius"), bad_positive()),
    (("particles", 0, "lattice", "spacing"), bad_positive()),
]


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float | np.floating):
        f = float(v)
        if math.isnan(f):
            return "nan"
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return repr(v) if isinstance(v, int) else repr(f)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # JSON string escapes are valid in TOML
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f'"{k}" = {toml_value(x)}' for k, x in v.items()) + " }"
    raise TypeError(type(v))


def plain_toml_key(key: str) -> bool:
    """Whether ``key`` is valid TOML between double quotes as it is (no quote, backslash
    or control character)."""
    return not any(c in '"\\' or ord(c) < 0x20 or ord(c) == 0x7F for c in key)


def to_toml(doc: dict, single: frozenset = frozenset()) -> str:
    """``doc`` as TOML; arrays of tables as [[name]] unless named in ``single`` (then
    written, wrongly, as one [name] table)."""
    out = []
    for top, val in doc.items():
        if top == "materials":
            for name, kw in val.items():
                out.append(f"[materials.{name}]")
                out += [f'"{k}" = {toml_value(x)}' for k, x in kw.items()]
        elif isinstance(val, list):
            for item in val:
                out.append(f"[{top}]" if top in single else f"[[{top}]]")
                out += [f'"{k}" = {toml_value(x)}' for k, x in item.items()]
        else:
            out.append(f"[{top}]")
            out += [f'"{k}" = {toml_value(x)}' for k, x in val.items()]
    return "\n".join(out) + "\n"


def copy_scene() -> dict:
    import copy

    return copy.deepcopy(BASE_SCENE)


def load(text: str):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "scene.toml"
        path.write_text(text, encoding="utf-8")
        read_scene(path)
        return load_scene(path)


def test_base_scene_loads():
    sim, run = load(to_toml(BASE_SCENE))
    assert len(sim.bodies) > 0 and run == {"steps": 10}


@FAST
@given(data=st.data(), k=st.integers(0, len(SCENE_VALUES) - 1))
def test_scene_file_values(data, k):
    where, strategy = SCENE_VALUES[k]
    # (a dict only with keys that toml_value writes as they are, so that the file is valid
    # TOML and what is refused is the value, not the file's syntax)
    value = data.draw(strategy.filter(lambda v: not isinstance(v, dict) or all(
        plain_toml_key(k) for k in v)))
    doc = copy_scene()
    node = doc
    for key in where[:-1]:
        node = node[key]
    node[where[-1]] = value
    try:
        text = to_toml(doc)
    except TypeError:
        return
    refused("scene value", where[-1], load, text)


def scene_keys() -> list[tuple]:
    """(path of a table in BASE_SCENE, its keys)."""
    out = []
    for top, val in BASE_SCENE.items():
        if top == "materials":
            out.append((("materials", "glass"), list(val["glass"])))
        elif isinstance(val, list):
            out.append(((top, 0), list(val[0])))
        else:
            out.append(((top,), list(val)))
    out.append((("particles", 0, "lattice"), list(BASE_SCENE["particles"][0]["lattice"])))
    out.append((("inlets", 0, "region", "box"), ["lower", "upper"]))
    return out


SCENE_KEYS = scene_keys()


@FAST
@given(data=st.data(), k=st.integers(0, len(SCENE_KEYS) - 1))
def test_scene_file_misspelt_keys(data, k):
    where, keys = SCENE_KEYS[k]
    old = data.draw(st.sampled_from(keys))
    new = data.draw(mutated(keys))
    doc = copy_scene()
    node = doc
    for key in where:
        node = node[key]
    node[new] = node.pop(old)
    refused("scene misspelt key", new, load, to_toml(doc))


@FAST
@given(tables=st.sets(st.sampled_from(["contacts", "boundaries", "inlets", "particles"]),
                      min_size=1))
def test_scene_file_single_table_for_an_array(tables):
    name = sorted(tables)[0]
    refused("scene [x] for [[x]]", f"[[{name}]]", load, to_toml(BASE_SCENE, frozenset(tables)))


def test_zz_case_count(capsys):
    """How many generated cases the module tried (pytest -s shows it)."""
    total = sum(CASES.values())
    with capsys.disabled():
        print(f"\nhostile-input cases tried: {total}")
        for key, n in sorted(CASES.items()):
            print(f"  {key}: {n}")
    if total:  # run alone, this test sees no cases
        assert total >= 200
