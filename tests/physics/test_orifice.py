"""Orifice plates and ring contacts against closed forms.

* A sphere smaller than a round orifice, dropped on its axis, falls through untouched (free
  fall to rounding).
* A sphere larger than the orifice rests centred in it on the whole rim: one contact
  integrated round the ring, N(d) z / s = m g with s the centre-rim distance (brentq);
  started off the axis (frictionless), it is centred by the rim, not pushed aside.
* On the plate's face, away from the hole, it rests as on a plane (the ring quadrature
  leaves a face contact whole).
* A sphere in a square opening of a rectangular plate rests on its 4 edges (mesh rules).
* Bad parameters are named.

The scenes share the step module of tests/physics/test_boundaries.py (sentinel boundaries of every
kind; the round plate is kind AXI, the rectangular one TRIANGLE).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from test_boundaries import R_BALL, G, hertz_force, scene, sentinels, sphere_mass, static_overlap

import dpm
from dpm.errors import ParameterError

HOLE = 3e-3  # orifice diameter: smaller than the 4 mm ball


def plate_scene(friction=0.5, **plate):
    sim, a, w = scene(friction=friction)
    params = dict(center=(0, 0, 0), normal=(0, 0, 1), hole=HOLE, radius=0.02)
    params.update(plate)
    bd = sim.add_boundary("orifice_plate", material=w, **params)
    sentinels(sim, w)
    return sim, a, bd


def ring_rest_height(rim: float, contacts: float = 1.0) -> float:
    """Height z of a ball on a rim of radius ``rim`` at z = 0: ``contacts`` N(r - s) z / s
    = m g with s = hypot(rim, z) (one ring contact, or 4 edge contacts)."""
    mg = sphere_mass(R_BALL) * G

    def residual(z):
        s = math.hypot(rim, z)
        return contacts * hertz_force(R_BALL - s, R_BALL) * z / s - mg

    top = math.sqrt(R_BALL**2 - rim**2)
    return brentq(residual, 0.5 * top, top, xtol=1e-18)


def test_small_sphere_falls_through_the_orifice():
    sim, a, bd = plate_scene()
    r = 1e-3
    sim.add_particles("sphere", material=a, radius=r, positions=[(0, 0, 3e-3)])
    t = 0.03  # 3 mm above: it passes the plate and falls 4.4 mm in all
    sim.run(until=t, progress=False)
    assert sim.bodies.position[0, 2] == pytest.approx(3e-3 - 0.5 * G * t * t, abs=1e-12)
    assert sim.contact_count() == 0 and np.all(bd.force == 0)


def test_large_sphere_rests_centred_in_the_orifice():
    sim, a, bd = plate_scene()
    z = ring_rest_height(HOLE / 2)
    sim.add_particles("sphere", material=a, radius=R_BALL,
                      positions=[(0, 0, math.sqrt(R_BALL**2 - (HOLE / 2) ** 2))])
    sim.run(until=0.04, progress=False)
    mg = sphere_mass(R_BALL) * G
    np.testing.assert_allclose(bd.force, [0, 0, -mg], rtol=0, atol=1e-9 * mg)
    np.testing.assert_allclose(sim.bodies.position[0], [0, 0, z], rtol=0, atol=1e-12)


def test_off_axis_sphere_is_centred_by_the_rim():
    """Frictionless, started 0.2 mm off the axis: the rim's ring contact pulls it to the
    axis (the single closest point would push it to one side and hold it there). The one
    contact damps along its normal (the axis) only, so a rattle of ~1e-4 r decays slowly:
    after 0.3 s centred and at the rest height to 1e-6 m, the kinetic energy down from
    2e-5 to below 1e-6 of m g r (decaying: the quadrature's force creates no energy)."""
    sim, a, bd = plate_scene(friction=0.0)
    z0 = math.sqrt(R_BALL**2 - (HOLE / 2) ** 2) + 3e-4  # just clear of the rim
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[(2e-4, 0, z0)])
    mg = sphere_mass(R_BALL) * G
    sim.run(until=0.05, progress=False)
    early = sim.kinetic_energy()
    sim.run(until=0.3, progress=False)
    p = sim.bodies.position[0]
    assert math.hypot(p[0], p[1]) < 1e-6
    assert p[2] == pytest.approx(ring_rest_height(HOLE / 2), abs=1e-6)
    assert sim.kinetic_energy() < min(1e-6 * mg * R_BALL, 0.1 * early)


