"""The scene-file reference (docs/scene-files.md, ``dpm run --reference``): the page is a
fresh rendering, its keys are those the calls take and the checks accept, and the
example scene files use no other."""

import inspect
import re
import tomllib
from pathlib import Path

import pytest

import dpm
from dpm.cli import main
from dpm.distributions import DISTRIBUTIONS
from dpm.flow import Inlet
from dpm.material import Material
from dpm.parameters import Parameter
from dpm.plugins import BUILTIN, registry
from dpm.scene_file import read_scene, scene_problems
from dpm.scene_reference import PAGE, markdown
from dpm.scene_reference import main as reference_main
from dpm.scene_reference import text as reference_text
from dpm.scene_tools import lattice
from dpm.simulation import Simulation

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.toml"))


def page_keys(page: str) -> dict[tuple[str, str | None], set[str]]:
    """{(table, variant or None): keys} of the page's tables: a ``### `header` ``
    section's own table, then its ``#### table: `by = name` `` variants."""
    out: dict[tuple[str, str | None], set[str]] = {}
    names = {"[simulation]": "simulation", "[materials.NAME]": "materials"}
    where = None
    for line in page.splitlines():
        h3 = re.match(r"^### `(.+)`$", line)
        h4 = re.match(r"^#### (\w+): `(?:\w+ = )?(\w+)`$", line)
        if h3:
            header = h3.group(1)
            name = names.get(header) or re.match(r"^\[*(\w+)", header).group(1)
            name = {"radius": "distributions"}.get(name, name)
            where = (name, None)
            out[where] = set()
        elif h4:
            where = (h4.group(1), h4.group(2))
            out[where] = set()
        elif where and line.startswith("| `"):
            out[where].add(re.match(r"^\| `([^`]+)`", line).group(1))
        elif line.startswith("## "):
            where = None
    return out


def builtins(kind: str) -> dict[str, type]:
    reg = registry()
    return {n: reg.entries[kind][n].cls for n in reg.names(kind)
            if reg.entries[kind][n].source == BUILTIN}


def arguments(fn, *leave) -> set[str]:
    """The keyword arguments a call takes (not self, *args, **kwargs, nor ``leave``)."""
    return {n for n, p in inspect.signature(fn).parameters.items()
            if n not in ("self", *leave) and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)}


PAGE_TEXT = PAGE.read_text(encoding="utf-8")
KEYS = page_keys(PAGE_TEXT)


def test_page_is_a_fresh_rendering():
    """docs/scene-files.md is generated: regenerate it with
    ``python -m dpm.scene_reference --write docs/scene-files.md``."""
    assert PAGE_TEXT == markdown(), ("docs/scene-files.md is out of date: python -m "
                                    "dpm.scene_reference --write docs/scene-files.md")
    assert reference_main(["--check", str(PAGE)]) == 0


def test_page_keys_equal_the_declarations():
    """Each table's keys are the arguments of the call it mirrors, or the parameters its
    class declares; each kind of boundary, impact model, motion, shape, region and
    distribution has its own table with its declared parameters."""
    expected = {
        ("simulation", None): arguments(Simulation.__init__),
        ("materials", None): set(Material.parameters),
        ("contacts", None): {"materials", "model"},  # sim.contact(a, b, model, ...)
        ("boundaries", None): {"kind", "material", "motion", "switch_off", "switch_on"},
        ("motion", None): {"type"},
        ("periodic", None): arguments(Simulation.set_periodic),
        ("particles", None): arguments(Simulation.add_particles) | {"csv", "lattice"},
        ("lattice", None): arguments(lattice),
        ("inlets", None): set(Inlet.parameters) | {"material", "region", "shapes"},
        ("shapes", None): {"shape", "fraction"},
        ("region", None): set(),
        ("distributions", None): set(),
        ("outlets", None): arguments(Simulation.add_outlet),
        ("output", None): arguments(Simulation.output),
        ("run", None): arguments(Simulation.run, "progress"),
        ("checkpoint", None): arguments(Simulation.checkpoint_every),
    }
    assert arguments(Simulation.__init__) == set(Simulation.parameters) | {"device"}
    assert arguments(Inlet.__init__) - {"shape_params"} == expected[("inlets", None)]
    for table, kind in (("contacts", "impact_model"), ("boundaries", "boundary"),
                        ("motion", "motion"), ("particles", "shape"), ("region", "region")):
        for name, cls in builtins(kind).items():
            expected[(table, name)] = set(cls.parameters)
    for name, cls in DISTRIBUTIONS.items():
        expected[("distributions", name)] = set(cls.parameters)
    assert set(KEYS) == set(expected)
    for where, keys in expected.items():
        assert KEYS[where] == keys, where


