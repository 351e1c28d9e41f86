"""The registry of boundary primitive kinds (dpm.boundaries.primitives): the built-ins
keep their codes, the generated ``closest`` is read from it, and a primitive kind defined
here, outside dpm (a fixed ball obstacle whose geometry function is in this file), works in
a run without any edit of dpm.

References: a sphere resting on top of the ball carries its weight m g at the Hertz
static overlap of a sphere on a wall, delta = (3 m g / (4 E* sqrt(r)))^(2/3), on the
ball's axis; a sphere set down off the axis rolls off, away from it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import dpm
from dpm import plan
from dpm.boundaries import Boundary, Primitives
from dpm.boundaries import primitives as reg
from dpm.boundaries.joints import join_pipe_ends
from dpm.errors import ParameterError
from dpm.kernels import boundary_geometry as bg
from dpm.kernels.config import inline_jit
from dpm.parameters import Parameter

BALL_CODE = 100
G = 9.81


@inline_jit
def ball_distance(p, x, y, z):
    """Distance from (x, y, z) to the surface of the ball of centre p[0:3] and radius
    p[3], and the outward normal."""
    dx = x - p[0]
    dy = y - p[1]
    dz = z - p[2]
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if d > 0.0:
        inv = 1.0 / d
        return d - p[3], dx * inv, dy * inv, dz * inv
    return -p[3], 0.0, 0.0, 1.0


BALL = reg.PrimitiveKind(BALL_CODE, "test_ball", 4, (__name__, "ball_distance"))


class BallObstacle(Boundary):
    """A fixed ball of ``radius`` at ``center``, touched from outside."""

    name = "test_ball_obstacle"
    parameters = {
        "center": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "radius": Parameter(low=0.0, low_open=True, unit="m"),
    }

    def primitives(self) -> Primitives:
        c = np.asarray(self.params["center"], float)
        r = float(self.params["radius"])
        return Primitives.build([(BALL_CODE, [*c, r], (c - r, c + r))])


@pytest.fixture
def ball_kind():
    reg.register_primitive(BALL)
    dpm.register("boundary", BallObstacle.name, BallObstacle)
    yield BALL
    reg.unregister_primitive(BALL_CODE)


def test_builtin_kinds_keep_their_codes_and_functions():
    expect = {bg.PLANE: "plane_distance", bg.SLAB: "slab_distance", bg.AXI: "axi_distance",
              bg.TORUS: "torus_distance", bg.TRIANGLE: "triangle_distance",
              bg.SIEVE: "sieve_distance"}
    for code, fn in expect.items():
        kind = reg.primitive_kind(code)
        assert kind.function == (reg.BUILTIN_MODULE, fn)
        assert hasattr(bg, fn) and kind.width <= bg.PAR_WIDTH
    assert {k.code for k in reg.kinds() if k.joinable} >= {bg.AXI, bg.TORUS}
    with pytest.raises(ParameterError, match="taken"):
        reg.register_primitive(reg.PrimitiveKind(bg.PLANE, "other", 6, ("m", "f")))
    with pytest.raises(ParameterError, match="width"):
        reg.register_primitive(reg.PrimitiveKind(200, "wide", 21, ("m", "f")))
    with pytest.raises(ParameterError, match="not registered"):
        reg.primitive_kind(12345)


def test_closest_of_a_plugin_kind_is_generated(ball_kind):
    lines = plan._closest_lines([bg.PLANE, BALL_CODE], False, True)
    assert f"from {__name__} import ball_distance as _kind_{BALL_CODE}" in lines
    assert f"    d, nx, ny, nz = _kind_{BALL_CODE}(p, x, y, z)" in lines
    assert "HAS_JOINTS = False" in lines


def test_pipe_ends_join_by_declared_capability():
    steel = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
    a = dpm.boundaries.Tube(steel, start=(0, 0, 0), axis=(1, 0, 0), length=0.02, radius=4e-3)
    b = dpm.boundaries.Tube(steel, start=(0.02, 0, 0), axis=(1, 0, 0), length=0.02,
                            radius=4e-3)
    c = dpm.boundaries.Tube(steel, start=(0.05, 0, 0), axis=(1, 0, 0), length=0.02,
                            radius=4e-3)
    plate = dpm.boundaries.Wall(steel, half_extents=(0.01, 0.01))
    assert a.joinable_ends and not plate.joinable_ends and plate.pipe_ends() == []
    join_pipe_ends([a, plate, b, c])
    assert a.joined == {"end"} and b.joined == {"start"} and c.joined == set()


def test_a_sphere_on_a_plugin_ball_obstacle(ball_kind):
    """Registered from this file: a sphere at rest on the top of the ball carries its weight
    at the static Hertz overlap, on the axis; one set down off the axis rolls off."""
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    steel = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
    sim = dpm.Simulation(dt=5e-6, gravity=(0, 0, -G))
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.1, friction=0.5)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.1, friction=0.5)
    big, r = 0.01, 1e-3
    on = sim.add_boundary(BallObstacle.name, material=steel, center=(0, 0, 0), radius=big)
    off = sim.add_boundary(BallObstacle.name, material=steel, center=(0.05, 0, 0), radius=big)
    z0 = big + r + 5e-5
    sim.add_particles("sphere", material=glass, radius=r,
                      positions=[(0, 0, z0), (0.05 + 1e-3, 0, z0)])
    sim.run(until=0.1, progress=False)
    assert sorted(set(sim.walls.kind.tolist())) == [BALL_CODE]
    m = float(sim.bodies.mass[0])
    es = 1.0 / ((1 - 0.45**2) / 5e6 + (1 - 0.3**2) / 2e8)
    delta = (3 * m * G / (4 * es * math.sqrt(r))) ** (2 / 3)
    p = sim.bodies.position
    print(f"resting: x, y = {p[0, :2]}, gap {big + r - p[0, 2]:.6g} m for delta {delta:.6g};"
          f" F = {on.force}, m g = {m * G:.6g}; rolling off: x = {p[1, 0] - 0.05:.4g} m")
    assert p[0, 0] == 0.0 and p[0, 1] == 0.0  # the normal is exactly vertical on the axis
    assert big + r - p[0, 2] == pytest.approx(delta, rel=1e-3)
    np.testing.assert_allclose(on.force, [0, 0, -m * G], rtol=0, atol=1e-3 * m * G)
    assert p[1, 0] - 0.05 > 2e-3 and sim.bodies.velocity[1, 0] > 0  # away from the axis
    assert off.force[0] < 0 or np.all(off.force == 0)  # pushed towards -x, or already off


def test_an_inlet_places_bodies_clear_of_a_plugin_primitive(ball_kind):
    """The inlets' placement test is generated for the scene's kinds (dpm.kernels.placement),
    so it knows a plugin kind: an inlet box that a plugin ball fills the middle of gets
    spheres only outside the ball, many of them within a few radii of its surface."""
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    steel = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
    sim = dpm.Simulation(dt=5e-6, gravity=(0, 0, 0))
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.1, friction=0.5)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.1, friction=0.5)
    big, r = 0.01, 1e-3
    sim.add_boundary(BallObstacle.name, material=steel, center=(0, 0, 0), radius=big)
    sim.add_inlet(dpm.BoxRegion((-0.012, -0.012, -0.012), (0.012, 0.012, 0.012)), glass,
                  rate=2e5, radius=r, seed=3, max_attempts=200)
    sim.run(steps=1, progress=False)
    dist = np.linalg.norm(sim.bodies.position, axis=1)
    print(f"{len(dist)} placed, centre distances {dist.min():.5g} .. {dist.max():.5g} m")
    assert len(dist) > 20
    assert np.all(dist >= big + r - 1e-12)  # none overlaps the ball
    assert np.sum(dist < big + 3 * r) > 5  # and the test is not vacuous
