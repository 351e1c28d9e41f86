"""help() and inspect.signature show what each boundary, motion and inlet takes (#17),
while a misspelt keyword still gets dpm's ParameterError naming it."""

from __future__ import annotations

import inspect
import pydoc

import pytest

import dpm
from dpm import boundaries as b
from dpm.boundaries.signature import document, keyword
from dpm.errors import ParameterError
from dpm.flow import Inlet
from dpm.parameters import REQUIRED, Parameter
from dpm.plugins import registry

STEEL = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)


BOUNDARIES = {"plane": b.Plane, "box": b.Box, "wall": b.Wall, "tube": b.Tube, "bend": b.Bend,
              "mesh": b.Mesh, "sieve": b.Sieve, "orifice_plate": b.OrificePlate}
MOTIONS = {"translation": dpm.Translation, "rotation": dpm.Rotation,
           "oscillation": dpm.Oscillation, "triangular_oscillation": dpm.TriangularOscillation,
           "tumbling": dpm.Tumbling}


def _keywords(sig: inspect.Signature) -> dict[str, inspect.Parameter]:
    return {n: p for n, p in sig.parameters.items() if p.kind is p.KEYWORD_ONLY}


@pytest.mark.parametrize("kind", sorted(BOUNDARIES))
def test_boundary_signature_lists_declared_parameters(kind):
    cls = BOUNDARIES[kind]
    assert registry().lookup("boundary", kind) is cls
    sig = inspect.signature(cls)
    assert list(sig.parameters)[:2] == ["material", "call"]
    kw = _keywords(sig)
    assert list(kw) == [*cls.parameters, "motion"]
    for name, p in cls.parameters.items():
        want = inspect.Parameter.empty if p.default is REQUIRED else p.default
        assert kw[name].default == want, (kind, name)
    assert kw["motion"].default is None
    # help() prints the signature and the generated table with units
    text = pydoc.render_doc(cls, renderer=pydoc.plaintext)
    assert f"{cls.__name__}(material" in text
    for name, p in cls.parameters.items():
        assert f"{name} :" in text
        if p.unit:
            assert f"[{p.unit}]" in text
    # a misspelt keyword is still dpm's error, naming it and the allowed ones
    with pytest.raises(ParameterError) as err:
        cls(STEEL, call=f"sim.add_boundary({kind!r})", thicknes=1e-3)
    msg = str(err.value)
    assert "thicknes=0.001" in msg and f"sim.add_boundary({kind!r})" in msg
    assert "allowed:" in msg and next(iter(cls.parameters)) in msg


def test_required_parameters_have_no_default():
    kw = _keywords(inspect.signature(b.Tube))
    assert kw["length"].default is inspect.Parameter.empty
    assert kw["radius"].default is None and kw["caps"].default == "none"
    assert kw["length"].annotation is float
    assert kw["start"].annotation == tuple[float, float, float]


@pytest.mark.parametrize("name", sorted(MOTIONS))
def test_motion_signature_lists_declared_parameters(name):
    cls = MOTIONS[name]
    assert registry().lookup("motion", name) is cls
    sig = inspect.signature(cls)
    assert list(_keywords(sig)) == list(cls.parameters) == list(sig.parameters)
    text = pydoc.render_doc(cls, renderer=pydoc.plaintext)
    for pname, p in cls.parameters.items():
        assert f"{pname} :" in text
        if p.unit:
            assert f"[{p.unit}]" in text
    with pytest.raises(ParameterError) as err:
        cls(rpmm=3.0)
    assert "unknown parameter rpmm=3.0" in str(err.value)
    assert f"{cls.__name__}()" in str(err.value)


def test_compose_keeps_its_own_signature():
    assert list(inspect.signature(dpm.Compose).parameters) == ["motions"]


def test_misspelt_keyword_through_add_boundary():
    sim = dpm.Simulation(dt=1e-5)
    with pytest.raises(ParameterError) as err:
        sim.add_boundary("tube", material=STEEL, length=0.1, radius=0.05, cap="both")
    msg = str(err.value)
    assert "sim.add_boundary('tube')" in msg and "cap='both'" in msg and "caps" in msg
    assert sim.boundaries == []
    with pytest.raises(ParameterError, match=r"Rotation\(\): unknown parameter omgea"):
        dpm.Rotation(omgea=1.0)


def test_add_boundary_docstring_lists_every_builtin_kind():
    doc = inspect.getdoc(dpm.Simulation.add_boundary)
    for kind, cls in BOUNDARIES.items():
        assert f"``{kind}``" in doc
        for name in cls.parameters:
            assert f"``{name}``" in doc
    assert "``length``: [m] number in (0, inf) (required)" in doc
    assert "``angle``: [rad] number in (0, 6.28319] (required)" in doc


def test_add_inlet_takes_the_inlets_keywords():
    inlet = inspect.signature(Inlet).parameters
    add = inspect.signature(dpm.Simulation.add_inlet).parameters
    assert list(add)[1:] == list(inlet)  # self first
    for name, p in inlet.items():
        assert add[name].default == p.default, name
        assert add[name].kind == p.kind or name in ("region", "material") or (
            add[name].kind is p.KEYWORD_ONLY and p.kind is p.POSITIONAL_OR_KEYWORD)
    sim = dpm.Simulation(dt=1e-5)
    region = dpm.BoxRegion((0, 0, 0), (0.1, 0.1, 0.1))
    with pytest.raises(ParameterError, match="sed=3"):
        sim.add_inlet(region, STEEL, rate=10.0, radius=1e-3, sed=3)
    got = sim.add_inlet(region, STEEL, rate=10.0, radius=1e-3, seed=3, stop=1.0)
    assert got.seed == 3 and got.stop == 1.0 and got.shapes == [
        {"shape": "sphere", "fraction": 1.0, "radius": 1e-3}]


def test_plugin_boundary_gets_a_signature():
    class Ring(dpm.Boundary):
        """A plugin's ring."""

        name = "ring"
        parameters = {"radius": Parameter(low=0.0, low_open=True, unit="m", doc="ring radius"),
                      "width": Parameter(default=1e-3, low=0.0, unit="m")}

        def __init__(self, material, call=None, **params):
            super().__init__(material, call, **params)

    class Spelt(dpm.Boundary):
        def __init__(self, material, *, size: float = 1.0):
            super().__init__(material)

    kw = _keywords(inspect.signature(Ring))
    assert list(kw) == ["radius", "width", "motion"]
    assert "[m] number in (0, inf); ring radius (required)" in Ring.__doc__
    # a class spelling out its own keywords keeps its own signature
    assert list(inspect.signature(Spelt).parameters) == ["material", "size"]


def test_document_helper_leaves_explicit_parameter_sections():
    class Done:
        """Has its own.

        Parameters
        ----------
        x : float
            mine
        """

        parameters = {"x": Parameter()}

        def __init__(self, **params):
            pass

    document(Done, leading=(keyword("a", positional=True),))
    assert Done.__doc__.count("Parameters") == 1
    assert list(inspect.signature(Done).parameters) == ["a", "x"]