def _doc_with(table: str, variant: str | None, keys: set[str]) -> tuple[dict, str]:
    """A scene document whose ``table`` (of kind ``variant``) has every key in ``keys``
    (values are placeholders: only the keys are checked); the name the checks give it."""
    filled = {k: 1.0 for k in keys}
    box = {"box": {"lower": [0, 0, 0], "upper": [1, 1, 1]}}
    doc: dict = {"simulation": {"dt": 1e-5}}
    if table in ("simulation", "output", "run", "checkpoint"):
        doc[table] = dict(doc.get(table, {}), **filled)
        return doc, f"[{table}]"
    if table == "materials":
        doc["materials"] = {"m": filled}
        return doc, "[materials.m]"
    if table == "contacts":
        doc["contacts"] = [dict(filled, **({"model": variant} if variant else {}))]
        return doc, "contacts[0]"
    if table == "boundaries":
        doc["boundaries"] = [dict(filled, kind=variant or "plane")]
        return doc, "boundaries[0]"
    if table == "motion":
        doc["boundaries"] = [{"kind": "plane", "material": "m",
                              "motion": dict(filled, type=variant or "translation")}]
        return doc, "boundaries[0]: motion"
    if table == "periodic":
        doc["periodic"] = [filled]
        return doc, "periodic[0]"
    if table == "particles":
        doc["particles"] = [dict(filled, shape=variant or "sphere")]
        return doc, "particles[0]"
    if table == "lattice":
        doc["particles"] = [{"shape": "sphere", "radius": 1.0, "lattice": filled}]
        return doc, "particles[0]: lattice"
    if table == "inlets":
        doc["inlets"] = [dict({k: v for k, v in filled.items() if k != "shapes"}, region=box,
                              shape="sphere")]
        return doc, "inlets[0]"
    if table == "shapes":
        doc["inlets"] = [{"region": box, "shapes": [dict(filled, shape="sphere")]}]
        return doc, "inlets[0]: shapes[0]"
    if table == "region":
        doc["inlets"] = [{"region": {variant or "box": filled}, "radius": 1.0}]
        return doc, "inlets[0]: region"
    if table == "distributions":
        doc["inlets"] = [{"region": box, "radius": {variant or "normal": filled}}]
        return doc, "inlets[0]: radius"
    if table == "outlets":
        doc["outlets"] = [dict(filled, region=box)]
        return doc, "outlets[0]"
    raise AssertionError(table)


@pytest.mark.parametrize("where", sorted(KEYS, key=str))
def test_the_checks_take_every_key_of_the_page_and_no_other(where):
    """Every key the page lists for a table is accepted there by the checks of a scene
    file; a key it does not list is refused there by name."""
    table, variant = where
    keys = KEYS[where] | (KEYS[(table, None)] if variant and table not in (
        "region", "distributions") else set())
    doc, name = _doc_with(table, variant, keys)
    unknown = [m for m in scene_problems(doc) if "unknown" in m and m.startswith(name)]
    assert unknown == []
    doc, name = _doc_with(table, variant, keys | {"not_a_key"})
    assert any(m.startswith(name) and "not_a_key" in m for m in scene_problems(doc))