def test_sphere_on_the_plate_face_rests_as_on_a_plane():
    """3 mm from the hole's edge (within the ring test's reach, so the quadrature runs):
    the face contact stays whole, rest height r - d and force m g to rounding."""
    sim, a, bd = plate_scene()
    x = HOLE / 2 + 3e-3
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[(x, 0, R_BALL)])
    sim.run(until=0.04, progress=False)
    mg = sphere_mass(R_BALL) * G
    np.testing.assert_allclose(bd.force, [0, 0, -mg], rtol=0, atol=1e-9 * mg)
    np.testing.assert_allclose(sim.bodies.position[0], [x, 0, R_BALL - static_overlap(R_BALL)],
                               rtol=0, atol=1e-8 * static_overlap(R_BALL))


def test_sphere_rests_on_the_four_edges_of_a_square_opening():
    sim, a, w = scene(friction=0.0)
    bd = sim.add_boundary("orifice_plate", material=w, shape="rectangle", hole=HOLE,
                          half_extents=(0.01, 0.015))
    sentinels(sim, w)
    assert bd.hole_area == pytest.approx(HOLE**2)
    z = ring_rest_height(HOLE / 2, contacts=4)
    sim.add_particles("sphere", material=a, radius=R_BALL,
                      positions=[(0, 0, math.sqrt(R_BALL**2 - (HOLE / 2) ** 2))])
    sim.run(until=0.04, progress=False)
    mg = sphere_mass(R_BALL) * G
    np.testing.assert_allclose(bd.force, [0, 0, -mg], rtol=0, atol=1e-9 * mg)
    np.testing.assert_allclose(sim.bodies.position[0], [0, 0, z], rtol=0, atol=1e-12)
    assert sim.wall_contacts.active[:sim.wall_contacts.count].sum() == 4


def test_slot_opening_passes_what_fits():
    """A slot 3 x 10 mm: a 2.8 mm ball over it falls through, one over the plate stays."""
    sim, a, w = scene()
    bd = sim.add_boundary("orifice_plate", material=w, shape="rectangle", hole=(3e-3, 10e-3),
                          half_extents=(0.02, 0.02))
    sentinels(sim, w)
    sim.add_particles("sphere", material=a, radius=1.4e-3,
                      positions=[(0, 3e-3, 2e-3), (5e-3, 0, 2e-3)])
    sim.run(until=0.03, progress=False)
    below = bd.below(sim.bodies.position)
    assert below.tolist() == [True, False]


def test_plate_volume_and_area():
    w = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    from dpm.boundaries import OrificePlate

    p = OrificePlate(w, hole=0.02, radius=0.1, thickness=0.004)
    assert p.hole_area == pytest.approx(math.pi * 1e-4)
    assert p.volume() == pytest.approx((math.pi * 0.01 - math.pi * 1e-4) * 0.004)
    q = OrificePlate(w, shape="rectangle", hole=(0.02, 0.04), half_extents=(0.1, 0.2),
                     thickness=0.002)
    assert q.volume() == pytest.approx((0.08 - 0.0008) * 0.002)


@pytest.mark.parametrize("params, match", [
    (dict(hole=0.01, radius=0.1, shape="oval"), "shape='oval'; allowed: round, rectangle"),
    (dict(hole=0.01), "needs radius="),
    (dict(hole=0.01, radius=0.004), "must exceed hole / 2"),
    (dict(hole=-0.01, radius=0.1), "must be the orifice diameter"),
    (dict(hole=(0.01, 0.02), radius=0.1), "must be the orifice diameter"),
    (dict(hole=0.01, radius=0.1, half_extents=(0.1, 0.1)), "half_extents is for"),
    (dict(hole=0.01, shape="rectangle"), "half_extents=None must be two positive lengths"),
    (dict(hole=0.3, shape="rectangle", half_extents=(0.1, 0.2)), "must exceed half the"),
    (dict(hole=(0.01, 0.0), shape="rectangle", half_extents=(0.1, 0.2)), "(width, length)"),
    (dict(hole=0.01, shape="rectangle", half_extents=(0.1, 0.2), radius=0.1),
     "radius is for shape='round'"),
])
def test_bad_orifice_plates_are_named(params, match):
    sim = dpm.Simulation(dt=1e-5)
    w = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    with pytest.raises(ParameterError, match=match.replace("(", r"\(").replace(")", r"\)")):
        sim.add_boundary("orifice_plate", material=w, **params)
