"""dpm.testing: the contract suites pass on the built-ins and fail on broken classes.

The built-in suites run as a plugin author runs them (subclasses of the contracts); the
broken classes are defined here (a law with a force at zero overlap, a model stating the
wrong restitution, shapes with a wrong mass, inertia or centre, or an element outside the
solid, a plane whose primitive is shifted or tilted) and each must fail its check.

The engine runs bind the laws of tests/physics/test_impact_models.py in its order, so they use
the two-sphere step module that file compiles; they are in the slow set, which CI runs
after the fast one (the module is cached by then: no compile of their own).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import dpm
import dpm.testing
from dpm.boundaries.base import Primitives
from dpm.boundaries.plane import Plane
from dpm.impact import HertzTsujiNormal, LinearTangential
from dpm.impact.parts import NormalPart
from dpm.kernels.boundary_geometry import PLANE
from dpm.kernels.config import inline_jit
from dpm.parameters import Parameter
from dpm.shapes import BodyBatch
from dpm.shapes.sphere import Sphere
from dpm.testing import ContractError

#: the laws of tests/physics/test_impact_models.py (its BIND), in its order
BIND = ["linear_spring_dashpot", "maw_linear_spring", "hooke", "hertz_brilliantov",
        "hertz_mindlin", "walton_braun", "linear_cohesion"]
MINIMAL = {"linear_spring_dashpot": {"stiffness": 500.0}, "walton_braun": {"stiffness": 500.0},
           "hertz_brilliantov": {"dissipation": 1e-5},
           "linear_cohesion": {"cohesion_energy_density": 1e3}}


# ------------------------------------------------------------------ impact models


class TestHertzMindlin(dpm.testing.ImpactModelContract):
    model = "hertz_mindlin"
    params = {"restitution": 0.5, "friction": 0.5}
    bind_models = BIND

    # (slow: the first of the suite's runs would compile the two-sphere step module that
    # tests/physics/test_impact_models.py compiles in the fast run; after it, they take a second)
    @pytest.mark.slow
    def test_engine_momentum_conserved(self):
        super().test_engine_momentum_conserved()

    @pytest.mark.slow
    def test_engine_head_on_restitution(self):
        super().test_engine_head_on_restitution()


class TestLinearSpringDashpot(dpm.testing.ImpactModelContract):
    model = "linear_spring_dashpot"
    params = {"stiffness": 500.0, "restitution": 0.7, "friction": 0.3}
    bind_models = BIND
    restitution_tolerance = 0.005

    @pytest.mark.slow
    def test_engine_momentum_conserved(self):
        super().test_engine_momentum_conserved()

    @pytest.mark.slow
    def test_engine_head_on_restitution(self):
        super().test_engine_head_on_restitution()


@pytest.mark.parametrize("name", BIND)
def test_every_builtin_law_has_no_force_without_overlap(name):
    out = dpm.testing.check_no_force_without_overlap(name, MINIMAL.get(name, {}))
    assert out["reference"] > 0.0 and out["zero"] == 0.0


@inline_jit
def offset_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """Broken on purpose: F_n = k_n d + F_0 (a force already at zero overlap)."""
    return q[0] * delta + q[1], q[0]


class OffsetNormal(NormalPart):
    name = "offset"
    slots = ("k_n", "f0")
    function = offset_normal
    parameters = {"stiffness": Parameter(low=0.0, low_open=True, unit="N/m")}

    def values(self, model, a, b, context):
        k = float(model.params["stiffness"])
        return k, 1e-3 * k * context.reff  # 0.1 of the force at the overlap 1e-2 R*

    def contact_time(self, model, a, b, meff, reff, speed):
        return math.pi * math.sqrt(meff / float(model.params["stiffness"]))


class OffsetModel(dpm.ImpactModel):
    """Broken: a linear spring with a constant offset force."""

    name = "offset_linear"
    kernel = (__name__, "offset_linear")
    normal = OffsetNormal()
    tangential = LinearTangential()


def test_broken_law_fails_no_force_check():
    with pytest.raises(ContractError, match="no force without overlap"):
        dpm.testing.check_no_force_without_overlap(OffsetModel, {"stiffness": 500.0,
                                                                 "tangential_damping_ratio": 0.5})


@pytest.mark.slow
def test_wrong_stated_restitution_fails():
    """hertz_mindlin set to 0.5 but said to give 0.55: the measured 0.5 is refused."""
    with pytest.raises(ContractError, match="restitution measured 0.5"):
        dpm.testing.check_restitution("hertz_mindlin", {"restitution": 0.5, "friction": 0.5},
                                      0.55, 0.01, bind_models=BIND)


@pytest.mark.slow
def test_momentum_check_reports_its_bound():
    out = dpm.testing.check_momentum("hertz_mindlin", {"restitution": 0.5, "friction": 0.5},
                                     bind_models=BIND)
    assert out["error"] <= out["bound"] < 1e-10 * 1e-5
    assert out["steps"] > 100


# ------------------------------------------------------------------ shapes


class TestSphere(dpm.testing.ShapeContract):
    shape = "sphere"
    params = {"radius": 1e-3}


class TestCylinder(dpm.testing.ShapeContract):
    """A ClusterShape: its own inside test is the ideal solid."""

    shape = "cylinder"
    params = {"r": 1e-3, "l": 3e-3, "resolution": 0.2}


class TestBlock(dpm.testing.ShapeContract):
    shape = "block"
    params = {"a": 1e-3, "b": 2e-3, "c": 4e-3, "resolution": 0.2}


class FatSphere(Sphere):
    """Broken: inertia 1/2 m r^2 (a cylinder's) instead of 2/5."""

    def build(self, count, density):
        b = super().build(count, density)
        b.inertia *= 1.25
        return b


class DoubleCountedDimer(dpm.Shape):
    """Broken: mass of two whole spheres (their shared lens counted twice)."""

    parameters = {"radius": Parameter(low=0.0, low_open=True, unit="m")}

    def build(self, count, density):
        r = float(self.params["radius"])
        m = 2 * 4 / 3 * math.pi * r**3 * density
        ix = 2 * 0.4 * (m / 2) * r**2
        iy = ix + m * (0.5 * r) ** 2
        return BodyBatch(np.full(count, m), np.tile([ix, iy, iy], (count, 1)),
                         np.full(count, 2, np.int64),
                         np.tile([[-0.5 * r, 0, 0], [0.5 * r, 0, 0]], (count, 1)),
                         np.full(2 * count, r), np.full(count, 1.5 * r))


class OffCentreSphere(Sphere):
    """Broken: the element is not at the centre of mass."""

    def build(self, count, density):
        b = super().build(count, density)
        b.element_offset[:, 0] = 0.2 * b.element_radius
        return b


def test_broken_shapes_fail():
    with pytest.raises(ContractError, match="inertia tensor"):
        dpm.testing.check_shape(FatSphere(radius=1e-3), checks=("inertia",))
    dpm.testing.check_shape(FatSphere(radius=1e-3), checks=("mass", "centre"))
    with pytest.raises(ContractError, match="mass"):
        dpm.testing.check_shape(DoubleCountedDimer(radius=1e-3), checks=("mass",))
    with pytest.raises(ContractError, match="centre of mass"):
        dpm.testing.check_shape(OffCentreSphere(radius=1e-3), checks=("centre",))
    # an element reaching out of the stated solid (a sphere of 0.9 r)
    with pytest.raises(ContractError, match="outside the solid"):
        dpm.testing.check_shape(Sphere(radius=1e-3), checks=("elements",),
                                inside=lambda p: np.linalg.norm(p, axis=1) <= 0.9e-3,
                                bounds=(-np.full(3, 1e-3), np.full(3, 1e-3)))


def test_monte_carlo_tolerance_follows_sample_count():
    """The allowed error is 5 standard errors: it shrinks as 1/sqrt(N)."""
    inside = lambda p: np.linalg.norm(p, axis=1) <= 1.0  # noqa: E731
    box = (-np.ones(3), np.ones(3))
    a = dpm.testing.shape.sampled_mass_properties(inside, box, 40_000)
    b = dpm.testing.shape.sampled_mass_properties(inside, box, 400_000)
    assert b["volume_error"] == pytest.approx(a["volume_error"] / math.sqrt(10), rel=0.05)
    assert abs(b["volume"] - 4 / 3 * math.pi) < 5 * b["volume_error"]


# ------------------------------------------------------------------ boundaries

R = 1e-3
H = R / 10  # sample spacing of the reference surfaces


def plane_patch(half: float) -> tuple[np.ndarray, float]:
    s = np.arange(-half, half + H / 2, H)
    x, y = np.meshgrid(s, s)
    pts = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    return pts, H / math.sqrt(2)  # farthest point of a square cell from its corners


class TestPlane(dpm.testing.BoundaryContract):
    boundary = "plane"
    params = {"point": (0, 0, 0), "normal": (0, 0, 1)}
    radius = R

    def surface(self):
        return plane_patch(5 * R)

    def outside(self, p):  # above the plane, over the middle of the patch
        return (p[:, 2] > 0) & np.all(np.abs(p[:, :2]) < 3 * R, axis=1)


class TestTube(dpm.testing.BoundaryContract):
    boundary = "tube"
    params = {"start": (0, 0, 0), "axis": (0, 0, 1), "length": 10 * R, "radius": 4 * R}
    radius = R

    def surface(self):
        n = int(math.ceil(2 * math.pi * 4 * R / H))
        phi = np.arange(n) * 2 * math.pi / n
        z = np.arange(0.0, 10 * R + H / 2, H)
        p, zz = np.meshgrid(phi, z)
        pts = np.column_stack([4 * R * np.cos(p.ravel()), 4 * R * np.sin(p.ravel()), zz.ravel()])
        chord = 2 * 4 * R * math.sin(math.pi / n)
        return pts, 0.5 * math.hypot(chord, H)

    def outside(self, p):  # inside the tube, away from its open ends
        return (np.hypot(p[:, 0], p[:, 1]) < 4 * R) & (p[:, 2] > 3 * R) & (p[:, 2] < 7 * R)


class ShiftedPlane(Plane):
    """Broken: its primitive sits 0.2 r above the plane it describes (the reference allows
    0.07 r, the spacing of its samples)."""

    def primitives(self):
        return Primitives.build([(PLANE, [0, 0, 0.2 * R, 0, 0, 1],
                                  (np.full(3, -np.inf), np.full(3, np.inf)))])


class TiltedPlane(Plane):
    """Broken: its primitive's normal is tilted by 5 degrees."""

    def primitives(self):
        a = math.radians(5)
        return Primitives.build([(PLANE, [0, 0, 0, math.sin(a), 0, math.cos(a)],
                                  (np.full(3, -np.inf), np.full(3, np.inf)))])


def test_broken_boundaries_fail():
    pts, spacing = plane_patch(5 * R)
    side = TestPlane().outside
    m = dpm.Material("m", density=1000.0)
    with pytest.raises(ContractError, match="contact distance"):
        dpm.testing.check_boundary(ShiftedPlane(m), None, pts, spacing, radius=R, outside=side,
                                   checks=("distance",))
    with pytest.raises(ContractError, match="contact normal"):
        dpm.testing.check_boundary(TiltedPlane(m), None, pts, spacing, radius=R, outside=side,
                                   checks=("normal",))


def test_contract_classes_are_not_collected_themselves():
    """The contracts hold checks only for their subclasses (no Test prefix)."""
    for c in (dpm.testing.ImpactModelContract, dpm.testing.ShapeContract,
              dpm.testing.BoundaryContract):
        assert not c.__name__.startswith("Test")


# (a composed model of dpm's own parts can also be checked without registering it)
class HertzLinearTangential(dpm.ImpactModel):
    name = "hertz_linear_tangential"
    normal = HertzTsujiNormal()
    tangential = LinearTangential()