def _allowed(table: str, variant: str | None) -> set[str]:
    return KEYS[(table, None)] | KEYS.get((table, variant), set())


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_scene_files_use_only_keys_of_the_page(path):
    """Every key of the example scene files is on the page, in its table (and the file
    passes the checks)."""
    assert EXAMPLES, "no examples/*.toml"
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    bad = []

    def check(where: str, table: str, kw: dict, variant: str | None = None) -> None:
        bad.extend(f"{where}: {k}" for k in kw if k not in _allowed(table, variant))

    assert set(doc) <= {"simulation", "materials", "contacts", "boundaries", "motion",
                        "periodic", "particles", "inlets", "outlets", "output", "run",
                        "checkpoint"}
    for single in ("simulation", "output", "run", "checkpoint"):
        check(f"[{single}]", single, doc.get(single, {}))
    for name, kw in doc.get("materials", {}).items():
        check(f"[materials.{name}]", "materials", kw)
    for k, c in enumerate(doc.get("contacts", [])):
        check(f"contacts[{k}]", "contacts", c, c.get("model", "hertz_mindlin"))
    for k, b in enumerate(doc.get("boundaries", [])):
        check(f"boundaries[{k}]", "boundaries", b, b["kind"])
        motions = b.get("motion", [])
        for m in motions if isinstance(motions, list) else [motions]:
            check(f"boundaries[{k}]: motion", "motion", m, m["type"])
    for k, p in enumerate(doc.get("particles", [])):
        check(f"particles[{k}]", "particles", p, p.get("shape", "sphere"))
        check(f"particles[{k}]: lattice", "lattice", p.get("lattice", {}))
    for spec in doc.get("inlets", []) + doc.get("outlets", []):
        (region, kw), = spec["region"].items()
        check(f"region {region}", "region", kw, region)
    for k, spec in enumerate(doc.get("inlets", [])):
        mix = spec.get("shapes", [spec])
        check(f"inlets[{k}]", "inlets", {key: v for key, v in spec.items()
                                          if "shapes" in spec or key not in
                                          KEYS[("particles", spec.get("shape", "sphere"))]})
        for s in mix:
            if s is not spec:
                check(f"inlets[{k}]: shapes", "shapes", {key: v for key, v in s.items() if key
                      not in KEYS[("particles", s.get("shape", "sphere"))]})
    for k, spec in enumerate(doc.get("outlets", [])):
        check(f"outlets[{k}]", "outlets", spec)
    for k, per in enumerate(doc.get("periodic", [])):
        check(f"periodic[{k}]", "periodic", per)
    assert bad == []
    read_scene(path)


def test_dpm_run_reference_prints_a_table_and_help_lists_the_tables(capsys):
    assert main(["run", "--reference", "boundaries.box"]) == 0
    out = capsys.readouterr().out
    assert 'boundaries.box (kind = "box")' in out and "lower" in out and "open" in out
    assert main(["run", "--reference", "units"]) == 0
    assert "deg" in capsys.readouterr().out
    assert main(["run", "--reference"]) == 0
    everything = capsys.readouterr().out
    for table in ("[simulation]", "[[boundaries]]", "[checkpoint]", "tumbling"):
        assert table in everything
    assert main(["run", "--reference", "boundary"]) == 2
    assert "did you mean boundaries?" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    help_text = capsys.readouterr().out
    assert "[[contacts]]" in help_text and "--reference" in help_text and "--set" in help_text
    assert "docs/scene-files.md" in help_text


def test_reference_text_names_plugins_kinds():
    """In a terminal the reference lists the kinds registered at run time, a plugin's
    marked with its source (the page lists the built-in ones only)."""

    class Ring(dpm.Motion):
        """A test motion."""

        name = "ring_for_reference"
        parameters = {"spin": Parameter(default=1.0, unit="rad/s")}

    dpm.register("motion", "ring_for_reference", Ring)
    out = reference_text("motion.ring_for_reference")
    assert "spin" in out and "rad/s" in out and "[<runtime>]" in out
    assert "ring_for_reference" not in markdown()
